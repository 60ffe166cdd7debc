//! Paraxial ray transfer between the retina, the eye lens, the lenslet array and the LCD: the
//! paper's eq. (1) (Sec. 2.3):
//!
//! ```text
//! x_{i+1} = x_i + w_i v_i                      (1a)   propagation over distance v_i
//! w_1 = w_0 - x_1 d_1,  w_2 = w_1 - (x_2 - x_c) d_2   (1b)   thin-lens refraction
//! ```
//!
//! `x` are transverse positions (mm) and `w` slopes (dx/dz) in x and y independently. `x_c` is
//! the centre of the lenslet the ray crosses: the lenslet whose centre is nearest to `x_2`
//! ([`crate::optics::lattice::Lattice::nearest`]); that one rule decides the lenslet in every
//! trace that crosses the lenslet plane. Positions of the eye-side segments are measured from
//! the eye's optical axis (through its pupil centre); positions on the display planes are world
//! x, y.
//!
//! Every trace of eq. (1) the program runs lives here, each fast path next to its slow twin
//! (the slow twin spells the equation out step by step; unit tests below hold them together):
//!
//! - eye -> LCD: [`eye_to_lcd`] (slow) and [`FastTransfer`] (per-eye constants folded in), which
//!   the perceived-image simulation runs for every retina and pupil sample;
//! - eye -> scene: [`eye_scene_ray`], the ground truth's ray leaving the eye lens;
//! - LCD -> eye: [`lcd_to_eye`] (slow) and [`camera_ray`], the display-image renderer's ray of
//!   a display pixel, plus [`pupil_center_point`], eq. (1) solved for the lenslet-plane point
//!   whose ray passes through the pupil centre (the PupilCenter method).
//!
//! A display with real (thick) lenslets replaces eq. (1b) by the exact trace of
//! [`crate::optics::lenslet`] (its slow twin: root finding of the sag equation): the eye's rays
//! find one LCD pixel per colour channel through [`FastTransfer::pixel_index_in`], and the
//! camera rays are [`ThickLenslet::camera_ray`].

use glam::{DVec2, DVec3, IVec2};

use super::display::{Display, PixelIndexer};
use super::eye::Eye;
use super::lenslet::{Intersection, ThickLenslet};
use super::spectrum::SpectrumSampler;
use crate::error::{Error, Result};
use crate::ray::Ray;

/// A ray crossing a plane: transverse position and slope (dx/dz, dy/dz), travelling toward +z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneRay {
    /// Transverse position (x, y), mm.
    pub position: DVec2,
    /// Slope (dx/dz, dy/dz).
    pub slope: DVec2,
}

impl PlaneRay {
    /// Eq. (1a): the ray after travelling `distance` along z.
    #[inline]
    pub fn propagate(self, distance: f64) -> PlaneRay {
        PlaneRay { position: self.position + self.slope * distance, slope: self.slope }
    }

    /// Eq. (1b): refraction by a thin lens of power `power` centred at `center`.
    #[inline]
    pub fn refract(self, center: DVec2, power: f64) -> PlaneRay {
        PlaneRay { position: self.position, slope: self.slope - (self.position - center) * power }
    }

    /// The inverse of [`PlaneRay::refract`]: the slope before the lens.
    #[inline]
    pub fn unrefract(self, center: DVec2, power: f64) -> PlaneRay {
        PlaneRay { position: self.position, slope: self.slope + (self.position - center) * power }
    }
}

/// Every point of one eye -> display trace (world x, y unless said otherwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeTrace {
    /// x0: retina point relative to the eye's axis (at z = eye z - v0).
    pub retina: DVec2,
    /// x1 and w1: the ray leaving the eye lens (position in world x, y at the pupil plane).
    pub pupil: PlaneRay,
    /// x2 and w2: the ray leaving the lenslet plane after refraction.
    pub lenslet: PlaneRay,
    /// The lenslet the ray crossed (nearest centre to x2).
    pub lenslet_index: IVec2,
    /// x3: where the ray meets the LCD plane.
    pub lcd: DVec2,
}

