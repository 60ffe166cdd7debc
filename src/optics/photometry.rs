//! The display's photometry (issue "perceptual scores at the display's real luminance"): how
//! inimtrace's linear values (scene radiance in albedo units, display values, retinal image values)
//! become absolute luminance in cd/m^2, as perceptual metrics and the pupil's response need them.
//!
//! The model is the gain-offset display model with reflected ambient light that ColorVideoVDP uses
//! (R. K. Mantiuk, P. Hanji, M. Ashraf, Y. Asano, A. Chapiro, "ColorVideoVDP: A visual difference
//! predictor for image, video and display distortions", ACM TOG 43(4), SIGGRAPH 2024, its display
//! model), with a linear transfer because inimtrace's values are already linear in light:
//!
//! `L(v) = L_black + (L_peak - L_black) v + L_refl`,  `L_refl = reflectance E_ambient / pi`,
//!
//! per colour channel, so that `v = 1` in all three channels is the panel's peak white (plus the
//! reflected light) and `v = 0` its black floor. The luminance of a pixel weights its channels by
//! the primaries' luminance shares ([`crate::optics::spectrum::Primaries::luminance_weights`],
//! which sum to 1), so a grey `v` has luminance `L(v)`.
//!
//! **The perceived image** is the eye's view of the display: each retinal value is a mean of
//! display values over the pupil and the pixel, and the map is affine, so the mean of the
//! luminances equals `L` of the mean value. (Eye rays that miss the LCD are counted at the black
//! floor, the light of a panel pixel driven to 0, not as darkness.)
//!
//! **The ground truth** is the scene as a perfect display of the same photometry shows it: scene
//! radiance `r` (a white Lambertian surface of albedo 1 under the scene's unit light is 1) has
//! luminance `L(r)`. A display that reproduced the scene's light field exactly would give a
//! perceived image equal to the ground truth, so the two differ only by what the display's
//! optics and sampling change, never by its black level or peak. Values above 1 (a scene lit
//! brighter than its white reference) map above peak white: the map is not clipped.
//!
//! Defaults (a typical near-eye LCD): peak white 100 cd/m^2 and black 0.1 cd/m^2 (contrast 1000:1),
//! ColorVideoVDP's `standard_hmd` display model (Mantiuk et al. 2024), within the 60-180 cd/m^2
//! that commercial head-mounted displays were measured to reach (Mehrfard, Fotouhi, Taylor,
//! Forster, Navab, Fuerst, "A comparative analysis of virtual reality head-mounted display
//! systems", arXiv:1912.02913, 2019); no ambient light (the panel is inside a closed headset), and
//! ColorVideoVDP's default panel reflectance 0.005 for a file that states an ambient illuminance.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Peak white of the default near-eye LCD, cd/m^2.
pub const DEFAULT_PEAK_LUMINANCE: f64 = 100.0;
/// Contrast ratio (peak / black) of the default near-eye LCD.
pub const DEFAULT_CONTRAST_RATIO: f64 = 1000.0;
/// Ambient illuminance on the default panel, lux (a closed headset).
pub const DEFAULT_AMBIENT_ILLUMINANCE: f64 = 0.0;
/// The default panel's diffuse reflectance of ambient light.
pub const DEFAULT_REFLECTANCE: f64 = 0.005;

/// `[photometry]` of a display file, as written: every field optional, at most one of
/// `black_level` and `contrast_ratio`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotometrySpec {
    /// Peak white luminance, cd/m^2 (default 100).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_luminance: Option<f64>,
    /// Black level (a pixel driven to 0), cd/m^2 (default: peak / 1000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub black_level: Option<f64>,
    /// Contrast ratio, peak / black (instead of `black_level`; default 1000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contrast_ratio: Option<f64>,
    /// Ambient illuminance on the panel, lux (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient_illuminance: Option<f64>,
    /// The panel's diffuse reflectance of ambient light, 0 to 1 (default 0.005).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflectance: Option<f64>,
}

/// A display's photometry, resolved and valid: see the module comment for the map it defines.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Photometry {
    /// Peak white luminance, cd/m^2.
    pub peak_luminance: f64,
    /// Black level, cd/m^2.
    pub black_level: f64,
    /// Ambient illuminance on the panel, lux.
    pub ambient_illuminance: f64,
    /// The panel's diffuse reflectance.
    pub reflectance: f64,
}

impl Default for Photometry {
    fn default() -> Self {
        Self::typical_near_eye_lcd()
    }
}

impl Photometry {
    /// The documented default (module comment).
    pub fn typical_near_eye_lcd() -> Self {
        Self {
            peak_luminance: DEFAULT_PEAK_LUMINANCE,
            black_level: DEFAULT_PEAK_LUMINANCE / DEFAULT_CONTRAST_RATIO,
            ambient_illuminance: DEFAULT_AMBIENT_ILLUMINANCE,
            reflectance: DEFAULT_REFLECTANCE,
        }
    }

