//! Provenance of a run: `results.json`, every EXR and every sweep point record name the scene
//! (name, path as given) and hold the SHA-256 of every file read (experiment, scene, display,
//! mesh, material library, texture), the `--set` overrides, the budgets and the seed as a
//! number; `inimtrace info --provenance RUN_DIR` hashes the files again and says what changed.
#![deny(unsafe_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::provenance::sha256_hex;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs inimtrace in `dir`: (exit code, stdout, stderr).
fn inimtrace(dir: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .current_dir(dir)
        .arg("--quiet")
        .args(args)
        .output()
        .expect("binary runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A folder with an experiment whose scene is a textured OBJ (with its material library).
fn setup(dir: &Path) {
    let meshes = root().join("tests/data/meshes");
    std::fs::create_dir_all(dir.join("in/textures")).unwrap();
    for f in ["pyramid.obj", "pyramid.mtl"] {
        std::fs::copy(meshes.join(f), dir.join("in").join(f)).unwrap();
    }
    let mut tex = inimtrace::raster::RgbImage::filled(4, 4, [0.2, 0.5, 0.8]);
    tex.pixels[0] = [1.0, 0.0, 0.0];
    inimtrace::io::png::write_preview(&dir.join("in/textures/stone.png"), &tex).unwrap();
    std::fs::write(
        dir.join("in/scene.toml"),
        "name = \"pyramid-scene\"\nbackground = [0.1, 0.1, 0.1]\n[[objects]]\ntype = \"mesh\"\nfile = \"pyramid.obj\"\n\
         fit = { size = 100.0, center = [0, 0, 400] }\n",
    )
    .unwrap();
    let exp = std::fs::read_to_string(root().join("experiments/paper.toml"))
        .unwrap()
        .replace("../scenes/paper.toml", "scene.toml")
        .replace("../displays/paper.toml", root().join("displays/paper.toml").to_str().unwrap());
    std::fs::write(dir.join("in/exp.toml"), exp).unwrap();
}

const SMALL: [&str; 6] = [
    "--set",
    "display.lcd.resolution=[270, 270]",
    "--set",
    "eye.retina_resolution=16",
    "--set",
    "eye_cases=[{ name = \"Eye\", focus_diopters = 2.5 }]",
];

fn hash(path: &Path) -> String {
    sha256_hex(&std::fs::read(path).unwrap())
}

#[test]
fn an_assess_run_records_what_it_read_and_info_provenance_says_what_changed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    let mut args = vec!["assess", "in/exp.toml", "--out", "run"];
    args.extend(SMALL);
    let (code, _, e) = inimtrace(d, &args);
    assert_eq!(code, Some(0), "{e}");

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("run/results.json")).unwrap()).unwrap();
    let p = &json["provenance"];
    assert_eq!(p["scene_name"], "pyramid-scene");
    assert_eq!(p["scene_path"], "scene.toml", "the path as the experiment gives it");
    assert_eq!(p["experiment_path"], "in/exp.toml");
    assert_eq!(p["seed"], 1, "the seed is a number");
    assert_eq!(
        p["set"],
        serde_json::json!([
            "display.lcd.resolution=[270, 270]",
            "eye.retina_resolution=16",
            "eye_cases=[{ name = \"Eye\", focus_diopters = 2.5 }]"
        ])
    );
    assert_eq!(p["budgets"]["estimator"], "grid");
    assert_eq!(p["budgets"]["max_seconds"], 600.0);
    assert_eq!(p["working_directory"], std::fs::canonicalize(d).unwrap().to_str().unwrap());
    let files = p["files"].as_array().unwrap();
    let by_name = |name: &str| {
        files
            .iter()
            .find(|f| f["path"].as_str().unwrap().ends_with(name))
            .unwrap_or_else(|| panic!("{name} not among {files:?}"))
    };
    for (name, path) in [
        ("exp.toml", d.join("in/exp.toml")),
        ("scene.toml", d.join("in/scene.toml")),
        ("displays/paper.toml", root().join("displays/paper.toml")),
        ("pyramid.obj", d.join("in/pyramid.obj")),
        ("pyramid.mtl", d.join("in/pyramid.mtl")),
        ("stone.png", d.join("in/textures/stone.png")),
    ] {
        let f = by_name(name);
        assert_eq!(f["sha256"], hash(&path), "{name}");
        assert_eq!(f["bytes"], std::fs::metadata(&path).unwrap().len(), "{name}");
    }

    // Every EXR names the scene and holds the hashes and the overrides.
    for exr in ["display_LC.exr", "gt_Eye.exr", "sim_LA_Eye.exr"] {
        let attrs = inimtrace::io::exr::read_attributes(&d.join("run").join(exr)).unwrap();
        let get = |k: &str| attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.to_string()).unwrap_or_default();
        assert_eq!(get("inimtrace:scene"), "pyramid-scene", "{exr}");
        assert_eq!(get("inimtrace:scene_path"), "scene.toml", "{exr}");
        assert_eq!(get("inimtrace:scene_sha256"), hash(&d.join("in/scene.toml")), "{exr}");
        let inputs = get("inimtrace:input_files_sha256");
        let line = format!("{}  ", hash(&d.join("in/textures/stone.png")));
        assert!(inputs.lines().any(|l| l.starts_with(&line) && l.ends_with("stone.png")), "{exr}: {inputs}");
        assert!(get("inimtrace:set").lines().any(|l| l == "eye.retina_resolution=16"), "{exr}");
    }

    // Nothing changed: every file unchanged.
    let (code, out, e) = inimtrace(d, &["info", "--provenance", "run"]);
    assert_eq!(code, Some(0), "{e}");
    assert!(out.contains("all 6 input files unchanged"), "{out}");
    assert!(out.contains("scene `pyramid-scene` (scene.toml)"), "{out}");
    // From another folder: relative paths resolve against the run's folder.
    let (code, out, e) = inimtrace(&root(), &["info", "--provenance", d.join("run").to_str().unwrap()]);
    assert_eq!(code, Some(0), "{e}");
    assert!(out.contains("all 6 input files unchanged"), "{out}");

    // A texture edited and a material library removed: both named.
    let mut tex = inimtrace::raster::RgbImage::filled(4, 4, [0.2, 0.5, 0.8]);
    tex.pixels[0] = [0.0, 1.0, 0.0];
    inimtrace::io::png::write_preview(&d.join("in/textures/stone.png"), &tex).unwrap();
    std::fs::remove_file(d.join("in/pyramid.mtl")).unwrap();
    let (code, out, e) = inimtrace(d, &["info", "--provenance", "run"]);
    assert_eq!(code, Some(0), "{e}");
    let line = |state: &str, name: &str| out.lines().any(|l| l.trim_start().starts_with(state) && l.contains(name));
    assert!(line("CHANGED", "stone.png") && line("MISSING", "pyramid.mtl"), "{out}");
    assert!(line("unchanged", "pyramid.obj") && line("unchanged", "exp.toml"), "{out}");
    assert!(out.contains("2 of 6 input files changed or missing since the run"), "{out}");

    // A folder that is no run.
    let (code, _, e) = inimtrace(d, &["info", "--provenance", "in"]);
    assert_eq!(code, Some(1));
    assert!(e.contains("RUN_DIR") && e.contains("results.json"), "{e}");
}

