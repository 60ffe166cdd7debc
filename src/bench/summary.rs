//! What the measured rows say about convergence: the observed rate of each convergence series
//! (error ~ samples^p) and the first setting within [`CONVERGED_TOLERANCE_DB`] of the converged
//! PSNR (that of the highest setting), with the helpers to compare sets of PSNRs.

use serde::Serialize;

use super::options::{Backend, BenchRow, Series};

/// PSNR reported for identical images, so that tables, fits and plots stay finite.
pub const IDENTICAL_PSNR_DB: f64 = 200.0;

/// Tolerance of "reaches the converged PSNR" in the report.
pub const CONVERGED_TOLERANCE_DB: f64 = 0.1;

/// A PSNR as the bench reports it: capped at [`IDENTICAL_PSNR_DB`] (also for identical images).
pub fn capped_psnr(db: f64) -> f64 {
    if db.is_finite() {
        db.min(IDENTICAL_PSNR_DB)
    } else {
        IDENTICAL_PSNR_DB
    }
}

/// Which setting of a convergence series first comes within [`CONVERGED_TOLERANCE_DB`] of the
/// converged PSNR (the PSNR of its highest setting), and what it costs.
#[derive(Clone, Debug, Serialize)]
pub struct WithinTolerance {
    /// The setting (the series' parameter).
    pub parameter: usize,
    /// Samples it takes (per pixel).
    pub samples: usize,
    /// Its wall time, s.
    pub seconds: f64,
    /// Its PSNR, dB.
    pub psnr_db: f64,
}

/// Observed convergence of one series.
#[derive(Clone, Debug, Serialize)]
pub struct ConvergenceSummary {
    /// The series.
    pub series: Series,
    /// What the series renders and varies, in words.
    pub quantity: String,
    /// The backend that rendered the series.
    pub backend: Backend,
    /// What the series is scored against.
    pub reference: String,
    /// p in error ~ samples^p: least-squares slope of ln(error) against ln(samples) over every
    /// point of the series, with error = 10^(-PSNR/20) (the geometric mean of the R, G, B
    /// RMSEs; peak 1). `None` with fewer than two usable points.
    pub rate: Option<f64>,
    /// PSNR of the highest setting.
    pub converged_psnr_db: f64,
    /// The series' highest setting.
    pub highest_parameter: usize,
    /// Its wall time, s.
    pub highest_seconds: f64,
    /// The cheapest setting within tolerance of the converged PSNR, if any.
    pub first_within_tolerance: Option<WithinTolerance>,
}

/// p in error ~ samples^p (see [`ConvergenceSummary::rate`]) from (samples, PSNR) points.
/// Points with non-finite or identical-image PSNR are left out.
pub fn convergence_rate(points: &[(f64, f64)]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|(n, p)| *n > 0.0 && p.is_finite() && *p < IDENTICAL_PSNR_DB)
        .map(|(n, p)| (n.ln(), -p / 20.0 * std::f64::consts::LN_10))
        .collect();
    if xy.len() < 2 {
        return None;
    }
    let m = xy.len() as f64;
    let (mx, my) = (xy.iter().map(|v| v.0).sum::<f64>() / m, xy.iter().map(|v| v.1).sum::<f64>() / m);
    let sxx: f64 = xy.iter().map(|v| (v.0 - mx) * (v.0 - mx)).sum();
    let sxy: f64 = xy.iter().map(|v| (v.0 - mx) * (v.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Index of the first point (in sweep order) whose PSNR is within `tolerance` dB of the last
/// point's (the highest setting's).
pub fn first_within(psnr: &[f64], tolerance: f64) -> Option<usize> {
    let last = *psnr.last()?;
    psnr.iter().position(|p| *p >= last - tolerance)
}

/// Largest |a - b| over two equally long lists; infinite when their lengths differ or a
/// difference is NaN.
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, |m, d| if d.is_nan() { f64::INFINITY } else { m.max(d) })
}

/// Index of the cheapest point of a sweep (the first: sweeps go from fewest to most samples)
/// whose every value is within `tolerance` of the same value at the last point (the converged
/// values): `points[i]` holds the values of point i, in the same order at every point.
pub fn cheapest_within(points: &[Vec<f64>], tolerance: f64) -> Option<usize> {
    let last = points.last()?;
    points.iter().position(|p| max_abs_diff(p, last) <= tolerance)
}

