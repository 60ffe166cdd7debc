//! Scores without noise bias, with 95% intervals: the statistics of the converged measurement
//! (the paper's Table 1 scores, PSNR and SSIM, of the converged images).
//!
//! With R independent replicates, let `X_r` and `Y_r` be a pixel's ground truth and a method's
//! perceived value in replicate `r` (one channel), and `D_r = Y_r - X_r`. Each `D_r` is an
//! unbiased estimate of the converged difference `d`, and for `r != s` the noises are
//! independent, so `E[D_r D_s] = d^2`. Hence
//!
//! ```text
//! MSE_hat = mean over pixels of  [ (sum_r D_r)^2 - sum_r D_r^2 ] / (R (R - 1))
//! ```
//!
//! is unbiased for the converged MSE at any number of samples, whereas the MSE of the mean image
//! (the naive estimate) adds the noise's variance. It is computed from the per-channel R x R Gram
//! matrix `G_rs = sum_pixels D_r D_s` (summed row by row in row order), so the leave-one-out
//! estimates drop a row and a column of `G`, with no second pass over the pixels.
//!
//! PSNR per channel is `-10 log10(MSE_hat)` (peak 1), the image PSNR the mean of the channels.
//! Every reported quantity (each channel and the mean) gets a 95% interval from the delete-one
//! jackknife over replicates: half-width `t(0.975, R - 1) * SE_jack`.
//!
//! **Equal up to noise.** When `MSE_hat <= 0` (the images differ by less than the noise can
//! show) or a leave-one-out estimate is, the log scale has no interval. The interval is then
//! taken on the MSE scale: the MSE's upper end `MSE_hat + t SE_jack(MSE)` gives the PSNR's lower
//! end `low`. The PSNR reported is `inf` when `MSE_hat <= 0` (else its value), and `ci95` is the
//! distance from it down to `low` (`inf` for an `inf` PSNR with a finite `low`; 0 when every
//! replicate's difference is exactly 0: identical images). Nothing is ever NaN.

use rayon::prelude::*;
use serde::ser::SerializeStruct;
use serde::Serialize;

use super::estimator::Replicates;

/// A score (PSNR in dB or SSIM) per channel (R, G, B) and their mean, with the half-widths of
/// their 95% intervals when the estimator knows its error (`None` for the grid estimator).
/// In JSON an infinite value is written as the string `"inf"` (JSON has no infinity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Per channel: R, G, B.
    pub channels: [f64; 3],
    /// Mean of the channels.
    pub mean: f64,
    /// Half-width of the 95% interval of `mean`.
    pub ci95: Option<f64>,
    /// Half-widths of the 95% intervals of `channels`.
    pub channels_ci95: Option<[f64; 3]>,
}

impl Estimate {
    /// A score with no known error (the grid estimator).
    pub fn exact(channels: [f64; 3], mean: f64) -> Self {
        Self { channels, mean, ci95: None, channels_ci95: None }
    }
}

impl From<crate::metrics::Psnr> for Estimate {
    fn from(p: crate::metrics::Psnr) -> Self {
        Self::exact(p.channels, p.mean)
    }
}

impl From<crate::metrics::Ssim> for Estimate {
    fn from(s: crate::metrics::Ssim) -> Self {
        Self::exact(s.channels, s.mean)
    }
}

/// A number for JSON: finite as is, infinite as `"inf"` / `"-inf"`.
struct Num(f64);

impl Serialize for Num {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.is_finite() {
            s.serialize_f64(self.0)
        } else if self.0 > 0.0 {
            s.serialize_str("inf")
        } else if self.0 < 0.0 {
            s.serialize_str("-inf")
        } else {
            s.serialize_str("nan")
        }
    }
}

impl Serialize for Estimate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let n = 2 + self.ci95.is_some() as usize + self.channels_ci95.is_some() as usize;
        let mut st = s.serialize_struct("Estimate", n)?;
        st.serialize_field("channels", &self.channels.map(Num))?;
        st.serialize_field("mean", &Num(self.mean))?;
        if let Some(h) = self.ci95 {
            st.serialize_field("ci95", &Num(h))?;
        }
        if let Some(h) = self.channels_ci95 {
            st.serialize_field("channels_ci95", &h.map(Num))?;
        }
        st.end()
    }
}

