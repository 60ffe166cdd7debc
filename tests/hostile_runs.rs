//! Hostile inputs, round three, through the command line: what a run deletes, what `--quiet`
//! hides, which sweep records a resume trusts, what `compare` pairs, how input images are read
//! and recorded, which settings the memory estimate refuses, and what a non-finite value's error
//! names. Set `INIMTRACE_TEST_BIN` to run the command-line checks against another build (the one
//! before a fix).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> String {
    std::env::var("INIMTRACE_TEST_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_inimtrace").to_string())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> Output {
    Command::new(bin()).args(args).current_dir(root()).output().expect("run inimtrace")
}

/// Runs inimtrace with its data segment (heap) capped at `mb` MB (`ulimit -d`): an allocation
/// the memory estimate should have refused aborts the child instead of passing unnoticed.
fn run_capped(mb: u64, args: &[&str]) -> Output {
    let cmd = format!("ulimit -d {}; exec \"$0\" \"$@\"", mb * 1024);
    Command::new("bash").arg("-c").arg(cmd).arg(bin()).args(args).current_dir(root()).output().expect("run bash")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `experiments/paper.toml` (grid estimator) at tiny sizes, one eye case.
const TINY: [&str; 8] = [
    "--set",
    "display.lcd.resolution=[108, 108]",
    "--set",
    "eye.retina_resolution=16",
    "--set",
    "eye.pupil_grid=2",
    "--set",
    "eye_cases=[{ name = \"E\", focus_diopters = 2.5 }]",
];

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn a_listed_file_that_changed_is_never_deleted() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut args = vec!["--quiet", "assess", "experiments/paper.toml", "--out", p(&out)];
    args.extend(TINY);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    // The user edits a file the report lists; a forced run into the folder must keep it.
    let table = out.join("table.md");
    let mut text = std::fs::read_to_string(&table).unwrap();
    text.push_str("\nmy notes\n");
    std::fs::write(&table, &text).unwrap();
    args.insert(2, "--force");
    let o = run(&args);
    let e = stderr(&o);
    assert_eq!(std::fs::read_to_string(&table).unwrap(), text, "the edited file was deleted or replaced: {e}");
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("table.md") && e.contains("changed"), "{e}");
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    // Moved away, the run goes ahead and removes only what still matches its listing.
    std::fs::rename(&table, dir.path().join("table.md")).unwrap();
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn quiet_never_hides_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj = std::fs::read_to_string(root().join("tests/data/meshes/pyramid.obj")).unwrap();
    std::fs::write(dir.path().join("pyramid.obj"), obj).unwrap();
    let fifo = dir.path().join("pyramid.mtl");
    if !Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false) {
        eprintln!("skipped: mkfifo is not available on this machine");
        return;
    }
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        "name = \"s\"\n[[objects]]\nname = \"p\"\ntype = \"mesh\"\nfile = \"pyramid.obj\"\n\
         transform = { translation = [0, 0, 400], scale = [50, 50, 50] }\n",
    )
    .unwrap();
    for quiet in [false, true] {
        let mut args = vec!["info", "--scene", p(&scene)];
        if quiet {
            args.insert(0, "--quiet");
        }
        let o = run(&args);
        let e = stderr(&o);
        assert!(o.status.success(), "{e}");
        assert!(e.contains("warning:") && e.contains("material library"), "quiet {quiet}: {e}");
    }
}

/// Reads, edits with `f` and writes back the JSON record `path`.
fn edit_record(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
}

#[test]
fn a_resume_runs_again_every_record_it_cannot_verify() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let args = ["--quiet", "sweep", "sweeps/tiny.toml", "--out", p(&out), "--points", "0..3"];
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut records: Vec<PathBuf> = std::fs::read_dir(out.join("points"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    records.sort();
    assert_eq!(records.len(), 3);
    // A score edited into another spelling of a number, an old version, and an unknown field.
    edit_record(&records[0], |v| {
        let s = v["scores"][0]["psnr_db"].as_str().unwrap().to_string();
        v["scores"][0]["psnr_db"] = serde_json::json!(format!("{s}0"));
    });
    edit_record(&records[1], |v| v["version"] = serde_json::json!("0.0.1"));
    edit_record(&records[2], |v| v["scores"][0]["note"] = serde_json::json!("checked by hand"));
    let o = run(&args);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("3 points run again") && e.contains("could not be verified"), "{e}");
    assert!(e.contains("0 already complete") && e.contains("3 run"), "{e}");
    for r in &records {
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(r).unwrap()).unwrap();
        assert_eq!(v["version"], env!("CARGO_PKG_VERSION"), "{r:?}");
        assert!(v["scores"][0].get("note").is_none(), "{r:?}");
    }
    // Untouched, they are trusted.
    let o = run(&args);
    assert!(stderr(&o).contains("3 already complete"), "{}", stderr(&o));
}

