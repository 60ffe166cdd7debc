//! `inimtrace sweep`: the paper's assessment (Sec. 4) over a sweep file's points, run here
//! (`--points` for a subset), submitted as a Slurm job array (`--slurm`, `--wait`), or only
//! collected (`--collect`). The library does not print: messages go to the caller's `log`.

use std::path::{Path, PathBuf};

use super::collect::{collect, Collected};
use super::run::{point_costs, run_points, LocalOptions, SweepInputs};
use super::slurm::{submit, sweep_command_line, wait_for, SlurmOptions};
use super::spec::parse_selection;
use super::store::Store;
use super::Sweep;
use crate::count::count;
use crate::error::{Error, Result};
use crate::overrides::Override;
use crate::render::BackendChoice;

/// The command's arguments.
#[derive(Clone, Debug, Default)]
pub struct SweepCommand {
    /// The sweep file.
    pub sweep: PathBuf,
    /// Output folder (`None`: the file's `out`, else `out/<sweep name>`).
    pub out: Option<PathBuf>,
    /// `--set`: applied to the base after the file's `[set]`.
    pub overrides: Vec<Override>,
    /// Scene intersection backend of every point.
    pub backend: BackendChoice,
    /// No progress bars.
    pub quiet: bool,
    /// Only these points (`0..4`, `3,5,8..10`), and no collection (what an array task runs).
    pub points: Option<String>,
    /// Every point's images too (also `images = true` in the file), with this EXR compression.
    pub images: bool,
    /// Compression of those images.
    pub exr_compression: crate::io::exr::ExrCompression,
    /// Collect what is complete and list what is missing; run nothing.
    pub collect: bool,
    /// Submit to Slurm instead of running here.
    pub slurm: Option<SlurmOptions>,
    /// With `slurm`: wait for the array, then collect.
    pub wait: bool,
    /// The sweep id the points were submitted under (array tasks check it).
    pub sweep_id: Option<String>,
}

/// What the command produced.
#[derive(Clone, Debug, Default)]
pub struct SweepOutput {
    /// What goes to stdout: the script of `--dry-run`, else the collection summary.
    pub stdout: String,
    /// Score rows of the collection whose intervals missed their targets (0 when nothing was
    /// collected).
    pub missed_rows: usize,
    /// The note that says so, for the end of the run (stderr): the count and where to look.
    pub missed_note: Option<String>,
}

impl From<String> for SweepOutput {
    fn from(stdout: String) -> Self {
        Self { stdout, ..Default::default() }
    }
}

/// The note at the end of a collection with rows that missed their precision target.
fn missed_note(sweep: &Sweep, c: &Collected) -> Option<String> {
    if c.missed_rows == 0 {
        return None;
    }
    let shown: Vec<String> = c.missed_points.iter().take(20).map(|i| i.to_string()).collect();
    let more = if c.missed_points.len() > 20 { ", ..." } else { "" };
    Some(format!(
        "sweep `{}`: {} of {} missed their precision target, in {} of {} (index {}{more}): \
         target_met = false in {} (sweep.json: points_missing_target); the budget (measurement.max_seconds, \
         measurement.max_samples_per_pixel) ran out first",
        sweep.spec.name,
        c.missed_rows,
        count(c.rows, "score row"),
        c.missed_points.len(),
        count(c.complete, "point"),
        shown.join(", "),
        c.csv.display()
    ))
}

/// A collection's output: its summary and, if rows missed their target, the note.
fn collected(sweep: &Sweep, c: &Collected) -> SweepOutput {
    SweepOutput { stdout: summary(sweep, c), missed_rows: c.missed_rows, missed_note: missed_note(sweep, c) }
}

/// `sweep --check`: the sweep file loaded, every point built and validated with its memory
/// estimate, and one line saying what would run (what building noticed goes to `log`). Nothing
/// is run or written, not even the output folder.
pub fn check(path: &Path, overrides: &[Override], log: &mut dyn FnMut(String)) -> Result<String> {
    let sweep = Sweep::load(path, overrides, None)?;
    let resolved = sweep.resolve()?;
    let (rays, warnings) = super::run::check_points(&resolved)?;
    for w in warnings {
        log(format!("warning: {w}"));
    }
    Ok(format!(
        "{}: valid; {}, about {:.2e} rays (nothing run)",
        path.display(),
        count(resolved.len(), "point"),
        rays as f64
    ))
}

