//! A sweep (the paper's assessment, Sec. 4, over ranges of settings) as a Slurm job array:
//! the points not yet recorded are spread over the array tasks by estimated cost (the rays each
//! point traces; longest first, each onto the task with the least cost so far), and each task
//! runs `inimtrace sweep SWEEP.toml --points ...` into the shared output folder, recording each
//! point atomically. A failed, timed-out or cancelled task therefore leaves only complete
//! points, and submitting again runs only what is missing. Slurm does the distribution; this
//! file only writes the batch script, calls `sbatch`, and polls `squeue` for `--wait`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use super::spec::format_selection;
use super::store::Store;
use super::PointSpec;
use super::Sweep;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::render::BackendChoice;

/// How to submit.
#[derive(Clone, Debug)]
pub struct SlurmOptions {
    /// `#SBATCH --partition`.
    pub partition: Option<String>,
    /// Most array tasks: the missing points are split into at most this many chunks.
    pub array_max: usize,
    /// `#SBATCH --time` (a Slurm time limit: `30`, `2:00:00`, `1-0`).
    pub time: Option<String>,
    /// `#SBATCH --cpus-per-task`; each task then runs that many threads.
    pub cpus_per_task: Option<usize>,
    /// At most this many tasks at once (`--array=0-N%M`).
    pub max_running: Option<usize>,
    /// Print the script instead of submitting it.
    pub dry_run: bool,
    /// Scene intersection backend of every point.
    pub backend: BackendChoice,
    /// Write every point's images too.
    pub images: bool,
    /// Compression of those images.
    pub exr_compression: crate::io::exr::ExrCompression,
    /// `--threads` at submission: each task runs that many (else `--cpus-per-task`, else all).
    pub threads: Option<usize>,
    /// `--max-memory` at submission, bytes: each task gets the same limit.
    pub max_memory: Option<u64>,
}

impl Default for SlurmOptions {
    fn default() -> Self {
        Self {
            partition: None,
            array_max: 100,
            time: None,
            cpus_per_task: None,
            max_running: None,
            dry_run: false,
            backend: BackendChoice::Auto,
            images: false,
            exr_compression: Default::default(),
            threads: None,
            max_memory: None,
        }
    }
}

/// What was submitted.
#[derive(Clone, Debug)]
pub struct Submission {
    /// Slurm's job id (none for a dry run or when nothing was missing).
    pub job_id: Option<String>,
    /// The points submitted, and the `--points` text of each task.
    pub points: Vec<usize>,
    /// The `--points` text of each array task.
    pub chunks: Vec<String>,
    /// The estimated cost of each array task (rays; see [`super::point_costs`]).
    pub task_costs: Vec<u64>,
    /// The job script.
    pub script: String,
    /// Where the script was written (`None` for a dry run).
    pub script_path: Option<PathBuf>,
}

