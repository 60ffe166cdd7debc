//! The field the eye adapts to, for the light-adapted pupil (`pupil_diameter = "auto"`,
//! [`crate::optics::eye::pupil`], Watson & Yellott 2012): a near-eye display fills the eye's view
//! with its LCD, so the adapting field is the display's field of view as seen from the pupil
//! centre (the LCD's angular width times its angular height, deg^2: `2 atan(W / 2 (v1 + v2))` by
//! `2 atan(H / 2 (v1 + v2))`, `inimtrace info`'s field of view), and its luminance is the mean
//! luminance of the scene across that field as a perfect display of the display's photometry shows
//! it: the radiance along chief rays from the pupil centre on a 64 x 64 grid uniform in angle,
//! each weighted by the primaries' luminance shares and mapped to cd/m^2
//! ([`crate::optics::photometry`]). This is the ground truth's mean luminance over the display's
//! field; every method shows about the same mean (the display images are the scene), so the pupil
//! is one for the ground truth and every perceived image.

use glam::DVec3;

use super::field::RadianceField;
use crate::error::Result;
use crate::optics::eye::pupil::{AutoPupil, Observer};
use crate::optics::Display;
use crate::ray::Ray;
use crate::scene::Scene;

/// Chief rays per axis of the adapting field's grid.
pub const GRID: usize = 64;

/// The light-adapted pupil of `observer` for `scene` shown by `display` to an eye at `eye`
/// (module comment), traced with the backend `auto` chooses.
pub fn auto_pupil(scene: &Scene, display: &Display, eye: DVec3, observer: Observer) -> Result<AutoPupil> {
    let (luminance, area) = super::backend::with_fields(scene, super::backend::BackendChoice::Auto, |f| {
        Ok(adapting_field(f.shade, display, eye))
    })?;
    Ok(AutoPupil::new(observer, luminance, area))
}

/// The adapting field of `display` seen from `eye` (the pupil centre) over the scene `field`:
/// `(mean luminance cd/m^2, area deg^2)` (module comment).
pub fn adapting_field(field: &dyn RadianceField, display: &Display, eye: DVec3) -> (f64, f64) {
    let half = display.field_half_angles();
    let area = display.field_area_deg2();
    let (photometry, weights) = (display.photometry(), display.luminance_weights());
    let mut sum = 0.0;
    for r in 0..GRID {
        let ay = half[1] * (1.0 - 2.0 * (r as f64 + 0.5) / GRID as f64);
        for c in 0..GRID {
            let ax = half[0] * (2.0 * (c as f64 + 0.5) / GRID as f64 - 1.0);
            let ray = Ray { origin: eye, dir: DVec3::new(ax.tan(), ay.tan(), 1.0) };
            let l = field.radiance(&ray);
            sum += weights[0] * l.x + weights[1] * l.y + weights[2] * l.z;
        }
    }
    (photometry.absolute(sum / (GRID * GRID) as f64), area)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Uniform(DVec3);
    impl RadianceField for Uniform {
        fn radiance(&self, _: &Ray) -> DVec3 {
            self.0
        }
    }

    #[test]
    fn a_uniform_white_field_adapts_to_peak_white_over_the_display_field() {
        let d = Display::paper();
        let (l, a) = adapting_field(&Uniform(DVec3::ONE), &d, DVec3::ZERO);
        assert!((l - d.photometry().white()).abs() < 1e-9, "{l}");
        let fov = 2.0 * (10.8f64 / 26.316).atan().to_degrees();
        assert!((a - fov * fov).abs() < 1e-9, "{a}");
        let (black, _) = adapting_field(&Uniform(DVec3::ZERO), &d, DVec3::ZERO);
        assert!((black - d.photometry().black_floor()).abs() < 1e-12);
    }
}
