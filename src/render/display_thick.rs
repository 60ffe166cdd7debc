//! Display images for real (thick) lenslets (paper Sec. 3 with the display's own optics): each
//! method's camera rays go through the same real lenslet the eye looks through
//! ([`ThickLenslet::camera_ray`]), each colour channel at its primary's median wavelength, so
//! each method renders for the optics the display has.
//!
//! - LC: the ray from the LCD point through the lenslet's centre on its back vertex plane;
//! - PC: the point of the back vertex plane whose ray reaches the pupil centre, by Newton's
//!   method ([`ThickLenslet::pupil_center_point`]) from the thin lens's closed form; where the
//!   real lenslet sends no light from the pixel to the pupil centre (the point would lie where
//!   the rays are totally reflected or miss the lens: from the pupil centre a lenslet shows only
//!   the middle of its elemental image, the paper display's real lenslets about a tenth of its
//!   pixels), the ray through the pupil centre of the lens's paraxial equivalent, its principal
//!   planes extended as eq. (1b) extends the thin lens
//!   ([`ThickLenslet::paraxial_pupil_center_ray`]; LC's ray only where that is singular). LC's
//!   ray there would make PC show LC's light field on most pixels, and give LC's focus cues
//!   (docs/OPTICS.md);
//! - LA: the k x k cell-centre points of the lenslet's pitch cell on the back vertex plane.
//!
//! The pixel's lenslet is its elemental image's, treated as extended (as eq. (1b) does). A ray
//! the lenslet blocks (total internal reflection, a missed surface) brings black and no depth.
//! There are no ray families (the real lens is not affine in the lenslet point), but every
//! lenslet is the same lens: when the lenslet pitch is a whole number of LCD pixels, LC's and LA's
//! rays are traced once per place relative to the lenslet and moved to each lenslet
//! ([`Sharing::Shared`], [`lattice_period`]); [`Sharing::PerPixel`] is the slow twin. A pixel's
//! rays go through the lens side by side ([`ThickLenslet::camera_rays_into`]; PupilCenter's three
//! channels' Newton solves in lockstep, [`ThickLenslet::pupil_center_rays`]), bit for bit the
//! one-ray traces.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::display_image::{DisplayRenderSettings, Method};
use super::field::{BundleSum, RadianceField, Sample};
use crate::error::Result;
use crate::optics::eye::stratified;
use crate::optics::lenslet::ThickLenslet;
use crate::optics::transfer::pupil_center_point;
use crate::optics::Display;
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::ray::Ray;

/// How LC's and LA's camera rays are traced: once per pixel, or shared between the pixels that
/// sit at the same place relative to their lenslets ([`lattice_period`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sharing {
    /// Every pixel traces its own rays through its lenslet, one ray at a time (the slow twin).
    PerPixel,
    /// Pixels at the same place relative to their lenslets share one trace, moved to each
    /// lenslet, when the lattices allow it ([`lattice_period`]); otherwise per pixel. A pixel's
    /// rays (and PupilCenter's three channels' Newton solves) are traced side by side
    /// (`optics::lenslet_lanes`, the same rays bit for bit).
    Shared,
}

/// The lenslet pitch in whole LCD pixels `(mx, my)`, when the lenslet lattice is axis-aligned
/// (a diagonal pitch matrix) and each pitch is a whole number of pixels (to 1e-9 pixel). Then
/// pixel (row, col) of lenslet (i, j) lies at the same place relative to its lenslet's centre as
/// pixel (row + my j, col - mx i) would relative to lenslet (0, 0): every pixel with the same
/// key `(col - mx i, row + my j)` has the same LCD points relative to its lenslet (exactly, up
/// to rounding) and so, the lenslet being the same lens everywhere, the same camera rays shifted
/// by its lenslet's centre.
pub fn lattice_period(display: &Display) -> Option<(i64, i64)> {
    let m = display.lenslets.matrix;
    if m.x_axis.y != 0.0 || m.y_axis.x != 0.0 {
        return None;
    }
    let w = display.lcd.pixel_pitch();
    let whole = |v: f64| (v.is_finite() && v.round() != 0.0 && (v - v.round()).abs() < 1e-9).then(|| v.round() as i64);
    Some((whole(m.x_axis.x / w.x)?, whole(m.y_axis.y / w.y)?))
}

