//! The outputs of an assessment as data and text: the scores of Table 1 (Sec. 4.2), the stage
//! timings, and their Markdown table, CSV and JSON reports.

use serde::Serialize;

use super::{Experiment, ExperimentSpec};
use crate::error::{Error, Result};
use crate::io::csv_table::CsvTable;
use crate::io::output::OutputDir;
use crate::measure::spec::EstimatorKind;
use crate::measure::stats::Estimate;
use crate::metrics::SsimConstants;
use crate::perception::PerceptualScores;
use crate::version::Tool;

/// One score: a method under an eye case. The converged estimator adds the 95% half-widths
/// (`ci95`, `channels_ci95` in `psnr` and `ssim`), its samples and whether the targets were met.
#[derive(Clone, Debug, Serialize)]
pub struct Score {
    /// The method's short name (LC, PC, LA, `LA<k>`).
    pub method: String,
    /// The eye case's name.
    pub eye_case: String,
    /// PSNR of the perceived image against the ground truth, dB.
    pub psnr: Estimate,
    /// SSIM of the perceived image against the ground truth.
    pub ssim: Estimate,
    /// Samples per retina pixel, over all replicates (converged estimator).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples_per_pixel: Option<u64>,
    /// Replicates of the converged estimator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replicates: Option<usize>,
    /// Both 95% half-widths within the experiment's targets.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_met: Option<bool>,
    /// The scores `[measurement] scores` names beyond PSNR and SSIM (luminance PSNR,
    /// ColorVideoVDP, FLIP), with their intervals and noise bias under the converged estimator.
    #[serde(skip_serializing_if = "PerceptualScores::is_empty")]
    pub perceptual: PerceptualScores,
}

/// The eye of one eye case beyond the thin lens (`results.json`'s `eyes`).
#[derive(Clone, Debug, Serialize)]
pub struct EyeReport {
    /// The eye case's name.
    pub eye_case: String,
    /// The model's name (`thin-lens`, `navarro-1985`, ...).
    pub model: String,
    /// Where its parameters come from.
    pub citation: String,
    /// The model's accommodation parameter solved from the case's focus, D.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accommodation_d: Option<f64>,
    /// The criterion it was solved by (`paraxial`, `min-rms-spot`).
    pub focus_criterion: String,
    /// The reference wavelength of the focus and the retina's map, nm.
    pub reference_wavelength_nm: f64,
    /// The entrance pupil's diameter (`pupil_diameter`), mm.
    pub entrance_pupil_mm: f64,
    /// The iris diameter that gives it, mm.
    pub iris_mm: f64,
    /// `single` or `primaries`.
    pub spectrum: String,
    /// The Stiles-Crawford rho, 1/mm^2, if applied.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiles_crawford_rho: Option<f64>,
}

impl EyeReport {
    /// The reports of every case of `exp` with an eye beyond the thin lens's fast paths.
    pub fn of(exp: &Experiment) -> Vec<EyeReport> {
        exp.cases
            .iter()
            .filter_map(|c| {
                let o = c.eye.optics.as_ref()?;
                Some(EyeReport {
                    eye_case: c.name.clone(),
                    model: o.model.name().to_string(),
                    citation: o.model.citation().to_string(),
                    accommodation_d: o.accommodation,
                    focus_criterion: crate::optics::eye::rays::criterion_name(o.criterion).to_string(),
                    reference_wavelength_nm: o.reference_nm,
                    entrance_pupil_mm: o.pupil_diameter,
                    iris_mm: o.iris_diameter,
                    spectrum: if o.is_single_wavelength() { "single" } else { "primaries" }.to_string(),
                    stiles_crawford_rho: o.stiles_crawford.map(|s| s.rho),
                })
            })
            .collect()
    }
}

/// Wall time of one stage.
#[derive(Clone, Debug, Serialize)]
pub struct StageTime {
    /// The stage ("display image", "ground truth", "perceived", "score", ...).
    pub stage: String,
    /// The method it ran for, if one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// The eye case it ran for, if one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eye_case: Option<String>,
    /// Wall time, s.
    pub seconds: f64,
}

/// What `assess` produced.
#[derive(Clone, Debug, Serialize)]
pub struct AssessReport {
    /// The inimtrace that wrote the report: version and git revision.
    pub tool: Tool,
    /// The experiment's name.
    pub experiment: String,
    /// The SSIM constants' name ("wang2004", "framework-8bit").
    pub ssim_constants: String,
    /// The intersection backend that ran.
    pub backend: String,
    /// Rayon worker threads.
    pub threads: usize,
    /// The display's parameters as fields (lengths in mm), its lenslets, the diffraction at its
    /// apertures and its photometry.
    pub display: super::simulated::DisplayReport,
    /// The display's central depth plane, mm from the pupil (`None`: at infinity or real).
    pub central_depth_plane_mm: Option<f64>,
    /// The eye of every case that is not the paper's thin lens (a schematic eye, the primaries'
    /// wavelengths, Stiles-Crawford): its model and solved accommodation. Absent for thin lenses.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub eyes: Vec<EyeReport>,
    /// How `eye.pupil_diameter = "auto"` chose the pupil: the adapting luminance and field, the
    /// observer and the diameter. Absent for a stated diameter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pupil: Option<crate::optics::eye::pupil::AutoPupil>,
    /// What was simulated, in words: eye model, spectrum, diffraction, lenslets (the table's
    /// title and caption and the figure's title say the same).
    pub simulated: super::simulated::Simulated,
    /// Table 1: every method under every eye case.
    pub scores: Vec<Score>,
    /// Wall time of every stage.
    pub stages: Vec<StageTime>,
    /// Wall time of the run, s.
    pub total_seconds: f64,
    /// The experiment's settings as resolved.
    pub settings: ExperimentSpec,
    /// OPT's convergence record, when OPT is among the methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimization: Option<crate::optimize::OptimizationReport>,
    /// Where the results come from: the scene's name and path as given, every file read with its
    /// SHA-256, the `--set` overrides, the budgets and the seed.
    pub provenance: crate::provenance::Provenance,
}

