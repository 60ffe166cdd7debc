//! Every command that traces rays says so before a long run: `ground-truth` with about 2e12
//! rays, and a resolution study with 65,536 samples per pixel, print the same long-run note as
//! `assess` before they start tracing. The child is killed as soon as the note appears, so the
//! test does not run the work.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Runs the CLI with `args` until its long-run note appears (or it ends, or 60 s pass), then
/// kills it; returns the note.
fn note_before_work(args: &[&str]) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let child = Arc::new(Mutex::new(child));
    let done = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let (child, done) = (child.clone(), done.clone());
        std::thread::spawn(move || {
            let start = Instant::now();
            while !done.load(Ordering::SeqCst) && start.elapsed() < Duration::from_secs(60) {
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.lock().unwrap().kill();
        })
    };
    let mut note = None;
    let mut seen = Vec::new();
    for line in BufReader::new(stderr).lines() {
        let line = line.unwrap();
        if line.starts_with("note: this run traces about") {
            note = Some(line);
            break;
        }
        seen.push(line);
    }
    done.store(true, Ordering::SeqCst);
    watchdog.join().unwrap();
    let _ = child.lock().unwrap().wait();
    note.unwrap_or_else(|| panic!("no long-run note; stderr: {seen:?}"))
}

#[test]
fn ground_truth_with_2e12_rays_prints_the_long_run_note_before_tracing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("gt.exr");
    // 512 x 512 pixels x 3 x 3 samples x 823,000 pupil samples (a 1024 x 1024 grid).
    let note = note_before_work(&[
        "ground-truth",
        "--focus-mm",
        "300",
        "--pupil-grid",
        "1024",
        "--retina-samples",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(note.contains("about 1.94e12 rays") && note.contains("hours"), "{note}");
    assert!(!out.exists(), "the image was written");
}

#[test]
fn a_resolution_study_with_65536_samples_per_pixel_prints_the_long_run_note_before_tracing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let note = note_before_work(&[
        "resolution",
        "--set",
        "measurement.samples_per_pixel=65536",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(note.contains("e12 rays") || note.contains("e13 rays"), "{note}");
    assert!(note.contains("hours"), "{note}");
    assert!(!out.join("study.json").exists(), "the study finished");
}
