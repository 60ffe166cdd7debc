//! Paraxial ray transfer between the retina, the eye lens, the lenslet array and the LCD: the
//! paper's eq. (1) (Sec. 2.3):
//!
//! ```text
//! x_{i+1} = x_i + w_i v_i                      (1a)   propagation over distance v_i
//! w_1 = w_0 - x_1 d_1,  w_2 = w_1 - (x_2 - x_c) d_2   (1b)   thin-lens refraction
//! ```
//!
//! `x` are transverse positions (mm) and `w` slopes (dx/dz) in x and y independently. `x_c` is
//! the centre of the lenslet the ray crosses: the lenslet whose centre is nearest to `x_2`
//! ([`crate::optics::lattice::Lattice::nearest`]); that one rule decides the lenslet in every
//! trace that crosses the lenslet plane. Positions of the eye-side segments are measured from
//! the eye's optical axis (through its pupil centre); positions on the display planes are world
//! x, y.

use glam::{DVec2, IVec2};

use super::display::Display;
use super::eye::Eye;

/// A ray crossing a plane: transverse position and slope (dx/dz, dy/dz), travelling toward +z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneRay {
    pub position: DVec2,
    pub slope: DVec2,
}

impl PlaneRay {
    /// Eq. (1a): the ray after travelling `distance` along z.
    #[inline]
    pub fn propagate(self, distance: f64) -> PlaneRay {
        PlaneRay { position: self.position + self.slope * distance, slope: self.slope }
    }

    /// Eq. (1b): refraction by a thin lens of power `power` centred at `center`.
    #[inline]
    pub fn refract(self, center: DVec2, power: f64) -> PlaneRay {
        PlaneRay { position: self.position, slope: self.slope - (self.position - center) * power }
    }

    /// The inverse of [`PlaneRay::refract`]: the slope before the lens.
    #[inline]
    pub fn unrefract(self, center: DVec2, power: f64) -> PlaneRay {
        PlaneRay { position: self.position, slope: self.slope + (self.position - center) * power }
    }
}

/// Every point of one eye -> display trace (world x, y unless said otherwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeTrace {
    /// x0: retina point relative to the eye's axis (at z = eye z - v0).
    pub retina: DVec2,
    /// x1 and w1: the ray leaving the eye lens (position in world x, y at the pupil plane).
    pub pupil: PlaneRay,
    /// x2 and w2: the ray leaving the lenslet plane after refraction.
    pub lenslet: PlaneRay,
    /// The lenslet the ray crossed (nearest centre to x2).
    pub lenslet_index: IVec2,
    /// x3: where the ray meets the LCD plane.
    pub lcd: DVec2,
}

/// The ray that leaves the eye lens for retina direction `tangent` (x0 = -v0 * tangent) through
/// pupil point `pupil_offset` (relative to the pupil centre): eq. (1a) then (1b) with d1.
#[inline]
pub fn eye_ray(eye: &Eye, tangent: DVec2, pupil_offset: DVec2) -> PlaneRay {
    let v0 = eye.retina_distance;
    let x0 = -v0 * tangent;
    let w0 = (pupil_offset - x0) / v0;
    PlaneRay { position: pupil_offset, slope: w0 }.refract(DVec2::ZERO, eye.power())
}

/// Traces retina -> pupil -> lenslet plane -> refraction at the nearest lenslet -> LCD plane.
#[inline]
pub fn eye_to_lcd(display: &Display, eye: &Eye, tangent: DVec2, pupil_offset: DVec2) -> EyeTrace {
    let local = eye_ray(eye, tangent, pupil_offset);
    let pupil = PlaneRay { position: local.position + eye.position.truncate(), slope: local.slope };
    let at_lenslets = pupil.propagate(display.lenslet_z() - eye.position.z);
    let lenslet_index = display.lenslets.nearest(at_lenslets.position);
    let center = display.lenslets.center(lenslet_index);
    let lenslet = at_lenslets.refract(center, display.lenslet_power());
    let lcd = lenslet.propagate(display.lenslets_to_lcd).position;
    EyeTrace { retina: -eye.retina_distance * tangent, pupil, lenslet, lenslet_index, lcd }
}

/// The reverse trace: light leaving LCD point `lcd` through lenslet-plane point `lenslet_point`,
/// refracted by the lenslet nearest to that point, back through the eye lens to the retina.
/// Returns (pupil-plane ray after the eye lens, travelling toward +z, world x, y; retina point
/// relative to the eye's axis).
pub fn lcd_to_eye(display: &Display, eye: &Eye, lcd: DVec2, lenslet_point: DVec2) -> (PlaneRay, DVec2) {
    let w2 = (lcd - lenslet_point) / display.lenslets_to_lcd;
    let center = display.lenslets.center(display.lenslets.nearest(lenslet_point));
    let before = PlaneRay { position: lenslet_point, slope: w2 }.unrefract(center, display.lenslet_power());
    let at_pupil = before.propagate(-(display.lenslet_z() - eye.position.z));
    let local = PlaneRay { position: at_pupil.position - eye.position.truncate(), slope: at_pupil.slope };
    let w0 = local.unrefract(DVec2::ZERO, eye.power()).slope;
    let x0 = local.position - w0 * eye.retina_distance;
    (at_pupil, x0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::eye::Focus;

    #[test]
    fn refraction_undoes_itself() {
        let r = PlaneRay { position: DVec2::new(0.3, -0.7), slope: DVec2::new(0.01, 0.02) };
        let back = r.refract(DVec2::new(0.1, 0.2), 0.15).unrefract(DVec2::new(0.1, 0.2), 0.15);
        assert!((back.slope - r.slope).length() < 1e-15);
    }

    #[test]
    fn eye_ray_through_pupil_centre_keeps_the_retina_direction() {
        let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8);
        let t = DVec2::new(0.1, -0.2);
        let r = eye_ray(&eye, t, DVec2::ZERO);
        assert!((r.slope - t).length() < 1e-15);
    }
}
