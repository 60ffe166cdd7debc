//! Table 1 cells and notes for `table.md` (paper Table 1): `value ± half-width` under the
//! converged estimator, today's plain values under the grid estimator.

use std::fmt::Write;

use crate::experiment::{AssessReport, Experiment, Score};
use crate::metrics::format_db;
use crate::perception::ScoreName;

/// Marks a cell whose interval is wider than the target.
const NOT_MET: &str = " *";

fn mark(score: &Score) -> &'static str {
    if score.target_met == Some(false) {
        NOT_MET
    } else {
        ""
    }
}

/// The PSNR cell: `21.37` (grid) or `21.37 ± 0.02` (converged; `inf` when the images are equal
/// up to the noise).
pub fn psnr_cell(score: &Score) -> String {
    let v = format_db(score.psnr.mean, 2);
    match score.psnr.ci95 {
        Some(h) if score.psnr.mean.is_finite() => format!("{v} ± {}{}", format_db(h, 2), mark(score)),
        Some(_) => format!("{v}{}", mark(score)),
        None => v,
    }
}

/// The SSIM cell with `digits` decimals (grid), or at least 4 and `± half-width` (converged).
pub fn ssim_cell(score: &Score, digits: usize) -> String {
    match score.ssim.ci95 {
        Some(h) => {
            let d = digits.max(4);
            format!("{:.d$} ± {h:.d$}{}", score.ssim.mean, mark(score))
        }
        None => format!("{:.digits$}", score.ssim.mean),
    }
}

/// The converged estimator's note under the table: what was measured, the samples, and whether
/// every target was met.
pub fn table_note(report: &AssessReport, exp: &Experiment) -> String {
    let m = &exp.measurement;
    let mut s = String::new();
    let _ = write!(
        s,
        "\nEstimator: converged. Each retina pixel is the average over its square and the continuous pupil disk, \
         estimated by randomized quasi-Monte Carlo (Owen-scrambled Sobol) with the same eye rays for the ground truth \
         and every method, in {} independent replicates (seed {}). Scores come from products of different replicates \
         (no noise bias); ± is the half-width of the 95% interval (delete-one jackknife over replicates, Student t with \
         {} degrees of freedom). Images are the replicates' means.\n",
        m.replicates,
        m.seed,
        m.replicates - 1
    );
    let samples: Vec<String> = exp
        .cases
        .iter()
        .filter_map(|c| {
            let spp = report.scores.iter().find(|x| x.eye_case == c.name)?.samples_per_pixel?;
            Some(format!("{} {spp}", c.name))
        })
        .collect();
    let _ = writeln!(s, "\nSamples per retina pixel (all replicates): {}.", samples.join(", "));
    let missed: Vec<String> = report
        .scores
        .iter()
        .filter(|x| x.target_met == Some(false))
        .map(|x| format!("{} {}", x.eye_case, x.method))
        .collect();
    let targets = format!("PSNR ± {} dB, SSIM ± {}", m.psnr_ci95_db, m.ssim_ci95);
    if missed.is_empty() {
        let _ = writeln!(s, "\nTargets ({targets}): met in every cell.");
    } else {
        let _ = writeln!(
            s,
            "\nTargets ({targets}): NOT met in {} of {} (marked *: {}); the budget (max_samples_per_pixel {}, \
             max_seconds {}) was spent first.",
            missed.len(),
            crate::count::count(report.scores.len(), "cell"),
            missed.join(", "),
            m.max_samples_per_pixel,
            m.max_seconds
        );
    }
    s
}

/// Marks a score whose removed noise bias exceeds its half-width.
const BIAS_ABOVE: &str = " †";

/// A cell of the extra scores: `value` (plain images) or `value ± half-width` (converged), with
/// `decimals` places.
fn extra_cell(score: &Score, name: ScoreName) -> String {
    let Some(e) = score.perceptual.get(name) else { return String::new() };
    let d = match name {
        ScoreName::Cvvdp => 3,
        ScoreName::Flip => 4,
        _ => 2,
    };
    let v = format_db(e.value, d);
    let bias = if e.bias_above_ci95() { BIAS_ABOVE } else { "" };
    match e.ci95 {
        Some(h) if e.value.is_finite() => format!("{v} ± {}{bias}{}", format_db(h, d), mark(score)),
        _ => format!("{v}{}", mark(score)),
    }
}

