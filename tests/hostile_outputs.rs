//! Hostile output folders (issue #30, round two): inimtrace never follows a link or writes
//! through a special file where it writes its outputs. A symbolic link planted at the lock, at a
//! would-be temporary name or at an output name, or a FIFO at an output name, is refused with its
//! name, the link's target is left as it was, and nothing hangs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use inimtrace::io::output::{write_atomic, OutputDir, LOCK_FILE, TEMP_PREFIX};

fn inimtrace() -> &'static str {
    env!("CARGO_BIN_EXE_inimtrace")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A one-method, 16 x 16 pinhole experiment (a fraction of a second).
fn tiny_experiment(dir: &Path) -> PathBuf {
    let p = dir.join("exp.toml");
    std::fs::write(
        &p,
        "name = \"tiny\"\nscene = \"builtin:paper\"\ndisplay = \"builtin:paper\"\nmethods = [\"LC\"]\n\
         [eye]\nretina_resolution = 16\n[[eye_cases]]\nname = \"Pin\"\npinhole = true\n",
    )
    .unwrap();
    p
}

/// Runs `assess` of the tiny experiment into `out`, killed after 60 s (a hang fails the test).
fn assess_into(dir: &Path, out: &Path) -> Output {
    let exp = tiny_experiment(dir);
    let mut child = Command::new(inimtrace())
        .args(["--quiet", "assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("assess hung on a hostile output folder");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A file outside the output folder, with known content.
fn outside_target(dir: &Path) -> PathBuf {
    let t = dir.join("precious.txt");
    std::fs::write(&t, b"do not touch").unwrap();
    t
}

fn assert_refused_naming(o: &Output, name: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "expected a clean refusal: {e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(e.contains(name), "the error does not name {name}: {e}");
}

#[test]
fn a_symlinked_lock_is_refused_and_its_target_is_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let target = outside_target(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&target, out.join(LOCK_FILE)).unwrap();
    let o = assess_into(dir.path(), &out);
    assert_refused_naming(&o, LOCK_FILE);
    assert!(stderr(&o).contains("symbolic link"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&target).unwrap(), b"do not touch", "the lock's target was truncated or written");
    assert!(!out.join("results.json").exists());
    // A lock hard-linked to an outside file would be truncated as well: refused too.
    std::fs::remove_file(out.join(LOCK_FILE)).unwrap();
    std::fs::hard_link(&target, out.join(LOCK_FILE)).unwrap();
    let e = OutputDir::open(&out, inimtrace::io::output::RunKind::Assess, false).unwrap_err().to_string();
    assert!(e.contains(LOCK_FILE) && e.contains("hard links"), "{e}");
    assert_eq!(std::fs::read(&target).unwrap(), b"do not touch");
}

#[test]
fn a_symlink_at_an_output_name_is_refused_before_work_and_its_target_is_intact() {
    let dir = tempfile::tempdir().unwrap();
    let target = outside_target(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    for name in ["table.md", "results.json", "display_LC.exr"] {
        let link = out.join(name);
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let o = assess_into(dir.path(), &out);
        assert_refused_naming(&o, name);
        assert!(stderr(&o).contains("symbolic link"), "{}", stderr(&o));
        assert_eq!(std::fs::read(&target).unwrap(), b"do not touch", "{name}: the link's target changed");
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "{name}: the link was replaced");
        // Refused when the folder is opened: not one image was written.
        let image = std::fs::symlink_metadata(out.join("display_LC.exr"));
        assert!(!image.is_ok_and(|m| m.is_file()) && !out.join("figure.png").exists(), "{name}");
        std::fs::remove_file(&link).unwrap();
    }
    // Without the links the same folder runs.
    let o = assess_into(dir.path(), &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("results.json").is_file());
}

#[test]
fn a_fifo_or_directory_at_an_output_name_is_refused_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let fifo = out.join("results.json");
    if !Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false) {
        eprintln!("skipped: mkfifo is not available on this machine");
        return;
    }
    let o = assess_into(dir.path(), &out);
    assert_refused_naming(&o, "results.json");
    assert!(stderr(&o).contains("FIFO"), "{}", stderr(&o));
    std::fs::remove_file(&fifo).unwrap();
    Command::new("mkfifo").arg(out.join("table.md")).status().unwrap();
    let o = assess_into(dir.path(), &out);
    assert_refused_naming(&o, "table.md");
    std::fs::remove_file(out.join("table.md")).unwrap();
    std::fs::create_dir(out.join("figure.png")).unwrap();
    let o = assess_into(dir.path(), &out);
    assert_refused_naming(&o, "figure.png");
    assert!(stderr(&o).contains("directory"), "{}", stderr(&o));
}