/// The ray that leaves the eye lens for retina direction `tangent` (x0 = -v0 * tangent) through
/// pupil point `pupil_offset` (relative to the pupil centre): eq. (1a) then (1b) with d1.
#[inline]
pub fn eye_ray(eye: &Eye, tangent: DVec2, pupil_offset: DVec2) -> PlaneRay {
    let v0 = eye.retina_distance;
    let x0 = -v0 * tangent;
    let w0 = (pupil_offset - x0) / v0;
    PlaneRay { position: pupil_offset, slope: w0 }.refract(DVec2::ZERO, eye.power())
}

/// Traces retina -> pupil -> lenslet plane -> refraction at the nearest lenslet -> LCD plane.
#[inline]
pub fn eye_to_lcd(display: &Display, eye: &Eye, tangent: DVec2, pupil_offset: DVec2) -> EyeTrace {
    let local = eye_ray(eye, tangent, pupil_offset);
    let pupil = PlaneRay { position: local.position + eye.position.truncate(), slope: local.slope };
    let at_lenslets = pupil.propagate(display.lenslet_z() - eye.position.z);
    let lenslet_index = display.lenslets.nearest(at_lenslets.position);
    let center = display.lenslets.center(lenslet_index);
    let lenslet = at_lenslets.refract(center, display.lenslet_power());
    let lcd = lenslet.propagate(display.lenslets_to_lcd).position;
    EyeTrace { retina: -eye.retina_distance * tangent, pupil, lenslet, lenslet_index, lcd }
}

/// The eye -> LCD trace of [`eye_to_lcd`] with the per-eye constants folded in, for the hot
/// loops of the perceived-image simulation (a fixed pupil grid, [`FastTransfer::new`]) and of
/// the converged measurement (any pupil point, [`FastTransfer::for_eye`]; its `EyeToLcd` is
/// built on this). Every path (pupil sample or pupil point, one ray or a batch) does the same
/// arithmetic in the same order, so they give the same LCD point bit for bit; tests check it
/// against `eye_to_lcd` (the slow twin).
pub struct FastTransfer<'a> {
    display: &'a Display,
    /// The eye's x, y (the pupil centre in world coordinates).
    eye_xy: DVec2,
    /// v0 and d1 of the eye.
    v0: f64,
    d1: f64,
    /// Per pupil sample: [`FastTransfer::pupil_constants`] of it.
    samples: Vec<(DVec2, DVec2)>,
    /// Distance from the pupil plane to the lenslets.
    to_lenslets: f64,
    lenslet_power: f64,
    v2: f64,
    indexer: PixelIndexer,
    /// A real lenslet: the lens, the channels' spectra, the pupil plane's z.
    thick: Option<ThickTransfer<'a>>,
}

/// What the exact trace through a real lenslet needs.
struct ThickTransfer<'a> {
    lens: &'a ThickLenslet,
    samplers: Box<[SpectrumSampler; 3]>,
    /// The material's index at each channel's median wavelength (spectral coordinate 0.5).
    median_index: [f64; 3],
    eye_z: f64,
}

impl<'a> FastTransfer<'a> {
    /// The trace through each of the pupil samples `pupil` (mm from the pupil centre), addressed
    /// by index ([`FastTransfer::lcd_point`]).
    pub fn new(display: &'a Display, eye: &Eye, pupil: &[DVec2]) -> Self {
        let mut t = Self::for_eye(display, eye);
        t.samples = pupil.iter().map(|&s| t.pupil_constants(s)).collect();
        t
    }

