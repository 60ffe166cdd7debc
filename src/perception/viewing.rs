//! What a perceptual metric must know of how the images are seen: the display's absolute
//! luminance (peak white, black level, reflected ambient light) and the retina image's angular
//! sampling, its pixels per degree. ColorVideoVDP's display model (Mantiuk et al., SIGGRAPH 2024,
//! Sec. 3.1: `L = (L_peak - L_black) V + L_black + L_refl`, `L_refl = k E_amb / pi`) and FLIP's
//! pixels per degree (Andersson et al., HPG 2020, Sec. 3) are built from it.
//!
//! Retinal images hold linear values in the scene's albedo units: 1 is the display's white, 0
//! its black. A value `v` of channel c is shown at `L_black + (L_peak - L_black) v` cd/m^2 in
//! that channel's BT.709 primary (the metrics' colour space), plus the reflected ambient light.

use crate::error::{Error, Result};
use crate::optics::Retina;

/// Rec. ITU-R BT.709 luminance of linear R, G, B: the weights of the metrics' colour space.
pub const BT709_LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The display's luminance as the metrics see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayLuminance {
    /// Luminance of white (every channel 1), cd/m^2.
    pub peak_white: f64,
    /// Luminance of black (every channel 0), cd/m^2: the panel's own, without ambient light.
    pub black: f64,
    /// Illuminance of the ambient light on the display, lux.
    pub ambient_lux: f64,
    /// Diffuse reflectance of the display for the ambient light, 0..1.
    pub reflectance: f64,
}

impl Default for DisplayLuminance {
    /// A typical near-eye LCD: 100 cd/m^2 white, 1000:1 contrast, no ambient light (a headset
    /// shuts it out).
    fn default() -> Self {
        Self { peak_white: 100.0, black: 0.1, ambient_lux: 0.0, reflectance: 0.0 }
    }
}

impl From<&crate::optics::photometry::Photometry> for DisplayLuminance {
    /// The display's photometry (`[photometry]` of its file, `optics/photometry.rs`).
    fn from(p: &crate::optics::photometry::Photometry) -> Self {
        Self {
            peak_white: p.peak_luminance,
            black: p.black_level,
            ambient_lux: p.ambient_illuminance,
            reflectance: p.reflectance,
        }
    }
}

impl DisplayLuminance {
    /// The reflected ambient light's luminance, cd/m^2: `reflectance * ambient / pi`.
    pub fn reflected(&self) -> f64 {
        self.reflectance * self.ambient_lux / std::f64::consts::PI
    }

    /// The luminance, cd/m^2, at which a channel value `v` is seen (panel and reflection).
    #[inline]
    pub fn absolute(&self, v: f64) -> f64 {
        self.black + (self.peak_white - self.black) * v + self.reflected()
    }

    /// The same display at another peak white, its contrast kept (`JOD against luminance`).
    pub fn with_peak(&self, peak_white: f64) -> Self {
        Self { peak_white, black: self.black * peak_white / self.peak_white, ..*self }
    }

    /// Checks every value; errors name `source` and `prefix.<field>`.
    pub fn validate(&self, source: &str, prefix: &str) -> Result<()> {
        let field = |f: &str| if prefix.is_empty() { f.to_string() } else { format!("{prefix}.{f}") };
        if !(self.peak_white.is_finite() && self.peak_white > 0.0) {
            return Err(Error::invalid(
                source,
                field("peak_white"),
                format!("must be a positive luminance in cd/m^2, got {}", self.peak_white),
            ));
        }
        if !(self.black.is_finite() && self.black >= 0.0 && self.black < self.peak_white) {
            return Err(Error::invalid(
                source,
                field("black"),
                format!(
                    "must be a luminance in cd/m^2 of at least 0 and below the peak white ({}), got {}",
                    self.peak_white, self.black
                ),
            ));
        }
        if !(self.ambient_lux.is_finite() && self.ambient_lux >= 0.0) {
            return Err(Error::invalid(
                source,
                field("ambient_lux"),
                format!("must be an illuminance of at least 0 lux, got {}", self.ambient_lux),
            ));
        }
        if !(self.reflectance.is_finite() && (0.0..=1.0).contains(&self.reflectance)) {
            return Err(Error::invalid(
                source,
                field("reflectance"),
                format!("must be between 0 and 1, got {}", self.reflectance),
            ));
        }
        // ColorVideoVDP's numerical domain (its f32 reductions): a million cd/m^2 at most.
        if self.peak_white + self.reflected() > 1e6 {
            return Err(Error::invalid(
                source,
                field("peak_white"),
                format!(
                    "peak white plus reflected ambient light is {} cd/m^2, above the metrics' range (1e6 cd/m^2)",
                    self.peak_white + self.reflected()
                ),
            ));
        }
        Ok(())
    }
}

