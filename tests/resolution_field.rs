//! The resolution study off axis (`field_deg`, the chart facing a field direction): a grating is
//! measured at its own frequency there (the ground truth through a thin-lens eye in focus, against
//! the retina pixel's analytic box response), a schematic eye shows its oblique astigmatism (the
//! gratings across and along the meridian peak at foci as far apart as Coddington's equations
//! predict, src/optics/eye/oblique.rs), the default field leaves the study as it was, and a field
//! out of range is refused naming it.

use std::path::Path;

use glam::DVec2;
use inimtrace::measure::sampler::Sampler;
use inimtrace::optics::eye::{oblique_foci, EyeModel, FocusCriterion, Gaze, SchematicEye};
use inimtrace::optics::{Eye, Focus};
use inimtrace::progress::Progress;
use inimtrace::resolution::chart::{Chart, ChartField, Pattern};
use inimtrace::resolution::defocus::{cpd_to_cycles_per_rad, eye_mtf};
use inimtrace::resolution::measure::SceneSource;
use inimtrace::resolution::run::{grating_value, run_study, Value};
use inimtrace::resolution::study::Study;
use inimtrace::resolution::window::measure_windows;

#[test]
fn an_off_axis_grating_in_focus_is_measured_at_its_own_frequency() {
    let ppd: f64 = 64.0;
    let freqs = [0.5, 2.0, 8.0, 12.0];
    let items: Vec<(Pattern, DVec2)> =
        freqs.iter().map(|&f| (Pattern::Grating { frequency_cpd: f }, DVec2::new(2.0, 0.25))).collect();
    let p = (1.0 / ppd).to_radians();
    for (i, field) in [Gaze::new(25.0, 0.0), Gaze::new(-12.0, 18.0)].into_iter().enumerate() {
        for (j, orientation) in [0.0, 90.0].into_iter().enumerate() {
            let chart = Chart::layout(&items, 0.5, ppd, 0.5, 0.8).at_field(field).turned(orientation);
            let depth = 500.0;
            let radiance = ChartField { chart: &chart, depth };
            // The thin lens focused on the content plane: every ray of a retina point meets it at
            // one point, so only the retina pixel's box is left.
            let eye = Eye::thin_lens(4.0, Focus::Millimetres(depth), 8);
            let sampler = Sampler::new(9, (2 * i + j) as u64, Some(2.0));
            let source = SceneSource { eye: &eye, field: &radiance };
            let windows = measure_windows(&source, &sampler, &chart, 6, 32, &Progress::hidden());
            for (patch, w) in chart.patches.iter().zip(&windows) {
                let Pattern::Grating { frequency_cpd: cpd } = patch.pattern else { unreachable!() };
                let g = grating_value(w, 0, cpd, ppd, chart.contrast);
                let analytic = eye_mtf(0.0, p, cpd_to_cycles_per_rad(cpd), 0.0);
                assert!(
                    (g.value - analytic).abs() < 0.01,
                    "{field:?} {orientation} deg, {cpd} cpd: {g:?} vs {analytic}"
                );
            }
        }
    }
}

/// The study of `body` with the common tables.
fn study(body: &str) -> Study {
    let common = r#"
[target]
mean = 0.5
contrast = 0.8
[limits]
contrast = 0.5
frequencies_cpd = [2]
[accommodation]
frequency_cpd = 2
area_limit_cpd = 6
"#;
    Study::from_text(&format!("{body}\n{common}"), "test study", Path::new("."), &[]).unwrap()
}

/// The focus of the parabola through the largest contrast and its two neighbours.
fn peak(focus: &[f64], contrast: &[Value]) -> f64 {
    let i = (1..focus.len() - 1).max_by(|&a, &b| contrast[a].value.total_cmp(&contrast[b].value)).unwrap();
    let (y0, y1, y2) = (contrast[i - 1].value, contrast[i].value, contrast[i + 1].value);
    let h = focus[i + 1] - focus[i];
    focus[i] + 0.5 * h * (y0 - y2) / (y0 - 2.0 * y1 + y2)
}