    /// The trace through any pupil point ([`FastTransfer::lcd_point_through`]), no samples.
    pub fn for_eye(display: &'a Display, eye: &Eye) -> Self {
        Self {
            display,
            eye_xy: eye.position.truncate(),
            v0: eye.retina_distance,
            d1: eye.power(),
            samples: Vec::new(),
            to_lenslets: display.lenslet_z() - eye.position.z,
            lenslet_power: display.lenslet_power(),
            v2: display.lenslets_to_lcd,
            indexer: PixelIndexer::new(&display.lcd),
            thick: display.thick_lenslet().map(|lens| {
                let samplers = Box::new(display.channel_samplers());
                let median_index = std::array::from_fn(|c| lens.material.index(samplers[c].wavelength(0.5)));
                ThickTransfer { lens, samplers, median_index, eye_z: eye.position.z }
            }),
        }
    }

    /// For pupil point `s`: the world position at the pupil plane, and the slope offset
    /// `s/v0 - s d1` so that `w1 = tangent + offset` (eq. (1a), (1b) with d1).
    #[inline(always)]
    fn pupil_constants(&self, s: DVec2) -> (DVec2, DVec2) {
        (s + self.eye_xy, s / self.v0 - s * self.d1)
    }

    /// The lenslet-plane point x2 and the slope w1 of the ray leaving the pupil at `x1` with
    /// slope `tangent + offset`.
    #[inline(always)]
    fn to_lenslet_plane(&self, (x1, offset): (DVec2, DVec2), tangent: DVec2) -> (DVec2, DVec2) {
        let w1 = tangent + offset;
        (x1 + w1 * self.to_lenslets, w1)
    }

    /// Refraction at the nearest lenslet and on to the LCD plane.
    #[inline(always)]
    fn to_lcd(&self, (x2, w1): (DVec2, DVec2)) -> DVec2 {
        let c = self.display.lenslets.center(self.display.lenslets.nearest(x2));
        let w2 = w1 - (x2 - c) * self.lenslet_power;
        x2 + w2 * self.v2
    }

    /// Where the ray for retina direction `tangent` through pupil sample `k` meets the LCD.
    #[inline(always)]
    pub fn lcd_point(&self, tangent: DVec2, k: usize) -> DVec2 {
        self.to_lcd(self.to_lenslet_plane(self.samples[k], tangent))
    }

    /// Where the ray for retina direction `tangent` through pupil point `pupil` (mm from the
    /// pupil centre) meets the LCD; at a pupil sample, the same point as [`FastTransfer::lcd_point`].
    #[inline(always)]
    pub fn lcd_point_through(&self, tangent: DVec2, pupil: DVec2) -> DVec2 {
        self.to_lcd(self.to_lenslet_plane(self.pupil_constants(pupil), tangent))
    }

    /// The LCD pixel met by any ray leaving the eye: `ray` is its line where it crosses the
    /// plane of the eye's pupil centre (world x, y; travelling toward +z), as a schematic eye's
    /// rays are given ([`crate::optics::eye::EyeOptics::rays`]). Eq. (1) from the lenslet plane
    /// on, the same arithmetic as every other path.
    #[inline(always)]
    pub fn pixel_index_of(&self, ray: PlaneRay) -> Option<usize> {
        self.indexer.index(self.to_lcd((ray.position + ray.slope * self.to_lenslets, ray.slope)))
    }

    /// [`FastTransfer::pixel_index_of`] with the ray's slope after the lenslet changed by
    /// `deviation` (the lenslet aperture's diffraction, `optics::diffraction`): the lenslet is
    /// still the one the ray crosses, the deviation bends it on to the LCD.
    #[inline(always)]
    pub fn pixel_index_deviated(&self, ray: PlaneRay, deviation: DVec2) -> Option<usize> {
        let x2 = ray.position + ray.slope * self.to_lenslets;
        let c = self.display.lenslets.center(self.display.lenslets.nearest(x2));
        let w2 = ray.slope - (x2 - c) * self.lenslet_power + deviation;
        self.indexer.index(x2 + w2 * self.v2)
    }

