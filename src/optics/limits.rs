//! The valid range of every optical setting (paper Sec. 2.3 and 4.1: the eye and display
//! parameters of eq. (1)). Inside these ranges the f64 optics keep at least 6 significant digits
//! through eq. (1) (see `docs/NUMERICS.md`); outside them a setting is refused with an error
//! naming its field, instead of an image that silently changes or turns black.

use crate::error::{Error, Result};

/// An inclusive range of a setting, in the setting's unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// The unit named in error messages ("mm", "D").
    pub unit: &'static str,
}

impl Range {
    /// Checks `value` (finite and within the range); `source` and `field` name it in the error.
    pub fn check(&self, source: &str, field: &str, value: f64) -> Result<()> {
        if value.is_finite() && value >= self.min && value <= self.max {
            return Ok(());
        }
        Err(Error::invalid(
            source,
            field,
            format!(
                "must be between {} and {} {}, got {} (valid ranges: docs/NUMERICS.md)",
                self.min,
                self.max,
                self.unit,
                if value != 0.0 && !(1e-4..1e9).contains(&value.abs()) {
                    format!("{value:e}")
                } else {
                    format!("{value}")
                }
            ),
        ))
    }
}

/// Eye lens to lenslet array, v1.
pub const EYE_TO_LENSLETS: Range = Range { min: 0.1, max: 1e4, unit: "mm" };
/// Lenslet array to LCD, v2.
pub const LENSLETS_TO_LCD: Range = Range { min: 1e-3, max: 1e3, unit: "mm" };
/// Lenslet focal length, f.
pub const FOCAL_LENGTH: Range = Range { min: 1e-3, max: 1e4, unit: "mm" };
/// Each side of the LCD.
pub const LCD_SIZE: Range = Range { min: 1e-3, max: 1e4, unit: "mm" };
/// Pupil to retina, v0 (the human eye: about 17 to 24 mm).
pub const RETINA_DISTANCE: Range = Range { min: 1.0, max: 100.0, unit: "mm" };
/// Pupil diameter (the pinhole eye is its own setting).
pub const PUPIL_DIAMETER: Range = Range { min: 1e-9, max: 100.0, unit: "mm" };
/// Focus distance from the pupil (`inf` is also allowed: focus at infinity).
pub const FOCUS_MM: Range = Range { min: 1.0, max: 1e12, unit: "mm" };
/// Focus in diopters (0 D is infinity; 1000 D is 1 mm).
pub const FOCUS_DIOPTERS: Range = Range { min: 0.0, max: 1000.0, unit: "D" };
/// Half field of the retinal image, as a tangent.
pub const RETINA_HALF_TANGENT: Range = Range { min: 1e-6, max: 100.0, unit: "(tangent)" };
/// z of the plane the camera rays of a display image start on.
pub const REFERENCE_PLANE_Z: Range = Range { min: -1e4, max: 1e4, unit: "mm" };
/// Each coordinate of the eye's pupil centre.
pub const EYE_POSITION: Range = Range { min: -1e4, max: 1e4, unit: "mm" };

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_what_is_outside_and_name_the_field() {
        FOCUS_MM.check("e.toml", "focus_mm", 300.0).unwrap();
        for bad in [1e-310, 0.5, -3.0, f64::NAN] {
            let e = FOCUS_MM.check("e.toml", "eye_cases[1].focus_mm", bad).unwrap_err().to_string();
            assert!(e.contains("e.toml") && e.contains("eye_cases[1].focus_mm") && e.contains("between"), "{e}");
        }
        assert!(RETINA_DISTANCE.check("x", "retina_distance", 1e-12).is_err());
        assert!(REFERENCE_PLANE_Z.check("x", "reference_plane_z", -1e12).is_err());
        REFERENCE_PLANE_Z.check("x", "reference_plane_z", 150.0).unwrap();
    }
}