    /// Checks every value: luminances positive and finite, black below peak, ambient light
    /// finite and not negative, reflectance in [0, 1]. Errors name `source` and
    /// `photometry.<field>`.
    pub fn validate(&self, source: &str) -> Result<()> {
        let field = |f: &str| format!("photometry.{f}");
        let luminance = |f: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    source,
                    field(f),
                    format!("must be a positive, finite luminance in cd/m^2, got {v}"),
                ))
            }
        };
        luminance("peak_luminance", self.peak_luminance)?;
        luminance("black_level", self.black_level)?;
        if self.black_level >= self.peak_luminance {
            return Err(Error::invalid(
                source,
                field("black_level"),
                format!(
                    "must be below photometry.peak_luminance ({} cd/m^2), got {} cd/m^2",
                    self.peak_luminance, self.black_level
                ),
            ));
        }
        if !(self.ambient_illuminance.is_finite() && self.ambient_illuminance >= 0.0) {
            return Err(Error::invalid(
                source,
                field("ambient_illuminance"),
                format!("must be a finite illuminance in lux, 0 or more, got {}", self.ambient_illuminance),
            ));
        }
        if !(self.reflectance.is_finite() && (0.0..=1.0).contains(&self.reflectance)) {
            return Err(Error::invalid(
                source,
                field("reflectance"),
                format!("must be a fraction between 0 and 1, got {}", self.reflectance),
            ));
        }
        Ok(())
    }

    /// Luminance of the ambient light the panel reflects, `reflectance E / pi`, cd/m^2.
    pub fn reflected_luminance(&self) -> f64 {
        self.reflectance * self.ambient_illuminance / std::f64::consts::PI
    }

    /// The darkest luminance the display shows (black level plus reflected light), cd/m^2.
    pub fn black_floor(&self) -> f64 {
        self.black_level + self.reflected_luminance()
    }

    /// The brightest (peak white plus reflected light), cd/m^2.
    pub fn white(&self) -> f64 {
        self.peak_luminance + self.reflected_luminance()
    }

    /// The contrast the eye sees, white / black floor.
    pub fn effective_contrast(&self) -> f64 {
        self.white() / self.black_floor()
    }

    /// Absolute luminance (cd/m^2) of one channel's linear value `v`: a display value, a
    /// perceived image's value (through the display) or a ground truth's scene radiance (as a
    /// perfect display of this photometry shows it); module comment.
    #[inline]
    pub fn absolute(&self, v: f64) -> f64 {
        self.black_level + (self.peak_luminance - self.black_level) * v + self.reflected_luminance()
    }

    /// [`Photometry::absolute`] of each channel of `rgb`: absolute linear RGB, each channel in
    /// cd/m^2 of the display's white (a grey `v` is `[L(v); 3]`).
    pub fn absolute_rgb(&self, rgb: [f32; 3]) -> [f64; 3] {
        rgb.map(|v| self.absolute(f64::from(v)))
    }

    /// Absolute luminance (cd/m^2) of the linear RGB value `rgb`, its channels weighted by the
    /// primaries' luminance shares `weights` (summing to 1).
    pub fn luminance(&self, rgb: [f32; 3], weights: &[f64; 3]) -> f64 {
        let v = weights[0] * f64::from(rgb[0]) + weights[1] * f64::from(rgb[1]) + weights[2] * f64::from(rgb[2]);
        self.absolute(v)
    }
}

impl PhotometrySpec {
    /// The resolved photometry (defaults filled in), validated; errors name `source` and the
    /// field.
    pub fn resolve(&self, source: &str) -> Result<Photometry> {
        let peak = self.peak_luminance.unwrap_or(DEFAULT_PEAK_LUMINANCE);
        let black = match (self.black_level, self.contrast_ratio) {
            (Some(_), Some(_)) => {
                return Err(Error::invalid(
                    source,
                    "photometry.contrast_ratio",
                    "give either photometry.black_level or photometry.contrast_ratio, not both",
                ))
            }
            (Some(b), None) => b,
            (None, Some(c)) => {
                if !(c.is_finite() && c > 1.0) {
                    return Err(Error::invalid(
                        source,
                        "photometry.contrast_ratio",
                        format!("must be a finite ratio above 1 (peak / black), got {c}"),
                    ));
                }
                peak / c
            }
            (None, None) => peak / DEFAULT_CONTRAST_RATIO,
        };
        let p = Photometry {
            peak_luminance: peak,
            black_level: black,
            ambient_illuminance: self.ambient_illuminance.unwrap_or(DEFAULT_AMBIENT_ILLUMINANCE),
            reflectance: self.reflectance.unwrap_or(DEFAULT_REFLECTANCE),
        };
        p.validate(source)?;
        Ok(p)
    }