/// Runs the command; returns what goes to stdout (the script of `--dry-run`, else the
/// collection summary) and whether score rows missed their precision target.
pub fn execute(cmd: &SweepCommand, log: &mut dyn FnMut(String)) -> Result<SweepOutput> {
    let (sweep, files) = crate::provenance::recording(|| Sweep::load(&cmd.sweep, &cmd.overrides, cmd.out.as_deref()));
    let sweep = sweep?;
    let resolved = sweep.resolve()?;
    let id = Sweep::id(&resolved)?;
    if let Some(expected) = &cmd.sweep_id {
        if *expected != id {
            return Err(Error::invalid(
                cmd.sweep.display().to_string(),
                "axes",
                "the sweep's points are not the ones submitted (the file or its experiment changed since): submit again",
            ));
        }
    }
    // A dry run writes nothing, not even the output folder.
    let dry_run = cmd.slurm.as_ref().is_some_and(|s| s.dry_run);
    let store = if dry_run { Store::existing(&sweep.out) } else { Store::open(&sweep.out)? };
    let images = cmd.images || sweep.spec.images;
    let n = sweep.points.len();
    let name = format!("sweep `{}`", sweep.spec.name);

    if cmd.collect {
        let c = collect(&sweep, &resolved, &store)?;
        return Ok(collected(&sweep, &c));
    }

    if let Some(slurm) = &cmd.slurm {
        let costs = point_costs(&resolved)?;
        let opts = SlurmOptions { images, backend: cmd.backend, exr_compression: cmd.exr_compression, ..slurm.clone() };
        let sub = submit(&sweep, &resolved, &costs, &store, &opts)?;
        if opts.dry_run {
            if sub.points.is_empty() {
                log(format!("{name}: {} complete; nothing to submit", all_points(n)));
            }
            return Ok(sub.script.into());
        }
        let Some(job) = &sub.job_id else {
            log(format!("{name}: {} complete; nothing to submit", all_points(n)));
            let c = collect(&sweep, &resolved, &store)?;
            return Ok(collected(&sweep, &c));
        };
        log(format!(
            "{name}: submitted job {job}: {} for the {} missing of {}, spread by estimated cost \
             (script {}, logs in {}/slurm/)",
            count(sub.chunks.len(), "array task"),
            sub.points.len(),
            count(n, "point"),
            sub.script_path.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
            store.root().display()
        ));
        if !cmd.wait {
            return Ok(format!(
                "submitted job {job}\ncollect at any time with:\n  {}\n",
                sweep_command_line(&sweep, store.root(), &["--collect"])
            )
            .into());
        }
        wait_for(job, &resolved, &sub.points, &store, cmd.quiet)?;
        let c = collect(&sweep, &resolved, &store)?;
        let text = summary(&sweep, &c);
        if !c.missing.is_empty() {
            return Err(Error::Incomplete(format!(
                "{text}job {job} ended with {} of {} missing (tasks failed, timed out or were cancelled; \
                 see {}/slurm/): submit only those with `{}`",
                c.missing.len(),
                count(n, "point"),
                store.root().display(),
                sweep_command_line(&sweep, store.root(), &resubmit_flags(slurm, images, cmd.backend))
            )));
        }
        return Ok(collected(&sweep, &c));
    }

    let selection = match &cmd.points {
        Some(text) => parse_selection(text, n).map_err(|e| Error::invalid("command line", "--points", e))?,
        None => (0..n).collect(),
    };
    let values = sweep.value_texts();
    let opts = LocalOptions { backend: cmd.backend, quiet: cmd.quiet, images, exr_compression: cmd.exr_compression };
    let inputs = SweepInputs {
        experiment_path: (sweep.spec.experiment != "builtin:paper")
            .then(|| sweep.spec.base().join(&sweep.spec.experiment).display().to_string()),
        files,
        set: sweep.spec.set.iter().chain(&sweep.overrides).map(|o| o.to_arg()).collect(),
    };
    let run = run_points(&resolved, &values, &selection, &store, opts, &inputs, &mut *log)?;
    if let Some(first) = run.redone.first() {
        log(format!(
            "{name}: {} run again: {} could not be verified (the first, {first})",
            count(run.redone.len(), "point"),
            if run.redone.len() == 1 { "its record" } else { "their records" }
        ));
    }
    // A study's points render their own display images (each study its charts').
    let shared = match sweep.study() {
        Some(_) => String::new(),
        None => format!(" ({} rendered, shared)", count(run.display_images, "display image")),
    };
    log(format!(
        "{name}: {} asked for, {} already complete, {} run in {:.2} s{shared}; {}",
        count(run.selected, "point"),
        run.already_complete,
        run.ran,
        run.seconds,
        count(rayon::current_num_threads(), "thread")
    ));
    if cmd.points.is_some() {
        return Ok(SweepOutput::default());
    }
    let c = collect(&sweep, &resolved, &store)?;
    Ok(collected(&sweep, &c))
}