/// How the images are seen: the display's luminance and the images' pixels per degree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewing {
    /// The display's luminance.
    pub luminance: DisplayLuminance,
    /// Image pixels per degree of visual angle at the image centre.
    pub pixels_per_degree: f64,
}

impl Viewing {
    /// The viewing of retinal images on `retina` (pixels per degree at its centre, where a
    /// pixel spans `2 T / n` in tangent, that many radians) of a display of `luminance`.
    pub fn of_retina(retina: &Retina, luminance: DisplayLuminance) -> Self {
        Self { luminance, pixels_per_degree: retina_pixels_per_degree(retina) }
    }

    /// Checks both parts; errors name `source` and the field.
    pub fn validate(&self, source: &str, prefix: &str) -> Result<()> {
        self.luminance.validate(source, prefix)?;
        if !(self.pixels_per_degree.is_finite() && self.pixels_per_degree > 0.0 && self.pixels_per_degree < 1e4) {
            return Err(Error::invalid(
                source,
                "pixels_per_degree",
                format!("must be positive and below 10000, got {}", self.pixels_per_degree),
            ));
        }
        Ok(())
    }
}

/// Pixels per degree at the centre of `retina`: `n / (2 T)` pixels per radian of tangent.
pub fn retina_pixels_per_degree(retina: &Retina) -> f64 {
    retina.resolution as f64 / (2.0 * retina.half_tangent) * std::f64::consts::PI / 180.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_retina_has_about_fifteen_pixels_per_degree() {
        let r = Retina { resolution: 512, half_tangent: 0.3, samples_per_pixel: 1 };
        // 512 pixels over 0.6 rad of tangent at the centre: 853.3 / rad = 14.89 / degree.
        assert!((retina_pixels_per_degree(&r) - 14.894).abs() < 1e-3);
    }

    #[test]
    fn bad_luminances_name_their_field() {
        let ok = DisplayLuminance::default();
        ok.validate("d.toml", "photometry").unwrap();
        for (bad, field) in [
            (DisplayLuminance { peak_white: 0.0, ..ok }, "photometry.peak_white"),
            (DisplayLuminance { peak_white: -5.0, ..ok }, "photometry.peak_white"),
            (DisplayLuminance { peak_white: f64::NAN, ..ok }, "photometry.peak_white"),
            (DisplayLuminance { black: 200.0, ..ok }, "photometry.black"),
            (DisplayLuminance { black: f64::NAN, ..ok }, "photometry.black"),
            (DisplayLuminance { ambient_lux: -1.0, ..ok }, "photometry.ambient_lux"),
            (DisplayLuminance { reflectance: 2.0, ..ok }, "photometry.reflectance"),
        ] {
            let e = bad.validate("d.toml", "photometry").unwrap_err().to_string();
            assert!(e.contains("d.toml") && e.contains(field), "{e}");
        }
    }

    #[test]
    fn absolute_luminance_spans_black_to_white_plus_reflection() {
        let d = DisplayLuminance { peak_white: 200.0, black: 0.5, ambient_lux: 100.0, reflectance: 0.02 };
        let refl = 0.02 * 100.0 / std::f64::consts::PI;
        assert!((d.absolute(0.0) - (0.5 + refl)).abs() < 1e-12);
        assert!((d.absolute(1.0) - (200.0 + refl)).abs() < 1e-12);
        let h = d.with_peak(2000.0);
        assert!((h.peak_white / h.black - 400.0).abs() < 1e-9);
    }
}
