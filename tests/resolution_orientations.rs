//! Gratings at several orientations in the resolution study (the chart turned about the axis):
//! a turned grating is measured at its own frequency (the ground truth through a thin-lens eye
//! against the analytic defocus MTF, at 30, 45 and 135 degrees as at 0), the square paper display
//! shows the same contrast at 0 and 90 degrees, and the study's files carry the orientation.

use std::path::Path;

use glam::DVec2;
use inimtrace::measure::sampler::Sampler;
use inimtrace::optics::{Eye, Focus};
use inimtrace::progress::Progress;
use inimtrace::resolution::chart::{Chart, ChartField, Pattern};
use inimtrace::resolution::defocus::{blur_diameter_rad, cpd_to_cycles_per_rad, defocus_first_zero, eye_mtf};
use inimtrace::resolution::grating;
use inimtrace::resolution::measure::SceneSource;
use inimtrace::resolution::run::{grating_value, run_study};
use inimtrace::resolution::study::Study;
use inimtrace::resolution::window::measure_windows;

const PUPIL_MM: f64 = 4.0;

#[test]
fn a_turned_grating_of_the_ground_truth_follows_the_analytic_defocus_mtf_at_its_own_frequency() {
    let ppd = 64.0;
    let freqs = [0.5, 2.0, 4.0, 8.0];
    let items: Vec<(Pattern, DVec2)> =
        freqs.iter().map(|&f| (Pattern::Grating { frequency_cpd: f }, DVec2::new(2.0, 0.25))).collect();
    let chart = Chart::layout(&items, 0.5, ppd, 0.5, 0.8);
    let p = (1.0 / ppd).to_radians();
    let target_d = 2.0;
    let orientations = [0.0, 45.0, 135.0, 30.0];
    let mut worst = [0.0f64; 4];
    for (oi, &o) in orientations.iter().enumerate() {
        let turned = chart.turned(o);
        let field = ChartField { chart: &turned, depth: 1000.0 / target_d };
        for (i, focus_d) in [2.0, 2.25].into_iter().enumerate() {
            let eye = Eye::thin_lens(PUPIL_MM, Focus::Diopters(focus_d), 8);
            let sampler = Sampler::new(5, (oi * 2 + i) as u64, Some(0.5 * PUPIL_MM));
            let source = SceneSource { eye: &eye, field: &field };
            let windows = measure_windows(&source, &sampler, &turned, 8, 64, &Progress::hidden());
            let b = blur_diameter_rad(PUPIL_MM, target_d, focus_d);
            let zero_cpd = if b == 0.0 { f64::INFINITY } else { defocus_first_zero(b) * std::f64::consts::PI / 180.0 };
            for (patch, w) in turned.patches.iter().zip(&windows) {
                let Pattern::Grating { frequency_cpd: cpd } = patch.pattern else { unreachable!() };
                if cpd > 0.98 * zero_cpd {
                    continue;
                }
                // The window's pixels are cut in the turned frame: the pixel box acts along the
                // modulation as at 0 degrees.
                let g = grating_value(w, 0, cpd, ppd, chart.contrast);
                let analytic = eye_mtf(b, p, cpd_to_cycles_per_rad(cpd), 0.0);
                eprintln!("{o} deg, focus {focus_d} D, {cpd} cpd: {:.4} +- {:.4} vs {analytic:.4}", g.value, g.ci95);
                worst[oi] = worst[oi].max((g.value - analytic).abs());
                assert!((g.value - analytic).abs() < 0.02, "{o} deg, focus {focus_d}, {cpd} cpd: {g:?} vs {analytic}");
                // Negative control: the same window read for a grating across it (90 degrees off
                // in its own frame; two periods over its 0.25 degree height at 8 cpd) finds none.
                if cpd >= 8.0 {
                    let across = grating::modulation(w, 0, cpd / ppd, 90.0).unwrap();
                    assert!(across.contrast / chart.contrast < 0.05, "{cpd} cpd across: {across:?}");
                }
            }
        }
    }
    eprintln!("worst deviation from the analytic MTF by orientation {orientations:?}: {worst:?}");
}

