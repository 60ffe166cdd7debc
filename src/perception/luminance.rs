//! Luminance PSNR: the PSNR of the images' luminance `Y = w_R R + w_G G + w_B B` (peak: the
//! white's, 1), beside the paper's mean of the three channel PSNRs (Sec. 4.2). The weights are
//! the display primaries' shares of the white's luminance; for the metrics' BT.709 primaries,
//! Rec. ITU-R BT.709's 0.2126, 0.7152, 0.0722. For the converged estimator the MSE comes, as the
//! channel PSNR's does (`measure/stats.rs`), from products of different replicates (no noise
//! bias), with the same jackknife interval.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::measure::estimator::Replicates;
use crate::measure::stats::{psnr_estimate, Estimate, Gram};
use crate::raster::RgbImage;

/// Luminance PSNR of `a` against `b` with luminance `weights`, dB (`inf` for equal luminance).
pub fn psnr_luminance(a: &RgbImage, b: &RgbImage, weights: [f64; 3]) -> Result<f64> {
    if a.width != b.width || a.height != b.height || a.pixels.len() != b.pixels.len() || a.pixels.is_empty() {
        return Err(Error::invalid(
            "luminance PSNR",
            "image size",
            format!("cannot compare a {}x{} image with a {}x{} image", a.width, a.height, b.width, b.height),
        ));
    }
    if !a.all_finite() || !b.all_finite() {
        return Err(Error::invalid("luminance PSNR", "pixels", "an image has a non-finite sample"));
    }
    let y = |p: &[f32; 3]| (0..3).map(|c| weights[c] * f64::from(p[c])).sum::<f64>();
    let sse: f64 = a
        .pixels
        .par_chunks(16_384)
        .zip(b.pixels.par_chunks(16_384))
        .map(|(pa, pb)| pa.iter().zip(pb).map(|(p, q)| (y(p) - y(q)).powi(2)).sum::<f64>())
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    let mse = sse / a.pixels.len() as f64;
    Ok(if mse == 0.0 { f64::INFINITY } else { -10.0 * mse.log10() })
}

/// The R x R Gram matrix of the luminance differences of image `k` against image 0 of `reps`,
/// summed over pixels (rows in parallel, added in row order: the same bits at any thread count).
fn luminance_gram(reps: &Replicates, k: usize, weights: [f64; 3]) -> Vec<f64> {
    let n = reps.resolution();
    let nr = reps.replicates();
    let rows: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|row| {
            let mut g = vec![0.0; nr * nr];
            let mut d = vec![0.0; n * nr];
            for r in 0..nr {
                for (c, w) in weights.iter().enumerate() {
                    let x = &reps.plane(r, 0, c)[row * n..(row + 1) * n];
                    let y = &reps.plane(r, k, c)[row * n..(row + 1) * n];
                    for (p, (a, b)) in x.iter().zip(y).enumerate() {
                        d[p * nr + r] += w * (f64::from(*b) - f64::from(*a));
                    }
                }
            }
            for dp in d.chunks_exact(nr) {
                for a in 0..nr {
                    for b in a..nr {
                        g[a * nr + b] += dp[a] * dp[b];
                    }
                }
            }
            g
        })
        .collect();
    let mut g = vec![0.0; nr * nr];
    for row in &rows {
        for (a, b) in g.iter_mut().zip(row) {
            *a += b;
        }
    }
    for a in 0..nr {
        for b in 0..a {
            g[a * nr + b] = g[b * nr + a];
        }
    }
    g
}

/// The luminance PSNR of image `k` of `reps` against image 0 without noise bias, with its 95%
/// interval (the channel PSNR's estimator on the one luminance plane).
pub fn psnr_luminance_estimate(reps: &Replicates, k: usize, weights: [f64; 3]) -> Estimate {
    let g = luminance_gram(reps, k, weights);
    let n = reps.resolution();
    let gram = Gram { replicates: reps.replicates(), pixels: n * n, g: [g.clone(), g.clone(), g] };
    let e = psnr_estimate(&gram);
    Estimate {
        channels: e.channels,
        mean: e.channels[0],
        ci95: e.channels_ci95.map(|h| h[0]),
        channels_ci95: e.channels_ci95,
    }
}
