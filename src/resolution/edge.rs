//! The slanted-edge MTF (measurement (b); ISO 12233, after the paper's Sec. 4
//! comparison of perceived resolution): from the retinal image of a slanted edge, the MTF along
//! the edge's normal in cycles per pixel, and MTF50. The one edge analysis: `inimtrace
//! resolution` runs it on its chart's edge window, the physics tests on it and on whole square
//! retinas (both as [`WindowSamples`]: rectangles of per-replicate grey means).
//!
//! The steps, on the grey plane (mean of R, G, B); an edge nearer horizontal than vertical is
//! transposed first:
//!
//! 1. **Edge location per row**: the centroid of the row's derivative (`v[c + 1] - v[c]`, at the
//!    boundary between the pixels), under a Hamming window as wide as the row, first centred
//!    on the row, then on the line fitted in the first pass; a least-squares line
//!    `x = a + b y` through the centroids (pixel-centre coordinates).
//! 2. **ESF**: every pixel's signed distance from the line, perpendicular to it, binned at 4x
//!    oversampling (bins of a quarter pixel) over the range every row covers; a bin that
//!    received no pixel is interpolated linearly from its neighbours.
//! 3. **LSF**: the central difference of the ESF, under a Hamming window centred on the edge.
//! 4. **MTF**: the magnitude of its FFT (`rustfft`), normalised at DC, divided by the response
//!    of the central difference, `sin(2 pi f D) / (2 pi f D)`, and of the quarter-pixel bins'
//!    averaging, `sinc(pi f D)` (`D` = 1/4 pixel), reported up to 1 cycle per pixel; at any
//!    other frequencies asked for (a study's), the same from the LSF's discrete-time Fourier
//!    transform there, so that no value is interpolated.
//! 5. **MTF50**: the first frequency where the MTF falls to 0.5, interpolated linearly.
//!
//! **Replicates.** Steps 2-4 are linear in the image once the line is fixed, so each replicate
//! gives an unbiased complex spectrum `C_r(f)`; the squared MTF is estimated from
//! cross-replicate products `Re(C_r conj(C_s))`, `r != s` (no noise bias, as the MSE in
//! `measure::stats`), the line from the replicates' mean image. The 95% intervals (each
//! frequency and MTF50) are delete-one jackknife intervals over the replicates, refitting the
//! line on each leave-one-out mean. [`EdgeMtf::naive`] is plain ISO 12233 on the mean image.
//!
//! Why these choices over a plainer ISO 12233 (no bin correction, empty bins from their two
//! neighbours' mean, jackknife of the mean image's MTF): the quarter-pixel bins blur the ESF by
//! their own width, 1.3% at 0.35 cycles per pixel, which the correction removes; the noise left
//! in a mean image biases its MTF up where the MTF is small, which cross-replicate products do
//! not.

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use super::window::WindowSamples;
use crate::error::{Error, Result};
use crate::measure::stats::jackknife_ci95;

/// Bins per pixel of the edge-spread function.
pub const OVERSAMPLING: usize = 4;

/// An MTF curve along the edge normal.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeCurve {
    /// Cycles per pixel along the edge's normal, from 0 to 1 in steps of `4 / bins`.
    pub frequencies: Vec<f64>,
    /// The MTF at each frequency (1 at 0).
    pub mtf: Vec<f64>,
    /// Cycles per pixel where the MTF first falls to 0.5; `None` if it stays above.
    pub mtf50: Option<f64>,
}

impl EdgeCurve {
    /// The MTF at `cycles_per_pixel`, interpolated linearly; `None` outside the curve.
    pub fn at(&self, cycles_per_pixel: f64) -> Option<f64> {
        interpolate(&self.frequencies, &self.mtf, cycles_per_pixel)
    }
}

/// The slanted-edge MTF of an image measured with replicates.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeMtf {
    /// From cross-replicate products (no noise bias).
    pub curve: EdgeCurve,
    /// Half-widths of the 95% intervals of `curve.mtf`, per frequency.
    pub ci95: Vec<f64>,
    /// Half-width of the 95% interval of `curve.mtf50`; `None` when some leave-one-out curve
    /// has no MTF50.
    pub mtf50_ci95: Option<f64>,
    /// Plain ISO 12233 on the replicates' mean image (biased up by the noise left in it).
    pub naive: EdgeCurve,
    /// The edge as fitted on the mean image.
    pub edge: EdgeLine,
    /// The MTF (cross-replicate) at each frequency asked for, exactly there.
    pub at: Vec<f64>,
    /// Half-widths of the 95% intervals of `at`.
    pub at_ci95: Vec<f64>,
}

