//! The display's photometry (`[photometry]`, `optics/photometry.rs`): the values a display file
//! states reach the display (explicit, by intent, through `--set`), `info` prints them, and every
//! impossible value is refused with one error naming the file and the field.

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::io::load_display;
use inimtrace::optics::photometry::Photometry;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

/// The paper's display file with `table` appended.
fn display_with(dir: &Path, name: &str, table: &str) -> PathBuf {
    let paper = std::fs::read_to_string(root().join("displays/paper.toml")).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, format!("{paper}\n[photometry]\n{table}\n")).unwrap();
    path
}

#[test]
fn a_stated_photometry_reaches_the_display_and_defaults_fill_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let p = display_with(
        dir.path(),
        "a.toml",
        "peak_luminance = 300.0\ncontrast_ratio = 1500.0\nambient_illuminance = 50.0",
    );
    let d = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
    let ph = d.photometry();
    assert_eq!(ph.peak_luminance, 300.0);
    assert_eq!(ph.black_level, 0.2);
    assert_eq!(ph.ambient_illuminance, 50.0);
    assert_eq!(ph.reflectance, 0.005);
    // A display without the table has the typical near-eye LCD's.
    let paper = load_display(&root().join("displays/paper.toml").to_string_lossy(), Path::new("")).unwrap();
    assert_eq!(paper.photometry, None);
    assert_eq!(paper.photometry(), Photometry::typical_near_eye_lcd());
}

#[test]
fn impossible_photometry_names_the_file_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("peak_luminance = 0.0", "photometry.peak_luminance"),
        ("peak_luminance = -100.0", "photometry.peak_luminance"),
        ("peak_luminance = nan", "photometry.peak_luminance"),
        ("peak_luminance = inf", "photometry.peak_luminance"),
        ("black_level = 0.0", "photometry.black_level"),
        ("black_level = -0.1", "photometry.black_level"),
        ("black_level = nan", "photometry.black_level"),
        ("black_level = 100.0", "photometry.black_level"),
        ("peak_luminance = 50.0\nblack_level = 80.0", "photometry.black_level"),
        ("contrast_ratio = 1.0", "photometry.contrast_ratio"),
        ("contrast_ratio = 0.0", "photometry.contrast_ratio"),
        ("contrast_ratio = nan", "photometry.contrast_ratio"),
        ("contrast_ratio = inf", "photometry.contrast_ratio"),
        ("black_level = 0.1\ncontrast_ratio = 1000.0", "photometry.contrast_ratio"),
        ("ambient_illuminance = -1.0", "photometry.ambient_illuminance"),
        ("ambient_illuminance = inf", "photometry.ambient_illuminance"),
        ("reflectance = 1.5", "photometry.reflectance"),
        ("reflectance = -0.1", "photometry.reflectance"),
        ("reflectance = nan", "photometry.reflectance"),
    ];
    for (i, (table, field)) in cases.iter().enumerate() {
        let p = display_with(dir.path(), &format!("bad{i}.toml"), table);
        let e = load_display(&p.to_string_lossy(), Path::new("")).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains(&format!("bad{i}.toml")), "{table}: {e}");
    }
    // An unknown key is refused by the file's parser, naming it.
    let p = display_with(dir.path(), "unknown.toml", "peak_lumiance = 100.0");
    let e = load_display(&p.to_string_lossy(), Path::new("")).unwrap_err().to_string();
    assert!(e.contains("peak_lumiance") && e.contains("unknown.toml"), "{e}");
}

#[test]
fn info_prints_the_photometry_and_set_reaches_it() {
    let (ok, out, err) = inimtrace(&["info"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("photometry (default: a typical near-eye LCD): peak white 100 cd/m^2, black 0.1 cd/m^2"),
        "{out}"
    );
    let (ok, out, err) = inimtrace(&["info", "--set", "display.photometry.peak_luminance=250", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["photometry"]["peak_luminance_cd_m2"], 250.0);
    assert_eq!(v["photometry"]["black_level_cd_m2"], 0.25);
    assert_eq!(v["photometry"]["stated"], true);
    let (ok, _, err) = inimtrace(&["info", "--set", "display.photometry.peak_luminance=0"]);
    assert!(!ok);
    assert!(err.contains("photometry.peak_luminance") && !err.contains("panicked"), "{err}");
}

#[test]
fn a_display_by_intent_carries_its_photometry() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("displays/hex-1mm.toml")).unwrap();
    let p = dir.path().join("hex.toml");
    std::fs::write(&p, format!("{text}\n[photometry]\npeak_luminance = 400.0\n")).unwrap();
    let d = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
    assert_eq!(d.photometry().peak_luminance, 400.0);
    std::fs::write(&p, format!("{text}\n[photometry]\npeak_luminance = -4.0\n")).unwrap();
    let e = load_display(&p.to_string_lossy(), Path::new("")).unwrap_err().to_string();
    assert!(e.contains("photometry.peak_luminance") && e.contains("hex.toml"), "{e}");
}
