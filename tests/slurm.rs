//! `inimtrace sweep --slurm` on a real (single-node) Slurm cluster, `scripts/slurm-local.sh`:
//! the tiny sweep as an array of 4 tasks gives the local run's `sweep.csv`; a task cancelled
//! mid-way with `scancel` leaves no partial point, and resubmitting runs only its missing points;
//! a request the node cannot satisfy (99 CPUs per task) is refused before anything is submitted.
//!
//! These tests start the cluster when it is not running (and stop it again), and are skipped,
//! saying so on the terminal, only where it cannot be started (no root, no slurm-wlm/munge).
#![deny(unsafe_code)]

use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The cluster is shared: one test at a time.
static CLUSTER: Mutex<()> = Mutex::new(());

/// Stops the cluster on drop if this test started it.
struct Cluster {
    started_here: bool,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if self.started_here {
            let _ = Command::new(root().join("scripts/slurm-local.sh")).arg("stop").output();
        }
    }
}

/// Says on the terminal (past the test harness's capture) that a test is skipped, and why.
fn skip(test: &str, why: &str) {
    let _ = writeln!(std::io::stderr(), "SKIPPED {test}: Slurm cannot be started here: {why}");
}

/// The local cluster, started if needed; `None` (skip) only when it cannot be started.
fn cluster(test: &str) -> Option<Cluster> {
    let script = root().join("scripts/slurm-local.sh");
    if Command::new(&script).arg("status").output().is_ok_and(|o| o.status.success()) {
        return Some(Cluster { started_here: false });
    }
    match Command::new(&script).arg("start").output() {
        Ok(o) if o.status.success() => Some(Cluster { started_here: true }),
        Ok(o) => {
            skip(test, String::from_utf8_lossy(&o.stderr).trim());
            let _ = Command::new(&script).arg("stop").output();
            None
        }
        Err(e) => {
            skip(test, &e.to_string());
            None
        }
    }
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .current_dir(root())
        .arg("--quiet")
        .args(args)
        .output()
        .expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn tiny() -> String {
    root().join("sweeps/tiny.toml").display().to_string()
}

/// `sweep.csv` without its last column (seconds).
fn csv_without_seconds(out: &Path) -> String {
    let text = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    text.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n").collect()
}

/// The point records in `out/points/`, by file name.
fn records(out: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(out.join("points"))
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().into_string().unwrap())
                .filter(|n| n.ends_with(".json") && !n.starts_with('.'))
                .map(|n| (n.clone(), std::fs::read(out.join("points").join(&n)).unwrap()))
                .collect()
        })
        .unwrap_or_default()
}

/// Point ids by index, from `sweep.json`.
fn point_ids(out: &Path) -> Vec<String> {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    json["points"].as_array().unwrap().iter().map(|p| p["id"].as_str().unwrap().to_string()).collect()
}

fn job_running(job: &str) -> bool {
    let out = Command::new("squeue").args(["-h", "-j", job, "-o", "%T"]).output().unwrap();
    out.status.success() && !String::from_utf8_lossy(&out.stdout).trim().is_empty()
}

#[test]
fn a_job_array_of_four_tasks_gives_the_local_table() {
    let _one = CLUSTER.lock().unwrap_or_else(|p| p.into_inner());
    let Some(_cluster) = cluster("a_job_array_of_four_tasks_gives_the_local_table") else { return };
    let start = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let local = dir.path().join("local");
    let remote = dir.path().join("slurm");
    let (ok, _, e) = inimtrace(&["sweep", &tiny(), "--out", local.to_str().unwrap()]);
    assert!(ok, "{e}");

    // The script: 4 tasks of 3 points each, dealt out in turn (the tiny sweep's points all cost
    // the same), and a complete command to collect.
    let (ok, script, e) =
        inimtrace(&["sweep", &tiny(), "--out", remote.to_str().unwrap(), "--slurm", "--array-max", "4", "--dry-run"]);
    assert!(ok, "{e}");
    assert!(script.contains("#SBATCH --array=0-3\n"), "{script}");
    for chunk in ["'0,4,8'", "'1,5,9'", "'2,6,10'", "'3,7,11'"] {
        assert!(script.contains(chunk), "{script}");
    }
    assert!(script.contains(&format!("sweep {} --out {} --collect", tiny(), remote.display())), "{script}");
    assert!(!remote.exists(), "--dry-run wrote into {}", remote.display());

    let (ok, stdout, e) = inimtrace(&[
        "sweep",
        &tiny(),
        "--out",
        remote.to_str().unwrap(),
        "--slurm",
        "--array-max",
        "4",
        "--cpus-per-task",
        "1",
        "--wait",
    ]);
    assert!(ok, "{e}");
    assert!(e.contains("4 array tasks for the 12 missing of 12 points"), "{e}");
    assert!(stdout.contains("12 of 12 points complete"), "{stdout}");
    assert_eq!(csv_without_seconds(&remote), csv_without_seconds(&local), "Slurm and local tables differ");
    let logs = std::fs::read_dir(remote.join("slurm"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".out"));
    assert_eq!(logs.count(), 4, "one log per task");
    // Everything is complete: submitting again submits nothing.
    let (ok, _, e) = inimtrace(&["sweep", &tiny(), "--out", remote.to_str().unwrap(), "--slurm", "--wait"]);
    assert!(ok && e.contains("nothing to submit"), "{e}");
    assert!(start.elapsed() < Duration::from_secs(600), "took {:?}", start.elapsed());
}

