//! Retinal images (paper Sec. 2.3 and 4.1).
//!
//! - Perceived image ([`simulate`]): for each retina sample and pupil sample, trace retina ->
//!   pupil -> lenslet plane -> refraction at the nearest lenslet -> LCD (eq. (1)) through the eye
//!   case's [`OpticalSystem`], and read the display image there (box pixels). A ray that misses
//!   the LCD carries black and still counts in the pixel's average, so no pixel is ever 0/0.
//! - Ground truth ([`ground_truth`]): the same eye rays, leaving the eye, straight into the scene
//!   ([`OpticalSystem::scene_only`]).
//!
//! The paper's pinhole eye is the one-sample limit: the chief ray through the pupil centre.

use glam::DVec3;
use rayon::prelude::*;

use super::field::{bounds, RadianceField, Sample};
use crate::error::{Error, Result};
use crate::optics::system::{GridBuffers, OpticalSystem, Traced, Traces, MISS};
use crate::optics::{Display, Eye, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;

pub use super::display_stack::DisplayStack;

/// Simulates what the eye sees of each display image in `displays` (all with the LCD's
/// resolution). Convenience wrapper over [`simulate_stack`].
///
/// Errors when a display image does not have the LCD's resolution.
///
/// ```
/// use inimtrace::optics::{Display, Eye, Focus, Retina};
/// use inimtrace::progress::Progress;
/// use inimtrace::raster::RgbImage;
/// use inimtrace::render::simulate;
///
/// let mut display = Display::paper();
/// display.lcd.resolution = [270, 270];
/// let retina = Retina { resolution: 16, ..Retina::default() };
/// let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 4);
/// // A uniformly lit LCD: every ray that reaches the panel reads the same colour, so no retina
/// // pixel can be brighter than the panel, and the central ones see it through every pupil point.
/// let white = RgbImage::filled(270, 270, [1.0, 0.5, 0.25]);
/// let seen = simulate(&display, &eye, &retina, &[&white], &Progress::hidden())?.remove(0);
/// assert_eq!((seen.width, seen.height), (16, 16));
/// assert!(seen.pixels.iter().all(|p| p[0] <= 1.0 + 1e-6 && p[1] <= 0.5 + 1e-6));
/// let centre = seen.get(8, 8);
/// assert!((centre[0] - 1.0).abs() < 1e-6 && (centre[2] - 0.25).abs() < 1e-6, "{centre:?}");
/// // A display image of the wrong size is refused.
/// let small = RgbImage::new(10, 10);
/// assert!(simulate(&display, &eye, &retina, &[&small], &Progress::hidden()).is_err());
/// # Ok::<(), inimtrace::Error>(())
/// ```
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
    crate::optics::transfer::check_eye_in_front(display, eye.position.z, "eye", "position")?;
    if stack.width() != display.lcd.columns() || stack.height() != display.lcd.rows() {
        return Err(Error::Mismatch("display stack does not match the display's LCD resolution".into()));
    }
    let m = stack.len();
    let stride = 3 * m;
    let n = retina.resolution;
    let system = OpticalSystem::geometric(display, eye);
    let inv = 1.0 / system.grid_samples_per_pixel(retina) as f64;
    let mut images: Vec<RgbImage> =
        (0..m).map(|_| RgbImage::try_new(n, n, "a retinal image")).collect::<Result<_>>()?;
    let mut rows = crate::budget::try_vec(n * n * stride, 0f32, "the retinal images' rows")?;
    if stride == 0 {
        return Ok(images);
    }
    // Row by row, each row's samples in the order the system traces its grid best (for the
    // thin lens's closed form, blocks of BLOCK columns pupil point by pupil point: the rays of
    // one pupil point from one block land in one small patch of the LCD, which then stays in
    // cache). Every pixel still sums its samples in one order (sub-pixel point, pupil point,
    // spectral number), so the result does not depend on it.
    const BLOCK: usize = 32;
    let no_draws = |_: u64, _: u64| [0.0; 4];
    rows.par_chunks_mut(n * stride).enumerate().for_each_init(
        || (GridBuffers::default(), vec![0f64; n * stride]),
        |(buf, acc), (row, out)| {
            if progress.cancelled() {
                return;
            }
            acc.iter_mut().for_each(|a| *a = 0.0);
            system.trace_grid(retina, row..row + 1, BLOCK, false, &no_draws, buf, |pixels, traces| {
                for (&p, t) in pixels.iter().zip(&traces.samples) {
                    let col = p as usize - row * n;
                    add_traced(&mut acc[col * stride..(col + 1) * stride], t, stack);
                }
            });
            for (o, a) in out.iter_mut().zip(acc.iter()) {
                *o = (*a * inv) as f32;
            }
            progress.inc(1);
        },
    );
    progress.check()?;
    for (i, px) in rows.chunks_exact(stride).enumerate() {
        for (k, img) in images.iter_mut().enumerate() {
            img.pixels[i] = [px[3 * k], px[3 * k + 1], px[3 * k + 2]];
        }
    }
    Ok(images)
}

