//! Sweep point records that are checked (issue #30, round two): a record with another format, a
//! score that is not a number, a method the point does not run or another point's settings hash
//! is never counted as complete: a collection reports it, a resumed run runs the point again.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn inimtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("run inimtrace")
}

fn text(o: &Output) -> (String, String) {
    (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// A three-point sweep on tiny images (well under a second a point).
fn write_sweep(dir: &Path) -> PathBuf {
    let p = dir.join("s.toml");
    std::fs::write(
        &p,
        format!(
            "name = \"s\"\nexperiment = \"{}/experiments/paper.toml\"\n[set]\n\"display.lcd.resolution\" = [216, 216]\n\
             \"eye.retina_resolution\" = 16\n\"eye.pupil_grid\" = 2\n\"methods\" = [\"LC\", \"PC\"]\n\
             \"eye_cases\" = [{{ name = \"Eye\", focus_diopters = 2.5 }}]\n[[axes]]\n\"eye.pupil_diameter\" = [2.0, 3.0, 4.0]\n",
            env!("CARGO_MANIFEST_DIR")
        ),
    )
    .unwrap();
    p
}

fn records(out: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(out.join("points"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    v.sort();
    v
}

fn edit(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
}

#[test]
fn corrupt_records_are_reported_by_collect_and_run_again_on_resume() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = write_sweep(dir.path());
    let (s, out) = (sweep.to_str().unwrap(), dir.path().join("out"));
    let o_s = out.to_str().unwrap();
    let o = inimtrace(&["--quiet", "sweep", s, "--out", o_s]);
    assert!(o.status.success(), "{}", text(&o).1);
    assert!(text(&o).0.starts_with("3 of 3 points complete"), "{}", text(&o).0);
    let recs = records(&out);
    assert_eq!(recs.len(), 3);
    let first: serde_json::Value = serde_json::from_slice(&std::fs::read(&recs[0]).unwrap()).unwrap();
    assert_eq!(first["format"], 1, "records state their format");
    // Three kinds of corruption, one per record.
    edit(&recs[0], |v| v["scores"][0]["psnr_db"] = "NaN".into());
    edit(&recs[1], |v| v["scores"][1]["method"] = "XX".into());
    edit(&recs[2], |v| v["format"] = 2.into());
    let o = inimtrace(&["--quiet", "sweep", s, "--out", o_s, "--collect"]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    assert!(stdout.starts_with("0 of 3 points complete"), "{stdout}");
    assert!(stdout.contains("3 point records cannot count"), "{stdout}");
    for why in ["not valid (PSNR NaN dB", "unknown method `XX`", "record format 2"] {
        assert!(stdout.contains(why), "{why}: {stdout}");
    }
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1, "a corrupt record reached sweep.csv: {csv}");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["complete"], 0);
    for p in json["points"].as_array().unwrap() {
        assert_eq!(p["complete"], false);
        assert!(p["invalid_record"].is_string(), "{p}");
    }
    // Resuming runs every corrupted point again and replaces its record.
    let o = inimtrace(&["sweep", s, "--out", o_s, "--points", "0..3", "--quiet"]);
    let (_, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("3 points asked for, 0 already complete, 3 run"), "{stderr}");
    let o = inimtrace(&["--quiet", "sweep", s, "--out", o_s, "--collect"]);
    assert!(text(&o).0.starts_with("3 of 3 points complete") && !text(&o).0.contains("cannot count"), "{}", text(&o).0);
}

/// A change to a record's JSON.
type Edit = dyn Fn(&mut serde_json::Value);

#[test]
fn records_are_checked_against_their_points_settings() {
    use inimtrace::sweep::{RecordState, Store, Sweep};
    let dir = tempfile::tempdir().unwrap();
    let sweep_file = write_sweep(dir.path());
    let out = dir.path().join("out");
    let o =
        inimtrace(&["--quiet", "sweep", sweep_file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--points", "0"]);
    assert!(o.status.success(), "{}", text(&o).1);
    let sweep = Sweep::load(&sweep_file, &[], Some(&out)).unwrap();
    let resolved = sweep.resolve().unwrap();
    let store = Store::open(&out).unwrap();
    let RecordState::Complete(good) = store.state(&resolved[0]) else { panic!("point 0 is not complete") };
    assert_eq!(store.state(&resolved[1]), RecordState::Missing);
    let path = out.join("points").join(format!("{}.json", resolved[0].id()));
    let cases: Vec<(&str, Box<Edit>)> = vec![
        ("SSIM", Box::new(|v| v["scores"][0]["ssim"] = "1.5".into())),
        ("PSNR", Box::new(|v| v["scores"][0]["psnr_db"] = "-inf".into())),
        ("not this point's", Box::new(|v| v["id"] = "0123456789abcdef".into())),
        ("scores of PC", Box::new(|v| v["scores"].as_array_mut().unwrap().truncate(1))),
        ("which the point does not run", Box::new(|v| v["scores"][1]["method"] = "LA".into())),
        ("not valid", Box::new(|v| v["scores"][0]["ssim_ci95"] = "NaN".into())),
        ("time", Box::new(|v| v["seconds"] = (-1.0).into())),
        ("not a point record", Box::new(|v| *v = serde_json::json!({"id": 3}))),
    ];
    let original = std::fs::read(&path).unwrap();
    for (why, f) in cases {
        edit(&path, f);
        match store.state(&resolved[0]) {
            RecordState::Invalid(w) => assert!(w.contains(why), "{why}: {w}"),
            other => panic!("{why}: counted as {other:?}"),
        }
        assert!(store.record_of(&resolved[0]).is_none());
        std::fs::write(&path, &original).unwrap();
    }
    // A record from before the format was stated is of format 1 and still counts.
    edit(&path, |v| {
        v.as_object_mut().unwrap().remove("format");
    });
    assert_eq!(store.record_of(&resolved[0]).as_ref(), Some(&good));
}
