//! Table 1 cells and notes for `table.md` (paper Table 1): `value ± half-width` under the
//! converged estimator, today's plain values under the grid estimator.

use std::fmt::Write;

use crate::experiment::{AssessReport, Experiment, Score};
use crate::metrics::format_db;

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
