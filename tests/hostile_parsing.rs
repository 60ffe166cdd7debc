//! Parsing that cannot be made quadratic (issue #30, round two): a concave polygon of 200,000
//! corners is refused at the documented corner limit (a convex one is a fan), YAML nested
//! 50,000 deep is refused by a pre-scan before the YAML parser sees it, and 100,000 eye cases
//! are checked for duplicate names with a hash set (a duplicate at the end is found at once).
//! None of these tests times anything: each asserts the limit's error, or a size at which a
//! quadratic check would take minutes.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn a_concave_face_of_200k_corners_is_refused_at_the_corner_limit() {
    let dir = tempfile::tempdir().unwrap();
    let n = 200_000;
    // A comb: teeth along x, a wavy back; concave everywhere.
    let mut text = String::with_capacity(n * 24);
    for i in 0..n / 2 {
        writeln!(text, "v {i} {} 0", if i % 2 == 0 { 0.0 } else { 0.5 }).unwrap();
    }
    for i in (0..n / 2).rev() {
        writeln!(text, "v {i} {} 0", 2 + i % 3).unwrap();
    }
    text.push('f');
    for i in 1..=n {
        write!(text, " {i}").unwrap();
    }
    text.push('\n');
    let obj = dir.path().join("comb.obj");
    std::fs::write(&obj, &text).unwrap();
    let e = inimtrace::io::load_mesh(&obj).expect_err("a 200k-corner concave face was triangulated").to_string();
    assert!(e.contains("comb.obj") && e.contains("face 0") && e.contains("200000 corners"), "{e}");
    assert!(e.contains("at most 20000"), "{e}");

    // The same in PLY.
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uint int vertex_indices\nend_header\n"
    );
    ply.push_str(&text.lines().filter(|l| l.starts_with("v ")).map(|l| &l[2..]).collect::<Vec<_>>().join("\n"));
    write!(ply, "\n{n}").unwrap();
    for i in 0..n {
        write!(ply, " {i}").unwrap();
    }
    ply.push('\n');
    let path = dir.path().join("comb.ply");
    std::fs::write(&path, &ply).unwrap();
    let e = inimtrace::io::load_mesh(&path).expect_err("PLY face triangulated").to_string();
    assert!(e.contains("comb.ply") && e.contains("face 0") && e.contains("200000 corners"), "{e}");
}

#[test]
fn yaml_nested_50k_deep_is_refused_before_parsing() {
    let dir = tempfile::tempdir().unwrap();
    let deep = 50_000;
    let flow = format!("%YAML:1.0\n---\nlenslettolcd: {}1{}\n", "[".repeat(deep), "]".repeat(deep));
    let block = format!("%YAML:1.0\n---\nlenslettolcd:\n  {}6.3\n", "- ".repeat(deep));
    for (name, text) in [("flow.yaml", flow), ("block.yaml", block)] {
        std::fs::write(dir.path().join(name), text).unwrap();
        let e = inimtrace::io::load_display(name, dir.path()).expect_err("accepted").to_string();
        assert!(
            e.contains(name)
                && e.contains("levels deep")
                && e.contains(&inimtrace::io::display_file::MAX_YAML_NESTING.to_string()),
            "{e}"
        );
    }
    // The framework's own display file is far inside the limit.
    assert!(inimtrace::io::load_display("lensletdisplay.yaml", &root().join("data")).is_ok());
}

#[test]
fn a_duplicate_among_20k_eye_cases_is_found_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("many.toml");
    std::fs::write(&path, many_eye_cases(20_000)).unwrap();
    assert!(std::fs::metadata(&path).unwrap().len() < 1 << 20, "the file must stay under the settings limit");
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["assess", path.to_str().unwrap(), "--out", dir.path().join("o").to_str().unwrap()])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("eye_cases[19999].name") && e.contains("`c0` appears twice"), "{e}");
    assert!(!dir.path().join("o").exists(), "the folder was touched before the settings were checked");
}

/// The paper's experiment with `n` eye cases, the last one a duplicate of the first.
fn many_eye_cases(n: usize) -> String {
    let paper = std::fs::read_to_string(root().join("experiments/paper.toml")).unwrap();
    let head = paper.split("[[eye_cases]]").next().unwrap();
    let head = head
        .replace("\"../scenes/paper.toml\"", "\"builtin:paper\"")
        .replace("\"../displays/paper.toml\"", "\"builtin:paper\"");
    let mut text = head.to_string();
    for i in 0..n {
        write!(text, "[[eye_cases]]\nname = \"c{}\"\nfocus_mm = 300.0\n", if i == n - 1 { 0 } else { i }).unwrap();
    }
    text
}

/// 100k eye cases (4.7 MB): refused by size before its TOML is parsed (whose tokens alone would
/// take about 110 MB), naming the file and the limit.
#[test]
fn a_settings_file_over_a_mebibyte_is_refused_before_it_is_parsed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("many.toml");
    std::fs::write(&path, many_eye_cases(100_000)).unwrap();
    for args in [
        vec!["assess", path.to_str().unwrap(), "--out", dir.path().join("o").to_str().unwrap()],
        vec!["info", "--display", path.to_str().unwrap()],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(&args).output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(
            e.contains("many.toml") && e.contains("4.5 MiB") && e.contains("1.0 MiB a settings file may have"),
            "{e}"
        );
    }
    assert!(!dir.path().join("o").exists());
}
