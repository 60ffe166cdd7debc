//! Adaptive precision for one eye case of Table 1 (paper Sec. 4.2): sample until every cell's
//! scores are known to the stated precision, or the budget is spent.
//!
//! A round adds samples to every replicate of every pixel ([`Replicates::extend`]), then computes
//! every cell's (scored image's) PSNR with its 95% half-width, and, once every PSNR meets its
//! target, every SSIM. When some cell misses its target, the samples per replicate grow to what
//! the slowest cell's half-width predicts (see `next_samples`), within the sample budget, and
//! only if the round's predicted time fits the time budget. The schedule depends only on the
//! numbers, so the same seed gives the same result, unless the time budget stops it.

use std::time::{Duration, Instant};

use super::estimator::{PairedSource, Replicates};
use super::sampler::{Sampler, MAX_SAMPLES_PER_REPLICATE};
use super::ssim::ssim_estimates;
use super::stats::{gram_matrices, psnr_estimate, Estimate};
use crate::metrics::SsimConstants;
use crate::optics::Retina;
use crate::progress::Progress;

/// What to reach and what may be spent.
#[derive(Clone, Copy, Debug)]
pub struct Precision {
    /// Target half-width of every PSNR mean's 95% interval, dB.
    pub psnr_ci95_db: f64,
    /// Target half-width of every SSIM mean's 95% interval.
    pub ssim_ci95: f64,
    /// Samples per pixel over all replicates, at most.
    pub max_samples_per_pixel: u64,
    /// Stop starting rounds that would end after this instant.
    pub deadline: Option<Instant>,
    /// Samples per replicate of the first round.
    pub initial_samples: u32,
    /// Independent replicates R (at least 3).
    pub replicates: usize,
}

/// One cell's scores.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellScores {
    /// PSNR against image 0 (the ground truth), dB, with its 95% interval.
    pub psnr: Estimate,
    /// SSIM against image 0, with its 95% interval.
    pub ssim: Estimate,
    /// Both half-widths within their targets.
    pub target_met: bool,
}

/// One round of sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Round {
    /// Samples per retina pixel after the round, over all replicates.
    pub samples_per_pixel: u64,
    /// Seconds spent tracing the round's samples.
    pub sample_seconds: f64,
    /// Seconds spent scoring after it.
    pub stats_seconds: f64,
}

/// The measurement of one eye case: the replicates and every cell's scores.
pub struct CaseMeasurement {
    /// The replicate images.
    pub replicates: Replicates,
    /// `cells[k - 1]`: image `k` against image 0.
    pub cells: Vec<CellScores>,
    /// Every round of sampling, in order.
    pub rounds: Vec<Round>,
    /// Why sampling stopped: "target met", "sample budget" or "time budget".
    pub stopped_by: &'static str,
}

impl CaseMeasurement {
    /// Samples per retina pixel taken, over all replicates.
    pub fn samples_per_pixel(&self) -> u64 {
        self.replicates.samples_per_pixel()
    }
}

/// Scores of every scored image of `reps`, and whether each meets `precision`.
pub fn score(reps: &Replicates, constants: SsimConstants, precision: &Precision) -> Vec<CellScores> {
    let (psnr, ssim) = rayon::join(|| psnr_estimates(reps), || ssim_estimates(reps, constants));
    cells(psnr, ssim, precision)
}

/// The PSNR and SSIM of every scored image of `reps` against image 0, exactly as the table's
/// last round computes them: for replicate sets read back from files (`compare`).
pub fn estimates(reps: &Replicates, constants: SsimConstants) -> Vec<(Estimate, Estimate)> {
    let (psnr, ssim) = rayon::join(|| psnr_estimates(reps), || ssim_estimates(reps, constants));
    psnr.into_iter().zip(ssim).collect()
}

fn psnr_estimates(reps: &Replicates) -> Vec<Estimate> {
    gram_matrices(reps).iter().map(psnr_estimate).collect()
}

