//! Errors that say what is wrong (issue #30, round two): a sweep axis with the same value twice
//! is refused naming the value and the axis (not "already complete" later), a range too long
//! says how many values it would have and the limit (not "no values"), an integer too large for
//! `--set` is called an integer out of range (not a string), and a PLY element that declares a
//! property twice is refused naming it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("run inimtrace")
}

/// A sweep over the tiny sweep's experiment with one axis of `axis` (TOML), refused: its one-line error.
fn sweep_error(dir: &Path, axis: &str) -> String {
    let experiment = root().join("experiments/paper.toml");
    let text = format!(
        "name = \"t\"\nexperiment = {:?}\n[set]\n\"eye.retina_resolution\" = 64\n[[axes]]\n{axis}\n",
        experiment.to_str().unwrap()
    );
    let path = dir.join("s.toml");
    std::fs::write(&path, text).unwrap();
    let o = inimtrace(&["sweep", path.to_str().unwrap(), "--out", dir.join("o").to_str().unwrap(), "--collect"]);
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{axis}: accepted: {e}");
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    e
}

#[test]
fn duplicate_sweep_values_are_refused_naming_the_value_and_the_axis() {
    let dir = tempfile::tempdir().unwrap();
    let e = sweep_error(dir.path(), "\"eye.pupil_diameter\" = [2.0, 4.0, 2.0]");
    assert!(e.contains("duplicate value 2.0 in axis 0") && e.contains("values 0 and 2"), "{e}");
    // 4 and 4.0 are one value; a range that repeats one too.
    let e = sweep_error(dir.path(), "\"eye.pupil_diameter\" = [4, 3.0, 4.0]");
    assert!(e.contains("duplicate value 4") && e.contains("in axis 0"), "{e}");
    // Zipped keys: a pair that repeats.
    let e = sweep_error(dir.path(), "\"eye.pupil_diameter\" = [2.0, 3.0, 2.0]\n\"eye.pupil_grid\" = [4, 4, 4]");
    assert!(e.contains("duplicate value eye.pupil_diameter = 2.0, eye.pupil_grid = 4 in axis 0"), "{e}");
}

#[test]
fn an_over_long_range_says_how_many_values_and_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let e = sweep_error(dir.path(), "\"eye.pupil_diameter\" = { from = 1, to = 1e300, step = 1 }");
    assert!(e.contains("would have 1.000e300 values, more than the limit of 1000000"), "{e}");
    let e = sweep_error(dir.path(), "\"eye.pupil_diameter\" = { from = 0, to = 2000000, step = 1 }");
    assert!(e.contains("would have 2000001 values, more than the limit of 1000000"), "{e}");
    assert!(!e.contains("no values"), "{e}");
}

#[test]
fn an_oversized_integer_in_set_is_an_integer_out_of_range() {
    for v in ["18446744073709551616", "-9223372036854775809", "99999999999999999999999"] {
        let o = inimtrace(&["info", "--set", &format!("eye.pupil_grid={v}"), "--print", "paper-grid-experiment"]);
        let e = String::from_utf8_lossy(&o.stderr);
        // A command-line value is refused by the argument parser (its usage error, exit 2).
        assert!(matches!(o.status.code(), Some(1 | 2)), "{v}: {e}");
        assert!(e.contains("--set") && e.contains(&format!("`{v}` is an integer out of range")), "{v}: {e}");
        assert!(!e.contains("string"), "{v}: {e}");
    }
}

#[test]
fn a_ply_property_declared_twice_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("twice.ply");
    std::fs::write(
        &path,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property float y\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0 0\n1 0 0 0\n0 1 0 1\n3 0 1 2\n",
    )
    .unwrap();
    let e = inimtrace::io::load_mesh(&path).expect_err("accepted").to_string();
    assert!(e.contains("twice.ply") && e.contains("line 7") && e.contains("declares property 'y' twice"), "{e}");
}
