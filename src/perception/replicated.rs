//! Perceptual scores of the converged measurement's replicates, corrected for the bias that the
//! estimator's noise leaves in them, with 95% intervals that include the correction's own
//! uncertainty.
//!
//! ColorVideoVDP and FLIP are not quadratic in the images, so the cross-replicate products that
//! free PSNR and SSIM of noise bias (`measure/stats.rs`, `measure/ssim.rs`) do not apply. A score
//! computed on the replicates' mean images (the ground truth's and the method's, paired: the
//! same eye rays) sees their noise as distortion: JOD is biased down, FLIP's sign depends on its
//! exposures. For a score smooth in the images the bias falls as `1/N` with the samples `N` (the
//! delta method: the noise's variance); where the score has a kink at zero difference (FLIP's
//! colour distance, `|dL| + |dab|`, on pixels whose true difference is below the noise) it falls
//! as `N^-1/2`. So the bias is `b N^-a` with `a` in a bracket: `[1, 1]` for ColorVideoVDP (its
//! pooling is a power above 1 of band differences), `[1/2, 1]` for FLIP.
//!
//! The estimator is a generalised delete-a-group jackknife (Gray and Schucany, *The Generalized
//! Jackknife Statistic*, 1972; Quenouille 1956 for `a = 1`). The replicates fall into `G`
//! groups (replicate `r` in group `r mod G`, `G = min(R, 8)`); `theta` is the score of the means
//! of all replicates and `theta_g` that of the means without group `g`, which keep a fraction
//! `f_g` of the samples. With bias `b N^-a`, `theta_g - theta` is `b N^-a (f_g^-a - 1)`, so the
//! pseudo-value `p_g = theta + K_g (theta - theta_g)`, `K_g = 1 / (f_g^-a - 1)`, is free of the
//! bias (for `a = 1` and equal groups, Tukey's `G theta - (G - 1) theta_g`). The reported value is
//! the mean of the pseudo-values at the bracket's middle (the mean of the two ends' `p_g`); its
//! 95% half-width is `t(0.975, G - 1)` times their standard error (which holds the correction's
//! sampling noise) plus half the difference of the corrections at the bracket's two ends (the
//! exponent's uncertainty). `noise_bias` is `theta` minus the reported value: what was removed.
//! `bias_above_ci95` flags a score whose removed bias exceeds its half-width: the value then
//! rests on the bias model more than on the samples, and more samples (a `[measurement]` target,
//! which drives the adaptive sampling) are the remedy. `G + 1` evaluations per score and cell;
//! `tests/perception.rs` checks the coverage of the interval against exact answers.

use rayon::prelude::*;
use serde::ser::SerializeStruct;
use serde::Serialize;

use crate::error::Result;
use crate::measure::estimator::Replicates;
use crate::measure::stats::t_quantile_975;
use crate::raster::RgbImage;

/// The most groups of the delete-a-group jackknife.
pub const MAX_GROUPS: usize = 8;

/// One scalar score with its 95% half-width and the noise bias removed from it (`None` for the
/// grid estimator and for two plain images, which have neither).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalarEstimate {
    /// The score, corrected for the estimator's noise (module comment).
    pub value: f64,
    /// Half-width of its 95% interval, the correction's uncertainty included.
    pub ci95: Option<f64>,
    /// The noise bias removed: the score of the replicates' mean images minus `value`.
    pub noise_bias: Option<f64>,
}

impl ScalarEstimate {
    /// A score with no known error (the grid estimator, or two plain images).
    pub fn exact(value: f64) -> Self {
        Self { value, ci95: None, noise_bias: None }
    }

    /// Whether the removed bias exceeds the half-width (module comment).
    pub fn bias_above_ci95(&self) -> bool {
        matches!((self.noise_bias, self.ci95), (Some(b), Some(h)) if b.abs() > h)
    }

    /// The four CSV cells of a score, as results.csv and sweep.csv write them: the value, the
    /// half-width, the removed noise bias and whether it exceeds the half-width, numbers as
    /// `number` writes them; empty where the score (or that part of it) is absent.
    pub fn csv_cells(score: Option<&ScalarEstimate>, number: impl Fn(f64) -> String) -> [String; 4] {
        let opt = |v: Option<f64>| v.map(&number).unwrap_or_default();
        let flag = score.filter(|e| e.noise_bias.is_some()).map(|e| e.bias_above_ci95().to_string());
        [
            opt(score.map(|e| e.value)),
            opt(score.and_then(|e| e.ci95)),
            opt(score.and_then(|e| e.noise_bias)),
            flag.unwrap_or_default(),
        ]
    }
}

impl Serialize for ScalarEstimate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let n = 1 + self.ci95.is_some() as usize + 2 * self.noise_bias.is_some() as usize;
        let mut st = s.serialize_struct("ScalarEstimate", n)?;
        let num = |v: f64| if v.is_finite() { serde_json::json!(v) } else { serde_json::json!(format!("{v}")) };
        st.serialize_field("value", &num(self.value))?;
        if let Some(h) = self.ci95 {
            st.serialize_field("ci95", &num(h))?;
        }
        if let Some(b) = self.noise_bias {
            st.serialize_field("noise_bias", &num(b))?;
            st.serialize_field("bias_above_ci95", &self.bias_above_ci95())?;
        }
        st.end()
    }
}

