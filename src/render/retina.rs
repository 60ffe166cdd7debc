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

use super::field::{AffineRays, RadianceField, Sample};
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

/// Component-wise bounds of `points`.
fn bounds(points: &[DVec2]) -> (DVec2, DVec2) {
    let inf = DVec2::splat(f64::INFINITY);
    points.iter().fold((inf, -inf), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// The family of eye rays [`eye_scene_ray`]`(eye, t, s)` for tangents `t` and pupil points `s`
/// in the boxes `tangents` and `pupil` (each `(low corner, high corner)`, either way round):
/// they start at `s` on the pupil plane with slope `t + s (1/v0 - d1)` (eq. (1a) with the eye
/// lens's refraction), an [`AffineRays`] family with `q = s`.
pub fn eye_rays(eye: &Eye, tangents: (DVec2, DVec2), pupil: (DVec2, DVec2)) -> AffineRays {
    let (t_lo, t_hi) = (tangents.0.min(tangents.1), tangents.0.max(tangents.1));
    AffineRays {
        origin: eye.position,
        dir: t_lo,
        q_lo: pupil.0.min(pupil.1),
        q_hi: pupil.0.max(pupil.1),
        alpha: 1.0,
        beta: 1.0 / eye.retina_distance - eye.power(),
        e_lo: DVec2::ZERO,
        e_hi: t_hi - t_lo,
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
        // One ray at a time, straight to the field's radiance (no depth, no buffers); a pixel
        // whose rays the field knows to bring back one colour adds that colour for each of them.
        let pupil_box = bounds(&pupil);
        let frac_box = bounds(&subpixels);
        let step = retina.tangent(0, 1, DVec2::ZERO) - retina.tangent(1, 0, DVec2::ZERO);
        image.pixels.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
            // (colour, its sum over a pixel's samples): the same additions as adding it ray by ray.
            let mut last_sum = (DVec3::NAN, DVec3::NAN);
            for (col, px) in out.iter_mut().enumerate() {
                let mut sum = DVec3::ZERO;
                let corner = retina.tangent(row, col, DVec2::ZERO);
                let tangents = (
                    corner + frac_box.0 * step * DVec2::new(1.0, -1.0),
                    corner + frac_box.1 * step * DVec2::new(1.0, -1.0),
                );
                let uniform = if per_pixel >= 4 { tracer.uniform(&eye_rays(eye, tangents, pupil_box)) } else { None };
                if let Some((c, _)) = uniform {
                    if last_sum.0.to_array().map(f64::to_bits) != c.to_array().map(f64::to_bits) {
                        last_sum = (c, (0..per_pixel).fold(DVec3::ZERO, |sum, _| sum + c));
                    }
                    sum = last_sum.1;
                } else {
                    for frac in &subpixels {
                        let t = retina.tangent(row, col, *frac);
                        for s in &pupil {
                            sum += tracer.radiance(&eye_scene_ray(eye, t, *s));
                        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::Lcg;
    use crate::optics::Focus;

    #[test]
    fn an_eye_family_holds_every_eye_ray_of_its_boxes() {
        let mut rng = Lcg(31);
        let mut moved = Eye::thin_lens(4.0, Focus::Millimetres(250.0), 8);
        moved.position = DVec3::new(-3.0, 2.0, 1.5);
        let eyes = [Eye::pinhole(), Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8), moved];
        for eye in &eyes {
            for _ in 0..2000 {
                let corner = DVec2::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
                let size = DVec2::new(rng.range(-0.01, 0.01), rng.range(-0.01, 0.01));
                let (p0, p1) = (DVec2::new(rng.range(-2.5, 2.5), rng.range(-2.5, 2.5)), DVec2::new(0.0, 0.3));
                let family = eye_rays(eye, (corner, corner + size), (p0, p0 + p1));
                for _ in 0..10 {
                    let t = corner + size * DVec2::new(rng.next(), rng.next());
                    let s = p0 + p1 * DVec2::new(rng.next(), rng.next());
                    let ray = eye_scene_ray(eye, t, s);
                    assert_eq!(ray.origin.z, family.origin.z);
                    assert_eq!(ray.dir.z, 1.0);
                    for d in [0.0, 1.0, 300.0, 1e4] {
                        let p = ray.origin.truncate() + ray.dir.truncate() * d;
                        let (lo, hi) = family.bounds_at(d);
                        // Rounding: a hundredth of what fields allow for (1e-12 of the magnitude).
                        let slack = family.magnitude_at(d) * 1e-14;
                        assert!(p.cmpge(lo - slack).all() && p.cmple(hi + slack).all(), "{p} {lo} {hi} {eye:?}");
                    }
                }
            }
        }
    }
}