    /// [`FastTransfer::pixel_index_deviated`] (or, where `pair(j)` gives no deviation,
    /// [`FastTransfer::pixel_index_of`]) of `out.len()` pairs of a ray and a deviation (`pair(j)`:
    /// the index of pair `j`'s ray in `rays`, its deviation), in passes: every ray's point on the
    /// lenslet plane and its lenslet's centre once (rays shared by several pairs are not traced
    /// again), then each pair's LCD pixel (`u32::MAX`: off the LCD). The same arithmetic, so the
    /// same pixels bit for bit. `scratch` is reused between calls.
    #[inline(always)]
    pub fn pixel_indices_deviated(
        &self,
        rays: &[PlaneRay],
        pair: impl Fn(usize) -> (usize, Option<DVec2>),
        scratch: &mut Vec<DVec2>,
        out: &mut [u32],
    ) {
        let n = rays.len();
        scratch.clear();
        scratch.resize(2 * n, DVec2::ZERO);
        let (x2s, centres) = scratch.split_at_mut(n);
        for (x2, r) in x2s.iter_mut().zip(rays) {
            *x2 = r.position + r.slope * self.to_lenslets;
        }
        centres.copy_from_slice(x2s);
        self.display.lenslets.nearest_centers(centres);
        for (j, o) in out.iter_mut().enumerate() {
            let (i, deviation) = pair(j);
            let (x2, c) = (x2s[i], centres[i]);
            let w2 = match deviation {
                Some(d) => rays[i].slope - (x2 - c) * self.lenslet_power + d,
                None => rays[i].slope - (x2 - c) * self.lenslet_power,
            };
            *o = self.indexer.index_u32(x2 + w2 * self.v2);
        }
    }

    /// The LCD pixels every deviated thin-lens ray of a retina pixel can meet, for the
    /// diffracted eye's shortcut (`optics/system/diffracted.rs`): the rays of
    /// `crate::optics::eye::ThinLensRay` `(v0, d1)` with retina tangents in the box `tangents`
    /// (already widened by the pupil's deviations), pupil points within `pupil_radius` mm of its
    /// centre in x and y, through any lenslet their lenslet-plane points can reach, bent after
    /// the lenslet by a deviation of at most `deviation` in x and y (as
    /// [`FastTransfer::pixel_indices_deviated`]). Calls `each(columns, rows)` (inclusive ranges)
    /// for one rectangle per lenslet, which together hold every such ray's pixel: eq. (1) is
    /// affine in the pupil point, the tangent and the deviation for a given lenslet, so
    /// intervals bound it; a margin of 1e-6 mm (about 1e-4 of a pixel, far beyond the rounding
    /// of the arithmetic) on each bound. False (and no more calls) when `each` says false, part
    /// of a rectangle lies off the LCD, the lattice is not axis-aligned or the rays reach more
    /// than `max_lenslets` lenslets.
    pub fn deviated_family_pixels(
        &self,
        (v0, d1): (f64, f64),
        tangents: (DVec2, DVec2),
        pupil_radius: f64,
        deviation: f64,
        max_lenslets: usize,
        mut each: impl FnMut([usize; 2], [usize; 2]) -> bool,
    ) -> bool {
        const MARGIN: f64 = 1e-6;
        let lattice = &self.display.lenslets;
        if self.thick.is_some() || !lattice.is_axis_aligned() {
            return false;
        }
        // a * [lo, hi] as an interval.
        let scale = |a: f64, lo: DVec2, hi: DVec2| ((lo * a).min(hi * a), (lo * a).max(hi * a));
        let add = |x: (DVec2, DVec2), y: (DVec2, DVec2)| (x.0 + y.0, x.1 + y.1);
        let r = DVec2::splat(pupil_radius.abs() * (1.0 + 1e-9) + 1e-12);
        let t = (tangents.0.min(tangents.1) - 1e-9, tangents.0.max(tangents.1) + 1e-9);
        let (l, p, v2) = (self.to_lenslets, self.lenslet_power, self.v2);
        // The slope t + s (1/v0 - d1); the lenslet-plane point eye + s (1 + k L) + t L.
        let k = 1.0 / v0 - d1;
        let x2 = add(scale(1.0 + k * l, -r, r), scale(l, t.0, t.1));
        let x2 = (x2.0 + self.eye_xy - MARGIN, x2.1 + self.eye_xy + MARGIN);
        let (i0, i1) = (lattice.nearest(x2.0), lattice.nearest(x2.1));
        let (ilo, ihi) = (i0.min(i1), i0.max(i1));
        let count = (ihi - ilo + 1).as_i64vec2();
        if count.x * count.y > max_lenslets as i64 {
            return false;
        }
        // The LCD point eye (1 - P v2) + s ((1 + k L)(1 - P v2) + k v2) + t (L (1 - P v2) + v2)
        // + c P v2 + deviation v2.
        let q = 1.0 - p * v2;
        let base = add(scale((1.0 + k * l) * q + k * v2, -r, r), scale(l * q + v2, t.0, t.1));
        let dev = DVec2::splat(deviation.abs() * v2.abs() + MARGIN);
        let eye = self.eye_xy * q;
        let base = (base.0 + eye - dev, base.1 + eye + dev);
        for iy in ilo.y..=ihi.y {
            for ix in ilo.x..=ihi.x {
                let c = lattice.center(glam::IVec2::new(ix, iy)) * (p * v2);
                let (lo, hi) = (base.0 + c, base.1 + c);
                let Some((cols, rows)) = self.indexer.box_pixels(lo, hi) else { return false };
                if !each(cols, rows) {
                    return false;
                }
            }
        }
        true
    }

