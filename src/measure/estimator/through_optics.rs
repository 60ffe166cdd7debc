//! The paired samples through an eye beyond the thin lens's fast paths (a schematic eye, the
//! display primaries' wavelengths, the Stiles-Crawford weight; `optics::eye::rays`): the same
//! measurement, each sample's object-space rays from [`EyeOptics::rays`] instead of eq. (1b)'s
//! thin lens. Channel c of the ground truth is the scene's channel c along channel c's ray, and
//! channel c of every perceived image the display image's channel c at the LCD pixel that ray
//! meets (eq. (1) from the lenslet plane on, [`FastTransfer::pixel_index_of`], or through real
//! lenslets each channel's own pixel, [`FastTransfer::pixel_index_in`]); a ray blocked
//! inside the eye carries black for every image, as a ray that misses the LCD does.
//!
//!
//! With diffraction (`optics::diffraction`), each channel's ray leaves its retina point bent by
//! the pupil's Airy deviation ([`EyeOptics::rays_diffracted`]) for the ground truth and the
//! perceived images alike, and a perceived ray is bent again after the lenslet it crosses by
//! that lenslet aperture's deviation (`[optics] diffraction = "apertures"`; through a real
//! lenslet where it leaves the back surface), both at the channel's wavelength. One draw per
//! sample and aperture serves the three channels, scaled by each one's wavelength.
//!
//! [`FastTransfer::pixel_index_of`]: crate::optics::transfer::FastTransfer::pixel_index_of
//! [`FastTransfer::pixel_index_in`]: crate::optics::transfer::FastTransfer::pixel_index_in

use std::cell::RefCell;

use glam::DVec2;

use super::{DisplaySource, EyeSample};
use crate::optics::eye::rays::SampleRays;
use crate::optics::eye::EyeOptics;
use crate::optics::PlaneRay;
use crate::ray::Ray;
use crate::render::{RadianceField, Sample};

/// A worker's buffers for [`DisplaySource::eval_through_batched`], kept between batches (no
/// allocation per batch once they have grown).
#[derive(Default)]
struct Buffers {
    /// Every sample's rays.
    rays: Vec<SampleRays>,
    /// Every carried ray (in sample, then channel order), world x, y at the eye's plane.
    lines: Vec<PlaneRay>,
    /// Their scene rays and hits, for fields that take batches.
    scene: Vec<Ray>,
    hits: Vec<Sample>,
    /// The ground truth's radiance along each line.
    radiance: Vec<[f64; 3]>,
    /// The LCD pixel each line meets (`u32::MAX`: none).
    pixels: Vec<u32>,
    scratch: Vec<DVec2>,
}

thread_local! {
    static BUFFERS: RefCell<Buffers> = RefCell::new(Buffers::default());
}