/// What every pixel's trace needs.
struct Setup<'a> {
    display: &'a Display,
    lens: &'a ThickLenslet,
    method: Method,
    pixel_samples: Vec<DVec2>,
    offsets: Vec<DVec2>,
    /// The material's index at each channel's wavelength.
    index: [f64; 3],
    front_z: f64,
    lcd_z: f64,
    z_ref: f64,
    eye: DVec3,
    /// `PerPixel`: every ray traced on its own as well (the slow twin of the lanes).
    sharing: Sharing,
}

impl Setup<'_> {
    /// LC's and LA's rays of pixel (row, col) whose lenslet is centred at `center`, in the order
    /// (pixel sample, channel, lenslet point), appended to `out`; `local`: traced in the
    /// lenslet's frame (LCD point and lenslet point relative to `center`, ray starts relative to
    /// it), else in the world.
    fn push_rays(&self, row: usize, col: usize, center: DVec2, local: bool, out: &mut Vec<Option<Ray>>) {
        let c = if local { DVec2::ZERO } else { center };
        // Every lenslet point at every channel's index, traced side by side.
        let ps: Vec<DVec2> = self.index.iter().flat_map(|_| self.offsets.iter().map(|o| c + *o)).collect();
        let ns: Vec<f64> = self.index.iter().flat_map(|&n| self.offsets.iter().map(move |_| n)).collect();
        for frac in &self.pixel_samples {
            let x3 = self.display.lcd.pixel_point(row, col, *frac) - (center - c);
            let at = out.len();
            out.resize(at + ps.len(), None);
            self.lens.camera_rays_into(c, self.front_z, self.lcd_z, x3, &ps, &ns, self.z_ref, &mut out[at..]);
        }
    }

    /// [`Setup::push_rays`] one ray at a time (the slow twin of its lanes; tested).
    fn push_rays_each(&self, row: usize, col: usize, center: DVec2, local: bool, out: &mut Vec<Option<Ray>>) {
        let c = if local { DVec2::ZERO } else { center };
        for frac in &self.pixel_samples {
            let x3 = self.display.lcd.pixel_point(row, col, *frac) - (center - c);
            for &n in &self.index {
                for o in &self.offsets {
                    out.push(self.lens.camera_ray_in(c, self.front_z, self.lcd_z, x3, c + *o, self.z_ref, n));
                }
            }
        }
    }

    /// The sums over `rays` (in [`Setup::push_rays`]'s order, shifted by `shift`), each ray
    /// bringing back its own channel.
    fn sum<R: RadianceField + ?Sized>(&self, rays: &[Option<Ray>], shift: DVec2, tracer: &R) -> BundleSum {
        let mut acc = BundleSum::default();
        let per_channel = self.offsets.len();
        for (k, ray) in rays.iter().enumerate() {
            let c = (k / per_channel) % 3;
            let s = match ray {
                Some(r) => tracer.sample(&Ray { origin: r.origin + shift.extend(0.0), dir: r.dir }),
                None => Sample { radiance: DVec3::ZERO, depth: f64::INFINITY },
            };
            let mut one = DVec3::ZERO;
            one[c] = s.radiance[c];
            acc.add(Sample { radiance: one, depth: s.depth });
        }
        acc
    }

    /// One pixel traced on its own (every method).
    fn pixel<R: RadianceField + ?Sized>(&self, row: usize, col: usize, center: DVec2, tracer: &R) -> BundleSum {
        if self.method != Method::PupilCenter {
            let mut rays = Vec::with_capacity(self.pixel_samples.len() * 3 * self.offsets.len());
            if self.sharing == Sharing::PerPixel {
                self.push_rays_each(row, col, center, false, &mut rays);
            } else {
                self.push_rays(row, col, center, false, &mut rays);
            }
            return self.sum(&rays, DVec2::ZERO, tracer);
        }
        let mut rays = Vec::with_capacity(self.pixel_samples.len() * 3);
        for frac in &self.pixel_samples {
            let x3 = self.display.lcd.pixel_point(row, col, *frac);
            let guess = pupil_center_point(self.display, x3, center, self.eye);
            if self.sharing == Sharing::PerPixel {
                self.pupil_center_each(x3, center, guess, &mut rays);
                continue;
            }
            // The three channels' solves in lockstep; the rays still to trace (LC's where a
            // solve fails, the solved point's from the reference plane) side by side.
            let solved = self.lens.pupil_center_rays(center, self.front_z, self.lcd_z, x3, self.eye, guess, self.index);
            let mut out = [None; 3];
            let (mut ps, mut ns, mut which) = ([DVec2::ZERO; 3], [0.0; 3], [0usize; 3]);
            let mut m = 0;
            for (c, s) in solved.into_iter().enumerate() {
                let p = match s {
                    Some((_, ray)) if self.z_ref == self.eye.z => {
                        out[c] = Some(ray);
                        continue;
                    }
                    Some((p, _)) => p,
                    None => match self.paraxial_ray(x3, center, self.index[c]) {
                        Some(ray) => {
                            out[c] = Some(ray);
                            continue;
                        }
                        None => center,
                    },
                };
                (ps[m], ns[m], which[m]) = (p, self.index[c], c);
                m += 1;
            }
            let mut traced = [None; 3];
            self.lens.camera_rays_into(
                center,
                self.front_z,
                self.lcd_z,
                x3,
                &ps[..m],
                &ns[..m],
                self.z_ref,
                &mut traced[..m],
            );
            for (j, &c) in which[..m].iter().enumerate() {
                out[c] = traced[j];
            }
            rays.extend(out);
        }
        self.sum(&rays, DVec2::ZERO, tracer)
    }

    /// PupilCenter's rays of one pixel sample, channel by channel and ray by ray (the slow twin
    /// of the lockstep solves).
    fn pupil_center_each(&self, x3: DVec2, center: DVec2, guess: DVec2, rays: &mut Vec<Option<Ray>>) {
        for &n in &self.index {
            let solved = self.lens.pupil_center_ray(center, self.front_z, self.lcd_z, x3, self.eye, guess, n);
            // The solve's own ray when it starts on the reference plane, else traced anew.
            rays.push(match solved {
                Some((_, ray)) if self.z_ref == self.eye.z => Some(ray),
                Some((p, _)) => self.lens.camera_ray_in(center, self.front_z, self.lcd_z, x3, p, self.z_ref, n),
                None => self
                    .paraxial_ray(x3, center, n)
                    .or_else(|| self.lens.camera_ray_in(center, self.front_z, self.lcd_z, x3, center, self.z_ref, n)),
            });
        }
    }

    /// PupilCenter's ray of the lens's paraxial equivalent (where the real lens sends no light
    /// from the pixel to the pupil centre).
    fn paraxial_ray(&self, x3: DVec2, center: DVec2, n: f64) -> Option<Ray> {
        self.lens.paraxial_pupil_center_ray(center, self.front_z, self.lcd_z, x3, self.eye, self.z_ref, n)
    }
}

