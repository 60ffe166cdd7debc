//! Image-quality metrics used to score display-image rendering methods: PSNR and SSIM, the two
//! columns of the paper's Table 1 (each simulated retinal image of LC, PC and LA is compared with
//! the ground-truth retinal image).
//!
//! * **PSNR** is computed on linear values with peak 1: `10 log10(1 / MSE)` per channel; the
//!   image PSNR is the mean of the three channel PSNRs, as the paper's framework did. Identical
//!   channels have MSE 0 and PSNR `f64::INFINITY`; use [`format_db`] / [`finite_db`] when
//!   writing tables or JSON so that no `NaN`/`inf` surprises appear there.
//! * **SSIM** follows Wang et al. 2004 exactly as their reference code `ssim_index.m`: an 11×11
//!   Gaussian window with σ = 1.5 (normalised to sum 1), `C1 = (K1 L)²`, `C2 = (K2 L)²` with
//!   `K1 = 0.01`, `K2 = 0.03`, statistics (population variances, no `N-1`) computed only at the
//!   window positions that lie fully inside the image (`filter2(..., 'valid')`), the mean of the
//!   SSIM map per channel, then the mean over the three channels. [`SsimConstants`] selects the
//!   dynamic range `L`: 1 for our `[0, 1]` data ([`SsimConstants::Wang2004`], the default), or
//!   the paper framework's 8-bit constants applied to `[0, 1]` data
//!   ([`SsimConstants::Framework8Bit`]), kept only to reproduce the paper's published numbers.
//!
//! [`ssim`] filters separably and in parallel; [`ssim_direct`] is its slow, obviously correct
//! twin (a direct 11×11 weighted sum at every window position) used by the tests.
//!
//! All inputs are checked: different sizes, empty images, images smaller than the SSIM window
//! and non-finite samples give an [`Error`], never a panic or a `NaN`.

use std::fmt;
use std::str::FromStr;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::raster::RgbImage;

/// Side of the square SSIM window, in pixels (Wang et al. 2004).
pub const SSIM_WINDOW: usize = 11;
/// Standard deviation of the Gaussian SSIM window, in pixels (Wang et al. 2004).
pub const SSIM_SIGMA: f64 = 1.5;
/// SSIM stabilising constant factor `K1` (Wang et al. 2004).
pub const SSIM_K1: f64 = 0.01;
/// SSIM stabilising constant factor `K2` (Wang et al. 2004).
pub const SSIM_K2: f64 = 0.03;

const HALF: usize = SSIM_WINDOW / 2;

// ---------------------------------------------------------------------------------------------
// PSNR
// ---------------------------------------------------------------------------------------------

/// PSNR in dB of two equally long sample planes of linear values with peak 1:
/// `10 log10(1 / MSE)`.
///
/// Returns `f64::INFINITY` when the planes are identical (MSE = 0). The result is `NaN` only if
/// an input contains `NaN`; [`psnr`] rejects such images before calling this.
///
/// # Panics
/// If the two slices differ in length or are empty (a programming error; [`psnr`] checks
/// image sizes and returns an error instead).
pub fn psnr_channel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "psnr_channel: planes differ in length");
    assert!(!a.is_empty(), "psnr_channel: empty planes");
    let sse: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    psnr_from_mse(sse / a.len() as f64)
}

fn psnr_from_mse(mse: f64) -> f64 {
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}

/// PSNR of an RGB image pair: the three channel PSNRs (R, G, B) and their mean.
///
/// `mean` is infinite when any channel is identical in both images.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Psnr {
    /// PSNR of R, G and B, dB.
    pub channels: [f64; 3],
    /// Mean of the three channel PSNRs, dB.
    pub mean: f64,
}

impl Psnr {
    /// The mean PSNR as table text, see [`format_db`].
    pub fn mean_text(&self, decimals: usize) -> String {
        format_db(self.mean, decimals)
    }
}