#[test]
fn a_cancelled_task_leaves_no_partial_point_and_a_resubmission_runs_only_its_points() {
    let _one = CLUSTER.lock().unwrap_or_else(|p| p.into_inner());
    let name = "a_cancelled_task_leaves_no_partial_point_and_a_resubmission_runs_only_its_points";
    let Some(_cluster) = cluster(name) else { return };
    let start = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slurm");
    let out_s = out.to_str().unwrap().to_string();
    let file = tiny();
    // Points that take a moment each, so that the cancel lands mid-task.
    let slow = ["--set", "eye.retina_resolution=256", "--set", "eye.pupil_grid=8"];
    let mut args = vec!["sweep", &file, "--out", &out_s, "--slurm", "--array-max", "4", "--cpus-per-task", "1"];
    args.extend(slow);
    let (ok, stdout, e) = inimtrace(&args);
    assert!(ok, "{e}");
    let first = stdout.lines().next().unwrap_or_default();
    let job = first.strip_prefix("submitted job ").unwrap_or_else(|| panic!("no job id: {stdout}")).to_string();
    // The hint is the complete command that collects this sweep.
    assert!(stdout.contains(&format!(" --out {out_s} --set eye.retina_resolution=256")), "{stdout}");
    assert!(stdout.trim_end().ends_with(" --collect"), "{stdout}");

    // Cancel task 1 (points 1, 5, 9: equal costs are dealt out in turn) once it has recorded its
    // first point.
    let mut collect_args = vec!["sweep", &file, "--out", &out_s, "--collect"];
    collect_args.extend(slow);
    let (ok, _, e) = inimtrace(&collect_args);
    assert!(ok, "{e}");
    let ids = point_ids(&out);
    let task1: Vec<&String> = [1, 5, 9].iter().map(|&i| &ids[i]).collect();
    loop {
        assert!(start.elapsed() < Duration::from_secs(300), "task 1 recorded no point");
        let done = records(&out);
        let n = task1.iter().filter(|id| done.contains_key(&format!("{id}.json"))).count();
        if n >= 1 {
            assert!(n < 3, "task 1 finished before it could be cancelled");
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("scancel").arg(format!("{job}_1")).status().unwrap();
    assert!(status.success());
    while job_running(&job) {
        assert!(start.elapsed() < Duration::from_secs(400), "job {job} does not end");
        std::thread::sleep(Duration::from_millis(200));
    }

    let before = records(&out);
    let missing: BTreeSet<usize> = (0..12).filter(|&i| !before.contains_key(&format!("{}.json", ids[i]))).collect();
    assert!(!missing.is_empty() && missing.iter().all(|i| [1, 5, 9].contains(i)), "missing {missing:?}");
    // No partial point: every record there is complete and names its point.
    for (name, bytes) in &before {
        let r: serde_json::Value = serde_json::from_slice(bytes).unwrap();
        assert_eq!(format!("{}.json", r["id"].as_str().unwrap()), *name);
        assert_eq!(r["scores"].as_array().unwrap().len(), 3);
    }
    let (ok, stdout, e) = inimtrace(&collect_args);
    assert!(ok, "{e}");
    assert!(stdout.contains(&format!("missing {}", inimtrace::count::count(missing.len(), "point"))), "{stdout}");

    // Resubmit: one chunk of exactly the missing points; the others are untouched.
    let mut again = vec!["sweep", &file, "--out", &out_s, "--slurm", "--array-max", "4", "--wait"];
    again.extend(slow);
    let (ok, stdout, e) = inimtrace(&again);
    assert!(ok, "{e}");
    assert!(e.contains(&format!("for the {} missing of 12 points", missing.len())), "{e}");
    assert!(stdout.contains("12 of 12 points complete"), "{stdout}");
    let after = records(&out);
    assert_eq!(after.len(), 12);
    for (name, bytes) in &before {
        assert_eq!(&after[name], bytes, "{name} ran again");
    }
    let newest = std::fs::read_dir(out.join("slurm"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "sbatch"))
        .max_by_key(|p| std::fs::metadata(p).unwrap().modified().unwrap())
        .unwrap();
    let script = std::fs::read_to_string(newest).unwrap();
    let listed: BTreeSet<usize> = script
        .lines()
        .skip_while(|l| *l != "POINTS=(")
        .take_while(|l| *l != ")")
        .filter_map(|l| l.trim().strip_prefix('\'').and_then(|l| l.strip_suffix('\'')))
        .flat_map(|sel| inimtrace::sweep::parse_selection(sel, 12).unwrap())
        .collect();
    assert_eq!(listed, missing, "the resubmission runs only the missing points");
    assert!(start.elapsed() < Duration::from_secs(600), "took {:?}", start.elapsed());
}

#[test]
fn a_request_the_node_cannot_satisfy_is_refused_at_submission() {
    let _one = CLUSTER.lock().unwrap_or_else(|p| p.into_inner());
    let Some(_cluster) = cluster("a_request_the_node_cannot_satisfy_is_refused_at_submission") else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slurm");
    let queued = || {
        let o = Command::new("squeue").args(["-h", "-o", "%i %j"]).output().unwrap();
        String::from_utf8_lossy(&o.stdout).lines().filter(|l| l.contains("inimtrace-tiny")).count()
    };
    let before = queued();
    let (ok, _, e) =
        inimtrace(&["sweep", &tiny(), "--out", out.to_str().unwrap(), "--slurm", "--cpus-per-task", "99", "--wait"]);
    assert!(!ok, "submitted: {e}");
    assert_eq!(e.trim().lines().count(), 1, "not one line: {e}");
    assert!(e.contains("--cpus-per-task 99") && e.contains("cannot run this job"), "{e}");
    assert_eq!(queued(), before, "a job was queued");
}
