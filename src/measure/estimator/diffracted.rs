//! The paired samples of the paper's thin-lens eye with diffraction (`optics::diffraction`:
//! the pupil's Airy pattern and the lenslet aperture's pattern, each channel at its wavelength)
//! in passes over the batch: the fast twin of the generic per-sample path
//! (`through_optics.rs`, [`super::DisplaySource::eval_each_ray`]), with the same arithmetic in
//! the same order, so the same values bit for bit (tested in `tests/diffraction.rs`).
//!
//! Per sample: the channels' wavelengths once (the generic path asks for each twice), the
//! pupil's and the lenslet's draws once, then each channel's ray (the thin lens's eq. (1a),
//! (1b) from the retina tangent moved by the channel's pupil deviation; one ray for all three
//! when the wavelengths are one or the eye is a pinhole); then all the batch's scene rays at
//! once, all its LCD pixels (eq. (1) with the lenslet's deviation after the lenslet), and last
//! the reads of the display images (independent loads the CPU overlaps).
//!
//! The ground truth's shortcut (exact, as `PairedSource::reference_over` without diffraction):
//! a sample's pupil deviation is known from its draw before any ray is traced. When the field
//! proves the pixel's ray family uniform with the tangents widened by a core radius
//! ([`DisplaySource::pupil_core`], about 95% of the Airy pattern's mass), every sample whose
//! deviations (every channel's) lie within that core has exactly that colour as its ground truth,
//! and its scene rays are not traced; the samples in the Airy tail are traced as before.

use std::cell::RefCell;
use std::f64::consts::PI;

use glam::DVec2;

use super::{DisplaySource, EyeSample};
use crate::optics::diffraction::{disk_draw, ApertureDraw};
use crate::optics::eye::EyeOptics;
use crate::optics::PlaneRay;
use crate::ray::Ray;
use crate::render::retina::eye_rays;
use crate::render::{RadianceField, Sample};

/// Off the LCD (no pixel); also: no scene ray traced (the ground truth known).
const MISS: u32 = u32::MAX;

/// The core of the pupil's Airy pattern whose samples may skip their scene rays: the Airy radius
/// `x = pi D theta / lambda` of the fourth dark ring (95.2% of the mass inside) ...
const CORE_X: f64 = 13.3237;
/// ... at this wavelength, nm (the deviations of longer wavelengths beyond the core are traced).
const CORE_NM: f64 = 700.0;
/// The lenslet aperture's core for the perceived images' shortcut, in units of its angle at
/// `CORE_NM` (`ApertureShape::angle`).
const LENS_CORE: f64 = 1.0;
/// The most lenslets a pixel's ray family may reach for the perceived images' shortcut.
const MAX_LENSLETS: usize = 64;