    /// The LCD's pixels per row.
    pub fn lcd_columns(&self) -> usize {
        self.indexer.columns()
    }

    /// Whether the display's lenslets are real ones: then each colour channel has its own LCD
    /// pixel ([`FastTransfer::pixel_index_in`]) and the one-pixel paths above do not apply.
    pub fn is_thick(&self) -> bool {
        self.thick.is_some()
    }

    /// The LCD pixel met in colour channel `c` by `ray` (given as for
    /// [`FastTransfer::pixel_index_of`]), at the wavelength the spectral coordinate `u` picks
    /// from the channel's primary: through a real lenslet, the exact trace
    /// ([`ThickLenslet::trace_to_lcd`]; a blocked ray meets no pixel); through the thin lens,
    /// [`FastTransfer::pixel_index_of`] for every channel.
    #[inline]
    pub fn pixel_index_in(&self, ray: PlaneRay, c: usize, u: f64) -> Option<usize> {
        let Some(t) = &self.thick else {
            return self.pixel_index_of(ray);
        };
        let n = if u == 0.5 { t.median_index[c] } else { t.lens.material.index(t.samplers[c].wavelength(u)) };
        let d = self.display;
        t.lens
            .trace_to_lcd_in(
                &d.lenslets,
                d.lenslet_z(),
                d.lcd_z(),
                ray.position.extend(t.eye_z),
                ray.slope,
                n,
                Intersection::ClosedForm,
            )
            .and_then(|tr| self.indexer.index(tr.lcd))
    }

    /// [`FastTransfer::pixel_index_in`] of one ray in each of the three colour channels (each at
    /// the wavelength `u` picks from its primary): through a real lenslet the ray meets the front
    /// surface at one point whatever its wavelength, found once
    /// ([`ThickLenslet::trace_to_lcd_each`]); the same pixels as three calls (tested).
    #[inline]
    pub fn pixel_indices_in(&self, ray: PlaneRay, u: f64) -> [Option<usize>; 3] {
        let Some(t) = &self.thick else {
            return [self.pixel_index_of(ray); 3];
        };
        let ns = if u == 0.5 {
            t.median_index
        } else {
            std::array::from_fn(|c| t.lens.material.index(t.samplers[c].wavelength(u)))
        };
        let d = self.display;
        t.lens
            .trace_to_lcd_each(
                &d.lenslets,
                d.lenslet_z(),
                d.lcd_z(),
                ray.position.extend(t.eye_z),
                ray.slope,
                ns,
                Intersection::ClosedForm,
            )
            .map(|tr| tr.and_then(|tr| self.indexer.index(tr.lcd)))
    }

