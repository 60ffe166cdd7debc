//! Methods keep their names: `LA` (the paper's 5 x 5), `LA3` and `LA7` sit in one experiment,
//! with distinct files, table columns, results and images.

use std::path::Path;

use inimtrace::experiment::{assess_images, table_markdown, RunOptions};
use inimtrace::overrides::Override;
use inimtrace::render::Method;
use inimtrace::settings::load_experiment;

fn overrides(list: &[&str]) -> Vec<Override> {
    list.iter().map(|s| s.parse().unwrap()).collect()
}

#[test]
fn la_la3_and_la7_run_in_one_experiment_under_their_own_names() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let set = overrides(&[
        "display.lcd.resolution=[540, 540]",
        "eye.retina_resolution=32",
        "eye.pupil_grid=2",
        r#"eye_cases=[{ name = "Near", focus_diopters = 2.5 }]"#,
        r#"methods=["LA", "LA3", "LA7"]"#,
    ]);
    let exp = load_experiment(Some(&path), None, &set).unwrap();
    let la = |grid| Method::LensletAverage { grid };
    assert_eq!(exp.methods, [la(5), la(3), la(7)]);

    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("names");
    let opts = RunOptions { quiet: true, ..Default::default() };
    let a = assess_images(&exp, Some(&out), opts).unwrap();

    for name in ["LA", "LA3", "LA7"] {
        assert!(out.join(format!("display_{name}.exr")).is_file(), "display_{name}.exr");
        assert!(out.join(format!("sim_{name}_Near.exr")).is_file(), "sim_{name}_Near.exr");
    }
    let methods: Vec<&str> = a.report.scores.iter().map(|s| s.method.as_str()).collect();
    assert_eq!(methods, ["LA", "LA3", "LA7"]);
    let table = table_markdown(&a.report, &exp);
    for column in ["PSNR LA |", "PSNR LA3 |", "PSNR LA7 |", "SSIM LA |", "SSIM LA3 |", "SSIM LA7 |"] {
        assert!(table.contains(column), "{column} in\n{table}");
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    for name in ["LA", "LA3", "LA7"] {
        assert!(csv.lines().any(|l| l.split(',').any(|f| f == name)), "{name} in results.csv:\n{csv}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let in_json: Vec<&str> = json["scores"].as_array().unwrap().iter().map(|s| s["method"].as_str().unwrap()).collect();
    assert_eq!(in_json, ["LA", "LA3", "LA7"]);

    // Different grids, different display images (and perceived images).
    assert!(a.displays[0] != a.displays[1], "LA and LA3 display images are equal");
    assert!(a.displays[1] != a.displays[2], "LA3 and LA7 display images are equal");
    assert!(a.perceived[0][0] != a.perceived[0][1], "LA and LA3 perceived images are equal");
}

#[test]
fn the_same_method_twice_is_refused_whatever_its_spelling() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    for (methods, name) in
        [(r#"methods=["LA", "LA5"]"#, "LA"), (r#"methods=["LA3", "la:3"]"#, "LA3"), (r#"methods=["LC", "lc"]"#, "LC")]
    {
        let err = load_experiment(Some(&path), None, &overrides(&[methods])).unwrap_err().to_string();
        assert!(err.contains("methods[1]") && err.contains(&format!("{name} appears twice")), "{methods}: {err}");
    }
}