/// A converged tiny run with `seed`, keeping its replicates, into `out`.
fn converged_run(out: &Path, seed: u64) -> Output {
    let seed = format!("measurement.seed={seed}");
    let mut args = vec!["--quiet", "assess", "experiments/paper-converged.toml", "--out", p(out), "--keep-replicates"];
    args.extend_from_slice(&TINY[..4]);
    args.extend([
        "--set",
        "eye_cases=[{ name = \"E\", focus_diopters = 2.5 }]",
        "--set",
        "measurement.replicates=3",
        "--set",
        "measurement.max_samples_per_pixel=48",
        "--set",
        &seed,
    ]);
    run(&args)
}

/// The keys of a JSON value, recursively (`a.b.c`), sorted.
fn keys(v: &serde_json::Value, prefix: &str, out: &mut Vec<String>) {
    if let serde_json::Value::Object(m) = v {
        for (k, x) in m {
            let name = format!("{prefix}{k}");
            out.push(name.clone());
            keys(x, &format!("{name}."), out);
        }
    }
}

#[test]
fn compare_pairs_only_replicates_of_one_measurement_and_has_one_json_schema() {
    let dir = tempfile::tempdir().unwrap();
    let (one, two) = (dir.path().join("seed1"), dir.path().join("seed2"));
    for (out, seed) in [(&one, 1), (&two, 2)] {
        let o = converged_run(out, seed);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let set = |d: &Path, stem: &str| d.join(format!("{stem}.replicates.exr"));
    // Different seeds: the replicates do not pair.
    let o = run(&["compare", p(&set(&one, "gt_E")), p(&set(&two, "sim_LC_E"))]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("seed"), "{e}");
    // One measurement: de-biased scores. The JSON of sets and of plain images has one schema.
    let sets = run(&["compare", "--json", p(&set(&one, "gt_E")), p(&set(&one, "sim_LC_E"))]);
    assert!(sets.status.success(), "{}", stderr(&sets));
    let plain = run(&["compare", "--json", p(&one.join("gt_E.exr")), p(&one.join("sim_LC_E.exr"))]);
    assert!(plain.status.success(), "{}", stderr(&plain));
    let (a, b): (serde_json::Value, serde_json::Value) =
        (serde_json::from_slice(&sets.stdout).unwrap(), serde_json::from_slice(&plain.stdout).unwrap());
    let (mut ka, mut kb) = (Vec::new(), Vec::new());
    keys(&a, "", &mut ka);
    keys(&b, "", &mut kb);
    ka.sort();
    kb.sort();
    let extra: Vec<&String> =
        ka.iter().filter(|k| !k.starts_with("psnr_db.channels_ci95") && !k.starts_with("ssim.channels_ci95")).collect();
    assert_eq!(extra, kb.iter().filter(|k| !k.contains("channels_ci95")).collect::<Vec<_>>(), "{a}\n{b}");
    assert_eq!(a["replicate_sets"], true);
    assert_eq!(b["replicate_sets"], false);
    // Identical sets: an infinite PSNR is null in both kinds.
    let same = run(&["compare", "--json", p(&set(&one, "gt_E")), p(&set(&one, "gt_E"))]);
    let v: serde_json::Value = serde_json::from_slice(&same.stdout).unwrap();
    assert!(v["psnr_db"]["mean"].is_null(), "{v}");
}

#[test]
fn an_input_image_is_read_once_through_the_gate_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("display.exr");
    let image = inimtrace::raster::RgbImage::filled(108, 108, [0.5, 0.25, 0.75]);
    inimtrace::io::exr::write_rgb(&img, &image, None, &[]).unwrap();
    let sha = inimtrace::provenance::sha256_hex(&std::fs::read(&img).unwrap());
    let out = dir.path().join("sim.exr");
    let o = run(&[
        "--quiet",
        "simulate",
        p(&img),
        "--pinhole",
        "--retina",
        "16",
        "--set",
        "display.lcd.resolution=[108, 108]",
        "--out",
        p(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let attrs = inimtrace::io::exr::read_attributes(&out).unwrap();
    let files = attrs.iter().find(|(k, _)| k == "inimtrace:input_files_sha256").map(|(_, v)| v.clone());
    let files = files.unwrap_or_default();
    assert!(files.contains(&format!("{sha}  {}", img.display())), "{attrs:?}");
}

#[test]
fn an_input_image_swapped_after_its_check_is_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("a.exr");
    let first = inimtrace::raster::RgbImage::filled(8, 8, [0.5, 0.25, 0.75]);
    inimtrace::io::exr::write_rgb(&img, &first, None, &[("inimtrace:method", "LC".into())]).unwrap();
    let ((file, _), files) = inimtrace::provenance::recording(|| {
        let f = inimtrace::io::exr::ExrFile::open(&img).unwrap();
        (f, ())
    });
    assert_eq!(files.len(), 1);
    assert_eq!(files[0].sha256, inimtrace::provenance::sha256_hex(&std::fs::read(&img).unwrap()));
    // Another image under the same name, after the check: the open file is what is read.
    let other = inimtrace::raster::RgbImage::filled(8, 8, [0.0, 1.0, 0.0]);
    let swap = dir.path().join("b.exr");
    inimtrace::io::exr::write_rgb(&swap, &other, None, &[("inimtrace:method", "PC".into())]).unwrap();
    std::fs::rename(&swap, &img).unwrap();
    assert_eq!(file.input(None).unwrap().image.pixels, first.pixels);
    let method = file.attributes().unwrap().into_iter().find(|(k, _)| k == "inimtrace:method").unwrap().1;
    assert_eq!(method, "LC");
}

#[test]
fn every_large_allocation_is_estimated_and_refused_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name).display().to_string();
    // OPT's training retina and operator (before: allocated, and aborted under the cap).
    let o1 = out("opt");
    let mut args = vec!["assess", "experiments/paper-optimal.toml", "--out", &o1];
    args.extend_from_slice(&TINY[..4]);
    args.extend(["--set", "optimize.retina_resolution=20000"]);
    let o = run_capped(400, &args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("optimize.retina_resolution") && e.contains("memory"), "{e}");
    // The converged estimator's replicate stores.
    let o2 = out("converged");
    let mut args = vec!["assess", "experiments/paper-converged.toml", "--out", &o2];
    args.extend_from_slice(&TINY[..2]);
    args.extend(["--set", "eye.retina_resolution=8000", "--set", "measurement.replicates=64"]);
    let o = run_capped(400, &args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("eye.retina_resolution") && e.contains("memory"), "{e}");
    // A resolution study's windows (before: measured until the allocation aborted).
    let o3 = out("study");
    let o = run_capped(
        400,
        &[
            "resolution",
            "studies/tiny.toml",
            "--out",
            &o3,
            "--set",
            "retina.pixels_per_degree=1000",
            "--set",
            "retina.window_deg=[4.0, 4.0]",
            "--set",
            "retina.edge_window_deg=[4.0, 4.0]",
        ],
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("retina.pixels_per_degree") && e.contains("memory"), "{e}");
}