impl EdgeMtf {
    /// The 95% half-width at `cycles_per_pixel`, interpolated linearly.
    pub fn ci95_at(&self, cycles_per_pixel: f64) -> Option<f64> {
        interpolate(&self.curve.frequencies, &self.ci95, cycles_per_pixel)
    }
}

/// The fitted edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeLine {
    /// Direction of the edge's normal in the image (+x right, +y up, as tangent space),
    /// degrees counter-clockwise from +x, in (-90, 180): the direction the MTF is measured
    /// along (the retina pixel's box response depends on it).
    pub normal_deg: f64,
    /// Angle between the edge and the nearest image axis, degrees (ISO 12233 wants a few).
    pub slant_deg: f64,
    /// Whether the edge was nearer horizontal (the image was transposed).
    pub horizontal: bool,
}

fn interpolate(xs: &[f64], ys: &[f64], x: f64) -> Option<f64> {
    let i = xs.partition_point(|&v| v < x);
    if i == 0 {
        return (xs.first() == Some(&x)).then(|| ys[0]);
    }
    if i == xs.len() {
        return None;
    }
    let t = (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
    Some(ys[i - 1] + t * (ys[i] - ys[i - 1]))
}

/// A grey plane, transposed if the edge is nearer horizontal, so that the edge crosses rows.
struct Plane {
    w: usize,
    h: usize,
    v: Vec<f64>,
}

impl Plane {
    fn new(v: Vec<f64>, w: usize, h: usize, transpose: bool) -> Self {
        if !transpose {
            return Self { w, h, v };
        }
        let mut t = vec![0.0; v.len()];
        for r in 0..h {
            for c in 0..w {
                t[c * h + r] = v[r * w + c];
            }
        }
        Self { w: h, h: w, v: t }
    }

    fn row(&self, r: usize) -> &[f64] {
        &self.v[r * self.w..(r + 1) * self.w]
    }
}

/// Whether the edge of a plane runs nearer horizontal (vertical differences dominate).
fn is_horizontal(v: &[f64], w: usize, h: usize) -> bool {
    let (mut gx, mut gy) = (0.0, 0.0);
    for r in 0..h {
        for c in 0..w {
            if c + 1 < w {
                gx += (v[r * w + c + 1] - v[r * w + c]).abs();
            }
            if r + 1 < h {
                gy += (v[(r + 1) * w + c] - v[r * w + c]).abs();
            }
        }
    }
    gy > gx
}

/// Hamming window of width `width` centred at `center`, zero beyond.
fn hamming(x: f64, center: f64, width: f64) -> f64 {
    let u = (x - center) / width;
    if u.abs() > 0.5 {
        0.0
    } else {
        0.54 + 0.46 * (TAU * u).cos()
    }
}

/// The edge line `x = a + b y` (pixel-centre coordinates: pixel c spans [c, c + 1]).
fn locate(p: &Plane, source: &str) -> Result<(f64, f64)> {
    let polarity: f64 = (0..p.h).map(|r| p.row(r)[p.w - 1] - p.row(r)[0]).sum::<f64>().signum();
    if polarity == 0.0 || p.w < 8 || p.h < 8 {
        return Err(Error::invalid(source, "image", "no edge: the image is flat or under 8 x 8 pixels"));
    }
    let centroids = |center: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..p.h)
            .filter_map(|r| {
                let y = r as f64 + 0.5;
                let row = p.row(r);
                let (mut s, mut sx) = (0.0, 0.0);
                for c in 0..p.w - 1 {
                    let x = c as f64 + 1.0;
                    let d = polarity * (row[c + 1] - row[c]) * hamming(x, center(y), p.w as f64);
                    s += d;
                    sx += d * x;
                }
                (s > 0.0).then(|| (y, sx / s))
            })
            .collect()
    };
    let fit = |pts: &[(f64, f64)]| -> Option<(f64, f64)> {
        let n = pts.len() as f64;
        let (my, mx) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
        let syy: f64 = pts.iter().map(|p| (p.0 - my) * (p.0 - my)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - my) * (p.1 - mx)).sum();
        (pts.len() >= p.h / 2 && syy > 0.0).then(|| {
            let b = sxy / syy;
            (mx - b * my, b)
        })
    };
    let half = 0.5 * p.w as f64;
    let first = fit(&centroids(&|_| half));
    let line = first.and_then(|(a, b)| fit(&centroids(&|y| a + b * y)));
    line.filter(|(a, b)| a.is_finite() && b.abs() < 1.0).ok_or_else(|| {
        Error::invalid(source, "image", "no slanted edge found (fewer than half the rows show one step)")
    })
}

