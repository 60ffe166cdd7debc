//! The perceptual scores against the metrics' reference implementations, on this tool's own
//! retinal images (docs/PERCEPTION.md): nine pairs (LC, PC and LA perceived by a pinhole eye and
//! eyes focused at 300 and 600 mm, each at one of 10, 100 and 1000 cd/m^2), each scored by
//! inimtrace and by `scripts/perception-reference.py` with NVIDIA's `flip-evaluator` (mean
//! HDR-FLIP within 1e-4) and the authors' `cvvdp` (JOD within 0.01).
//!
//! The references live in the Python of `INIMTRACE_PERCEPTION_PYTHON` (default
//! `target/venv-perception/bin/python`, which `scripts/install-deps.sh` makes). Without them the
//! test says so and passes, unless `INIMTRACE_REQUIRE_FLIP` (or `INIMTRACE_REQUIRE_CVVDP`) is set,
//! as CI sets them: then a missing reference fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::experiment::{assess_images, RunOptions};
use inimtrace::overrides::Override;
use inimtrace::perception::{cvvdp, flip, DisplayLuminance, Viewing};
use inimtrace::raster::RgbImage;

fn python() -> PathBuf {
    std::env::var_os("INIMTRACE_PERCEPTION_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target/venv-perception/bin/python"))
}

/// Whether `module` imports in the reference Python; a required one that does not fails.
fn available(module: &str, require: &str) -> bool {
    let ok =
        Command::new(python()).args(["-c", &format!("import {module}")]).output().is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var_os(require).is_none(),
            "{require} is set but {} cannot import {module} (scripts/install-deps.sh installs it)",
            python().display()
        );
        eprintln!("skipped: {} cannot import {module} (scripts/install-deps.sh installs it)", python().display());
    }
    ok
}

struct Pair {
    name: String,
    test: RgbImage,
    reference: RgbImage,
    viewing: Viewing,
}

/// Nine retinal image pairs of the paper's experiment on a small retina (about 14 pixels per
/// degree, as the paper's), grid estimator.
fn pairs() -> Vec<Pair> {
    let set: Vec<Override> = [
        "display.lcd.resolution=[540, 540]",
        "eye.retina_resolution=96",
        "eye.retina_half_tangent=0.06",
        "eye.pupil_grid=4",
        r#"eye_cases=[{ name = "Pin", pinhole = true }, { name = "Near", focus_mm = 300.0 }, { name = "Far", focus_mm = 600.0 }]"#,
    ]
    .iter()
    .map(|s| s.parse().unwrap())
    .collect();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let exp = inimtrace::settings::load_experiment(Some(&path), None, &set).unwrap();
    let run = assess_images(&exp, None, RunOptions { quiet: true, ..Default::default() }).unwrap();
    let ppd = inimtrace::perception::viewing::retina_pixels_per_degree(&exp.retina);
    let mut out = Vec::new();
    for (c, case) in exp.cases.iter().enumerate() {
        for (k, m) in exp.methods.iter().enumerate() {
            let peak = [10.0, 100.0, 1000.0][(c + k) % 3];
            let luminance = DisplayLuminance { ambient_lux: 10.0, reflectance: 0.01, ..DisplayLuminance::default() };
            out.push(Pair {
                name: format!("{}_{}_{peak}", m.name(), case.name),
                test: run.perceived[c][k].clone(),
                reference: run.ground_truths[c].clone(),
                viewing: Viewing { luminance: luminance.with_peak(peak), pixels_per_degree: ppd },
            });
        }
    }
    out
}

fn write_f32(path: &Path, values: &[f32]) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// Runs the reference script on `pairs` for `metric`, returning one value per pair.
fn reference(pairs: &[Pair], metric: &str) -> Vec<f64> {
    let dir = tempfile::tempdir().unwrap();
    let mut manifest = Vec::new();
    for p in pairs {
        let file = |what: &str| dir.path().join(format!("{}_{what}.f32", p.name));
        write_f32(&file("flip_test"), &flip::absolute_rgb(&p.viewing, &p.test));
        write_f32(&file("flip_reference"), &flip::absolute_rgb(&p.viewing, &p.reference));
        write_f32(&file("cvvdp_test"), &cvvdp::panel_rgb(&p.viewing, &p.test));
        write_f32(&file("cvvdp_reference"), &cvvdp::panel_rgb(&p.viewing, &p.reference));
        let l = &p.viewing.luminance;
        manifest.push(serde_json::json!({
            "name": p.name, "width": p.test.width, "height": p.test.height, "ppd": p.viewing.pixels_per_degree,
            "peak": l.peak_white, "contrast": cvvdp::contrast(&p.viewing), "ambient_lux": l.ambient_lux,
            "reflectance": l.reflectance,
            "flip_test": file("flip_test"), "flip_reference": file("flip_reference"),
            "cvvdp_test": file("cvvdp_test"), "cvvdp_reference": file("cvvdp_reference"),
        }));
    }
    let manifest_path = dir.path().join("manifest.json");
    std::fs::write(&manifest_path, serde_json::to_vec(&manifest).unwrap()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/perception-reference.py");
    let out = Command::new(python()).arg(&script).arg(&manifest_path).arg(metric).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(rows.len(), pairs.len(), "{text}");
    rows.iter().map(|r| r[metric].as_f64().unwrap()).collect()
}

#[test]
fn mean_flip_matches_nvidia_flip_evaluator_within_1e_4() {
    if !available("flip_evaluator", "INIMTRACE_REQUIRE_FLIP") {
        return;
    }
    let pairs = pairs();
    let want = reference(&pairs, "flip");
    for (p, w) in pairs.iter().zip(want) {
        let got = flip::flip(&p.test, &p.reference, &p.viewing).unwrap().mean;
        eprintln!("{}: FLIP {got:.6} (flip-evaluator {w:.6})", p.name);
        assert!(got > 0.0, "{}: the pairs differ", p.name);
        assert!((got - w).abs() < 1e-4, "{}: inimtrace {got} vs flip-evaluator {w}", p.name);
    }
}

#[test]
fn jod_matches_the_authors_cvvdp_within_0_01() {
    if !available("pycvvdp", "INIMTRACE_REQUIRE_CVVDP") {
        return;
    }
    let pairs = pairs();
    let want = reference(&pairs, "cvvdp");
    for (p, w) in pairs.iter().zip(want) {
        let (n, h) = (p.test.width, p.test.height);
        let got = cvvdp::Cvvdp::new(&p.viewing, n, h, false).unwrap().score(&p.test, &p.reference).unwrap().jod;
        eprintln!("{}: JOD {got:.5} (cvvdp {w:.5})", p.name);
        assert!(got < 10.0, "{}: the pairs differ", p.name);
        assert!((got - w).abs() < 0.01, "{}: inimtrace {got} vs cvvdp {w}", p.name);
    }
}
