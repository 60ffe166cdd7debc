//! The resolution study with the eye turned (`[eye] gaze_deg` about its centre of rotation) and
//! moved (`[eye] position`), issue #50's MTF maps: the chart goes with the eye, so the thin-lens
//! eye turned by g measures the chart on its line of sight as the eye at rest measures it on the
//! axis, and a ground-truth MTF does not depend on where the pupil is; a method's does once the
//! pupil leaves the display's eye box. PupilCenter renders for the pupil its tracking says. Bad
//! placements are refused naming the field; straight ahead at the origin is the study as it was.

use std::path::Path;

use inimtrace::resolution::chart::Chart;
use inimtrace::resolution::run::{run_study, StudyResults, Value};
use inimtrace::resolution::study::Study;

/// A small study of the paper's display: one content depth with the eye on it, three
/// frequencies, a coarse retina. `eye` and `extra` are added to its `[eye]` table and its top.
fn text(methods: &str, eye: &str, extra: &str) -> String {
    format!(
        r#"
name = "gaze"
display = "builtin:paper"
methods = {methods}
pupil_diameter_mm = 5.0
content_diopters = [2.0]
focus_diopters = [2.0]
frequencies_cpd = [1, 2, 4]
orientations_deg = [0]
{extra}
[eye]
{eye}
[target]
mean = 0.5
contrast = 0.8
[retina]
pixels_per_degree = 32
window_deg = [1.0, 0.25]
guard_deg = 0.25
edge_window_deg = [1.0, 0.5]
edge_angle_deg = 5.0
[measurement]
samples_per_pixel = 4
replicates = 4
seed = 3
[accommodation]
frequency_cpd = 2
area_limit_cpd = 4
[limits]
contrast = 0.5
frequencies_cpd = [2]
"#
    )
}

fn load(methods: &str, eye: &str, extra: &str) -> inimtrace::error::Result<Study> {
    Study::from_text(&text(methods, eye, extra), "gaze.toml", Path::new("."), &[])
}

fn run(methods: &str, eye: &str, extra: &str) -> StudyResults {
    run_study(&load(methods, eye, extra).unwrap(), true).unwrap()
}

/// Every value of source `k` (the gratings and the edge's MTF50 with the eye on the content;
/// NaN where the MTF stays above 0.5 up to the retina's Nyquist frequency).
fn values(r: &StudyResults, k: usize) -> Vec<Value> {
    r.grating[k][0][0].iter().copied().chain([r.mtf50[k][0][0]]).collect()
}

/// The largest difference of two runs' values of source `k` over their combined 95% half-widths.
fn worst(a: &StudyResults, b: &StudyResults, k: usize) -> (f64, f64) {
    let mut ratio: f64 = 0.0;
    let mut diff: f64 = 0.0;
    for (x, y) in values(a, k).iter().zip(values(b, k)) {
        // An MTF50 beyond the retina's Nyquist frequency (the ground truth's) is not measured.
        assert_eq!(x.value.is_nan(), y.value.is_nan(), "{x:?} {y:?}");
        if x.value.is_nan() {
            continue;
        }
        let d = (x.value - y.value).abs();
        diff = diff.max(d);
        ratio = ratio.max(d / x.ci95.hypot(y.ci95).max(1e-12));
    }
    (diff, ratio)
}