#[test]
fn atomic_writes_refuse_a_planted_link_and_use_fresh_unpredictable_temporaries() {
    let dir = tempfile::tempdir().unwrap();
    let target = outside_target(dir.path());
    // A link at the final name: refused before the writer runs, target intact.
    let link = dir.path().join("sweep.csv");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let mut ran = false;
    let e = write_atomic(&link, |p| {
        ran = true;
        std::fs::write(p, b"x").map_err(|e| inimtrace::error::Error::io(p, e))
    })
    .unwrap_err()
    .to_string();
    assert!(!ran && e.contains("sweep.csv") && e.contains("symbolic link"), "{e}");
    assert_eq!(std::fs::read(&target).unwrap(), b"do not touch");
    // Links planted at every name the old scheme used (`.inimtrace-tmp-<pid>-<name>`) are not
    // followed; the temporary is somewhere new each time, inside a private folder.
    let pid = std::process::id();
    for name in ["a.csv", "b.csv"] {
        std::os::unix::fs::symlink(&target, dir.path().join(format!("{TEMP_PREFIX}{pid}-{name}"))).unwrap();
    }
    let mut temps = Vec::new();
    for name in ["a.csv", "b.csv", "a.csv"] {
        write_atomic(&dir.path().join(name), |p| {
            temps.push(p.to_path_buf());
            let folder = p.parent().unwrap();
            assert!(folder.file_name().unwrap().to_string_lossy().starts_with(TEMP_PREFIX));
            let meta = std::fs::symlink_metadata(folder).unwrap();
            assert!(meta.is_dir(), "the temporary's folder is not a fresh directory");
            assert_eq!(std::os::unix::fs::PermissionsExt::mode(&meta.permissions()) & 0o777, 0o700);
            assert!(std::fs::symlink_metadata(p).unwrap().is_file(), "the temporary was not created new");
            std::fs::write(p, name).map_err(|e| inimtrace::error::Error::io(p, e))
        })
        .unwrap();
    }
    assert_eq!(temps.len(), 3);
    assert!(temps[0] != temps[2], "the same temporary name twice: {temps:?}");
    assert_eq!(std::fs::read(&target).unwrap(), b"do not touch");
    assert_eq!(std::fs::read(dir.path().join("a.csv")).unwrap(), b"a.csv");
    // No temporary folder is left behind.
    let left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(TEMP_PREFIX) && !n.starts_with(&format!("{TEMP_PREFIX}{pid}-")))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn sweep_records_and_scripts_do_not_follow_links() {
    let dir = tempfile::tempdir().unwrap();
    let target = outside_target(dir.path());
    let store = inimtrace::sweep::Store::open(&dir.path().join("sw")).unwrap();
    let points = dir.path().join("sw/points");
    // A record that is a link to a file elsewhere, or a FIFO, is not complete and is not read
    // (no hang); writing the point replaces nothing through it.
    let id = "00000000000000aa".to_string();
    std::os::unix::fs::symlink(&target, points.join(format!("{id}.json"))).unwrap();
    assert!(store.read(&id).is_none());
    assert!(store.complete([&id]).is_empty());
    let fifo_id = "00000000000000bb".to_string();
    if Command::new("mkfifo").arg(points.join(format!("{fifo_id}.json"))).status().map(|s| s.success()).unwrap_or(false)
    {
        let t = Instant::now();
        assert!(store.read(&fifo_id).is_none());
        assert!(t.elapsed() < Duration::from_secs(5));
    }
    assert_eq!(std::fs::read(&target).unwrap(), b"do not touch");
}

/// Names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    n.sort();
    n
}

fn resolution_into(out: &Path, force: bool) -> Output {
    let mut args = vec!["--quiet", "resolution", "studies/tiny.toml", "--out", out.to_str().unwrap()];
    if force {
        args.push("--force");
    }
    Command::new(inimtrace()).args(&args).output().unwrap()
}

#[test]
fn one_folder_holds_one_commands_results_and_force_removes_only_what_its_report_lists() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = assess_into(dir.path(), &out);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(out.join("my-notes.md"), b"mine").unwrap();
    let assessed = listing(&out);
    assert!(assessed.iter().any(|n| n == "results.json"), "{assessed:?}");
    assert!(!assessed.iter().any(|n| n.starts_with('.')), "the lock or a journal stayed behind: {assessed:?}");
    let bytes: Vec<Vec<u8>> = assessed.iter().map(|n| std::fs::read(out.join(n)).unwrap()).collect();

    // `resolution` refuses the folder, naming `assess` and --force, and nothing changes.
    let o = resolution_into(&out, false);
    assert_refused_naming(&o, "inimtrace assess");
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(listing(&out), assessed, "a refused run changed the folder");
    for (n, b) in assessed.iter().zip(&bytes) {
        assert_eq!(&std::fs::read(out.join(n)).unwrap(), b, "{n} changed");
    }

    // Forced, it removes exactly the files results.json listed, keeps the user's, and writes its own.
    let report: serde_json::Value =
        serde_json::from_slice(&bytes[assessed.iter().position(|n| n == "results.json").unwrap()]).unwrap();
    let listed: Vec<String> =
        report["files"].as_array().unwrap().iter().map(|f| f["name"].as_str().unwrap().to_string()).collect();
    assert!(!listed.is_empty());
    let o = resolution_into(&out, true);
    assert!(o.status.success(), "{}", stderr(&o));
    let after = listing(&out);
    for n in &listed {
        assert!(!after.contains(n), "{n} of the assess run is still there: {after:?}");
    }
    assert!(!after.iter().any(|n| n == "results.json"));
    assert!(after.iter().any(|n| n == "my-notes.md") && after.iter().any(|n| n == "study.json"), "{after:?}");
    assert_eq!(std::fs::read(out.join("my-notes.md")).unwrap(), b"mine");

    // And `assess` now refuses the resolution folder.
    let o = assess_into(dir.path(), &out);
    assert_refused_naming(&o, "inimtrace resolution");
}

#[test]
fn a_users_results_json_is_never_deleted() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("results.json"), b"{\"mine\": 1}").unwrap();
    let o = assess_into(dir.path(), &out);
    assert_refused_naming(&o, "results.json");
    assert_eq!(std::fs::read(out.join("results.json")).unwrap(), b"{\"mine\": 1}");
}