#[test]
fn every_sweep_point_record_holds_its_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    std::fs::write(
        d.join("in/sweep.toml"),
        "name = \"p\"\nexperiment = \"exp.toml\"\n[set]\n\"display.lcd.resolution\" = [270, 270]\n\
         \"eye.retina_resolution\" = 16\n\"eye_cases\" = [{ name = \"Eye\", focus_diopters = 2.5 }]\n\
         [[axes]]\n\"eye.pupil_diameter\" = [3.0, 5.0]\n",
    )
    .unwrap();
    let (code, _, e) = inimtrace(d, &["sweep", "in/sweep.toml", "--out", "sw", "--set", "methods=[\"LC\"]"]);
    assert_eq!(code, Some(0), "{e}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("sw/sweep.json")).unwrap()).unwrap();
    for (i, pupil) in [(0, "3.0"), (1, "5.0")] {
        let id = json["points"][i]["id"].as_str().unwrap();
        let rec: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("sw/points").join(format!("{id}.json"))).unwrap())
                .unwrap();
        let p = &rec["provenance"];
        assert_eq!(p["scene_name"], "pyramid-scene");
        assert_eq!(p["scene_path"], "scene.toml");
        assert_eq!(p["seed"], 1);
        let set: Vec<&str> = p["set"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
        assert_eq!(set.first(), Some(&"display.lcd.resolution=[270, 270]"), "{set:?}");
        assert!(set.contains(&"methods=[\"LC\"]"), "{set:?}");
        assert_eq!(set.last().copied(), Some(format!("eye.pupil_diameter={pupil}").as_str()), "{set:?}");
        let files = p["files"].as_array().unwrap();
        for (name, path) in [
            ("sweep.toml", d.join("in/sweep.toml")),
            ("exp.toml", d.join("in/exp.toml")),
            ("scene.toml", d.join("in/scene.toml")),
            ("pyramid.obj", d.join("in/pyramid.obj")),
            ("stone.png", d.join("in/textures/stone.png")),
        ] {
            let f = files.iter().find(|f| f["path"].as_str().unwrap().ends_with(name)).unwrap_or_else(|| {
                panic!("point {i}: {name} not among {files:?}");
            });
            assert_eq!(f["sha256"], hash(&path), "point {i}: {name}");
        }
    }
    std::fs::write(d.join("in/pyramid.obj"), "# emptied\n").unwrap();
    let (code, out, e) = inimtrace(d, &["info", "--provenance", "sw"]);
    assert_eq!(code, Some(0), "{e}");
    assert!(
        out.contains("2 records") && out.lines().any(|l| l.contains("CHANGED") && l.contains("pyramid.obj")),
        "{out}"
    );
}
