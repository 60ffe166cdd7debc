//! The light-adapted pupil (`pupil_diameter = "auto"`, Watson & Yellott, J. Vision 12(10):12,
//! 2012): the formula against its published equations worked here by hand, and "auto" in an
//! experiment (`--set eye.pupil_diameter=auto`), a resolution study and `info`, with its report.

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::optics::eye::pupil::{monocular_effect, stanley_davies, Observer};
use inimtrace::optics::Aperture;
use inimtrace::overrides::{parse_value, Override};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn set(pairs: &[(&str, &str)]) -> Vec<Override> {
    pairs.iter().map(|(k, v)| Override::new(k, parse_value(v).unwrap()).unwrap()).collect()
}

/// Watson & Yellott's published equations, written out again: Stanley & Davies (1995)
/// `D_SD = 7.75 - 5.75 (F/846)^0.41 / ((F/846)^0.41 + 2)` of the flux `F = L a M(e)`, `M(1) = 0.1`,
/// `M(2) = 1`, and the age term `(y - 28.58) (0.02132 - 0.009562 D_SD)` (their eq. 21).
fn published(l: f64, a: f64, age: f64, eyes: u8) -> f64 {
    let m = if eyes == 1 { 0.1 } else { 1.0 };
    let x = (l * a * m / 846.0).powf(0.41);
    let d_sd = 7.75 - 5.75 * x / (x + 2.0);
    d_sd + (age - 28.58) * (0.02132 - 0.009562 * d_sd)
}

#[test]
fn the_unified_formula_reproduces_the_published_equations_worked_by_hand() {
    // Worked by hand (to 4 decimals) from the equations above for a 1000 deg^2 field: a
    // 30-year-old adapted with both eyes, and a 60-year-old with one eye; and a 10 deg disc
    // (78.54 deg^2) at 25 with both.
    let by_hand = [
        (0.01, 7.2498, 5.9685, 7.7739),
        (0.1, 6.6971, 5.7899, 7.5323),
        (10.0, 4.3899, 4.6887, 5.9968),
        (100.0, 3.2530, 3.7617, 4.6391),
        (1000.0, 2.5650, 2.9554, 3.4066),
    ];
    let disc = 25.0 * std::f64::consts::PI;
    for (l, young, old_one_eye, small) in by_hand {
        let a = Observer { age: 30.0, eyes: 2 }.pupil_diameter(l, 1000.0);
        let b = Observer { age: 60.0, eyes: 1 }.pupil_diameter(l, 1000.0);
        let c = Observer { age: 25.0, eyes: 2 }.pupil_diameter(l, disc);
        assert!((a - young).abs() < 0.01, "{l} cd/m^2: {a} vs {young}");
        assert!((b - old_one_eye).abs() < 0.01, "{l} cd/m^2: {b} vs {old_one_eye}");
        assert!((c - small).abs() < 0.01, "{l} cd/m^2: {c} vs {small}");
        for (age, eyes, area) in [(30.0, 2, 1000.0), (60.0, 1, 1000.0), (25.0, 2, disc), (83.0, 1, 4.0)] {
            let got = Observer { age, eyes }.pupil_diameter(l, area);
            assert!((got - published(l, area, age, eyes)).abs() < 1e-12, "{l} {age} {eyes} {area}");
        }
    }
    // The pieces: Stanley & Davies alone at the reference age, and one eye is a tenth of the flux.
    assert!((Observer { age: 28.58, eyes: 2 }.pupil_diameter(50.0, 400.0) - stanley_davies(20_000.0)).abs() < 1e-12);
    assert_eq!(monocular_effect(1), 0.1);
    assert_eq!(
        Observer { age: 40.0, eyes: 1 }.pupil_diameter(10.0, 100.0),
        Observer { age: 40.0, eyes: 2 }.pupil_diameter(1.0, 100.0)
    );
    // Brighter light, a larger field, age: a smaller pupil.
    let o = Observer::default();
    assert!(o.pupil_diameter(100.0, 100.0) < o.pupil_diameter(10.0, 100.0));
    assert!(o.pupil_diameter(10.0, 1000.0) < o.pupil_diameter(10.0, 100.0));
    assert!(Observer { age: 70.0, eyes: 2 }.pupil_diameter(1.0, 100.0) < o.pupil_diameter(1.0, 100.0));
}

/// A scene whose every ray sees albedo 1: the adapting field is the display's peak white.
fn white_scene(dir: &Path) -> PathBuf {
    let p = dir.join("white.toml");
    std::fs::write(
        &p,
        "name = \"white\"\nbackground = [1.0, 1.0, 1.0]\n[[objects]]\nname = \"wall\"\ntype = \"rect\"\n\
         center = [0.0, 0.0, 500.0]\nsize = [4000.0, 4000.0]\nmaterial = { albedo = [1.0, 1.0, 1.0] }\n",
    )
    .unwrap();
    p
}

