//! Collecting a sweep: the records of its points (Table 1's scores, Sec. 4.2, per point) into
//! `sweep.csv` (one row per point x eye case x method, with the perceptual scores the
//! experiment names and their intervals), `sweep.json` (the resolved base, the
//! axes, every point with its id, values and whether it is complete) and plots of each score
//! against each numeric axis. Collecting reads only complete records, so it can run at any
//! time, also while points are still running; it names the points still missing.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde_json::json;

use super::plots::{write_plots, PlotRow};
use super::spec::Point;
use super::store::{PointRecord, RecordState, ScoreRow, Store};
use super::PointSpec;
use super::Sweep;
use crate::error::{Error, Result};
use crate::io::csv_table::CsvTable;
use crate::io::output::write_atomic;
use crate::overrides::value_text;
use crate::perception::replicated::ScalarEstimate;
use crate::perception::ScoreName;

/// What a collection found and wrote.
#[derive(Clone, Debug, Default)]
pub struct Collected {
    /// Points with a record.
    pub complete: usize,
    /// Indices of the points without a complete record (missing or invalid).
    pub missing: Vec<usize>,
    /// The points whose record is there but cannot count, and why (also in `missing`).
    pub invalid: Vec<(usize, String)>,
    /// Rows of `sweep.csv`.
    pub rows: usize,
    /// `sweep.csv`, written.
    pub csv: PathBuf,
    /// `sweep.json`, written.
    pub json: PathBuf,
    /// The plots written.
    pub plots: Vec<PathBuf>,
    /// Rows of `sweep.csv` whose 95% intervals are wider than the measurement's targets
    /// (`target_met` false).
    pub missed_rows: usize,
    /// The points with such a row.
    pub missed_points: Vec<usize>,
}

/// Writes `sweep.csv`, `sweep.json` and the plots into the sweep's folder from the records
/// there. `resolved` are the sweep's points, resolved (see [`Sweep::resolve`]).
pub fn collect(sweep: &Sweep, resolved: &[PointSpec], store: &Store) -> Result<Collected> {
    let states: Vec<RecordState> = resolved.iter().map(|r| store.state(r)).collect();
    let mut invalid = Vec::new();
    for (p, st) in sweep.points.iter().zip(&states) {
        if let RecordState::Invalid(why) = st {
            invalid.push((p.index, why.clone()));
        }
    }
    let records: Vec<Option<PointRecord>> = states
        .into_iter()
        .map(|st| match st {
            RecordState::Complete(rec) => Some(rec),
            _ => None,
        })
        .collect();
    let keys = sweep.spec.keys();
    let mut out = Collected {
        csv: store.root().join("sweep.csv"),
        json: store.root().join("sweep.json"),
        invalid,
        ..Default::default()
    };
    let (csv, plot_rows) = if sweep.study().is_some() {
        study_csv(sweep, resolved, &records, &keys, &mut out)
    } else {
        sweep_csv(sweep, resolved, &records, &keys, &mut out)
    };
    write_text(&out.csv, &csv)?;
    let text = sweep_json(sweep, resolved, &records, &out)?;
    write_text(&out.json, &text)?;

    let axes: Vec<usize> =
        sweep.spec.axes.iter().enumerate().flat_map(|(a, axis)| axis.keys.iter().map(move |_| a)).collect();
    out.plots = write_plots(&store.root().join("plots"), &keys, &axes, &plot_rows)?;
    // The page, from the files just written.
    crate::report::write(store.root())?;
    Ok(out)
}

/// The extra scores (`[measurement] scores` beyond PSNR and SSIM) of any complete record, in
/// report order: each gets `sweep.csv`'s columns value, `_ci95`, `_noise_bias` and
/// `_bias_above_ci95`, as `results.csv` has them.
fn extra_scores(records: &[Option<PointRecord>]) -> Vec<ScoreName> {
    let names: BTreeSet<ScoreName> =
        records.iter().flatten().flat_map(|r| r.scores.iter()).flat_map(|s| s.perceptual.keys().copied()).collect();
    names.into_iter().collect()
}

