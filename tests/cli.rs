//! The command line as a user meets it: a small experiment end to end, and bad input that must
//! fail with a clear message naming the file and the field, never a panic.
#![deny(unsafe_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).arg("--quiet").output().expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A small version of the paper's experiment (quarter-resolution LCD, 64 x 64 retina).
fn small_experiment(dir: &Path) -> PathBuf {
    let display =
        std::fs::read_to_string(root().join("displays/paper.toml")).unwrap().replace("[2160, 2160]", "[540, 540]");
    std::fs::write(dir.join("display.toml"), display).unwrap();
    let exp = std::fs::read_to_string(root().join("experiments/paper.toml"))
        .unwrap()
        .replace("../scenes/paper.toml", &root().join("scenes/paper.toml").display().to_string())
        .replace("../displays/paper.toml", "display.toml")
        .replace("retina_resolution = 512", "retina_resolution = 64")
        .replace("pupil_grid = 8", "pupil_grid = 4")
        .replace("name = \"paper\"", "name = \"small\"");
    let path = dir.join("small.toml");
    std::fs::write(&path, exp).unwrap();
    path
}

#[test]
fn assess_writes_every_output_with_the_documented_names() {
    let dir = tempfile::tempdir().unwrap();
    let exp = small_experiment(dir.path());
    let out = dir.path().join("out");
    let (ok, stdout, stderr) = inimtrace(&["assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("| Near |"), "{stdout}");
    let mut names = vec!["table.md".to_string(), "results.csv".into(), "results.json".into(), "figure.png".into()];
    for c in ["Pin", "Near", "Cen", "Far"] {
        names.push(format!("gt_{c}.exr"));
        names.push(format!("gt_{c}.png"));
        for m in ["LC", "PC", "LA"] {
            names.push(format!("sim_{m}_{c}.exr"));
            names.push(format!("sim_{m}_{c}.png"));
        }
    }
    for m in ["LC", "PC", "LA"] {
        names.push(format!("display_{m}.exr"));
        names.push(format!("display_{m}.png"));
    }
    for n in &names {
        assert!(out.join(n).is_file(), "missing {n}");
    }
    let gt = inimtrace::io::exr::read_rgb(&out.join("gt_Near.exr")).unwrap();
    assert_eq!((gt.width, gt.height), (64, 64));
    assert!(gt.all_finite());
    let d = inimtrace::io::exr::read_rgb(&out.join("display_LA.exr")).unwrap();
    assert_eq!((d.width, d.height), (540, 540));
    let attrs = inimtrace::io::exr::read_attributes(&out.join("sim_PC_Near.exr")).unwrap();
    let get = |k: &str| attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.clone()).unwrap_or_default();
    assert_eq!(get("inimtrace:method"), "PC");
    assert_eq!(get("inimtrace:eye_case"), "Near");
    assert_eq!(get("inimtrace:focus_mm"), "300");
    assert_eq!(get("inimtrace:pupil_diameter_mm"), "5");
    assert!(get("inimtrace:units").contains("mm"));
    // The table's numbers are the JSON's, and none is NaN.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let scores = json["scores"].as_array().unwrap();
    assert_eq!(scores.len(), 12);
    for s in scores {
        let p = s["psnr"]["mean"].as_f64().unwrap();
        let q = s["ssim"]["mean"].as_f64().unwrap();
        assert!(p.is_finite() && p > 5.0 && p < 60.0 && q > 0.0 && q <= 1.0, "{s}");
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().filter(|l| l.starts_with("score,")).count(), 12 * 4);
    assert!(csv.contains("stage,small,LA,,,,,render_display,"));
    assert!(!csv.contains("NaN") && !csv.to_lowercase().contains(",nan"));

    // compare: an image against itself, and the stages on their own agree with assess.
    let gt_path = out.join("gt_Near.exr");
    let (ok, stdout, stderr) = inimtrace(&["compare", gt_path.to_str().unwrap(), gt_path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("SSIM  1.00000"), "{stdout}");
    let sim = dir.path().join("sim.exr");
    let display = dir.path().join("display.toml");
    let (ok, _, stderr) = inimtrace(&[
        "simulate",
        out.join("display_LC.exr").to_str().unwrap(),
        "--display",
        display.to_str().unwrap(),
        "--focus-mm",
        "300",
        "--pupil-grid",
        "4",
        "--retina",
        "64",
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let a = inimtrace::io::exr::read_rgb(&sim).unwrap();
    let b = inimtrace::io::exr::read_rgb(&out.join("sim_LC_Near.exr")).unwrap();
    assert!(a == b, "simulate from the written display image equals assess's simulation");
}

fn expect_error(args: &[&str], needles: &[&str]) {
    let (ok, _, stderr) = inimtrace(args);
    assert!(!ok, "{args:?} should fail");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{args:?}: message should name `{n}`: {stderr}");
    }
    assert_eq!(stderr.trim().lines().count(), 1, "one clear line: {stderr}");
}

#[test]
fn bad_input_gives_one_clear_error_and_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let w = |name: &str, text: &str| -> String {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    let good_display = std::fs::read_to_string(root().join("displays/paper.toml")).unwrap();
    let out = d.join("o").display().to_string();
    let out_exr = d.join("o.exr").display().to_string();

    expect_error(&["assess", "does-not-exist.toml"], &["does-not-exist.toml"]);
    expect_error(&["assess", d.to_str().unwrap()], &["directory"]);
    let p = w("empty.toml", "");
    expect_error(&["assess", &p, "--out", &out], &["empty.toml", "name"]);
    let p = w("syntax.toml", "name = \"x\"\n[eye\n");
    expect_error(&["assess", &p, "--out", &out], &["syntax.toml", "line 2"]);
    let p = w(
        "types.toml",
        "name = \"x\"\n[eye]\npupil_diameter = \"five\"\n[[eye_cases]]\nname = \"A\"\npinhole = true\n",
    );
    expect_error(&["assess", &p, "--out", &out], &["types.toml", "pupil_diameter"]);
    let p = w("unknown.toml", "name = \"x\"\nfocus = 3\n[[eye_cases]]\nname = \"A\"\npinhole = true\n");
    expect_error(&["assess", &p, "--out", &out], &["unknown.toml", "focus"]);
    let p = w(
        "negpupil.toml",
        "name = \"x\"\n[eye]\npupil_diameter = -5.0\n[[eye_cases]]\nname = \"A\"\nfocus_mm = 300.0\n",
    );
    expect_error(&["assess", &p, "--out", &out], &["negpupil.toml", "pupil_diameter"]);
    let p = w("nanfocus.toml", "name = \"x\"\n[[eye_cases]]\nname = \"A\"\nfocus_mm = nan\n");
    expect_error(&["assess", &p, "--out", &out], &["nanfocus.toml", "focus_mm"]);

    let p = w("f.toml", &good_display.replace("focal_length = 6.427", "focal_length = -6.427"));
    expect_error(&["info", "--display", &p], &["f.toml", "focal_length"]);
    let p = w("res.toml", &good_display.replace("[2160, 2160]", "[0, 2160]"));
    expect_error(&["info", "--display", &p], &["res.toml", "lcd.resolution[0]"]);
    let p = w("sing.toml", &good_display.replace("pitch = 1.2", "pitch = [[1.2, 2.4], [0.6, 1.2]]"));
    expect_error(&["info", "--display", &p], &["sing.toml", "lenslets.pitch", "singular"]);
    let p = w("size.toml", &good_display.replace("size = [21.6, 21.6]", "size = [-21.6, 21.6]"));
    expect_error(&["info", "--display", &p], &["size.toml", "lcd.size[0]"]);
    let yaml = std::fs::read_to_string(root().join("data/lensletdisplay.yaml")).unwrap();
    let p = w("nan.yaml", &yaml.replace("lenslettoorigin: 20.", "lenslettoorigin: .nan"));
    expect_error(&["info", "--display", &p], &["nan.yaml", "lenslettoorigin"]);
    let p = w("missing.yaml", &yaml.replace("lensletfocallength: 6.427\n", ""));
    expect_error(&["info", "--display", &p], &["missing.yaml", "lensletfocallength", "missing"]);
    let p = w("broken.yaml", "%YAML:1.0\n---\nlenslettolcd: [1, 2\n");
    expect_error(&["info", "--display", &p], &["broken.yaml"]);

    // PupilCenter at the singular configuration: the lenslet images the pupil centre onto the LCD.
    let singular = good_display
        .replace("lenslets_to_lcd = 6.316", &format!("lenslets_to_lcd = {}", 1.0 / (1.0 / 6.427 - 1.0 / 20.0)));
    let sp = w("singular.toml", &singular);
    let e = std::fs::read_to_string(root().join("experiments/paper.toml"))
        .unwrap()
        .replace("../scenes/paper.toml", "builtin:paper")
        .replace("../displays/paper.toml", &sp);
    let p = w("pc.toml", &e);
    expect_error(&["assess", &p, "--out", &out], &["PupilCenter", "image the pupil centre onto the LCD"]);

    // Broken EXR input.
    let p = w("bad.exr", "this is not an EXR file");
    expect_error(&["compare", &p, &p], &["bad.exr"]);
    let p = w("empty.exr", "");
    expect_error(&["simulate", &p, "--pinhole", "--out", &out_exr], &["empty.exr"]);

    // An EXR display image holding NaN: refused with the pixel and channel named.
    {
        use exr::prelude::*;
        let mut g = vec![0.5f32; 16];
        g[5] = f32::NAN;
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            AnyChannel::new("R", FlatSamples::F32(vec![0.5; 16])),
            AnyChannel::new("G", FlatSamples::F32(g)),
            AnyChannel::new("B", FlatSamples::F32(vec![0.5; 16])),
        ]));
        let p = d.join("nan.exr");
        Image::from_channels((4, 4), channels).write().to_file(&p).unwrap();
        expect_error(
            &["simulate", p.to_str().unwrap(), "--pinhole", "--out", &out_exr],
            &["nan.exr", "row 1", "col 1", "channel G"],
        );
    }

    // An output directory that cannot be created.
    let blocker = w("blocker", "a file where a directory should be");
    expect_error(&["assess", "--out", &format!("{blocker}/sub")], &["blocker"]);
}

