//! Sweeps of a resolution study (the paper's abstract: "perceived spatial resolution at
//! different focused depths", over ranges of its settings): a sweep file naming `study` instead
//! of `experiment`. Each point is the study with the point's settings (`--set` keys of the study
//! file), run as `inimtrace resolution` runs it ([`run_study`]), identified by the content hash
//! of its resolved settings and recorded as every sweep point is (`points/<id>.json`): its rows are
//! each source's slanted-edge MTF50 (cycles per degree, with its 95% half-width) with the eye on
//! the content, per content depth, exactly the rows of the study's `mtf50.csv` with
//! `target_diopters = focus_diopters`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::store::{exact, host_name, unix_now, PointRecord, RECORD_FORMAT};
use crate::error::{Error, Result};
use crate::io::text::{base_dir, read_text};
use crate::overrides::Override;
use crate::resolution::run::{run_study, StudySetup};
use crate::resolution::study::{Study, PAPER_STUDY};
use crate::settings::hash_json;

/// One MTF50 row of a study point: a source (the ground truth or a method) at a content depth,
/// the eye focused on the content. Numbers are stored as [`super::store::ScoreRow`]'s are: exact
/// decimal text; `NaN` where the MTF stays above 0.5 up to the retina's Nyquist frequency.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mtf50Row {
    /// `ground_truth` or the method's short name.
    pub source: String,
    /// The content depth (and the eye's focus), dioptres.
    #[serde(with = "exact")]
    pub content_diopters: f64,
    /// MTF50 of the slanted edge, cycles per degree.
    #[serde(with = "exact")]
    pub mtf50_cpd: f64,
    /// Its 95% half-width (the jackknife over the replicates).
    #[serde(with = "exact")]
    pub mtf50_ci95: f64,
    /// Samples per retina pixel over all replicates.
    pub samples_per_pixel: u64,
    /// Independent replicates.
    pub replicates: usize,
}

/// The study a sweep's points change: its text, where it came from, the folder its paths resolve
/// against.
#[derive(Clone, Debug)]
pub struct StudyBase {
    text: String,
    /// The study as the sweep file names it.
    pub reference: String,
    /// Its file (or `builtin:paper (studies/paper.toml)`).
    pub source: String,
    dir: PathBuf,
}

/// A study point: the study with the point's settings, resolved, and its id.
#[derive(Clone, Debug)]
pub struct StudyPoint {
    /// The resolved study.
    pub study: Study,
    /// Content hash of its settings (name, description and the file's place left out; the
    /// display inline).
    pub id: String,
}

impl StudyBase {
    /// The study `reference` (relative to `sweep_dir`, or `builtin:paper`); errors name `sweep`
    /// and its field `study`.
    pub fn load(reference: &str, sweep_dir: &Path, sweep: &str) -> Result<Self> {
        if reference == "builtin:paper" {
            return Ok(Self {
                text: PAPER_STUDY.to_string(),
                reference: reference.into(),
                source: "builtin:paper (studies/paper.toml)".into(),
                dir: PathBuf::from("."),
            });
        }
        let path = sweep_dir.join(reference);
        let text = read_text(&path).map_err(|e| Error::load(sweep, "study", reference, e))?;
        Ok(Self { text, reference: reference.into(), source: path.display().to_string(), dir: base_dir(&path) })
    }

    /// The study with `overrides` applied, resolved; `label` names it in errors (a point:
    /// `sweeps/x.toml point 3`).
    pub fn resolve(&self, overrides: &[Override], label: Option<&str>) -> Result<StudyPoint> {
        let source = match label {
            Some(l) => format!("{} at {l}", self.source),
            None => self.source.clone(),
        };
        let study = Study::from_text(&self.text, &source, &self.dir, overrides)?;
        let id = study_id(&study)?;
        Ok(StudyPoint { study, id })
    }
}

/// The content hash of a resolved study: its `study.json` settings without its name, description
/// and file, and its display inline.
fn study_id(study: &Study) -> Result<String> {
    let mut v = serde_json::to_value(study).map_err(|e| Error::serialize("hash settings", e))?;
    if let Some(m) = v.as_object_mut() {
        for k in ["name", "description", "source", "display_source"] {
            m.remove(k);
        }
    }
    hash_json(&(v, crate::io::display_file::DisplaySpec::from_display(&study.display)))
}

/// The rays a study point traces (its cost, for Slurm's balance and the long-run note).
pub fn point_rays(p: &StudyPoint) -> Result<u64> {
    Ok(StudySetup::new(&p.study)?.rays(&p.study))
}

/// Checks a study point before anything runs: its setup (optics, crop) and its memory estimate.
pub fn check_point(p: &StudyPoint) -> Result<u64> {
    let setup = StudySetup::new(&p.study)?;
    setup.memory(&p.study).check_memory(&crate::budget::memory_budget(), &p.study.source)?;
    Ok(setup.rays(&p.study))
}

/// Runs study point `p` (point `index` with the swept `values`) and returns its record.
pub fn run_point(p: &StudyPoint, index: usize, values: &[String]) -> Result<PointRecord> {
    let t = Instant::now();
    let r = run_study(&p.study, true)?;
    let s = &r.study;
    let spp = crate::resolution::report::samples_per_pixel(s);
    let mut rows = Vec::new();
    for (k, source) in r.sources.iter().enumerate() {
        for (di, d) in s.depths.iter().enumerate() {
            let fi = s.focus_index(d.diopters).expect("content depths are measured focuses");
            let v = r.mtf50[k][di][fi];
            rows.push(Mtf50Row {
                source: source.clone(),
                content_diopters: d.diopters,
                mtf50_cpd: v.value,
                mtf50_ci95: v.ci95,
                samples_per_pixel: spp,
                replicates: s.measurement.replicates,
            });
        }
    }
    Ok(PointRecord {
        format: RECORD_FORMAT,
        id: p.id.clone(),
        index,
        values: values.to_vec(),
        scores: Vec::new(),
        mtf50: rows,
        seconds: t.elapsed().as_secs_f64(),
        backend: "chart".into(),
        threads: rayon::current_num_threads(),
        host: host_name(),
        finished_unix: unix_now(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        provenance: None,
    })
}

/// Why `rec` cannot be the complete record of study point `p`, if it cannot: a score row of an
/// experiment, a source or depth the study does not measure, one missing or twice, a number
/// that is not one the study can give.
pub fn record_problem(rec: &PointRecord, p: &StudyPoint) -> Option<String> {
    if !rec.scores.is_empty() {
        return Some("it holds an experiment's scores, not a study's MTF50 rows".into());
    }
    let sources = crate::resolution::run::source_names(&p.study);
    for row in &rec.mtf50 {
        if !sources.contains(&row.source) {
            return Some(format!("an MTF50 of `{}`, which the study does not measure", row.source.escape_debug()));
        }
        let ok = |v: f64| v.is_nan() || (v.is_finite() && v >= 0.0);
        if !(ok(row.mtf50_cpd) && ok(row.mtf50_ci95)) {
            return Some(format!("the MTF50 of {} is not valid ({} cpd)", row.source, row.mtf50_cpd));
        }
    }
    for s in &sources {
        for d in &p.study.depths {
            let n = rec.mtf50.iter().filter(|r| r.source == *s && r.content_diopters == d.diopters).count();
            if n != 1 {
                return Some(format!("{} of {s} at {} D, not one", crate::count::count(n, "MTF50"), d.diopters));
            }
        }
    }
    None
}

/// A number as the study's CSV files write it: shortest round-trip form, empty when not a
/// number.
pub fn number(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}