#[test]
fn a_non_finite_value_names_the_inputs_that_led_there() {
    let dir = tempfile::tempdir().unwrap();
    let mut img = inimtrace::raster::RgbImage::filled(4, 4, [0.5; 3]);
    img.pixels[5] = [f32::NAN, 0.0, 0.0];
    let mut attrs = inimtrace::io::exr::Attributes::new();
    attrs.set("inimtrace:experiment", "exp").set("inimtrace:eye_case", "Near").set("inimtrace:method", "LC");
    let e = inimtrace::io::exr::write_rgb_with(&dir.path().join("sim.exr"), &img, None, &attrs, Default::default())
        .unwrap_err()
        .to_string();
    assert!(!e.contains("bug in the renderer"), "{e}");
    assert!(e.contains("exp") && e.contains("Near") && e.contains("LC") && e.contains("row 1, col 1"), "{e}");
}

#[test]
fn the_pupil_warning_is_given_by_every_command_that_uses_a_pupil() {
    // An experiment warns of a 40 mm pupil; the single-image commands did not.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("gt.exr");
    let o = run(&["ground-truth", "--focus-diopters", "2", "--pupil", "40", "--retina", "8", "--out", p(&out)]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("warning:") && e.contains("--pupil = 40 mm"), "{e}");
}