    /// [`FastTransfer::pixel_index_in`] with the lenslet aperture's diffraction `deviation` (a
    /// slope change, `optics::diffraction`): through a real lenslet the exact trace's ray is bent
    /// where it leaves the back surface and goes on straight to the LCD; through the thin lens,
    /// [`FastTransfer::pixel_index_deviated`].
    #[inline]
    pub fn pixel_index_in_deviated(&self, ray: PlaneRay, c: usize, u: f64, deviation: DVec2) -> Option<usize> {
        let Some(t) = &self.thick else {
            return self.pixel_index_deviated(ray, deviation);
        };
        let n = if u == 0.5 { t.median_index[c] } else { t.lens.material.index(t.samplers[c].wavelength(u)) };
        let d = self.display;
        let tr = t.lens.trace_to_lcd_in(
            &d.lenslets,
            d.lenslet_z(),
            d.lcd_z(),
            ray.position.extend(t.eye_z),
            ray.slope,
            n,
            Intersection::ClosedForm,
        )?;
        let slope = tr.dir.truncate() / tr.dir.z + deviation;
        self.indexer.index(tr.back.truncate() + slope * (d.lcd_z() - tr.back.z))
    }

    /// The LCD pixel that ray hits, if any ([`crate::optics::Lcd::pixel_index`]).
    #[inline(always)]
    pub fn pixel_index(&self, tangent: DVec2, k: usize) -> Option<usize> {
        self.indexer.index(self.lcd_point(tangent, k))
    }

    /// The LCD pixel the ray through pupil point `pupil` hits, if any.
    #[inline(always)]
    pub fn pixel_index_through(&self, tangent: DVec2, pupil: DVec2) -> Option<usize> {
        self.indexer.index(self.lcd_point_through(tangent, pupil))
    }

    /// [`FastTransfer::pixel_index`] for every tangent through pupil sample `k` (`u32::MAX`: off
    /// the LCD), in passes over the batch ([`lcd_pixels`]); same arithmetic, so the same pixels
    /// (tested). `scratch` is reused between calls.
    pub fn pixel_indices(&self, tangents: &[DVec2], k: usize, scratch: &mut Vec<DVec2>, out: &mut [u32]) {
        let constants = self.samples[k];
        self.batch(tangents.len(), |i| self.to_lenslet_plane(constants, tangents[i]), scratch, out);
    }

    /// [`FastTransfer::pixel_index_through`] for the `out.len()` rays `ray(i)` = (tangent,
    /// pupil point) (`u32::MAX`: off the LCD), in passes over the batch; same arithmetic, so the
    /// same pixels.
    pub fn pixel_indices_through(
        &self,
        ray: impl Fn(usize) -> (DVec2, DVec2),
        scratch: &mut Vec<DVec2>,
        out: &mut [u32],
    ) {
        self.batch(
            out.len(),
            |i| {
                let (tangent, pupil) = ray(i);
                self.to_lenslet_plane(self.pupil_constants(pupil), tangent)
            },
            scratch,
            out,
        );
    }

    /// [`FastTransfer::pixel_index_of`] for the `out.len()` rays `ray(i)` (given as for it;
    /// `u32::MAX`: off the LCD), in passes over the batch; same arithmetic, so the same pixels.
    pub fn pixel_indices_of(&self, ray: impl Fn(usize) -> PlaneRay, scratch: &mut Vec<DVec2>, out: &mut [u32]) {
        self.batch(
            out.len(),
            |i| {
                let r = ray(i);
                (r.position + r.slope * self.to_lenslets, r.slope)
            },
            scratch,
            out,
        );
    }

