//! The kernel of the paper's thin-lens eye with diffraction (`optics::diffraction`: the pupil's
//! Airy pattern and the lenslet aperture's pattern, each channel at its wavelength) through
//! paraxial lenslets, in passes over the batch: the fast twin of the general per-sample path
//! ([`OpticalSystem::trace_each`]), with the same arithmetic in the same order, so the same bits
//! (tested in `tests/diffraction.rs` and `system/tests.rs`).
//!
//! Per sample: the channels' wavelengths once, the pupil's and the lenslet's draws once, then
//! each channel's ray (the thin lens's eq. (1a), (1b) from the retina tangent moved by the
//! channel's pupil deviation; one ray for all three when the wavelengths are one or the eye is a
//! pinhole); then all the batch's LCD pixels (eq. (1) with the lenslet's deviation after the
//! lenslet).
//!
//! The shortcuts (exact): a sample's pupil deviation is known from its draw before any ray is
//! traced. When the consumer knows the field one colour over the pixel's ray family widened by
//! the pupil's core ([`OpticalSystem::ray_family`], about 95% of the Airy pattern's mass;
//! [`Hint::reference`]), every sample whose deviations (every channel's) lie in that core has
//! that colour as its ground truth and its scene rays are not traced. When it also knows every
//! display image one value over the LCD pixels the family reaches with the lenslets' deviations
//! within their core ([`OpticalSystem::family_lcd_pixels`], [`Hint::images`]), a sample
//! deviated within both cores traces nothing.

use std::f64::consts::PI;

use super::trace::{Hint, Traced, Traces, KNOWN, MISS};
use super::{EyeSample, OpticalSystem};
use crate::optics::diffraction::{disk_draw, ApertureDraw};
use crate::optics::PlaneRay;
use crate::ray::Ray;

/// The core of the pupil's Airy pattern whose samples may skip their scene rays: the Airy radius
/// `x = pi D theta / lambda` of the fourth dark ring (95.2% of the mass inside) ...
const CORE_X: f64 = 13.3237;
/// ... at this wavelength, nm (the deviations of longer wavelengths beyond the core are traced).
const CORE_NM: f64 = 700.0;
/// The lenslet aperture's core for the perceived images' shortcut, in units of its angle at
/// `CORE_NM` (`ApertureShape::angle`).
const LENS_CORE: f64 = 1.0;
/// The most lenslets a pixel's ray family may reach for the perceived images' shortcut.
pub(super) const MAX_LENSLETS: usize = 64;

