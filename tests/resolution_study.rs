//! `inimtrace resolution` end to end: the tiny study's files with their exact names
//! and columns, the ground truth's predicted accommodation against the content depth, and the
//! analytic property of the display path (LC's contrast for content at the central depth plane).

use std::path::Path;
use std::process::Command;

use inimtrace::resolution::limits::{display_limits, lc_cdp_contrast};
use inimtrace::resolution::report::accommodation_rows;
use inimtrace::resolution::run::run_study;
use inimtrace::resolution::study::Study;

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn the_tiny_study_writes_every_file_with_the_issue_columns() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r");
    let st = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "resolution", "studies/tiny.toml", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    for f in [
        "mtf.csv",
        "mtf50.csv",
        "accommodation.csv",
        "study.json",
        "display.md",
        "display.json",
        "mtf.png",
        "mtf.svg",
        "through_focus.png",
        "through_focus.svg",
        "accommodation.png",
        "accommodation.svg",
        "orientations.png",
        "orientations.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let mtf = read(&out, "mtf.csv");
    let mut lines = mtf.lines();
    assert_eq!(
        lines.next().unwrap(),
        "source,target_diopters,focus_diopters,frequency_cpd,orientation_deg,measure,contrast,contrast_ci95,\
         samples_per_pixel,replicates"
    );
    // 3 sources x 2 depths x 3 focuses (1, 2, 3 D; 2.5 D added) ... 4 focuses x 3 frequencies x 2
    // measures; and the gratings at the default 45, 90 and 135 degrees with the eye on the content.
    assert_eq!(lines.count(), 3 * 2 * 4 * 3 * 2 + 3 * 3 * 2 * 3);
    assert!(mtf.contains("\nground_truth,1,1,2,0,grating,") && mtf.contains(",edge,"));
    assert!(mtf.contains("\nground_truth,1,1,2,45,grating,") && mtf.contains("\nPC,2.5,2.5,4,135,grating,"));
    assert_eq!(
        read(&out, "mtf50.csv").lines().next().unwrap(),
        "source,target_diopters,focus_diopters,mtf50_cpd,mtf50_ci95,samples_per_pixel,replicates"
    );
    let acc = read(&out, "accommodation.csv");
    assert_eq!(
        acc.lines().next().unwrap(),
        "source,target_diopters,rule,frequency_cpd,predicted_focus_diopters,predicted_focus_ci95,grid_edge,\
         contrast_at_peak,contrast_at_peak_ci95,samples_per_pixel,replicates"
    );
    assert_eq!(acc.lines().count(), 1 + 3 * 2 * 2);
    // Every row carries its precision: a finite positive half-width (the ground truth's too: the
    // pupil is sampled), and the study's samples per pixel over all its replicates.
    let tiny = read(Path::new("studies"), "tiny.toml");
    let setting = |key: &str| -> u64 {
        let line = tiny.lines().find(|l| l.trim_start().starts_with(key)).unwrap();
        line.split('=').nth(1).unwrap().split('#').next().unwrap().trim().parse().unwrap()
    };
    let (spp, reps) = (setting("samples_per_pixel"), setting("replicates"));
    let tail = format!(",{},{reps}", spp * reps);
    for row in acc.lines().skip(1) {
        assert!(row.ends_with(&tail), "{row}: not {tail}");
        let cells: Vec<&str> = row.split(',').collect();
        let ci95: f64 = cells[8].parse().unwrap_or(f64::NAN);
        assert!(ci95.is_finite() && ci95 > 0.0, "{row}");
        // The ground truth of content at 1 D peaks on the focus grid's floor (1, 2, 3 D): flagged,
        // with no interval; content at 2.5 D peaks inside the grid, with a finite interval.
        let (focus, edge) = (cells[4].parse::<f64>().unwrap(), cells[6]);
        let focus_ci95: f64 = cells[5].parse().unwrap_or(f64::NAN);
        match (cells[0], cells[1]) {
            ("ground_truth", "1") => assert!(edge == "floor" && focus == 1.0 && cells[5].is_empty(), "{row}"),
            ("ground_truth", "2.5") => {
                assert!(edge.is_empty() && focus_ci95 > 0.0 && focus_ci95 < 0.5, "{row}")
            }
            _ => assert_eq!(edge.is_empty(), focus > 1.0 && focus < 3.0, "{row}"),
        }
    }
    for row in mtf.lines().skip(1).chain(read(&out, "mtf50.csv").lines().skip(1)) {
        assert!(row.ends_with(&tail), "{row}: not {tail}");
    }
    let json: serde_json::Value = serde_json::from_str(&read(&out, "study.json")).unwrap();
    assert_eq!(json["study"]["pupil_diameter_mm"], 5.0);
    assert_eq!(json["study"]["retina_pixel_deg"], 1.0 / 32.0);
    assert_eq!(json["sources"], serde_json::json!(["ground_truth", "LC", "PC"]));
    assert!(json["timings"].as_array().unwrap().len() >= 6);
    assert!(json["files"].as_array().unwrap().iter().any(|f| f["name"] == "mtf.csv"));
    let display: serde_json::Value = serde_json::from_str(&read(&out, "display.json")).unwrap();
    assert!((display["pixels_per_degree"][0].as_f64().unwrap() - 11.63).abs() < 0.01);
    assert!(read(&out, "display.md").contains("| LC | 1 |"));

    // A bad study names the file and the field, and writes nothing.
    let bad = tmp.path().join("bad.toml");
    std::fs::write(&bad, read(Path::new("studies"), "tiny.toml").replace("[1, 2, 4]", "[1, 2, 4.3]")).unwrap();
    let st = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "resolution"])
        .arg(&bad)
        .arg("--out")
        .arg(tmp.path().join("b"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&st.stderr);
    assert!(!st.status.success() && e.contains("bad.toml") && e.contains("frequencies_cpd[2]"), "{e}");

    // The same mistake made by --set: the error names the override as well as the file.
    let st = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "resolution", "studies/tiny.toml", "--set", "frequencies_cpd=[1, 2, 4.3]", "--out"])
        .arg(tmp.path().join("c"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&st.stderr);
    assert!(
        !st.status.success()
            && e.contains("tiny.toml with --set frequencies_cpd=[1, 2, 4.3]")
            && e.contains("frequencies_cpd[2]"),
        "{e}"
    );

    // The study folder records its inputs' hashes, and `info --provenance` checks them again.
    let json: serde_json::Value = serde_json::from_str(&read(&out, "study.json")).unwrap();
    let p = &json["provenance"];
    assert_eq!(p["study_path"], "studies/tiny.toml");
    let tiny = std::fs::read("studies/tiny.toml").unwrap();
    let file =
        p["files"].as_array().unwrap().iter().find(|f| f["path"] == "studies/tiny.toml").expect("the study file");
    assert_eq!(file["sha256"], inimtrace::provenance::sha256_hex(&tiny));
    assert_eq!(file["bytes"], tiny.len() as u64);
    assert_eq!(p["seed"], 1);
    let info = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(["info", "--provenance"]).arg(&out).output().unwrap();
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(info.status.success(), "{}", String::from_utf8_lossy(&info.stderr));
    assert!(
        text.contains("study studies/tiny.toml")
            && text.contains("unchanged")
            && text.contains("all 1 input file unchanged"),
        "{text}"
    );
}

