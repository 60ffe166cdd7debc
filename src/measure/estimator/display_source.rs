//! The experiment's paired source (paper Sec. 2.3, 4.1): every eye sample traced once through
//! the eye case's [`OpticalSystem`] gives the ground truth (the scene along its rays) and what
//! the eye perceives of every display image (each channel read at its LCD pixel), so the images
//! share their rays. The system decides how the samples are traced; this file only reads the
//! field and the display images along what it traced.

use std::cell::RefCell;

use glam::DVec2;

use super::{EyeSample, PairedSource};
use crate::optics::system::{Hint, OpticalSystem, Traced, Traces, KNOWN, MISS};
use crate::optics::{Display, Eye};
use crate::render::retina::DisplayStack;
use crate::render::{RadianceField, Sample};

/// Image 0 is the ground truth (the eye's rays into the scene), image `1 + m` what the eye
/// perceives of display image `m` of `stack`.
pub struct DisplaySource<'a, F: RadianceField + ?Sized> {
    system: OpticalSystem<'a>,
    field: &'a F,
    stack: &'a DisplayStack,
}

/// A worker's buffers, kept between batches.
#[derive(Default)]
struct Buffers {
    traces: Traces,
    hints: Vec<Hint>,
    hits: Vec<Sample>,
    radiance: Vec<[f64; 3]>,
}

thread_local! {
    static BUFFERS: RefCell<Buffers> = RefCell::new(Buffers::default());
}

impl<'a, F: RadianceField + ?Sized> DisplaySource<'a, F> {
    /// Samples of `eye`: the ground truth from `field`, and what it perceives of every display image
    /// of `stack` on `display`.
    pub fn new(display: &'a Display, eye: &Eye, field: &'a F, stack: &'a DisplayStack) -> Self {
        Self { system: OpticalSystem::new(display, eye), field, stack }
    }

    /// The optical system the samples are traced through.
    pub fn system(&self) -> &OpticalSystem<'a> {
        &self.system
    }

    /// Slow twin of [`PairedSource::eval`]: every sample traced one at a time
    /// ([`OpticalSystem::trace_each`]), nothing taken from what is known of its pixel. Same values.
    pub fn eval_each_ray(&self, samples: &[EyeSample], out: &mut [[f64; 3]]) {
        let mut b = Buffers::default();
        self.system.trace_each(samples, &mut b.traces);
        self.read(&mut b, &[], &[], out);
    }

    /// Traces `samples` and reads the field and the display images along them.
    fn eval_in(
        &self,
        samples: &[EyeSample],
        known: &[Option<[f64; 3]>],
        images: &[u32],
        out: &mut [[f64; 3]],
        b: &mut Buffers,
    ) {
        b.hints.clear();
        if !known.is_empty() || !images.is_empty() {
            b.hints.extend((0..samples.len()).map(|i| Hint {
                reference: matches!(known.get(i), Some(Some(_))),
                images: images.get(i).is_some_and(|&p| p != MISS),
            }));
        }
        self.system.trace(samples, &b.hints, &mut b.traces);
        self.read(b, known, images, out);
    }

    /// The field along every traced scene ray, then every sample's images. A field that takes
    /// batches gets every ray at once; otherwise each ray's radiance is asked where it is read.
    fn read(&self, b: &mut Buffers, known: &[Option<[f64; 3]>], images: &[u32], out: &mut [[f64; 3]]) {
        let scene = &b.traces.scene;
        let batched = self.field.prefers_batches();
        b.radiance.clear();
        if batched {
            b.hits.clear();
            b.hits.resize(scene.len(), Sample::default());
            self.field.sample_many(scene, &mut b.hits);
            b.radiance.extend(b.hits.iter().map(|h| h.radiance.to_array()));
        }
        let radiance = |j: usize| if batched { b.radiance[j] } else { self.field.radiance(&scene[j]).to_array() };
        let k = 1 + self.stack.len();
        debug_assert_eq!(out.len(), b.traces.samples.len() * k);
        for (i, (o, t)) in out.chunks_exact_mut(k).zip(&b.traces.samples).enumerate() {
            let w = t.weight;
            o[0] = if t.first == KNOWN {
                known[i].expect("a known ground truth").map(|v| v * w)
            } else if t.single {
                match t.scene_ray(0) {
                    Some(j) => radiance(j).map(|v| v * w),
                    None => [0.0; 3],
                }
            } else {
                std::array::from_fn(|c| t.scene_ray(c).map_or(0.0, |j| radiance(j)[c] * w))
            };
            self.read_images(t, images.get(i).copied().unwrap_or(MISS), &mut o[1..]);
        }
    }

    /// Every display image's channels at the sample's LCD pixels, times its weight (`known`:
    /// the pixel's known LCD pixel, for [`KNOWN`]).
    #[inline(always)]
    fn read_images(&self, t: &Traced, known: u32, o: &mut [[f64; 3]]) {
        let w = t.weight;
        let pixel = |idx: u32| match idx {
            MISS => None,
            KNOWN => Some(self.stack.pixel(known as usize)),
            i => Some(self.stack.pixel(i as usize)),
        };
        if t.shared {
            match pixel(t.lcd[0]) {
                None => o.fill([0.0; 3]),
                // The weight skipped where it is 1 (the same bits), for the common stack sizes
                // with the image count known to the compiler.
                Some(px) if w == 1.0 => match o.len() {
                    1 => read_pixel::<1>(px, o),
                    2 => read_pixel::<2>(px, o),
                    3 => read_pixel::<3>(px, o),
                    _ => read_pixel_each(px, o),
                },
                Some(px) => {
                    for (j, v) in o.iter_mut().enumerate() {
                        *v = std::array::from_fn(|c| f64::from(px[3 * j + c]) * w);
                    }
                }
            }
            return;
        }
        for c in 0..3 {
            match pixel(t.lcd[c]) {
                None => o.iter_mut().for_each(|v| v[c] = 0.0),
                Some(px) => {
                    for (j, v) in o.iter_mut().enumerate() {
                        v[c] = f64::from(px[3 * j + c]) * w;
                    }
                }
            }
        }
    }
}

