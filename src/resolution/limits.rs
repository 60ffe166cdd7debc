//! The display's own limits (the paper's conclusion: "to profile the capabilities of
//! the given display itself"; its Sec. 2.2 trade-off of views through the pupil against spatial
//! resolution): the design quantities of [`crate::info::display_design`] in the units of the
//! resolution study (pixels per degree, Nyquist in cpd), the views a point at the central depth
//! plane (CDP) sends through the pupil, and, from the measured study, the content depths over
//! which each source keeps a stated contrast.
//!
//! **The analytic property of the display path** ([`lc_cdp_contrast`]): content at the CDP seen
//! with the eye focused there. LC samples the content at each LCD pixel's image on the CDP (the
//! chief ray through its lenslet's centre meets the CDP at the centre of the pixel's image) and
//! each pixel shows that sample over its whole image, a box of `a` degrees (the angular pixel
//! pitch at the CDP). The lenslets in the pupil show the same samples with different phases, so
//! aliases from each partly cancel, but the component at the grating's own frequency `f` is
//! `sinc(pi f a)` for every phase. The retina pixel (`s` degrees) multiplies by `sinc(pi f s)`:
//! contrast `|sinc(pi f a) sinc(pi f s)|`, whose first zero is at `f = 1/a`, the display's pixels
//! per degree, twice its Nyquist frequency. `tests/resolution_study.rs` measures it.

use serde::Serialize;

use super::run::StudyResults;
use crate::info::{display_design, DisplayParameters};
use crate::optics::Display;

/// The content depths over which one source keeps `contrast` at one frequency (eye focused on
/// the content).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DepthRange {
    /// "ground_truth" or a method's short name.
    pub source: String,
    /// The frequency, cpd.
    pub frequency_cpd: f64,
    /// The contrast threshold (relative to the target's).
    pub contrast: f64,
    /// Every measured content depth (diopters) where the grating contrast is above `contrast`.
    pub passing_diopters: Vec<f64>,
    /// The longest run of consecutive measured depths that pass: nearest and farthest, diopters
    /// (`None`: none passes).
    pub range_diopters: Option<[f64; 2]>,
    /// The same run in mm from the pupil: farthest, nearest.
    pub range_mm: Option<[f64; 2]>,
}

/// `display.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DisplayLimits {
    /// The display's parameters.
    pub display: DisplayParameters,
    /// The pupil the limits are for, mm.
    pub pupil_diameter_mm: f64,
    /// The central depth plane, mm from the pupil (`None`: at infinity or virtual).
    pub central_depth_plane_mm: Option<f64>,
    /// The same, dioptres.
    pub central_depth_plane_diopters: Option<f64>,
    /// One LCD pixel's image at the CDP seen from the pupil centre, arcmin (x, y).
    pub angular_pixel_pitch_arcmin: Option<[f64; 2]>,
    /// Pixels per degree at the CDP, x and y.
    pub pixels_per_degree: Option<[f64; 2]>,
    /// Half the pixels per degree.
    pub nyquist_cpd: Option<[f64; 2]>,
    /// One lenslet seen from the pupil centre: pitch over the eye relief, degrees.
    pub lenslet_angular_pitch_deg: [f64; 2],
    /// Views per axis a point on the axis at the CDP sends through the pupil: the pupil diameter
    /// over the spacing of its rays through neighbouring lenslet centres at the pupil.
    pub views_across_pupil: Option<[f64; 2]>,
    /// Rays of that point through lenslet centres that enter the pupil disk.
    pub views_in_pupil: Option<usize>,
    /// v1: pupil to lenslets, mm.
    pub eye_relief_mm: f64,
    /// Width and height of the eye box, mm (`None`: the viewing zones share no point).
    pub eye_box_mm: Option<[f64; 2]>,
    /// Field of view, horizontal and vertical, degrees.
    pub field_of_view_deg: [f64; 2],
    /// The analytic property (module documentation): LC's contrast at the CDP falls to its
    /// first zero here, cpd (x).
    pub lc_cdp_first_zero_cpd: Option<f64>,
    /// Content depths over which each source keeps the limits' contrast.
    pub depth_ranges: Vec<DepthRange>,
}

/// LC's contrast for content at the CDP with the eye focused there (module documentation), for
/// an angular pixel pitch `a_deg` and retina pixels of `s_deg`.
pub fn lc_cdp_contrast(frequency_cpd: f64, a_deg: f64, s_deg: f64) -> f64 {
    let sinc = |x: f64| if x.abs() < 1e-12 { 1.0 } else { x.sin() / x };
    (sinc(std::f64::consts::PI * frequency_cpd * a_deg) * sinc(std::f64::consts::PI * frequency_cpd * s_deg)).abs()
}