/// Table 1 as Markdown: rows are eye cases, columns PSNR per method | SSIM per method.
pub fn table_markdown(report: &AssessReport, exp: &Experiment) -> String {
    let methods: Vec<String> = exp.methods.iter().map(|m| m.name()).collect();
    let mut s = format!(
        "# {} ({}): PSNR (dB) and SSIM ({}) of the perceived retinal image against the ground truth\n\n{}\n\n",
        report.experiment,
        report.simulated.title_part(),
        report.ssim_constants,
        report.simulated.sentence()
    );
    s.push_str("| Eye |");
    for m in &methods {
        s.push_str(&format!(" PSNR {m} |"));
    }
    for m in &methods {
        s.push_str(&format!(" SSIM {m} |"));
    }
    s.push_str("\n|---|");
    s.push_str(&"---:|".repeat(2 * methods.len()));
    s.push('\n');
    for case in &exp.cases {
        match &exp.optimize {
            Some(opt) => {
                s.push_str(&format!("| {} ({}) |", case.name, crate::optimize::report::case_role(opt, &case.name)))
            }
            None => s.push_str(&format!("| {} |", case.name)),
        }
        let find = |m: &str| report.scores.iter().find(|x| x.method == m && x.eye_case == case.name);
        for m in &methods {
            let v = find(m).map(crate::experiment::converged_report::psnr_cell).unwrap_or_default();
            s.push_str(&format!(" {v} |"));
        }
        // The framework's 8-bit constants pin SSIM near 1: show enough digits to tell methods apart.
        let digits = if exp.ssim == SsimConstants::Framework8Bit { 5 } else { 3 };
        for m in &methods {
            let v = find(m).map(|x| crate::experiment::converged_report::ssim_cell(x, digits)).unwrap_or_default();
            s.push_str(&format!(" {v} |"));
        }
        s.push('\n');
    }
    s.push_str(&format!(
        "\nPSNR: mean of the R, G, B channel PSNRs (linear values, peak 1). SSIM: Wang et al. 2004 window (11 x 11 Gaussian, sigma 1.5), constants `{}`, mean of channels.\n",
        report.ssim_constants
    ));
    if exp.measurement.estimator == EstimatorKind::Converged {
        s.push_str(&crate::experiment::converged_report::table_note(report, exp));
    }
    if !exp.extra_scores.is_empty() {
        s.push_str(&crate::experiment::converged_report::perceptual_table(report, exp));
    }
    if let Some(opt) = &exp.optimize {
        s.push_str(&crate::optimize::report::table_note(opt, report.optimization.as_ref()));
    }
    s
}

/// The eye cases whose converged sampling cost per sample is more than three times their
/// neighbours' (the cases before and after in the table), each with its reason where inimtrace
/// knows it (a schematic eye aiming every ray exactly: [`super::exact_aim_note`]).
pub fn sampling_cost_warnings(report: &AssessReport, exp: &Experiment) -> Vec<String> {
    let cost: Vec<Option<f64>> = exp
        .cases
        .iter()
        .map(|c| {
            let seconds: f64 = report
                .stages
                .iter()
                .filter(|s| s.stage == "converged_sampling" && s.eye_case.as_deref() == Some(c.name.as_str()))
                .map(|s| s.seconds)
                .sum();
            let samples = report.scores.iter().find(|s| s.eye_case == c.name)?.samples_per_pixel?;
            (samples > 0 && seconds > 0.0).then(|| seconds / samples as f64)
        })
        .collect();
    let mut out = Vec::new();
    for (i, case) in exp.cases.iter().enumerate() {
        let neighbours: Vec<f64> = [i.checked_sub(1), Some(i + 1)]
            .into_iter()
            .flatten()
            .filter_map(|j| cost.get(j).copied().flatten())
            .collect();
        let (Some(mine), false) = (cost[i], neighbours.is_empty()) else { continue };
        let theirs = neighbours.iter().sum::<f64>() / neighbours.len() as f64;
        if mine > 3.0 * theirs {
            let why = super::exact_aim_note(case, &exp.cases).map_or_else(
                || "inimtrace knows no reason (another load on the machine during the case?)".to_string(),
                |n| n.split_once(": ").map_or(n.clone(), |(_, r)| r.to_string()),
            );
            out.push(format!(
                "eye case `{}` cost {:.1}x its neighbours' sampling time per sample: {why}",
                case.name,
                mine / theirs
            ));
        }
    }
    out
}

