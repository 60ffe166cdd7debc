//! `--set` and `inimtrace sweep` on this machine, as a user runs them: overrides on numbers,
//! arrays, nested and indexed keys with errors that name the key; the tiny sweep as a product
//! and zipped, every point's scores equal to `assess --set ...` run by hand; a sweep killed
//! mid-way and resumed runs only the missing points, and its table has every row once.
#![deny(unsafe_code)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .current_dir(root())
        .args(args)
        .arg("--quiet")
        .output()
        .expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn expect_error(args: &[&str], needles: &[&str]) {
    let (ok, _, stderr) = inimtrace(args);
    assert!(!ok, "{args:?} should fail");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{args:?}: the message should name `{n}`: {stderr}");
    }
    assert_eq!(stderr.trim().lines().count(), 1, "one clear line: {stderr}");
}

/// Splits a CSV line into fields (quoted fields may hold commas).
fn csv_fields(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            c => out.last_mut().unwrap().push(c),
        }
    }
    out
}

/// `sweep.csv` as a header and rows of named fields.
fn read_csv(path: &Path) -> (Vec<String>, Vec<BTreeMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = csv_fields(lines.next().unwrap());
    let rows = lines
        .map(|l| {
            let f = csv_fields(l);
            assert_eq!(f.len(), header.len(), "{l}");
            header.iter().cloned().zip(f).collect()
        })
        .collect();
    (header, rows)
}

fn tiny() -> String {
    root().join("sweeps/tiny.toml").display().to_string()
}