/// The design limits of `display` for a pupil of `pupil_diameter` mm (no depth ranges).
pub fn display_limits(display: &Display, pupil_diameter: f64) -> DisplayLimits {
    let d = display_design(display, pupil_diameter);
    let cdp = display.central_depth_plane();
    // A real lenslet's centre is seen at its front principal (nodal) plane, as `info` reads it.
    let (v1, _) = display.principal_plane_distances();
    let lenslet = display.lenslets.reduced_matrix();
    let pitch = [lenslet.x_axis.length(), lenslet.y_axis.length()];
    DisplayLimits {
        display: d.display.clone(),
        pupil_diameter_mm: pupil_diameter,
        central_depth_plane_mm: cdp,
        central_depth_plane_diopters: cdp.map(|z| 1000.0 / z),
        angular_pixel_pitch_arcmin: d.angular_pixel_pitch_arcmin,
        pixels_per_degree: d.pixels_per_degree,
        nyquist_cpd: d.pixels_per_degree.map(|p| [0.5 * p[0], 0.5 * p[1]]),
        lenslet_angular_pitch_deg: [(pitch[0] / v1).atan().to_degrees(), (pitch[1] / v1).atan().to_degrees()],
        views_across_pupil: d.views_across_pupil,
        views_in_pupil: d.views_in_pupil,
        eye_relief_mm: d.eye_relief_mm,
        eye_box_mm: d.eye_box_mm,
        field_of_view_deg: d.field_of_view_deg,
        lc_cdp_first_zero_cpd: d.pixels_per_degree.map(|p| p[0]),
        depth_ranges: Vec::new(),
    }
}

/// The depth ranges of every source at the study's `[limits]` frequencies.
pub fn depth_ranges(results: &StudyResults) -> Vec<DepthRange> {
    let s = &results.study;
    let mut out = Vec::new();
    for (k, source) in results.sources.iter().enumerate() {
        for &f in &s.limits.frequencies_cpd {
            let qi = s.frequency_index(f).expect("validated: a study frequency");
            let pass: Vec<bool> = s
                .depths
                .iter()
                .enumerate()
                .map(|(di, d)| {
                    let fi = s.focus_index(d.diopters).expect("content depths are measured focuses");
                    results.grating[k][di][fi][qi].value > s.limits.contrast
                })
                .collect();
            let passing: Vec<f64> = s.depths.iter().zip(&pass).filter(|(_, p)| **p).map(|(d, _)| d.diopters).collect();
            // Longest run of consecutive passing depths.
            let (mut best, mut start) = (None::<(usize, usize)>, None::<usize>);
            for i in 0..=pass.len() {
                let on = i < pass.len() && pass[i];
                match (on, start) {
                    (true, None) => start = Some(i),
                    (false, Some(a)) => {
                        if best.is_none_or(|(b0, b1)| i - a > b1 - b0 + 1) {
                            best = Some((a, i - 1));
                        }
                        start = None;
                    }
                    _ => {}
                }
            }
            let range = best.map(|(a, b)| [s.depths[a].diopters, s.depths[b].diopters]);
            out.push(DepthRange {
                source: source.clone(),
                frequency_cpd: f,
                contrast: s.limits.contrast,
                passing_diopters: passing,
                range_diopters: range,
                range_mm: best.map(|(a, b)| [s.depths[a].mm, s.depths[b].mm]),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_display_limits_are_its_design_numbers() {
        let l = display_limits(&Display::paper(), 5.0);
        let cdp = l.central_depth_plane_mm.unwrap();
        // 1/v2 - 1/f = 1/d: d = 365.7 mm, CDP at 385.7 mm.
        assert!((cdp - (20.0 + 1.0 / (1.0 / 6.316 - 1.0 / 6.427))).abs() < 1e-9);
        // A 10 um pixel magnified (z - v1) / v2 and seen from z: 0.0859 degree, 11.6 px/deg.
        let ppd = l.pixels_per_degree.unwrap()[0];
        let a = 0.01 * (cdp - 20.0) / (6.316 * cdp);
        assert!((ppd - 1.0 / a.to_degrees()).abs() < 1e-9 && (ppd - 11.63).abs() < 0.01, "{ppd}");
        assert!((l.nyquist_cpd.unwrap()[0] - 0.5 * ppd).abs() < 1e-12);
        // 1.2 mm lenslets at 20 mm: 3.43 degrees.
        assert!((l.lenslet_angular_pitch_deg[0] - 3.434).abs() < 1e-3);
        // The paper's "4 x 4 rays within the pupil": 5 mm over 1.2 x 385.7 / 365.7 mm.
        let v = l.views_across_pupil.unwrap()[0];
        assert!((v - 5.0 / (1.2 * cdp / (cdp - 20.0))).abs() < 1e-12 && v.round() == 4.0, "{v}");
        // Within the disk: the centre, 4 neighbours and 4 diagonals (1.79 mm from the axis).
        assert_eq!(l.views_in_pupil, Some(9));
        assert_eq!(l.lc_cdp_first_zero_cpd, Some(ppd));
    }

    #[test]
    fn the_lc_model_has_its_first_zero_at_the_pixels_per_degree() {
        let (a, s) = (1.0 / 11.64, 1.0 / 64.0);
        assert!(lc_cdp_contrast(11.64, a, s) < 1e-12);
        assert!(lc_cdp_contrast(11.0, a, s) > lc_cdp_contrast(11.5, a, s));
        assert!((lc_cdp_contrast(0.0, a, s) - 1.0).abs() < 1e-12);
        // At the Nyquist frequency the display box alone gives 2 / pi.
        assert!((lc_cdp_contrast(5.82, a, 1e-9) - 2.0 / std::f64::consts::PI).abs() < 1e-3);
    }
}