/// `dst += weight * stack.pixel(lcd)` for every channel of a traced sample at its LCD pixel
/// (none: off the LCD or blocked; the weight skipped where it is 1, the same bits).
#[inline(always)]
fn add_traced(dst: &mut [f64], t: &Traced, stack: &DisplayStack) {
    let w = t.weight;
    if t.shared {
        if t.lcd[0] == MISS {
        } else if w == 1.0 {
            add_samples(dst, std::iter::once(t.lcd[0]), stack);
        } else {
            let px = stack.pixel(t.lcd[0] as usize);
            dst.iter_mut().zip(px).for_each(|(a, v)| *a += f64::from(*v) * w);
        }
        return;
    }
    for c in 0..3 {
        if t.lcd[c] != MISS {
            let px = stack.pixel(t.lcd[c] as usize);
            for (a, v) in dst.chunks_exact_mut(3).zip(px.chunks_exact(3)) {
                a[c] += f64::from(v[c]) * w;
            }
        }
    }
}

/// `dst += stack.pixel(i)` for each LCD pixel `i` of `indices` in turn (`u32::MAX`: off the LCD,
/// adds nothing). For the common strides (one to three display images) the run is summed in
/// registers from `dst`: the same additions in the same order, without a store and a load per
/// sample.
#[inline(always)]
fn add_samples(dst: &mut [f64], indices: impl Iterator<Item = u32>, stack: &DisplayStack) {
    #[inline(always)]
    fn fixed<const N: usize>(dst: &mut [f64], indices: impl Iterator<Item = u32>, stack: &DisplayStack) {
        let d: &mut [f64; N] = dst.try_into().expect("stride");
        let mut a = *d;
        for idx in indices {
            if idx != u32::MAX {
                let s: &[f32; N] = stack.pixel(idx as usize).try_into().expect("stride");
                for j in 0..N {
                    a[j] += s[j] as f64;
                }
            }
        }
        *d = a;
    }
    match dst.len() {
        3 => fixed::<3>(dst, indices, stack),
        6 => fixed::<6>(dst, indices, stack),
        9 => fixed::<9>(dst, indices, stack),
        _ => add_samples_each(dst, indices, stack),
    }
}

/// The slow twin of [`add_samples`]: into memory, sample by sample.
fn add_samples_each(dst: &mut [f64], indices: impl Iterator<Item = u32>, stack: &DisplayStack) {
    for idx in indices.filter(|&i| i != u32::MAX) {
        dst.iter_mut().zip(stack.pixel(idx as usize)).for_each(|(a, v)| *a += f64::from(*v));
    }
}