/// Half the number of ESF bins for an edge `x = a + b y` on a plane: the range (in quarter
/// pixels) of perpendicular distances that every row covers, less half a pixel.
fn half_bins(p: &Plane, (a, b): (f64, f64), source: &str) -> Result<usize> {
    let (x0, x1) = (a + b * 0.5, a + b * (p.h as f64 - 0.5));
    let room = x0.min(x1) - 0.5;
    let room = room.min(p.w as f64 - 0.5 - x0.max(x1));
    let perp = room / (1.0 + b * b).sqrt() - 0.5;
    if perp.is_nan() || perp < 4.0 {
        return Err(Error::invalid(
            source,
            "image",
            format!("the edge leaves only {perp:.1} pixels to one side in some row (need 4)"),
        ));
    }
    Ok((perp * OVERSAMPLING as f64).floor() as usize)
}

/// The windowed LSF (`2 half` bins of a quarter pixel). Linear in the plane's values.
fn lsf(p: &Plane, (a, b): (f64, f64), half: usize) -> Vec<f64> {
    let n = 2 * half;
    let q = OVERSAMPLING as f64;
    let inv_len = 1.0 / (1.0 + b * b).sqrt();
    let (mut sum, mut count) = (vec![0.0; n], vec![0u32; n]);
    for r in 0..p.h {
        let y = r as f64 + 0.5;
        let xe = a + b * y;
        for (c, v) in p.row(r).iter().enumerate() {
            let d = (c as f64 + 0.5 - xe) * inv_len;
            let k = (d * q).floor() + half as f64;
            if k >= 0.0 && k < n as f64 {
                sum[k as usize] += v;
                count[k as usize] += 1;
            }
        }
    }
    let mut esf: Vec<Option<f64>> = sum.iter().zip(&count).map(|(s, &c)| (c > 0).then(|| s / f64::from(c))).collect();
    fill_gaps(&mut esf);
    let esf: Vec<f64> = esf.into_iter().map(|v| v.unwrap_or(0.0)).collect();
    let center = half as f64 - 0.5;
    (0..n)
        .map(|k| {
            let lsf = if k == 0 || k + 1 == n { 0.0 } else { 0.5 * (esf[k + 1] - esf[k - 1]) };
            lsf * hamming(k as f64, center, n as f64)
        })
        .collect()
}

/// The transforms of an LSF of `n` bins: its FFT on the grid `j 4 / n` cycles per pixel up to
/// 1, then its discrete-time Fourier transform at the frequencies asked for (one row of
/// `exp(-2 pi i f k / 4)` per frequency, the FFT's convention).
struct Transforms {
    fft: Arc<dyn Fft<f64>>,
    grid: usize,
    at: Vec<Vec<Complex<f64>>>,
}

impl Transforms {
    fn new(n: usize, at_cycles_per_pixel: &[f64]) -> Self {
        let q = OVERSAMPLING as f64;
        let at = at_cycles_per_pixel
            .iter()
            .map(|&f| (0..n).map(|k| Complex::from_polar(1.0, -TAU * f * k as f64 / q)).collect())
            .collect();
        Self { fft: FftPlanner::new().plan_fft_forward(n), grid: n / OVERSAMPLING + 1, at }
    }

    /// `C(f)` on the grid, then at the frequencies asked for, before the corrections.
    fn spectrum(&self, lsf: &[f64]) -> Vec<Complex<f64>> {
        let mut buf: Vec<Complex<f64>> = lsf.iter().map(|&v| Complex::new(v, 0.0)).collect();
        self.fft.process(&mut buf);
        buf.truncate(self.grid);
        buf.extend(self.at.iter().map(|row| row.iter().zip(lsf).map(|(e, v)| e * v).sum::<Complex<f64>>()));
        buf
    }
}