/// A study of `body` plus the common tables.
fn study(body: &str) -> Study {
    let common = r#"
[target]
mean = 0.5
contrast = 0.8
[measurement]
samples_per_pixel = 8
replicates = 4
seed = 3
[limits]
contrast = 0.5
frequencies_cpd = [1]
"#;
    Study::from_text(&format!("{body}\n{common}"), "test study", Path::new("."), &[]).unwrap()
}

#[test]
fn the_ground_truth_predicts_focus_at_the_content_depth() {
    // Issue 13: within 0.05 D at every depth, by both rules.
    let s = study(
        r#"
name = "gt"
display = "builtin:paper"
methods = []
pupil_diameter_mm = 5.0
content_diopters = [0.5, 1.3, 2.2, 3.5]
focus_diopters = { from = 0.0, to = 4.0, step = 0.25 }
frequencies_cpd = [1, 2, 4]
orientations_deg = [0]
[retina]
pixels_per_degree = 64
window_deg = [1.0, 0.125]
guard_deg = 0.5
edge_window_deg = [1.0, 0.25]
edge_angle_deg = 5.0
[accommodation]
frequency_cpd = 2
area_limit_cpd = 4
"#,
    );
    let r = run_study(&s, true).unwrap();
    let rows = accommodation_rows(&r);
    assert_eq!(rows.len(), 4 * 2);
    for a in &rows {
        assert!(
            (a.predicted_focus_diopters - a.target_diopters).abs() < 0.05,
            "{} at {} D: {} D",
            a.rule,
            a.target_diopters,
            a.predicted_focus_diopters
        );
        assert!(a.contrast_at_peak > 0.95, "{a:?}");
    }
}