/// How a score's noise bias falls with the samples `N`: as `N^-a`, `a` within `[lo, hi]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasExponent {
    /// The bracket's low end.
    pub lo: f64,
    /// The bracket's high end.
    pub hi: f64,
}

impl BiasExponent {
    /// A score smooth in the images: `1/N`.
    pub const SMOOTH: BiasExponent = BiasExponent { lo: 1.0, hi: 1.0 };
    /// A score with a kink at zero difference: between `N^-1/2` and `1/N`.
    pub const KINKED: BiasExponent = BiasExponent { lo: 0.5, hi: 1.0 };
}

/// The bias-corrected estimate from the score of all replicates `theta` and the scores without
/// each group, `dropped[g] = (theta_g, f_g)` (module comment).
pub fn corrected(theta: f64, dropped: &[(f64, f64)], exponent: BiasExponent) -> ScalarEstimate {
    let g = dropped.len();
    let k = |f: f64, a: f64| 1.0 / (f.powf(-a) - 1.0);
    let pseudo = |a: f64| dropped.iter().map(|&(t, f)| theta + k(f, a) * (theta - t)).collect::<Vec<_>>();
    let (lo, hi) = (pseudo(exponent.lo), pseudo(exponent.hi));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mid: Vec<f64> = lo.iter().zip(&hi).map(|(a, b)| 0.5 * (a + b)).collect();
    let value = mean(&mid);
    let var = mid.iter().map(|p| (p - value).powi(2)).sum::<f64>() / (g - 1) as f64;
    let half = t_quantile_975(g - 1) * (var / g as f64).sqrt() + 0.5 * (mean(&lo) - mean(&hi)).abs();
    ScalarEstimate { value, ci95: Some(half), noise_bias: Some(theta - value) }
}

/// Sums over a set of replicates of one image: `sum[pixel][channel]` in `f64`.
fn sums(reps: &Replicates, k: usize, keep: impl Fn(usize) -> bool + Sync) -> Vec<[f64; 3]> {
    let n = reps.resolution();
    let mut out = vec![[0.0f64; 3]; n * n];
    out.par_chunks_mut(n).enumerate().for_each(|(row, px)| {
        for r in (0..reps.replicates()).filter(|r| keep(*r)) {
            for c in 0..3 {
                for (p, v) in px.iter_mut().zip(&reps.plane(r, k, c)[row * n..(row + 1) * n]) {
                    p[c] += f64::from(*v);
                }
            }
        }
    });
    out
}

/// The image of `(sum - replicates less of image k) / count`.
fn mean_of(n: usize, sum: &[[f64; 3]], reps: &Replicates, k: usize, less: &[usize], count: usize) -> RgbImage {
    let inv = 1.0 / count as f64;
    let mut img = RgbImage::new(n, n);
    img.pixels.par_chunks_mut(n).enumerate().for_each(|(row, px)| {
        for (j, p) in px.iter_mut().enumerate() {
            let i = row * n + j;
            *p = std::array::from_fn(|c| {
                let s = sum[i][c] - less.iter().map(|&r| f64::from(reps.plane(r, k, c)[i])).sum::<f64>();
                (s * inv) as f32
            });
        }
    });
    img
}

