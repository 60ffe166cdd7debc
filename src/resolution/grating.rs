//! Grating modulation (measurement (a); the paper's Sec. 4 comparison "in terms of
//! perceived spatial resolution", as the field reports it: contrast in cycles per degree): the
//! contrast of a retinal image at the grating's own frequency, so that contrast aliased into
//! other frequencies is not counted. The one grating analysis: `inimtrace resolution` runs it
//! on each grating window of its chart, the physics tests on it and on whole square retinas
//! (both as [`WindowSamples`]: rectangles of per-replicate grey means, any size and offset).
//!
//! **Estimator.** A least-squares fit of `a + b cos(phi) + s sin(phi)`, with
//! `phi = 2 pi f (x cos(theta) + y sin(theta))` at the grating's known frequency `f` (cycles per
//! retina pixel) and orientation `theta` (pixel coordinates from the window's centre, +y up as
//! in tangent space), every pixel weighted alike. The fit is exact for a sinusoid plus a
//! constant at any frequency, whole number of periods or not (no leakage from the mean, which
//! plain projections suffer at the one or two periods a narrow field holds at 0.5 cpd). When
//! the window holds a whole number of periods (the study's chart makes sure of it) the three
//! functions are orthogonal and the fit is the window's plain Fourier coefficient at `f`, so
//! that the other frequencies of the window's grid (the chart's other gratings, harmonics) add
//! nothing. The fit is linear in the image, so each replicate gives unbiased coefficients. The
//! contrast is `A / a` with `A = sqrt(b^2 + s^2)` (the same as `2 |c| / mean` for the complex
//! Fourier coefficient `c`).
//!
//! Why no taper (a Hann window was tried): the aliases a display makes of a grating near its
//! sampling limit lie within a fraction of a bin of the grating's frequency (6 cpd on the paper
//! display aliases to 5.6 cpd, 0.8 bin on a 2 degree window). The untapered window passes 23% of
//! such a component, a Hann window 65%: on the paper study it read 0.96 instead of 0.72 for PC
//! at 6 cpd, past the display's 5.8 cpd limit. A taper only helps against components many bins
//! away, which the untapered window's sidelobes already damp to a few percent.
//!
//! **Noise bias.** `A^2` of a noisy image is biased up by the noise. With R independent
//! replicates, `A^2` is estimated from cross-replicate products only,
//! `sum_{r != s} (b_r b_s + s_r s_s) / (R (R - 1))`, as the MSE in `measure::stats`; the
//! contrast's 95% interval is the delete-one jackknife over replicates
//! (`measure::stats::jackknife_ci95`). The grating is grey: the fit runs on the mean of R, G
//! and B.

use std::f64::consts::TAU;

use super::window::WindowSamples;
use crate::measure::stats::jackknife_ci95;

/// The modulation of one image at one frequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Modulation {
    /// Michelson contrast at the grating's frequency, from cross-replicate products (no noise
    /// bias); 0 when the noise hides it.
    pub contrast: f64,
    /// Half-width of its 95% interval (jackknife over replicates; infinite when the mean is
    /// not positive).
    pub ci95: f64,
    /// The contrast of the replicates' mean image (biased up by the noise left in it).
    pub naive_contrast: f64,
    /// The image's mean value (the fitted constant, averaged over replicates).
    pub mean: f64,
    /// Phase of the fitted sinusoid at the image centre, degrees (the grating's `phase_deg`
    /// when the image reproduces it; 180 degrees off past a defocus zero).
    pub phase_deg: f64,
}

/// The fit's linear functionals: three weight planes whose dot products with an image give
/// its `a`, `b`, `s`.
pub struct GratingFit {
    weights: [Vec<f64>; 3],
}

