//! Displays stated by intent (`[intent]`: the central depth plane, v1, f, the lenslet pitch and
//! lattice): the derived display against the paper's explicit one, against the explicit file
//! `info --write-display` writes, and hostile intent refused naming the file and the field.

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::io::load_display;
use inimtrace::optics::Display;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

const PAPER_BY_INTENT: &str = r#"
name = "paper by intent"
[intent]
central_depth_plane = 385.7
eye_to_lenslets = 20.0
focal_length = 6.427
lattice = "square"
lenslet_pitch = 1.2
[lcd]
size = [21.6, 21.6]
resolution = [2160, 2160]
"#;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Every number of two displays differs by at most `tol` mm (names aside).
fn max_difference(a: &Display, b: &Display) -> f64 {
    let mut d = (a.eye_to_lenslets - b.eye_to_lenslets).abs();
    d = d.max((a.lenslets_to_lcd - b.lenslets_to_lcd).abs());
    d = d.max((a.focal_length - b.focal_length).abs());
    for (x, y) in [(&a.lenslets, &b.lenslets), (&a.elemental_images, &b.elemental_images)] {
        for (p, q) in x.row_major().iter().zip(y.row_major()) {
            d = d.max((p - q).abs());
        }
        d = d.max((x.shift - y.shift).abs().max_element());
    }
    d.max((a.lcd.size - b.lcd.size).abs().max_element())
}

#[test]
fn the_papers_display_by_intent_reproduces_its_v2_and_elemental_image_pitch() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "paper-intent.toml", PAPER_BY_INTENT);
    let d = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
    let paper = load_display("displays/paper.toml", &root()).unwrap();
    // v2: 1 / (1/6.427 + 1/365.7) = 6.31599 mm against the file's 6.316.
    assert!((d.lenslets_to_lcd - paper.lenslets_to_lcd).abs() < 0.001, "{}", d.lenslets_to_lcd);
    // The elemental-image pitch: 1.2 x 26.316 / 20 = 1.57896 mm against the file's rounded 1.58.
    let [a, b, c, e] = d.elemental_images.row_major();
    assert!((a - 1.58).abs() < 0.002 && (e - 1.58).abs() < 0.002 && b == 0.0 && c == 0.0, "{a} {b} {c} {e}");
    assert!((a - 1.2 * (20.0 + d.lenslets_to_lcd) / 20.0).abs() < 1e-15);
    assert_eq!(d.lenslets.row_major(), paper.lenslets.row_major());
    assert_eq!((d.eye_to_lenslets, d.focal_length, d.lcd), (20.0, 6.427, paper.lcd));
    // The CDP is where the intent put it.
    assert!((d.central_depth_plane().unwrap() - 385.7).abs() < 1e-9);
    println!("v2 {:.6} (file {}), EI pitch {:.6} (file 1.58)", d.lenslets_to_lcd, paper.lenslets_to_lcd, a);
}

#[test]
fn a_display_by_intent_equals_the_explicit_file_info_writes_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let paper = write(dir.path(), "paper-intent.toml", PAPER_BY_INTENT);
    let hex = root().join("displays/hex-1mm.toml");
    let views = write(
        dir.path(),
        "views.toml",
        &PAPER_BY_INTENT
            .replace("lenslet_pitch = 1.2", "views_across_pupil = 4.0\npupil_diameter = 3.0")
            .replace("\"square\"", "\"hexagonal\""),
    );
    for intent in [paper, hex, views] {
        let out = dir.path().join("explicit.toml");
        let _ = std::fs::remove_file(&out);
        let (ok, stdout, stderr) =
            inimtrace(&["info", "--display", &intent.to_string_lossy(), "--write-display", &out.to_string_lossy()]);
        assert!(ok, "{stderr}");
        assert!(stdout.contains("display stated by intent") && stdout.contains("v2 = 1 / (1/f"), "{stdout}");
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(!text.contains("[intent]"), "{text}");
        let by_intent = load_display(&intent.to_string_lossy(), Path::new("")).unwrap();
        let explicit = load_display(&out.to_string_lossy(), Path::new("")).unwrap();
        let diff = max_difference(&by_intent, &explicit);
        assert!(diff <= 1e-12, "{}: {diff} mm", intent.display());
        assert_eq!(by_intent.name, explicit.name);
        // An existing file is kept unless --force.
        let (ok, _, stderr) =
            inimtrace(&["info", "--display", &intent.to_string_lossy(), "--write-display", &out.to_string_lossy()]);
        assert!(!ok && stderr.contains("--force") && stderr.contains("explicit.toml"), "{stderr}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), text);
        let (ok, _, stderr) = inimtrace(&[
            "info",
            "--display",
            &intent.to_string_lossy(),
            "--write-display",
            &out.to_string_lossy(),
            "--force",
        ]);
        assert!(ok, "{stderr}");
    }
}