/// "all 5 points are" (or "its only point is") of a sweep of `n` points.
fn all_points(n: usize) -> String {
    if n == 1 {
        "its only point is".into()
    } else {
        format!("all {} are", count(n, "point"))
    }
}

/// What a collection wrote and which points are missing.
fn summary(sweep: &Sweep, c: &Collected) -> String {
    let mut s = format!(
        "{} of {} complete: {} ({}), {}, {}\n",
        c.complete,
        count(sweep.points.len(), "point"),
        c.csv.display(),
        count(c.rows, "row"),
        c.json.display(),
        count(c.plots.len(), "plot")
    );
    if !c.invalid.is_empty() {
        s.push_str(&format!(
            "{} cannot count (they run again on the next run):\n",
            count(c.invalid.len(), "point record")
        ));
        for (i, why) in c.invalid.iter().take(50) {
            s.push_str(&format!("  point {i}: {why}\n"));
        }
    }
    if !c.missing.is_empty() {
        s.push_str(&format!("missing {}:\n", count(c.missing.len(), "point")));
        let values = sweep.value_texts();
        for &i in c.missing.iter().take(50) {
            s.push_str(&format!("  point {i}: {}\n", values[i].join(" ")));
        }
        if c.missing.len() > 50 {
            s.push_str(&format!("  ... and {} more (sweep.json lists every point)\n", c.missing.len() - 50));
        }
        s.push_str(&format!(
            "run them here with `{}`, or on Slurm with `{}`\n",
            sweep_command_line::<&str>(sweep, &sweep.out, &[]),
            sweep_command_line(sweep, &sweep.out, &["--slurm"])
        ));
    }
    s
}

/// The flags of a submission that matter for running its points again (not `--wait` or
/// `--dry-run`).
fn resubmit_flags(slurm: &SlurmOptions, images: bool, backend: BackendChoice) -> Vec<String> {
    let mut flags: Vec<String> = vec!["--slurm".into()];
    if let Some(p) = &slurm.partition {
        flags.extend(["--partition".into(), p.clone()]);
    }
    if slurm.array_max != SlurmOptions::default().array_max {
        flags.extend(["--array-max".into(), slurm.array_max.to_string()]);
    }
    if let Some(t) = &slurm.time {
        flags.extend(["--time".into(), t.clone()]);
    }
    if let Some(c) = slurm.cpus_per_task {
        flags.extend(["--cpus-per-task".into(), c.to_string()]);
    }
    if let Some(m) = slurm.max_running {
        flags.extend(["--max-running".into(), m.to_string()]);
    }
    if images {
        flags.push("--images".into());
    }
    if backend != BackendChoice::Auto {
        flags.extend(["--backend".into(), backend.to_string()]);
    }
    flags.push("--wait".into());
    flags
}
