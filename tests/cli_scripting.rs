//! The command line as scripts use it (issue "scriptable commands"): closed sets of values are
//! checked by the parser (a typo exits 2 before any work), `compare` and `info` print JSON, the
//! single-stage commands take every eye setting of an experiment file and write the same images
//! and the same EXR metadata as `assess`, and `results.json` and the figure describe the run.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use inimtrace::io::exr::{read_rgb, read_typed_attributes, AttrValue};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).arg("--quiet").output().expect("binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A small experiment (LCD 360 x 360, retina 48 x 48, 4 x 4 pupil grid) with an eye that is not
/// the default one: moved, with a longer retina distance, 2 x 2 samples per retina pixel and a
/// narrower field.
fn small_experiment(dir: &Path) -> PathBuf {
    let display = std::fs::read_to_string(root().join("displays/paper.toml"))
        .unwrap()
        .replace("size = [21.6, 21.6]", "size = [3.6, 3.6]")
        .replace("[2160, 2160]", "[360, 360]");
    std::fs::write(dir.join("display.toml"), display).unwrap();
    let exp = std::fs::read_to_string(root().join("experiments/paper.toml"))
        .unwrap()
        .replace("../scenes/paper.toml", &root().join("scenes/paper.toml").display().to_string())
        .replace("../displays/paper.toml", "display.toml")
        .replace("retina_distance = 17.0", "retina_distance = 18.5")
        .replace("retina_resolution = 512", "retina_resolution = 48")
        .replace("retina_half_tangent = 0.3", "retina_half_tangent = 0.05")
        .replace("retina_samples = 1", "retina_samples = 2")
        .replace("pupil_grid = 8", "pupil_grid = 4")
        .replace("position = [0.0, 0.0, 0.0]", "position = [0.25, -0.5, 0.0]")
        .replace("la_grid = 5", "la_grid = 2")
        .replace("name = \"paper\"", "name = \"small\"");
    let path = dir.join("small.toml");
    std::fs::write(&path, exp).unwrap();
    path
}

/// The eye flags of `small_experiment`.
const EYE: [&str; 12] = [
    "--retina-distance",
    "18.5",
    "--retina",
    "48",
    "--half-tangent",
    "0.05",
    "--retina-samples",
    "2",
    "--pupil-grid",
    "4",
    "--eye-position",
    "0.25,-0.5,0",
];

fn attrs(path: &Path) -> Vec<(String, AttrValue)> {
    read_typed_attributes(path).unwrap()
}

/// The provenance attributes `assess` writes (its experiment's files and overrides).
const PROVENANCE: [&str; 6] = [
    "inimtrace:scene",
    "inimtrace:scene_path",
    "inimtrace:scene_sha256",
    "inimtrace:experiment_path",
    "inimtrace:input_files_sha256",
    "inimtrace:set",
];

/// The attributes of `a` and `b` agree except for those only `assess` knows (and its
/// provenance, which `b`, written by `assess`, must carry).
fn same_metadata(a: &Path, b: &Path, only_assess: &[&str]) {
    let names: Vec<String> = attrs(b).into_iter().map(|(k, _)| k).collect();
    for p in ["inimtrace:scene", "inimtrace:scene_sha256", "inimtrace:input_files_sha256"] {
        assert!(names.iter().any(|n| n == p), "{} lacks {p}", b.display());
    }
    let keep = |v: Vec<(String, AttrValue)>| -> Vec<(String, AttrValue)> {
        v.into_iter().filter(|(k, _)| !only_assess.contains(&k.as_str()) && !PROVENANCE.contains(&k.as_str())).collect()
    };
    let (x, y) = (keep(attrs(a)), keep(attrs(b)));
    assert_eq!(x, y, "{} and {} carry different metadata", a.display(), b.display());
}