#[test]
fn experiments_and_settings_see_the_derived_display() {
    // The settings path (assess, sweeps) inlines the derived explicit display.
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "paper-intent.toml", PAPER_BY_INTENT);
    let direct = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
    let via = inimtrace::settings::display_with(Some(&p), &[]).unwrap();
    assert_eq!(max_difference(&direct, &via), 0.0);
    let o: inimtrace::overrides::Override = "display.lenslets_to_lcd=6.0".parse().unwrap();
    let changed = inimtrace::settings::display_with(Some(&p), &[o]).unwrap();
    assert_eq!(changed.lenslets_to_lcd, 6.0);
}

#[test]
fn hostile_intent_is_refused_naming_the_file_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("central_depth_plane = 385.7", "central_depth_plane = 15.0", "intent.central_depth_plane"),
        ("central_depth_plane = 385.7", "central_depth_plane = -385.7", "intent.central_depth_plane"),
        ("central_depth_plane = 385.7", "central_depth_plane = nan", "intent.central_depth_plane"),
        ("central_depth_plane = 385.7", "central_depth_plane = 20.0", "intent.central_depth_plane"),
        ("focal_length = 6.427", "focal_length = -6.427", "intent.focal_length"),
        ("focal_length = 6.427", "focal_length = nan", "intent.focal_length"),
        ("focal_length = 6.427", "focal_length = 1e9", "intent.focal_length"),
        ("eye_to_lenslets = 20.0", "eye_to_lenslets = -20.0", "intent.eye_to_lenslets"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 0.0", "intent.lenslet_pitch"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = inf", "intent.lenslet_pitch"),
        ("lenslet_pitch = 1.2", "", "intent.lenslet_pitch"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 1.2\nviews_across_pupil = 4", "intent.views_across_pupil"),
        ("lenslet_pitch = 1.2", "views_across_pupil = nan", "intent.views_across_pupil"),
        ("lenslet_pitch = 1.2", "views_across_pupil = 4\npupil_diameter = -5", "intent.pupil_diameter"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 1.2\npupil_diameter = 5", "intent.pupil_diameter"),
        ("\"square\"", "\"triangular\"", "lattice"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 1.2\nlenslets_to_lcd = 6.3", "lenslets_to_lcd"),
        ("name = \"paper by intent\"", "lenslet = { kind = \"thick\" }", "lenslet"),
    ];
    for (i, (from, to, field)) in cases.iter().enumerate() {
        let text = PAPER_BY_INTENT.replace(from, to);
        assert_ne!(text, PAPER_BY_INTENT, "{from}");
        let name = format!("hostile{i}.toml");
        let p = write(dir.path(), &name, &text);
        let e = load_display(&p.to_string_lossy(), Path::new("")).expect_err(to).to_string();
        assert!(e.contains(&name) && e.contains(field), "{to}: {e}");
        assert_eq!(e.lines().count(), 1, "{e}");
        // The settings path (assess, sweeps) refuses it the same way.
        let e = inimtrace::settings::display_with(Some(&p), &[]).expect_err(to).to_string();
        assert!(e.contains(&name) && e.contains(field), "{to}: {e}");
    }
}
