//! `inimtrace sweep`: an experiment over the points of a sweep file, here on all cores or as a Slurm
//! job array (the library's `sweep::execute`), or `--check` of every point without running it.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::{BackendArg, Globals, TargetsMissed};

/// The flags of `inimtrace sweep`.
#[derive(Args)]
pub(crate) struct SweepArgs {
    /// Sweep TOML (see sweeps/tiny.toml, sweeps/pupil-focus.toml).
    sweep: PathBuf,
    /// Output directory (default: out/<sweep name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run only these points, without collecting: indices and ranges I..J (J excluded), e.g.
    /// 0..12 or 3,5,8..10. What each Slurm array task runs.
    #[arg(long, conflicts_with = "slurm")]
    points: Option<String>,
    /// Write every point's images and figure too (points/<id>/), as `images = true`.
    #[arg(long)]
    images: bool,
    /// Collect the complete points into sweep.csv, sweep.json and plots, list the missing
    /// ones; run nothing.
    #[arg(long, conflicts_with_all = ["slurm", "points"])]
    collect: bool,
    /// Submit the missing points to Slurm as a job array instead of running them here.
    #[arg(long)]
    slurm: bool,
    /// Slurm partition.
    #[arg(long, requires = "slurm")]
    partition: Option<String>,
    /// Most array tasks: the missing points are split into at most this many chunks.
    #[arg(long, requires = "slurm", default_value_t = 100)]
    array_max: usize,
    /// Time limit of each array task (Slurm syntax: 30, 2:00:00, 1-0).
    #[arg(long, requires = "slurm")]
    time: Option<String>,
    /// Cores of each array task (it runs that many threads).
    #[arg(long, requires = "slurm")]
    cpus_per_task: Option<usize>,
    /// At most this many array tasks at once.
    #[arg(long, requires = "slurm")]
    max_running: Option<usize>,
    /// Print the sbatch script instead of submitting it.
    #[arg(long, requires = "slurm")]
    dry_run: bool,
    /// Wait for the job array to end, then collect (an error when points are missing).
    #[arg(long, requires = "slurm")]
    wait: bool,
    /// The sweep's id at submission (array tasks refuse to run a changed sweep).
    #[arg(long, hide = true)]
    sweep_id: Option<String>,
    /// Build and validate every point (files, settings, eyes, the memory estimate), print
    /// the sweep's size, and exit without running or writing anything.
    #[arg(long, conflicts_with_all = ["slurm", "collect", "points"])]
    check: bool,
    /// Exit with status 3 when a score's 95% interval missed its precision target (the
    /// results are still written; without it a miss is reported on stderr and exits 0).
    #[arg(long)]
    strict: bool,
    #[command(flatten)]
    backend: BackendArg,
}

/// `inimtrace sweep`; `threads` and `max_memory` are the global `--threads` and `--max-memory`,
/// which each Slurm array task is given again. Returns whether the total time is not to be
/// printed (`--check` prints none).
pub(crate) fn sweep(g: &Globals, threads: Option<usize>, max_memory: Option<u64>, a: SweepArgs) -> Result<bool> {
    if a.check {
        let text = inimtrace::sweep::check(&a.sweep, &g.set, &mut |m| eprintln!("{m}"))?;
        outln!("{text}");
        return Ok(true);
    }
    let slurm = a.slurm.then(|| inimtrace::sweep::SlurmOptions {
        partition: a.partition,
        array_max: a.array_max,
        time: a.time,
        cpus_per_task: a.cpus_per_task,
        max_running: a.max_running,
        dry_run: a.dry_run,
        threads,
        max_memory,
        ..Default::default()
    });
    let cmd = inimtrace::sweep::SweepCommand {
        sweep: a.sweep,
        out: a.out,
        overrides: g.set.clone(),
        backend: a.backend.choice()?,
        quiet: g.quiet,
        points: a.points,
        images: a.images,
        exr_compression: g.exr_compression,
        collect: a.collect,
        slurm,
        wait: a.wait,
        sweep_id: a.sweep_id,
    };
    let output = inimtrace::sweep::execute(&cmd, &mut |m| eprintln!("{m}"))?;
    out!("{}", output.stdout);
    if let Some(note) = &output.missed_note {
        eprintln!("warning: {note}");
    }
    if a.strict && output.missed_rows > 0 {
        return Err(TargetsMissed(output.missed_rows).into());
    }
    Ok(false)
}