    /// The table that states `p` (`black_level` explicit), for files written from a display.
    pub fn of(p: &Photometry) -> Self {
        Self {
            peak_luminance: Some(p.peak_luminance),
            black_level: Some(p.black_level),
            contrast_ratio: None,
            ambient_illuminance: Some(p.ambient_illuminance),
            reflectance: Some(p.reflectance),
        }
    }
}

/// A display's photometry as `inimtrace info` reports it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhotometryInfo {
    /// Whether the display file states `[photometry]` (else these are the defaults).
    pub stated: bool,
    /// Peak white, cd/m^2.
    pub peak_luminance_cd_m2: f64,
    /// Black level, cd/m^2.
    pub black_level_cd_m2: f64,
    /// Peak / black.
    pub contrast_ratio: f64,
    /// Ambient illuminance on the panel, lux.
    pub ambient_illuminance_lux: f64,
    /// The panel's diffuse reflectance.
    pub reflectance: f64,
    /// Reflected ambient light, cd/m^2.
    pub reflected_luminance_cd_m2: f64,
    /// (Peak + reflected) / (black + reflected).
    pub effective_contrast: f64,
    /// The red, green and blue primaries' shares of the luminance (V(lambda)-weighted spectra).
    pub luminance_weights: [f64; 3],
}

impl PhotometryInfo {
    /// The report of `d`'s photometry.
    pub fn of(d: &super::Display) -> Self {
        let p = d.photometry();
        Self {
            stated: d.photometry.is_some(),
            peak_luminance_cd_m2: p.peak_luminance,
            black_level_cd_m2: p.black_level,
            contrast_ratio: p.peak_luminance / p.black_level,
            ambient_illuminance_lux: p.ambient_illuminance,
            reflectance: p.reflectance,
            reflected_luminance_cd_m2: p.reflected_luminance(),
            effective_contrast: p.effective_contrast(),
            luminance_weights: d.luminance_weights(),
        }
    }

    /// The line `info` prints.
    pub fn text(&self) -> String {
        let w = self.luminance_weights;
        format!(
            "photometry{}: peak white {} cd/m^2, black {} cd/m^2 (contrast {:.0}:1), ambient {} lux x reflectance {} \
             (reflected {:.4} cd/m^2; effective contrast {:.0}:1); luminance shares R / G / B {:.4} / {:.4} / {:.4}\n",
            if self.stated { "" } else { " (default: a typical near-eye LCD)" },
            self.peak_luminance_cd_m2,
            self.black_level_cd_m2,
            self.contrast_ratio,
            self.ambient_illuminance_lux,
            self.reflectance,
            self.reflected_luminance_cd_m2,
            self.effective_contrast,
            w[0],
            w[1],
            w[2]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_puts_white_at_peak_and_black_at_the_floor_and_is_affine() {
        let p = Photometry { peak_luminance: 200.0, black_level: 0.2, ambient_illuminance: 250.0, reflectance: 0.005 };
        let refl = 0.005 * 250.0 / std::f64::consts::PI;
        assert!((p.absolute(1.0) - (200.0 + refl)).abs() < 1e-12);
        assert!((p.absolute(0.0) - (0.2 + refl)).abs() < 1e-12);
        // Affine: the mean of luminances is the luminance of the mean (the perceived image).
        let (a, b) = (0.3, 0.9);
        assert!((0.5 * (p.absolute(a) + p.absolute(b)) - p.absolute(0.5 * (a + b))).abs() < 1e-12);
        // A grey's luminance is its channels' for any weights summing to 1.
        let w = [0.2, 0.7, 0.1];
        assert!((p.luminance([0.4; 3], &w) - p.absolute(0.4f32 as f64)).abs() < 1e-12);
        assert!((p.effective_contrast() - (200.0 + refl) / (0.2 + refl)).abs() < 1e-9);
    }

    #[test]
    fn defaults_are_the_typical_near_eye_lcd() {
        let p = PhotometrySpec::default().resolve("d").unwrap();
        assert_eq!(p, Photometry::typical_near_eye_lcd());
        assert_eq!((p.peak_luminance, p.black_level, p.ambient_illuminance), (100.0, 0.1, 0.0));
        let c = PhotometrySpec { contrast_ratio: Some(500.0), ..Default::default() }.resolve("d").unwrap();
        assert_eq!(c.black_level, 0.2);
        assert_eq!(PhotometrySpec::of(&c).resolve("d").unwrap(), c);
    }
}
