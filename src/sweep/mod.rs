//! Parameter sweeps: the paper's assessment (Sec. 4, Table 1) over ranges of its settings
//! (pupil, focus, eye position, lenslet pitch, gap, methods, ...). A sweep file names a base
//! experiment and axes of `--set` overrides (`spec`); each point is a fully resolved
//! experiment identified by the content hash of its settings ([`crate::settings`]). A sweep may
//! name a resolution study instead ([`study`]): each point is then the study with its settings,
//! recorded with each source's MTF50. Points run
//! on all cores sharing display images (`run`) or as a Slurm job array (`slurm`), are
//! recorded atomically one by one (`store`), and are collected into `sweep.csv`,
//! `sweep.json` and plots ([`collect`], `plots`). A rerun skips recorded points.

mod collect;
mod command;
mod plots;
mod run;
mod slurm;
mod spec;
mod store;
pub mod study;
pub mod units;

pub use collect::{collect, Collected};
pub use command::{check, execute, SweepCommand, SweepOutput};
pub use run::{point_costs, run_points, validate, LocalOptions, RunSummary, SweepInputs};
pub use slurm::{submit, wait_for, SlurmOptions, Submission};
pub use spec::{format_selection, parse_selection, Axis, AxisKey, Point, SweepSpec};
pub use store::{PointRecord, RecordState, ScoreRow, Store, RECORD_FORMAT};
pub use study::Mtf50Row;

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::experiment::ExperimentSpec;
use crate::overrides::{value_text, Override};
use crate::settings::{hash_json, Resolved, Settings};

/// Bytes a resolved point takes in memory (its settings document as a tree, the typed specs,
/// the expanded point) for each byte of its settings as JSON: measured at about 21 for the
/// paper's experiment (30 KB a point from 1.4 KB of JSON), rounded up.
const RESOLVED_BYTES_PER_DOCUMENT_BYTE: u64 = 24;

/// A loaded sweep: its file, the base settings (base experiment, `[set]`, then the command
/// line's `--set`), its points and where it writes.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The sweep file, parsed.
    pub spec: SweepSpec,
    /// Every point of the expansion, in order.
    pub points: Vec<Point>,
    /// The output folder.
    pub out: PathBuf,
    /// `--set` overrides from the command line.
    pub overrides: Vec<Override>,
    base: Base,
}

/// What a sweep's points change: an experiment's settings, or a resolution study.
#[derive(Clone, Debug)]
enum Base {
    Experiment(Settings),
    /// The study with the file's `[set]` and the command line's `--set`, in order.
    Study(study::StudyBase, Vec<Override>),
}

/// A point's settings, resolved: an experiment's, or a resolution study's.
#[derive(Clone, Debug)]
pub enum PointSpec {
    /// A point of a sweep of an experiment.
    Experiment(Box<Resolved>),
    /// A point of a sweep of a study.
    Study(Box<study::StudyPoint>),
}

impl PointSpec {
    /// The content hash of the point's settings: its record's name.
    pub fn id(&self) -> &str {
        match self {
            PointSpec::Experiment(r) => &r.id,
            PointSpec::Study(s) => &s.id,
        }
    }

    /// The experiment's settings of an experiment's point.
    pub fn resolved(&self) -> Option<&Resolved> {
        match self {
            PointSpec::Experiment(r) => Some(r),
            PointSpec::Study(_) => None,
        }
    }

    /// The experiment of an experiment's point, built ([`Resolved::experiment`]); a study's
    /// point has none.
    pub fn experiment(&self) -> Result<crate::experiment::Experiment> {
        match self {
            PointSpec::Experiment(r) => r.experiment(),
            PointSpec::Study(s) => {
                Err(Error::Mismatch(format!("the point of study {} is not an experiment", s.study.source)))
            }
        }
    }
}