/// The small display the tiny sweep uses, as a file.
fn small_display(dir: &Path) -> String {
    let text =
        std::fs::read_to_string(root().join("displays/paper.toml")).unwrap().replace("[2160, 2160]", "[540, 540]");
    let p = dir.join("display.toml");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn set_changes_numbers_arrays_nested_and_indexed_keys_on_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A number in the display: the central depth plane moves (v2 6.316 -> 6.2 mm).
    let (ok, base, e) = inimtrace(&["info"]);
    assert!(ok, "{e}");
    let (ok, moved, e) = inimtrace(&["info", "--set", "display.lenslets_to_lcd=6.2"]);
    assert!(ok, "{e}");
    assert!(base.contains("385.7 mm") && !moved.contains("385.7 mm") && moved.contains("v2 6.2 mm"), "{moved}");
    // An array (LCD resolution) and a nested, indexed key of the scene on render-display.
    let out = d.join("lc.exr");
    let (ok, _, e) = inimtrace(&[
        "render-display",
        "--set",
        "display.lcd.resolution=[270, 270]",
        "--set",
        "scene.objects[3].material.albedo=[1, 0, 0]",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{e}");
    let img = inimtrace::io::exr::read_rgb(&out).unwrap();
    assert_eq!((img.width, img.height), (270, 270));
    // The background (object 3) is now pure red: no pixel has green or blue above its red.
    assert!(img.pixels.iter().any(|p| p[0] == 1.0 && p[1] == 0.0 && p[2] == 0.0), "no red background pixel");
    assert!(!img.pixels.iter().any(|p| (p[1] - 0.7).abs() < 1e-6 && (p[2] - 0.8).abs() < 1e-6));
    // Indexed eye case and the eye on assess: the scores follow the overrides.
    let display = small_display(d);
    let run = |extra: &[&str], out: &str| -> serde_json::Value {
        let mut args = vec![
            "assess",
            "experiments/paper.toml",
            "--out",
            out,
            "--set",
            "eye.retina_resolution=48",
            "--set",
            "eye.pupil_grid=4",
        ];
        let disp = format!("display=\"{display}\"");
        args.extend(["--set", disp.as_str()]);
        args.extend(extra);
        let (ok, _, e) = inimtrace(&args);
        assert!(ok, "{e}");
        serde_json::from_str(&std::fs::read_to_string(Path::new(out).join("results.json")).unwrap()).unwrap()
    };
    let a = run(&[], d.join("a").to_str().unwrap());
    let b =
        run(&["--set", "eye_cases[1].focus_mm=600", "--set", "eye.pupil_diameter=3"], d.join("b").to_str().unwrap());
    assert_eq!(a["settings"]["eye"]["retina_resolution"], 48);
    assert_eq!(b["settings"]["eye_cases"][1]["focus_mm"], 600.0);
    assert_eq!(b["settings"]["eye"]["pupil_diameter"], 3.0);
    assert_eq!(b["settings"]["eye_cases"][2]["focus_mm"], 400.0, "other eye cases keep their settings");
    let psnr = |v: &serde_json::Value, case: &str| {
        v["scores"].as_array().unwrap().iter().find(|s| s["eye_case"] == case && s["method"] == "LC").unwrap()["psnr"]
            ["mean"]
            .as_f64()
            .unwrap()
    };
    assert_eq!(psnr(&a, "Pin"), psnr(&b, "Pin"), "a pinhole eye does not see the pupil");
    assert_ne!(psnr(&a, "Near"), psnr(&b, "Near"));
    let gt = inimtrace::io::exr::read_rgb(&d.join("b/gt_Near.exr")).unwrap();
    assert_eq!(gt.width, 48);
}

#[test]
fn set_errors_name_the_key() {
    expect_error(&["assess", "--set", "eye.pupil_diam=3"], &["eye.pupil_diam", "unknown field"]);
    expect_error(
        &["assess", "--set", "eye.pupil_diameter=\"wide\""],
        &["eye.pupil_diameter", "`wide` is not a pupil diameter"],
    );
    expect_error(&["assess", "--set", "eye.pupil_grid=[8]"], &["eye.pupil_grid", "invalid type"]);
    expect_error(&["assess", "--set", "eye_cases[7].focus_mm=300"], &["eye_cases[7]", "out of range"]);
    expect_error(&["assess", "--set", "eye.pupil_diameter.x=1"], &["eye.pupil_diameter", "not a table"]);
    expect_error(&["assess", "--set", "eye.pupil_diameter=-2"], &["eye.pupil_diameter", "--set eye.pupil_diameter=-2"]);
    // A malformed argument is a usage error, as clap reports it.
    let (ok, _, e) = inimtrace(&["assess", "--set", "eye.pupil_diameter"]);
    assert!(!ok && e.contains("KEY=VALUE") && !e.contains("panicked"), "{e}");
    expect_error(&["info", "--set", "display.lenslets.pich=1"], &["display.lenslets.pich", "unknown field"]);
    expect_error(&["info", "--set", "eye.pupil_diameter=3"], &["eye.pupil_diameter", "`display.`"]);
    expect_error(
        &["ground-truth", "--pinhole", "--set", "scene.objects[0].center=[0, 0]", "--out", "/tmp/x.exr"],
        &["scene.objects[0].center", "invalid length"],
    );
    expect_error(&["compare", "a.exr", "b.exr", "--set", "eye.pupil_diameter=3"], &["--set", "compare"]);
    expect_error(&["info", "--print", "paper-scene", "--set", "scene.name=x"], &["--set", "--print"]);
    expect_error(&["info", "--set", "scene.name=x"], &["scene.name", "`display.`"]);
}

/// Runs the tiny sweep into `out` with extra arguments.
fn sweep(out: &Path, extra: &[&str]) -> (bool, String, String) {
    let file = tiny();
    let mut args = vec!["sweep", file.as_str(), "--out", out.to_str().unwrap()];
    args.extend(extra);
    inimtrace(&args)
}

#[test]
fn a_local_sweep_is_a_product_of_zipped_axes_and_each_point_scores_as_assess_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiny");
    let (ok, stdout, stderr) = sweep(&out, &[]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("12 of 12 points complete"), "{stdout}");
    // LC and LA shared by all 12 points, PC once per eye position.
    assert!(stderr.contains("12 run") && stderr.contains("4 display images rendered"), "{stderr}");
    let (header, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(
        header,
        [
            "point",
            "id",
            "eye.pupil_diameter",
            "eye_cases[0].focus_diopters",
            "eye_cases[0].name",
            "eye.position",
            "method",
            "eye_case",
            "psnr_db",
            "psnr_ci95_db",
            "ssim",
            "ssim_ci95",
            "samples_per_pixel",
            "replicates",
            "target_met",
            "seconds"
        ]
    );
    // The grid estimator has no interval and no target: those columns are empty.
    for r in &rows {
        for col in ["psnr_ci95_db", "ssim_ci95", "samples_per_pixel", "replicates", "target_met"] {
            assert_eq!(r[col], "", "{col} of {r:?}");
        }
    }
    assert_eq!(rows.len(), 12 * 3);
    // Product: every pupil x eye x position once; zipped: the name moves with the focus.
    let combos: BTreeSet<(String, String, String)> = rows
        .iter()
        .map(|r| (r["eye.pupil_diameter"].clone(), r["eye_cases[0].focus_diopters"].clone(), r["eye.position"].clone()))
        .collect();
    assert_eq!(combos.len(), 12);
    for r in &rows {
        let expected = if r["eye_cases[0].focus_diopters"] == "0.0" { "Far" } else { "Near" };
        assert_eq!(r["eye_cases[0].name"], expected);
        assert_eq!(r["eye_case"], expected);
    }
    assert_eq!(rows[0]["eye.position"], "[0.0, 0.0, 0.0]");
    let ids: BTreeSet<&String> = rows.iter().map(|r| &r["id"]).collect();
    assert_eq!(ids.len(), 12, "one content hash per point");
    // The plots of each score against each numeric axis (not the array-valued position).
    for name in ["psnr_vs_eye.pupil_diameter", "ssim_vs_eye_cases_0_.focus_diopters"] {
        assert!(out.join("plots").join(format!("{name}.png")).is_file(), "{name}");
        assert!(out.join("plots").join(format!("{name}.svg")).is_file(), "{name}");
    }
    assert!(!out.join("plots/psnr_vs_eye.position.png").exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["base"]["eye"]["retina_resolution"], 64);
    assert_eq!(json["base"]["display"]["lcd"]["resolution"][0], 540, "the display inlined in the resolved base");
    assert_eq!(json["axes"][1].as_array().unwrap().len(), 2, "two zipped keys in one axis");
    assert_eq!(json["missing"].as_array().unwrap().len(), 0);

    // Two points by hand: `assess` with the point's --set arguments gives the same scores, to
    // the last digit.
    let experiment = json["experiment_file"].as_str().unwrap().to_string();
    for p in [3usize, 10] {
        let point = &json["points"][p];
        let by_hand = dir.path().join(format!("by-hand-{p}"));
        let mut args = vec!["assess".to_string(), experiment.clone(), "--out".into(), by_hand.display().to_string()];
        args.extend(point["assess_args"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, _, e) = inimtrace(&args);
        assert!(ok, "{e}");
        let csv = std::fs::read_to_string(by_hand.join("results.csv")).unwrap();
        let mut compared = 0;
        for line in csv.lines().filter(|l| l.starts_with("score,") && l.contains(",mean,")) {
            let f = csv_fields(line);
            let (method, case, psnr, ssim) = (&f[2], &f[3], &f[5], &f[6]);
            let row = rows
                .iter()
                .find(|r| r["point"] == p.to_string() && &r["method"] == method && &r["eye_case"] == case)
                .unwrap_or_else(|| panic!("no sweep row for point {p} {method} {case}"));
            assert_eq!(&row["psnr_db"], psnr, "point {p} {method} PSNR");
            assert_eq!(&row["ssim"], ssim, "point {p} {method} SSIM");
            compared += 1;
        }
        assert_eq!(compared, 3);
    }

    // A rerun finds every point complete and runs nothing.
    let (ok, _, stderr) = sweep(&out, &[]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("12 already complete, 0 run"), "{stderr}");
}

#[test]
fn a_killed_sweep_resumes_with_only_the_missing_points() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiny");
    let points = out.join("points");
    // Larger retina so that a point takes a moment, one thread so that they come one by one.
    let slow = ["--set", "eye.retina_resolution=256", "--set", "eye.pupil_grid=8"];
    let mut child = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .current_dir(root())
        .args(["--quiet", "--threads", "1", "sweep", &tiny(), "--out", out.to_str().unwrap()])
        .args(slow)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let records = |dir: &Path| -> BTreeMap<String, Vec<u8>> {
        std::fs::read_dir(dir)
            .map(|entries| {
                entries
                    .flatten()
                    .map(|e| e.file_name().into_string().unwrap())
                    .filter(|n| n.ends_with(".json") && !n.starts_with('.'))
                    .map(|n| (n.clone(), std::fs::read(dir.join(&n)).unwrap()))
                    .collect()
            })
            .unwrap_or_default()
    };
    let start = Instant::now();
    while records(&points).len() < 3 {
        assert!(start.elapsed() < Duration::from_secs(60), "no point finished");
        assert!(child.try_wait().unwrap().is_none(), "the sweep ended before it could be killed");
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = records(&points);
    assert!(before.len() >= 3 && before.len() < 12, "killed mid-way: {} points recorded", before.len());
    assert!(!out.join("sweep.csv").exists(), "a killed sweep wrote no table");

    // Collecting now lists the missing points.
    let (ok, stdout, e) = sweep(&out, &["--collect"].iter().chain(&slow).copied().collect::<Vec<_>>());
    assert!(ok, "{e}");
    let missing = 12 - before.len();
    assert!(stdout.contains(&format!("missing {}", inimtrace::count::count(missing, "point"))), "{stdout}");

    let (ok, _, stderr) = sweep(&out, &slow);
    assert!(ok, "{stderr}");
    assert!(stderr.contains(&format!("{} already complete, {missing} run", before.len())), "{stderr}");
    let after = records(&points);
    assert_eq!(after.len(), 12);
    for (name, bytes) in &before {
        assert_eq!(&after[name], bytes, "{name} ran again");
    }
    let (_, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 36);
    let keys: BTreeSet<(String, String)> = rows.iter().map(|r| (r["point"].clone(), r["method"].clone())).collect();
    assert_eq!(keys.len(), 36, "no duplicate row");
    let pts: BTreeSet<String> = rows.iter().map(|r| r["point"].clone()).collect();
    assert_eq!(pts.len(), 12, "no missing point");
}

#[test]
fn images_on_request_and_a_subset_of_points() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiny");
    let (ok, stdout, stderr) = sweep(&out, &["--points", "1,4", "--images"]);
    assert!(ok, "{stderr}");
    assert!(stdout.is_empty(), "--points collects nothing: {stdout}");
    assert!(stderr.contains("2 points asked for"), "{stderr}");
    let dirs: Vec<PathBuf> =
        std::fs::read_dir(out.join("points")).unwrap().flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
    assert_eq!(dirs.len(), 2);
    for d in &dirs {
        for f in ["results.json", "figure.png", "gt_Far.exr", "sim_PC_Far.exr", "display_LA.exr"] {
            assert!(d.join(f).is_file(), "{} lacks {f}", d.display());
        }
        assert!(out.join("points").join(format!("{}.json", d.file_name().unwrap().to_string_lossy())).is_file());
    }
    // The rest run without images; the two points with images are not run again.
    let (ok, stdout, stderr) = sweep(&out, &[]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("2 already complete, 10 run"), "{stderr}");
    assert!(stdout.contains("12 of 12 points complete"), "{stdout}");
}

#[test]
fn bad_sweeps_name_the_file_and_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let w = |name: &str, text: &str| -> String {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    let exp = root().join("experiments/paper.toml").display().to_string();
    let axis = w("axis.toml", &format!("experiment = \"{exp}\"\n[[axes]]\n\"eye.pupil_diam\" = [2, 3]\n"));
    expect_error(&["sweep", &axis], &["axis.toml axes", "eye.pupil_diam", "unknown field"]);
    let set = w("set.toml", &format!("experiment = \"{exp}\"\n[set]\n\"eye.retina_resolution\" = \"big\"\n"));
    expect_error(&["sweep", &set], &["set.toml [set]", "eye.retina_resolution", "invalid type"]);
    let bad = w("bad.toml", &format!("experiment = \"{exp}\"\n[[axes]]\n\"eye.pupil_diameter\" = [2, -1]\n"));
    expect_error(&["sweep", &bad], &["bad.toml point 1", "eye.pupil_diameter"]);
    let zip = w("zip.toml", &format!("experiment = \"{exp}\"\n[[axes]]\na = [1, 2]\nb = [1]\n"));
    expect_error(&["sweep", &zip], &["zip.toml", "axes[0].\"b\"", "zipped"]);
    let missing = w("missing.toml", "experiment = \"nowhere.toml\"\n");
    expect_error(&["sweep", &missing], &["missing.toml", "experiment", "nowhere.toml"]);
    expect_error(&["sweep", &tiny(), "--points", "5..20"], &["--points", "0..12"]);
    // A sweep that names points of different settings than the ones submitted.
    expect_error(&["sweep", &tiny(), "--points", "0", "--sweep-id", "0000000000000000"], &["submit again"]);
}

#[test]
fn a_converged_sweep_carries_each_scores_interval_as_assess_gives_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("converged.toml");
    let exp = root().join("experiments/paper-converged.toml");
    std::fs::write(
        &file,
        format!(
            "experiment = \"{}\"\n[set]\n\"display.lcd.resolution\" = [540, 540]\n\"eye.retina_resolution\" = 48\n\
             \"eye_cases\" = [{{ name = \"Eye\", focus_diopters = 2.5 }}]\n\"methods\" = [\"LC\", \"LA\"]\n\
             \"measurement.psnr_ci95_db\" = 0.3\n\"measurement.ssim_ci95\" = 0.02\n\"measurement.replicates\" = 4\n\
             [[axes]]\n\"eye.pupil_diameter\" = [2.0, 4.0]\n",
            exp.display()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, _, e) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{e}");
    let (_, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let (p, s): (f64, f64) = (r["psnr_ci95_db"].parse().unwrap(), r["ssim_ci95"].parse().unwrap());
        assert!(p > 0.0 && p < 1.0 && s > 0.0 && s < 0.05, "{r:?}");
    }
    // Point 1 by hand: the same scores and intervals.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let by_hand = dir.path().join("by-hand");
    let mut args = vec!["assess".to_string(), exp.display().to_string(), "--out".into(), by_hand.display().to_string()];
    args.extend(json["points"][1]["assess_args"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()));
    let (ok, _, e) = inimtrace(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{e}");
    let (header, results) = {
        let text = std::fs::read_to_string(by_hand.join("results.csv")).unwrap();
        let mut lines = text.lines();
        let header = csv_fields(lines.next().unwrap());
        let rows: Vec<Vec<String>> = lines.map(csv_fields).collect();
        (header, rows)
    };
    let col = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"));
    let mut compared = 0;
    for f in results.iter().filter(|f| f[0] == "score" && f[col("channel")] == "mean") {
        let row = rows.iter().find(|r| r["point"] == "1" && r["method"] == f[col("method")]).unwrap();
        for (ours, theirs) in
            [("psnr_db", "psnr_db"), ("psnr_ci95_db", "psnr_ci95_db"), ("ssim", "ssim"), ("ssim_ci95", "ssim_ci95")]
        {
            assert_eq!(row[ours], f[col(theirs)], "{ours} of {}", row["method"]);
        }
        compared += 1;
    }
    assert_eq!(compared, 2);
}

#[test]
fn a_sweep_with_a_tiny_time_budget_marks_the_rows_that_missed_and_strict_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("budget.toml");
    let exp = root().join("experiments/paper-converged.toml");
    // Point 0 has a microsecond to measure in (one round, wide intervals); point 1 ten minutes.
    std::fs::write(
        &file,
        format!(
            "name = \"budget\"\nexperiment = \"{}\"\n[set]\n\"display.lcd.resolution\" = [540, 540]\n\
             \"eye.retina_resolution\" = 32\n\"eye_cases\" = [{{ name = \"Eye\", focus_diopters = 2.5 }}]\n\
             \"methods\" = [\"LC\", \"LA\"]\n\"measurement.psnr_ci95_db\" = 0.5\n\"measurement.ssim_ci95\" = 0.05\n\
             \"measurement.replicates\" = 4\n[[axes]]\n\"measurement.max_seconds\" = [0.000001, 600.0]\n",
            exp.display()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let args = ["sweep", file.to_str().unwrap(), "--out", out.to_str().unwrap()];
    let status = |extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
            .current_dir(root())
            .arg("--quiet")
            .args(args)
            .args(extra)
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    // A miss is a result: exit 0, said once at the end with the count and where to look.
    let (code, stderr) = status(&[]);
    assert_eq!(code, Some(0), "{stderr}");
    let csv_path = out.join("sweep.csv").display().to_string();
    let note = stderr.lines().last().unwrap();
    assert!(note.starts_with("warning: sweep `budget`: 2 of 4 score rows missed their precision target"), "{stderr}");
    assert!(note.contains("in 1 of 2 points (index 0)") && note.contains(&csv_path), "{stderr}");

    let (_, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let (p, s): (f64, f64) = (r["psnr_ci95_db"].parse().unwrap(), r["ssim_ci95"].parse().unwrap());
        let met = p <= 0.5 && s <= 0.05;
        assert_eq!(r["target_met"], met.to_string(), "{r:?}");
        assert_eq!(r["target_met"], (r["point"] == "1").to_string(), "only the starved point misses: {r:?}");
        assert_eq!(r["replicates"], "4");
        let spp: u64 = r["samples_per_pixel"].parse().unwrap();
        // The starved point stops after its first round (4 samples per replicate).
        if r["point"] == "0" {
            assert_eq!(spp, 16, "{r:?}");
        } else {
            assert!(spp > 16 && spp.is_multiple_of(4), "{r:?}");
        }
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["rows_missing_target"], 2);
    assert_eq!(json["points_missing_target"], serde_json::json!([0]));
    assert_eq!(json["points"][0]["targets_missed"], 2);
    assert_eq!(json["points"][1]["targets_missed"], 0);
    for (p, met) in [(0, false), (1, true)] {
        for s in json["points"][p]["scores"].as_array().unwrap() {
            assert_eq!(s["target_met"], met, "{s}");
            assert!(s["psnr_ci95_db"].is_string() && s["samples_per_pixel"].is_u64(), "{s}");
        }
    }

    // --strict: the same results (nothing runs again), exit status 3; also on --collect.
    let before = std::fs::read(out.join("sweep.csv")).unwrap();
    let (code, stderr) = status(&["--strict"]);
    assert_eq!(code, Some(3), "{stderr}");
    assert!(stderr.contains("2 already complete, 0 run") && stderr.contains("--strict: 2 scores"), "{stderr}");
    assert_eq!(std::fs::read(out.join("sweep.csv")).unwrap(), before);
    let (code, stderr) = status(&["--collect", "--strict"]);
    assert_eq!(code, Some(3), "{stderr}");

    // Targets the first round meets: --strict exits 0 and nothing is said of targets.
    let met = dir.path().join("met");
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .current_dir(root())
        .args(["--quiet", "sweep", file.to_str().unwrap(), "--out", met.to_str().unwrap(), "--strict"])
        .args(["--set", "measurement.psnr_ci95_db=50", "--set", "measurement.ssim_ci95=0.5"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let (_, rows) = read_csv(&met.join("sweep.csv"));
    assert!(rows.len() == 4 && rows.iter().all(|r| r["target_met"] == "true"), "{rows:?}");
    assert!(!stderr.contains("precision target"), "{stderr}");
}

/// OPT in a sweep: its display image is keyed on its resolved `[optimize]` settings, so points
/// whose training states differ (a trained eye case's focus) get their own, and points that
/// differ only in what OPT does not train on (a held-out case's focus) share one. Each point's
/// OPT scores are those of `assess` by hand, to the last digit.
#[test]
fn a_sweep_with_opt_keys_its_display_image_on_the_optimize_settings() {
    let dir = tempfile::tempdir().unwrap();
    let exp = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let sweep = dir.path().join("opt.toml");
    std::fs::write(
        &sweep,
        format!(
            "name = \"opt\"\nexperiment = {:?}\n[set]\n\"methods\" = [\"LA\", \"OPT\"]\n\
             \"display.lcd.resolution\" = [540, 540]\n\"eye.retina_resolution\" = 24\n\"eye.pupil_grid\" = 2\n\
             \"optimize\" = {{ train_cases = [\"Near\", \"Cen\"], iterations = 3, pupil_grid = 2 }}\n\
             [[axes]]\n\"eye_cases[1].focus_mm\" = [300.0, 320.0]\n[[axes]]\n\"eye_cases[3].focus_mm\" = [600.0, 700.0]\n",
            exp.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, stdout, stderr) = inimtrace(&["sweep", sweep.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("4 of 4 points complete"), "{stdout}");
    // LA once for all four points; OPT once per trained focus (two), shared across the held-out one.
    assert!(stderr.contains("4 run") && stderr.contains("3 display images rendered"), "{stderr}");
    let (_, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 4 * 2 * 4, "4 points x 2 methods x 4 eye cases");
    let opt = |point: &str, case: &str| {
        rows.iter()
            .find(|r| r["point"] == point && r["method"] == "OPT" && r["eye_case"] == case)
            .map(|r| r["psnr_db"].clone())
            .unwrap()
    };
    // Points 0 and 1 differ only in the held-out Far focus: the same OPT image, the same Cen score.
    // Points 0 and 2 differ in the trained Near focus: different OPT images.
    assert_eq!(opt("0", "Cen"), opt("1", "Cen"));
    assert_ne!(opt("0", "Cen"), opt("2", "Cen"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let experiment = json["experiment_file"].as_str().unwrap().to_string();
    for p in [1usize, 2] {
        let point = &json["points"][p];
        let by_hand = dir.path().join(format!("by-hand-{p}"));
        let mut args = vec!["assess".to_string(), experiment.clone(), "--out".into(), by_hand.display().to_string()];
        args.extend(point["assess_args"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, _, e) = inimtrace(&args);
        assert!(ok, "{e}");
        let csv = std::fs::read_to_string(by_hand.join("results.csv")).unwrap();
        let mut compared = 0;
        for line in csv.lines().filter(|l| l.starts_with("score,") && l.contains(",mean,")) {
            let f = csv_fields(line);
            let (method, case, psnr) = (&f[2], &f[3], &f[5]);
            if method == "OPT" {
                assert_eq!(&opt(&p.to_string(), case), psnr, "point {p} OPT {case}");
                compared += 1;
            }
        }
        assert_eq!(compared, 4);
    }
}