impl OpticalSystem<'_> {
    /// The half-width (a tangent) by which a pixel's square is widened for the ground truth's
    /// shortcut: the pupil's Airy core (`CORE_X` at `CORE_NM`); 0 without pupil diffraction
    /// (a pinhole's rays do not deviate).
    pub(super) fn pupil_core(&self) -> f64 {
        if self.optics.pupil_diameter > 0.0 {
            CORE_X * CORE_NM * 1e-6 / (PI * self.optics.pupil_diameter)
        } else {
            0.0
        }
    }

    /// The half-width (a slope change, in x and y) of the lenslet deviations the perceived
    /// images' shortcut covers: the aperture's pattern out to `LENS_CORE` times its angle at
    /// `CORE_NM` (for the square lenslet, the sinc^2 draws within +-1: its central lobe, about
    /// 90% of each axis's mass); 0 without lenslet diffraction.
    pub(super) fn lenslet_core(&self) -> f64 {
        self.lenslet.as_ref().map_or(0.0, |shape| LENS_CORE * shape.angle(CORE_NM))
    }

    /// The thin lens with diffraction, batched (see the module comment).
    pub(super) fn trace_diffracted(&self, samples: &[EyeSample], hints: &[Hint], out: &mut Traces) {
        let optics = &*self.optics;
        let eye = self.eye.position;
        let single = optics.is_single_wavelength();
        let pupil_on = optics.pupil_diameter > 0.0;
        // `EyeOptics::rays` of the thin lens (no Stiles-Crawford weight), inlined: the same
        // arithmetic.
        let lens = optics.thin_lens_ray().expect("the thin lens (Kernel::ThinDiffracted)");
        // Three rays per sample when the channels' pupil deviations differ.
        let per_ray = if pupil_on && !single { 3 } else { 1 };
        // Each channel's own LCD pixel when its lenslet deviation (or its ray) is its own.
        let per_pixel = per_ray == 3 || (self.lenslet.is_some() && !single);
        let b = &mut out.bufs;
        b.nm.clear();
        b.lens_draw.clear();
        b.lines.clear();
        b.slot.clear();
        b.active.clear();
        b.pos.clear();
        let core = self.pupil_core();
        let lens_core = self.lenslet_core();
        for (i, s) in samples.iter().enumerate() {
            let hint = hints.get(i).copied().unwrap_or_default();
            let u = s.spectral;
            let l: [f64; 3] =
                if single { [optics.wavelength(0, u); 3] } else { std::array::from_fn(|c| optics.wavelength(c, u)) };
            b.nm.push(l);
            let lens_draw = self.lenslet.as_ref().map(|shape| shape.draw([s.diffraction[2], s.diffraction[3]]));
            if let Some(d) = lens_draw {
                b.lens_draw.push(d);
            }
            // `EyeOptics::rays_diffracted`'s tangents: moved by the channel's Airy deviation.
            let draw = if pupil_on { disk_draw([s.diffraction[0], s.diffraction[1]]) } else { ApertureDraw::default() };
            let mut in_core = hint.reference;
            let mut tangents = [s.tangent; 3];
            for (t, &lc) in tangents.iter_mut().zip(&l[..per_ray]) {
                if pupil_on {
                    let d = draw.disk(optics.pupil_diameter, lc);
                    in_core &= d.x.abs() <= core && d.y.abs() <= core;
                    *t = s.tangent + d;
                }
            }
            // The perceived images known too: every channel's lenslet deviation in its core.
            let seen = in_core
                && hint.images
                && match (&self.lenslet, lens_draw) {
                    (Some(shape), Some(d)) => l.iter().all(|&lc| {
                        let v = shape.scaled(d, lc);
                        v.x.abs() <= lens_core && v.y.abs() <= lens_core
                    }),
                    _ => true,
                };
            if seen {
                b.pos.push(MISS);
                continue;
            }
            b.pos.push(b.active.len() as u32);
            b.active.push(i as u32);
            for &tangent in &tangents[..per_ray] {
                let r = lens.ray(tangent, s.pupil);
                b.lines.push(PlaneRay { position: r.position + eye.truncate(), slope: r.slope });
            }
            b.slot.push(if in_core { MISS } else { 0 });
        }
        let na = b.active.len();

        // The ground truth: the rays of the samples not known, into the scene.
        for (w, slot) in b.lines.chunks_exact(per_ray).zip(b.slot.iter_mut()) {
            if *slot != MISS {
                *slot = out.scene.len() as u32;
                out.scene.extend(w.iter().map(|w| Ray { origin: w.position.extend(eye.z), dir: w.slope.extend(1.0) }));
            }
        }

        // The LCD pixel of each sample's channels (one for all when `!per_pixel`), each ray's
        // lenslet found once.
        let pixels = if per_pixel { 3 } else { 1 };
        b.pixels.clear();
        b.pixels.resize(na * pixels, MISS);
        let Some(t) = &self.transfer else {
            self.push_diffracted(per_ray, pixels, out);
            return;
        };
        let ray_of = |j: usize| (j / pixels) * per_ray + (j % pixels).min(per_ray - 1);
        let (nm, lens_draw, active) = (&b.nm, &b.lens_draw, &b.active);
        match &self.lenslet {
            None => t.pixel_indices_deviated(&b.lines, |j| (ray_of(j), None), &mut b.scratch, &mut b.pixels),
            Some(shape) => t.pixel_indices_deviated(
                &b.lines,
                |j| {
                    let (i, c) = (active[j / pixels] as usize, j % pixels);
                    (ray_of(j), Some(shape.scaled(lens_draw[i], nm[i][c])))
                },
                &mut b.scratch,
                &mut b.pixels,
            ),
        }

        self.push_diffracted(per_ray, pixels, out);
    }

    /// The traces of [`OpticalSystem::trace_diffracted`] from its buffers.
    fn push_diffracted(&self, per_ray: usize, pixels: usize, out: &mut Traces) {
        let b = &out.bufs;
        let base =
            Traced { weight: 1.0, first: KNOWN, rays: 0b111, single: per_ray == 1, lcd: [KNOWN; 3], shared: true };
        for &a in &b.pos {
            if a == MISS {
                // Both known: the pixel's ground truth and its LCD pixel's values.
                out.samples.push(base);
                continue;
            }
            let a = a as usize;
            let first = match b.slot[a] {
                MISS => KNOWN,
                j => j,
            };
            let lcd = std::array::from_fn(|c| b.pixels[a * pixels + c.min(pixels - 1)]);
            out.samples.push(Traced { first, lcd, shared: pixels == 1, ..base });
        }
    }
}
