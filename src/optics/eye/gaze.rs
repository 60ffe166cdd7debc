//! The eye turned about its centre of rotation: where the pupil goes and how it faces at a gaze.
//!
//! **Gaze** `[horizontal, vertical]`, degrees, in Fick's coordinates (A. Fick, Z. rationelle
//! Med. 4:101, 1854; R. H. S. Carpenter, "Movements of the Eyes", 2nd ed., Pion 1988): the line of sight
//! turned `horizontal` toward +x about the head's vertical axis, then `vertical` toward +y,
//! `(cos v sin h, sin v, cos v cos h)`. The eye's orientation about its line of sight follows
//! **Listing's law** (H. von Helmholtz, "Handbuch der physiologischen Optik", 1867; Carpenter
//! 1988): the rotation from the primary position (straight ahead, +z) is about an
//! axis in Listing's plane, perpendicular to +z, by the angle between the two lines of sight,
//! the shortest arc.
//!
//! **Centre of rotation**: one point on the optical axis, [`CentreOfRotation::DEFAULT_MM`] =
//! 13.3 mm behind the cornea's front vertex, the value usually assumed for emmetropes (G. K. von
//! Noorden & E. C. Campos, "Binocular Vision and Ocular Motility", 6th ed., Mosby 2002), between
//! G. A. Fry & W. W. Hill's measured centres for horizontal and vertical rotations (14.8 and
//! 12.2 mm behind the cornea; "The center of rotation of the eye", Am. J. Optom. 39:581, 1962,
//! and Am. J. Optom. 40:707, 1963). The eye frame's origin is the entrance pupil's centre,
//! [`CentreOfRotation::pupil_depth`] behind the cornea (3.04 mm for Navarro's eyes, 2.96 mm for
//! Arizona, 3.04 mm for Le Grand; the thin-lens eye, which has no cornea, takes Navarro's), so
//! the centre lies about 10.3 mm behind the pupil and the pupil travels about
//! `10.3 mm x sin(gaze)`.
//!
//! An [`EyePose`] is the rigid motion of the whole eye: `x -> c + R (x - c)` for points of the
//! eye at rest (c the centre, R the rotation); the pupil centre goes to `c + R (p0 - c)` and its
//! normal (the line of sight) to `R z`.