/// The ground-truth retinal image: the eye looking straight at the scene, every grid sample's
/// scene rays traced through the eye alone ([`OpticalSystem::scene_only`]).
pub fn ground_truth<R: RadianceField + ?Sized>(
    eye: &Eye,
    retina: &Retina,
    tracer: &R,
    progress: &Progress,
) -> RgbImage {
    let system = OpticalSystem::scene_only(eye);
    let n = retina.resolution;
    let per_pixel = system.grid_samples_per_pixel(retina);
    let inv = 1.0 / per_pixel as f64;
    let mut image = RgbImage::new(n, n);
    let no_draws = |_: u64, _: u64| [0.0; 4];
    if !tracer.prefers_batches() {
        // Pixel by pixel, one ray at a time straight to the field's radiance (no depth, no
        // buffers); a pixel whose rays the field knows to bring back one colour adds that colour
        // for each of them.
        let pupil_box = bounds(system.pupil_grid().iter().copied());
        let frac_box = bounds(retina.subpixel_offsets());
        image.pixels.par_chunks_mut(n).enumerate().for_each_init(
            || (Vec::new(), Traces::default(), Vec::new()),
            |(samples, traces, radiance), (row, out)| {
                if progress.cancelled() {
                    return;
                }
                // (colour, its sum over a pixel's samples): the same additions as adding it ray by ray.
                let mut last_sum = (DVec3::NAN, DVec3::NAN);
                for (col, px) in out.iter_mut().enumerate() {
                    let tangents = (retina.tangent(row, col, frac_box.0), retina.tangent(row, col, frac_box.1));
                    let family = if per_pixel >= 4 { system.ray_family(tangents, pupil_box) } else { None };
                    let sum = if let Some((c, _)) = family.and_then(|f| tracer.uniform(&f)) {
                        if last_sum.0.to_array().map(f64::to_bits) != c.to_array().map(f64::to_bits) {
                            last_sum = (c, (0..per_pixel).fold(DVec3::ZERO, |sum, _| sum + c));
                        }
                        last_sum.1
                    } else {
                        system.grid_samples(retina, (row, col), &no_draws, samples);
                        system.trace(samples, &[], traces);
                        radiance.clear();
                        radiance.extend(traces.scene.iter().map(|r| tracer.radiance(r)));
                        sum_traced(&traces.samples, radiance)
                    };
                    let v = sum * inv;
                    *px = [v.x as f32, v.y as f32, v.z as f32];
                }
                progress.inc(1);
            },
        );
        return image;
    }
    // Rays of a block of one retina row go to the field together, laid out (for the thin lens's
    // closed form) [sub-pixel][pupil][column] so that consecutive rays are neighbouring pixels
    // through the same pupil point (coherent runs for packets); every pixel sums in the order
    // sub-pixel sample, then pupil sample.
    const BLOCK: usize = 128;
    image.pixels.par_chunks_mut(n).enumerate().for_each_init(
        || (GridBuffers::default(), Vec::new(), vec![DVec3::ZERO; n], Vec::new()),
        |(buf, hits, sums, owned), (row, out)| {
            if progress.cancelled() {
                return;
            }
            sums.iter_mut().for_each(|s| *s = DVec3::ZERO);
            system.trace_grid(retina, row..row + 1, BLOCK, true, &no_draws, buf, |pixels, traces| {
                hits.clear();
                hits.resize(traces.scene.len(), Sample::default());
                tracer.sample_many(&traces.scene, hits);
                owned.clear();
                owned.extend(hits.iter().map(|h: &Sample| h.radiance));
                for (&p, t) in pixels.iter().zip(&traces.samples) {
                    let sum = &mut sums[p as usize - row * n];
                    *sum = add_traced_radiance(*sum, t, owned);
                }
            });
            for (px, sum) in out.iter_mut().zip(sums.iter()) {
                let v = *sum * inv;
                *px = [v.x as f32, v.y as f32, v.z as f32];
            }
            progress.inc(1);
        },
    );
    image
}

/// The sum over traced samples of their channels' radiance times their weight.
fn sum_traced(samples: &[Traced], radiance: &[DVec3]) -> DVec3 {
    samples.iter().fold(DVec3::ZERO, |sum, t| add_traced_radiance(sum, t, radiance))
}