/// The two-sided 95% quantile of Student's t with `nu` degrees of freedom, `t(0.975, nu)`,
/// by bisection on the closed-form distribution function for integer `nu` (Abramowitz and
/// Stegun 26.7.3-4). `nu = 0` gives infinity.
pub fn t_quantile_975(nu: usize) -> f64 {
    if nu == 0 {
        return f64::INFINITY;
    }
    let (mut lo, mut hi) = (0.0f64, 1e3f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t_central_probability(mid, nu) < 0.95 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `P(|T| <= t)` for Student's t with integer `nu >= 1` degrees of freedom.
fn t_central_probability(t: f64, nu: usize) -> f64 {
    let theta = (t / (nu as f64).sqrt()).atan();
    let (s, c) = theta.sin_cos();
    let c2 = c * c;
    if nu % 2 == 1 {
        // (2/pi) [theta + sin(theta) (cos + 2/3 cos^3 + ... + (2 4 .. (nu-3))/(1 3 .. (nu-2)) cos^(nu-2))]
        let mut sum = 0.0;
        if nu > 1 {
            let mut term = c;
            sum = term;
            let mut j = 1;
            while 2 * j + 1 < nu {
                term *= c2 * (2 * j) as f64 / (2 * j + 1) as f64;
                sum += term;
                j += 1;
            }
        }
        std::f64::consts::FRAC_2_PI * (theta + s * sum)
    } else {
        // sin(theta) [1 + 1/2 cos^2 + (1 3)/(2 4) cos^4 + ... + (1 3 .. (nu-3))/(2 4 .. (nu-2)) cos^(nu-2)]
        let mut term = 1.0;
        let mut sum = 1.0;
        let mut j = 1;
        while 2 * j < nu {
            term *= c2 * (2 * j - 1) as f64 / (2 * j) as f64;
            sum += term;
            j += 1;
        }
        s * sum
    }
}

/// Delete-one jackknife standard error of a statistic from its leave-one-out values:
/// `sqrt((R - 1)/R * sum_k (theta_k - mean_k theta_k)^2)`.
pub fn jackknife_se(loo: &[f64]) -> f64 {
    let r = loo.len() as f64;
    let mean = loo.iter().sum::<f64>() / r;
    ((r - 1.0) / r * loo.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>()).sqrt()
}

/// The 95% half-width of a statistic from its leave-one-out values: `t(0.975, R-1) SE_jack`.
pub fn jackknife_ci95(loo: &[f64]) -> f64 {
    t_quantile_975(loo.len() - 1) * jackknife_se(loo)
}

/// Per-channel R x R Gram matrices of the differences `D_r = Y_r - X_r` of one scored image
/// against the reference, summed over pixels, and the pixel count.
#[derive(Clone, Debug, PartialEq)]
pub struct Gram {
    /// R: replicates.
    pub replicates: usize,
    /// Pixels summed over.
    pub pixels: usize,
    /// `[channel][r * R + s]`, symmetric.
    pub g: [Vec<f64>; 3],
}

impl Gram {
    /// The unbiased MSE of channel `c` over the replicates whose `keep` is true (at least 2).
    pub fn mse(&self, c: usize, keep: impl Fn(usize) -> bool) -> f64 {
        let r = self.replicates;
        let mut off = 0.0;
        let mut m = 0usize;
        for a in 0..r {
            if !keep(a) {
                continue;
            }
            m += 1;
            for b in a + 1..r {
                if keep(b) {
                    off += self.g[c][a * r + b];
                }
            }
        }
        2.0 * off / ((m * (m - 1)) as f64 * self.pixels as f64)
    }

    /// The MSE of the replicates' mean image (the naive, noise-biased estimate) of channel `c`.
    pub fn naive_mse(&self, c: usize) -> f64 {
        let r = self.replicates as f64;
        self.g[c].iter().sum::<f64>() / (r * r * self.pixels as f64)
    }
}

/// The Gram matrix of every scored image `k >= 1` against image 0 of `reps` (`result[k - 1]`).
/// Rows are summed in parallel and added in row order: the same bits at any thread count.
pub fn gram_matrices(reps: &Replicates) -> Vec<Gram> {
    let n = reps.resolution();
    let (nr, ni) = (reps.replicates(), reps.images());
    let per_row: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|row| {
            // [image - 1][channel][a * R + b], upper triangle.
            let mut g = vec![0.0f64; (ni - 1) * 3 * nr * nr];
            let mut d = vec![0.0f64; n * nr];
            let span = row * n..(row + 1) * n;
            for k in 1..ni {
                for c in 0..3 {
                    // d[pixel][r] for this row.
                    for r in 0..nr {
                        let (x, y) = (&reps.plane(r, 0, c)[span.clone()], &reps.plane(r, k, c)[span.clone()]);
                        for (p, (a, b)) in x.iter().zip(y).enumerate() {
                            d[p * nr + r] = f64::from(*b) - f64::from(*a);
                        }
                    }
                    let gm = &mut g[((k - 1) * 3 + c) * nr * nr..((k - 1) * 3 + c + 1) * nr * nr];
                    for dp in d.chunks_exact(nr) {
                        for a in 0..nr {
                            let da = dp[a];
                            for (g, db) in gm[a * nr + a..(a + 1) * nr].iter_mut().zip(&dp[a..]) {
                                *g += da * db;
                            }
                        }
                    }
                }
            }
            g
        })
        .collect();
    (1..ni)
        .map(|k| {
            let g = std::array::from_fn(|c| {
                let mut m = vec![0.0f64; nr * nr];
                for row in &per_row {
                    let src = &row[((k - 1) * 3 + c) * nr * nr..((k - 1) * 3 + c + 1) * nr * nr];
                    for (a, b) in m.iter_mut().zip(src) {
                        *a += b;
                    }
                }
                for a in 0..nr {
                    for b in 0..a {
                        m[a * nr + b] = m[b * nr + a];
                    }
                }
                m
            });
            Gram { replicates: nr, pixels: n * n, g }
        })
        .collect()
}

/// PSNR in dB of an MSE (peak 1); `inf` for a non-positive MSE.
fn db(mse: f64) -> f64 {
    if mse > 0.0 {
        -10.0 * mse.log10()
    } else {
        f64::INFINITY
    }
}

/// The PSNR of one scored image with its 95% intervals (module comment).
pub fn psnr_estimate(gram: &Gram) -> Estimate {
    let r = gram.replicates;
    let t = t_quantile_975(r - 1);
    let mut channels = [0.0; 3];
    let mut half = [0.0; 3];
    let mut low = [0.0; 3];
    let mut loo_db = vec![[0.0f64; 3]; r];
    let mut regular = true;
    for c in 0..3 {
        let full = gram.mse(c, |_| true);
        let loo: Vec<f64> = (0..r).map(|k| gram.mse(c, |a| a != k)).collect();
        channels[c] = db(full);
        if full > 0.0 && loo.iter().all(|&m| m > 0.0) {
            for (k, m) in loo.iter().enumerate() {
                loo_db[k][c] = db(*m);
            }
            let col: Vec<f64> = loo_db.iter().map(|v| v[c]).collect();
            half[c] = t * jackknife_se(&col);
            low[c] = channels[c] - half[c];
        } else {
            regular = false;
            let upper = full + t * jackknife_se(&loo);
            low[c] = db(upper);
            half[c] = if low[c] == f64::INFINITY { 0.0 } else { channels[c] - low[c] };
        }
    }
    let mean = channels.iter().sum::<f64>() / 3.0;
    let ci95 = if regular {
        let loo_mean: Vec<f64> = loo_db.iter().map(|v| v.iter().sum::<f64>() / 3.0).collect();
        t * jackknife_se(&loo_mean)
    } else {
        let low_mean = low.iter().sum::<f64>() / 3.0;
        if low_mean == f64::INFINITY {
            0.0
        } else {
            mean - low_mean
        }
    };
    Estimate { channels, mean, ci95: Some(ci95), channels_ci95: Some(half) }
}

/// An SSIM (or any bounded score) with its 95% intervals from its full-sample values and its
/// leave-one-out values `loo[k][channel]`.
pub fn jackknife_estimate(channels: [f64; 3], loo: &[[f64; 3]]) -> Estimate {
    let half = std::array::from_fn(|c| jackknife_ci95(&loo.iter().map(|v| v[c]).collect::<Vec<_>>()));
    let loo_mean: Vec<f64> = loo.iter().map(|v| v.iter().sum::<f64>() / 3.0).collect();
    Estimate {
        channels,
        mean: channels.iter().sum::<f64>() / 3.0,
        ci95: Some(jackknife_ci95(&loo_mean)),
        channels_ci95: Some(half),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_match_the_tables() {
        for (nu, t) in [(1, 12.7062), (2, 4.3027), (3, 3.1824), (4, 2.7764), (7, 2.3646), (9, 2.2622), (30, 2.0423)] {
            assert!((t_quantile_975(nu) - t).abs() < 1e-4, "{nu}: {}", t_quantile_975(nu));
        }
        assert!((t_quantile_975(100_000) - 1.95997).abs() < 1e-4);
    }

    #[test]
    fn jackknife_of_the_mean_is_the_classical_standard_error() {
        let x = [0.3, 1.7, -0.4, 2.2, 0.9, 1.1, -1.3];
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let s2 = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
        let loo: Vec<f64> = (0..x.len()).map(|k| (x.iter().sum::<f64>() - x[k]) / (n - 1.0)).collect();
        assert!((jackknife_se(&loo) - (s2 / n).sqrt()).abs() < 1e-14);
        // And of the (unbiased) variance: a known closed form is not needed; it must be positive
        // and scale with the data.
        let loo2: Vec<f64> = loo.iter().map(|v| 2.0 * v).collect();
        assert!((jackknife_se(&loo2) - 2.0 * jackknife_se(&loo)).abs() < 1e-14);
    }

    fn toy_gram(d: &[Vec<[f64; 3]>]) -> Gram {
        // d[pixel][replicate][channel]
        let r = d[0].len();
        let g = std::array::from_fn(|c| {
            let mut m = vec![0.0; r * r];
            for px in d {
                for a in 0..r {
                    for b in 0..r {
                        m[a * r + b] += px[a][c] * px[b][c];
                    }
                }
            }
            m
        });
        Gram { replicates: r, pixels: d.len(), g }
    }

    #[test]
    fn gram_mse_equals_the_direct_formula_and_leave_one_out_equals_recomputation() {
        let mut s = 1u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (pixels, r) = (50, 6);
        let d: Vec<Vec<[f64; 3]>> =
            (0..pixels).map(|_| (0..r).map(|_| [next(), next() + 0.3, next() * 0.1]).collect()).collect();
        let gram = toy_gram(&d);
        let direct = |c: usize, keep: &dyn Fn(usize) -> bool| {
            let m = (0..r).filter(|&a| keep(a)).count() as f64;
            d.iter()
                .map(|px| {
                    let sum: f64 = (0..r).filter(|&a| keep(a)).map(|a| px[a][c]).sum();
                    let sq: f64 = (0..r).filter(|&a| keep(a)).map(|a| px[a][c] * px[a][c]).sum();
                    (sum * sum - sq) / (m * (m - 1.0))
                })
                .sum::<f64>()
                / pixels as f64
        };
        for c in 0..3 {
            assert!((gram.mse(c, |_| true) - direct(c, &|_| true)).abs() < 1e-14);
            for k in 0..r {
                // Leave-one-out by dropping a row and column equals recomputing without k.
                let sub: Vec<Vec<[f64; 3]>> = d
                    .iter()
                    .map(|px| px.iter().enumerate().filter(|(a, _)| *a != k).map(|(_, v)| *v).collect())
                    .collect();
                let re = toy_gram(&sub).mse(c, |_| true);
                assert!((gram.mse(c, |a| a != k) - re).abs() < 1e-14);
                assert!((re - direct(c, &|a| a != k)).abs() < 1e-14);
            }
            // The naive MSE is that of the mean difference.
            let naive: f64 = d
                .iter()
                .map(|px| {
                    let m = px.iter().map(|v| v[c]).sum::<f64>() / r as f64;
                    m * m
                })
                .sum::<f64>()
                / pixels as f64;
            assert!((gram.naive_mse(c) - naive).abs() < 1e-14);
        }
    }

    #[test]
    fn psnr_of_identical_and_noise_equal_images_is_never_nan() {
        // Identical images: every difference exactly 0.
        let zero = toy_gram(&vec![vec![[0.0; 3]; 4]; 10]);
        let e = psnr_estimate(&zero);
        assert_eq!(e.mean, f64::INFINITY);
        assert_eq!(e.ci95, Some(0.0));
        // Pure noise of zero mean: the unbiased MSE can be negative; PSNR inf or large, never NaN.
        let d: Vec<Vec<[f64; 3]>> = (0..20)
            .map(|p| (0..5).map(|r| [((p * 7 + r * 3) % 5) as f64 - 2.0, 0.0, 1e-3 * (r as f64 - 2.0)]).collect())
            .collect();
        let e = psnr_estimate(&toy_gram(&d));
        assert!(!e.mean.is_nan() && !e.ci95.unwrap().is_nan(), "{e:?}");
        assert!(e.channels_ci95.unwrap().iter().all(|h| !h.is_nan()));
        let json = serde_json::to_string(&e).unwrap();
        assert!(!json.contains("null") && !json.contains("NaN"), "{json}");
    }
}