#[test]
fn a_schematic_eye_off_axis_focuses_the_two_grating_orientations_as_far_apart_as_its_astigmatism() {
    // Navarro 1999, 20 degrees to the right, a 3 mm pupil, one wavelength: the tangential focal
    // line (sharp for modulation along the meridian, 0 degrees) and the sagittal one (90 degrees).
    let s = study(
        r#"
name = "astigmatism"
display = "builtin:paper"
methods = ["LC"]
pupil_diameter_mm = 3.0
content_diopters = [2.0]
focus_diopters = { from = 0.5, to = 3.5, step = 0.125 }
frequencies_cpd = [2, 6]
orientations_deg = [0, 90]
orientations_through_focus = true
field_deg = [20, 0]
[eye]
model = "navarro-1999"
spectrum = "single"
[retina]
pixels_per_degree = 32
window_deg = [1.0, 0.25]
guard_deg = 0.25
edge_window_deg = [1.0, 0.5]
edge_angle_deg = 5.0
[measurement]
samples_per_pixel = 16
replicates = 3
seed = 2
"#,
    );
    assert_eq!(s.field_deg, Gaze::new(20.0, 0.0));
    let r = run_study(&s, true).unwrap();
    let qi = s.frequency_index(6.0).unwrap();
    let at = |oi: usize| -> Vec<Value> { r.grating_at(oi)[0][0].iter().map(|g| g[qi]).collect() };
    let (tangential, sagittal) = (peak(&s.focus_diopters, &at(0)), peak(&s.focus_diopters, &at(1)));
    // Coddington's prediction for the eye accommodated to the content.
    let (eye, _) =
        SchematicEye::focused(&EyeModel::Navarro1999, 2.0, 555.0, FocusCriterion::Paraxial, 3.0, "t", "f").unwrap();
    let a = oblique_foci(&eye, 20.0, 2.0, 555.0).unwrap().astigmatism_d;
    assert!(a > 0.6, "{a}");
    eprintln!(
        "peaks at {tangential:.3} D (0 deg) and {sagittal:.3} D (90 deg): {:.3} D apart; astigmatism {a:.3} D",
        sagittal - tangential
    );
    assert!(
        ((sagittal - tangential) - a).abs() < 0.15,
        "peaks at {tangential} (0 deg) and {sagittal} (90 deg) D; astigmatism {a} D"
    );
}

#[test]
fn the_default_field_is_the_axis_and_a_field_out_of_range_is_refused() {
    let body = |field: &str| {
        format!(
            r#"
name = "f"
display = "builtin:paper"
methods = ["LC"]
pupil_diameter_mm = 3.0
content_diopters = [2.0]
focus_diopters = [2.0]
frequencies_cpd = [2, 6]
{field}
[target]
mean = 0.5
contrast = 0.8
[limits]
contrast = 0.5
frequencies_cpd = [2]
[accommodation]
frequency_cpd = 2
area_limit_cpd = 6
[retina]
pixels_per_degree = 32
window_deg = [1.0, 0.25]
guard_deg = 0.25
edge_window_deg = [1.0, 0.5]
edge_angle_deg = 5.0
[measurement]
samples_per_pixel = 4
replicates = 3
seed = 1
"#
        )
    };
    let load = |field: &str| Study::from_text(&body(field), "f.toml", Path::new("."), &[]);
    let ahead = load("").unwrap();
    assert!(ahead.field_deg.is_ahead());
    assert!(!serde_json::to_string(&ahead).unwrap().contains("field_deg"));
    assert_eq!(Chart::of_study(&ahead), Chart::of_study(&load("field_deg = [0, 0]").unwrap()));
    for bad in ["field_deg = [61, 0]", "field_deg = [50, 40]", "field_deg = [nan, 0]"] {
        let e = load(bad).unwrap_err().to_string();
        assert!(e.contains("field_deg") && e.contains("f.toml"), "{bad}: {e}");
    }
    // Beyond the display's LCD: a warning before the run, not an error.
    let far = load("field_deg = [40, 0]").unwrap();
    let w = inimtrace::resolution::command::plausibility_warnings(&far);
    assert!(w.iter().any(|w| w.contains("field_deg") && w.contains("LCD")), "{w:?}");
    assert!(inimtrace::resolution::command::plausibility_warnings(&ahead).iter().all(|w| !w.contains("field_deg")));
}