impl Sweep {
    /// Loads `path`; `overrides` apply to the base after the file's `[set]`; `out` defaults
    /// to `out/<name>`.
    pub fn load(path: &Path, overrides: &[Override], out: Option<&Path>) -> Result<Self> {
        let spec = SweepSpec::load(path)?;
        let src = path.display().to_string();
        let set: Vec<Override> = spec.set.iter().map(|o| o.clone().from_origin(format!("{src} [set]"))).collect();
        let out = out.map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("out").join(&spec.name));
        if let Some(reference) = &spec.study {
            let base = study::StudyBase::load(reference, &spec.base(), &src)?;
            let all: Vec<Override> = set.iter().chain(overrides).cloned().collect();
            // The base study, checked before any point is made.
            base.resolve(&all, None)?;
            let base = Base::Study(base, all);
            let mut sweep = Self { points: Vec::new(), spec, out, overrides: overrides.to_vec(), base };
            sweep.points = sweep.spec.points();
            return Ok(sweep);
        }
        let base = if spec.experiment == "builtin:paper" {
            Settings::builtin(&ExperimentSpec::paper(), "built-in paper experiment", &spec.base())?
        } else {
            let file = spec.base().join(&spec.experiment);
            Settings::experiment_file(&file).map_err(|e| Error::load(&src, "experiment", &spec.experiment, e))?
        };
        let base = Base::Experiment(base.with_overrides(&set).with_overrides(overrides));
        let mut sweep = Self { points: Vec::new(), spec, out, overrides: overrides.to_vec(), base };
        sweep.check_memory()?;
        sweep.points = sweep.spec.points();
        Ok(sweep)
    }

    /// Refuses a sweep whose points, expanded and resolved (every command resolves them all
    /// before it starts), would not fit in the memory budget: point 0 is resolved alone and its
    /// size, times the number of points, is checked before any other point is made.
    fn check_memory(&self) -> Result<()> {
        let n = self.spec.point_count();
        let Base::Experiment(base) = &self.base else { return Ok(()) };
        if n == 0 {
            return Ok(());
        }
        let first = self.point_settings(base, &self.spec.point(0)).resolve()?;
        let text = serde_json::to_vec(&first.document).map(|v| v.len() as u64).unwrap_or(0);
        let mut estimate = crate::budget::Estimate::default();
        estimate.add(
            format!("the {n} points' settings, resolved"),
            "axes",
            n as u64,
            RESOLVED_BYTES_PER_DOCUMENT_BYTE.saturating_mul(text),
        );
        estimate.check_memory(&crate::budget::memory_budget(), &self.spec.path.display().to_string())
    }

    /// The point's values as overrides, named by the sweep file's axes.
    fn point_values(&self, p: &Point) -> Vec<Override> {
        let origin = format!("{} axes", self.spec.path.display());
        self.spec.point_overrides(p).into_iter().map(|o| o.from_origin(origin.clone())).collect()
    }

    /// The settings of point `p` of an experiment's sweep: the base, then the point's values.
    fn point_settings(&self, base: &Settings, p: &Point) -> Settings {
        base.clone().with_overrides(&self.point_values(p)).labelled(format!(
            "{} point {}",
            self.spec.path.display(),
            p.index
        ))
    }

    /// Point `p`, resolved (deserialized and hashed; not yet built).
    fn resolve_point(&self, p: &Point) -> Result<PointSpec> {
        match &self.base {
            Base::Experiment(base) => Ok(PointSpec::Experiment(Box::new(self.point_settings(base, p).resolve()?))),
            Base::Study(base, set) => {
                let all: Vec<Override> = set.iter().cloned().chain(self.point_values(p)).collect();
                let label = format!("{} point {}", self.spec.path.display(), p.index);
                Ok(PointSpec::Study(Box::new(base.resolve(&all, Some(&label))?)))
            }
        }
    }

    /// Every point's resolved settings (deserialized and hashed; not yet built).
    pub fn resolve(&self) -> Result<Vec<PointSpec>> {
        self.points.iter().map(|p| self.resolve_point(p)).collect()
    }

    /// The base settings (before the axes), resolved.
    pub fn resolve_base(&self) -> Result<PointSpec> {
        match &self.base {
            Base::Experiment(base) => Ok(PointSpec::Experiment(Box::new(base.resolve()?))),
            Base::Study(base, set) => Ok(PointSpec::Study(Box::new(base.resolve(set, None)?))),
        }
    }

    /// The base study as the sweep file names it and its file, for a sweep of a study.
    pub fn study(&self) -> Option<(&str, &str)> {
        match &self.base {
            Base::Study(b, _) => Some((&b.reference, &b.source)),
            Base::Experiment(_) => None,
        }
    }

    /// Identifies the sweep's set of points: the hash of every point's id in order. A Slurm
    /// task checks it, so that a sweep file edited after submission is not run half old, half new.
    pub fn id(resolved: &[PointSpec]) -> Result<String> {
        hash_json(&resolved.iter().map(|r| r.id()).collect::<Vec<_>>())
    }

    /// Each point's values as `KEY=VALUE` texts.
    pub fn value_texts(&self) -> Vec<Vec<String>> {
        self.points.iter().map(|p| p.values.iter().map(|(k, v)| format!("{k}={}", value_text(v))).collect()).collect()
    }

    /// The `--set` arguments that make `inimtrace assess <base experiment>` (or `inimtrace
    /// resolution <base study>`) run point `p` by hand: the file's `[set]`, the command line's,
    /// then the point's values.
    pub fn assess_args(&self, p: &Point) -> Vec<String> {
        let mut args = Vec::new();
        for o in self.spec.set.iter().chain(&self.overrides).chain(&self.spec.point_overrides(p)) {
            args.push("--set".to_string());
            args.push(o.to_arg());
        }
        args
    }
}