/// `results.csv`: every score row (each channel and their mean) and every stage's time.
fn results_csv(report: &AssessReport, exp: &Experiment) -> String {
    // psnr_ci95_db and ssim_ci95 (empty for the grid estimator): 95% half-widths; then the
    // converged estimator's samples per retina pixel, replicates and whether both half-widths
    // are within the targets (empty for the grid estimator and for stage rows). Names
    // (experiment, eye case) are quoted where they hold a comma, a quote or a line break.
    let mut csv = CsvTable::new();
    let extra = exp.extra_scores.names();
    let extra_header: Vec<String> = extra
        .iter()
        .flat_map(|n| {
            [n.name().to_string(), format!("{n}_ci95"), format!("{n}_noise_bias"), format!("{n}_bias_above_ci95")]
        })
        .collect();
    let blank = vec![String::new(); extra_header.len()];
    row(
        &mut csv,
        &extra_header,
        [
            "record",
            "experiment",
            "method",
            "eye_case",
            "channel",
            "psnr_db",
            "ssim",
            "stage",
            "seconds",
            "psnr_ci95_db",
            "ssim_ci95",
            "samples_per_pixel",
            "replicates",
            "target_met",
        ],
    );
    let ci = |h: Option<f64>| h.map(csv_db).unwrap_or_default();
    let e = report.experiment.as_str();
    for s in &report.scores {
        let spp = s.samples_per_pixel.map(|n| n.to_string()).unwrap_or_default();
        let reps = s.replicates.map(|n| n.to_string()).unwrap_or_default();
        let met = s.target_met.map(|m| m.to_string()).unwrap_or_default();
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            row(
                &mut csv,
                &blank,
                [
                    "score",
                    e,
                    &s.method,
                    &s.eye_case,
                    name,
                    &csv_db(s.psnr.channels[c]),
                    &s.ssim.channels[c].to_string(),
                    "",
                    "",
                    &ci(s.psnr.channels_ci95.map(|h| h[c])),
                    &ci(s.ssim.channels_ci95.map(|h| h[c])),
                    &spp,
                    &reps,
                    &met,
                ],
            );
        }
        let values = perceptual_values(s, extra);
        row(
            &mut csv,
            &values,
            [
                "score",
                e,
                &s.method,
                &s.eye_case,
                "mean",
                &csv_db(s.psnr.mean),
                &s.ssim.mean.to_string(),
                "",
                "",
                &ci(s.psnr.ci95),
                &ci(s.ssim.ci95),
                &spp,
                &reps,
                &met,
            ],
        );
    }
    for st in &report.stages {
        row(
            &mut csv,
            &blank,
            [
                "stage",
                e,
                st.method.as_deref().unwrap_or(""),
                st.eye_case.as_deref().unwrap_or(""),
                "",
                "",
                "",
                &st.stage,
                &st.seconds.to_string(),
                "",
                "",
                "",
                "",
                "",
            ],
        );
    }
    row(
        &mut csv,
        &blank,
        ["stage", e, "", "", "", "", "", "total", &report.total_seconds.to_string(), "", "", "", "", ""],
    );
    csv.finish()
}

/// The extra scores' cells of one score row: value, half-width, removed noise bias and whether
/// it exceeds the half-width, per score `extra` names (empty where not measured).
fn perceptual_values(s: &Score, extra: &[crate::perception::ScoreName]) -> Vec<String> {
    use crate::perception::replicated::ScalarEstimate;
    extra.iter().flat_map(|n| ScalarEstimate::csv_cells(s.perceptual.get(*n), csv_db)).collect()
}

pub(super) fn write_reports(report: &AssessReport, exp: &Experiment, dir: &OutputDir) -> Result<()> {
    let write = |name: &str, text: String| -> Result<()> { dir.write_bytes(name, text.as_bytes()) };
    write("table.md", table_markdown(report, exp))?;
    write("results.csv", results_csv(report, exp))?;
    // Last: its presence marks a complete run, and it lists every other file of the run with
    // its size and CRC-32 (`files`), so a reader can verify the set.
    dir.finish_report("results.json", |files| {
        let mut value = serde_json::to_value(report).map_err(|e| Error::serialize("serialise the report", e))?;
        value["files"] = serde_json::to_value(files).map_err(|e| Error::serialize("serialise the report", e))?;
        serde_json::to_vec_pretty(&value).map_err(|e| Error::serialize("serialise the report", e))
    })
}

/// One row of `results.csv`: its 14 columns, then the extra scores' columns (none unless
/// `[measurement] scores` names some).
fn row(csv: &mut CsvTable, extra: &[String], fields: [&str; 14]) {
    csv.row(fields.iter().copied().chain(extra.iter().map(String::as_str)));
}

/// PSNR for CSV: identical images give "inf".
fn csv_db(db: f64) -> String {
    if db.is_finite() {
        format!("{db}")
    } else {
        "inf".into()
    }
}
