//! `inimtrace assess`: runs an experiment and writes every image, the table and the figure;
//! a score whose interval missed its precision target is reported (and with `--strict` fails).

use std::path::PathBuf;

use anyhow::Result;

use inimtrace::experiment::{self, RunOptions};
use inimtrace::settings::load_experiment;

use super::announce;
use crate::{BackendArg, Globals, TargetsMissed};

/// `inimtrace assess`; returns whether it printed its own total time.
#[allow(clippy::too_many_arguments)] // the command's flags, as clap parsed them
pub(crate) fn assess(
    g: &Globals,
    experiment: Option<PathBuf>,
    out: Option<PathBuf>,
    scene: Option<PathBuf>,
    force: bool,
    strict: bool,
    keep_replicates: bool,
    backend: BackendArg,
) -> Result<bool> {
    let (set, quiet) = (&g.set[..], g.quiet);
    let mut printed_total = false;
    let backend = backend.choice()?;
    let exp = load_experiment(experiment.as_deref(), scene.as_deref(), set)?;
    for w in exp.plausibility_warnings() {
        eprintln!("warning: {w}");
    }
    announce(&exp.scene, backend, quiet);
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&exp.name));
    if !quiet {
        eprintln!("{}", exp.display.summary());
        if let Some(p) = &exp.auto_pupil {
            eprintln!("{}", p.text());
        }
    }
    if keep_replicates && exp.measurement.estimator != inimtrace::measure::spec::EstimatorKind::Converged {
        eprintln!(
            "warning: --keep-replicates has nothing to keep: {} uses the grid estimator, which has no replicates \
             (measurement.estimator = \"converged\" has)",
            exp.source
        );
    }
    let options = RunOptions { quiet, backend, exr_compression: g.exr_compression, force, keep_replicates };
    let report = experiment::assess(&exp, &out, options)?;
    for w in experiment::sampling_cost_warnings(&report, &exp) {
        eprintln!("warning: {w}");
    }
    out!("{}", experiment::table_markdown(&report, &exp));
    if g.timings {
        printed_total = true;
        for s in &report.stages {
            let what = [s.method.as_deref(), s.eye_case.as_deref()].into_iter().flatten().collect::<Vec<_>>().join(" ");
            eprintln!("{:>8.3} s  {} {}", s.seconds, s.stage, what);
        }
        eprintln!("{:>8.3} s  total ({} threads, backend {})", report.total_seconds, report.threads, report.backend);
    }
    if !quiet {
        eprintln!("wrote {}", out.display());
    }
    let missed = report.scores.iter().filter(|s| s.target_met == Some(false)).count();
    if missed > 0 {
        eprintln!(
            "warning: {} of {} missed their precision target (PSNR ± {} dB, SSIM ± {}): marked * in {}, \
             target_met = false in {}; the budget (measurement.max_seconds, measurement.max_samples_per_pixel) ran out \
             first",
            missed,
            inimtrace::count::count(report.scores.len(), "score"),
            exp.measurement.psnr_ci95_db,
            exp.measurement.ssim_ci95,
            out.join("table.md").display(),
            out.join("results.json").display()
        );
        if strict {
            return Err(TargetsMissed(missed).into());
        }
    }
    Ok(printed_total)
}