/// The broken inputs kept under tests/data/bad/, run as a new user would: each exits non-zero
/// with one line naming the file and the field or line, never panics, and leaves no
/// `results.json` (the marker of a complete run) behind.
#[test]
fn every_file_in_tests_data_bad_fails_cleanly() {
    let bad = root().join("tests/data/bad");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let f = |name: &str| bad.join(name).display().to_string();
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (vec!["assess".into(), f("missing.toml")], vec!["missing.toml", "No such file"]),
        (vec!["assess".into(), f("a_directory.obj")], vec!["a_directory.obj", "directory"]),
        (vec!["assess".into(), f("empty.toml")], vec!["empty.toml", "missing field `name`"]),
        (vec!["assess".into(), f("not_utf8.toml")], vec!["not_utf8.toml", "UTF-8"]),
        (vec!["assess".into(), f("wrong_type.toml")], vec!["wrong_type.toml", "line 3", "pupil_diameter"]),
        (vec!["assess".into(), f("unknown_key.toml")], vec!["unknown_key.toml", "line 2", "focus"]),
        (vec!["assess".into(), f("negative_pupil.toml")], vec!["negative_pupil.toml", "pupil_diameter"]),
        (vec!["assess".into(), f("nan_focus.toml")], vec!["nan_focus.toml", "focus_mm"]),
        (
            vec!["info".into(), "--display".into(), f("negative_size_display.toml")],
            vec!["negative_size_display.toml", "lcd.size[0]"],
        ),
        (
            vec!["info".into(), "--display".into(), f("zero_resolution_display.toml")],
            vec!["zero_resolution_display.toml", "lcd.resolution[0]"],
        ),
        (
            vec!["info".into(), "--display".into(), f("singular_pitch_display.toml")],
            vec!["singular_pitch_display.toml", "lenslets.pitch", "singular"],
        ),
        (vec!["info".into(), "--display".into(), f("nan_display.yaml")], vec!["nan_display.yaml", "lenslettoorigin"]),
        (vec!["info".into(), "--display".into(), f("malformed_display.yaml")], vec!["malformed_display.yaml", "YAML"]),
        (vec!["compare".into(), f("truncated.exr"), f("truncated.exr")], vec!["truncated.exr"]),
        (vec!["simulate".into(), f("text.exr"), "--pinhole".into()], vec!["text.exr"]),
    ];
    // Broken meshes reached through a scene file, as a user would.
    let mesh_scene = |mesh: &str| -> String {
        let p = dir.path().join(format!("scene_{mesh}.toml"));
        std::fs::write(
            &p,
            format!("name = \"m\"\nallow_outside_paths = true\n[[objects]]\ntype = \"mesh\"\nfile = \"{}\"\nmaterial = {{ albedo = [1.0, 1.0, 1.0] }}\n", f(mesh)),
        )
        .unwrap();
        p.display().to_string()
    };
    let mut cases = cases;
    for (mesh, needles) in [
        ("truncated.ply", vec!["truncated.ply", "face 3 of 5"]),
        ("index_out_of_range.obj", vec!["index_out_of_range.obj", "line 5"]),
        ("nan_vertex.obj", vec!["nan_vertex.obj", "line"]),
        ("empty.obj", vec!["empty.obj"]),
    ] {
        cases.push((vec!["ground-truth".into(), "--scene".into(), mesh_scene(mesh), "--pinhole".into()], needles));
    }
    for (mut args, needles) in cases {
        if args[0] == "ground-truth" {
            args.extend(["--out".into(), format!("{o}/gt.exr")]);
        }
        if args[0] == "assess" || args[0] == "simulate" {
            args.extend(["--out".into(), if args[0] == "assess" { o.into() } else { format!("{o}/sim.exr") }]);
        }
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        expect_error(&refs, &needles);
        assert!(!out.join("results.json").exists(), "{args:?} left a complete-looking run behind");
    }
}