use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The largest gaze eccentricity accepted, degrees (the oculomotor range is about 45-55
/// degrees; beyond, people turn the head).
pub const MAX_GAZE_DEG: f64 = 60.0;

/// A gaze direction in Fick's coordinates, degrees (module documentation). Written in files as
/// `[horizontal, vertical]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "[f64; 2]", into = "[f64; 2]")]
pub struct Gaze {
    /// Toward +x (the scene's right), about the head's vertical axis, degrees.
    pub horizontal_deg: f64,
    /// Toward +y (up), after the horizontal turn, degrees.
    pub vertical_deg: f64,
}

impl From<[f64; 2]> for Gaze {
    fn from([horizontal_deg, vertical_deg]: [f64; 2]) -> Self {
        Self { horizontal_deg, vertical_deg }
    }
}

impl From<Gaze> for [f64; 2] {
    fn from(g: Gaze) -> Self {
        [g.horizontal_deg, g.vertical_deg]
    }
}

impl Gaze {
    /// Straight ahead.
    pub const AHEAD: Gaze = Gaze { horizontal_deg: 0.0, vertical_deg: 0.0 };

    /// A gaze of `horizontal` and `vertical` degrees.
    pub fn new(horizontal_deg: f64, vertical_deg: f64) -> Self {
        Self { horizontal_deg, vertical_deg }
    }

    /// Whether this is straight ahead.
    pub fn is_ahead(&self) -> bool {
        self.horizontal_deg == 0.0 && self.vertical_deg == 0.0
    }

    /// The unit line of sight, `(cos v sin h, sin v, cos v cos h)`.
    pub fn line_of_sight(&self) -> DVec3 {
        let (sh, ch) = self.horizontal_deg.to_radians().sin_cos();
        let (sv, cv) = self.vertical_deg.to_radians().sin_cos();
        DVec3::new(cv * sh, sv, cv * ch)
    }

    /// The angle between the line of sight and straight ahead, degrees.
    pub fn eccentricity_deg(&self) -> f64 {
        let l = self.line_of_sight();
        l.truncate().length().atan2(l.z).to_degrees()
    }

    /// The eye's rotation from straight ahead (Listing's law; exact identity straight ahead).
    pub fn rotation(&self) -> DQuat {
        if self.is_ahead() {
            return DQuat::IDENTITY;
        }
        DQuat::from_rotation_arc(DVec3::Z, self.line_of_sight())
    }

    /// [`Gaze::rotation`] as a matrix.
    pub fn matrix(&self) -> DMat3 {
        DMat3::from_quat(self.rotation())
    }

    /// Checks the gaze: finite, at most [`MAX_GAZE_DEG`] from straight ahead; errors name
    /// `source` and `field`.
    pub fn validate(&self, source: &str, field: &str) -> Result<()> {
        if !(self.horizontal_deg.is_finite() && self.vertical_deg.is_finite()) {
            return Err(Error::invalid(
                source,
                field,
                format!("must be finite degrees, got [{}, {}]", self.horizontal_deg, self.vertical_deg),
            ));
        }
        let e = self.eccentricity_deg();
        if e > MAX_GAZE_DEG + 1e-9 {
            return Err(Error::invalid(
                source,
                field,
                format!(
                    "[{}, {}] points {e:.1} degrees from straight ahead: at most {MAX_GAZE_DEG} degrees \
                     (beyond, people turn the head)",
                    self.horizontal_deg, self.vertical_deg
                ),
            ));
        }
        Ok(())
    }
}

/// Where the eye's centre of rotation lies: mm behind the cornea's front vertex, on the optical
/// axis (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct CentreOfRotation {
    /// Distance behind the cornea's front vertex, mm.
    pub behind_cornea_mm: f64,
}

impl Default for CentreOfRotation {
    fn default() -> Self {
        Self { behind_cornea_mm: Self::DEFAULT_MM }
    }
}

impl CentreOfRotation {
    /// The default: 13.3 mm behind the cornea (von Noorden & Campos 2002; module documentation).
    pub const DEFAULT_MM: f64 = 13.3;
    /// The thin-lens eye's pupil (which has no cornea) is taken this far behind the cornea: the
    /// entrance pupil of Navarro's eyes at 555 nm, mm.
    pub const THIN_LENS_PUPIL_DEPTH_MM: f64 = 3.04;
    /// The farthest behind the cornea accepted, mm (beyond any eye's axial length).
    pub const MAX_MM: f64 = 30.0;

    /// The entrance pupil's depth behind the cornea for an eye whose paraxial data (at its
    /// reference wavelength) are `paraxial`, or the thin-lens eye's for `None`, mm.
    pub fn pupil_depth(paraxial: Option<&super::Paraxial>) -> f64 {
        paraxial.map_or(Self::THIN_LENS_PUPIL_DEPTH_MM, |p| p.cornea_z - p.entrance_pupil_z)
    }

    /// The centre's distance behind the entrance pupil, for a pupil `pupil_depth_mm` behind the
    /// cornea, mm.
    pub fn behind_pupil_mm(&self, pupil_depth_mm: f64) -> f64 {
        self.behind_cornea_mm - pupil_depth_mm
    }