/// Writes the batch script for the points of `sweep` that `store` has no record of and, unless
/// `dry_run`, submits it with `sbatch`. `costs` are the points' estimated costs by index
/// ([`super::point_costs`]). Nothing is submitted when every point is complete; a dry run
/// writes nothing.
pub fn submit(
    sweep: &Sweep,
    resolved: &[PointSpec],
    costs: &[u64],
    store: &Store,
    opts: &SlurmOptions,
) -> Result<Submission> {
    if opts.array_max == 0 {
        return Err(Error::invalid("command line", "--array-max", "must be at least 1"));
    }
    validate_options(opts)?;
    let mut seen = std::collections::HashSet::new();
    let missing: Vec<usize> = sweep
        .points
        .iter()
        .map(|p| p.index)
        .filter(|&i| seen.insert(resolved[i].id().to_string()) && store.record_of(&resolved[i]).is_none())
        .collect();
    let (chunks, task_costs) = balance(&missing, costs, opts.array_max);
    let mut sub =
        Submission { job_id: None, points: missing, chunks, task_costs, script: String::new(), script_path: None };
    if sub.points.is_empty() {
        return Ok(sub);
    }
    let id = Sweep::id(resolved)?;
    sub.script = script(sweep, &sub.chunks, &sub.task_costs, &id, store.root(), opts)?;
    if opts.dry_run {
        return Ok(sub);
    }
    let dir = store.root().join("slurm");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let path = dir.join(format!("submit-{}-{}.sbatch", super::store::unix_now(), std::process::id()));
    crate::io::output::write_atomic(&path, |tmp| std::fs::write(tmp, &sub.script).map_err(|e| Error::io(tmp, e)))?;
    if let Err(e) = test_only(&path, opts) {
        let _ = std::fs::remove_file(&path);
        return Err(e);
    }
    let out = run_sbatch(&["--parsable"], &path)?;
    if !out.status.success() {
        return Err(Error::External {
            program: "sbatch",
            message: format!("sbatch {} failed: {}", path.display(), String::from_utf8_lossy(&out.stderr).trim()),
        });
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let job = text.trim().split(';').next().unwrap_or("").trim().to_string();
    if job.is_empty() {
        return Err(Error::External {
            program: "sbatch",
            message: format!("sbatch printed no job id for {}", path.display()),
        });
    }
    sub.job_id = Some(job);
    sub.script_path = Some(path);
    Ok(sub)
}

/// Runs `sbatch ARGS SCRIPT`.
fn run_sbatch(args: &[&str], script: &Path) -> Result<std::process::Output> {
    Command::new("sbatch").args(args).arg(script).output().map_err(|e| Error::External {
        program: "sbatch",
        message: format!(
            "cannot run `sbatch` ({e}): is this a Slurm cluster? (`scripts/slurm-local.sh start` brings up one on this machine)"
        ),
    })
}

/// Asks Slurm, with `sbatch --test-only`, whether the cluster can ever run the script as written
/// (partition, time limit, CPUs per task): a request it cannot satisfy would otherwise stay
/// pending for ever. The refusal is one line naming the requested resources and Slurm's reasons.
fn test_only(script: &Path, opts: &SlurmOptions) -> Result<()> {
    let out = run_sbatch(&["--test-only"], script)?;
    if out.status.success() {
        return Ok(());
    }
    let mut asked = Vec::new();
    if let Some(p) = &opts.partition {
        asked.push(format!("--partition {p}"));
    }
    if let Some(t) = &opts.time {
        asked.push(format!("--time {t}"));
    }
    if let Some(c) = opts.cpus_per_task {
        asked.push(format!("--cpus-per-task {c}"));
    }
    let asked = if asked.is_empty() { String::new() } else { format!(" ({})", asked.join(", ")) };
    Err(Error::External {
        program: "sbatch",
        message: format!(
            "the cluster cannot run this job as requested{asked}: {} (`sbatch --test-only` refused it; nothing was submitted)",
            slurm_reasons(&String::from_utf8_lossy(&out.stderr))
        ),
    })
}

/// Slurm's error text as one line: its lines without the `sbatch: error:` and `allocation
/// failure:` prefixes, each once, joined by `; `.
fn slurm_reasons(stderr: &str) -> String {
    let mut reasons: Vec<String> = Vec::new();
    for line in stderr.lines() {
        let mut l = line.trim();
        for prefix in ["sbatch: error:", "sbatch:", "error:", "allocation failure:", "Batch job submission failed:"] {
            l = l.strip_prefix(prefix).map(str::trim).unwrap_or(l);
        }
        let l: String = l.chars().filter(|c| !c.is_control()).collect();
        if !l.is_empty() && !reasons.iter().any(|r| r.eq_ignore_ascii_case(&l)) {
            reasons.push(l);
        }
    }
    if reasons.is_empty() {
        "sbatch gave no reason".to_string()
    } else {
        reasons.join("; ")
    }
}

/// Whether a pending job's `squeue` reason (`%r`) is one that cannot clear by waiting: the job
/// asks for more than its partition or the cluster has, for nodes that are not there, or for
/// what its account or QOS may never have.
fn reason_never_clears(reason: &str) -> bool {
    const NEVER: [&str; 12] = [
        "PartitionConfig",
        "PartitionNodeLimit",
        "PartitionTimeLimit",
        "BadConstraints",
        "ReqNodeNotAvail",
        "InvalidAccount",
        "InvalidQOS",
        "DependencyNeverSatisfied",
        "Nodes_required_for_job_are_DOWN",
        "AssocMaxCpuPerJobLimit",
        "AssocMaxNodePerJobLimit",
        "AssocMaxWallDurationPerJobLimit",
    ];
    let r = reason.trim();
    NEVER.iter().any(|n| r.starts_with(n))
        || (r.starts_with("QOSMax") && r.ends_with("PerJobLimit"))
        || (r.starts_with("QOSMin") && r.ends_with("Limit"))
}

/// How many polls in a row (half a second apart) a pending reason that cannot clear is seen
/// before `--wait` gives up: one poll could catch the controller between two decisions.
const HOPELESS_POLLS: usize = 3;

/// Waits until job `job` has no task pending or running, showing the points recorded so far.
/// A task pending for a reason that cannot clear (`reason_never_clears`) stops the wait with
/// an error naming the reason (the job stays queued; `scancel` removes it).
pub fn wait_for(job: &str, resolved: &[PointSpec], points: &[usize], store: &Store, quiet: bool) -> Result<()> {
    let progress = Progress::new(points.len() as u64, &format!("slurm job {job}"), quiet);
    let mut shown = 0;
    let mut failures = 0;
    let mut hopeless = 0;
    loop {
        let done = points.iter().filter(|&&i| store.record_of(&resolved[i]).is_some()).count();
        if done > shown {
            progress.inc((done - shown) as u64);
            shown = done;
        }
        let out = Command::new("squeue")
            .args(["-h", "-j", job, "-o", "%T %r"])
            .output()
            .map_err(|e| Error::External { program: "squeue", message: format!("cannot run `squeue` ({e})") })?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        if out.status.success() {
            failures = 0;
            let stdout = String::from_utf8_lossy(&out.stdout);
            if stdout.trim().is_empty() {
                break;
            }
            let stuck = stdout.lines().find_map(|l| {
                let (state, reason) = l.trim().split_once(' ')?;
                (state == "PENDING" && reason_never_clears(reason)).then(|| reason.trim().to_string())
            });
            match stuck {
                Some(reason) => {
                    hopeless += 1;
                    if hopeless >= HOPELESS_POLLS {
                        progress.finish();
                        let reason: String = reason.chars().filter(|c| !c.is_control()).take(200).collect();
                        return Err(Error::External {
                            program: "squeue",
                            message: format!(
                                "job {job} is pending for a reason that cannot clear by waiting: {reason} \
                                 (the cluster cannot give it what it asks for); it is still queued: \
                                 `scancel {job}` removes it"
                            ),
                        });
                    }
                }
                None => hopeless = 0,
            }
        } else if stderr.contains("Invalid job id") {
            break; // finished long enough ago that Slurm forgot it
        } else {
            failures += 1;
            if failures >= 30 {
                return Err(Error::External {
                    program: "squeue",
                    message: format!("squeue keeps failing for job {job}: {}", stderr.trim()),
                });
            }
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    progress.finish();
    Ok(())
}

/// Spreads the point indices `points` over at most `n` tasks by cost (`costs[i]` of point `i`):
/// the costliest point first, each onto the task with the least cost so far (the lowest task on
/// a tie), so that equal costs are dealt out in turn (0, n, 2n, ... to the first task) and a
/// sweep whose cost grows along an axis does not give one task all the expensive points.
/// Returns each task's points as `--points` text and its total cost.
fn balance(points: &[usize], costs: &[u64], n: usize) -> (Vec<String>, Vec<u64>) {
    let tasks = n.min(points.len());
    if tasks == 0 {
        return (Vec::new(), Vec::new());
    }
    let cost = |i: usize| costs.get(i).copied().unwrap_or(1).max(1);
    let mut order = points.to_vec();
    // Stable: equal costs keep the sweep's order.
    order.sort_by_key(|&i| std::cmp::Reverse(cost(i)));
    let mut bins: Vec<(u64, Vec<usize>)> = vec![(0, Vec::new()); tasks];
    for i in order {
        let t = (0..tasks).min_by_key(|&t| bins[t].0).unwrap_or(0);
        bins[t].0 = bins[t].0.saturating_add(cost(i));
        bins[t].1.push(i);
    }
    bins.into_iter()
        .map(|(total, mut members)| {
            members.sort_unstable();
            (format_selection(&members), total)
        })
        .unzip()
}

/// A complete `inimtrace sweep` command line for `sweep` writing into `out`: this program, the
/// sweep file and `--out` as absolute paths, the command line's `--set` overrides, then `extra`
/// (each a word, quoted for a shell as needed). For the hints of submission and collection.
pub fn sweep_command_line<S: AsRef<str>>(sweep: &Sweep, out: &Path, extra: &[S]) -> String {
    let exe = std::env::current_exe().map(|p| p.display().to_string()).unwrap_or_else(|_| "inimtrace".into());
    let abs = |p: &Path| absolute(p).unwrap_or_else(|_| p.to_path_buf()).display().to_string();
    let mut words = vec![shell_word(&exe), "sweep".into(), shell_word(&abs(&sweep.spec.path))];
    words.extend(["--out".into(), shell_word(&abs(out))]);
    for o in &sweep.overrides {
        words.extend(["--set".into(), shell_word(&o.to_arg())]);
    }
    words.extend(extra.iter().map(|w| shell_word(w.as_ref())));
    words.join(" ")
}

/// A word for a shell: as it is when it holds only characters no shell treats specially, else
/// single-quoted.
fn shell_word(s: &str) -> String {
    if !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b"/._-+=,:@%".contains(&b)) {
        s.to_string()
    } else {
        quote(s)
    }
}

/// A word for bash, single-quoted.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).map_err(|e| Error::io(p, e))
}

/// The sbatch script of a job array over `chunks` (with their estimated costs).
fn script(
    sweep: &Sweep,
    chunks: &[String],
    task_costs: &[u64],
    id: &str,
    out: &Path,
    opts: &SlurmOptions,
) -> Result<String> {
    let exe = std::env::current_exe()
        .map_err(|e| Error::External { program: "current_exe", message: format!("cannot find this program: {e}") })?;
    let cwd = std::env::current_dir()
        .map_err(|e| Error::External { program: "current_dir", message: format!("no current directory: {e}") })?;
    let sweep_file = absolute(&sweep.spec.path)?;
    let out = absolute(out)?;
    for (flag, path) in [("--out", &out), ("SWEEP", &sweep_file), ("current directory", &cwd), ("program", &exe)] {
        script_path_text(flag, path)?;
    }
    for o in &sweep.overrides {
        script_text("--set", &o.to_arg())?;
    }
    let mut s = String::from("#!/bin/bash\n");
    s.push_str(&format!("#SBATCH --job-name=inimtrace-{}\n", sweep.spec.name));
    let throttle = opts.max_running.map(|m| format!("%{m}")).unwrap_or_default();
    s.push_str(&format!("#SBATCH --array=0-{}{throttle}\n", chunks.len() - 1));
    let log = format!("{}/slurm/", slurm_pattern_literal(&script_path_text("--out", &out)?));
    s.push_str(&format!("#SBATCH --output={}\n", sbatch_quote(&format!("{log}%A_%a.out"))));
    if let Some(p) = &opts.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = &opts.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    if let Some(c) = opts.cpus_per_task {
        s.push_str(&format!("#SBATCH --cpus-per-task={c}\n"));
    }
    let points: usize =
        chunks.iter().map(|c| super::parse_selection(c, usize::MAX).map(|v| v.len()).unwrap_or(0)).sum();
    let (lo, hi) = (task_costs.iter().min().copied().unwrap_or(0), task_costs.iter().max().copied().unwrap_or(0));
    s.push_str(&format!(
        "#\n# inimtrace sweep {} as a Slurm job array: {points} of its {} points in {} tasks, spread by\n\
         # estimated cost (rays traced; costliest first, each onto the least-loaded task): {lo} to {hi} rays\n\
         # per task. Written by `inimtrace sweep --slurm`. Each task runs its points and records each one\n\
         # atomically in {}/points/, so a failed, timed-out or cancelled task leaves no partial point;\n\
         # submitting again runs only the missing points. Collect at any time with:\n\
         #   {}\n",
        sweep_file.display(),
        sweep.points.len(),
        chunks.len(),
        out.display(),
        sweep_command_line(sweep, &out, &["--collect"]),
    ));
    s.push_str("set -euo pipefail\nPOINTS=(\n");
    for c in chunks {
        s.push_str(&format!("  {}\n", quote(c)));
    }
    s.push_str(")\n");
    s.push_str(&format!("cd {}\n", quote(&cwd.display().to_string())));
    match opts.threads {
        Some(n) => s.push_str(&format!("THREADS=(--threads {n})\n")),
        None => s.push_str(
            "THREADS=()\nif [ -n \"${SLURM_CPUS_PER_TASK:-}\" ]; then THREADS=(--threads \"$SLURM_CPUS_PER_TASK\"); fi\n",
        ),
    }
    let memory = opts.max_memory.map(|b| format!(" --max-memory {b}")).unwrap_or_default();
    let mut lines = vec![
        format!(
            "exec {} --quiet \"${{THREADS[@]}}\"{memory} sweep {}",
            quote(&exe.display().to_string()),
            quote(&sweep_file.display().to_string())
        ),
        format!("--out {} --points \"${{POINTS[$SLURM_ARRAY_TASK_ID]}}\"", quote(&out.display().to_string())),
        format!("--sweep-id {id} --backend {}", opts.backend),
    ];
    if opts.images {
        lines.push(format!("--images --exr-compression {}", opts.exr_compression.name()));
    }
    for o in &sweep.overrides {
        lines.push(format!("--set {}", quote(&o.to_arg())));
    }
    s.push_str(&lines.join(" \\\n  "));
    s.push('\n');
    Ok(s)
}

/// Checks every option that goes into the batch script, naming the flag.
fn validate_options(opts: &SlurmOptions) -> Result<()> {
    if let Some(t) = &opts.time {
        check_time(t).map_err(|m| Error::invalid("command line", "--time", m))?;
    }
    if let Some(p) = &opts.partition {
        check_partition(p).map_err(|m| Error::invalid("command line", "--partition", m))?;
    }
    for (flag, v) in [("--cpus-per-task", opts.cpus_per_task), ("--max-running", opts.max_running)] {
        if v == Some(0) {
            return Err(Error::invalid("command line", flag, "must be at least 1"));
        }
    }
    Ok(())
}

/// A Slurm time limit: `minutes`, `minutes:seconds`, `hours:minutes:seconds`, `days-hours`,
/// `days-hours:minutes`, `days-hours:minutes:seconds` (each part decimal digits), or
/// `INFINITE` / `UNLIMITED`.
fn check_time(t: &str) -> std::result::Result<(), String> {
    let shown = t.escape_debug();
    let number = |p: &str| !p.is_empty() && p.len() <= 9 && p.bytes().all(|b| b.is_ascii_digit());
    let ok = if matches!(t, "INFINITE" | "UNLIMITED" | "infinite" | "unlimited") {
        true
    } else if let Some((days, rest)) = t.split_once('-') {
        let parts: Vec<&str> = rest.split(':').collect();
        number(days) && parts.len() <= 3 && parts.iter().all(|p| number(p))
    } else {
        let parts: Vec<&str> = t.split(':').collect();
        parts.len() <= 3 && parts.iter().all(|p| number(p))
    };
    if ok {
        Ok(())
    } else {
        Err(format!(
            "`{shown}` is not a Slurm time limit (minutes, minutes:seconds, hours:minutes:seconds, days-hours, \
             days-hours:minutes or days-hours:minutes:seconds, e.g. 30, 2:00:00, 1-0)"
        ))
    }
}

/// A partition name, or a comma-separated list of them: letters, digits, `_`, `.` and `-`.
fn check_partition(p: &str) -> std::result::Result<(), String> {
    let name =
        |n: &str| !n.is_empty() && n.bytes().all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'.' | b'-'));
    if p.split(',').all(name) {
        Ok(())
    } else {
        Err(format!(
            "`{}` is not a partition name (letters, digits, _, . and -; several separated by commas)",
            p.escape_debug()
        ))
    }
}

