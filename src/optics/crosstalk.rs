//! Where the light of a perceived image comes from on the LCD (paper Sec. 2.3, eq. (1)): each
//! eye ray crosses one lenslet (the nearest centre) and meets the LCD in one elemental image.
//! The ray sees its own elemental image when that image is the lenslet's (the elemental-image
//! lattice's nearest cell has the lenslet's index), a neighbour's otherwise (crosstalk: a ghost
//! of the scene one elemental image over), or nothing when it meets the LCD plane off the panel
//! (the light a uniformly white display loses: its relative illumination).
//!
//! Every retina sample carries the same weight and every pupil sample the same area (the thin
//! lens's pupil grid, as the grid estimator samples it), so the shares are the fractions of a
//! uniformly white display's perceived light, averaged over the retina. They measure the eye
//! box ([`FIELD.md`](../../docs/FIELD.md)): a pupil inside the box sees only its own elemental
//! images, a pupil at its edge half a neighbour's.

use glam::DVec2;

use super::display::Display;
use super::eye::{Eye, Retina};
use super::transfer::eye_to_lcd;
use crate::error::{Error, Result};

/// The shares of the perceived light of a uniformly white display, each in [0, 1], summing to 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightShares {
    /// From the elemental image of the lenslet the ray crossed.
    pub own: f64,
    /// From another lenslet's elemental image (crosstalk).
    pub neighbour: f64,
    /// Off the LCD panel (no light).
    pub off_panel: f64,
}

impl LightShares {
    /// The light a uniformly white display gives the eye, over what it would give with every
    /// ray on the panel: `own + neighbour` (the relative illumination).
    pub fn illumination(&self) -> f64 {
        self.own + self.neighbour
    }

    /// The share of the light on the panel that comes from a neighbour's elemental image.
    pub fn crosstalk(&self) -> f64 {
        let lit = self.illumination();
        if lit > 0.0 {
            self.neighbour / lit
        } else {
            0.0
        }
    }
}

/// The light shares seen by `eye` (eq. (1)'s thin-lens or pinhole eye at `eye.position`,
/// looking straight ahead) over `retina`'s pixel centres and `eye`'s pupil grid. A turned or
/// schematic eye is refused (its rays are not eq. (1)'s): errors name `source`.
pub fn light_shares(display: &Display, eye: &Eye, retina: &Retina, source: &str) -> Result<LightShares> {
    if eye.pose.is_some() || eye.optics.is_some() {
        return Err(Error::invalid(
            source,
            "eye",
            "the light shares trace eq. (1)'s thin-lens eye looking straight ahead (no gaze, no schematic eye)",
        ));
    }
    let pupil = eye.pupil_samples();
    let n = retina.resolution;
    let half = 0.5 * display.lcd.size;
    let (mut own, mut neighbour, mut off) = (0u64, 0u64, 0u64);
    for row in 0..n {
        for col in 0..n {
            let tangent = retina.tangent(row, col, DVec2::splat(0.5));
            for &p in &pupil {
                let t = eye_to_lcd(display, eye, tangent, p);
                if t.lcd.x.abs() > half.x || t.lcd.y.abs() > half.y {
                    off += 1;
                } else if display.elemental_image_of(t.lcd) == t.lenslet_index {
                    own += 1;
                } else {
                    neighbour += 1;
                }
            }
        }
    }
    let total = (own + neighbour + off) as f64;
    Ok(LightShares { own: own as f64 / total, neighbour: neighbour as f64 / total, off_panel: off as f64 / total })
}
