//! The paired estimator of the converged measurement: the ground-truth and perceived retinal
//! images of one eye case (paper Sec. 2.3, 4.1) from the same eye rays.
//!
//! Every sample of a retina pixel ([`super::sampler`]) is ONE eye ray: a point of the pixel's
//! square (its tangent) and a point of the pupil. The ray's radiance into the scene is the ground
//! truth's sample (`render::retina`'s eye rays and the radiance field); the same ray
//! traced retina -> eye lens -> lenslet -> LCD by eq. (1) reads every method's display image at
//! the LCD pixel it meets (a ray that misses the LCD carries black and still counts). Because
//! the images share their rays, the noise of their difference is much smaller than the noise of
//! each.
//!
//! [`Replicates`] keeps, for each of R independent replicates (independent scrambles) and each
//! pixel, the mean of every image over that replicate's samples; sums are taken in `f64` over a
//! pass and stored as `f32` means. More samples are added by [`Replicates::extend`] (points
//! `N..2N` of the same sequences), so nothing already traced is traced again.

use glam::DVec2;
use rayon::prelude::*;

use super::sampler::Sampler;

mod display_source;
mod pass;
pub use display_source::DisplaySource;

use crate::optics::transfer::FastTransfer;
use crate::optics::{Display, Eye, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;

pub use crate::optics::system::EyeSample;

/// What is measured along each eye ray: the radiance of several images, image 0 being the
/// reference (the ground truth) and the others the images scored against it.
pub trait PairedSource: Sync {
    /// Number of images (at least 2: the reference and one scored image).
    fn images(&self) -> usize;

    /// The radiance of every image along every ray: `out[i * images + k]` is image `k`'s RGB
    /// for `samples[i]` (`out.len() == samples.len() * images`).
    fn eval(&self, samples: &[EyeSample], out: &mut [[f64; 3]]);

    /// True when the samples need their spectral number ([`EyeSample::spectral`]).
    fn spectral(&self) -> bool {
        false
    }

    /// True when the samples need their diffraction numbers ([`EyeSample::diffraction`]).
    fn diffraction(&self) -> bool {
        false
    }

    /// Image 0's radiance when it is one value along every eye ray of a retina pixel (tangents
    /// in the box `tangents`, pupil points within `pupil_radius` mm of the pupil centre), exactly
    /// what [`PairedSource::eval`] gives each of them; `None` when that is not known (the default).
    fn reference_over(&self, tangents: (DVec2, DVec2), pupil_radius: f64) -> Option<[f64; 3]> {
        let _ = (tangents, pupil_radius);
        None
    }

    /// [`PairedSource::eval`], told image 0 of sample `i` where `known[i]` is `Some` (what
    /// [`PairedSource::reference_over`] said of its pixel), so it need not trace it. Same values.
    fn eval_known(&self, samples: &[EyeSample], known: &[Option<[f64; 3]>], out: &mut [[f64; 3]]) {
        let _ = known;
        self.eval(samples, out);
    }

    /// A handle of the scored images' radiance (images 1..) when it is known for every eye ray
    /// of a retina pixel whose image 0 is known ([`PairedSource::reference_over`]) and whose
    /// random deviations lie within the source's own bounds; `None` when that is not known (the
    /// default). Only [`PairedSource::eval_known_images`] reads it.
    fn images_over(&self, tangents: (DVec2, DVec2), pupil_radius: f64) -> Option<u32> {
        let _ = (tangents, pupil_radius);
        None
    }

    /// [`PairedSource::eval_known`], also told sample `i`'s pixel's [`PairedSource::images_over`]
    /// handle in `images[i]` (`u32::MAX`: none; `images` may be empty). Same values.
    fn eval_known_images(
        &self,
        samples: &[EyeSample],
        known: &[Option<[f64; 3]>],
        images: &[u32],
        out: &mut [[f64; 3]],
    ) {
        let _ = images;
        self.eval_known(samples, known, out);
    }
}

/// Eq. (1) from the eye to the LCD for any retina tangent and pupil point: the grid
/// simulation's [`FastTransfer`] through pupil points instead of pupil-grid indices, so at one of
/// its pupil-grid points both give the same LCD point bit for bit (tested).
pub struct EyeToLcd<'a> {
    transfer: FastTransfer<'a>,
}