/// The observed convergence of `series` (one of [`Series::CONVERGENCE`]) over its rows.
pub fn summarize(series: Series, rows: &[BenchRow]) -> Option<ConvergenceSummary> {
    let pts: Vec<&BenchRow> = rows.iter().filter(|r| r.series == series).collect();
    let last = pts.last()?;
    let psnr: Vec<f64> = pts.iter().map(|r| r.psnr_db).collect();
    let within = first_within(&psnr, CONVERGED_TOLERANCE_DB).map(|i| WithinTolerance {
        parameter: pts[i].parameter,
        samples: pts[i].samples,
        seconds: pts[i].seconds,
        psnr_db: pts[i].psnr_db,
    });
    Some(ConvergenceSummary {
        series,
        quantity: describe_series(series, last),
        backend: last.backend,
        reference: last.reference.clone(),
        rate: convergence_rate(&pts.iter().map(|r| (r.samples as f64, r.psnr_db)).collect::<Vec<_>>()),
        converged_psnr_db: last.psnr_db,
        highest_parameter: last.parameter,
        highest_seconds: last.seconds,
        first_within_tolerance: within,
    })
}

/// What a series renders and varies, in words (`r`: one of its rows).
fn describe_series(series: Series, r: &BenchRow) -> String {
    match series {
        Series::LaGrid => "LA display image, k x k lenslet grid".into(),
        Series::PupilGrid => format!("LC perceived image ({}), n x n pupil grid", r.eye_case),
        Series::RetinaSamples => format!("ground truth ({}), k x k samples per retina pixel", r.eye_case),
        Series::Method | Series::Precision => series.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_of_an_exact_power_law() {
        // error = 0.3 N^-0.75  ->  PSNR = -20 log10(0.3 N^-0.75).
        let pts: Vec<(f64, f64)> =
            [1.0, 4.0, 9.0, 16.0, 64.0].iter().map(|&n: &f64| (n, -20.0 * (0.3 * n.powf(-0.75)).log10())).collect();
        assert!((convergence_rate(&pts).unwrap() + 0.75).abs() < 1e-12);
        // Identical-image points are left out; one point is not a fit.
        let mut with_cap = pts.clone();
        with_cap.push((256.0, IDENTICAL_PSNR_DB));
        assert!((convergence_rate(&with_cap).unwrap() + 0.75).abs() < 1e-12);
        assert_eq!(convergence_rate(&pts[..1]), None);
        assert_eq!(convergence_rate(&[(4.0, 20.0), (4.0, 30.0)]), None);
    }

    #[test]
    fn first_setting_within_tolerance_of_the_highest() {
        assert_eq!(first_within(&[20.0, 30.0, 33.95, 34.0], 0.1), Some(2));
        assert_eq!(first_within(&[20.0, 30.0, 34.2, 34.0], 0.1), Some(2));
        assert_eq!(first_within(&[20.0, 30.0, 33.8, 34.0], 0.1), Some(3));
        assert_eq!(first_within(&[], 0.1), None);
    }

    #[test]
    fn cheapest_setting_within_tolerance_of_the_converged_values() {
        // Two values per point; the last point is converged.
        let pts = vec![vec![20.0, 30.0], vec![21.95, 30.5], vec![21.93, 30.05], vec![22.0, 30.0]];
        assert_eq!(cheapest_within(&pts, 0.1), Some(2));
        // Overshooting counts as away from converged too.
        let pts = vec![vec![22.2, 30.0], vec![22.05, 30.0], vec![22.0, 30.0]];
        assert_eq!(cheapest_within(&pts, 0.1), Some(1));
        // The highest setting always qualifies; nothing to compare without points.
        assert_eq!(cheapest_within(&[vec![1.0], vec![5.0]], 0.1), Some(1));
        assert_eq!(cheapest_within(&[], 0.1), None);
        // NaN and length mismatches never qualify.
        assert_eq!(cheapest_within(&[vec![f64::NAN, 30.0], vec![22.0], vec![22.0, 30.0]], 0.1), Some(2));
        assert_eq!(max_abs_diff(&[1.0, 2.0], &[1.5, 1.0]), 1.0);
    }

    #[test]
    fn identical_images_read_as_the_cap() {
        assert_eq!(capped_psnr(f64::INFINITY), IDENTICAL_PSNR_DB);
        assert_eq!(capped_psnr(f64::NAN), IDENTICAL_PSNR_DB);
        assert_eq!(capped_psnr(250.0), IDENTICAL_PSNR_DB);
        assert_eq!(capped_psnr(31.5), 31.5);
    }
}
