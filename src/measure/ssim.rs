//! SSIM without noise bias, with 95% intervals: the paper's second Table 1 score (Wang et al.
//! 2004, as [`crate::metrics::ssim`] defines it) of the converged images, from R replicates.
//!
//! The SSIM map at a window needs five local second-order quantities: `mu_x^2 + mu_y^2`,
//! `mu_x mu_y`, `E_w[x^2] + E_w[y^2]` and `E_w[xy]` (the variances and the covariance are these
//! minus products of means). Each is estimated from products of *different* replicates, which
//! have no noise bias (for independent unbiased replicates `E[a_r b_s] = a b` when `r != s`):
//!
//! ```text
//! mu_x^2  ~  sum_{r != s} mu_xr mu_xs / (R (R-1)) = [(sum_r mu_xr)^2 - sum_r mu_xr^2] / (R (R-1))
//! mu_x mu_y ~ [(sum_r mu_xr)(sum_r mu_yr) - sum_r mu_xr mu_yr] / (R (R-1))
//! E_w[x^2] ~ window of [(sum_r X_r)^2 - sum_r X_r^2] / (R (R-1)),   E_w[xy] likewise
//! ```
//!
//! with `mu_xr` the windowed mean of replicate `r`. The window is today's (11 x 11 Gaussian,
//! sigma 1.5, 'valid' positions only); the map is averaged per channel, then over channels.
//! Negative estimates of `mu_x^2 + mu_y^2` or of `sigma_x^2 + sigma_y^2` (which cannot be
//! negative; their estimates can, when noise exceeds them) count as 0.
//!
//! The 95% interval is the delete-one jackknife over replicates. Its cost is kept down by
//! filtering each replicate once (the windowed means) and getting every leave-one-out set by
//! subtraction: `sum_{r,s != k, r != s} X_r X_s = T - 2 X_k (S - X_k)` with `S = sum_r X_r`,
//! `T = S^2 - sum_r X_r^2`, so each left-out replicate costs two more filtered planes per
//! scored image and channel. The work runs in bands of window rows (in parallel, summed in band
//! order, so the result does not depend on the thread count).

use rayon::prelude::*;

use super::estimator::Replicates;
use super::stats::{jackknife_estimate, Estimate};
use crate::metrics::{filter_column_valid, filter_row_valid, gaussian_1d, SsimConstants, SSIM_WINDOW};

/// Window rows per parallel task.
const BAND: usize = 64;

/// 'valid' separable filtering of a `rows x width` plane by the SSIM window into `out`
/// (`(rows - 10) x (width - 10)`); `tmp` is scratch.
fn filter_valid<T: Copy + Into<f64>>(
    src: &[T],
    width: usize,
    rows: usize,
    g: &[f64; SSIM_WINDOW],
    tmp: &mut Vec<f64>,
    out: &mut [f64],
) {
    let wv = width - (SSIM_WINDOW - 1);
    tmp.resize(rows * wv, 0.0);
    for y in 0..rows {
        filter_row_valid(&src[y * width..(y + 1) * width], g, &mut tmp[y * wv..(y + 1) * wv]);
    }
    for i in 0..rows - (SSIM_WINDOW - 1) {
        let taps = std::array::from_fn(|k| &tmp[(i + k) * wv..(i + k + 1) * wv]);
        filter_column_valid(taps, g, &mut out[i * wv..(i + 1) * wv]);
    }
}

/// Local sums at one window over the replicates in use: `a = sum mu_x`, `b = sum mu_y`,
/// `axx = sum mu_x^2`, `ayy`, `axy`, the windowed `t = sum_{r != s}(X_r X_s + Y_r Y_s)` and
/// `txy = sum_{r != s} X_r Y_s`; `pairs = R (R - 1)`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn ssim_value(pairs: f64, a: f64, b: f64, axx: f64, ayy: f64, axy: f64, t: f64, txy: f64, c1: f64, c2: f64) -> f64 {
    let inv = 1.0 / pairs;
    let msq = ((a * a - axx) + (b * b - ayy)) * inv;
    let mxy = (a * b - axy) * inv;
    let ssq = (t * inv - msq).max(0.0);
    let sxy = txy * inv - mxy;
    ((2.0 * mxy + c1) * (2.0 * sxy + c2)) / ((msq.max(0.0) + c1) * (ssq + c2))
}

