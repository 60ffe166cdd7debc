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
/// SSIM stabilising constant factors `K1`, `K2` (Wang et al. 2004).
pub const SSIM_K1: f64 = 0.01;
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
    let mse = sse / a.len() as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}

/// PSNR of an RGB image pair: the three channel PSNRs (R, G, B) and their mean.
///
/// `mean` is infinite when any channel is identical in both images.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Psnr {
    pub channels: [f64; 3],
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
pub fn psnr(a: &RgbImage, b: &RgbImage) -> Result<Psnr> {
    check_pair(a, b, "PSNR")?;
    let mut channels = [0.0; 3];
    for (c, out) in channels.iter_mut().enumerate() {
        *out = psnr_channel(&a.channel(c), &b.channel(c));
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
        SsimConstants::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                Error::invalid(
                    "SSIM constants",
                    "name",
                    format!(
                        "unknown SSIM constants `{s}` (expected `wang2004` or `framework-8bit`)"
                    ),
                )
            })
    }
}

/// SSIM of an RGB image pair: the mean SSIM of each channel (R, G, B) and their mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ssim {
    pub channels: [f64; 3],
    pub mean: f64,
}

/// The normalised 1-D Gaussian window; its outer product with itself is the normalised 2-D
/// window of `fspecial('gaussian', 11, 1.5)` (up to rounding).
fn gaussian_1d() -> [f64; SSIM_WINDOW] {
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

/// `out[j] += gk * (a[j] + b[j])`, written so that it vectorises.
#[inline]
fn accumulate_pair(out: &mut [f64], gk: f64, a: &[f64], b: &[f64]) {
    let n = out.len();
    for ((o, &p), &q) in out.iter_mut().zip(&a[..n]).zip(&b[..n]) {
        *o += gk * (p + q);
    }
}

/// 'valid' 1-D filtering of `src` with the symmetric window `g`: `out.len() == src.len() - 10`.
fn filter_row_valid(src: &[f64], g: &[f64; SSIM_WINDOW], out: &mut [f64]) {
    let n = out.len();
    debug_assert_eq!(n + SSIM_WINDOW - 1, src.len());
    for (o, &s) in out.iter_mut().zip(&src[HALF..HALF + n]) {
        *o = g[HALF] * s;
    }
    for k in 0..HALF {
        accumulate_pair(
            out,
            g[k],
            &src[k..k + n],
            &src[SSIM_WINDOW - 1 - k..SSIM_WINDOW - 1 - k + n],
        );
    }
}

/// Mean SSIM of one channel, separable filtering, rows in parallel.
fn ssim_channel_fast(x: &[f64], y: &[f64], width: usize, height: usize, c1: f64, c2: f64) -> f64 {
    let g = gaussian_1d();
    let wv = width - (SSIM_WINDOW - 1);
    let hv = height - (SSIM_WINDOW - 1);
    // Horizontal pass: for every image row, the five filtered quantities x, y, x², y², xy,
    // stored as [row][quantity][column].
    let stride = 5 * wv;
    let mut horiz = vec![0.0f64; height * stride];
    horiz
        .par_chunks_mut(stride)
        .enumerate()
        .for_each(|(r, out)| {
            let xr = &x[r * width..(r + 1) * width];
            let yr = &y[r * width..(r + 1) * width];
            let xx: Vec<f64> = xr.iter().map(|v| v * v).collect();
            let yy: Vec<f64> = yr.iter().map(|v| v * v).collect();
            let xy: Vec<f64> = xr.iter().zip(yr).map(|(a, b)| a * b).collect();
            for (q, src) in [xr, yr, &xx, &yy, &xy].into_iter().enumerate() {
                filter_row_valid(src, &g, &mut out[q * wv..(q + 1) * wv]);
            }
        });
    // Vertical pass and SSIM map, one output row at a time; per-row sums are added in a fixed
    // order so the result does not depend on the thread schedule.
    let row_sums: Vec<f64> = (0..hv)
        .into_par_iter()
        .map(|i| {
            let mut acc = vec![0.0f64; stride];
            let centre = &horiz[(i + HALF) * stride..(i + HALF + 1) * stride];
            for (o, &s) in acc.iter_mut().zip(centre) {
                *o = g[HALF] * s;
            }
            for k in 0..HALF {
                let a = &horiz[(i + k) * stride..(i + k + 1) * stride];
                let b = &horiz[(i + SSIM_WINDOW - 1 - k) * stride..(i + SSIM_WINDOW - k) * stride];
                accumulate_pair(&mut acc, g[k], a, b);
            }
            let (mx, rest) = acc.split_at(wv);
            let (my, rest) = rest.split_at(wv);
            let (exx, rest) = rest.split_at(wv);
            let (eyy, exy) = rest.split_at(wv);
            (0..wv)
                .map(|j| ssim_value(mx[j], my[j], exx[j], eyy[j], exy[j], c1, c2))
                .sum::<f64>()
        })
        .collect();
    row_sums.iter().sum::<f64>() / (wv * hv) as f64
}

/// Mean SSIM of one channel by direct 11×11 weighted sums at every valid window position.
fn ssim_channel_direct(x: &[f64], y: &[f64], width: usize, height: usize, c1: f64, c2: f64) -> f64 {
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
pub fn ssim(a: &RgbImage, b: &RgbImage, constants: SsimConstants) -> Result<Ssim> {
    ssim_with(a, b, constants, ssim_channel_fast)
}

/// SSIM computed by direct 11×11 sums at every window position: the slow, obviously correct
/// twin of [`ssim`] (same definition, same errors), for tests.
pub fn ssim_direct(a: &RgbImage, b: &RgbImage, constants: SsimConstants) -> Result<Ssim> {
    ssim_with(a, b, constants, ssim_channel_direct)
}

type ChannelSsim = fn(&[f64], &[f64], usize, usize, f64, f64) -> f64;

fn ssim_with(a: &RgbImage, b: &RgbImage, constants: SsimConstants, f: ChannelSsim) -> Result<Ssim> {
    check_pair(a, b, "SSIM")?;
    if a.width < SSIM_WINDOW || a.height < SSIM_WINDOW {
        return Err(Error::invalid(
            "SSIM",
            "image size",
            format!(
                "{}x{} image is smaller than the {SSIM_WINDOW}x{SSIM_WINDOW} SSIM window",
                a.width, a.height
            ),
        ));
    }
    let (c1, c2) = constants.c1_c2();
    let per: Vec<f64> = (0..3)
        .into_par_iter()
        .map(|c| f(&a.channel(c), &b.channel(c), a.width, a.height, c1, c2))
        .collect();
    let channels = [per[0], per[1], per[2]];
    Ok(Ssim {
        channels,
        mean: channels.iter().sum::<f64>() / 3.0,
    })
}

/// Both images the same, non-zero size, every sample finite.
fn check_pair(a: &RgbImage, b: &RgbImage, metric: &str) -> Result<()> {
    if a.width != b.width || a.height != b.height {
        return Err(Error::invalid(
            metric,
            "image size",
            format!(
                "cannot compare a {}x{} image with a {}x{} image",
                a.width, a.height, b.width, b.height
            ),
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
                format!(
                    "{name} image has {} pixels, expected {}x{}",
                    img.pixels.len(),
                    img.width,
                    img.height
                ),
            ));
        }
        if let Some(i) = img
            .pixels
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        {
            return Err(Error::invalid(
                metric,
                "pixels",
                format!(
                    "{name} image has a non-finite sample at (row {}, col {})",
                    i / img.width,
                    i % img.width
                ),
            ));
        }
    }
    Ok(())
}
