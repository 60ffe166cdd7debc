//! The per-sample trace of an [`OpticalSystem`] (paper Sec. 2.3, eq. (1); the eye's rays of
//! `optics::eye::rays`, the real lenslets of `optics::lenslet`, diffraction of
//! `optics::diffraction`): each sample's scene rays (the ground truth's) and each channel's LCD
//! pixel (where every method's display image is read), for a batch of samples at once
//! ([`OpticalSystem::trace`]: the kernel the system chose) or one sample at a time
//! ([`OpticalSystem::trace_each`]: the slow twin, the same arithmetic, the same bits).
//!
//! Channel `c` of the ground truth is the scene's channel `c` along channel `c`'s ray, and
//! channel `c` of every perceived image the display image's channel `c` at channel `c`'s LCD
//! pixel, both times the sample's weight (Stiles-Crawford; 1 otherwise). A ray blocked inside the
//! eye carries black for every image, as a ray that misses the LCD does.

use glam::DVec2;

use super::{EyeSample, Kernel, OpticalSystem};
use crate::optics::eye::rays::SampleRays;
use crate::optics::eye::EyePose;
use crate::optics::transfer::{eye_ray, eye_scene_ray};
use crate::optics::PlaneRay;
use crate::ray::Ray;

/// No LCD pixel: the ray misses the LCD or is blocked inside the eye.
pub const MISS: u32 = u32::MAX;
/// Known without tracing: the ground truth of [`Traced::first`] is the pixel's known colour
/// ([`Hint::reference`]); an LCD pixel of [`Traced::lcd`], the pixel's known LCD pixel
/// ([`Hint::images`]).
pub const KNOWN: u32 = u32::MAX - 1;

/// What a consumer knows of a sample's retina pixel before it is traced (see
/// [`OpticalSystem::ray_family`] and [`OpticalSystem::family_lcd_pixels`]): the system then
/// traces nothing it can take from there, and says so with [`KNOWN`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Hint {
    /// The field is one colour over the pixel's [`OpticalSystem::ray_family`].
    pub reference: bool,
    /// Every display image holds one value over the pixel's
    /// [`OpticalSystem::family_lcd_pixels`].
    pub images: bool,
}

/// One sample's trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Traced {
    /// The sample's weight (the Stiles-Crawford weight; 1 otherwise).
    pub weight: f64,
    /// The sample's first ray in [`Traces::scene`], or [`KNOWN`].
    pub first: u32,
    /// Bit `c` set: channel `c` has a ray (it is not blocked inside the eye).
    pub rays: u8,
    /// One ray carries the three channels (else one ray per channel).
    pub single: bool,
    /// Each channel's LCD pixel ([`MISS`]: none; [`KNOWN`]: the pixel's known one).
    pub lcd: [u32; 3],
    /// `lcd[0]` serves the three channels.
    pub shared: bool,
}

impl Traced {
    /// The index in [`Traces::scene`] of channel `c`'s ray, if it has one and it was traced.
    #[inline(always)]
    pub fn scene_ray(&self, c: usize) -> Option<usize> {
        if self.first == KNOWN || self.rays & (1 << c) == 0 {
            return None;
        }
        let before = if self.single { 0 } else { (self.rays & ((1u8 << c) - 1)).count_ones() };
        Some(self.first as usize + before as usize)
    }

    /// Channel `c`'s LCD pixel ([`MISS`], [`KNOWN`] or an index).
    #[inline(always)]
    pub fn lcd_of(&self, c: usize) -> u32 {
        self.lcd[if self.shared { 0 } else { c }]
    }
}

/// The traces of a batch of samples, and the buffers the kernels reuse between batches.
#[derive(Default)]
pub struct Traces {
    /// Each sample's trace, in sample order.
    pub samples: Vec<Traced>,
    /// The scene rays of the ground truth, in sample, then channel order.
    pub scene: Vec<Ray>,
    pub(super) bufs: Buffers,
}

/// A kernel's working buffers.
#[derive(Default)]
pub(super) struct Buffers {
    pub rays: Vec<SampleRays>,
    pub lines: Vec<PlaneRay>,
    pub pixels: Vec<u32>,
    pub scratch: Vec<DVec2>,
    pub nm: Vec<[f64; 3]>,
    pub lens_draw: Vec<crate::optics::diffraction::ApertureDraw>,
    pub slot: Vec<u32>,
    pub active: Vec<u32>,
    pub pos: Vec<u32>,
}

