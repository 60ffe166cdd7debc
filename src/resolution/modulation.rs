//! Contrast from a measured window (issue 13's two MTF measurements, the paper's suggested
//! "Fourier domain analysis"), each with a 95% interval from the replicates (delete-one
//! jackknife, `t(0.975, R - 1)`).
//!
//! - [`grating_contrast`]: the window's Fourier coefficient at the grating's own frequency
//!   along x over the mean, divided by the target's contrast. The window holds a whole number of
//!   periods, so power that sampling aliases to other frequencies does not count.
//! - [`edge_mtf`]: ISO 12233 slanted edge: per-row edge centroids of the x-derivative, a line
//!   fit, every pixel's distance across the edge binned at a quarter pixel (the edge-spread
//!   function), its derivative (the line-spread function) under a Hamming window, and the
//!   discrete Fourier transform at the asked frequencies, normalised at zero and corrected for
//!   the derivative's own response; MTF50 where it first falls to 0.5.

use std::f64::consts::TAU;

use super::window::WindowSamples;
use crate::measure::stats::jackknife_ci95;

/// A value with the half-width of its 95% interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Value {
    pub value: f64,
    pub ci95: f64,
}

/// `f` of all replicates, with the jackknife interval from `f` of every leave-one-out set.
fn jackknife(replicates: usize, f: impl Fn(&dyn Fn(usize) -> bool) -> f64) -> Value {
    let value = f(&|_| true);
    let loo: Vec<f64> = (0..replicates).map(|out| f(&|r| r != out)).collect();
    let ci95 = if loo.iter().all(|v| v.is_finite()) { jackknife_ci95(&loo) } else { f64::NAN };
    Value { value, ci95 }
}

/// Source `k`'s modulation at `frequency_cpd` along x in window `w` (pixels `1 / ppd` degrees),
/// over the target's `contrast`: 1 for a perfect eye and display (less the retina pixel's own
/// box response).
pub fn grating_contrast(w: &WindowSamples, k: usize, frequency_cpd: f64, ppd: f64, contrast: f64) -> Value {
    // Per replicate: column sums, then the coefficient (a, b) and the mean.
    let cols = w.cols;
    let phase: Vec<(f64, f64)> = (0..cols).map(|c| (TAU * frequency_cpd * (c as f64 + 0.5) / ppd).sin_cos()).collect();
    let per: Vec<[f64; 3]> = (0..w.replicates)
        .map(|r| {
            let plane = w.plane(r, k);
            let mut col = vec![0.0f64; cols];
            for row in plane.chunks_exact(cols) {
                for (s, v) in col.iter_mut().zip(row) {
                    *s += f64::from(*v);
                }
            }
            let (mut a, mut b, mut m) = (0.0, 0.0, 0.0);
            for (s, (sin, cos)) in col.iter().zip(&phase) {
                a += s * cos;
                b += s * sin;
                m += s;
            }
            [a, b, m]
        })
        .collect();
    jackknife(w.replicates, |keep| {
        let mut t = [0.0; 3];
        for (_, v) in per.iter().enumerate().filter(|(r, _)| keep(*r)) {
            for j in 0..3 {
                t[j] += v[j];
            }
        }
        // Amplitude 2 |c| / N over the mean m / N.
        2.0 * (t[0] * t[0] + t[1] * t[1]).sqrt() / t[2] / contrast
    })
}