impl<'a> EyeToLcd<'a> {
    /// The eye -> LCD transfer of eq. (1) for `eye` looking at `display`.
    pub fn new(display: &'a Display, eye: &Eye) -> Self {
        Self { transfer: FastTransfer::for_eye(display, eye) }
    }

    /// Where the eye ray for retina direction `tangent` through pupil point `pupil` meets the
    /// LCD plane.
    #[inline(always)]
    pub fn lcd_point(&self, tangent: DVec2, pupil: DVec2) -> DVec2 {
        self.transfer.lcd_point_through(tangent, pupil)
    }

    /// The LCD pixel that ray meets, if any.
    #[inline(always)]
    pub fn pixel_index(&self, tangent: DVec2, pupil: DVec2) -> Option<usize> {
        self.transfer.pixel_index_through(tangent, pupil)
    }

    /// [`EyeToLcd::pixel_index`] of every sample (`u32::MAX`: the ray misses the LCD), in
    /// passes over the batch; same arithmetic as one ray at a time, so the same pixels (tested).
    pub fn pixel_indices(&self, samples: &[EyeSample], out: &mut [u32]) {
        let mut scratch = Vec::new();
        self.transfer.pixel_indices_through(|i| (samples[i].tangent, samples[i].pupil), &mut scratch, out);
    }
}

/// Per-replicate, per-pixel means of every image of a [`PairedSource`] on a square retina.
#[derive(Clone, Debug, PartialEq)]
pub struct Replicates {
    resolution: usize,
    replicates: usize,
    images: usize,
    samples: u32,
    /// Planes `[replicate][image][channel]` of `resolution^2` pixels each, row-major.
    means: Vec<f32>,
}

impl Replicates {
    /// No samples yet: every mean is 0 until [`Replicates::extend`] adds some.
    pub fn new(resolution: usize, replicates: usize, images: usize) -> Self {
        Self {
            resolution,
            replicates,
            images,
            samples: 0,
            means: vec![0.0; resolution * resolution * replicates * images * 3],
        }
    }

    /// Empty storage for a new measurement that reuses `self`'s buffer when it is large enough
    /// (no new pages to fault in for every eye case). Like [`Replicates::new`], but the means are
    /// not zeroed: they are meaningless until the first [`Replicates::extend`], which writes
    /// every one of them.
    pub fn recycle(mut self, resolution: usize, replicates: usize, images: usize) -> Self {
        let len = resolution * resolution * replicates * images * 3;
        if self.means.capacity() < len {
            return Self::new(resolution, replicates, images);
        }
        self.means.truncate(len);
        self.means.resize(len, 0.0);
        Self { resolution, replicates, images, samples: 0, means: self.means }
    }

    /// Replicates whose means are given: `f(pixel, replicate, image, channel)`, as if from
    /// `samples` samples per replicate (for tests and for replicates computed elsewhere).
    pub fn from_fn(
        resolution: usize,
        replicates: usize,
        images: usize,
        samples: u32,
        f: impl Fn(usize, usize, usize, usize) -> f32,
    ) -> Self {
        let mut reps = Self::new(resolution, replicates, images);
        reps.samples = samples;
        let pixels = resolution * resolution;
        for (i, v) in reps.means.iter_mut().enumerate() {
            let (plane, p) = (i / pixels, i % pixels);
            *v = f(p, plane / (images * 3), (plane / 3) % images, plane % 3);
        }
        reps
    }

    /// Retina pixels per side.
    pub fn resolution(&self) -> usize {
        self.resolution
    }
    /// Independent replicates R.
    pub fn replicates(&self) -> usize {
        self.replicates
    }
    /// Images per replicate (the ground truth first, then one per method).
    pub fn images(&self) -> usize {
        self.images
    }
    /// Samples per pixel in each replicate.
    pub fn samples_per_replicate(&self) -> u32 {
        self.samples
    }
    /// Samples per pixel over all replicates.
    pub fn samples_per_pixel(&self) -> u64 {
        u64::from(self.samples) * self.replicates as u64
    }

    /// Channel `c` of image `k` in replicate `r`: one mean per pixel, row-major.
    #[inline]
    pub fn plane(&self, r: usize, k: usize, c: usize) -> &[f32] {
        let pixels = self.resolution * self.resolution;
        let i = (r * self.images + k) * 3 + c;
        &self.means[i * pixels..(i + 1) * pixels]
    }