fn cells(psnr: Vec<Estimate>, ssim: Vec<Estimate>, precision: &Precision) -> Vec<CellScores> {
    psnr.into_iter()
        .zip(ssim)
        .map(|(psnr, ssim)| CellScores {
            psnr,
            ssim,
            target_met: psnr.ci95.is_some_and(|h| h <= precision.psnr_ci95_db)
                && ssim.ci95.is_some_and(|h| h <= precision.ssim_ci95),
        })
        .collect()
}

/// Measures one eye case of `source` on `retina` to `precision`, in the buffer of `storage`
/// when given (the replicates of an earlier case, see [`Replicates::recycle`]).
///
/// Each round computes the PSNRs (cheap: Gram matrices); the SSIMs (many filtered planes) only
/// once every PSNR meets its target, or when sampling must stop.
pub fn measure_case<S: PairedSource + ?Sized>(
    source: &S,
    sampler: &Sampler,
    retina: &Retina,
    constants: SsimConstants,
    precision: &Precision,
    progress: &Progress,
    storage: Option<Replicates>,
) -> CaseMeasurement {
    measure_case_with(source, sampler, retina, constants, precision, progress, storage, &mut |_| None)
}

/// Further targets of a measurement: given the replicates, every cell's half-width over its
/// target (at most 1: met) of each further score, or `None` when there is nothing more to ask
/// (no further target, or the scores cannot be computed: the caller reports why).
pub type FurtherTargets<'a> = dyn FnMut(&Replicates) -> Option<Vec<f64>> + 'a;

