//! Slurm submission that cannot be injected (issue #30, round two), without a running Slurm:
//! the batch script of `sweep --slurm --dry-run` quotes every path for bash and for sbatch's
//! `#SBATCH` lines, refuses values that would end a line or are not in Slurm's grammar, naming
//! the flag, and passes `--threads` and `--max-memory` on to the tasks. With a fake `sbatch` and
//! `squeue` first on `PATH`: a resource request the cluster refuses under `sbatch --test-only` is
//! never submitted, and `--wait` stops on a job pending for a reason that cannot clear.

use std::path::Path;
use std::process::{Command, Output};

fn inimtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("run inimtrace")
}

fn tiny() -> String {
    format!("{}/sweeps/tiny.toml", env!("CARGO_MANIFEST_DIR"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The words of an `#SBATCH` line's options as sbatch reads them: whitespace separates, double
/// quotes group, a backslash escapes the next character, `#` outside quotes ends the line.
fn sbatch_words(line: &str) -> Vec<String> {
    let mut words = Vec::new();
    let (mut word, mut quoted, mut escaped, mut any) = (String::new(), false, false, false);
    for c in line.chars() {
        if escaped {
            word.push(c);
            escaped = false;
        } else if c == '\\' {
            escaped = true;
            any = true;
        } else if c == '"' {
            quoted = !quoted;
            any = true;
        } else if c == '#' && !quoted {
            break;
        } else if c.is_whitespace() && !quoted {
            if any {
                words.push(std::mem::take(&mut word));
                any = false;
            }
        } else {
            word.push(c);
            any = true;
        }
    }
    assert!(!quoted && !escaped, "unbalanced #SBATCH line: {line}");
    if any {
        words.push(word);
    }
    words
}

/// The arguments the script's task 0 would run inimtrace with, as bash parses them (the `exec`
/// of the program replaced by printing each argument on its own line).
fn task_arguments(script: &str, dir: &Path) -> Vec<String> {
    let body: String = script
        .lines()
        .map(|l| match l.strip_prefix("exec ") {
            Some(rest) => format!("printf '%s\\n' {rest}"),
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let file = dir.join("task.sh");
    std::fs::write(&file, body).unwrap();
    let o = Command::new("bash")
        .arg(&file)
        .env("SLURM_ARRAY_TASK_ID", "0")
        .env_remove("SLURM_CPUS_PER_TASK")
        .output()
        .unwrap();
    assert!(o.status.success(), "the script does not run under bash: {}", stderr(&o));
    String::from_utf8(o.stdout).unwrap().lines().map(String::from).collect()
}

#[test]
fn an_out_folder_with_spaces_quotes_and_percent_signs_is_quoted_for_sbatch_and_bash() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("my sweep \"x\" 100%A #1 $(id) 'q'");
    let out_s = out.to_str().unwrap();
    let o = inimtrace(&[
        "--threads",
        "3",
        "--max-memory",
        "2G",
        "sweep",
        &tiny(),
        "--out",
        out_s,
        "--slurm",
        "--dry-run",
        "--time",
        "1-02:03:04",
        "--partition",
        "short,long",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let script = String::from_utf8(o.stdout).unwrap();
    let sbatch: Vec<&str> = script.lines().filter(|l| l.starts_with("#SBATCH")).collect();
    let option = |name: &str| -> String {
        let line = sbatch.iter().find(|l| l.starts_with(&format!("#SBATCH --{name}="))).unwrap_or_else(|| {
            panic!("no #SBATCH --{name}: {script}");
        });
        let words = sbatch_words(&line["#SBATCH".len()..]);
        assert_eq!(words.len(), 1, "{line} is read as {words:?}");
        words[0][name.len() + 3..].to_string()
    };
    // The log pattern is the folder itself (its `%` doubled, so that `%A` in it stays literal).
    let abs = std::path::absolute(&out).unwrap();
    assert_eq!(option("output"), format!("{}/slurm/%A_%a.out", abs.to_str().unwrap().replace('%', "%%")));
    assert_eq!(option("time"), "1-02:03:04");
    assert_eq!(option("partition"), "short,long");
    // bash reads the folder as one word, unexpanded; the task gets --threads and --max-memory.
    let args = task_arguments(&script, dir.path());
    let at = |flag: &str| args.iter().position(|a| a == flag).map(|i| args[i + 1].clone());
    assert_eq!(at("--out").as_deref(), abs.to_str(), "{args:?}");
    assert_eq!(at("--threads").as_deref(), Some("3"), "{args:?}");
    assert_eq!(at("--max-memory").as_deref(), Some(&(2u64 << 30).to_string()[..]), "{args:?}");
    assert_eq!(at("--points").as_deref(), Some("0"), "{args:?}");
}

#[test]
fn without_threads_the_task_runs_its_cpus_per_task() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o =
        inimtrace(&["sweep", &tiny(), "--out", out.to_str().unwrap(), "--slurm", "--dry-run", "--cpus-per-task", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let script = String::from_utf8(o.stdout).unwrap();
    assert!(script.contains("SLURM_CPUS_PER_TASK") && !script.contains("--max-memory"), "{script}");
}

#[test]
fn values_that_would_break_the_script_are_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let out_s = out.to_str().unwrap();
    let base = ["sweep", &tiny(), "--out", out_s, "--slurm", "--dry-run"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--time", "30\n#SBATCH --uid=0"], "--time"),
        (vec!["--time", "2h"], "--time"),
        (vec!["--time", "1:2:3:4"], "--time"),
        (vec!["--partition", "local\n#SBATCH --uid=0"], "--partition"),
        (vec!["--partition", "a b"], "--partition"),
        (vec!["--partition", "$(reboot)"], "--partition"),
        (vec!["--cpus-per-task", "0"], "--cpus-per-task"),
        (vec!["--set", "description=\"\"\"a\n#SBATCH --uid=0\"\"\""], "--set"),
    ];
    for (extra, flag) in cases {
        let mut args: Vec<&str> = base.to_vec();
        args.extend(extra.iter().copied());
        let o = inimtrace(&args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?} was accepted: {}", String::from_utf8_lossy(&o.stdout));
        assert!(e.contains(flag) && !e.contains("panicked"), "{extra:?}: {e}");
        assert!(o.stdout.is_empty(), "{extra:?}: a script was printed");
    }
    // A folder whose name holds a line break.
    let bad = dir.path().join("a\nb");
    let o = inimtrace(&["sweep", &tiny(), "--out", bad.to_str().unwrap(), "--slurm", "--dry-run"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--out") && stderr(&o).contains("control character"), "{}", stderr(&o));
}

#[test]
fn slurm_local_stop_cancels_only_its_own_clusters_jobs() {
    let text = std::fs::read_to_string(format!("{}/scripts/slurm-local.sh", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let cancels: Vec<&str> = text.lines().filter(|l| l.contains("scancel ")).collect();
    assert!(!cancels.is_empty());
    for l in cancels {
        assert!(!l.contains("--user") && !l.contains("-u "), "cancels by user: {l}");
        assert!(l.contains("--partition=\"$PARTITION\""), "not limited to its own partition: {l}");
    }
}

/// A folder holding fake `sbatch` and `squeue` (shell scripts) that log their arguments to
/// `calls.log` beside them.
fn fake_slurm(dir: &Path, sbatch: &str, squeue: &str) -> std::path::PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    for (name, body) in [("sbatch", sbatch), ("squeue", squeue)] {
        let file = bin.join(name);
        let log = bin.join("calls.log");
        let text = format!("#!/bin/sh\necho \"{name} $*\" >> '{}'\n{body}\n", log.display());
        std::fs::write(&file, text).unwrap();
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    bin
}

fn with_path(bin: &Path, args: &[&str]) -> Output {
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).env("PATH", path).output().expect("run inimtrace")
}

#[test]
fn a_request_the_cluster_cannot_satisfy_is_refused_before_submission() {
    let dir = tempfile::tempdir().unwrap();
    // Slurm's answer for 99 CPUs per task on a 2-CPU node.
    let sbatch = r#"case " $* " in *" --test-only "*)
  echo "allocation failure: Requested node configuration is not available" >&2; exit 1;;
esac
echo 4242"#;
    let bin = fake_slurm(dir.path(), sbatch, "exit 0");
    let out = dir.path().join("o");
    let o = with_path(
        &bin,
        &["--quiet", "sweep", &tiny(), "--out", out.to_str().unwrap(), "--slurm", "--cpus-per-task", "99"],
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "accepted: {e}");
    assert_eq!(e.trim().lines().count(), 1, "not one line: {e}");
    assert!(e.contains("--cpus-per-task 99") && e.contains("Requested node configuration is not available"), "{e}");
    let calls = std::fs::read_to_string(bin.join("calls.log")).unwrap();
    assert_eq!(calls.lines().count(), 1, "{calls}");
    assert!(calls.starts_with("sbatch --test-only "), "{calls}");
    // No script is left behind for a job that was never submitted.
    let scripts = std::fs::read_dir(out.join("slurm")).map(|d| d.count()).unwrap_or(0);
    assert_eq!(scripts, 0);
}

#[test]
fn wait_stops_on_a_job_pending_for_a_reason_that_cannot_clear() {
    for reason in ["PartitionConfig", "ReqNodeNotAvail,_UnavailableNodes:vm", "BadConstraints", "PartitionNodeLimit"] {
        let dir = tempfile::tempdir().unwrap();
        let bin = fake_slurm(dir.path(), "echo 4242", &format!("echo 'PENDING {reason}'"));
        let out = dir.path().join("o");
        let o = with_path(&bin, &["--quiet", "sweep", &tiny(), "--out", out.to_str().unwrap(), "--slurm", "--wait"]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{reason}: {e}");
        let last = e.trim().lines().last().unwrap_or("");
        assert!(last.contains("job 4242") && last.contains(reason) && last.contains("scancel 4242"), "{reason}: {e}");
        let calls = std::fs::read_to_string(bin.join("calls.log")).unwrap();
        assert!(calls.contains("sbatch --test-only") && calls.contains("sbatch --parsable"), "{calls}");
    }
}

#[test]
fn wait_keeps_waiting_on_a_reason_that_clears() {
    // Pending on `Resources` for five polls (longer than the hopeless reasons are given), then
    // gone: the wait ends normally and reports the points the (fake) job did not record.
    let dir = tempfile::tempdir().unwrap();
    let count = dir.path().join("polls");
    let squeue = format!(
        "n=$(cat '{0}' 2>/dev/null || echo 0); echo $((n+1)) > '{0}'; [ \"$n\" -lt 5 ] && echo 'PENDING Resources'; exit 0",
        count.display()
    );
    let bin = fake_slurm(dir.path(), "echo 4242", &squeue);
    let out = dir.path().join("o");
    let o = with_path(&bin, &["--quiet", "sweep", &tiny(), "--out", out.to_str().unwrap(), "--slurm", "--wait"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("job 4242 ended with 12 of 12 points missing") && !e.contains("cannot clear"), "{e}");
    assert_eq!(std::fs::read_to_string(&count).unwrap().trim(), "6");
}

/// Every file under `dir` with its bytes (empty when `dir` is not there).
fn tree(dir: &Path) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                out.push((p.clone(), Vec::new()));
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn a_dry_run_writes_nothing_and_its_script_spreads_points_and_hints_complete_commands() {
    let dir = tempfile::tempdir().unwrap();
    // A folder that is not there stays absent.
    let out = dir.path().join("fresh");
    let o = inimtrace(&["sweep", &tiny(), "--out", out.to_str().unwrap(), "--slurm", "--dry-run", "--array-max", "5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.exists(), "--dry-run created {}", out.display());
    let script = String::from_utf8(o.stdout).unwrap();
    // 12 points of equal cost over 5 tasks: dealt out in turn, never contiguous runs.
    for chunk in ["'0,5,10'", "'1,6,11'", "'2,7'", "'3,8'", "'4,9'"] {
        assert!(script.contains(chunk), "{chunk}: {script}");
    }
    assert!(script.contains("spread by\n# estimated cost"), "{script}");
    // The collect hint is a complete command: this program, the sweep, --out, the --set.
    let o = inimtrace(&[
        "sweep",
        &tiny(),
        "--out",
        out.to_str().unwrap(),
        "--slurm",
        "--dry-run",
        "--set",
        "eye.retina_resolution=48",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let script = String::from_utf8(o.stdout).unwrap();
    let hint = script.lines().find(|l| l.ends_with(" --collect")).unwrap_or_else(|| panic!("{script}"));
    let exe = std::fs::canonicalize(env!("CARGO_BIN_EXE_inimtrace")).unwrap();
    assert_eq!(
        hint,
        format!(
            "#   {} sweep {} --out {} --set eye.retina_resolution=48 --collect",
            exe.display(),
            tiny(),
            std::path::absolute(&out).unwrap().display()
        )
    );

    // A folder with a finished point in it: byte for byte the same afterwards.
    let used = dir.path().join("used");
    let run = inimtrace(&["--quiet", "sweep", &tiny(), "--out", used.to_str().unwrap(), "--points", "0"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let before = tree(&used);
    assert!(before.iter().any(|(p, _)| p.extension().is_some_and(|e| e == "json")));
    let o = inimtrace(&["sweep", &tiny(), "--out", used.to_str().unwrap(), "--slurm", "--dry-run"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let script = String::from_utf8(o.stdout).unwrap();
    assert!(script.contains("11 of its 12 points in 11 tasks"), "the recorded point is not submitted: {script}");
    assert_eq!(tree(&used), before, "--dry-run changed {}", used.display());
}