/// Splits one CSV line (fields with commas are quoted, `""` is a quote).
fn csv_fields(line: &str) -> Vec<String> {
    let (mut fields, mut cur, mut quoted, mut chars) = (Vec::new(), String::new(), false, line.chars().peekable());
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    fields.push(cur);
    fields
}

/// `inimtrace bench --quick` writes its CSVs, JSON, Markdown report and plots; every backend
/// that can render the paper's scene measures every method on the display image and on each
/// focused eye case; the convergence series approach their references; LA with k = 1 is LC; the
/// cost of precision measures every Table 1 estimator against a converged reference (the grid
/// estimator at the paper's settings being `assess`'s Table 1), and its thresholds are what its
/// points say.
#[test]
fn bench_quick_writes_well_formed_reports() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let (ok, stdout, stderr) = inimtrace(&["bench", "--quick", "--out", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("| la_grid |"), "{stdout}");
    for f in ["bench.csv", "builds.csv", "bench.json", "bench.md", "summary.md"] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    for name in ["speed_psnr", "speed_ssim", "la_grid", "pupil_grid", "retina_samples", "precision"] {
        let png = std::fs::read(out.join(format!("{name}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 10_000, "{name}.png");
        let svg = std::fs::read_to_string(out.join(format!("{name}.svg"))).unwrap();
        assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"), "{name}.svg");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let rows = report["rows"].as_array().unwrap();
    let backends: Vec<&str> = report["backends"].as_array().unwrap().iter().map(|b| b.as_str().unwrap()).collect();
    let mut expected = vec!["analytic-fused", "analytic"];
    if cfg!(feature = "embree") {
        expected.push("embree");
    }
    expected.push("bvh");
    assert_eq!(backends, expected);

    // Every row: finite scores, a time, its settings and provenance.
    for r in rows {
        let psnr = r["psnr_db"].as_f64().unwrap();
        let ssim = r["ssim"].as_f64().unwrap();
        assert!(psnr.is_finite() && psnr > 5.0 && psnr < 200.0, "{r}");
        assert!(ssim > 0.0 && ssim <= 1.0, "{r}");
        assert!(r["seconds"].as_f64().unwrap() > 0.0 && r["rays_per_second"].as_f64().unwrap() > 0.0, "{r}");
        assert!(r["git_revision"].as_str().is_some_and(|s| !s.is_empty()), "{r}");
        assert!(r["threads"].as_u64().unwrap() >= 1 && r["cores"].as_u64().unwrap() >= 1, "{r}");
        assert_eq!(r["lcd_resolution"], 540);
        assert_eq!(r["retina_resolution"], 128);
        assert!(!r["reference"].as_str().unwrap().is_empty(), "{r}");
    }

    // Methods x backends: the display image and every focused eye case of the paper's
    // experiment (Near 300, Cen 400, Far 600 mm).
    let cases: Vec<(String, f64)> = report["eye_cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c[0].as_str().unwrap().to_string(), c[1].as_f64().unwrap()))
        .collect();
    assert_eq!(cases, [("Near".to_string(), 300.0), ("Cen".to_string(), 400.0), ("Far".to_string(), 600.0)]);
    let method_row = |b: &str, m: &str, eye: &str| {
        let found: Vec<&serde_json::Value> = rows
            .iter()
            .filter(|r| r["series"] == "method" && r["backend"] == b && r["method"] == m && r["eye_case"] == eye)
            .collect();
        assert_eq!(found.len(), 1, "{b} {m} {eye}");
        found[0]
    };
    for m in ["LC", "PC", "LA"] {
        for eye in ["", "Near", "Cen", "Far"] {
            let reference = method_row("analytic-fused", m, eye);
            assert_eq!(reference["quantity"], if eye.is_empty() { "display" } else { "perceived" });
            for b in &backends {
                let r = method_row(b, m, eye);
                // Same scene, same rays: the analytic kernels agree bit for bit, and the mesh
                // backends (tessellated rectangles) to well within a hundredth of a dB.
                let d = (r["psnr_db"].as_f64().unwrap() - reference["psnr_db"].as_f64().unwrap()).abs();
                assert!(if *b == "analytic" { d == 0.0 } else { d < 0.01 }, "{b} {m} {eye}: {d} dB");
                if !eye.is_empty() {
                    let display = method_row(b, m, "");
                    assert!(r["seconds"].as_f64().unwrap() > display["seconds"].as_f64().unwrap());
                    assert_eq!(r["pupil_grid"], 8);
                }
            }
        }
        // LA (5 x 5) traces 25 times LC's camera rays.
        assert_eq!(method_row("bvh", "LA", "")["rays"], 25 * method_row("bvh", "LC", "")["rays"].as_u64().unwrap());
    }
    // LA is the most accurate method for every focused eye (the paper's finding).
    for (eye, _) in &cases {
        let p = |m: &str| method_row("analytic-fused", m, eye)["psnr_db"].as_f64().unwrap();
        assert!(p("LA") > p("LC") && p("LC") > p("PC"), "{eye}");
    }

    // Convergence: each series gets closer to its reference overall, at a stated rate.
    let series = |s: &str| -> Vec<(u64, f64)> {
        rows.iter()
            .filter(|r| r["series"] == s)
            .map(|r| (r["parameter"].as_u64().unwrap(), r["psnr_db"].as_f64().unwrap()))
            .collect()
    };
    assert_eq!(series("la_grid").iter().map(|p| p.0).collect::<Vec<_>>(), (1..=8).collect::<Vec<_>>());
    assert_eq!(series("pupil_grid").iter().map(|p| p.0).collect::<Vec<_>>(), [2, 3, 4, 5, 6, 8, 10, 12, 16]);
    assert_eq!(series("retina_samples").iter().map(|p| p.0).collect::<Vec<_>>(), [1, 2, 3, 4]);
    for s in ["la_grid", "pupil_grid", "retina_samples"] {
        let pts = series(s);
        assert!(pts.last().unwrap().1 > pts[0].1 + 8.0, "{s}: {pts:?}");
        // Overall decrease: no point falls more than 0.5 dB below the point at half its index.
        for i in 2..pts.len() {
            assert!(pts[i].1 > pts[i / 2].1 - 0.5, "{s}: {pts:?}");
        }
        let c = report["convergence"].as_array().unwrap().iter().find(|c| c["series"] == s).unwrap();
        let rate = c["rate"].as_f64().unwrap();
        assert!((-2.0..-0.2).contains(&rate), "{s}: rate {rate}");
        assert_eq!(c["converged_psnr_db"].as_f64().unwrap(), pts.last().unwrap().1);
        let within = &c["first_within_tolerance"];
        let first = pts.iter().position(|p| p.1 >= pts.last().unwrap().1 - 0.1).unwrap();
        assert_eq!(within["parameter"].as_u64().unwrap(), pts[first].0, "{s}");
    }
    // LA at k = 1 is LC, bit for bit.
    assert_eq!(report["checks"]["la_k1_equals_lc"], true);

    // Builds: each mesh backend over the 4 tessellated rectangles.
    let builds = report["builds"].as_array().unwrap();
    assert_eq!(builds.len(), expected.len() - 2);
    for b in builds {
        assert_eq!(b["triangles"], 8);
        assert!(b["build_seconds"].as_f64().unwrap() >= 0.0);
    }
    let builds_csv = std::fs::read_to_string(out.join("builds.csv")).unwrap();
    assert_eq!(builds_csv.lines().count(), builds.len() + 1);
    assert!(builds_csv.lines().any(|l| l.starts_with("bvh,8,")), "{builds_csv}");

    // The CSV holds the same rows, every line as many fields as the header.
    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let lines: Vec<Vec<String>> = csv.lines().map(csv_fields).collect();
    assert_eq!(lines.len(), rows.len() + 1);
    let col = |name: &str| lines[0].iter().position(|h| h == name).unwrap();
    for (fields, r) in lines[1..].iter().zip(rows) {
        assert_eq!(fields.len(), lines[0].len(), "{fields:?}");
        assert_eq!(fields[col("series")], r["series"].as_str().unwrap());
        assert_eq!(fields[col("sweep")], r["sweep"].as_str().unwrap());
        assert_eq!(fields[col("estimator")], r["estimator"].as_str().unwrap_or(""));
        assert_eq!(fields[col("backend")], r["backend"].as_str().unwrap());
        assert_eq!(fields[col("reference")], r["reference"].as_str().unwrap());
        // (serde_json's float parsing may differ from Rust's in the last bit.)
        let (a, b) = (fields[col("psnr_db")].parse::<f64>().unwrap(), r["psnr_db"].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-12 * b.abs(), "{a} {b}");
    }

    // The Markdown report: the methods x backends table, builds, convergence and the check.
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    for needle in ["| LA | bvh |", "| LC | analytic-fused |", "| bvh | 8 |", "rate p", "bit for bit the same"] {
        assert!(md.contains(needle), "bench.md lacks `{needle}`");
    }
    assert!(std::fs::read_to_string(out.join("summary.md")).unwrap().contains("| PC | analytic |"));

    check_precision_series(&report, &stdout, &out, dir.path());
}

/// The `precision` rows and summary of a `bench --quick` report.
fn check_precision_series(report: &serde_json::Value, stdout: &str, out: &Path, dir: &Path) {
    let rows: Vec<&serde_json::Value> =
        report["rows"].as_array().unwrap().iter().filter(|r| r["series"] == "precision").collect();
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap();
    let u = |r: &serde_json::Value, k: &str| r[k].as_u64().unwrap() as usize;
    let cases = ["Pin", "Near", "Cen", "Far"];
    let methods = ["LC", "PC", "LA"];
    let p = &report["precision"];
    // The reference: the tight target met, one row per method and eye case.
    assert!(f(p, "reference_ci95_db") <= f(p, "reference_target_db") && f(p, "reference_target_db") <= 0.01, "{p}");
    assert_eq!(p["reference_stopped_by"], "target met");
    let reference: Vec<&serde_json::Value> = rows.iter().copied().filter(|r| r["estimator"] == "reference").collect();
    assert_eq!(reference.len(), 12);
    let ref_psnr = |case: &serde_json::Value, method: &serde_json::Value| {
        f(reference.iter().find(|r| &r["eye_case"] == case && &r["method"] == method).unwrap(), "psnr_db")
    };
    // Quick sizes: 4 grid settings, 6 sample counts of 8 replicates.
    let points = p["points"].as_array().unwrap();
    let spp = [8, 16, 32, 64, 128, 256];
    let expect: [(&str, Vec<usize>); 4] = [
        ("grid", vec![12, 52, 208, 1872]),
        ("random", spp.to_vec()),
        ("rqmc_naive", spp.to_vec()),
        ("rqmc", spp.to_vec()),
    ];
    let mut errors: Vec<(&str, usize, f64, f64)> = Vec::new();
    for (e, counts) in &expect {
        let pts: Vec<&serde_json::Value> = points.iter().filter(|q| q["estimator"] == *e).collect();
        assert_eq!(pts.iter().map(|q| u(q, "samples_per_pixel")).collect::<Vec<_>>(), *counts, "{e}");
        for q in &pts {
            let n = u(q, "samples_per_pixel");
            let pt: Vec<&serde_json::Value> =
                rows.iter().copied().filter(|r| r["estimator"] == *e && u(r, "samples") == n).collect();
            // Every method under every eye case, with finite scores and the point's seconds.
            assert_eq!(pt.len(), 12, "{e} {n}");
            let mut worst = 0.0f64;
            for r in &pt {
                assert!(
                    cases.contains(&r["eye_case"].as_str().unwrap())
                        && methods.contains(&r["method"].as_str().unwrap())
                );
                assert_eq!(r["quantity"], "perceived");
                let (db, ssim) = (f(r, "psnr_db"), f(r, "ssim"));
                assert!(db.is_finite() && db > 5.0 && db < 60.0 && ssim > 0.0 && ssim < 1.0, "{r}");
                assert_eq!(f(r, "seconds"), f(q, "seconds"));
                worst = worst.max((db - ref_psnr(&r["eye_case"], &r["method"])).abs());
            }
            // The point's error is the largest over its rows.
            assert!((f(q, "max_psnr_error_db") - worst).abs() < 1e-9, "{e} {n}: {q} vs {worst}");
            // Its time is recorded (not compared between points: wall time under a loaded machine is no
            // property of the code; costs are measured in SPEED.md).
            assert!(f(q, "max_ssim_error").is_finite() && f(q, "seconds") > 0.0, "{q}");
            errors.push((e, n, worst, f(q, "seconds")));
        }
    }
    let err = |e: &str, n: usize| errors.iter().find(|x| x.0 == e && x.1 == n).unwrap().2;
    for n in spp {
        // The naive PSNR is biased by the noise left in the images; the de-biased one is not.
        assert!(err("rqmc", n) < err("rqmc_naive", n), "{n}: {} vs {}", err("rqmc", n), err("rqmc_naive", n));
    }
    // Scrambled Sobol points beat independent ones with the same naive scores, once there are
    // enough samples per replicate for the stratification to show.
    assert!(err("rqmc_naive", 256) < err("random", 256));
    // More samples, closer to converged: the naive bias falls as 1/N (32x over the sweep), the
    // de-biased error with the noise of the estimate.
    assert!(err("random", 256) * 4.0 < err("random", 8));
    assert!(err("rqmc_naive", 256) * 4.0 < err("rqmc_naive", 8));
    assert!(err("rqmc", 256) < err("rqmc", 8));

    // The thresholds: for each estimator and target, the first point after which every point
    // is within the target, or none.
    let reached = p["reached"].as_array().unwrap();
    assert_eq!(reached.len(), 16);
    for r in reached {
        let (e, target) = (r["estimator"].as_str().unwrap(), f(r, "target_db"));
        let mine: Vec<&(&str, usize, f64, f64)> = errors.iter().filter(|x| x.0 == e).collect();
        let first = (0..mine.len()).find(|&i| mine[i..].iter().all(|x| x.2 <= target));
        match first {
            Some(i) => {
                assert_eq!(r["seconds"].as_f64(), Some(mine[i].3), "{r}");
                assert_eq!(r["samples_per_pixel"].as_u64(), Some(mine[i].1 as u64), "{r}");
                let line =
                    format!("precision {e}: +-{target} dB in {:.3} s ({} samples per pixel)", mine[i].3, mine[i].1);
                assert!(stdout.contains(&line), "{line}\n{stdout}");
            }
            None => {
                assert!(r["seconds"].is_null() && r["samples_per_pixel"].is_null(), "{r}");
                assert!(stdout.contains(&format!("precision {e}: +-{target} dB not reached")), "{stdout}");
            }
        }
    }

    // The grid estimator at the paper's settings (pupil grid 8, 1 sample per retina pixel).
    let paper_table: Vec<f64> = (0..12)
        .map(|i| {
            let r = rows
                .iter()
                .find(|r| {
                    r["estimator"] == "grid"
                        && u(r, "pupil_grid") == 8
                        && u(r, "retina_samples") == 1
                        && r["eye_case"] == cases[i / 3]
                        && r["method"] == methods[i % 3]
                })
                .unwrap();
            f(r, "psnr_db")
        })
        .collect();
    let paper_tables = [paper_table];
    // It is `inimtrace assess`'s Table 1 for the same display, retina and settings.
    let display =
        std::fs::read_to_string(root().join("displays/paper.toml")).unwrap().replace("[2160, 2160]", "[540, 540]");
    std::fs::write(dir.join("display-540.toml"), display).unwrap();
    let exp = std::fs::read_to_string(root().join("experiments/paper.toml"))
        .unwrap()
        .replace("../scenes/paper.toml", "builtin:paper")
        .replace("../displays/paper.toml", "display-540.toml")
        .replace("retina_resolution = 512", "retina_resolution = 128");
    std::fs::write(dir.join("quick.toml"), exp).unwrap();
    let assessed = dir.join("assessed");
    let (ok, _, stderr) =
        inimtrace(&["assess", dir.join("quick.toml").to_str().unwrap(), "--out", assessed.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(assessed.join("results.json")).unwrap()).unwrap();
    let scores = results["scores"].as_array().unwrap();
    assert_eq!(scores.len(), 12);
    for (i, v) in paper_tables[0].iter().enumerate() {
        let s = scores.iter().find(|s| s["eye_case"] == cases[i / 3] && s["method"] == methods[i % 3]).unwrap();
        let a = s["psnr"]["mean"].as_f64().unwrap();
        assert!((a - v).abs() <= 1e-9 * a.abs(), "{} {}: assess {a} vs bench {v}", cases[i / 3], methods[i % 3]);
    }

    // The reports.
    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    for needle in [
        "**The cost of precision**",
        "| estimator | +-0.1 dB | +-0.05 dB | +-0.02 dB | +-0.01 dB |",
        "| RQMC de-biased (cross-replicate) |",
    ] {
        assert!(summary.contains(needle), "summary.md lacks `{needle}`");
    }
    assert!(!summary.contains("Table 1 convergence"));
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    for needle in ["## The cost of precision", "| rqmc | 8 x 32 | 256 |", "![The cost of precision](precision.png)"] {
        assert!(md.contains(needle), "bench.md lacks `{needle}`");
    }
}

#[test]
fn bench_with_a_missing_scene_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    expect_error(
        &["bench", "--quick", "--scene", "no-such-scene.toml", "--out", out.to_str().unwrap()],
        &["no-such-scene.toml"],
    );
    assert!(!out.join("bench.json").exists());
}