impl<F: RadianceField + ?Sized> DisplaySource<'_, F> {
    /// Whether [`DisplaySource::eval_diffracted`] serves `optics`: the thin lens without the
    /// Stiles-Crawford weight, thin lenslets, diffraction on.
    pub(super) fn is_thin_diffracted(&self, optics: &EyeOptics) -> bool {
        optics.diffraction.is_on()
            && optics.schematic().is_none()
            && optics.stiles_crawford.is_none()
            && !self.transfer.transfer.is_thick()
    }

    /// The half-width (a tangent) by which a pixel's square is widened for the ground truth's
    /// shortcut: the pupil's Airy core (`CORE_X` at `CORE_NM`); 0 without pupil diffraction
    /// (a pinhole's rays do not deviate).
    fn pupil_core(&self, optics: &EyeOptics) -> f64 {
        if optics.pupil_diameter > 0.0 {
            CORE_X * CORE_NM * 1e-6 / (PI * optics.pupil_diameter)
        } else {
            0.0
        }
    }

    /// [`super::PairedSource::reference_over`] with `optics`: for the thin lens with diffraction
    /// ([`DisplaySource::is_thin_diffracted`]), the field's uniform colour over the pixel's ray
    /// family with its tangents widened by [`DisplaySource::pupil_core`], which is the ground
    /// truth of every sample whose pupil deviations lie in the core; `None` otherwise.
    pub(super) fn reference_over_diffracted(
        &self,
        optics: &EyeOptics,
        tangents: (DVec2, DVec2),
        pupil_radius: f64,
    ) -> Option<[f64; 3]> {
        if !self.is_thin_diffracted(optics) {
            return None;
        }
        let core = DVec2::splat(self.pupil_core(optics));
        let widened = (tangents.0.min(tangents.1) - core, tangents.0.max(tangents.1) + core);
        let pupil = (DVec2::splat(-pupil_radius), DVec2::splat(pupil_radius));
        self.field.uniform(&eye_rays(self.eye, widened, pupil)).map(|(c, _)| c.to_array())
    }

    /// The half-width (a slope change, in x and y) of the lenslet deviations the perceived
    /// images' shortcut covers: the aperture's pattern out to `LENS_CORE` times its angle at
    /// `CORE_NM` (for the square lenslet, the sinc^2 draws within +-1: its central lobe, about
    /// 90% of each axis's mass); 0 without lenslet diffraction.
    fn lenslet_core(&self) -> f64 {
        self.lenslet.as_ref().map_or(0.0, |shape| LENS_CORE * shape.angle(CORE_NM))
    }

    /// [`super::PairedSource::images_over`] with `optics`: for the thin lens with diffraction,
    /// an LCD pixel whose values every display image holds on every LCD pixel that the pixel's
    /// ray family can meet with its tangents widened by [`DisplaySource::pupil_core`] and the
    /// lenslets' deviations within [`DisplaySource::lenslet_core`]
    /// (`FastTransfer::deviated_family_pixels`); so every sample of the pixel whose deviations
    /// (each channel's) lie in those cores perceives exactly that pixel's values. `None`
    /// otherwise.
    pub(super) fn images_over_diffracted(
        &self,
        optics: &EyeOptics,
        tangents: (DVec2, DVec2),
        pupil_radius: f64,
    ) -> Option<u32> {
        if !self.is_thin_diffracted(optics) {
            return None;
        }
        let lens = optics.thin_lens_ray()?;
        let core = DVec2::splat(self.pupil_core(optics));
        let widened = (tangents.0.min(tangents.1) - core, tangents.0.max(tangents.1) + core);
        let t = &self.transfer.transfer;
        let nx = t.lcd_columns();
        let mut first: Option<usize> = None;
        let same = t.deviated_family_pixels(
            (lens.v0, lens.d1),
            widened,
            pupil_radius,
            self.lenslet_core(),
            MAX_LENSLETS,
            |cols, rows| {
                for row in rows[0]..=rows[1] {
                    for col in cols[0]..=cols[1] {
                        let idx = row * nx + col;
                        match first {
                            None => first = Some(idx),
                            Some(f) if self.stack.same_values(f, idx) => {}
                            Some(_) => return false,
                        }
                    }
                }
                true
            },
        );
        first.filter(|_| same).and_then(|f| u32::try_from(f).ok()).filter(|&f| f != MISS)
    }

    /// [`super::PairedSource::eval_known`] of the thin-lens eye with diffraction, batched
    /// ([`DisplaySource::is_thin_diffracted`]): `out[i * images + k]` is image `k` of sample `i`;
    /// `known` (empty, or one entry per sample) holds [`DisplaySource::reference_over_diffracted`]'s
    /// colour of the sample's pixel, the ground truth of the samples deviated within the core;
    /// `images` (empty, or one entry per sample) [`DisplaySource::images_over_diffracted`]'s
    /// LCD pixel (`u32::MAX`: none), whose values the samples deviated within both cores
    /// perceive: those samples trace nothing and read that pixel.
    pub(super) fn eval_diffracted(
        &self,
        optics: &EyeOptics,
        samples: &[EyeSample],
        known: &[Option<[f64; 3]>],
        images: &[u32],
        out: &mut [[f64; 3]],
    ) {
        BUFFERS.with(|b| match b.try_borrow_mut() {
            Ok(mut b) => self.eval_diffracted_in(optics, samples, known, images, out, &mut b),
            // Re-entered on this thread (a field that runs parallel work): fresh buffers.
            Err(_) => self.eval_diffracted_in(optics, samples, known, images, out, &mut Buffers::default()),
        });
    }

    fn eval_diffracted_in(
        &self,
        optics: &EyeOptics,
        samples: &[EyeSample],
        known: &[Option<[f64; 3]>],
        images: &[u32],
        out: &mut [[f64; 3]],
        b: &mut Buffers,
    ) {
        let k = 1 + self.stack.len();
        let eye_xy = self.eye.position.truncate();
        let z = self.eye.position.z;
        let single = optics.is_single_wavelength();
        let pupil_on = optics.pupil_diameter > 0.0;
        // `EyeOptics::rays` of the thin lens (no Stiles-Crawford weight: `is_thin_diffracted`),
        // inlined: the same arithmetic.
        let lens = optics.thin_lens_ray().expect("the thin lens (is_thin_diffracted)");
        // Three rays per sample when the channels' pupil deviations differ.
        let per_ray = if pupil_on && !single { 3 } else { 1 };
        // Each channel's own LCD pixel when its lenslet deviation (or its ray) is its own.
        let per_pixel = per_ray == 3 || (self.lenslet.is_some() && !single);

        // Wavelengths, draws and rays (world coordinates at the pupil plane).
        b.nm.clear();
        b.lens_draw.clear();
        b.rays.clear();
        b.slot.clear();
        b.active.clear();
        b.pos.clear();
        let core = self.pupil_core(optics);
        let lens_core = self.lenslet_core();
        // Each sample's first ray among the scene rays, or MISS when its ground truth is known.
        let mut traced = 0u32;
        for (i, s) in samples.iter().enumerate() {
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
            let mut in_core = matches!(known.get(i), Some(Some(_)));
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
                && images.get(i).is_some_and(|&p| p != MISS)
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
                b.rays.push(PlaneRay { position: r.position + eye_xy, slope: r.slope });
            }
            if in_core {
                b.slot.push(MISS);
            } else {
                b.slot.push(traced);
                traced += per_ray as u32;
            }
        }
        let na = b.active.len();

        // The ground truth: the rays of the samples not known into the scene.
        b.scene.clear();
        b.scene.extend(
            b.rays
                .chunks_exact(per_ray)
                .zip(&b.slot)
                .filter(|(_, &j)| j != MISS)
                .flat_map(|(w, _)| w.iter().map(|w| Ray { origin: w.position.extend(z), dir: w.slope.extend(1.0) })),
        );
        b.hits.clear();
        b.hits.resize(b.scene.len(), Sample::default());
        if self.field.prefers_batches() {
            self.field.sample_many(&b.scene, &mut b.hits);
        } else {
            for (h, r) in b.hits.iter_mut().zip(&b.scene) {
                h.radiance = self.field.radiance(r);
            }
        }

        // The LCD pixel of each sample's channels (one for all when `!per_pixel`), each ray's
        // lenslet found once.
        let pixels = if per_pixel { 3 } else { 1 };
        let t = &self.transfer.transfer;
        b.lcd.clear();
        b.lcd.resize(na * pixels, MISS);
        let ray_of = |j: usize| (j / pixels) * per_ray + (j % pixels).min(per_ray - 1);
        let (nm, lens_draw, active) = (&b.nm, &b.lens_draw, &b.active);
        match &self.lenslet {
            None => t.pixel_indices_deviated(&b.rays, |j| (ray_of(j), None), &mut b.scratch, &mut b.lcd),
            Some(shape) => t.pixel_indices_deviated(
                &b.rays,
                |j| {
                    let (i, c) = (active[j / pixels] as usize, j % pixels);
                    (ray_of(j), Some(shape.scaled(lens_draw[i], nm[i][c])))
                },
                &mut b.scratch,
                &mut b.lcd,
            ),
        }

        // The reads: the ground truth's channel c from channel c's ray, every image's channel
        // c at channel c's pixel.
        for (i, o) in out.chunks_exact_mut(k).enumerate() {
            let a = b.pos[i];
            if a == MISS {
                // Both known: the pixel's ground truth and its LCD pixel's values.
                o[0] = known[i].expect("a known ground truth");
                let px = self.stack.pixel(images[i] as usize);
                for (j, v) in o[1..].iter_mut().enumerate() {
                    *v = std::array::from_fn(|c| f64::from(px[3 * j + c]));
                }
                continue;
            }
            let a = a as usize;
            for c in 0..3 {
                o[0][c] = match b.slot[a] {
                    MISS => known[i].expect("a known ground truth")[c],
                    j => b.hits[j as usize + c.min(per_ray - 1)].radiance.to_array()[c],
                };
                let idx = b.lcd[a * pixels + c.min(pixels - 1)];
                if idx == MISS {
                    for v in o[1..].iter_mut() {
                        v[c] = 0.0;
                    }
                } else {
                    let px = self.stack.pixel(idx as usize);
                    for (j, v) in o[1..].iter_mut().enumerate() {
                        v[c] = f64::from(px[3 * j + c]);
                    }
                }
            }
        }
    }
}

/// A worker's buffers for [`DisplaySource::eval_diffracted`], kept between batches.
#[derive(Default)]
struct Buffers {
    /// Each sample's three wavelengths, nm.
    nm: Vec<[f64; 3]>,
    /// Each sample's lenslet draw (with lenslet diffraction).
    lens_draw: Vec<ApertureDraw>,
    /// Each sample's rays (1 or 3), world x, y at the eye's plane.
    rays: Vec<PlaneRay>,
    /// Each traced sample's first scene ray, or MISS.
    slot: Vec<u32>,
    /// The samples traced (not known in both cores), in order.
    active: Vec<u32>,
    /// Each sample's place in `active`, or MISS when known in both cores.
    pos: Vec<u32>,
    scene: Vec<Ray>,
    hits: Vec<Sample>,
    /// The LCD pixel of each sample's channels (MISS: none).
    lcd: Vec<u32>,
    scratch: Vec<DVec2>,
}

thread_local! {
    static BUFFERS: RefCell<Buffers> = RefCell::new(Buffers::default());
}
