//! Perceptual scores of the converged measurement's replicates, with 95% intervals and the bias
//! that the estimator's noise leaves in them.
//!
//! ColorVideoVDP and FLIP are not quadratic in the images, so the cross-replicate products that
//! free PSNR and SSIM of noise bias (`measure/stats.rs`, `measure/ssim.rs`) do not apply. Each is
//! computed on the replicates' mean images (the ground truth's and the method's, paired: the
//! same eye rays), whose noise the metric sees as distortion: JOD is biased down and FLIP up, by
//! an amount that falls with the samples taken (for noise far below the metric's threshold, as
//! a power of the noise's standard deviation). The 95% interval is the delete-one jackknife over
//! replicates (the score of the means without replicate `k`), half-width `t(0.975, R - 1)
//! SE_jack`, as for PSNR. The bias is measured from the score's change from half the replicates
//! to all of them: with a bias `b N^-a`, the mean score of the two halves minus the full score is
//! `(2^a - 1) b N^-a`, so the bias of the reported value is that change over `2^a - 1`.
//! ColorVideoVDP pools squared band differences (its bias goes as the noise's variance, `a = 1`);
//! FLIP's error is close to linear in the colour difference's magnitude (its bias goes as the
//! noise's standard deviation, `a = 1/2`); `tests/perception.rs` checks both against the true bias
//! of a synthetic case. `docs/PERCEPTION.md` shows the bias below the interval in the paper's
//! experiment.

use rayon::prelude::*;
use serde::ser::SerializeStruct;
use serde::Serialize;

use crate::error::Result;
use crate::measure::estimator::Replicates;
use crate::measure::stats::jackknife_ci95;
use crate::raster::RgbImage;

/// One scalar score with its 95% half-width and its estimated noise bias (`None` for the grid
/// estimator, which has neither).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalarEstimate {
    /// The score of the images (the replicates' means).
    pub value: f64,
    /// Half-width of its 95% interval.
    pub ci95: Option<f64>,
    /// Its estimated bias from the estimator's noise, `value` minus the converged score: the
    /// mean score of the two halves of the replicates minus `value` (module comment).
    pub noise_bias: Option<f64>,
}

impl ScalarEstimate {
    /// A score with no known error (the grid estimator, or two plain images).
    pub fn exact(value: f64) -> Self {
        Self { value, ci95: None, noise_bias: None }
    }
}

impl Serialize for ScalarEstimate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let n = 1 + self.ci95.is_some() as usize + self.noise_bias.is_some() as usize;
        let mut st = s.serialize_struct("ScalarEstimate", n)?;
        let num = |v: f64| if v.is_finite() { serde_json::json!(v) } else { serde_json::json!(format!("{v}")) };
        st.serialize_field("value", &num(self.value))?;
        if let Some(h) = self.ci95 {
            st.serialize_field("ci95", &num(h))?;
        }
        if let Some(b) = self.noise_bias {
            st.serialize_field("noise_bias", &num(b))?;
        }
        st.end()
    }
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

/// The image of `sum / count`, less replicate `r` when given.
fn mean_of(n: usize, sum: &[[f64; 3]], less: Option<(&Replicates, usize, usize)>, count: usize) -> RgbImage {
    let inv = 1.0 / count as f64;
    let mut img = RgbImage::new(n, n);
    img.pixels.par_chunks_mut(n).enumerate().for_each(|(row, px)| {
        for (j, p) in px.iter_mut().enumerate() {
            let i = row * n + j;
            *p = std::array::from_fn(|c| {
                let s = sum[i][c] - less.map_or(0.0, |(reps, r, k)| f64::from(reps.plane(r, k, c)[i]));
                (s * inv) as f32
            });
        }
    });
    img
}

/// `score(test, reference)` of image `k` of `reps` against image 0: on the means of all
/// replicates, with its jackknife interval and its noise bias (module comment). `R + 3` scores.
pub fn replicated_estimate(
    reps: &Replicates,
    k: usize,
    noise_exponent: f64,
    score: &(dyn Fn(&RgbImage, &RgbImage) -> Result<f64> + Sync),
) -> Result<ScalarEstimate> {
    let (n, nr) = (reps.resolution(), reps.replicates());
    let (s0, sk) = (sums(reps, 0, |_| true), sums(reps, k, |_| true));
    let value = score(&mean_of(n, &sk, None, nr), &mean_of(n, &s0, None, nr))?;
    let loo: Vec<f64> = (0..nr)
        .map(|r| score(&mean_of(n, &sk, Some((reps, r, k)), nr - 1), &mean_of(n, &s0, Some((reps, r, 0)), nr - 1)))
        .collect::<Result<_>>()?;
    let half = nr / 2;
    let mut halves = 0.0;
    for part in [0..half, half..nr] {
        let count = part.len();
        let keep = |r: usize| part.contains(&r);
        let (h0, hk) = (sums(reps, 0, keep), sums(reps, k, keep));
        halves += score(&mean_of(n, &hk, None, count), &mean_of(n, &h0, None, count))? / 2.0;
    }
    let bias = (halves - value) / (2f64.powf(noise_exponent) - 1.0);
    Ok(ScalarEstimate { value, ci95: Some(jackknife_ci95(&loo)), noise_bias: Some(bias) })
}