impl GratingFit {
    /// The fit for a `width` x `height` image and a grating of `cycles_per_pixel` modulated at
    /// `orientation_deg` (counter-clockwise from +x, +y up: row 0 is the top). `None` when the
    /// three functions cannot be told apart on the image (the frequency is too low for its
    /// size, or the image is empty).
    pub fn new(width: usize, height: usize, cycles_per_pixel: f64, orientation_deg: f64) -> Option<Self> {
        if width == 0 || height == 0 || !cycles_per_pixel.is_finite() || !orientation_deg.is_finite() {
            return None;
        }
        let (sn, cs) = orientation_deg.to_radians().sin_cos();
        let mut basis = vec![[0.0f64; 3]; width * height]; // [1, cos, sin]
        let mut m = [[0.0f64; 3]; 3];
        for r in 0..height {
            let y = 0.5 * height as f64 - (r as f64 + 0.5);
            for c in 0..width {
                let x = c as f64 + 0.5 - 0.5 * width as f64;
                let phi = TAU * cycles_per_pixel * (x * cs + y * sn);
                let (s, co) = phi.sin_cos();
                let b = [1.0, co, s];
                for i in 0..3 {
                    for j in 0..3 {
                        m[i][j] += b[i] * b[j];
                    }
                }
                basis[r * width + c] = b;
            }
        }
        let inv = invert3(m)?;
        let weights = std::array::from_fn(|k| {
            basis.iter().map(|b| inv[k][0] * b[0] + inv[k][1] * b[1] + inv[k][2] * b[2]).collect()
        });
        Some(Self { weights })
    }

    /// The coefficients `[a, b, s]` of a row-major plane of the fit's size.
    pub fn coefficients<T: Copy + Into<f64>>(&self, plane: &[T]) -> [f64; 3] {
        debug_assert_eq!(plane.len(), self.weights[0].len());
        std::array::from_fn(|k| self.weights[k].iter().zip(plane).map(|(w, v)| w * (*v).into()).sum())
    }
}

/// Inverse of a symmetric 3 x 3 matrix; `None` when it is (nearly) singular.
fn invert3(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let scale = m[0][0] * m[1][1] * m[2][2];
    if !(det.is_finite() && det > 1e-10 * scale.abs()) {
        return None;
    }
    Some(std::array::from_fn(|i| std::array::from_fn(|j| c(j, i) / det)))
}

/// Contrast of one image's coefficients `[a, b, s]`, and its phase in degrees.
pub fn contrast_of(coefficients: [f64; 3]) -> (f64, f64) {
    let [a, b, s] = coefficients;
    let contrast = if a > 0.0 { b.hypot(s) / a } else { 0.0 };
    (contrast, (-s).atan2(b).to_degrees())
}

/// The squared amplitude from cross-replicate products (unbiased, can be negative) and the
/// mean, over the replicates `keep` allows (at least two).
fn unbiased_parts(coef: &[[f64; 3]], keep: impl Fn(usize) -> bool) -> (f64, f64) {
    let (mut sum, mut sq, mut m) = ([0.0f64; 3], [0.0f64; 3], 0usize);
    for (r, c) in coef.iter().enumerate() {
        if keep(r) {
            m += 1;
            for k in 0..3 {
                sum[k] += c[k];
                sq[k] += c[k] * c[k];
            }
        }
    }
    let mf = m as f64;
    ((sum[1] * sum[1] - sq[1] + sum[2] * sum[2] - sq[2]) / (mf * (mf - 1.0)), sum[0] / mf)
}

/// The contrast from per-replicate coefficients (NaN when the mean is not positive).
fn unbiased_contrast(coef: &[[f64; 3]], keep: impl Fn(usize) -> bool) -> f64 {
    let (amp2, mean) = unbiased_parts(coef, keep);
    if mean > 0.0 {
        amp2.max(0.0).sqrt() / mean
    } else {
        f64::NAN
    }
}