#[test]
fn a_turned_eye_measures_the_chart_on_its_line_of_sight_as_the_eye_at_rest_on_the_axis() {
    let rest = run(r#"["LC"]"#, "", "");
    for gaze in ["[10, -6]", "[-12, 0]", "[0, 12]"] {
        let turned = run(r#"["LC"]"#, &format!("gaze_deg = {gaze}"), "");
        let (diff, ratio) = worst(&rest, &turned, 0);
        eprintln!("gaze {gaze}: ground truth differs by at most {diff:.2e} ({ratio:.3} of the intervals)");
        assert!(ratio <= 1.0, "gaze {gaze}: the turned eye's ground truth differs by {ratio} intervals");
        // LC sees the display through other lenslets from a pupil moved about 2 mm: it differs
        // (the eye's rays did turn, not only the chart).
        let (diff, ratio) = worst(&rest, &turned, 1);
        eprintln!("gaze {gaze}: LC differs by up to {diff:.3} ({ratio:.1} intervals)");
        assert!(ratio > 3.0, "gaze {gaze}: LC the same as at rest ({ratio} intervals)");
    }
}

#[test]
fn a_moved_pupil_keeps_the_ground_truth_and_a_method_changes_out_of_the_eye_box() {
    let rest = run(r#"["LC"]"#, "", "");
    let moved = run(r#"["LC"]"#, "position = [1.0, -0.5, 0.0]", "");
    let (diff, ratio) = worst(&rest, &moved, 0);
    eprintln!("pupil at (1, -0.5, 0): ground truth differs by at most {diff:.2e} ({ratio:.3} of the intervals)");
    assert!(ratio <= 1.0, "the moved eye's ground truth differs by {ratio} intervals");
    // 3.5 mm sideways, a 5 mm pupil: most of it outside the paper display's 2.5 mm eye box sees
    // the neighbouring elemental images; the ground truth stays, LC does not.
    let out = run(r#"["LC"]"#, "position = [3.5, 0.0, 0.0]", "");
    assert!(worst(&rest, &out, 0).1 <= 1.0);
    let (diff, ratio) = worst(&rest, &out, 1);
    eprintln!("pupil at (3.5, 0, 0): LC differs by up to {diff:.3} ({ratio:.1} intervals)");
    assert!(ratio > 5.0 && diff > 0.05, "LC out of the eye box: {diff} ({ratio} intervals)");
}

#[test]
fn pupil_center_renders_for_the_pupil_its_tracking_says() {
    let eye = "gaze_deg = [8, 0]";
    let ideal = run(r#"["LC", "PC"]"#, eye, "");
    let none = run(r#"["LC", "PC"]"#, eye, "[display_render]\npupil_tracking = \"none\"");
    assert_eq!(values(&ideal, 1), values(&none, 1), "LC does not aim at the pupil");
    assert_ne!(values(&ideal, 2), values(&none, 2), "PC renders for another pupil");
    let s = load(r#"["PC"]"#, eye, "").unwrap();
    let pose = s.eye_place.pose.unwrap();
    assert_eq!(s.eye_place.pupil_center, pose.pupil_centre);
    // Sideways by 10.26 mm x sin 8 degrees.
    assert!((pose.pupil_centre.x - 10.26 * 8f64.to_radians().sin()).abs() < 1e-9, "{}", pose.pupil_centre);
    let s = load(r#"["PC"]"#, "position = [1, 2, 0]", "[display_render]\ntracking_error_mm = [0.5, 0, 0]").unwrap();
    assert_eq!(s.eye_place.pupil_center.to_array(), [1.5, 2.0, 0.0]);
}

#[test]
fn straight_ahead_at_the_origin_is_the_study_as_it_was() {
    let plain = load(r#"["LC"]"#, "", "").unwrap();
    let stated = load(r#"["LC"]"#, "gaze_deg = [0, 0]\nposition = [0, 0, 0]", "").unwrap();
    assert!(stated.eye_place.pose.is_none() && stated.eye_place.frame().is_none());
    assert_eq!(Chart::of_study(&plain), Chart::of_study(&stated));
    let (a, b) = (run_study(&plain, true).unwrap(), run_study(&stated, true).unwrap());
    for k in 0..2 {
        let bits =
            |r: &StudyResults| values(r, k).iter().map(|v| (v.value.to_bits(), v.ci95.to_bits())).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b));
    }
    assert_eq!(a.lcd_crop, b.lcd_crop);
}

#[test]
fn bad_placements_are_refused_naming_the_field() {
    for (eye, extra, field) in [
        ("gaze_deg = [70, 0]", "", "eye.gaze_deg"),
        // The line of sight from the turned pupil meets the LCD plane off the 21.6 mm panel.
        ("gaze_deg = [20, 0]", "", "eye.gaze_deg"),
        ("gaze_deg = [nan, 0]", "", "eye.gaze_deg"),
        ("gaze_deg = [5, 0]\ncentre_of_rotation_mm = -1", "", "eye.centre_of_rotation_mm"),
        ("position = [0, 0, 25]", "", "eye.position"),
        ("position = [nan, 0, 0]", "", "eye.position"),
        ("position = [1e6, 0, 0]", "", "eye.position[0]"),
        ("gaze_deg = [5, 0]", "[display_render]\npupil_tracking = \"sometimes\"", "display_render.pupil_tracking"),
        (
            "",
            "[display_render]\npupil_tracking = \"none\"\ntracking_error_mm = [1, 0, 0]",
            "display_render.tracking_error_mm",
        ),
        ("", "[display_render]\neye_position = [0, 0, 0]", "eye_position"),
    ] {
        let e = load(r#"["LC", "PC"]"#, eye, extra).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains("gaze.toml"), "{eye} {extra}: {e}");
    }
}

/// display.md says where the study's eye was: its gaze about the centre of rotation and its
/// pupil's position when moved, nothing at rest (the line as before the eye could move).
#[test]
fn display_md_names_a_turned_or_moved_eye_and_not_an_eye_at_rest() {
    use inimtrace::resolution::limits::display_limits;
    use inimtrace::resolution::report::display_md;
    let md = |eye: &str| {
        let study = load(r#"["LC"]"#, eye, "").unwrap();
        display_md(&display_limits(&study.display, study.pupil_diameter_mm), &study)
    };
    let rest = md("");
    assert!(rest.contains("Study `gaze`, pupil 5 mm.\n"), "{rest}");
    let turned = md("gaze_deg = [6, -3]\ncentre_of_rotation_mm = 12");
    // 12 mm behind the cornea, which lies 3.04 mm in front of the thin-lens eye's pupil
    // (Navarro's depth, docs/EYE.md): z = 3.04 - 12 = -8.96 mm.
    assert!(turned.contains("gaze [6, -3] degrees about the centre of rotation (0, 0, -8.96) mm.\n"), "{turned}");
    assert!(!turned.contains("pupil at"), "{turned}");
    let moved = md("position = [1.5, -0.5, 0]");
    assert!(moved.contains("Study `gaze`, pupil 5 mm, pupil at (1.5, -0.5, 0) mm.\n"), "{moved}");
    assert!(!moved.contains("gaze ["), "{moved}");
}