/// `sum` plus a traced sample's channels' radiance times its weight (the weight skipped where it
/// is 1, the same bits).
#[inline(always)]
fn add_traced_radiance(sum: DVec3, t: &Traced, radiance: &[DVec3]) -> DVec3 {
    if t.single {
        return match t.scene_ray(0) {
            Some(j) if t.weight == 1.0 => sum + radiance[j],
            Some(j) => sum + radiance[j] * t.weight,
            None => sum,
        };
    }
    let mut sum = sum;
    for c in 0..3 {
        if let Some(j) = t.scene_ray(c) {
            sum[c] += radiance[j][c] * t.weight;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::Lcg;
    use crate::optics::transfer::{eye_scene_ray, FastTransfer};
    use crate::optics::Focus;
    use crate::raster::RgbView;
    use crate::render::display_stack::StackBuilder;
    use glam::DVec2;

    /// Sample by sample, ray by ray: the slow twin of [`simulate_stack`].
    fn simulate_ray_by_ray(display: &Display, eye: &Eye, retina: &Retina, stack: &DisplayStack) -> Vec<RgbImage> {
        let (pupil, subpixels) = (eye.pupil_samples(), retina.subpixel_offsets());
        let fast = FastTransfer::new(display, eye, &pupil);
        let inv_count = 1.0 / (pupil.len() * subpixels.len()) as f64;
        let n = retina.resolution;
        let mut images: Vec<RgbImage> = (0..stack.len()).map(|_| RgbImage::new(n, n)).collect();
        for row in 0..n {
            for col in 0..n {
                let mut sum = vec![0.0f64; 3 * stack.len()];
                for frac in &subpixels {
                    let t = retina.tangent(row, col, *frac);
                    for k in 0..pupil.len() {
                        if let Some(i) = fast.pixel_index(t, k) {
                            add_samples_each(&mut sum, std::iter::once(i as u32), stack);
                        }
                    }
                }
                for (m, img) in images.iter_mut().enumerate() {
                    img.pixels[row * n + col] = std::array::from_fn(|c| (sum[3 * m + c] * inv_count) as f32);
                }
            }
        }
        images
    }

    #[test]
    fn the_tiled_simulation_sums_every_ray_as_the_ray_by_ray_twin() {
        let mut display = Display::paper();
        display.lcd.resolution = [300, 240];
        let (w, h) = (300, 240);
        let mut rng = Lcg(8);
        // Few distinct values (the palette layout) and all distinct (dense).
        let few: Vec<RgbImage> = (0..4)
            .map(|m| {
                let mut img = RgbImage::new(w, h);
                for (i, px) in img.pixels.iter_mut().enumerate() {
                    *px = [((i / 7 + m) % 3) as f32 * 0.25, 0.5, ((i % 11) % 2) as f32];
                }
                img
            })
            .collect();
        let dense: Vec<RgbImage> = (0..3)
            .map(|_| {
                let mut img = RgbImage::new(w, h);
                img.pixels.iter_mut().for_each(|px| *px = std::array::from_fn(|_| rng.next() as f32));
                img
            })
            .collect();
        let eyes = [Eye::thin_lens(5.0, Focus::Millimetres(350.0), 6), Eye::pinhole()];
        for eye in &eyes {
            for samples_per_pixel in [1, 2] {
                let retina = Retina { resolution: 37, half_tangent: 0.3, samples_per_pixel };
                for images in [&few[..1], &few[..2], &few[..3], &few[..], &dense[..]] {
                    let refs: Vec<&RgbImage> = images.iter().collect();
                    // Packed at once (dense) and image by image (a palette while it fits).
                    let mut builder = StackBuilder::new(&display, images.len());
                    for img in images {
                        builder.push(RgbView::from(img)).unwrap();
                    }
                    let built = builder.finish().unwrap();
                    let is_dense = std::ptr::eq(images.as_ptr(), dense.as_ptr());
                    assert_eq!(built.is_palette(), !is_dense, "{} images", images.len());
                    for stack in [DisplayStack::new(&display, &refs).unwrap(), built] {
                        let tiled = simulate_stack(&display, eye, &retina, &stack, &Progress::hidden()).unwrap();
                        let twin = simulate_ray_by_ray(&display, eye, &retina, &stack);
                        assert!(tiled == twin, "{} images, {eye:?}, {samples_per_pixel}", images.len());
                    }
                }
            }
        }
    }

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
                let family = OpticalSystem::scene_only(eye).ray_family((corner, corner + size), (p0, p0 + p1)).unwrap();
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