#[test]
fn single_stage_commands_match_assess_in_pixels_and_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let exp = small_experiment(dir.path());
    let out = dir.path().join("out");
    let o = run(&["assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap(), "--timings"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // --timings: one total line.
    assert_eq!(text(&o.stderr).matches("total").count(), 1, "{}", text(&o.stderr));

    let display = dir.path().join("display.toml");
    let d = display.to_str().unwrap();
    let scene = root().join("scenes/paper.toml");
    let s = scene.to_str().unwrap();

    // render-display: the PC display image aims at the experiment's eye position.
    let pc = dir.path().join("display_PC.exr");
    let o = run(&[
        "render-display",
        "--method",
        "pc",
        "--display",
        d,
        "--scene",
        s,
        "--eye-position",
        "0.25,-0.5,0",
        "--out",
        pc.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(read_rgb(&pc).unwrap() == read_rgb(&out.join("display_PC.exr")).unwrap());
    same_metadata(&pc, &out.join("display_PC.exr"), &["inimtrace:experiment"]);

    // ground-truth with the experiment's eye.
    let gt = dir.path().join("gt.exr");
    let mut args = vec!["ground-truth", "--focus-mm", "300", "--scene", s, "--out", gt.to_str().unwrap()];
    args.extend(EYE);
    let o = run(&args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(read_rgb(&gt).unwrap() == read_rgb(&out.join("gt_Near.exr")).unwrap());
    same_metadata(&gt, &out.join("gt_Near.exr"), &["inimtrace:experiment", "inimtrace:eye_case"]);

    // simulate from assess's LA display image: the method comes from its header.
    let sim = dir.path().join("sim.exr");
    let la = out.join("display_LA2.exr");
    let mut args =
        vec!["simulate", la.to_str().unwrap(), "--focus-mm", "300", "--display", d, "--out", sim.to_str().unwrap()];
    args.extend(EYE);
    let o = run(&args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(read_rgb(&sim).unwrap() == read_rgb(&out.join("sim_LA2_Near.exr")).unwrap());
    same_metadata(
        &sim,
        &out.join("sim_LA2_Near.exr"),
        &["inimtrace:experiment", "inimtrace:eye_case", "inimtrace:source"],
    );
    let get = |p: &Path, k: &str| attrs(p).into_iter().find(|(n, _)| n == k).map(|(_, v)| v);
    assert_eq!(get(&sim, "inimtrace:method"), Some(AttrValue::Text("LA (2x2)".into())));
    assert_eq!(get(&sim, "inimtrace:retina_distance_mm"), Some(AttrValue::F64(18.5)));
    assert_eq!(get(&sim, "inimtrace:eye_y_mm"), Some(AttrValue::F64(-0.5)));
    assert_eq!(get(&sim, "inimtrace:retina_samples_per_pixel"), Some(AttrValue::I32(4)));

    // results.json: the tool and the display as fields.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["tool"]["version"], inimtrace::version::VERSION);
    assert_eq!(json["tool"]["git_revision"], inimtrace::version::GIT_REVISION);
    assert_ne!(json["tool"]["git_revision"], "");
    assert_eq!(json["display"]["eye_to_lenslets_mm"], 20.0);
    assert_eq!(json["display"]["lenslets"]["pitch_matrix_mm"], serde_json::json!([1.2, 0.0, 0.0, 1.2]));
    assert_eq!(json["display"]["lcd_resolution"], serde_json::json!([360, 360]));

    // The figure has the title strip and a caption strip under every row.
    let layout = inimtrace::io::figure::Layout {
        title: inimtrace::io::figure::TITLE_HEIGHT,
        caption: inimtrace::io::figure::CAPTION_HEIGHT,
    };
    let png = image::open(out.join("figure.png")).unwrap().to_rgb8();
    let (w, h) = layout.size(4, 4);
    assert_eq!((png.width() as usize, png.height() as usize), (w, h));
    // Caption text (dark pixels) under the LC panel of the first row, none under GT.
    let (x0, y0) = layout.cell_origin(0, 1);
    let dark = |x0: usize| {
        (x0..x0 + inimtrace::io::figure::CELL_SIZE)
            .flat_map(|x| {
                (y0 + inimtrace::io::figure::CELL_SIZE..y0 + inimtrace::io::figure::CELL_SIZE + layout.caption)
                    .map(move |y| (x, y))
            })
            .filter(|&(x, y)| png.get_pixel(x as u32, y as u32).0.iter().all(|&v| v < 100))
            .count()
    };
    assert!(dark(x0) > 20, "no caption under LC");
    assert_eq!(dark(layout.cell_origin(0, 0).0), 0, "a caption under GT");
}

#[test]
fn typos_in_closed_sets_exit_2_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.exr");
    let o_s = out.to_str().unwrap();
    for args in [
        vec!["render-display", "--method", "LB", "--out", o_s],
        vec!["render-display", "--method", "LA0", "--out", o_s],
        vec!["render-display", "--backend", "embre", "--out", o_s],
        vec!["ground-truth", "--pinhole", "--backend", "bhv", "--out", o_s],
        vec!["ground-truth", "--pinhole", "--eye-position", "1,2", "--out", o_s],
        vec!["ground-truth", "--pinhole", "--exr-compression", "zipp", "--out", o_s],
        vec!["compare", o_s, o_s, "--ssim", "wang"],
        vec!["info", "--print", "paper-scen"],
        vec!["assess", "--backend", "gpu", "--out", dir.path().to_str().unwrap()],
    ] {
        let t = Instant::now();
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        let err = text(&o.stderr);
        assert!(err.contains("invalid value") && !err.contains("panicked"), "{args:?}: {err}");
        assert!(t.elapsed() < Duration::from_secs(5), "{args:?} took {:?}: work started", t.elapsed());
        assert!(!out.exists(), "{args:?} wrote output");
    }
    // --help lists the values.
    let help = text(&run(&["render-display", "--help"]).stdout);
    for v in ["LC", "PC", "LA<k>", "embree", "bvh", "brute"] {
        assert!(help.contains(v), "--help lacks {v}");
    }
    // Methods and backends stay case-insensitive.
    let o = run(&["info", "--print", "paper-display"]);
    assert!(o.status.success());
    let o = run(&["compare", o_s, o_s, "--ssim", "framework-8bit"]);
    assert_eq!(o.status.code(), Some(1), "a valid value gets past the parser: {}", text(&o.stderr));
    let gt = dir.path().join("gt.exr");
    let o = run(&["ground-truth", "--pinhole", "--backend", "BVH", "--retina", "8", "--out", gt.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = run(&["render-display", "--method", "la3", "--display", "/nonexistent.toml", "--out", o_s]);
    assert_eq!(o.status.code(), Some(1), "la3 parses; the missing display fails later: {}", text(&o.stderr));
}

#[test]
fn compare_and_info_print_json() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    let mut img = inimtrace::raster::RgbImage::filled(32, 32, [0.5, 0.25, 0.125]);
    inimtrace::io::exr::write_rgb(&a, &img, None, &[]).unwrap();
    // R differs by 0.1 everywhere: PSNR 20 dB; G and B are identical (infinite PSNR: null).
    for p in &mut img.pixels {
        p[0] += 0.1;
    }
    inimtrace::io::exr::write_rgb(&b, &img, None, &[]).unwrap();
    let o = run(&["compare", a.to_str().unwrap(), b.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    let r = v["psnr_db"]["R"].as_f64().unwrap();
    assert!((r - 20.0).abs() < 1e-4, "{v}");
    assert!(v["psnr_db"]["G"].is_null() && v["psnr_db"]["B"].is_null() && v["psnr_db"]["mean"].is_null(), "{v}");
    for c in ["R", "G", "B", "mean"] {
        let s = v["ssim"][c].as_f64().unwrap();
        assert!(s > 0.0 && s <= 1.0, "{c}: {v}");
    }
    assert_eq!(v["ssim"]["G"], 1.0);
    assert_eq!(v["ssim_constants"], "wang2004");
    assert_eq!((v["width"].as_u64(), v["height"].as_u64()), (Some(32), Some(32)));

    // info --json: the paper display's design quantities.
    let o = run(&["info", "--json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    let cdp = v["display"]["central_depth_plane_mm"].as_f64().unwrap();
    assert!((cdp - 385.7).abs() < 0.1, "{v}");
    assert!(v["eye_box_mm"][0].as_f64().unwrap() > 4.9, "{v}");
    assert_eq!(v["pixels_per_elemental_image_xy"][0].as_f64().map(|x| x.round()), Some(158.0));
    // info --scene --json: triangle counts, bounds after the transform, depth range.
    let o = run(&["info", "--scene", root().join("scenes/paper.toml").to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    assert_eq!(v["objects"].as_array().unwrap().len(), 4);
    assert_eq!(v["depth_range_mm"], serde_json::json!([300.0, 1302.0]));
    assert_eq!(v["objects"][0]["bounds_min_mm"], serde_json::json!([-90.0, -90.0, 300.0]));
    let text_out = text(&run(&["info", "--scene", root().join("scenes/paper.toml").to_str().unwrap()]).stdout);
    assert!(text_out.contains("3.333 to 0.768 D"), "{text_out}");
}

#[test]
fn a_missing_file_is_reported_once() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.exr");
    let o = run(&["compare", missing.to_str().unwrap(), missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}