/// The study of `body` with the common tables.
fn study(body: &str) -> Study {
    let common = r#"
[target]
mean = 0.5
contrast = 0.8
[measurement]
samples_per_pixel = 8
replicates = 8
seed = 3
[limits]
contrast = 0.5
frequencies_cpd = [1]
[retina]
pixels_per_degree = 64
window_deg = [2.0, 0.25]
guard_deg = 0.25
edge_window_deg = [2.0, 0.5]
edge_angle_deg = 5.0
[accommodation]
frequency_cpd = 2
area_limit_cpd = 4
"#;
    Study::from_text(&format!("{body}\n{common}"), "test study", Path::new("."), &[]).unwrap()
}

#[test]
fn the_square_paper_display_shows_no_anisotropy_between_0_and_90_degrees() {
    let cdp = inimtrace::optics::Display::paper().central_depth_plane().unwrap();
    let s = study(&format!(
        r#"
name = "square"
display = "builtin:paper"
methods = ["LC"]
pupil_diameter_mm = 3.0
content_diopters = [1.0]
content_mm = [{cdp}]
focus_diopters = [1.0]
frequencies_cpd = [1, 2, 3, 4]
orientations_deg = [90, 0, 45]
"#
    ));
    assert_eq!(s.orientations_deg, [0.0, 45.0, 90.0]);
    let r = run_study(&s, true).unwrap();
    assert_eq!(r.oriented.len(), 2);
    assert_eq!(r.oriented[1].orientation_deg, 90.0);
    let mut worst: f64 = 0.0;
    for k in 0..2 {
        for di in 0..2 {
            let fi = s.focus_index(s.depths[di].diopters).unwrap();
            for (qi, f) in s.frequencies_cpd.iter().enumerate() {
                let a = r.grating[k][di][fi][qi];
                let b = r.oriented[1].grating[k][di][fi][qi];
                let c = r.oriented[0].grating[k][di][fi][qi];
                eprintln!(
                    "{} at {:.3} D, {f} cpd: 0 deg {:.4} +- {:.4}, 90 deg {:.4} +- {:.4}, 45 deg {:.4} +- {:.4}",
                    r.sources[k], s.depths[di].diopters, a.value, a.ci95, b.value, b.ci95, c.value, c.ci95
                );
                assert!(a.value.is_finite() && b.value.is_finite() && c.value.is_finite());
                worst = worst.max((a.value - b.value).abs() / (a.ci95 + b.ci95));
                assert!(
                    (a.value - b.value).abs() <= a.ci95 + b.ci95,
                    "{} at {} D, {f} cpd: 0 deg {a:?} vs 90 deg {b:?}",
                    r.sources[k],
                    s.depths[di].diopters
                );
            }
        }
    }
    eprintln!("largest |0 - 90| over the sum of the half-widths: {worst:.3}");
}

#[test]
fn the_study_files_carry_the_orientation_and_the_0_degree_rows_stay_first() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "resolution", "studies/tiny.toml", "--set", "orientations_deg=[0, 90]", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let mtf = std::fs::read_to_string(out.join("mtf.csv")).unwrap();
    // 3 sources x 2 depths x 4 focuses x 3 frequencies x (grating 0, edge), and the 90-degree
    // gratings with the eye on the content: 3 sources x 2 depths x 3 frequencies.
    assert_eq!(mtf.lines().count(), 1 + 3 * 2 * 4 * 3 * 2 + 3 * 2 * 3);
    // The first block: ground truth, content 1 D, focus 1 D (on the content).
    let block: Vec<&str> = mtf.lines().skip(1).take(10).collect();
    assert!(block[..3].iter().all(|l| l.starts_with("ground_truth,1,1,") && l.contains(",0,grating,")), "{block:?}");
    assert!(block[3..6].iter().all(|l| l.contains(",5,edge,")), "{block:?}");
    assert!(block[6..9].iter().all(|l| l.contains(",90,grating,")), "{block:?}");
    assert!(block[9].starts_with("ground_truth,1,2,") && block[9].contains(",0,grating,"), "{block:?}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("study.json")).unwrap()).unwrap();
    assert_eq!(json["study"]["orientations_deg"], serde_json::json!([0.0, 90.0]));
    let md = std::fs::read_to_string(out.join("display.md")).unwrap();
    assert!(md.contains("| source | content (D) | frequency (cpd) | 0 deg | 90 deg | spread |"), "{md}");
    assert!(out.join("orientations.png").is_file() && out.join("orientations.svg").is_file());
}