    /// Mean of image `k`, channel `c` in replicate `r` at `pixel` (row-major index).
    #[inline]
    pub fn value(&self, pixel: usize, r: usize, k: usize, c: usize) -> f32 {
        self.plane(r, k, c)[pixel]
    }

    /// Image `k` of replicate `r`.
    pub fn replicate_image(&self, k: usize, r: usize) -> RgbImage {
        let n = self.resolution;
        let mut img = RgbImage::new(n, n);
        for (p, px) in img.pixels.iter_mut().enumerate() {
            *px = std::array::from_fn(|c| self.value(p, r, k, c));
        }
        img
    }

    /// Image `k` averaged over the replicates: each pixel's sum in replicate order, in `f64`,
    /// times `1 / R`. Row by row, a whole row of one replicate plane at a time (contiguous reads
    /// the compiler vectorises; the same additions as [`Replicates::mean_image_by_pixel`]).
    pub fn mean_image(&self, k: usize) -> RgbImage {
        let n = self.resolution;
        let mut img = RgbImage::new(n, n);
        let inv = 1.0 / self.replicates as f64;
        img.pixels.par_chunks_mut(n).enumerate().for_each_init(
            || vec![0.0f64; n],
            |sum, (row, px)| {
                for c in 0..3 {
                    let row_of = |r: usize| &self.plane(r, k, c)[row * n..(row + 1) * n];
                    // The first term as is: `-0.0 + x == x`, as in an iterator's `sum`.
                    for (s, v) in sum.iter_mut().zip(row_of(0)) {
                        *s = f64::from(*v);
                    }
                    for r in 1..self.replicates {
                        for (s, v) in sum.iter_mut().zip(row_of(r)) {
                            *s += f64::from(*v);
                        }
                    }
                    for (p, s) in px.iter_mut().zip(sum.iter()) {
                        p[c] = (s * inv) as f32;
                    }
                }
            },
        );
        img
    }

    /// Slow, obviously correct twin of [`Replicates::mean_image`]: pixel by pixel, the sum of
    /// its replicates' means.
    pub fn mean_image_by_pixel(&self, k: usize) -> RgbImage {
        let n = self.resolution;
        let mut img = RgbImage::new(n, n);
        let inv = 1.0 / self.replicates as f64;
        for (p, px) in img.pixels.iter_mut().enumerate() {
            *px = std::array::from_fn(|c| {
                let s: f64 = (0..self.replicates).map(|r| f64::from(self.value(p, r, k, c))).sum();
                (s * inv) as f32
            });
        }
        img
    }

    /// Adds samples `N..total` of every replicate's sequences to every pixel (N: the samples
    /// taken so far), through `source`. Bands of rows run in parallel; each pixel sums its
    /// samples in index order, so the result does not depend on the thread count or the tiling.
    pub fn extend<S: PairedSource + ?Sized>(
        &mut self,
        source: &S,
        sampler: &Sampler,
        retina: &Retina,
        total: u32,
        progress: &Progress,
    ) {
        assert_eq!(retina.resolution, self.resolution, "retina and replicate storage differ in size");
        assert_eq!(source.images(), self.images, "source and replicate storage differ in images");
        let old = self.samples;
        if total <= old {
            return;
        }
        let n = self.resolution;
        let pass = pass::Pass::new(source, sampler, retina, (self.replicates, self.images), (old, total));
        // Every plane cut into bands of TILE rows; band b of every plane goes to one task.
        let band_len = pass::TILE * n;
        let bands = n.div_ceil(pass::TILE);
        let mut per_band: Vec<Vec<&mut [f32]>> =
            (0..bands).map(|_| Vec::with_capacity(self.replicates * self.images * 3)).collect();
        for plane in self.means.chunks_mut(n * n) {
            for (b, chunk) in plane.chunks_mut(band_len).enumerate() {
                per_band[b].push(chunk);
            }
        }
        per_band.into_par_iter().enumerate().for_each(|(band, mut planes)| pass.band(band, &mut planes, progress));
        self.samples = total;
    }
}

#[cfg(test)]
mod tests;
