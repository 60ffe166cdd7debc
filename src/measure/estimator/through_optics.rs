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

use super::{DisplaySource, EyeSample};
use crate::optics::eye::EyeOptics;
use crate::optics::PlaneRay;
use crate::ray::Ray;
use crate::render::{RadianceField, Sample};

impl<F: RadianceField + ?Sized> DisplaySource<'_, F> {
    /// [`super::PairedSource::eval`] through `optics`: `out[i * images + k]` is image `k` of
    /// sample `i`.
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
