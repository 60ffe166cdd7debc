//! OPT's table explains itself (issue #53): each eye case's row says whether OPT was trained on
//! it or held out, the note beside the table states the training's pupil grid and samples and
//! says which bound is which.

use std::process::Command;

#[test]
fn the_opt_table_marks_trained_and_held_out_rows_and_states_the_training_grid() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("opt");
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "assess", "experiments/paper-optimal.toml", "--out"])
        .arg(&out)
        .args([
            "--set",
            "display.lcd.resolution=[108, 108]",
            "--set",
            "eye.retina_resolution=12",
            "--set",
            "measurement.estimator=\"grid\"",
            "--set",
            "eye.pupil_grid=2",
            "--set",
            "optimize.iterations=2",
            "--set",
            "optimize.pupil_grid=3",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(out.join("table.md")).unwrap();
    for trained in ["Pin", "Near", "Cen", "Far"] {
        assert!(table.contains(&format!("\n| {trained} (trained) |")), "{trained}: {table}");
    }
    for held in ["Mid-heldout", "Shift-heldout"] {
        assert!(table.contains(&format!("\n| {held} (held out) |")), "{held}: {table}");
    }
    // The training's pupil grid (3 x 3, the points inside the pupil) and which bound is which.
    assert!(table.contains("3 x 3 pupil grid"), "{table}");
    assert!(table.contains("Pin (pinhole"), "{table}");
    assert!(table.contains("OPT's score bounds what LC, PC and LA"), "{table}");
    assert!(table.contains("lower bound on the headroom"), "{table}");
    assert!(table.contains("stopped after 2 iterations"), "{table}");

    // Without OPT the rows carry no marks.
    let plain = dir.path().join("plain");
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "assess", "experiments/paper.toml", "--out"])
        .arg(&plain)
        .args([
            "--set",
            "display.lcd.resolution=[54, 54]",
            "--set",
            "eye.retina_resolution=12",
            "--set",
            "eye.pupil_grid=2",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(plain.join("table.md")).unwrap();
    assert!(table.contains("\n| Pin |") && !table.contains("trained") && !table.contains("held out"), "{table}");
}