impl Traces {
    fn clear(&mut self) {
        self.samples.clear();
        self.scene.clear();
    }
}

/// `r` (eye coordinates) in world coordinates at the eye's plane.
#[inline(always)]
pub(super) fn world(r: PlaneRay, eye: glam::DVec3) -> PlaneRay {
    PlaneRay { position: r.position + eye.truncate(), slope: r.slope }
}

/// The world ray `r` of the eye at rest (crossing the plane `z` of its pupil centre) moved by
/// `pose`: the scene ray (`x -> c + R (x - c)`, directions by R), and the same line where it
/// crosses the plane `z` again, where the transfer to the LCD starts (`None`: it travels away
/// from the display).
#[inline]
pub(super) fn posed(pose: &EyePose, r: PlaneRay, z: f64) -> (Ray, Option<PlaneRay>) {
    let origin = pose.point(r.position.extend(z));
    let dir = pose.direction(r.slope.extend(1.0));
    let line = (dir.z > 0.0).then(|| {
        let slope = dir.truncate() / dir.z;
        PlaneRay { position: origin.truncate() + slope * (z - origin.z), slope }
    });
    (Ray { origin, dir }, line)
}

/// The trace of a sample that sees nothing (every ray blocked).
const DARK: Traced = Traced { weight: 1.0, first: 0, rays: 0, single: true, lcd: [MISS; 3], shared: true };