#[test]
fn auto_in_an_experiment_adapts_to_the_scene_at_the_display_photometry() {
    let dir = tempfile::tempdir().unwrap();
    let scene = white_scene(dir.path());
    let exp_path = root().join("experiments/paper.toml");
    let overrides = set(&[("eye.pupil_diameter", "\"auto\""), ("display.photometry.peak_luminance", "300")]);
    let exp = inimtrace::settings::load_experiment(Some(&exp_path), Some(&scene), &overrides).unwrap();
    let auto = exp.auto_pupil.expect("auto chose a pupil");
    let fov = 2.0 * (10.8f64 / 26.316).atan().to_degrees();
    assert!((auto.field_area_deg2 - fov * fov).abs() < 1e-9);
    assert!((auto.adapting_luminance_cd_m2 - 300.0).abs() < 1e-9, "{}", auto.adapting_luminance_cd_m2);
    let expected = published(300.0, fov * fov, 30.0, 2);
    assert!((auto.diameter_mm - expected).abs() < 1e-12);
    for c in &exp.cases {
        if let Aperture::ThinLens { pupil_diameter, .. } = c.eye.aperture {
            assert_eq!(pupil_diameter, auto.diameter_mm, "{}", c.name);
        }
    }
    // Age and eyes are settings; a stated diameter reads neither.
    let older = set(&[("eye.pupil_diameter", "\"auto\""), ("eye.age", "70"), ("eye.adapted_eyes", "1")]);
    let exp = inimtrace::settings::load_experiment(Some(&exp_path), Some(&scene), &older).unwrap();
    let p = exp.auto_pupil.unwrap();
    assert!((p.diameter_mm - published(100.0, fov * fov, 70.0, 1)).abs() < 1e-12);
    for (pairs, field) in [
        (vec![("eye.age", "40")], "eye.age"),
        (vec![("eye.pupil_diameter", "\"auto\""), ("eye.age", "12")], "eye.age"),
        (vec![("eye.pupil_diameter", "\"auto\""), ("eye.adapted_eyes", "3")], "eye.adapted_eyes"),
        (vec![("eye.pupil_diameter", "\"big\"")], "eye.pupil_diameter"),
    ] {
        let e = inimtrace::settings::load_experiment(Some(&exp_path), Some(&scene), &set(&pairs)).unwrap_err();
        assert!(e.to_string().contains(field), "{pairs:?}: {e}");
    }
}

#[test]
fn auto_in_a_study_adapts_to_the_chart_grey() {
    let text = std::fs::read_to_string(root().join("studies/tiny.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.toml");
    let text = text.replace(
        &text.lines().find(|l| l.starts_with("pupil_diameter_mm")).unwrap().to_string(),
        "pupil_diameter_mm = \"auto\"",
    );
    std::fs::write(&p, &text).unwrap();
    let s = inimtrace::resolution::study::Study::load(&p, &[]).unwrap();
    let auto = s.auto_pupil.expect("auto chose a pupil");
    let l = 0.1 + (100.0 - 0.1) * s.target.mean;
    assert!((auto.adapting_luminance_cd_m2 - l).abs() < 1e-9);
    assert!((s.pupil_diameter_mm - published(l, auto.field_area_deg2, 30.0, 2)).abs() < 1e-12);
}

#[test]
fn info_reports_the_chosen_pupil() {
    let dir = tempfile::tempdir().unwrap();
    let scene = white_scene(dir.path());
    let (ok, out, err) = inimtrace(&["info", "--pupil", "auto", "--scene", &scene.to_string_lossy(), "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let d = v["auto_pupil"]["diameter_mm"].as_f64().unwrap();
    let a = v["auto_pupil"]["field_area_deg2"].as_f64().unwrap();
    assert!((d - published(100.0, a, 30.0, 2)).abs() < 1e-12, "{d}");
    // The design is figured at the chosen pupil, to the micrometre.
    assert!((v["pupil_diameter_mm"].as_f64().unwrap() - d).abs() <= 5e-4);
    let (ok, out, err) = inimtrace(&["info", "--pupil", "auto"]);
    assert!(ok, "{err}");
    assert!(out.contains("pupil \"auto\": ") && out.contains("Watson & Yellott 2012"), "{out}");
    let (ok, _, err) = inimtrace(&["info", "--pupil", "wide"]);
    assert!(!ok && err.contains("--pupil") && !err.contains("panicked"), "{err}");
}