    /// The batched trace: `ray(i)` is ray `i`'s (x2, w1) at the lenslet plane.
    #[inline(always)]
    fn batch(&self, n: usize, ray: impl Fn(usize) -> (DVec2, DVec2), scratch: &mut Vec<DVec2>, out: &mut [u32]) {
        scratch.clear();
        scratch.resize(3 * n, DVec2::ZERO);
        let (x2s, rest) = scratch.split_at_mut(n);
        let (w1s, centres) = rest.split_at_mut(n);
        for (i, (x2, w1)) in x2s.iter_mut().zip(w1s.iter_mut()).enumerate() {
            (*x2, *w1) = ray(i);
        }
        lcd_pixels(self.display, &self.indexer, x2s, w1s, centres, out);
    }
}

/// The last steps of eq. (1) for a batch of rays, from where each meets the lenslet plane
/// (`x2`) with its slope there (`w1`): the nearest lenslet's centre, the refracted slope, the LCD
/// pixel (`u32::MAX`: off the LCD). Each a pass over the batch that vectorises, with the
/// arithmetic of [`FastTransfer::lcd_point`] per ray. `centres` is scratch of the batch's size.
pub fn lcd_pixels(
    display: &Display,
    indexer: &PixelIndexer,
    x2: &[DVec2],
    w1: &[DVec2],
    centres: &mut [DVec2],
    out: &mut [u32],
) {
    debug_assert!(x2.len() == w1.len() && x2.len() == centres.len() && x2.len() == out.len());
    centres.copy_from_slice(x2);
    display.lenslets.nearest_centers(centres);
    let (power, v2) = (display.lenslet_power(), display.lenslets_to_lcd);
    for (((o, x2), c), w1) in out.iter_mut().zip(x2).zip(centres.iter()).zip(w1) {
        let w2 = *w1 - (*x2 - *c) * power;
        *o = indexer.index_u32(*x2 + w2 * v2);
    }
}

/// The ray into the scene that leaves the eye lens for retina direction `tangent` through pupil
/// offset `pupil_offset`.
#[inline]
pub fn eye_scene_ray(eye: &Eye, tangent: DVec2, pupil_offset: DVec2) -> Ray {
    let r = eye_ray(eye, tangent, pupil_offset);
    Ray { origin: (r.position + eye.position.truncate()).extend(eye.position.z), dir: r.slope.extend(1.0) }
}

/// The reverse trace: light leaving LCD point `lcd` through lenslet-plane point `lenslet_point`,
/// refracted by the lenslet nearest to that point, back through the eye lens to the retina.
/// Returns (pupil-plane ray after the eye lens, travelling toward +z, world x, y; retina point
/// relative to the eye's axis).
pub fn lcd_to_eye(display: &Display, eye: &Eye, lcd: DVec2, lenslet_point: DVec2) -> (PlaneRay, DVec2) {
    let w2 = (lcd - lenslet_point) / display.lenslets_to_lcd;
    let center = display.lenslets.center(display.lenslets.nearest(lenslet_point));
    let before = PlaneRay { position: lenslet_point, slope: w2 }.unrefract(center, display.lenslet_power());
    let at_pupil = before.propagate(-(display.lenslet_z() - eye.position.z));
    let local = PlaneRay { position: at_pupil.position - eye.position.truncate(), slope: at_pupil.slope };
    let w0 = local.unrefract(DVec2::ZERO, eye.power()).slope;
    let x0 = local.position - w0 * eye.retina_distance;
    (at_pupil, x0)
}

/// The eye-side camera ray for light leaving LCD point `lcd_point` through lenslet-plane point
/// `lenslet_point`, refracted by the lenslet centred at `lenslet_center`; it starts on the plane
/// `z = reference_z` and has unit z component.
#[inline]
pub fn camera_ray(
    display: &Display,
    lcd_point: DVec2,
    lenslet_center: DVec2,
    lenslet_point: DVec2,
    reference_z: f64,
) -> Ray {
    let w2 = (lcd_point - lenslet_point) / display.lenslets_to_lcd;
    let w1 = w2 + (lenslet_point - lenslet_center) * display.lenslet_power();
    let start = lenslet_point - w1 * (display.lenslet_z() - reference_z);
    Ray { origin: start.extend(reference_z), dir: w1.extend(1.0) }
}