/// `text`, refused if it holds a line break or another control character (it would end a line of
/// the batch script).
fn script_text(flag: &str, text: &str) -> Result<()> {
    match text.chars().find(|c| c.is_control()) {
        Some(c) => Err(Error::invalid(
            "command line",
            flag,
            format!(
                "`{}` holds the control character {:?}, which cannot go into a batch script",
                text.escape_debug(),
                c
            ),
        )),
        None => Ok(()),
    }
}

/// A path as UTF-8 text for the batch script (see [`script_text`]).
fn script_path_text(flag: &str, path: &Path) -> Result<String> {
    let text = path
        .to_str()
        .ok_or_else(|| Error::invalid("command line", flag, format!("`{}` is not UTF-8 text", path.display())))?;
    script_text(flag, text)?;
    Ok(text.to_string())
}

/// A literal part of a Slurm file name pattern: `%` doubled, so that `%A`-like text in a folder
/// name is not replaced.
fn slurm_pattern_literal(s: &str) -> String {
    s.replace('%', "%%")
}

/// A value of an `#SBATCH` line: double-quoted, with `\` and `"` escaped by a backslash (sbatch
/// reads such a line as a shell-like word: quotes group, a backslash escapes, `#` outside quotes
/// starts a comment).
fn sbatch_quote(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        if matches!(c, '\\' | '"') {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limits_follow_slurms_grammar() {
        for good in ["30", "30:00", "2:00:00", "1-0", "1-12", "1-12:30", "1-12:30:15", "INFINITE", "0"] {
            assert!(check_time(good).is_ok(), "{good}");
        }
        for bad in [
            "",
            "1:2:3:4",
            "1-",
            "-1",
            "1-2-3",
            "1-1:1:1:1",
            "2h",
            "1 0",
            "30\n#SBATCH --uid=0",
            "30;rm",
            "1-0\n",
            ":",
            "1::2",
            "１２",
            "+5",
        ] {
            let e = check_time(bad).unwrap_err();
            assert!(e.contains("Slurm time limit"), "{bad}: {e}");
        }
    }

    #[test]
    fn partitions_are_conservative_names() {
        for good in ["local", "gpu-a100", "short,long", "p_1.x"] {
            assert!(check_partition(good).is_ok(), "{good}");
        }
        for bad in ["", "a,,b", ",a", "a b", "a\n#SBATCH --x", "a;b", "$(id)", "a'b", "a\"b"] {
            assert!(check_partition(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn script_values_refuse_control_characters_and_quote_for_sbatch() {
        assert!(script_text("--out", "/a b/c").is_ok());
        for bad in ["/a\nb", "/a\rb", "/a\tb", "/a\u{1b}b", "/a\0b"] {
            let e = script_text("--out", bad).unwrap_err().to_string();
            assert!(e.contains("--out") && e.contains("control character"), "{e}");
        }
        assert_eq!(sbatch_quote("/a b/%A_%a.out"), "\"/a b/%A_%a.out\"");
        assert_eq!(sbatch_quote("/q\"x\\y #z"), "\"/q\\\"x\\\\y #z\"");
        assert_eq!(slurm_pattern_literal("/100%A/"), "/100%%A/");
        let o = SlurmOptions { time: Some("1:00\n".into()), ..Default::default() };
        assert!(validate_options(&o).unwrap_err().to_string().contains("--time"));
        let o = SlurmOptions { partition: Some("x\ny".into()), ..Default::default() };
        assert!(validate_options(&o).unwrap_err().to_string().contains("--partition"));
    }

    #[test]
    fn points_of_equal_cost_are_dealt_out_in_turn() {
        let ones = vec![7; 12];
        let (chunks, totals) = balance(&(0..12).collect::<Vec<_>>(), &ones, 4);
        assert_eq!(chunks, ["0,4,8", "1,5,9", "2,6,10", "3,7,11"]);
        assert_eq!(totals, [21, 21, 21, 21]);
        assert_eq!(balance(&[0, 1, 2, 3, 4], &ones, 2).0, ["0,2,4", "1,3"]);
        assert_eq!(balance(&[3, 4, 5], &ones, 4).0, ["3", "4", "5"]);
        assert_eq!(balance(&[1, 3, 4, 9], &[1; 10], 1).0, ["1,3..5,9"]);
        assert!(balance(&[], &ones, 4).0.is_empty());
    }

    #[test]
    fn costs_growing_along_an_axis_are_balanced_unlike_contiguous_chunks() {
        // Cost grows with the index (a pupil or resolution axis): contiguous halves would be
        // 1+..+8 = 36 against 9+..+16 = 100.
        let costs: Vec<u64> = (1..=16).collect();
        let points: Vec<usize> = (0..16).collect();
        let (chunks, totals) = balance(&points, &costs, 2);
        assert_eq!(totals.iter().sum::<u64>(), 136);
        assert_eq!(totals, [68, 68], "{chunks:?}");
        // Every point in exactly one task.
        let mut all: Vec<usize> = chunks.iter().flat_map(|c| crate::sweep::parse_selection(c, 16).unwrap()).collect();
        all.sort_unstable();
        assert_eq!(all, points);
        // One very costly point gets a task of its own.
        let mut costs = vec![1u64; 9];
        costs[4] = 100;
        let (chunks, totals) = balance(&(0..9).collect::<Vec<_>>(), &costs, 3);
        assert_eq!(chunks[0], "4");
        assert_eq!(totals, [100, 4, 4]);
    }

    #[test]
    fn hint_words_are_quoted_only_when_needed() {
        assert_eq!(shell_word("/a/b.toml"), "/a/b.toml");
        assert_eq!(shell_word("eye.pupil_diameter=3"), "eye.pupil_diameter=3");
        assert_eq!(shell_word("methods=[\"LC\"]"), "'methods=[\"LC\"]'");
        assert_eq!(shell_word("/a b"), "'/a b'");
        assert_eq!(shell_word(""), "''");
    }

    #[test]
    fn pending_reasons_that_cannot_clear_are_told_from_those_that_can() {
        for never in [
            "PartitionConfig",
            "PartitionNodeLimit",
            "PartitionTimeLimit",
            "BadConstraints",
            "ReqNodeNotAvail,_UnavailableNodes:vm",
            "ReqNodeNotAvail(Unavailable)",
            "InvalidQOS",
            "QOSMaxCpuPerJobLimit",
            "DependencyNeverSatisfied",
        ] {
            assert!(reason_never_clears(never), "{never}");
        }
        for clears in [
            "None",
            "Resources",
            "Priority",
            "JobArrayTaskLimit",
            "BeginTime",
            "Dependency",
            "QOSMaxJobsPerUserLimit",
            "",
        ] {
            assert!(!reason_never_clears(clears), "{clears}");
        }
    }

    #[test]
    fn slurms_refusal_becomes_one_line() {
        let text = "allocation failure: Requested node configuration is not available\n";
        assert_eq!(slurm_reasons(text), "Requested node configuration is not available");
        let text = "sbatch: error: CPU count per node can not be satisfied\n\
                    sbatch: error: Batch job submission failed: Requested node configuration is not available\n";
        assert_eq!(
            slurm_reasons(text),
            "CPU count per node can not be satisfied; Requested node configuration is not available"
        );
        assert_eq!(slurm_reasons(""), "sbatch gave no reason");
    }

    #[test]
    fn words_are_quoted_for_bash() {
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote("it's"), "'it'\\''s'");
    }
}