/// Fills empty bins by linear interpolation between the nearest filled ones (constant beyond).
fn fill_gaps(v: &mut [Option<f64>]) {
    let filled: Vec<usize> = (0..v.len()).filter(|&i| v[i].is_some()).collect();
    let (Some(&first), Some(&last)) = (filled.first(), filled.last()) else { return };
    for i in 0..v.len() {
        if v[i].is_some() {
            continue;
        }
        v[i] = Some(if i < first {
            v[first].unwrap_or(0.0)
        } else if i > last {
            v[last].unwrap_or(0.0)
        } else {
            let hi = filled[filled.partition_point(|&j| j < i)];
            let lo = filled[filled.partition_point(|&j| j < i) - 1];
            let t = (i - lo) as f64 / (hi - lo) as f64;
            v[lo].unwrap_or(0.0) * (1.0 - t) + v[hi].unwrap_or(0.0) * t
        });
    }
}

/// The response of the central difference and of the bin averaging at `f` cycles per pixel,
/// which the MTF is divided by.
fn correction(f: f64) -> f64 {
    let delta = 1.0 / OVERSAMPLING as f64;
    let sinc = |x: f64| if x.abs() < 1e-12 { 1.0 } else { x.sin() / x };
    (sinc(TAU * f * delta) * sinc(PI * f * delta)).abs()
}

/// Frequencies (cycles per pixel) of the FFT grid of `2 half` bins, then `at`, and the
/// corrections of each.
fn frequencies_and_corrections(half: usize, at: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = 2 * half;
    let grid = (0..=n / OVERSAMPLING).map(|j| j as f64 * OVERSAMPLING as f64 / n as f64);
    let freqs: Vec<f64> = grid.chain(at.iter().copied()).collect();
    let corr = freqs.iter().map(|&f| correction(f)).collect();
    (freqs, corr)
}

/// The first frequency where `mtf` falls to 0.5 (linear interpolation).
fn mtf50(freqs: &[f64], mtf: &[f64]) -> Option<f64> {
    let i = mtf.iter().position(|&m| m <= 0.5)?;
    if i == 0 {
        return Some(0.0);
    }
    let t = (mtf[i - 1] - 0.5) / (mtf[i - 1] - mtf[i]);
    Some(freqs[i - 1] + t * (freqs[i] - freqs[i - 1]))
}

fn curve(freqs: &[f64], mtf: Vec<f64>) -> EdgeCurve {
    EdgeCurve { frequencies: freqs.to_vec(), mtf50: mtf50(freqs, &mtf), mtf }
}

fn edge_line((_, b): (f64, f64), horizontal: bool) -> EdgeLine {
    // Along rows x = a + b y_down: the line runs along (b, -1) with y up, its normal along
    // (1, b); transposed, the normal is (b, 1) in the original image.
    let slant = b.atan().to_degrees();
    let normal_deg = if horizontal { 90.0 - slant } else { slant };
    EdgeLine { normal_deg, slant_deg: slant.abs(), horizontal }
}

/// Plain ISO 12233 on one row-major grey plane of `width` x `height` pixels.
/// Errors (naming `source` and the field `image`) when no edge crossing the image is found.
pub fn iso12233(plane: &[f64], width: usize, height: usize, source: &str) -> Result<(EdgeCurve, EdgeLine)> {
    let horizontal = is_horizontal(plane, width, height);
    let p = Plane::new(plane.to_vec(), width, height, horizontal);
    let line = locate(&p, source)?;
    let half = half_bins(&p, line, source)?;
    let (freqs, corr) = frequencies_and_corrections(half, &[]);
    let c = Transforms::new(2 * half, &[]).spectrum(&lsf(&p, line, half));
    let dc = c[0].re;
    let mtf = c.iter().zip(&corr).map(|(v, k)| v.norm() / dc.abs() / k).collect();
    Ok((curve(&freqs, mtf), edge_line(line, horizontal)))
}

/// The MTF from per-replicate spectra over the replicates `keep` allows.
fn unbiased_mtf(spectra: &[Vec<Complex<f64>>], corr: &[f64], keep: impl Fn(usize) -> bool) -> Vec<f64> {
    unbiased_mtf2(spectra, corr, keep).into_iter().map(|v| v.max(0.0).sqrt()).collect()
}