/// The slanted-edge MTF of one image at `frequencies` (cycles per pixel), and its MTF50
/// (cycles per pixel; NaN when it never falls to 0.5 below the pixel Nyquist frequency).
pub fn edge_mtf_of_image(img: &[f64], cols: usize, rows: usize, frequencies: &[f64]) -> (Vec<f64>, f64) {
    let hamming = |i: usize, n: usize| 0.54 - 0.46 * (TAU * i as f64 / (n - 1) as f64).cos();
    // 1. Per row: the centroid of the x-derivative, under a Hamming window.
    let centroids = |center: Option<(f64, f64)>| -> Vec<(f64, f64)> {
        (0..rows)
            .filter_map(|r| {
                let row = &img[r * cols..(r + 1) * cols];
                let (mut s, mut sx) = (0.0, 0.0);
                for c in 0..cols - 1 {
                    let d = row[c + 1] - row[c];
                    let x = c as f64 + 1.0;
                    let wgt = match center {
                        // Re-window around the fitted line: a Hamming window of the row's width.
                        Some((a, b)) => {
                            let mid = a + b * r as f64;
                            let u = (x - mid) / cols as f64 + 0.5;
                            if (0.0..=1.0).contains(&u) {
                                0.54 - 0.46 * (TAU * u).cos()
                            } else {
                                0.0
                            }
                        }
                        None => hamming(c, cols - 1),
                    };
                    s += d * wgt;
                    sx += d * wgt * x;
                }
                (s.abs() > 1e-12).then(|| (r as f64 + 0.5, sx / s))
            })
            .collect()
    };
    let fit = |pts: &[(f64, f64)]| -> Option<(f64, f64)> {
        let n = pts.len() as f64;
        if n < 2.0 {
            return None;
        }
        let (my, mx) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
        let syy: f64 = pts.iter().map(|p| (p.0 - my).powi(2)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - my) * (p.1 - mx)).sum();
        let b = sxy / syy;
        // Row r (0-based, centre r + 0.5): x = a + b r in pixel-edge coordinates.
        Some((mx - b * my + 0.5 * b, b))
    };
    let nan = (vec![f64::NAN; frequencies.len()], f64::NAN);
    let Some(first) = fit(&centroids(None)) else { return nan };
    let Some((a, b)) = fit(&centroids(Some(first))) else { return nan };
    // 2. Edge-spread function: each pixel centre's distance across the edge, quarter-pixel bins.
    let cos = 1.0 / (1.0 + b * b).sqrt();
    let q = 4.0;
    let half = (0.5 * cols as f64 * cos * q).floor() as i64;
    let nb = (2 * half) as usize;
    let mut sum = vec![0.0; nb];
    let mut count = vec![0usize; nb];
    for r in 0..rows {
        let edge = a + b * r as f64;
        for c in 0..cols {
            let d = (c as f64 + 0.5 - edge - 0.5 * b) * cos;
            let bin = (d * q).floor() as i64 + half;
            if (0..nb as i64).contains(&bin) {
                sum[bin as usize] += img[r * cols + c];
                count[bin as usize] += 1;
            }
        }
    }
    let mut esf: Vec<Option<f64>> = sum.iter().zip(&count).map(|(s, &n)| (n > 0).then(|| s / n as f64)).collect();
    // Empty bins: the nearest filled neighbour on each side, averaged.
    let filled: Vec<usize> = (0..nb).filter(|&i| esf[i].is_some()).collect();
    if filled.len() < 4 {
        return nan;
    }
    for i in 0..nb {
        if esf[i].is_none() {
            let lo = filled.iter().rev().find(|&&j| j < i).copied();
            let hi = filled.iter().find(|&&j| j > i).copied();
            esf[i] = match (lo, hi) {
                (Some(l), Some(h)) => Some(0.5 * (esf[l].unwrap_or(0.0) + esf[h].unwrap_or(0.0))),
                (Some(l), None) => esf[l],
                (None, Some(h)) => esf[h],
                (None, None) => Some(0.0),
            };
        }
    }
    let esf: Vec<f64> = esf.into_iter().map(|v| v.unwrap_or(0.0)).collect();
    // 3. Line-spread function: central differences, Hamming window centred on its centroid.
    let mut lsf = vec![0.0; nb];
    for i in 1..nb - 1 {
        lsf[i] = 0.5 * (esf[i + 1] - esf[i - 1]);
    }
    let (s, sx) = lsf.iter().enumerate().fold((0.0, 0.0), |(s, sx), (i, v)| (s + v, sx + v * i as f64));
    if s.abs() < 1e-12 {
        return nan;
    }
    let centre = sx / s;
    let width = nb as f64;
    for (i, v) in lsf.iter_mut().enumerate() {
        let u = (i as f64 - centre) / width + 0.5;
        *v *= if (0.0..=1.0).contains(&u) { 0.54 - 0.46 * (TAU * u).cos() } else { 0.0 };
    }
    // 4. DFT at any frequency (cycles per pixel), normalised at 0, with the central
    //    difference's response sin(2 pi f h) / (2 pi f h), h = 1/4 pixel, divided out.
    let dc: f64 = lsf.iter().sum();
    let mtf_at = |f: f64| -> f64 {
        let (mut re, mut im) = (0.0, 0.0);
        for (i, v) in lsf.iter().enumerate() {
            let (sn, cs) = (TAU * f * (i as f64 - centre) / q).sin_cos();
            re += v * cs;
            im += v * sn;
        }
        let x = TAU * f / q;
        let diff = if x.abs() < 1e-9 { 1.0 } else { x.sin() / x };
        (re * re + im * im).sqrt() / dc.abs() / diff.max(0.1)
    };
    let values = frequencies.iter().map(|&f| mtf_at(f)).collect();
    // MTF50: the first fall below 0.5 on a grid of 1/128 cycle per pixel up to the pixel
    // Nyquist frequency, interpolated linearly.
    let n = 64;
    let mut prev = (0.0, 1.0);
    let mut mtf50 = f64::NAN;
    for i in 1..=n {
        let f = 0.5 * i as f64 / n as f64;
        let m = mtf_at(f);
        if m < 0.5 {
            mtf50 = prev.0 + (prev.1 - 0.5) / (prev.1 - m) * (f - prev.0);
            break;
        }
        prev = (f, m);
    }
    (values, mtf50)
}

