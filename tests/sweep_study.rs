//! A sweep of a resolution study (`study = "..."` in a sweep file): each point is the study with
//! its settings, and `sweep.csv` carries every source's MTF50 with the eye on the content, per
//! content depth, with its 95% half-width, digit for digit what `inimtrace resolution --set`
//! writes into `mtf50.csv` at each value; a rerun finds every point recorded; a record edited
//! into an experiment's does not count.
#![deny(unsafe_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

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

/// A CSV file's rows as maps from column to field (no field of these files is quoted).
fn rows(path: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            let r: Vec<String> = l.split(',').map(String::from).collect();
            assert_eq!(r.len(), header.len(), "{l}");
            header.iter().cloned().zip(r).collect()
        })
        .collect()
}

#[test]
fn a_study_sweep_gives_each_sources_mtf50_as_the_study_gives_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("tiny-gaze.toml");
    let study = root().join("studies/tiny.toml");
    std::fs::write(
        &file,
        format!(
            "study = \"{}\"\n[set]\n\"eye.gaze_deg\" = [0, 0]\n[[axes]]\n\"eye.gaze_deg[0]\" = [0, 8]\n",
            study.display()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, _, err) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    let swept = rows(&out.join("sweep.csv"));
    // Two points x (the ground truth, LC, PC) x two content depths.
    assert_eq!(swept.len(), 2 * 3 * 2, "{swept:?}");
    for gaze in ["0", "8"] {
        let by_hand = dir.path().join(format!("by-hand-{gaze}"));
        let set = format!("eye.gaze_deg=[{gaze}, 0]");
        let (ok, _, err) =
            inimtrace(&["resolution", study.to_str().unwrap(), "--set", &set, "--out", by_hand.to_str().unwrap()]);
        assert!(ok, "{err}");
        let on_content: Vec<_> = rows(&by_hand.join("mtf50.csv"))
            .into_iter()
            .filter(|r| r["target_diopters"] == r["focus_diopters"])
            .collect();
        assert_eq!(on_content.len(), 6);
        for r in &on_content {
            let s = swept
                .iter()
                .find(|s| {
                    s["eye.gaze_deg[0]"] == gaze
                        && s["source"] == r["source"]
                        && s["content_diopters"] == r["target_diopters"]
                })
                .unwrap_or_else(|| panic!("no sweep row for {r:?}"));
            assert_eq!((&s["mtf50_cpd"], &s["mtf50_ci95"]), (&r["mtf50_cpd"], &r["mtf50_ci95"]), "gaze {gaze}: {r:?}");
            assert_eq!((&s["samples_per_pixel"], &s["replicates"]), (&r["samples_per_pixel"], &r["replicates"]));
        }
        // The methods measure an MTF50 with an interval.
        assert!(on_content.iter().any(|r| r["source"] != "ground_truth" && !r["mtf50_ci95"].is_empty()));
    }
    // The gaze moves the methods' MTF50 (PC at 1 D, far from its image plane, the least).
    let lc =
        |g: &str| swept.iter().find(|s| s["eye.gaze_deg[0]"] == g && s["source"] == "LC").unwrap()["mtf50_cpd"].clone();
    assert_ne!(lc("0"), lc("8"));
    assert!(out.join("plots/mtf50_vs_eye.gaze_deg_0_.png").is_file());
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("sweep.json")).unwrap()).unwrap();
    let args = json["points"][1]["resolution_args"].as_array().unwrap();
    assert_eq!((args.len(), args[3].as_str()), (4, Some("eye.gaze_deg[0]=8")), "{args:?}");
    assert_eq!(json["study"], study.display().to_string());

    // Resumable: a rerun runs nothing.
    let (ok, _, err) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(err.contains("2 already complete, 0 run"), "{err}");
    // A record made into an experiment's (its MTF50 rows taken out) runs again.
    let points = out.join("points");
    let record = std::fs::read_dir(&points)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "json"))
        .unwrap();
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(&record).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("mtf50");
    std::fs::write(&record, serde_json::to_vec(&v).unwrap()).unwrap();
    let (ok, _, err) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(err.contains("1 already complete, 1 run") && err.contains("MTF50"), "{err}");
}

/// `sweep.csv` without its `seconds` column.
fn table_without_seconds(dir: &Path) -> Vec<BTreeMap<String, String>> {
    let mut t = rows(&dir.join("sweep.csv"));
    for r in &mut t {
        r.remove("seconds");
    }
    t
}

#[test]
fn a_study_sweep_runs_point_by_point_as_slurm_tasks_do() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("tiny-pupil.toml");
    let study = root().join("studies/tiny.toml");
    std::fs::write(&file, format!("study = \"{}\"\n[[axes]]\n\"pupil_diameter_mm\" = [3, 5]\n", study.display()))
        .unwrap();
    let f = file.to_str().unwrap();
    let (whole, tasks) = (dir.path().join("whole"), dir.path().join("tasks"));
    let (ok, _, err) = inimtrace(&["sweep", f, "--out", whole.to_str().unwrap()]);
    assert!(ok, "{err}");
    // A job array's tasks: each its points, then a collection.
    for p in ["1", "0"] {
        let (ok, _, err) = inimtrace(&["sweep", f, "--out", tasks.to_str().unwrap(), "--points", p]);
        assert!(ok, "{err}");
    }
    let (ok, stdout, err) = inimtrace(&["sweep", f, "--out", tasks.to_str().unwrap(), "--collect"]);
    assert!(ok && stdout.contains("2 of 2 points complete"), "{stdout} {err}");
    assert_eq!(table_without_seconds(&tasks), table_without_seconds(&whole));
    // The script a submission would send: one task per point (they cost the same), and a
    // dry run writes nothing.
    let remote = dir.path().join("remote");
    let (ok, script, err) =
        inimtrace(&["sweep", f, "--out", remote.to_str().unwrap(), "--slurm", "--array-max", "2", "--dry-run"]);
    assert!(ok, "{err}");
    assert!(script.contains("#SBATCH --array=0-1\n"), "{script}");
    assert!(!remote.exists());
    // The study's own refusals name the sweep's point.
    std::fs::write(&file, format!("study = \"{}\"\n[[axes]]\n\"eye.gaze_deg\" = [[0, 0], [30, 0]]\n", study.display()))
        .unwrap();
    let (ok, _, err) = inimtrace(&["sweep", f, "--out", remote.to_str().unwrap()]);
    assert!(!ok && err.contains("point 1") && err.contains("eye.gaze_deg"), "{err}");
}
