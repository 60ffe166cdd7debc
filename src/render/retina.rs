//! Retinal images (paper Sec. 2.3 and 4.1).
//!
//! - Perceived image ([`simulate`]): for each retina sample and pupil sample, trace retina ->
//!   pupil (thin lens) -> lenslet plane -> refraction at the nearest lenslet -> LCD (eq. (1),
//!   [`FastTransfer`]), and read the display image there (box pixels). A ray that misses the
//!   LCD carries black and still counts in the pixel's average, so no pixel is ever 0/0.
//! - Ground truth ([`ground_truth`]): the same eye rays, leaving the eye lens, straight into the
//!   scene ([`eye_scene_ray`]).
//!
//! The paper's pinhole eye is the one-sample limit: the chief ray through the pupil centre.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::field::{RadianceField, Sample};
use crate::error::{Error, Result};
use crate::optics::transfer::{eye_scene_ray, FastTransfer};
use crate::optics::{Display, Eye, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;

pub use super::display_stack::DisplayStack;

/// Simulates what the eye sees of each display image in `displays` (all with the LCD's
/// resolution). Convenience wrapper over [`simulate_stack`].
pub fn simulate(
    display: &Display,
    eye: &Eye,
    retina: &Retina,
    displays: &[&RgbImage],
    progress: &Progress,
) -> Result<Vec<RgbImage>> {
    let stack = DisplayStack::new(display, displays)?;
    simulate_stack(display, eye, retina, &stack, progress)
}

/// Simulates what the eye sees of every display image in `stack`. Each ray is traced once and
/// read from every image.
pub fn simulate_stack(
    display: &Display,
    eye: &Eye,
    retina: &Retina,
    stack: &DisplayStack,
    progress: &Progress,
) -> Result<Vec<RgbImage>> {
    if stack.width() != display.lcd.columns() || stack.height() != display.lcd.rows() {
        return Err(Error::Unsupported("display stack does not match the display's LCD resolution".into()));
    }
    let m = stack.len();
    let stride = 3 * m;
    let n = retina.resolution;
    let pupil = eye.pupil_samples();
    let subpixels = retina.subpixel_offsets();
    let inv_count = 1.0 / (pupil.len() * subpixels.len()) as f64;
    let fast = FastTransfer::new(display, eye, &pupil);

    let mut images: Vec<RgbImage> = (0..m).map(|_| RgbImage::new(n, n)).collect();
    let mut rows = vec![0f32; n * n * stride];
    if stride == 0 {
        return Ok(images);
    }
    // Work in tiles of TILE x TILE retina pixels, pupil samples outside the tile's pixels: the
    // rays of one pupil sample from one tile land in one small patch of the LCD, which then
    // stays in cache. Every pixel still sums its samples in the same order (sub-pixel sample,
    // then pupil sample), so the result does not depend on the tiling.
    const TILE: usize = 16;
    rows.par_chunks_mut(TILE * n * stride).enumerate().for_each(|(band, out)| {
        let row0 = band * TILE;
        let band_rows = out.len() / (n * stride);
        let mut acc = vec![0f64; TILE * TILE * stride];
        let mut tangents = vec![DVec2::ZERO; TILE * TILE];
        let (mut lcd, mut scratch) = (vec![0u32; TILE * TILE], Vec::new());
        for col0 in (0..n).step_by(TILE) {
            let tile_cols = TILE.min(n - col0);
            acc.iter_mut().for_each(|a| *a = 0.0);
            for frac in &subpixels {
                for r in 0..band_rows {
                    for c in 0..tile_cols {
                        tangents[r * TILE + c] = retina.tangent(row0 + r, col0 + c, *frac);
                    }
                }
                for k in 0..pupil.len() {
                    // Every pixel of the tile (rows past the band's end unused).
                    fast.pixel_indices(&tangents, k, &mut scratch, &mut lcd);
                    for r in 0..band_rows {
                        for c in 0..tile_cols {
                            let idx = lcd[r * TILE + c];
                            if idx != u32::MAX {
                                let dst = &mut acc[(r * TILE + c) * stride..(r * TILE + c + 1) * stride];
                                add_f32(dst, stack.pixel(idx as usize));
                            }
                        }
                    }
                }
            }
            for r in 0..band_rows {
                for c in 0..tile_cols {
                    let o = &mut out[(r * n + col0 + c) * stride..(r * n + col0 + c + 1) * stride];
                    for (o, a) in o.iter_mut().zip(&acc[(r * TILE + c) * stride..]) {
                        *o = (*a * inv_count) as f32;
                    }
                }
            }
        }
        progress.inc(band_rows as u64);
    });
    for (i, px) in rows.chunks_exact(stride).enumerate() {
        for (k, img) in images.iter_mut().enumerate() {
            img.pixels[i] = [px[3 * k], px[3 * k + 1], px[3 * k + 2]];
        }
    }
    Ok(images)
}

/// `dst += src`, unrolled for the common strides (one to three display images).
#[inline(always)]
fn add_f32(dst: &mut [f64], src: &[f32]) {
    #[inline(always)]
    fn fixed<const N: usize>(dst: &mut [f64], src: &[f32]) {
        let (d, s): (&mut [f64; N], &[f32; N]) = (dst.try_into().expect("stride"), src.try_into().expect("stride"));
        for j in 0..N {
            d[j] += s[j] as f64;
        }
    }
    match src.len() {
        3 => fixed::<3>(dst, src),
        6 => fixed::<6>(dst, src),
        9 => fixed::<9>(dst, src),
        _ => dst.iter_mut().zip(src).for_each(|(a, v)| *a += *v as f64),
    }
}

/// The ground-truth retinal image: the eye looking straight at the scene.
pub fn ground_truth<R: RadianceField + ?Sized>(
    eye: &Eye,
    retina: &Retina,
    tracer: &R,
    progress: &Progress,
) -> RgbImage {
    let n = retina.resolution;
    let pupil = eye.pupil_samples();
    let subpixels = retina.subpixel_offsets();
    let inv_count = 1.0 / (pupil.len() * subpixels.len()) as f64;
    // Rays of a block of one retina row go to the field together, laid out [sub-pixel][pupil][column] so
    // that consecutive rays are neighbouring pixels through the same pupil point (coherent runs
    // for packets); every pixel sums in the order sub-pixel sample, then pupil sample.
    let per_pixel = subpixels.len() * pupil.len();
    let mut image = RgbImage::new(n, n);
    if !tracer.prefers_batches() {
        // One ray at a time, straight to the field's radiance (no depth, no buffers).
        image.pixels.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
            for (col, px) in out.iter_mut().enumerate() {
                let mut sum = DVec3::ZERO;
                for frac in &subpixels {
                    let t = retina.tangent(row, col, *frac);
                    for s in &pupil {
                        sum += tracer.radiance(&eye_scene_ray(eye, t, *s));
                    }
                }
                let v = sum * inv_count;
                *px = [v.x as f32, v.y as f32, v.z as f32];
            }
            progress.inc(1);
        });
        return image;
    }
    let block = 128;
    image.pixels.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
        let mut rays = Vec::with_capacity(per_pixel * block);
        let mut samples = Vec::with_capacity(per_pixel * block);
        for col0 in (0..n).step_by(block) {
            let cols = block.min(n - col0);
            rays.clear();
            for frac in &subpixels {
                for s in &pupil {
                    for col in col0..col0 + cols {
                        rays.push(eye_scene_ray(eye, retina.tangent(row, col, *frac), *s));
                    }
                }
            }
            samples.clear();
            samples.resize(rays.len(), Sample::default());
            tracer.sample_many(&rays, &mut samples);
            for (c, px) in out[col0..col0 + cols].iter_mut().enumerate() {
                let mut sum = DVec3::ZERO;
                for k in 0..per_pixel {
                    sum += samples[k * cols + c].radiance;
                }
                let v = sum * inv_count;
                *px = [v.x as f32, v.y as f32, v.z as f32];
            }
        }
        progress.inc(1);
    });
    image
}