/// [`measure_case`] with `further` targets (the perceptual scores'), asked once PSNR and SSIM
/// meet theirs: sampling goes on, as the slowest cell's ratio predicts, until they are met too.
#[allow(clippy::too_many_arguments)]
pub fn measure_case_with<S: PairedSource + ?Sized>(
    source: &S,
    sampler: &Sampler,
    retina: &Retina,
    constants: SsimConstants,
    precision: &Precision,
    progress: &Progress,
    storage: Option<Replicates>,
    further: &mut FurtherTargets<'_>,
) -> CaseMeasurement {
    let nr = precision.replicates;
    let max_n = (precision.max_samples_per_pixel / nr as u64).clamp(1, MAX_SAMPLES_PER_REPLICATE) as u32;
    let mut reps = match storage {
        Some(old) => old.recycle(retina.resolution, nr, source.images()),
        None => Replicates::new(retina.resolution, nr, source.images()),
    };
    let mut n = precision.initial_samples.clamp(1, max_n);
    let mut rounds = Vec::new();
    // Half-widths of every cell's PSNR mean at each round, and of its SSIM mean when computed.
    let mut psnr_history: Vec<(u32, Vec<f64>)> = Vec::new();
    let mut ssim_history: Vec<(u32, Vec<f64>)> = Vec::new();
    // Half-widths over targets of the further scores, when asked (target 1).
    let mut further_history: Vec<(u32, Vec<f64>)> = Vec::new();
    let widths = |e: &[Estimate]| e.iter().map(|x| x.ci95.unwrap_or(f64::INFINITY)).collect::<Vec<_>>();
    loop {
        let t = Instant::now();
        reps.extend(source, sampler, retina, n, progress);
        if progress.cancelled() {
            // Tiles were skipped: no scores; the caller discards the measurement.
            return CaseMeasurement { replicates: reps, cells: Vec::new(), rounds, stopped_by: "cancelled" };
        }
        let sample_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let psnr = psnr_estimates(&reps);
        psnr_history.push((n, widths(&psnr)));
        let psnr_met = psnr.iter().all(|p| p.ci95.is_some_and(|h| h <= precision.psnr_ci95_db));
        let plan = |psnr_history: &[(u32, Vec<f64>)], ssim_history: &[(u32, Vec<f64>)]| {
            let a = next_samples(psnr_history, precision.psnr_ci95_db);
            let b = next_samples(ssim_history, precision.ssim_ci95);
            a.max(b).clamp(n + 1, max_n)
        };
        let mut next = (n < max_n).then(|| plan(&psnr_history, &ssim_history));
        let mut stats_seconds = t.elapsed().as_secs_f64();
        if let Some(m) = next {
            // Time of the next round: sampling scales with the samples added.
            let per_sample: f64 = rounds.iter().map(|r: &Round| r.sample_seconds).sum::<f64>() + sample_seconds;
            let predicted = per_sample / f64::from(n) * f64::from(m - n) + stats_seconds;
            if precision.deadline.is_some_and(|d| Instant::now() + Duration::from_secs_f64(predicted) > d) {
                next = None;
            }
        }
        let stopped_by = match next {
            None if n >= max_n => Some("sample budget"),
            None => Some("time budget"),
            Some(_) => None,
        };
        if psnr_met || stopped_by.is_some() {
            let t = Instant::now();
            let ssim = ssim_estimates(&reps, constants);
            stats_seconds += t.elapsed().as_secs_f64();
            rounds.push(Round { samples_per_pixel: reps.samples_per_pixel(), sample_seconds, stats_seconds });
            let ssim_met = ssim.iter().all(|s| s.ci95.is_some_and(|h| h <= precision.ssim_ci95));
            ssim_history.push((n, widths(&ssim)));
            let further_met = match (stopped_by, ssim_met) {
                (None, true) => {
                    let t = Instant::now();
                    let ratios = further(&reps);
                    rounds.last_mut().expect("this round").stats_seconds += t.elapsed().as_secs_f64();
                    let met = ratios.as_ref().is_none_or(|r| r.iter().all(|x| *x <= 1.0));
                    further_history.extend(ratios.map(|r| (n, r)));
                    met
                }
                _ => true,
            };
            let cells = cells(psnr, ssim, precision);
            match stopped_by {
                Some(why) => return CaseMeasurement { replicates: reps, cells, rounds, stopped_by: why },
                None if ssim_met && further_met => {
                    return CaseMeasurement { replicates: reps, cells, rounds, stopped_by: "target met" }
                }
                None => {
                    let more = next_samples(&further_history, 1.0);
                    n = plan(&psnr_history, &ssim_history).max(more.min(max_n));
                    continue;
                }
            }
        }
        rounds.push(Round { samples_per_pixel: reps.samples_per_pixel(), sample_seconds, stats_seconds });
        n = next.expect("a next round when sampling goes on");
    }
}

/// The samples per replicate the next round should reach, from the half-widths `history[i] =
/// (samples per replicate, half-width of every cell)` of one score and its `target`; 0 when
/// every cell meets it (or nothing is known yet).
///
/// What the slowest cell needs if its half-width fell as `1/N` (faster than randomized QMC
/// achieves on this kind of image, so the prediction errs on the side of too few samples), plus
/// 30%, at least 1.25 and at most 16 times the current count, rounded up to a multiple of 4.
/// The counts stay nested (each round adds the next points of the same sequences), so a round
/// that falls short loses nothing but one more PSNR pass, while one that overshoots would waste
/// samples. The 30% lands most rounds clearly below the target rather than just at it: stopping
/// as soon as an *estimated* half-width meets the target favours runs whose half-width happens
/// to be underestimated, which costs coverage when the true half-width sits right at the target
/// (`tests/measure.rs` checks the coverage of adaptive runs).
fn next_samples(history: &[(u32, Vec<f64>)], target: f64) -> u32 {
    let Some((n, now)) = history.last() else { return 0 };
    let worst = now.iter().fold(0.0f64, |w, h| w.max(if h.is_finite() { h / target } else { 16.0 }));
    if worst <= 1.0 {
        return 0;
    }
    let n = f64::from(*n);
    let want = (n * worst * 1.3).clamp(1.25 * n, 16.0 * n).ceil() as u32;
    want.div_ceil(4) * 4
}
