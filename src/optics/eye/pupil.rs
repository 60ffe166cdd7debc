//! The light-adapted pupil: the unified formula of A. B. Watson and J. I. Yellott, "A unified
//! formula for light-adapted pupil size", Journal of Vision 12(10):12, 2012
//! (doi:10.1167/12.10.12), which `pupil_diameter = "auto"` gives the entrance pupil by.
//!
//! The formula starts from Stanley and Davies' (1995) pupil of the corneal flux density
//! `F = L a` (luminance `L` in cd/m^2 times the adapting field's area `a` in deg^2):
//!
//! `D_SD(F) = 7.75 - 5.75 (F / 846)^0.41 / ((F / 846)^0.41 + 2)` mm,
//!
//! takes monocular adaptation as a tenfold loss of flux (`F = L a M(e)`, `M(1) = 0.1`,
//! `M(2) = 1`, from Blanchard's and Reeves' 1918 data), and adds the effect of age `y`
//! (years, from Winn et al. 1994) around the reference age `y0 = 28.58`:
//!
//! `D = D_SD(F) + (y - y0) (0.02132 - 0.009562 D_SD(F))`  (their eq. 21),
//!
//! for ages 20 to 83, the range of the data the age term was fit to. The defaults are an
//! observer of 30 years (the age of Watson and Yellott's Fig. 16) adapted with both eyes (a
//! head-mounted display lights both).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The reference age of the age term, years (Watson & Yellott 2012).
pub const REFERENCE_AGE: f64 = 28.58;
/// The default observer's age, years.
pub const DEFAULT_AGE: f64 = 30.0;
/// The default number of adapted eyes.
pub const DEFAULT_EYES: u8 = 2;
/// The ages the formula's age term was fit to, years.
pub const AGES: (f64, f64) = (20.0, 83.0);

/// Stanley and Davies' (1995) pupil diameter (mm) for the corneal flux density `flux`
/// (cd/m^2 x deg^2).
pub fn stanley_davies(flux: f64) -> f64 {
    let f = (flux / 846.0).powf(0.41);
    7.75 - 5.75 * f / (f + 2.0)
}

/// The monocular effect `M(e)`: the factor on the corneal flux of adapting `eyes` eyes (1 or 2).
pub fn monocular_effect(eyes: u8) -> f64 {
    if eyes == 1 {
        0.1
    } else {
        1.0
    }
}

/// The observer of the formula: age and adapted eyes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Observer {
    /// Age, years (20 to 83).
    pub age: f64,
    /// Eyes adapted to the field: 1 or 2.
    pub eyes: u8,
}

impl Default for Observer {
    fn default() -> Self {
        Self { age: DEFAULT_AGE, eyes: DEFAULT_EYES }
    }
}

impl Observer {
    /// Checks the age and the eyes; errors name `source` and `prefix` + the field (`age`,
    /// `adapted_eyes`).
    pub fn validate(&self, source: &str, prefix: &str) -> Result<()> {
        if !(self.age.is_finite() && (AGES.0..=AGES.1).contains(&self.age)) {
            return Err(Error::invalid(
                source,
                format!("{prefix}age"),
                format!(
                    "must be between {} and {} years (the ages Watson & Yellott's age term was fit to), got {}",
                    AGES.0, AGES.1, self.age
                ),
            ));
        }
        if !(self.eyes == 1 || self.eyes == 2) {
            return Err(Error::invalid(
                source,
                format!("{prefix}adapted_eyes"),
                format!("must be 1 or 2, got {}", self.eyes),
            ));
        }
        Ok(())
    }

    /// The unified formula's pupil diameter (mm) for an adapting field of `luminance` cd/m^2
    /// over `area_deg2` square degrees.
    pub fn pupil_diameter(&self, luminance: f64, area_deg2: f64) -> f64 {
        let d = stanley_davies(luminance * area_deg2 * monocular_effect(self.eyes));
        d + (self.age - REFERENCE_AGE) * (0.02132 - 0.009562 * d)
    }
}

/// `pupil_diameter`: a diameter in mm, or `"auto"` (the unified formula).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PupilSetting {
    /// A stated diameter, mm.
    Mm(f64),
    /// From the adapting luminance and field (module comment).
    Auto,
}

impl PupilSetting {
    /// The stated diameter (`None` for `"auto"`).
    pub fn stated(&self) -> Option<f64> {
        match self {
            PupilSetting::Mm(d) => Some(*d),
            PupilSetting::Auto => None,
        }
    }
}

impl Serialize for PupilSetting {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            PupilSetting::Mm(d) => s.serialize_f64(*d),
            PupilSetting::Auto => s.serialize_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for PupilSetting {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = PupilSetting;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number (the pupil diameter in mm) or \"auto\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<PupilSetting, E> {
                Ok(PupilSetting::Mm(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<PupilSetting, E> {
                Ok(PupilSetting::Mm(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<PupilSetting, E> {
                Ok(PupilSetting::Mm(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<PupilSetting, E> {
                match v {
                    "auto" => Ok(PupilSetting::Auto),
                    other => Err(E::custom(format!(
                        "`{other}` is not a pupil diameter: give a number of mm or \"auto\" (Watson & Yellott 2012)"
                    ))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// How `"auto"` chose a pupil: the adapting field, the observer and the diameter, for reports.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AutoPupil {
    /// The adapting field's mean luminance, cd/m^2.
    pub adapting_luminance_cd_m2: f64,
    /// The adapting field's area, deg^2.
    pub field_area_deg2: f64,
    /// The observer's age, years.
    pub age: f64,
    /// Adapted eyes.
    pub eyes: u8,
    /// The pupil diameter the formula gives, mm.
    pub diameter_mm: f64,
}

impl AutoPupil {
    /// The pupil of `observer` adapted to `luminance` cd/m^2 over `area_deg2`.
    pub fn new(observer: Observer, luminance: f64, area_deg2: f64) -> Self {
        Self {
            adapting_luminance_cd_m2: luminance,
            field_area_deg2: area_deg2,
            age: observer.age,
            eyes: observer.eyes,
            diameter_mm: observer.pupil_diameter(luminance, area_deg2),
        }
    }

    /// One line for `info` and run logs.
    pub fn text(&self) -> String {
        format!(
            "pupil \"auto\": {:.3} mm (Watson & Yellott 2012: adapting luminance {:.4} cd/m^2 over {:.0} deg^2, age {}, \
             {} adapted)",
            self.diameter_mm,
            self.adapting_luminance_cd_m2,
            self.field_area_deg2,
            self.age,
            if self.eyes == 1 { "one eye" } else { "both eyes" }
        )
    }
}