#[test]
fn lc_at_the_central_depth_plane_has_the_display_pixel_box_mtf() {
    // The analytic property (src/resolution/limits.rs): content at the CDP, the eye focused
    // there, LC's contrast at frequency f is |sinc(pi f a) sinc(pi f s)|, a the angular pixel
    // pitch (first zero at the display's pixels per degree, 11.6 cpd), s the retina pixel. A 3 mm
    // pupil sees 3 x 3 lenslets, every ray inside its lenslet's own elemental image (at 5 mm the
    // outermost rays land one pixel past it: crosstalk, which lowers the contrast further).
    let cdp = inimtrace::optics::Display::paper().central_depth_plane().unwrap();
    let s = study(&format!(
        r#"
name = "cdp"
display = "builtin:paper"
methods = ["LC"]
pupil_diameter_mm = 3.0
content_diopters = []
content_mm = [{cdp}]
focus_diopters = [{}]
frequencies_cpd = [1, 2, 3, 4, 8, 11.5]
orientations_deg = [0]
[retina]
pixels_per_degree = 64
window_deg = [2.0, 0.25]
guard_deg = 0.25
edge_window_deg = [2.0, 0.5]
edge_angle_deg = 5.0
[accommodation]
frequency_cpd = 2
area_limit_cpd = 4
"#,
        1000.0 / cdp
    ));
    let r = run_study(&s, true).unwrap();
    let l = display_limits(&s.display, 3.0);
    let ppd = l.pixels_per_degree.unwrap()[0];
    let lc = &r.grating[1][0][0];
    for (f, v) in s.frequencies_cpd.iter().zip(lc) {
        let model = lc_cdp_contrast(*f, 1.0 / ppd, 1.0 / 64.0);
        eprintln!("{f} cpd: measured {:.4} +- {:.4}, model {model:.4}", v.value, v.ci95);
    }
    // Within 0.02 up to 0.7 of the display's Nyquist frequency (5.8 cpd); beyond it, where an
    // alias can fall within the window's frequency resolution (0.5 cpd) of f, within 0.03; and
    // at 11.5 cpd, next to the zero, no contrast left.
    for (f, v) in s.frequencies_cpd.iter().zip(lc) {
        let model = lc_cdp_contrast(*f, 1.0 / ppd, 1.0 / 64.0);
        let tol = if *f <= 0.7 * 0.5 * ppd { 0.02 } else { 0.03 };
        assert!((v.value - model).abs() < tol, "{f} cpd: measured {v:?}, model {model}");
    }
    assert!(lc[5].value < 0.02 && (ppd - 11.63).abs() < 0.01);
}