/// PSNR of `a` against `b` per channel and their mean (see the module comment).
///
/// Errors if the images differ in size, are empty, or contain a non-finite sample.
///
/// ```
/// use inimtrace::metrics::psnr;
/// use inimtrace::raster::RgbImage;
///
/// // Every sample off by 0.1 with peak 1: MSE = 0.01, PSNR = 10 log10(1 / 0.01) = 20 dB.
/// let a = RgbImage::filled(8, 8, [0.5, 0.5, 0.5]);
/// let b = RgbImage::filled(8, 8, [0.6, 0.4, 0.6]);
/// let p = psnr(&a, &b)?;
/// assert!((p.mean - 20.0).abs() < 1e-5 && p.channels.iter().all(|c| (c - 20.0).abs() < 1e-5));
/// // Identical images: infinite PSNR, never NaN.
/// assert_eq!(psnr(&a, &a)?.mean, f64::INFINITY);
/// # Ok::<(), inimtrace::Error>(())
/// ```
pub fn psnr(a: &RgbImage, b: &RgbImage) -> Result<Psnr> {
    check_pair(a, b, "PSNR")?;
    // Per-chunk sums of squared errors in f64, added in a fixed order (schedule-independent).
    let chunk_sse: Vec<[f64; 3]> = a
        .pixels
        .par_chunks(16_384)
        .zip(b.pixels.par_chunks(16_384))
        .map(|(pa, pb)| {
            let mut sse = [0.0f64; 3];
            for (p, q) in pa.iter().zip(pb) {
                for c in 0..3 {
                    let d = p[c] as f64 - q[c] as f64;
                    sse[c] += d * d;
                }
            }
            sse
        })
        .collect();
    let n = a.pixels.len() as f64;
    let mut channels = [0.0; 3];
    for (c, out) in channels.iter_mut().enumerate() {
        *out = psnr_from_mse(chunk_sse.iter().map(|s| s[c]).sum::<f64>() / n);
    }
    let mean = channels.iter().sum::<f64>() / 3.0;
    Ok(Psnr { channels, mean })
}

/// A PSNR (or other dB value) as text for tables: `decimals` places when finite, `"inf"` for
/// identical images, `"-inf"`, and `"n/a"` for `NaN` (which the metrics never return).
pub fn format_db(db: f64, decimals: usize) -> String {
    if db.is_nan() {
        "n/a".to_string()
    } else if db == f64::INFINITY {
        "inf".to_string()
    } else if db == f64::NEG_INFINITY {
        "-inf".to_string()
    } else {
        format!("{db:.decimals$}")
    }
}

/// `Some(db)` when finite, `None` otherwise: for JSON, where infinity cannot be written
/// (`serde_json` would silently write `null`, so make the choice explicit).
pub fn finite_db(db: f64) -> Option<f64> {
    db.is_finite().then_some(db)
}

// ---------------------------------------------------------------------------------------------
// SSIM
// ---------------------------------------------------------------------------------------------

/// The SSIM stabilising constants `C1`, `C2`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SsimConstants {
    /// Wang et al. 2004 with the dynamic range of our data, `L = 1`:
    /// `C1 = (0.01)² = 1e-4`, `C2 = (0.03)² = 9e-4`. Name `"wang2004"`.
    #[default]
    #[serde(rename = "wang2004")]
    Wang2004,
    /// The constants for 8-bit data, `C1 = (0.01·255)² = 6.5025`, `C2 = (0.03·255)² = 58.5225`,
    /// applied to `[0, 1]` data — what the paper's published framework did. These constants
    /// dwarf the image statistics and pin SSIM near 0.999 for almost any pair of images; use
    /// only to reproduce the paper's numbers. Name `"framework-8bit"`.
    #[serde(rename = "framework-8bit")]
    Framework8Bit,
}

impl SsimConstants {
    /// Every variant, in a fixed order.
    pub const ALL: [SsimConstants; 2] = [SsimConstants::Wang2004, SsimConstants::Framework8Bit];

    /// The name used on the command line and in configuration files.
    pub fn name(self) -> &'static str {
        match self {
            SsimConstants::Wang2004 => "wang2004",
            SsimConstants::Framework8Bit => "framework-8bit",
        }
    }

    /// `(C1, C2)`.
    pub fn c1_c2(self) -> (f64, f64) {
        let l = match self {
            SsimConstants::Wang2004 => 1.0,
            SsimConstants::Framework8Bit => 255.0,
        };
        ((SSIM_K1 * l).powi(2), (SSIM_K2 * l).powi(2))
    }
}

impl fmt::Display for SsimConstants {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SsimConstants {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        SsimConstants::ALL.into_iter().find(|c| c.name() == s).ok_or_else(|| {
            Error::invalid(
                "SSIM constants",
                "name",
                format!("unknown SSIM constants `{s}` (expected `wang2004` or `framework-8bit`)"),
            )
        })
    }
}