/// The table of the scores `[measurement] scores` names beyond PSNR and SSIM, and how they were
/// computed (luminance, pixels per degree, the eye's optics, the noise's bias).
pub fn perceptual_table(report: &AssessReport, exp: &Experiment) -> String {
    let names = exp.extra_scores.names();
    let methods: Vec<String> = exp.methods.iter().map(|m| m.name()).collect();
    let label = |n: ScoreName| match n {
        ScoreName::Cvvdp => "JOD".to_string(),
        ScoreName::Flip => "FLIP".to_string(),
        ScoreName::PsnrLuminance => "PSNR-Y".to_string(),
        other => other.name().to_string(),
    };
    let mut s = String::from("\n## What a person would see\n\n| Eye |");
    for n in names {
        for m in &methods {
            let _ = write!(s, " {} {m} |", label(*n));
        }
    }
    s.push_str("\n|---|");
    s.push_str(&"---:|".repeat(names.len() * methods.len()));
    s.push('\n');
    for case in &exp.cases {
        let _ = write!(s, "| {} |", case.name);
        for n in names {
            for m in &methods {
                let cell = report
                    .scores
                    .iter()
                    .find(|x| &x.method == m && x.eye_case == case.name)
                    .map(|x| extra_cell(x, *n))
                    .unwrap_or_default();
                let _ = write!(s, " {cell} |");
            }
        }
        s.push('\n');
    }
    let v = crate::experiment::perceptual::viewing(exp);
    let l = &v.luminance;
    let _ = write!(
        s,
        "\nJOD: ColorVideoVDP 0.5.7 (Mantiuk et al. 2024; 10 = no visible difference). FLIP: HDR-FLIP mean \
         (Andersson et al. 2020, 2021; 0 = none). PSNR-Y: PSNR of the luminance (the primaries' V(lambda) shares, \
         peak 1). The display: \
         white {} cd/m^2, black {} cd/m^2, ambient {} lux; the retina image: {:.2} pixels per degree. The eye's \
         optics: `{}`",
        l.peak_white,
        l.black,
        l.ambient_lux,
        v.pixels_per_degree,
        exp.measurement.optics.name()
    );
    let compensated: Vec<&str> = (0..exp.cases.len())
        .filter(|c| exp.measurement.optics.compensates(crate::experiment::perceptual::has_aberrations(exp, *c)))
        .map(|c| exp.cases[c].name.as_str())
        .collect();
    if compensated.is_empty() {
        s.push_str(" (the metrics' sensitivity as published, with its typical eye's optics).\n");
    } else {
        let _ = writeln!(s, " (Barten's typical optics divided out for {}).", compensated.join(", "));
    }
    let worst = report
        .scores
        .iter()
        .flat_map(|x| x.perceptual.0.iter())
        .filter_map(|(n, e)| Some((*n, e.noise_bias?.abs() / e.ci95?)))
        .filter(|(_, r)| r.is_finite())
        .fold(None, |w: Option<(ScoreName, f64)>, x| if w.is_none_or(|w| x.1 > w.1) { Some(x) } else { w });
    if let Some((n, r)) = worst {
        let _ = writeln!(
            s,
            "\nJOD and FLIP are of the replicates' mean images, whose noise biases them; each value is corrected \
             for that bias (a generalised jackknife over groups of replicates) and its 95% half-width holds the \
             correction's uncertainty. The largest bias removed is {r:.1} times its half-width ({n}){}",
            if r > 1.0 {
                "; † marks a value whose removed bias exceeds its half-width: it rests on the bias model more \
                 than on the samples (a `[measurement]` target on the score samples until the half-width meets it)."
            } else {
                "."
            }
        );
    }
    s
}