impl OpticalSystem<'_> {
    /// Traces `samples` into `out` (cleared first) with the system's kernel. `hints` is empty
    /// or holds one entry per sample. Every kernel gives the bits of
    /// [`OpticalSystem::trace_each`] (where a hint lets it skip a ray, the value it would have
    /// traced is the known one).
    pub fn trace(&self, samples: &[EyeSample], hints: &[Hint], out: &mut Traces) {
        out.clear();
        match self.kernel {
            Kernel::Paraxial => self.trace_paraxial(samples, hints, out),
            Kernel::ThinThick => self.trace_thin_thick(samples, hints, out),
            Kernel::EyeRays => self.trace_eye_rays(samples, out),
            Kernel::ThinDiffracted => self.trace_diffracted(samples, hints, out),
            Kernel::General | Kernel::Rotated => self.trace_general(samples, out),
        }
    }

    /// The slow twin of [`OpticalSystem::trace`]: one sample at a time, without hints.
    pub fn trace_each(&self, samples: &[EyeSample], out: &mut Traces) {
        out.clear();
        for s in samples {
            match self.kernel {
                Kernel::Paraxial => {
                    out.samples.push(Traced {
                        first: out.scene.len() as u32,
                        ..Traced { lcd: [self.paraxial_pixel(s); 3], rays: 0b111, ..DARK }
                    });
                    out.scene.push(eye_scene_ray(&self.eye, s.tangent, s.pupil));
                }
                Kernel::ThinThick => {
                    let r = world(eye_ray(&self.eye, s.tangent, s.pupil), self.eye.position);
                    let t = self.transfer.as_ref();
                    let lcd = std::array::from_fn(|c| index_u32(t.and_then(|t| t.pixel_index_in(r, c, 0.5))));
                    out.samples.push(Traced { first: out.scene.len() as u32, rays: 0b111, lcd, shared: false, ..DARK });
                    out.scene.push(eye_scene_ray(&self.eye, s.tangent, s.pupil));
                }
                _ => {
                    let sr = self.sample_rays(s);
                    self.push_general(s, &sr, out);
                }
            }
        }
    }

    fn paraxial_pixel(&self, s: &EyeSample) -> u32 {
        index_u32(self.transfer.as_ref().and_then(|t| t.pixel_index_through(s.tangent, s.pupil)))
    }

    /// The eye's rays of sample `s` (diffracted at the pupil when the system models it).
    #[inline]
    pub(super) fn sample_rays(&self, s: &EyeSample) -> SampleRays {
        if self.diffraction {
            self.optics.rays_diffracted(s.tangent, s.pupil, s.spectral, [s.diffraction[0], s.diffraction[1]])
        } else {
            self.optics.rays(s.tangent, s.pupil, s.spectral)
        }
    }

    /// The paper's thin lens through paraxial lenslets: every scene ray, then every LCD pixel in
    /// passes over the batch.
    fn trace_paraxial(&self, samples: &[EyeSample], hints: &[Hint], out: &mut Traces) {
        let b = &mut out.bufs;
        b.pixels.clear();
        b.pixels.resize(samples.len(), 0);
        match &self.transfer {
            Some(t) => {
                t.pixel_indices_through(|i| (samples[i].tangent, samples[i].pupil), &mut b.scratch, &mut b.pixels)
            }
            None => b.pixels.fill(MISS),
        }
        for (i, (s, &lcd)) in samples.iter().zip(&b.pixels).enumerate() {
            let first = self.thin_scene(s, hints.get(i), &mut out.scene);
            out.samples.push(Traced { first, rays: 0b111, lcd: [lcd; 3], ..DARK });
        }
    }

    /// The scene ray of the thin lens's sample `s` (pushed to `scene`), or [`KNOWN`] when the
    /// hint says the pixel's ray family is one colour (every thin-lens ray of the pixel is in it).
    #[inline(always)]
    fn thin_scene(&self, s: &EyeSample, hint: Option<&Hint>, scene: &mut Vec<Ray>) -> u32 {
        if hint.is_some_and(|h| h.reference) {
            return KNOWN;
        }
        scene.push(eye_scene_ray(&self.eye, s.tangent, s.pupil));
        scene.len() as u32 - 1
    }

    /// The thin lens through real lenslets: one ray, each channel's pixel at its primary's
    /// median wavelength, the front surface's hit found once for the three.
    fn trace_thin_thick(&self, samples: &[EyeSample], hints: &[Hint], out: &mut Traces) {
        for (i, s) in samples.iter().enumerate() {
            let first = self.thin_scene(s, hints.get(i), &mut out.scene);
            let r = world(eye_ray(&self.eye, s.tangent, s.pupil), self.eye.position);
            let lcd = self.transfer.as_ref().map_or([MISS; 3], |t| t.pixel_indices_in(r, 0.5).map(index_u32));
            out.samples.push(Traced { first, rays: 0b111, lcd, shared: false, ..DARK });
        }
    }

    /// An eye's own rays through paraxial lenslets, without diffraction: every sample's rays
    /// (two at a time: a schematic eye's ray map shares its coefficients, bit for bit `rays` one
    /// by one), every scene ray, every LCD pixel, in passes.
    fn trace_eye_rays(&self, samples: &[EyeSample], out: &mut Traces) {
        let b = &mut out.bufs;
        b.rays.clear();
        let mut pairs = samples.chunks_exact(2);
        for pair in &mut pairs {
            let (x, y) = (&pair[0], &pair[1]);
            b.rays.extend(self.optics.rays2((x.tangent, x.pupil, x.spectral), (y.tangent, y.pupil, y.spectral)));
        }
        b.rays.extend(pairs.remainder().iter().map(|s| self.optics.rays(s.tangent, s.pupil, s.spectral)));
        b.lines.clear();
        let eye = self.eye.position;
        for sr in &b.rays {
            let n = if sr.single { 1 } else { 3 };
            b.lines.extend(sr.rays[..n].iter().flatten().map(|r| world(*r, eye)));
        }
        out.scene.extend(b.lines.iter().map(|w| Ray { origin: w.position.extend(eye.z), dir: w.slope.extend(1.0) }));
        b.pixels.clear();
        b.pixels.resize(b.lines.len(), 0);
        let lines = &b.lines;
        match &self.transfer {
            Some(t) => t.pixel_indices_of(|i| lines[i], &mut b.scratch, &mut b.pixels),
            None => b.pixels.fill(MISS),
        }
        let mut next = 0u32;
        for sr in &b.rays {
            let (rays, n) = carried(sr);
            let mut lcd = [MISS; 3];
            let mut j = next;
            for (c, l) in lcd.iter_mut().enumerate().take(n) {
                if rays & (1 << c) != 0 {
                    *l = b.pixels[j as usize];
                    j += 1;
                }
            }
            if sr.single {
                lcd = [lcd[0]; 3];
            }
            out.samples.push(Traced {
                weight: sr.weight,
                first: next,
                rays,
                single: sr.single,
                lcd,
                shared: sr.single,
            });
            next = j;
        }
    }

    /// Everything else, sample by sample (each sample's rays two at a time when the pupil does
    /// not diffract, as [`OpticalSystem::trace_eye_rays`]).
    fn trace_general(&self, samples: &[EyeSample], out: &mut Traces) {
        let mut rays = std::mem::take(&mut out.bufs.rays);
        rays.clear();
        if self.diffraction {
            rays.extend(samples.iter().map(|s| self.sample_rays(s)));
        } else {
            let mut pairs = samples.chunks_exact(2);
            for pair in &mut pairs {
                let (a, b) = (&pair[0], &pair[1]);
                rays.extend(self.optics.rays2((a.tangent, a.pupil, a.spectral), (b.tangent, b.pupil, b.spectral)));
            }
            rays.extend(pairs.remainder().iter().map(|s| self.optics.rays(s.tangent, s.pupil, s.spectral)));
        }
        for (s, sr) in samples.iter().zip(&rays) {
            self.push_general(s, sr, out);
        }
        out.bufs.rays = rays;
    }

    /// The trace of sample `s` with rays `sr`, each channel's LCD pixel found one at a time.
    fn push_general(&self, s: &EyeSample, sr: &SampleRays, out: &mut Traces) {
        let optics = &*self.optics;
        let transfer = self.transfer.as_ref();
        let thick = transfer.is_some_and(|t| t.is_thick());
        let single = optics.is_single_wavelength();
        // Each channel finds its own LCD pixel through a real lenslet (refracted at its own
        // wavelength), and through a diffracting lenslet when the channels' wavelengths differ
        // (the deviation scales with the wavelength); else one pixel serves a ray's channels.
        let per_channel = thick || (self.lenslet.is_some() && !single);
        // Each channel at the sampled wavelength, else its primary's median (real lenslets).
        let u_lens = if single { 0.5 } else { s.spectral };
        // The lenslet's draw once for the three channels, scaled by each one's wavelength.
        let draw = self.lenslet.as_ref().map(|shape| (shape, shape.draw([s.diffraction[2], s.diffraction[3]])));
        let (rays, n) = carried(sr);
        let first = out.scene.len() as u32;
        let mut lcd = [MISS; 3];
        for c in 0..n {
            let Some(r) = sr.rays[c].filter(|_| rays & (1 << c) != 0) else { continue };
            let r = world(r, self.eye.position);
            let (scene, r) = match &self.eye.pose {
                None => (Ray { origin: r.position.extend(self.eye.position.z), dir: r.slope.extend(1.0) }, Some(r)),
                Some(pose) => posed(pose, r, self.eye.position.z),
            };
            out.scene.push(scene);
            // The LCD pixel of this ray in channel `ch`.
            let index = |ch: usize| {
                let (Some(t), Some(r)) = (transfer, r) else { return MISS };
                let pixel = match (thick, draw) {
                    (false, None) => t.pixel_index_of(r),
                    (false, Some((shape, draw))) => {
                        t.pixel_index_deviated(r, shape.scaled(draw, optics.wavelength(ch, s.spectral)))
                    }
                    (true, None) => t.pixel_index_in(r, ch, u_lens),
                    // Bent where it leaves the lenslet by the cell's deviation.
                    (true, Some((shape, draw))) => {
                        let deviation = shape.scaled(draw, optics.wavelength(ch, s.spectral));
                        t.pixel_index_in_deviated(r, ch, u_lens, deviation)
                    }
                };
                index_u32(pixel)
            };
            // The channels this ray carries: all three for one ray, else its own.
            let carries = if sr.single { 0..3 } else { c..c + 1 };
            if per_channel {
                for ch in carries {
                    lcd[ch] = index(ch);
                }
            } else {
                let i = index(c);
                for ch in carries {
                    lcd[ch] = i;
                }
            }
        }
        let shared = sr.single && !per_channel;
        out.samples.push(Traced { weight: sr.weight, first, rays, single: sr.single, lcd, shared });
    }
}

/// The channels of `sr` with a ray (bits) and the number of rays it holds (1 or 3).
#[inline(always)]
fn carried(sr: &SampleRays) -> (u8, usize) {
    if sr.single {
        (if sr.rays[0].is_some() { 0b111 } else { 0 }, 1)
    } else {
        let bits = (0..3).filter(|&c| sr.rays[c].is_some()).fold(0u8, |b, c| b | (1 << c));
        (bits, 3)
    }
}

/// An LCD pixel index as stored in [`Traced::lcd`].
#[inline(always)]
pub(super) fn index_u32(i: Option<usize>) -> u32 {
    i.and_then(|i| u32::try_from(i).ok()).filter(|&i| i < KNOWN).unwrap_or(MISS)
}