/// `sweep.csv` and the plots' rows; counts the rows and the points complete, missing and
/// missing their targets into `out`.
fn sweep_csv(
    sweep: &Sweep,
    resolved: &[PointSpec],
    records: &[Option<PointRecord>],
    keys: &[String],
    out: &mut Collected,
) -> (String, Vec<PlotRow>) {
    let mut csv = CsvTable::new();
    let extra = extra_scores(records);
    // The precision of each row (empty under the grid estimator, which has no interval and no
    // target), then the point's time last.
    let extra_header: Vec<String> = extra
        .iter()
        .flat_map(|n| {
            [n.name().to_string(), format!("{n}_ci95"), format!("{n}_noise_bias"), format!("{n}_bias_above_ci95")]
        })
        .collect();
    let scores = ["method", "eye_case", "psnr_db", "psnr_ci95_db", "ssim", "ssim_ci95"];
    let precision = ["samples_per_pixel", "replicates", "target_met", "seconds"];
    csv.row(
        ["point", "id"]
            .into_iter()
            .chain(keys.iter().map(|k| k.as_str()))
            .chain(scores)
            .chain(extra_header.iter().map(String::as_str))
            .chain(precision),
    );
    let mut plot_rows = Vec::new();
    for ((point, r), rec) in sweep.points.iter().zip(resolved).zip(records) {
        let Some(rec) = rec else {
            out.missing.push(point.index);
            continue;
        };
        out.complete += 1;
        let (values, xs) = point_values(point);
        for s in &rec.scores {
            let row = [point.index.to_string(), r.id().to_string()]
                .into_iter()
                .chain(values.iter().cloned())
                .chain([
                    s.method.clone(),
                    s.eye_case.clone(),
                    number_text(s.psnr_db),
                    s.psnr_ci95_db.map(number_text).unwrap_or_default(),
                    number_text(s.ssim),
                    s.ssim_ci95.map(number_text).unwrap_or_default(),
                ])
                .chain(extra_cells(s, &extra))
                .chain([
                    s.samples_per_pixel.map(|n| n.to_string()).unwrap_or_default(),
                    s.replicates.map(|n| n.to_string()).unwrap_or_default(),
                    s.target_met.map(|m| m.to_string()).unwrap_or_default(),
                    rec.seconds.to_string(),
                ]);
            csv.row(row);
            out.rows += 1;
            if s.missed() {
                out.missed_rows += 1;
                if out.missed_points.last() != Some(&point.index) {
                    out.missed_points.push(point.index);
                }
            }
            plot_rows.push(PlotRow::of_score(xs.clone(), s));
        }
    }
    (csv.finish(), plot_rows)
}

/// `sweep.csv` of a study's sweep and the plots' rows: one row per point, source and content
/// depth, the MTF50 with the eye on the content and its 95% half-width as the study's
/// `mtf50.csv` writes them (empty where the MTF stays above 0.5 up to the retina's Nyquist
/// frequency); counts the points complete and missing into `out`.
fn study_csv(
    sweep: &Sweep,
    resolved: &[PointSpec],
    records: &[Option<PointRecord>],
    keys: &[String],
    out: &mut Collected,
) -> (String, Vec<PlotRow>) {
    let mut csv = CsvTable::new();
    let columns =
        ["source", "content_diopters", "mtf50_cpd", "mtf50_ci95", "samples_per_pixel", "replicates", "seconds"];
    csv.row(["point", "id"].into_iter().chain(keys.iter().map(|k| k.as_str())).chain(columns));
    let mut plot_rows = Vec::new();
    let n = super::study::number;
    for ((point, r), rec) in sweep.points.iter().zip(resolved).zip(records) {
        let Some(rec) = rec else {
            out.missing.push(point.index);
            continue;
        };
        out.complete += 1;
        let (values, xs) = point_values(point);
        for m in &rec.mtf50 {
            csv.row([point.index.to_string(), r.id().to_string()].into_iter().chain(values.iter().cloned()).chain([
                m.source.clone(),
                n(m.content_diopters),
                n(m.mtf50_cpd),
                n(m.mtf50_ci95),
                m.samples_per_pixel.to_string(),
                m.replicates.to_string(),
                rec.seconds.to_string(),
            ]));
            out.rows += 1;
            plot_rows.push(PlotRow::of_mtf50(xs.clone(), m));
        }
    }
    (csv.finish(), plot_rows)
}

/// A point's swept values as `sweep.csv`'s cells (strings as they are) and as the plots' numbers
/// (none where a value is not a number).
fn point_values(point: &Point) -> (Vec<String>, Vec<Option<f64>>) {
    let cells = point
        .values
        .iter()
        .map(|(_, v)| match v {
            toml::Value::String(s) => s.clone(),
            other => value_text(other),
        })
        .collect();
    (cells, point.values.iter().map(|(_, v)| number(v)).collect())
}