/// `score(test, reference)` of image `k` of `reps` against image 0, corrected for the noise's
/// bias with its interval (module comment): `G + 1` scores, evaluated in parallel.
pub fn replicated_estimate(
    reps: &Replicates,
    k: usize,
    exponent: BiasExponent,
    score: &(dyn Fn(&RgbImage, &RgbImage) -> Result<f64> + Sync),
) -> Result<ScalarEstimate> {
    let (n, nr) = (reps.resolution(), reps.replicates());
    let groups = nr.min(MAX_GROUPS);
    let (s0, sk) = (sums(reps, 0, |_| true), sums(reps, k, |_| true));
    // Index 0: all replicates; 1 + g: without group g.
    let scores: Vec<(f64, f64)> = (0..=groups)
        .into_par_iter()
        .map(|i| {
            let less: Vec<usize> = match i {
                0 => Vec::new(),
                _ => (0..nr).filter(|r| r % groups == i - 1).collect(),
            };
            let count = nr - less.len();
            let t = mean_of(n, &sk, reps, k, &less, count);
            let r = mean_of(n, &s0, reps, 0, &less, count);
            Ok((score(&t, &r)?, count as f64 / nr as f64))
        })
        .collect::<Result<_>>()?;
    Ok(corrected(scores[0].0, &scores[1..], exponent))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gaussian noise from a fixed stream (Box-Muller over a 64-bit LCG).
    struct Gauss(u64);
    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn next(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    const N: usize = 8;

    /// Replicates of a reference (0.5 everywhere) and a test image that differs by `diff(pixel)`,
    /// each replicate with independent Gaussian noise of standard deviation `sigma`.
    fn noisy(seed: u64, replicates: usize, sigma: f64, diff: impl Fn(usize) -> f64) -> Replicates {
        let mut g = Gauss(seed);
        let noise: Vec<f64> = (0..N * N * 3 * replicates * 2).map(|_| sigma * g.next()).collect();
        Replicates::from_fn(N, replicates, 2, 1, |p, r, k, c| {
            let base = 0.5 + if k == 1 { diff(p) } else { 0.0 };
            (base + noise[((p * 3 + c) * replicates + r) * 2 + k]) as f32
        })
    }

    fn each_value<'a>(t: &'a RgbImage, r: &'a RgbImage) -> impl Iterator<Item = f64> + 'a {
        t.pixels.iter().zip(&r.pixels).flat_map(|(a, b)| (0..3).map(move |c| f64::from(a[c]) - f64::from(b[c])))
    }

    /// The fraction of `trials` whose interval covers `truth`, and the mean ratio of the removed
    /// bias to the true bias of the plain score of the means.
    fn coverage(
        trials: u64,
        replicates: usize,
        exponent: BiasExponent,
        truth: f64,
        make: impl Fn(u64, usize) -> Replicates,
        score: &(dyn Fn(&RgbImage, &RgbImage) -> Result<f64> + Sync),
    ) -> (f64, f64) {
        let (mut hits, mut removed, mut raw) = (0, 0.0, 0.0);
        for t in 0..trials {
            let reps = make(1000 + t, replicates);
            let e = replicated_estimate(&reps, 1, exponent, score).unwrap();
            hits += ((e.value - truth).abs() <= e.ci95.unwrap()) as u64;
            removed += e.noise_bias.unwrap();
            raw += e.value + e.noise_bias.unwrap() - truth;
        }
        (hits as f64 / trials as f64, removed / raw)
    }

    /// At least 95% less three binomial standard deviations.
    fn covers(rate: f64, trials: u64) -> bool {
        rate >= 0.95 - 3.0 * (0.95 * 0.05 / trials as f64).sqrt()
    }

    #[test]
    fn the_interval_of_a_smooth_score_covers_the_truth_at_95_percent() {
        // The mean squared difference: bias 2 sigma^2 / R exactly, far above the jackknife's
        // half-width of the uncorrected score.
        let diff = |p: usize| 0.05 * ((p % 5) as f64 - 2.0);
        let truth = (0..N * N).map(|p| diff(p).powi(2)).sum::<f64>() / (N * N) as f64;
        let mse = |t: &RgbImage, r: &RgbImage| Ok(each_value(t, r).map(|d| d * d).sum::<f64>() / (N * N * 3) as f64);
        let trials = 400;
        let (rate, removed) = coverage(trials, 8, BiasExponent::SMOOTH, truth, |s, nr| noisy(s, nr, 0.1, diff), &mse);
        assert!(covers(rate, trials), "coverage {rate}");
        assert!((removed - 1.0).abs() < 0.05, "removed {removed} of the bias");
        // The uncorrected score with the plain jackknife interval would not cover it.
        let reps = noisy(7, 8, 0.1, diff);
        let e = replicated_estimate(&reps, 1, BiasExponent::SMOOTH, &mse).unwrap();
        assert!(e.bias_above_ci95(), "{e:?}");
    }

    #[test]
    fn the_interval_of_a_kinked_score_covers_the_truth_at_95_percent() {
        // The mean absolute difference, zero on half the values (bias as N^-1/2 there) and
        // well above the noise on the rest (bias as 1/N): the exponent lies in the bracket.
        let diff = |p: usize| if p.is_multiple_of(2) { 0.0f64 } else { 0.3 };
        let truth = (0..N * N).map(|p| diff(p).abs()).sum::<f64>() / (N * N) as f64;
        let mad = |t: &RgbImage, r: &RgbImage| Ok(each_value(t, r).map(f64::abs).sum::<f64>() / (N * N * 3) as f64);
        let trials = 400;
        for sigma in [0.02, 0.1] {
            let (rate, removed) =
                coverage(trials, 8, BiasExponent::KINKED, truth, |s, nr| noisy(s, nr, sigma, diff), &mad);
            assert!(covers(rate, trials), "sigma {sigma}: coverage {rate}");
            assert!((removed - 1.0).abs() < 0.35, "sigma {sigma}: removed {removed} of the bias");
        }
    }

    #[test]
    fn groups_of_unequal_size_keep_the_correction_exact_for_a_smooth_score() {
        // 11 replicates in 8 groups (three of two, five of one): a bias exactly c / N leaves
        // every pseudo-value at the truth.
        let (truth, c, nr) = (2.0f64, 0.3, 11usize);
        let score = |count: usize| truth + c / count as f64;
        let dropped: Vec<(f64, f64)> = (0..8)
            .map(|g| {
                let size = (0..nr).filter(|r| r % 8 == g).count();
                (score(nr - size), (nr - size) as f64 / nr as f64)
            })
            .collect();
        let e = corrected(score(nr), &dropped, BiasExponent::SMOOTH);
        assert!((e.value - truth).abs() < 1e-12 && e.ci95.unwrap() < 1e-12, "{e:?}");
    }
}