/// Independent partial sums (in a fixed order), so that the additions and divisions of
/// consecutive windows overlap instead of waiting for each other.
const LANES: usize = 4;

/// The sum of `f(w)` over `0..len`, in `LANES` interleaved partial sums added in a fixed order.
#[inline(always)]
fn lane_sum(len: usize, f: impl Fn(usize) -> f64) -> f64 {
    let mut acc = [0.0; LANES];
    let whole = len / LANES * LANES;
    for w0 in (0..whole).step_by(LANES) {
        for (j, a) in acc.iter_mut().enumerate() {
            *a += f(w0 + j);
        }
    }
    for (j, w) in (whole..len).enumerate() {
        acc[j] += f(w);
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// `dst[p] = sum_r f(src[r * len + p])` over the `R` planes of `src`, plane by plane.
fn sum_planes(src: &[f64], len: usize, f: impl Fn(f64) -> f64, dst: &mut [f64]) {
    sum_slices(src.chunks_exact(len), f, dst);
}

/// `dst[p] = sum_r f(planes[r][p])`, plane by plane.
fn sum_slices<'a, T: Copy + Into<f64> + 'a>(
    planes: impl IntoIterator<Item = &'a [T]>,
    f: impl Fn(f64) -> f64,
    dst: &mut [f64],
) {
    dst.iter_mut().for_each(|d| *d = 0.0);
    for plane in planes {
        for (d, v) in dst.iter_mut().zip(plane) {
            *d += f((*v).into());
        }
    }
}

/// Sums of the SSIM map over one band's windows, for every scored image: the full set of
/// replicates and each leave-one-out set. `result[m] = (full, loo[R])`.
fn band_sums(reps: &Replicates, c: usize, i0: usize, i1: usize, c1: f64, c2: f64) -> Vec<(f64, Vec<f64>)> {
    let n = reps.resolution();
    let (nr, ni) = (reps.replicates(), reps.images());
    let g = gaussian_1d();
    let rows = i1 - i0 + SSIM_WINDOW - 1;
    let (wv, hb) = (n - (SSIM_WINDOW - 1), i1 - i0);
    let (plane, wplane) = (rows * n, hb * wv);
    let mut tmp = Vec::new();
    // The band's rows of image k in every replicate, read in place (f32 -> f64 is exact).
    let band = |k: usize| -> Vec<&[f32]> { (0..nr).map(|r| &reps.plane(r, k, c)[i0 * n..i0 * n + plane]).collect() };
    // The reference: its replicates, their windowed means, and S, sum of squares.
    let xs = band(0);
    let mut mux = vec![0.0; nr * wplane];
    for (r, x) in xs.iter().enumerate() {
        filter_valid(x, n, rows, &g, &mut tmp, &mut mux[r * wplane..(r + 1) * wplane]);
    }
    let (mut sx, mut qx) = (vec![0.0; plane], vec![0.0; plane]);
    sum_slices(xs.iter().copied(), |v| v, &mut sx);
    sum_slices(xs.iter().copied(), |v| v * v, &mut qx);
    // Window sums of the reference's windowed means: a = sum mu_x, axx = sum mu_x^2.
    let (mut a, mut axx) = (vec![0.0; wplane], vec![0.0; wplane]);
    sum_planes(&mux, wplane, |v| v, &mut a);
    sum_planes(&mux, wplane, |v| v * v, &mut axx);

    let mut muy = vec![0.0; nr * wplane];
    let (mut sy, mut q, mut q2) = (vec![0.0; plane], vec![0.0; plane], vec![0.0; plane]);
    let (mut b, mut ayy, mut axy) = (vec![0.0; wplane], vec![0.0; wplane], vec![0.0; wplane]);
    let (mut ft, mut ftxy) = (vec![0.0; wplane], vec![0.0; wplane]);
    let (mut f1, mut f2) = (vec![0.0; wplane], vec![0.0; wplane]);
    let full_pairs = (nr * (nr - 1)) as f64;
    let loo_pairs = ((nr - 1) * (nr - 2)) as f64;
    let mut out = Vec::with_capacity(ni - 1);
    for k in 1..ni {
        let ys = band(k);
        for (r, y) in ys.iter().enumerate() {
            filter_valid(y, n, rows, &g, &mut tmp, &mut muy[r * wplane..(r + 1) * wplane]);
        }
        sum_slices(ys.iter().copied(), |v| v, &mut sy);
        sum_planes(&muy, wplane, |v| v, &mut b);
        sum_planes(&muy, wplane, |v| v * v, &mut ayy);
        axy.iter_mut().for_each(|v| *v = 0.0);
        // Full set: T = (Sx^2 - Qx) + (Sy^2 - Qy), Txy = Sx Sy - Pxy.
        sum_slices(ys.iter().copied(), |v| v * v, &mut q);
        q2.iter_mut().for_each(|v| *v = 0.0);
        for r in 0..nr {
            let (x, y) = (xs[r], ys[r]);
            for ((d, u), v) in q2.iter_mut().zip(x).zip(y) {
                *d += f64::from(*u) * f64::from(*v);
            }
            let (mx, my) = (&mux[r * wplane..(r + 1) * wplane], &muy[r * wplane..(r + 1) * wplane]);
            for ((d, u), v) in axy.iter_mut().zip(mx).zip(my) {
                *d += u * v;
            }
        }
        for p in 0..plane {
            q[p] = (sx[p] * sx[p] - qx[p]) + (sy[p] * sy[p] - q[p]);
            q2[p] = sx[p] * sy[p] - q2[p];
        }
        filter_valid(&q, n, rows, &g, &mut tmp, &mut ft);
        filter_valid(&q2, n, rows, &g, &mut tmp, &mut ftxy);
        let full =
            lane_sum(wplane, |w| ssim_value(full_pairs, a[w], b[w], axx[w], ayy[w], axy[w], ft[w], ftxy[w], c1, c2));
        let mut loo = Vec::with_capacity(nr);
        for kk in 0..nr {
            let (x, y) = (xs[kk], ys[kk]);
            for p in 0..plane {
                let (x, y) = (f64::from(x[p]), f64::from(y[p]));
                q[p] = x * (sx[p] - x) + y * (sy[p] - y);
                q2[p] = x * (sy[p] - y) + y * (sx[p] - x);
            }
            filter_valid(&q, n, rows, &g, &mut tmp, &mut f1);
            filter_valid(&q2, n, rows, &g, &mut tmp, &mut f2);
            let (mx, my) = (&mux[kk * wplane..(kk + 1) * wplane], &muy[kk * wplane..(kk + 1) * wplane]);
            loo.push(lane_sum(wplane, |w| {
                ssim_value(
                    loo_pairs,
                    a[w] - mx[w],
                    b[w] - my[w],
                    axx[w] - mx[w] * mx[w],
                    ayy[w] - my[w] * my[w],
                    axy[w] - mx[w] * my[w],
                    ft[w] - 2.0 * f1[w],
                    ftxy[w] - f2[w],
                    c1,
                    c2,
                )
            }));
        }
        out.push((full, loo));
    }
    out
}

/// The cross-replicate SSIM of every scored image `k >= 1` of `reps` against image 0, with
/// jackknife 95% intervals (`result[k - 1]`). Needs at least 3 replicates and an image of at
/// least 11 x 11 pixels.
pub fn ssim_estimates(reps: &Replicates, constants: SsimConstants) -> Vec<Estimate> {
    let n = reps.resolution();
    let nr = reps.replicates();
    assert!(nr >= 3, "the jackknife of cross-replicate products needs at least 3 replicates");
    assert!(n >= SSIM_WINDOW, "SSIM needs at least {SSIM_WINDOW} x {SSIM_WINDOW} pixels");
    let (c1, c2) = constants.c1_c2();
    let hv = n - (SSIM_WINDOW - 1);
    let tasks: Vec<(usize, usize)> = (0..3).flat_map(|c| (0..hv).step_by(BAND).map(move |i0| (c, i0))).collect();
    let results: Vec<Vec<(f64, Vec<f64>)>> =
        tasks.par_iter().map(|&(c, i0)| band_sums(reps, c, i0, (i0 + BAND).min(hv), c1, c2)).collect();
    let windows = (hv * hv) as f64;
    (1..reps.images())
        .map(|k| {
            let mut full = [0.0; 3];
            let mut loo = vec![[0.0; 3]; nr];
            for (&(c, _), res) in tasks.iter().zip(&results) {
                let (f, l) = &res[k - 1];
                full[c] += f;
                for (dst, v) in loo.iter_mut().zip(l) {
                    dst[c] += v;
                }
            }
            let full = full.map(|v| v / windows);
            let loo: Vec<[f64; 3]> = loo.iter().map(|v| v.map(|x| x / windows)).collect();
            jackknife_estimate(full, &loo)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::ssim;

    /// A source-free `Replicates` filled from closures (tests only).
    fn replicates(n: usize, nr: usize, f: impl Fn(usize, usize, usize, usize) -> f32) -> Replicates {
        Replicates::from_fn(n, nr, 2, 1, f)
    }

    fn pattern(p: usize, c: usize, shift: f32) -> f32 {
        let (y, x) = ((p / 24) as f32, (p % 24) as f32);
        (0.5 + 0.4 * ((x + shift) * 0.7 + c as f32).sin() * (y * 0.3).cos()).clamp(0.0, 1.0)
    }

    #[test]
    fn identical_replicates_give_the_ordinary_ssim() {
        let n = 24;
        let reps = replicates(n, 4, |p, _, k, c| pattern(p, c, k as f32 * 0.8));
        let e = ssim_estimates(&reps, SsimConstants::Wang2004)[0];
        let (a, b) = (reps.replicate_image(0, 0), reps.replicate_image(1, 0));
        let want = ssim(&b, &a, SsimConstants::Wang2004).unwrap();
        for c in 0..3 {
            assert!((e.channels[c] - want.channels[c]).abs() < 1e-12, "{c}: {} vs {}", e.channels[c], want.channels[c]);
        }
        // No spread between replicates: a zero-width interval.
        assert!(e.ci95.unwrap() < 1e-12);
    }

    #[test]
    fn leave_one_out_by_subtraction_equals_recomputation() {
        let n = 20;
        let nr = 5;
        let noise = |p: usize, r: usize, k: usize, c: usize| {
            let h = super::super::sampler::mix64((p * 131 + r * 17 + k * 7 + c) as u64);
            ((h >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.2
        };
        let f = |p: usize, r: usize, k: usize, c: usize| pattern(p, c, k as f32 * 0.5) + noise(p, r, k, c);
        let reps = replicates(n, nr, f);
        let all = ssim_estimates(&reps, SsimConstants::Wang2004)[0];
        // Recompute every leave-one-out set from scratch, then jackknife by hand.
        let mut loo = Vec::new();
        for k in 0..nr {
            let sub = replicates(n, nr - 1, |p, r, i, c| f(p, if r < k { r } else { r + 1 }, i, c));
            loo.push(ssim_estimates(&sub, SsimConstants::Wang2004)[0].channels);
        }
        let by_hand = jackknife_estimate(all.channels, &loo);
        assert!((by_hand.ci95.unwrap() - all.ci95.unwrap()).abs() < 1e-12, "{by_hand:?} {all:?}");
        for c in 0..3 {
            let (h, a) = (by_hand.channels_ci95.unwrap()[c], all.channels_ci95.unwrap()[c]);
            assert!((h - a).abs() < 1e-12 && a > 0.0, "{h} {a}");
        }
    }
}