/// SSIM of an RGB image pair: the mean SSIM of each channel (R, G, B) and their mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ssim {
    /// SSIM of R, G and B.
    pub channels: [f64; 3],
    /// Mean of the three channel SSIMs.
    pub mean: f64,
}

/// The normalised 1-D Gaussian window; its outer product with itself is the normalised 2-D
/// window of `fspecial('gaussian', 11, 1.5)` (up to rounding).
pub(crate) fn gaussian_1d() -> [f64; SSIM_WINDOW] {
    let mut g = [0.0; SSIM_WINDOW];
    for (k, v) in g.iter_mut().enumerate() {
        let d = k as f64 - HALF as f64;
        *v = (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    let s: f64 = g.iter().sum();
    g.iter_mut().for_each(|v| *v /= s);
    g
}

/// The normalised 2-D Gaussian window exactly as `fspecial('gaussian', 11, 1.5)` builds it.
fn gaussian_2d() -> [[f64; SSIM_WINDOW]; SSIM_WINDOW] {
    let mut w = [[0.0; SSIM_WINDOW]; SSIM_WINDOW];
    let mut s = 0.0;
    for (u, row) in w.iter_mut().enumerate() {
        for (v, val) in row.iter_mut().enumerate() {
            let du = u as f64 - HALF as f64;
            let dv = v as f64 - HALF as f64;
            *val = (-(du * du + dv * dv) / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
            s += *val;
        }
    }
    w.iter_mut().flatten().for_each(|v| *v /= s);
    w
}

/// The same SSIM map value from `E[x² + y²]` instead of `E[x²]` and `E[y²]` (the formula only
/// needs `σx² + σy²`), which saves one of five filtered quantities in the fast path.
#[inline]
fn ssim_value_combined(mx: f64, my: f64, esq: f64, exy: f64, c1: f64, c2: f64) -> f64 {
    let mxy = mx * my;
    let msq = mx * mx + my * my;
    let s_sum = esq - msq;
    let sxy = exy - mxy;
    ((2.0 * mxy + c1) * (2.0 * sxy + c2)) / ((msq + c1) * (s_sum + c2))
}

/// One SSIM map value from the local statistics (ssim_index.m, case C1 > 0 and C2 > 0).
#[inline]
#[allow(clippy::too_many_arguments)]
fn ssim_value(mx: f64, my: f64, exx: f64, eyy: f64, exy: f64, c1: f64, c2: f64) -> f64 {
    let mxy = mx * my;
    let mxx = mx * mx;
    let myy = my * my;
    let sxx = exx - mxx;
    let syy = eyy - myy;
    let sxy = exy - mxy;
    ((2.0 * mxy + c1) * (2.0 * sxy + c2)) / ((mxx + myy + c1) * (sxx + syy + c2))
}

/// 'valid' 1-D filtering of `src` with the symmetric 11-tap window `g`:
/// `out.len() == src.len() - 10`. Written per output sample with the taps folded in symmetric
/// pairs (6 multiplications), which the compiler vectorises across outputs.
#[inline]
pub(crate) fn filter_row_valid<T: Copy + Into<f64>>(src: &[T], g: &[f64; SSIM_WINDOW], out: &mut [f64]) {
    debug_assert_eq!(out.len() + SSIM_WINDOW - 1, src.len());
    let [g0, g1, g2, g3, g4, g5, ..] = *g;
    for (o, w) in out.iter_mut().zip(src.windows(SSIM_WINDOW)) {
        let w: [f64; SSIM_WINDOW] = std::array::from_fn(|i| w[i].into());
        *o = g5 * w[5]
            + g0 * (w[0] + w[10])
            + g1 * (w[1] + w[9])
            + g2 * (w[2] + w[8])
            + g3 * (w[3] + w[7])
            + g4 * (w[4] + w[6]);
    }
}

/// 'valid' vertical filtering: `out[j] = Σk g[k] rows[k][j]`, taps folded as in
/// [`filter_row_valid`].
#[inline]
pub(crate) fn filter_column_valid(rows: [&[f64]; SSIM_WINDOW], g: &[f64; SSIM_WINDOW], out: &mut [f64]) {
    let n = out.len();
    let [g0, g1, g2, g3, g4, g5, ..] = *g;
    let r: [&[f64]; SSIM_WINDOW] = rows.map(|row| &row[..n]);
    for (j, o) in out.iter_mut().enumerate() {
        *o = g5 * r[5][j]
            + g0 * (r[0][j] + r[10][j])
            + g1 * (r[1][j] + r[9][j])
            + g2 * (r[2][j] + r[8][j])
            + g3 * (r[3][j] + r[7][j])
            + g4 * (r[4][j] + r[6][j]);
    }
}

/// Output rows per parallel task of [`ssim_channel_fast`]: large enough that recomputing the
/// 10 rows of overlap between bands costs little, small enough for several tasks per core.
const BAND_ROWS: usize = 64;

/// Mean SSIM of channel `c`, separable filtering. The 'valid' output rows are split into bands
/// processed in parallel; inside a band the four horizontally filtered quantities (x, y,
/// x² + y², xy) of the last 11 input rows are kept in a ring buffer (cache-sized), from which the
/// vertical pass makes one row of the SSIM map at a time. Band sums are added in a fixed order,
/// so the result does not depend on the thread schedule.
fn ssim_channel_fast(a: &RgbImage, b: &RgbImage, c: usize, c1: f64, c2: f64) -> f64 {
    let (width, height) = (a.width, a.height);
    let g = gaussian_1d();
    let wv = width - (SSIM_WINDOW - 1);
    let hv = height - (SSIM_WINDOW - 1);
    let stride = 4 * wv;
    let band_starts: Vec<usize> = (0..hv).step_by(BAND_ROWS).collect();
    let band_sums: Vec<f64> = band_starts
        .par_iter()
        .map(|&i0| {
            let i1 = (i0 + BAND_ROWS).min(hv);
            let mut ring = vec![0.0f64; SSIM_WINDOW * stride];
            let mut quantities = vec![0.0f64; 4 * width];
            let mut acc = vec![0.0f64; stride];
            let mut sum = 0.0;
            let mut filter_input_row = |r: usize, ring: &mut [f64]| {
                let (qx, rest) = quantities.split_at_mut(width);
                let (qy, rest) = rest.split_at_mut(width);
                let (qsq, qxy) = rest.split_at_mut(width);
                let row_a = &a.pixels[r * width..(r + 1) * width];
                let row_b = &b.pixels[r * width..(r + 1) * width];
                for j in 0..width {
                    let (u, v) = (row_a[j][c] as f64, row_b[j][c] as f64);
                    qx[j] = u;
                    qy[j] = v;
                    qsq[j] = u * u + v * v;
                    qxy[j] = u * v;
                }
                let slot = &mut ring[(r % SSIM_WINDOW) * stride..(r % SSIM_WINDOW + 1) * stride];
                for (q, out) in slot.chunks_exact_mut(wv).enumerate() {
                    filter_row_valid(&quantities[q * width..(q + 1) * width], &g, out);
                }
            };
            for r in i0..i0 + SSIM_WINDOW - 1 {
                filter_input_row(r, &mut ring);
            }
            for i in i0..i1 {
                filter_input_row(i + SSIM_WINDOW - 1, &mut ring);
                let row = |k: usize| {
                    let s = (i + k) % SSIM_WINDOW;
                    &ring[s * stride..(s + 1) * stride]
                };
                filter_column_valid(std::array::from_fn(row), &g, &mut acc);
                let (mx, rest) = acc.split_at(wv);
                let (my, rest) = rest.split_at(wv);
                let (esq, exy) = rest.split_at(wv);
                sum += (0..wv).map(|j| ssim_value_combined(mx[j], my[j], esq[j], exy[j], c1, c2)).sum::<f64>();
            }
            sum
        })
        .collect();
    band_sums.iter().sum::<f64>() / (wv * hv) as f64
}

/// Mean SSIM of one channel by direct 11×11 weighted sums at every valid window position.
fn ssim_channel_direct(a: &RgbImage, b: &RgbImage, c: usize, c1: f64, c2: f64) -> f64 {
    let (x, y) = (a.channel(c), b.channel(c));
    let (width, height) = (a.width, a.height);
    let w = gaussian_2d();
    let mut total = 0.0;
    let mut count = 0usize;
    for i in 0..=height - SSIM_WINDOW {
        for j in 0..=width - SSIM_WINDOW {
            let (mut mx, mut my, mut exx, mut eyy, mut exy) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for (u, wrow) in w.iter().enumerate() {
                for (v, &wt) in wrow.iter().enumerate() {
                    let idx = (i + u) * width + (j + v);
                    let (a, b) = (x[idx], y[idx]);
                    mx += wt * a;
                    my += wt * b;
                    exx += wt * a * a;
                    eyy += wt * b * b;
                    exy += wt * a * b;
                }
            }
            total += ssim_value(mx, my, exx, eyy, exy, c1, c2);
            count += 1;
        }
    }
    total / count as f64
}

/// SSIM of `a` against `b` (see the module comment), fast separable implementation.
///
/// Errors if the images differ in size, are smaller than 11×11, or contain a non-finite sample.
///
/// ```
/// use inimtrace::metrics::{ssim, SsimConstants};
/// use inimtrace::raster::RgbImage;
///
/// // A horizontal ramp against itself and against its mirror image.
/// let mut a = RgbImage::new(32, 32);
/// let mut b = RgbImage::new(32, 32);
/// for r in 0..32 {
///     for c in 0..32 {
///         a.set(r, c, [c as f32 / 31.0; 3]);
///         b.set(r, c, [(31 - c) as f32 / 31.0; 3]);
///     }
/// }
/// assert!((ssim(&a, &a, SsimConstants::Wang2004)?.mean - 1.0).abs() < 1e-9);
/// // Anti-correlated structure: SSIM below 0 with the data's own constants...
/// assert!(ssim(&a, &b, SsimConstants::Wang2004)?.mean < 0.0);
/// // ...while the published framework's 8-bit constants, which dwarf the data's variances,
/// // keep it above 0.9.
/// assert!(ssim(&a, &b, SsimConstants::Framework8Bit)?.mean > 0.9);
/// # Ok::<(), inimtrace::Error>(())
/// ```
pub fn ssim(a: &RgbImage, b: &RgbImage, constants: SsimConstants) -> Result<Ssim> {
    ssim_with(a, b, constants, ssim_channel_fast)
}

/// SSIM computed by direct 11×11 sums at every window position: the slow, obviously correct
/// twin of [`ssim`] (same definition, same errors), for tests.
pub fn ssim_direct(a: &RgbImage, b: &RgbImage, constants: SsimConstants) -> Result<Ssim> {
    ssim_with(a, b, constants, ssim_channel_direct)
}

type ChannelSsim = fn(&RgbImage, &RgbImage, usize, f64, f64) -> f64;

fn ssim_with(a: &RgbImage, b: &RgbImage, constants: SsimConstants, f: ChannelSsim) -> Result<Ssim> {
    check_pair(a, b, "SSIM")?;
    if a.width < SSIM_WINDOW || a.height < SSIM_WINDOW {
        return Err(Error::invalid(
            "SSIM",
            "image size",
            format!("{}x{} image is smaller than the {SSIM_WINDOW}x{SSIM_WINDOW} SSIM window", a.width, a.height),
        ));
    }
    let (c1, c2) = constants.c1_c2();
    let per: Vec<f64> = (0..3).into_par_iter().map(|c| f(a, b, c, c1, c2)).collect();
    let channels = [per[0], per[1], per[2]];
    Ok(Ssim { channels, mean: channels.iter().sum::<f64>() / 3.0 })
}

/// Both images the same, non-zero size, every sample finite.
fn check_pair(a: &RgbImage, b: &RgbImage, metric: &str) -> Result<()> {
    if a.width != b.width || a.height != b.height {
        return Err(Error::invalid(
            metric,
            "image size",
            format!("cannot compare a {}x{} image with a {}x{} image", a.width, a.height, b.width, b.height),
        ));
    }
    if a.width == 0 || a.height == 0 {
        return Err(Error::invalid(metric, "image size", "images are empty"));
    }
    for (name, img) in [("first", a), ("second", b)] {
        if img.pixels.len() != img.width * img.height {
            return Err(Error::invalid(
                metric,
                "pixels",
                format!("{name} image has {} pixels, expected {}x{}", img.pixels.len(), img.width, img.height),
            ));
        }
        if let Some(i) = img.pixels.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(Error::invalid(
                metric,
                "pixels",
                format!("{name} image has a non-finite sample at (row {}, col {})", i / img.width, i % img.width),
            ));
        }
    }
    Ok(())
}