/// Every image's three channels of LCD pixel `px` into `o` (`M` images).
#[inline(always)]
fn read_pixel<const M: usize>(px: &[f32], o: &mut [[f64; 3]]) {
    let (px, o) = (&px[..3 * M], &mut o[..M]);
    for j in 0..M {
        o[j] = [f64::from(px[3 * j]), f64::from(px[3 * j + 1]), f64::from(px[3 * j + 2])];
    }
}

/// The slow twin of [`read_pixel`], for any number of images.
fn read_pixel_each(px: &[f32], o: &mut [[f64; 3]]) {
    for (j, v) in o.iter_mut().enumerate() {
        *v = std::array::from_fn(|c| f64::from(px[3 * j + c]));
    }
}

impl<F: RadianceField + ?Sized> PairedSource for DisplaySource<'_, F> {
    fn images(&self) -> usize {
        1 + self.stack.len()
    }

    fn eval(&self, samples: &[EyeSample], out: &mut [[f64; 3]]) {
        self.eval_known_images(samples, &[], &[], out);
    }

    fn spectral(&self) -> bool {
        self.system.needs_spectral()
    }

    fn diffraction(&self) -> bool {
        self.system.needs_diffraction()
    }

    fn reference_over(&self, tangents: (DVec2, DVec2), pupil_radius: f64) -> Option<[f64; 3]> {
        let pupil = (DVec2::splat(-pupil_radius), DVec2::splat(pupil_radius));
        let family = self.system.ray_family(tangents, pupil)?;
        self.field.uniform(&family).map(|(c, _)| c.to_array())
    }

    fn images_over(&self, tangents: (DVec2, DVec2), pupil_radius: f64) -> Option<u32> {
        let nx = self.system.lcd_columns();
        let mut first: Option<usize> = None;
        let same = self.system.family_lcd_pixels(tangents, pupil_radius, |cols, rows| {
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
        })?;
        first.filter(|_| same).and_then(|f| u32::try_from(f).ok()).filter(|&f| f < KNOWN)
    }

    fn eval_known(&self, samples: &[EyeSample], known: &[Option<[f64; 3]>], out: &mut [[f64; 3]]) {
        self.eval_known_images(samples, known, &[], out);
    }

    fn eval_known_images(
        &self,
        samples: &[EyeSample],
        known: &[Option<[f64; 3]>],
        images: &[u32],
        out: &mut [[f64; 3]],
    ) {
        BUFFERS.with(|b| match b.try_borrow_mut() {
            Ok(mut b) => self.eval_in(samples, known, images, out, &mut b),
            // Re-entered on this thread (a field that runs parallel work): fresh buffers.
            Err(_) => self.eval_in(samples, known, images, out, &mut Buffers::default()),
        });
    }
}