/// One LCD row's colours and depths.
type RowOut<'a> = (&'a mut [[f32; 3]], &'a mut [f32]);

/// Writes a pixel's sums into its colour and depth.
#[inline]
fn store(acc: &BundleSum, inv_count: f64, px: &mut [f32; 3], z: &mut f32) {
    let v = acc.radiance * inv_count;
    *px = [v.x as f32, v.y as f32, v.z as f32];
    *z = if acc.hits > 0 { (acc.depth / acc.hits as f64) as f32 } else { f32::INFINITY };
}

/// Renders `method`'s display image through `lens` into `dst` (row-major), its depths into
/// `depth`; returns `depth` and whether the depths are known.
#[allow(clippy::too_many_arguments)]
pub(super) fn render_into<R: RadianceField + ?Sized>(
    display: &Display,
    lens: &ThickLenslet,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
    dst: &mut [[f32; 3]],
    depth: Vec<f32>,
) -> Result<(Vec<f32>, bool)> {
    render_into_with(display, lens, method, settings, tracer, progress, dst, depth, Sharing::Shared)
}

/// [`render_into`] with the choice of [`Sharing`].
#[allow(clippy::too_many_arguments)]
fn render_into_with<R: RadianceField + ?Sized>(
    display: &Display,
    lens: &ThickLenslet,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
    dst: &mut [[f32; 3]],
    mut depth: Vec<f32>,
    sharing: Sharing,
) -> Result<(Vec<f32>, bool)> {
    let lcd = display.lcd;
    let (nx, ny) = (lcd.columns(), lcd.rows());
    let setup = Setup {
        display,
        lens,
        method,
        pixel_samples: stratified(settings.samples_per_pixel),
        offsets: match method {
            Method::LensletAverage { grid } => stratified(grid)
                .into_iter()
                .map(|f| display.lenslets.reduced_matrix() * (f - DVec2::splat(0.5)))
                .collect(),
            _ => vec![DVec2::ZERO],
        },
        index: display.channel_wavelengths().map(|nm| lens.material.index(nm)),
        front_z: display.lenslet_z(),
        lcd_z: display.lcd_z(),
        z_ref: settings.reference_plane_z,
        eye: settings.eye_position,
        sharing,
    };
    let inv_count = 1.0 / (setup.pixel_samples.len() * setup.offsets.len()) as f64;
    depth.resize(nx * ny, 0.0);
    let depth_known = std::sync::atomic::AtomicBool::new(true);
    let known = |acc: &BundleSum| {
        if !acc.depth_known {
            depth_known.store(false, std::sync::atomic::Ordering::Relaxed);
        }
    };
    let period = match (sharing, method) {
        (Sharing::Shared, Method::LensletCenter | Method::LensletAverage { .. }) => lattice_period(display),
        _ => None,
    };
    if let Some((mx, my)) = period {
        // Rows with the same key `row + my j` (j: the lenslet row of the row's first pixel) form
        // one task, which traces each key `col - mx i` once; a pixel in another lenslet row
        // than its row's first pixel is traced on its own.
        let row_cell: Vec<i32> = (0..ny).map(|r| display.elemental_image_of(lcd.pixel_center(r, 0)).y).collect();
        let mut groups: std::collections::BTreeMap<i64, Vec<usize>> = Default::default();
        for (r, &j) in row_cell.iter().enumerate() {
            groups.entry(r as i64 + my * i64::from(j)).or_default().push(r);
        }
        let mut rows: Vec<Option<RowOut<'_>>> = dst.chunks_mut(nx).zip(depth.chunks_mut(nx)).map(Some).collect();
        let tasks: Vec<Vec<(usize, RowOut<'_>)>> =
            groups.values().map(|rs| rs.iter().filter_map(|&r| rows[r].take().map(|out| (r, out))).collect()).collect();
        let per_pixel = setup.pixel_samples.len() * 3 * setup.offsets.len();
        tasks.into_par_iter().for_each(|group| {
            let mut table: rustc_hash::FxHashMap<i64, usize> = Default::default();
            let mut rays: Vec<Option<Ray>> = Vec::new();
            for (row, (out, zout)) in group {
                if progress.cancelled() {
                    return;
                }
                for (col, (px, z)) in out.iter_mut().zip(zout.iter_mut()).enumerate() {
                    let cell = display.elemental_image_of(lcd.pixel_center(row, col));
                    let center = display.lenslets.center(cell);
                    let acc = if cell.y == row_cell[row] {
                        let key = col as i64 - mx * i64::from(cell.x);
                        let start = *table.entry(key).or_insert_with(|| {
                            let start = rays.len();
                            setup.push_rays(row, col, center, true, &mut rays);
                            start
                        });
                        setup.sum(&rays[start..start + per_pixel], center, tracer)
                    } else {
                        setup.pixel(row, col, center, tracer)
                    };
                    known(&acc);
                    store(&acc, inv_count, px, z);
                }
                progress.inc(1);
            }
        });
    } else {
        dst.par_chunks_mut(nx).zip(depth.par_chunks_mut(nx)).enumerate().for_each(|(row, (out, zout))| {
            if progress.cancelled() {
                return;
            }
            for (col, (px, z)) in out.iter_mut().zip(zout.iter_mut()).enumerate() {
                let center = display.lenslets.center(display.elemental_image_of(lcd.pixel_center(row, col)));
                let acc = setup.pixel(row, col, center, tracer);
                known(&acc);
                store(&acc, inv_count, px, z);
            }
            progress.inc(1);
        });
    }
    progress.check()?;
    Ok((depth, depth_known.into_inner()))
}

/// A display image of `method` through `lens` (the one-image twin of the renderer's buffer form).
pub fn render<R: RadianceField + ?Sized>(
    display: &Display,
    lens: &ThickLenslet,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
) -> Result<RgbImage> {
    render_with(display, lens, method, settings, tracer, Sharing::Shared)
}

/// [`render`] with the choice of [`Sharing`] (`PerPixel`: the slow twin the tests compare with).
pub fn render_with<R: RadianceField + ?Sized>(
    display: &Display,
    lens: &ThickLenslet,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    sharing: Sharing,
) -> Result<RgbImage> {
    let mut image = RgbImage::new(display.lcd.columns(), display.lcd.rows());
    let hidden = Progress::hidden();
    render_into_with(display, lens, method, settings, tracer, &hidden, &mut image.pixels, Vec::new(), sharing)?;
    Ok(image)
}