/// The squared MTF from cross-replicate products (unbiased, can be negative).
fn unbiased_mtf2(spectra: &[Vec<Complex<f64>>], corr: &[f64], keep: impl Fn(usize) -> bool) -> Vec<f64> {
    let m = (0..spectra.len()).filter(|&r| keep(r)).count() as f64;
    let mut out = Vec::with_capacity(corr.len());
    let dc = spectra.iter().enumerate().filter(|(r, _)| keep(*r)).map(|(_, s)| s[0].re).sum::<f64>() / m;
    for (j, k) in corr.iter().enumerate() {
        let (mut sum, mut sq) = (Complex::new(0.0, 0.0), 0.0);
        for (_, s) in spectra.iter().enumerate().filter(|(r, _)| keep(*r)) {
            sum += s[j];
            sq += s[j].norm_sqr();
        }
        let cross = (sum.norm_sqr() - sq) / (m * (m - 1.0));
        out.push(cross / (dc * dc * k * k));
    }
    out
}

/// The slanted-edge MTF of source `k` in window `w` (module comment), with 95% intervals, on
/// the FFT grid and at `at_cycles_per_pixel`. Errors (naming the field `image`) when no edge
/// crossing the window is found, or `replicates` when there are fewer than 3.
pub fn edge_mtf(w: &WindowSamples, k: usize, at_cycles_per_pixel: &[f64]) -> Result<EdgeMtf> {
    let nr = w.replicates;
    let source = "slanted-edge MTF";
    if nr < 3 {
        return Err(Error::invalid(source, "replicates", format!("need at least 3, got {nr}")));
    }
    let mean = w.mean_image(k, |_| true);
    let horizontal = is_horizontal(&mean, w.cols, w.rows);
    let plane = |v: Vec<f64>| Plane::new(v, w.cols, w.rows, horizontal);
    let planes: Vec<Plane> = (0..nr).map(|r| plane(w.plane(r, k).iter().map(|&v| f64::from(v)).collect())).collect();
    let mean = plane(mean);
    let line = locate(&mean, source)?;
    let half = half_bins(&mean, line, source)?;
    let (freqs, corr) = frequencies_and_corrections(half, at_cycles_per_pixel);
    let transforms = Transforms::new(2 * half, at_cycles_per_pixel);
    let spectra_for = |line: (f64, f64)| -> Vec<Vec<Complex<f64>>> {
        planes.iter().map(|p| transforms.spectrum(&lsf(p, line, half))).collect()
    };
    let mtf = unbiased_mtf(&spectra_for(line), &corr, |_| true);
    let naive_c = transforms.spectrum(&lsf(&mean, line, half));
    let naive: Vec<f64> = naive_c.iter().zip(&corr).map(|(v, c)| v.norm() / naive_c[0].re.abs() / c).collect();
    let mut loo = Vec::with_capacity(nr);
    for d in 0..nr {
        let line_d = locate(&plane(w.mean_image(k, |r| r != d)), source).unwrap_or(line);
        loo.push(unbiased_mtf(&spectra_for(line_d), &corr, |r| r != d));
    }
    let ci95: Vec<f64> =
        (0..freqs.len()).map(|j| jackknife_ci95(&loo.iter().map(|c| c[j]).collect::<Vec<_>>())).collect();
    let g = transforms.grid;
    let grid = &freqs[..g];
    let loo50: Option<Vec<f64>> = loo.iter().map(|c| mtf50(grid, &c[..g])).collect();
    let curve = curve(grid, mtf[..g].to_vec());
    let mtf50_ci95 = match (curve.mtf50, loo50) {
        (Some(_), Some(v)) => Some(jackknife_ci95(&v)),
        _ => None,
    };
    Ok(EdgeMtf {
        curve,
        ci95: ci95[..g].to_vec(),
        mtf50_ci95,
        naive: self::curve(grid, naive[..g].to_vec()),
        edge: edge_line(line, horizontal),
        at: mtf[g..].to_vec(),
        at_ci95: ci95[g..].to_vec(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian-blurred edge (sigma in pixels) point-sampled at pixel centres: its MTF along
    /// the normal is `exp(-2 pi^2 sigma^2 f^2)`. `angle_deg`: the normal's direction (+y up).
    fn gaussian_edge(n: usize, angle_deg: f64, sigma: f64, offset: f64) -> Vec<f64> {
        let (s, c) = angle_deg.to_radians().sin_cos();
        (0..n * n)
            .map(|i| {
                let (r, col) = (i / n, i % n);
                let x = col as f64 + 0.5 - 0.5 * n as f64;
                let y = 0.5 * n as f64 - (r as f64 + 0.5);
                let d = x * c + y * s - offset;
                0.1 + 0.8 * 0.5 * (1.0 + libm::erf(d / (sigma * std::f64::consts::SQRT_2)))
            })
            .collect()
    }

    #[test]
    fn iso12233_recovers_a_gaussian_mtf_for_vertical_and_horizontal_edges() {
        for (angle, sigma) in [(5.0, 0.8), (-4.0, 1.5), (95.0, 0.8), (183.0, 1.0), (-86.0, 1.2)] {
            let img = gaussian_edge(96, angle, sigma, 0.37);
            let (curve, line) = iso12233(&img, 96, 96, "test").unwrap();
            let mut worst: f64 = 0.0;
            for (f, m) in curve.frequencies.iter().zip(&curve.mtf) {
                if *f <= 0.7 {
                    worst = worst.max((m - (-2.0 * PI * PI * sigma * sigma * f * f).exp()).abs());
                }
            }
            assert!(worst < 0.01, "angle {angle}, sigma {sigma}: worst {worst}");
            let slant = (angle.rem_euclid(90.0) + 45.0).rem_euclid(90.0) - 45.0;
            assert!((line.slant_deg - slant.abs()).abs() < 0.05, "{angle}: {line:?}");
            assert_eq!(line.horizontal, angle.to_radians().sin().abs() > 0.7, "{angle}");
            // The normal direction's axis (the pixel box response is even in it).
            let dn = ((line.normal_deg - angle).rem_euclid(180.0) + 90.0).rem_euclid(180.0) - 90.0;
            assert!(dn.abs() < 0.05, "{angle}: {line:?}");
            let f50 = (0.5f64.ln() / (-2.0 * PI * PI * sigma * sigma)).sqrt();
            assert!((curve.mtf50.unwrap() - f50).abs() < 0.01, "{angle}: {:?} vs {f50}", curve.mtf50);
        }
        assert!(iso12233(&vec![0.5; 64 * 64], 64, 64, "flat.exr").unwrap_err().to_string().contains("flat.exr"));
    }

    /// A window of `cols` x `rows` pixels, `reps` replicates, one source: `f(pixel, replicate)`.
    fn window(cols: usize, rows: usize, reps: usize, f: impl Fn(usize, usize) -> f64) -> WindowSamples {
        let values = (0..reps).flat_map(|r| (0..cols * rows).map(move |p| (p, r))).map(|(p, r)| f(p, r) as f32);
        WindowSamples { cols, rows, replicates: reps, sources: 1, values: values.collect() }
    }

    #[test]
    fn the_study_window_of_a_sharp_edge_gives_the_pixel_box_mtf_at_any_frequency() {
        // The study's edge window, 128 x 32 pixels, a pixel-averaged step 5 degrees off vertical
        // through (64.3, 16) pixels: the MTF along the normal is the pixel box's, |sinc(pi f)|
        // (the box along the normal at 5 degrees differs from it by < 0.002 below 0.35), within
        // 0.01 up to 0.7 of Nyquist, on the grid and at frequencies off it.
        let (cols, rows) = (128, 32);
        let t = 5f64.to_radians().tan();
        let img: Vec<f64> = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64, (i % cols) as f64);
                let mut s = 0.0;
                for a in 0..16 {
                    for b in 0..16 {
                        let (x, y) = (c + (a as f64 + 0.5) / 16.0, r + (b as f64 + 0.5) / 16.0);
                        s += if x > 64.3 - t * (y - 16.0) { 0.9 } else { 0.1 };
                    }
                }
                s / 256.0
            })
            .collect();
        let w = window(cols, rows, 4, |p, r| img[p] + 1e-4 * noise(p, r, 5));
        let at: Vec<f64> = (1..=7).map(|i| 0.05 * i as f64 + 0.0123).collect();
        let m = edge_mtf(&w, 0, &at).unwrap();
        let sinc = |f: f64| (PI * f).sin() / (PI * f);
        for (f, v) in at.iter().zip(&m.at) {
            assert!((v - sinc(*f)).abs() < 0.01, "{f}: {v} vs {}", sinc(*f));
        }
        for (f, v) in m.curve.frequencies.iter().zip(&m.curve.mtf).skip(1) {
            if *f <= 0.35 {
                assert!((v - sinc(*f)).abs() < 0.01, "{f}: {v} vs {}", sinc(*f));
            }
        }
        // The frequencies asked for that are on the grid give the grid's values.
        let grid: Vec<f64> = m.curve.frequencies[3..6].to_vec();
        let again = edge_mtf(&w, 0, &grid).unwrap();
        for (a, b) in again.at.iter().zip(&m.curve.mtf[3..6]) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        assert!((m.edge.slant_deg - 5.0).abs() < 0.1 && !m.edge.horizontal, "{:?}", m.edge);
        // The box along the normal falls to 0.5 at 0.6057 cycles per pixel, beyond Nyquist
        // (where the 32 rows' 2.8-pixel drift fills the quarter-pixel bins less evenly).
        assert!((m.curve.mtf50.unwrap() - 0.6057).abs() < 0.015, "{:?}", m.curve.mtf50);
        // Too few replicates, or no edge: errors, not panics.
        assert!(edge_mtf(&window(cols, rows, 2, |p, _| img[p]), 0, &[]).is_err());
        assert!(edge_mtf(&window(cols, rows, 3, |_, _| 0.5), 0, &[]).is_err());
    }

    fn noise(p: usize, r: usize, seed: u64) -> f64 {
        let mut z = ((p as u64) << 16 | (r as u64) << 8 | seed).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    #[test]
    fn replicates_remove_the_noise_bias_of_the_high_frequencies() {
        // Past 0.7 cycles per pixel: over noise seeds, the naive squared MTF averages the clean
        // image's plus the noise's, the cross-replicate one the clean image's alone.
        let n = 64;
        let clean = gaussian_edge(n, 5.0, 1.0, 0.2);
        let (mut naive, mut fair) = (Vec::new(), Vec::new());
        for seed in 0..16 {
            let reps = window(n, n, 8, |p, r| clean[p] + 0.05 * noise(p, r, seed));
            let m = edge_mtf(&reps, 0, &[]).unwrap();
            let planes: Vec<Plane> = (0..8)
                .map(|r| Plane::new(reps.plane(r, 0).iter().map(|&v| f64::from(v)).collect(), n, n, false))
                .collect();
            let mean = Plane::new(clean.clone(), n, n, false);
            let line = locate(&mean, "t").unwrap();
            let half = half_bins(&mean, line, "t").unwrap();
            let (freqs, corr) = frequencies_and_corrections(half, &[]);
            let t = Transforms::new(2 * half, &[]);
            let spectra: Vec<_> = planes.iter().map(|p| t.spectrum(&lsf(p, line, half))).collect();
            let j = freqs.iter().position(|&f| f >= 0.7).unwrap();
            let band = |v: &[f64]| v[j..].iter().sum::<f64>() / (v.len() - j) as f64;
            let c = t.spectrum(&lsf(&mean, line, half));
            let clean2: Vec<f64> = c.iter().zip(&corr).map(|(v, k)| v.norm_sqr() / (c[0].re * k).powi(2)).collect();
            naive.push(band(&m.naive.mtf.iter().map(|v| v * v).collect::<Vec<_>>()) - band(&clean2));
            fair.push(band(&unbiased_mtf2(&spectra, &corr, |_| true)) - band(&clean2));
        }
        let stats = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt();
            (mean, sd / (v.len() as f64).sqrt())
        };
        let ((nm, nse), (fm, fse)) = (stats(&naive), stats(&fair));
        assert!(
            nm > 4.0 * nse && fm.abs() < 3.0 * fse && fm.abs() < 0.25 * nm,
            "unbiased {fm} +- {fse}, naive {nm} +- {nse}"
        );

        // And the intervals cover the truth at the frequencies that matter.
        let reps = window(n, n, 8, |p, r| clean[p] + 0.05 * noise(p, r, 99));
        let m = edge_mtf(&reps, 0, &[]).unwrap();
        let inside = (0..m.curve.mtf.len())
            .filter(|&i| m.curve.frequencies[i] <= 0.5)
            .filter(|&i| {
                let f = m.curve.frequencies[i];
                (m.curve.mtf[i] - (-2.0 * PI * PI * f * f).exp()).abs() <= m.ci95[i].max(0.01)
            })
            .count();
        let total = m.curve.frequencies.iter().filter(|&&f| f <= 0.5).count();
        assert!(inside * 10 >= total * 8, "{inside} of {total} inside their intervals");
        assert!(m.mtf50_ci95.is_some_and(|h| h > 0.0 && h < 0.05), "{:?}", m.mtf50_ci95);
    }
}