/// The extra scores' cells of one row: value, half-width, removed noise bias and whether it
/// exceeds the half-width, per score of `extra` (empty where not measured or not given).
fn extra_cells(s: &ScoreRow, extra: &[ScoreName]) -> Vec<String> {
    let cells =
        |n: &ScoreName| ScalarEstimate::csv_cells(s.perceptual.get(n).map(|e| e.estimate()).as_ref(), number_text);
    extra.iter().flat_map(cells).collect()
}

/// `sweep.json`: the sweep, its resolved base, its axes and every point with its scores.
fn sweep_json(
    sweep: &Sweep,
    resolved: &[PointSpec],
    records: &[Option<PointRecord>],
    out: &Collected,
) -> Result<String> {
    let base = sweep.resolve_base()?;
    let (base_document, base_id) = match &base {
        PointSpec::Experiment(r) => (serde_json::to_value(&r.document).unwrap_or_default(), r.id.clone()),
        PointSpec::Study(s) => (serde_json::to_value(&s.study).unwrap_or_default(), s.id.clone()),
    };
    let args = if sweep.study().is_some() { "resolution_args" } else { "assess_args" };
    let points: Vec<serde_json::Value> = sweep
        .points
        .iter()
        .zip(resolved)
        .zip(records)
        .map(|((p, r), rec)| {
            let values: serde_json::Map<String, serde_json::Value> = p
                .values
                .iter()
                .map(|(k, v)| (k.clone(), serde_json::to_value(v).unwrap_or(serde_json::Value::Null)))
                .collect();
            let mut point = json!({
                "index": p.index,
                "id": r.id(),
                "values": values,
                "complete": rec.is_some(),
            });
            point[args] = json!(sweep.assess_args(p));
            // Only for a record that cannot count, so sweeps without one are written as before.
            if let Some((_, why)) = out.invalid.iter().find(|(i, _)| *i == p.index) {
                point["invalid_record"] = json!(why);
            }
            // Every score row of the point with its precision, as in its record and sweep.csv.
            if let Some(rec) = rec.as_ref().filter(|_| sweep.study().is_some()) {
                point["mtf50"] = serde_json::to_value(&rec.mtf50).unwrap_or_default();
            } else if let Some(rec) = rec {
                point["scores"] = serde_json::to_value(&rec.scores).unwrap_or_default();
                point["targets_missed"] = json!(rec.scores.iter().filter(|s| s.missed()).count());
            }
            point
        })
        .collect();
    let axes: Vec<serde_json::Value> = sweep
        .spec
        .axes
        .iter()
        .map(|a| {
            json!(a
                .keys
                .iter()
                .map(|k| json!({ "key": k.key, "values": serde_json::to_value(&k.values).unwrap_or_default() }))
                .collect::<Vec<_>>())
        })
        .collect();
    let doc = json!({
        "version": env!("CARGO_PKG_VERSION"),
        "sweep": sweep.spec.path.display().to_string(),
        "name": sweep.spec.name,
        "description": sweep.spec.description,
        "experiment": sweep.spec.experiment,
        "experiment_file": if sweep.spec.experiment == "builtin:paper" {
            sweep.spec.experiment.clone()
        } else {
            sweep.spec.base().join(&sweep.spec.experiment).display().to_string()
        },
        "set": sweep.spec.set.iter().chain(&sweep.overrides).map(|o| o.to_arg()).collect::<Vec<_>>(),
        "base": base_document,
        "base_id": base_id,
        "axes": axes,
        "point_count": sweep.points.len(),
        "complete": out.complete,
        "missing": out.missing,
        "rows_missing_target": out.missed_rows,
        "points_missing_target": out.missed_points,
        "points": points,
    });
    let mut doc = doc;
    if let Some((study, file)) = sweep.study() {
        doc["experiment"] = serde_json::Value::Null;
        doc["experiment_file"] = serde_json::Value::Null;
        doc["study"] = json!(study);
        doc["study_file"] = json!(file);
    }
    serde_json::to_string_pretty(&doc).map_err(|e| Error::serialize("serialise sweep.json", e))
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |tmp| std::fs::write(tmp, text).map_err(|e| Error::io(tmp, e)))
}

/// A number in CSV: shortest round-trip form, `inf` for an infinite PSNR.
fn number_text(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else if v > 0.0 {
        "inf".into()
    } else if v < 0.0 {
        "-inf".into()
    } else {
        "nan".into()
    }
}

/// An axis value as a number, if it is one.
fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_as_in_json() {
        assert_eq!(number_text(f64::INFINITY), "inf");
        assert_eq!(number_text(2.5), "2.5");
    }
}