    /// Checks the centre: finite, behind the cornea (a centre in front of it is refused) and at
    /// most [`CentreOfRotation::MAX_MM`] behind; errors name `source` and `field`.
    pub fn validate(&self, source: &str, field: &str) -> Result<()> {
        let mm = self.behind_cornea_mm;
        if !mm.is_finite() {
            return Err(Error::invalid(source, field, format!("must be a finite number of mm, got {mm}")));
        }
        if mm <= 0.0 {
            return Err(Error::invalid(
                source,
                field,
                format!(
                    "{mm} mm puts the centre of rotation in front of the cornea (or on it): it must lie \
                     behind the cornea, about {} mm",
                    Self::DEFAULT_MM
                ),
            ));
        }
        if mm > Self::MAX_MM {
            return Err(Error::invalid(
                source,
                field,
                format!("{mm} mm lies behind any eye (at most {} mm behind the cornea)", Self::MAX_MM),
            ));
        }
        Ok(())
    }
}

/// The whole eye turned to a gaze about its centre of rotation (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyePose {
    /// The gaze.
    pub gaze: Gaze,
    /// The centre of rotation, in the scene's frame, mm.
    pub centre: DVec3,
    /// The rotation from the eye at rest (straight ahead).
    pub rotation: DQuat,
    /// The entrance pupil's centre at this gaze, mm.
    pub pupil_centre: DVec3,
    /// The pupil's normal, the line of sight: the rotated +z.
    pub line_of_sight: DVec3,
}

impl EyePose {
    /// The eye whose pupil centre is at `pupil_at_rest` when it looks straight ahead, with its
    /// centre of rotation `behind_pupil_mm` behind that pupil on the axis, turned to `gaze`.
    pub fn new(gaze: Gaze, pupil_at_rest: DVec3, behind_pupil_mm: f64) -> Self {
        let centre = pupil_at_rest - DVec3::new(0.0, 0.0, behind_pupil_mm);
        let rotation = gaze.rotation();
        Self {
            gaze,
            centre,
            rotation,
            pupil_centre: centre + rotation * (pupil_at_rest - centre),
            line_of_sight: rotation * DVec3::Z,
        }
    }

    /// A point of the eye at rest (scene frame), moved with the eye.
    pub fn point(&self, at_rest: DVec3) -> DVec3 {
        self.centre + self.rotation * (at_rest - self.centre)
    }

    /// A direction of the eye at rest, turned with the eye.
    pub fn direction(&self, at_rest: DVec3) -> DVec3 {
        self.rotation * at_rest
    }

    /// How far the pupil centre has moved from where it was at rest, mm.
    pub fn pupil_travel(&self, pupil_at_rest: DVec3) -> DVec3 {
        self.pupil_centre - pupil_at_rest
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_ahead_is_the_identity_and_listing_keeps_torsion_out_of_primary_gazes() {
        let p0 = DVec3::new(0.3, -0.2, 1.0);
        let rest = EyePose::new(Gaze::AHEAD, p0, 10.26);
        assert_eq!(rest.rotation, DQuat::IDENTITY);
        assert_eq!(rest.pupil_centre, p0);
        // A purely horizontal gaze turns about the vertical axis only: y stays put.
        let g = Gaze::new(25.0, 0.0);
        let y = g.rotation() * DVec3::Y;
        assert!((y - DVec3::Y).length() < 1e-15, "{y}");
        // Listing: the rotation axis is perpendicular to straight ahead, for any gaze.
        for g in [Gaze::new(20.0, 15.0), Gaze::new(-35.0, 40.0), Gaze::new(0.0, -50.0)] {
            let (axis, angle) = g.rotation().to_axis_angle();
            assert!(axis.z.abs() < 1e-12, "{g:?} {axis}");
            assert!((angle.to_degrees() - g.eccentricity_deg()).abs() < 1e-9);
            assert!((g.rotation() * DVec3::Z - g.line_of_sight()).length() < 1e-15);
        }
    }

    #[test]
    fn serde_reads_and_writes_the_pair() {
        let g: Gaze = serde_json::from_str("[10.5, -3]").unwrap();
        assert_eq!(g, Gaze::new(10.5, -3.0));
        assert_eq!(serde_json::to_string(&g).unwrap(), "[10.5,-3.0]");
        let c: CentreOfRotation = serde_json::from_str("14.8").unwrap();
        assert_eq!(c.behind_cornea_mm, 14.8);
    }
}