/// Source `k`'s slanted-edge MTF in window `w` at `frequencies_cpd`, and its MTF50 (cpd), each
/// with the jackknife interval over the replicates.
pub fn edge_mtf(w: &WindowSamples, k: usize, frequencies_cpd: &[f64], ppd: f64) -> (Vec<Value>, Value) {
    let per_pixel: Vec<f64> = frequencies_cpd.iter().map(|f| f / ppd).collect();
    let run = |keep: &dyn Fn(usize) -> bool| {
        let (v, m) = edge_mtf_of_image(&w.mean_image(k, keep), w.cols, w.rows, &per_pixel);
        (v, m * ppd)
    };
    let full = run(&|_| true);
    let loo: Vec<(Vec<f64>, f64)> = (0..w.replicates).map(|out| run(&|r| r != out)).collect();
    let interval = |xs: Vec<f64>| if xs.iter().all(|v| v.is_finite()) { jackknife_ci95(&xs) } else { f64::NAN };
    let values = (0..frequencies_cpd.len())
        .map(|i| Value { value: full.0[i], ci95: interval(loo.iter().map(|l| l.0[i]).collect()) })
        .collect();
    let mtf50 = Value { value: full.1, ci95: interval(loo.iter().map(|l| l.1).collect()) };
    (values, mtf50)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn window(cols: usize, rows: usize, f: impl Fn(usize, f64, f64) -> f64) -> WindowSamples {
        let reps = 4;
        let mut values = Vec::new();
        for r in 0..reps {
            for row in 0..rows {
                for c in 0..cols {
                    values.push(f(r, c as f64 + 0.5, row as f64 + 0.5) as f32);
                }
            }
        }
        WindowSamples { cols, rows, replicates: reps, sources: 1, values }
    }

    #[test]
    fn a_grating_gives_its_contrast_and_other_frequencies_nothing() {
        let ppd = 64.0;
        // 0.5 + 0.2 cos(2 pi 2 x) + 0.1 cos(2 pi 3 x + 1): contrast 0.4 at 2 cpd, 0.2 at 3 cpd.
        let w = window(128, 4, |r, x, _| {
            let d = x / ppd;
            0.5 + 0.2 * (TAU * 2.0 * d + 0.3).cos() + 0.1 * (TAU * 3.0 * d + 1.0).cos() + 1e-4 * r as f64
        });
        let at = |f: f64| grating_contrast(&w, 0, f, ppd, 1.0);
        assert!((at(2.0).value - 0.4).abs() < 2e-4, "{:?}", at(2.0));
        assert!((at(3.0).value - 0.2).abs() < 2e-4);
        assert!(at(1.5).value < 1e-3 && at(5.0).value < 1e-3);
        assert!(at(2.0).ci95 < 1e-3);
        // Divided by the target's contrast.
        assert!((grating_contrast(&w, 0, 2.0, ppd, 0.8).value - 0.5).abs() < 3e-4);
    }

    #[test]
    fn the_window_coefficient_agrees_with_the_retina_grating_fit() {
        // The same square window as WindowSamples and as Replicates: this module's whole-period
        // Fourier coefficient and resolution::grating's Hann-weighted fit give one contrast.
        use crate::measure::estimator::Replicates;
        let (n, reps) = (64, 4);
        let value = |p: usize, r: usize| {
            let x = (p % n) as f64 + 0.5;
            let y = (p / n) as f64;
            // 4 periods over 64 pixels, contrast 0.3, a little per-replicate noise.
            0.5 * (1.0 + 0.3 * (TAU * 4.0 * x / 64.0 + 0.7).cos()) + 1e-3 * ((p * 7 + r * 13 + y as usize) % 5) as f64
        };
        let w = WindowSamples {
            cols: n,
            rows: n,
            replicates: reps,
            sources: 1,
            values: (0..reps).flat_map(|r| (0..n * n).map(move |p| value(p, r) as f32)).collect(),
        };
        let ours = grating_contrast(&w, 0, 4.0, 64.0, 1.0);
        let replicates = Replicates::from_fn(n, reps, 1, 8, |p, r, _, _| value(p, r) as f32);
        let theirs = crate::resolution::grating::modulation(&replicates, 0, 4.0 / 64.0, 0.0).unwrap();
        assert!((ours.value - 0.3).abs() < 2e-3, "{ours:?}");
        assert!((ours.value - theirs.contrast).abs() < 2e-3, "{ours:?} vs {theirs:?}");
    }

    #[test]
    fn a_sharp_slanted_edge_has_the_pixel_box_mtf() {
        // A pixel-averaged step at 5 degrees: the MTF of the pixel box, |sinc(pi f)| (f in
        // cycles per pixel), within 0.03 up to 0.35 cycles per pixel (0.7 of Nyquist).
        let (cols, rows) = (96, 64);
        let t = 5f64.to_radians().tan();
        let img: Vec<f64> = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64, (i % cols) as f64);
                // Fraction of the pixel right of the edge x = 48 - t (y - 32), 16 x 16 sub-samples.
                let mut s = 0.0;
                for a in 0..16 {
                    for b in 0..16 {
                        let (x, y) = (c + (a as f64 + 0.5) / 16.0, r + (b as f64 + 0.5) / 16.0);
                        s += if x > 48.0 - t * (y - 32.0) { 0.9 } else { 0.1 };
                    }
                }
                s / 256.0
            })
            .collect();
        let fs: Vec<f64> = (1..=7).map(|i| 0.05 * i as f64).collect();
        let (mtf, mtf50) = edge_mtf_of_image(&img, cols, rows, &fs);
        for (f, m) in fs.iter().zip(&mtf) {
            let sinc = (PI * f).sin() / (PI * f);
            assert!((m - sinc).abs() < 0.03, "f {f}: {m} vs {sinc}");
        }
        // sinc(pi f) = 0.5 at f = 0.6034.. cycles per pixel, beyond Nyquist: none below it.
        assert!(mtf50.is_nan(), "{mtf50}");
    }

    #[test]
    fn a_blurred_edge_has_a_lower_mtf50() {
        // An edge blurred by a Gaussian of sigma 3 pixels: MTF exp(-2 pi^2 sigma^2 f^2) (times
        // the pixel box), MTF50 near sqrt(ln 2 / 2) / (pi sigma) = 0.0625 cycles per pixel.
        let (cols, rows, sigma) = (128, 64, 3.0);
        let t = 5f64.to_radians().tan();
        let erf = |x: f64| {
            // Abramowitz and Stegun 7.1.26.
            let s = x.signum();
            let x = x.abs();
            let k = 1.0 / (1.0 + 0.3275911 * x);
            let y = 1.0
                - (((((1.061405429 * k - 1.453152027) * k) + 1.421413741) * k - 0.284496736) * k + 0.254829592)
                    * k
                    * (-x * x).exp();
            s * y
        };
        let cos = 1.0 / (1.0 + t * t).sqrt();
        let img: Vec<f64> = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64 + 0.5, (i % cols) as f64 + 0.5);
                let d = (c - (64.0 - t * (r - 32.0))) * cos;
                0.5 + 0.4 * erf(d / (sigma * 2f64.sqrt()))
            })
            .collect();
        let (_, mtf50) = edge_mtf_of_image(&img, cols, rows, &[0.05]);
        let expected = (2f64.ln() / 2.0).sqrt() / (PI * sigma);
        assert!((mtf50 - expected).abs() < 0.004, "{mtf50} vs {expected}");
    }
}