/// PupilCenter's lenslet-plane point, in closed form. With `L = v1 - e_z` the distance from the
/// eye to the lenslets, the refracted ray through `p` reaches the eye plane at
/// `p - L ((x3 - p)/v2 + (p - xc)/f)`; setting that to the pupil centre `e` gives
/// `p (1/L + 1/v2 - 1/f) = e/L + x3/v2 - xc/f`.
#[inline]
pub fn pupil_center_point(display: &Display, lcd_point: DVec2, lenslet_center: DVec2, eye: DVec3) -> DVec2 {
    let l = display.lenslet_z() - eye.z;
    let denom = pupil_center_denominator(display, eye);
    (eye.truncate() / l + lcd_point / display.lenslets_to_lcd - lenslet_center * display.lenslet_power()) / denom
}

/// `1/L + 1/v2 - 1/f`: zero when the lenslet images the pupil centre onto the LCD.
pub fn pupil_center_denominator(display: &Display, eye: DVec3) -> f64 {
    1.0 / (display.lenslet_z() - eye.z) + 1.0 / display.lenslets_to_lcd - display.lenslet_power()
}

/// Relative size of `1/L + 1/v2 - 1/f` below which PupilCenter is refused as singular. The
/// solution `p` scales with the inverse of this quantity; at 1e-9 of the terms' magnitude the
/// cancellation has already lost nine of sixteen significant digits.
pub const PUPIL_CENTER_SINGULAR_TOLERANCE: f64 = 1e-9;

/// How far in front of the lenslet plane the eye's pupil must at least be, mm (1 um). An eye at
/// or beyond the lenslet plane sees nothing of the display (every image black, PSNR inf), and
/// nearer than this the pupil-to-lenslet distance in eq. (1) is no longer a physical one.
pub const MIN_EYE_TO_LENSLETS_MM: f64 = 1e-3;

/// Refuses an eye (pupil centre) at `eye_z` that is not at least [`MIN_EYE_TO_LENSLETS_MM`] in
/// front of `display`'s lenslet plane, naming `source` and `field`; every method and stage checks it.
pub fn check_eye_in_front(display: &Display, eye_z: f64, source: &str, field: &str) -> Result<()> {
    let lenslets = display.lenslet_z();
    let limit = lenslets - MIN_EYE_TO_LENSLETS_MM;
    if eye_z <= limit {
        return Ok(());
    }
    Err(Error::invalid(
        source,
        field,
        format!(
            "the eye at z = {eye_z} mm is at or beyond the lenslet plane (z = {lenslets} mm, eye_to_lenslets of the \
             display): it must be in front of it, at z <= {limit} mm"
        ),
    ))
}

/// Errors when PupilCenter has no answer for this display and eye position.
pub fn check_pupil_center(display: &Display, eye: DVec3) -> Result<()> {
    let l = display.lenslet_z() - eye.z;
    if l <= 0.0 || l.is_nan() {
        return Err(Error::Singular(format!(
            "PupilCenter needs the eye in front of the lenslets, but the eye is at z = {} and the lenslets at z = {}",
            eye.z,
            display.lenslet_z()
        )));
    }
    let scale = 1.0 / l + 1.0 / display.lenslets_to_lcd + display.lenslet_power();
    let denom = pupil_center_denominator(display, eye);
    if denom.abs() <= PUPIL_CENTER_SINGULAR_TOLERANCE * scale {
        return Err(Error::Singular(format!(
            "PupilCenter is undefined: the lenslets image the pupil centre onto the LCD \
             (1/L + 1/v2 - 1/f = {denom:.3e} with L = {l} mm, v2 = {} mm, f = {} mm), so every ray \
             through the pupil centre meets the LCD at one point per lenslet",
            display.lenslets_to_lcd, display.focal_length
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