impl<F: RadianceField + ?Sized> DisplaySource<'_, F> {
    /// Whether [`DisplaySource::eval_through_batched`] serves `optics`: no diffraction and thin
    /// lenslets (one LCD pixel per ray, [`FastTransfer::pixel_index_of`]).
    ///
    /// [`FastTransfer::pixel_index_of`]: crate::optics::transfer::FastTransfer::pixel_index_of
    pub(super) fn is_batched_through(&self, optics: &EyeOptics) -> bool {
        !optics.diffraction.is_on() && self.lenslet.is_none() && !self.transfer.transfer.is_thick()
    }

    /// [`DisplaySource::eval_through`] in passes over the batch (every sample's rays, the
    /// scene along every ray, every ray's LCD pixel, the reads), in a worker's reused buffers,
    /// for the eyes of [`DisplaySource::is_batched_through`]: the same arithmetic, so the same
    /// values bit for bit (tested against `eval_through`, its slow twin).
    pub(super) fn eval_through_batched(&self, optics: &EyeOptics, samples: &[EyeSample], out: &mut [[f64; 3]]) {
        debug_assert!(self.is_batched_through(optics));
        BUFFERS.with(|b| match b.try_borrow_mut() {
            Ok(mut b) => self.eval_batched_in(optics, samples, out, &mut b),
            // Re-entered on this thread (a field that runs parallel work): fresh buffers.
            Err(_) => self.eval_batched_in(optics, samples, out, &mut Buffers::default()),
        });
    }

    fn eval_batched_in(&self, optics: &EyeOptics, samples: &[EyeSample], out: &mut [[f64; 3]], b: &mut Buffers) {
        let k = 1 + self.stack.len();
        let eye_xy = self.eye.position.truncate();
        let z = self.eye.position.z;
        b.rays.clear();
        let mut pairs = samples.chunks_exact(2);
        for pair in &mut pairs {
            let (x, y) = (&pair[0], &pair[1]);
            b.rays.extend(optics.rays2((x.tangent, x.pupil, x.spectral), (y.tangent, y.pupil, y.spectral)));
        }
        b.rays.extend(pairs.remainder().iter().map(|s| optics.rays(s.tangent, s.pupil, s.spectral)));
        b.lines.clear();
        for sr in &b.rays {
            let n = if sr.single { 1 } else { 3 };
            let world = |r: &PlaneRay| PlaneRay { position: r.position + eye_xy, slope: r.slope };
            b.lines.extend(sr.rays[..n].iter().flatten().map(world));
        }
        let n = b.lines.len();
        let scene_ray = |w: &PlaneRay| Ray { origin: w.position.extend(z), dir: w.slope.extend(1.0) };
        b.radiance.clear();
        if self.field.prefers_batches() {
            b.scene.clear();
            b.scene.extend(b.lines.iter().map(scene_ray));
            b.hits.clear();
            b.hits.resize(n, Sample::default());
            self.field.sample_many(&b.scene, &mut b.hits);
            b.radiance.extend(b.hits.iter().map(|h| h.radiance.to_array()));
        } else {
            b.radiance.extend(b.lines.iter().map(|w| self.field.radiance(&scene_ray(w)).to_array()));
        }
        b.pixels.clear();
        b.pixels.resize(n, 0);
        let lines = &b.lines;
        self.transfer.transfer.pixel_indices_of(|i| lines[i], &mut b.scratch, &mut b.pixels);
        let mut next = 0;
        for (o, sr) in out.chunks_exact_mut(k).zip(&b.rays) {
            o.fill([0.0; 3]);
            let channels = if sr.single { 0..1 } else { 0..3 };
            for c in channels {
                if sr.rays[c].is_none() {
                    continue;
                }
                let (gt, idx) = (b.radiance[next], b.pixels[next]);
                next += 1;
                let px = (idx != u32::MAX).then(|| self.stack.pixel(idx as usize));
                // The channels this ray carries: all three for one ray, else its own.
                let carried = if sr.single { 0..3 } else { c..c + 1 };
                for ch in carried {
                    o[0][ch] = gt[ch] * sr.weight;
                    if let Some(px) = px {
                        for (j, v) in o[1..].iter_mut().enumerate() {
                            v[ch] = f64::from(px[3 * j + ch]) * sr.weight;
                        }
                    }
                }
            }
        }
        debug_assert_eq!(next, n);
    }

    /// [`super::PairedSource::eval`] through `optics`, sample by sample: `out[i * images + k]`
    /// is image `k` of sample `i`.
    pub(super) fn eval_through(&self, optics: &EyeOptics, samples: &[EyeSample], out: &mut [[f64; 3]]) {
        let k = 1 + self.stack.len();
        let eye_xy = self.eye.position.truncate();
        let z = self.eye.position.z;
        let world = |r: PlaneRay| PlaneRay { position: r.position + eye_xy, slope: r.slope };
        // Every sample's rays (1 or 3), the scene traced in one batch when the field wants it.
        // Two at a time: a schematic eye's ray map shares its coefficients between them (bit for
        // bit `rays` one by one).
        let mut all = Vec::with_capacity(samples.len());
        if optics.diffraction.is_on() {
            all.extend(samples.iter().map(|s| {
                let xi = [s.diffraction[0], s.diffraction[1]];
                optics.rays_diffracted(s.tangent, s.pupil, s.spectral, xi)
            }));
        } else {
            let mut pairs = samples.chunks_exact(2);
            for pair in &mut pairs {
                let (a, b) = (&pair[0], &pair[1]);
                all.extend(optics.rays2((a.tangent, a.pupil, a.spectral), (b.tangent, b.pupil, b.spectral)));
            }
            all.extend(pairs.remainder().iter().map(|s| optics.rays(s.tangent, s.pupil, s.spectral)));
        }
        let mut rays = Vec::with_capacity(samples.len() * 3);
        for sr in &all {
            let n = if sr.single { 1 } else { 3 };
            for r in sr.rays[..n].iter().flatten() {
                let w = world(*r);
                rays.push(Ray { origin: w.position.extend(z), dir: w.slope.extend(1.0) });
            }
        }
        let mut hits = vec![Sample::default(); rays.len()];
        if self.field.prefers_batches() {
            self.field.sample_many(&rays, &mut hits);
        } else {
            for (h, r) in hits.iter_mut().zip(&rays) {
                h.radiance = self.field.radiance(r);
            }
        }
        let mut next = 0;
        let thick = self.transfer.transfer.is_thick();
        // Each carried channel finds its own LCD pixel through a real lenslet (refracted at its
        // own wavelength), and through a diffracting lenslet when the channels' wavelengths differ
        // (the deviation scales with the wavelength); else one pixel serves them all.
        let per_channel = thick || (self.lenslet.is_some() && !optics.is_single_wavelength());
        // Each channel at the sampled wavelength, else its primary's median (real lenslets).
        let u_lens = |s: &EyeSample| if optics.is_single_wavelength() { 0.5 } else { s.spectral };
        for ((o, sr), s) in out.chunks_exact_mut(k).zip(&all).zip(samples) {
            o.fill([0.0; 3]);
            // The lenslet's draw once for the three channels, scaled by each one's wavelength.
            let draw = self.lenslet.as_ref().map(|shape| (shape, shape.draw([s.diffraction[2], s.diffraction[3]])));
            let channels: &[usize] = if sr.single { &[0] } else { &[0, 1, 2] };
            for &c in channels {
                let Some(r) = sr.rays[c] else { continue };
                let gt = hits[next].radiance.to_array();
                next += 1;
                // The LCD pixel of this ray in channel `ch`.
                let index = |ch: usize| match (thick, draw) {
                    (false, None) => self.transfer.transfer.pixel_index_of(world(r)),
                    (false, Some((shape, draw))) => {
                        let deviation = shape.scaled(draw, optics.wavelength(ch, s.spectral));
                        self.transfer.transfer.pixel_index_deviated(world(r), deviation)
                    }
                    (true, None) => self.transfer.transfer.pixel_index_in(world(r), ch, u_lens(s)),
                    // Bent where it leaves the lenslet by the cell's deviation.
                    (true, Some((shape, draw))) => {
                        let deviation = shape.scaled(draw, optics.wavelength(ch, s.spectral));
                        self.transfer.transfer.pixel_index_in_deviated(world(r), ch, u_lens(s), deviation)
                    }
                };
                let mut px = if per_channel { None } else { index(c).map(|i| self.stack.pixel(i)) };
                // The channels this ray carries: all three for one ray, else its own.
                let carried = if sr.single { 0..3 } else { c..c + 1 };
                for ch in carried {
                    o[0][ch] = gt[ch] * sr.weight;
                    if per_channel {
                        px = index(ch).map(|i| self.stack.pixel(i));
                    }
                    if let Some(px) = px {
                        for (j, v) in o[1..].iter_mut().enumerate() {
                            v[ch] = f64::from(px[3 * j + ch]) * sr.weight;
                        }
                    }
                }
            }
        }
        debug_assert_eq!(next, rays.len());
    }
}