/// The modulation of source `k` in window `w` at a grating of `cycles_per_pixel` (retina
/// pixels) modulated at `orientation_deg`, phase at the window's centre. `None` when the fit is
/// impossible ([`GratingFit::new`]) or there are fewer than 2 replicates.
pub fn modulation(w: &WindowSamples, k: usize, cycles_per_pixel: f64, orientation_deg: f64) -> Option<Modulation> {
    let nr = w.replicates;
    if nr < 2 {
        return None;
    }
    let fit = GratingFit::new(w.cols, w.rows, cycles_per_pixel, orientation_deg)?;
    let coef: Vec<[f64; 3]> = (0..nr).map(|r| fit.coefficients(w.plane(r, k))).collect();
    let mean_coef: [f64; 3] = std::array::from_fn(|j| coef.iter().map(|c| c[j]).sum::<f64>() / nr as f64);
    let (naive_contrast, phase_deg) = contrast_of(mean_coef);
    let contrast = unbiased_contrast(&coef, |_| true);
    let loo: Vec<f64> = (0..nr).map(|d| unbiased_contrast(&coef, |r| r != d)).collect();
    let (contrast, ci95) = if contrast.is_finite() && loo.iter().all(|v| v.is_finite()) {
        (contrast, if nr > 2 { jackknife_ci95(&loo) } else { f64::INFINITY })
    } else {
        (0.0, f64::INFINITY)
    };
    Some(Modulation { contrast, ci95, naive_contrast, mean: mean_coef[0], phase_deg })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sinusoid `a + A cos(2 pi f n.p + phase)` on an n x n image (pixel centres, +y up).
    fn sinusoid(n: usize, f: f64, theta_deg: f64, a: f64, amp: f64, phase_deg: f64) -> Vec<f64> {
        let (s, c) = theta_deg.to_radians().sin_cos();
        (0..n * n)
            .map(|i| {
                let (r, col) = (i / n, i % n);
                let x = col as f64 + 0.5 - 0.5 * n as f64;
                let y = 0.5 * n as f64 - (r as f64 + 0.5);
                a + amp * (TAU * f * (x * c + y * s) + phase_deg.to_radians()).cos()
            })
            .collect()
    }

    #[test]
    fn the_fit_recovers_a_sinusoid_at_any_frequency_and_ignores_others() {
        // One period over the image, a fractional number of periods, near Nyquist, oblique.
        for (f, theta, phase) in
            [(1.0 / 64.0, 0.0, 30.0), (0.0731, 90.0, -100.0), (0.43, 0.0, 5.0), (0.11, 37.0, 170.0)]
        {
            let img = sinusoid(64, f, theta, 0.5, 0.2, phase);
            let fit = GratingFit::new(64, 64, f, theta).unwrap();
            let (c, ph) = contrast_of(fit.coefficients(&img));
            assert!((c - 0.4).abs() < 1e-10, "{f} {theta}: {c}");
            let dphase = (ph - phase + 540.0).rem_euclid(360.0) - 180.0;
            assert!(dphase.abs() < 1e-8, "{f} {theta}: phase {ph}");
        }
        // A second sinusoid far away in frequency barely leaks in (the window's sidelobes).
        let mut img = sinusoid(64, 0.1, 0.0, 0.5, 0.1, 0.0);
        for (v, o) in img.iter_mut().zip(sinusoid(64, 0.3, 20.0, 0.0, 0.2, 40.0)) {
            *v += o;
        }
        let (c, _) = contrast_of(GratingFit::new(64, 64, 0.1, 0.0).unwrap().coefficients(&img));
        assert!((c - 0.2).abs() < 2e-3, "{c}");
        assert!(GratingFit::new(64, 64, 0.0, 0.0).is_none(), "a zero frequency is the constant itself");
    }

    /// A window of `cols` x `rows` pixels, `reps` replicates, one source: `f(replicate, pixel)`.
    fn window(cols: usize, rows: usize, reps: usize, f: impl Fn(usize, usize) -> f64) -> WindowSamples {
        let values = (0..reps).flat_map(|r| (0..cols * rows).map(move |p| (r, p))).map(|(r, p)| f(r, p) as f32);
        WindowSamples { cols, rows, replicates: reps, sources: 1, values: values.collect() }
    }

    #[test]
    fn a_rectangular_window_gives_its_grating_contrast_and_phase_whatever_else_it_holds() {
        // The study's grating window, 128 x 16 pixels (2 x 0.25 degrees at 64 per degree), with
        // bars along x: 0.5 + 0.2 cos(2 pi 2 cpd x + 0.3) plus 0.1 cos(2 pi 5 cpd x + 1), x in
        // degrees from the window's centre; a little noise per replicate.
        let ppd = 64.0;
        let (cols, rows) = (128, 16);
        let w = window(cols, rows, 6, |r, p| {
            let x = ((p % cols) as f64 + 0.5 - 0.5 * cols as f64) / ppd;
            0.5 + 0.2 * (TAU * 2.0 * x + 0.3).cos() + 0.1 * (TAU * 5.0 * x + 1.0).cos() + 0.002 * (noise(p, r) - 0.5)
        });
        let at = |cpd: f64| modulation(&w, 0, cpd / ppd, 0.0).unwrap();
        let two = at(2.0);
        assert!((two.contrast - 0.4).abs() < 1e-3 && two.ci95 < 1e-3, "{two:?}");
        assert!((two.phase_deg - 0.3f64.to_degrees()).abs() < 0.1, "{two:?}");
        assert!((two.mean - 0.5).abs() < 1e-4);
        assert!((at(5.0).contrast - 0.2).abs() < 1e-3, "{:?}", at(5.0));
        // Frequencies held by neither: nothing (the cross-replicate amplitude of the noise only).
        for cpd in [0.5, 3.5, 8.0] {
            assert!(at(cpd).contrast < 2e-3, "{cpd}: {:?}", at(cpd));
        }
        // An alias 0.4 cpd (0.8 of the window's frequency step) from the grating, as a display
        // makes near its sampling limit: the untapered window passes about sinc(0.8 pi) = 0.23
        // of it, where a Hann taper would pass 0.65.
        let alias = window(cols, rows, 3, |_, p| {
            0.5 + 0.2 * (TAU * 5.6 * ((p % cols) as f64 + 0.5 - 0.5 * cols as f64) / ppd + 0.5).cos()
        });
        let leak = modulation(&alias, 0, 6.0 / ppd, 0.0).unwrap().contrast / 0.4;
        assert!(leak < 0.3, "{leak}");
        // A window too short for its frequency: no fit, not a panic.
        assert!(modulation(&w, 0, 0.0, 0.0).is_none());
    }

    #[test]
    fn cross_replicate_contrast_removes_the_noise_bias_that_the_naive_one_keeps() {
        // Pure noise around a flat grey: the true amplitude is 0 at every frequency. Over many
        // frequencies, the naive squared amplitude (of the mean image) averages the noise's
        // variance; the cross-replicate one averages 0.
        let (n, nr) = (32, 8);
        let reps = window(n, n, nr, |r, p| 0.5 + 0.2 * (noise(p, r) - 0.5));
        let (mut naive, mut fair, mut covered) = (Vec::new(), Vec::new(), 0);
        for i in 0..40 {
            let f = 0.06 + 0.01 * i as f64;
            let fit = GratingFit::new(n, n, f, 10.0 * i as f64).unwrap();
            let coef: Vec<[f64; 3]> = (0..nr).map(|r| fit.coefficients(reps.plane(r, 0))).collect();
            let m: [f64; 3] = std::array::from_fn(|j| coef.iter().map(|c| c[j]).sum::<f64>() / nr as f64);
            naive.push(m[1] * m[1] + m[2] * m[2]);
            fair.push(unbiased_parts(&coef, |_| true).0);
            let md = modulation(&reps, 0, f, 10.0 * i as f64).unwrap();
            covered += (md.contrast <= md.ci95) as usize;
        }
        let stats = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt();
            (mean, sd / (v.len() as f64).sqrt())
        };
        let ((nm, nse), (fm, fse)) = (stats(&naive), stats(&fair));
        assert!(nm > 6.0 * nse, "naive squared amplitude is biased up: {nm} +- {nse}");
        assert!(fm.abs() < 3.0 * fse && fm.abs() < 0.2 * nm, "unbiased: {fm} +- {fse} (naive {nm})");
        // The interval of the (clamped) contrast reaches 0 in most cases.
        assert!(covered >= 30, "{covered} of 40 intervals reach the true 0");
    }

    /// Uniform in [0, 1), independent across pixels and replicates.
    fn noise(p: usize, r: usize) -> f64 {
        let mut z = ((p as u64) << 8 | r as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}
