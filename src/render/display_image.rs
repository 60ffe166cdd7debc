//! Display-image rendering (paper Sec. 3, Fig. 2b-d): one colour per LCD pixel from camera rays
//! traced into the scene.
//!
//! Every camera ray is the eye-side line of the light that leaves the pixel, crosses the lenslet
//! plane at a point `p` and refracts there (eq. (1b) run backwards); it starts on a reference
//! plane (the pupil plane `z = 0` by default, the paper's "near-clip plane" analogue) and is
//! traced toward +z. The pixel's lenslet is the lenslet of its elemental image (the EI whose
//! centre is nearest to the pixel centre). The methods differ in the choice of `p`:
//!
//! - LensletCenter (LC): `p` is the lenslet centre (a pinhole array);
//! - PupilCenter (PC): `p` is chosen so that the refracted ray passes through the eye's pupil
//!   centre; closed form below; the point may lie outside the lenslet's aperture (the lens is
//!   treated as extended), exactly as the closed form implies;
//! - LensletAverage (LA): `p` on a k x k grid of cell centres over the lenslet's pitch cell
//!   (paper: 5 x 5), averaged. With k = 1 this is exactly LC.

use std::fmt;
use std::str::FromStr;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::accel::{Intersector, Ray};
use crate::error::{Error, Result};
use crate::optics::eye::stratified;
use crate::optics::Display;
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::scene::Scene;

/// A display-image rendering method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    LensletCenter,
    PupilCenter,
    /// `grid` x `grid` samples over the lenslet's pitch cell.
    LensletAverage {
        grid: usize,
    },
}

impl Method {
    /// The paper's abbreviation, used in file names: "LC", "PC", "LA".
    pub fn short_name(&self) -> &'static str {
        match self {
            Method::LensletCenter => "LC",
            Method::PupilCenter => "PC",
            Method::LensletAverage { .. } => "LA",
        }
    }

    /// Lenslet-plane samples per display-pixel sample.
    pub fn lenslet_samples(&self) -> usize {
        match self {
            Method::LensletAverage { grid } => grid * grid,
            _ => 1,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::LensletAverage { grid } => write!(f, "LA ({grid}x{grid})"),
            m => f.write_str(m.short_name()),
        }
    }
}

impl FromStr for Method {
    type Err = String;
    /// "LC", "PC", "LA" (5 x 5) or "LA3" / "LA:3" for a 3 x 3 grid; case-insensitive.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let u = s.trim().to_ascii_uppercase();
        match u.as_str() {
            "LC" | "LENSLETCENTER" => Ok(Method::LensletCenter),
            "PC" | "PUPILCENTER" => Ok(Method::PupilCenter),
            "LA" | "LENSLETAVERAGE" => Ok(Method::LensletAverage { grid: 5 }),
            _ => {
                let rest = u.strip_prefix("LA").map(|r| r.trim_start_matches([':', '-', '_']));
                match rest.and_then(|r| r.parse::<usize>().ok()) {
                    Some(k) if (1..=64).contains(&k) => Ok(Method::LensletAverage { grid: k }),
                    _ => Err(format!("unknown method `{s}`: expected LC, PC, LA or LA<k> with 1 <= k <= 64")),
                }
            }
        }
    }
}

/// Settings shared by all methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayRenderSettings {
    /// k: k x k stratified samples per display pixel (1 = the pixel centre).
    pub samples_per_pixel: usize,
    /// z of the plane camera rays start on (0 = the pupil plane).
    pub reference_plane_z: f64,
    /// The eye's pupil centre, used by PupilCenter.
    pub eye_position: DVec3,
}

impl Default for DisplayRenderSettings {
    fn default() -> Self {
        Self { samples_per_pixel: 1, reference_plane_z: 0.0, eye_position: DVec3::ZERO }
    }
}

/// A scene and the backend that intersects it. Generic so that hot loops inline a concrete
/// backend; `SceneTracer<'_, dyn Intersector>` works for any backend chosen at run time.
pub struct SceneTracer<'a, I: Intersector + ?Sized = dyn Intersector> {
    pub scene: &'a Scene,
    pub backend: &'a I,
}

impl<I: Intersector + ?Sized> Clone for SceneTracer<'_, I> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<I: Intersector + ?Sized> Copy for SceneTracer<'_, I> {}

/// What one ray sees: its radiance and the distance to what it hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub radiance: DVec3,
    /// World distance (mm) from the ray's origin to its hit along the ray; `+inf` for a miss;
    /// NaN when the field does not know (fields that only implement `radiance`).
    pub depth: f64,
}

impl Default for Sample {
    fn default() -> Self {
        Sample { radiance: DVec3::ZERO, depth: f64::NAN }
    }
}

/// Anything that tells the radiance seen along a ray: a scene with an intersection backend, or
/// a fused fast kernel for a special kind of scene.
///
/// Renderers hand rays over in batches ([`RadianceField::sample_many`]) laid out so that
/// consecutive rays are neighbours (adjacent pixels, same sub-sample), which lets mesh backends
/// trace them as packets. The defaults fall back to one ray at a time.
pub trait RadianceField: Sync {
    fn radiance(&self, ray: &Ray) -> DVec3;

    /// Radiance and hit distance. Default: the depth is unknown (NaN).
    fn sample(&self, ray: &Ray) -> Sample {
        Sample { radiance: self.radiance(ray), depth: f64::NAN }
    }

    /// Whether [`RadianceField::sample_many`] gains from long batches of neighbouring rays
    /// (packets). Renderers then trace blocks of pixels at once; otherwise pixel by pixel,
    /// which is cheaper for fields whose per-ray cost is tiny. Same results either way.
    fn prefers_batches(&self) -> bool {
        false
    }

    /// [`RadianceField::sample`] of every ray (`out.len() == rays.len()`).
    fn sample_many(&self, rays: &[Ray], out: &mut [Sample]) {
        for (ray, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.sample(ray);
        }
    }
}

/// World distance of a hit at ray parameter `t` (`+inf` for a miss).
#[inline]
fn hit_distance(ray: &Ray, t: Option<f64>) -> f64 {
    t.map_or(f64::INFINITY, |t| t * ray.dir.length())
}

impl<I: Intersector + ?Sized> RadianceField for SceneTracer<'_, I> {
    #[inline]
    fn radiance(&self, ray: &Ray) -> DVec3 {
        self.scene.shade(ray, self.backend.intersect(ray, f64::INFINITY).as_ref(), self.backend)
    }

    #[inline]
    fn sample(&self, ray: &Ray) -> Sample {
        let hit = self.backend.intersect(ray, f64::INFINITY);
        Sample {
            radiance: self.scene.shade(ray, hit.as_ref(), self.backend),
            depth: hit_distance(ray, hit.map(|h| h.t)),
        }
    }

    fn prefers_batches(&self) -> bool {
        self.backend.prefers_batches()
    }

    /// Intersects the whole batch with [`Intersector::intersect_many`] (packets on coherent
    /// runs for backends that have them), then shades.
    fn sample_many(&self, rays: &[Ray], out: &mut [Sample]) {
        // Chunks of 256 (a multiple of the 16-ray packet) with the hits on the stack.
        const CHUNK: usize = 256;
        let mut hits = [None; CHUNK];
        for (rays, out) in rays.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let hits = &mut hits[..rays.len()];
            self.backend.intersect_many(rays, hits);
            for ((ray, hit), o) in rays.iter().zip(hits.iter()).zip(out.iter_mut()) {
                *o = Sample {
                    radiance: self.scene.shade(ray, hit.as_ref(), self.backend),
                    depth: hit_distance(ray, hit.map(|h| h.t)),
                };
            }
        }
    }
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

/// Errors when PupilCenter has no answer for this display and eye position.
pub fn check_pupil_center(display: &Display, eye: DVec3) -> Result<()> {
    let l = display.lenslet_z() - eye.z;
    if !(l > 0.0) {
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

/// Pixels of one display row traced as one batch (for fields that prefer batches): enough for
/// long coherent runs (packets of 16), small enough that a batch's rays stay in cache.
const BLOCK: usize = 128;

/// Renders the display image for `method`. Every pixel is finite; rays that hit nothing carry
/// the scene's background.
pub fn render_display_image<R: RadianceField + ?Sized>(
    display: &Display,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
) -> Result<RgbImage> {
    render_display_image_with_depth(display, method, settings, tracer, progress).map(|(img, _)| img)
}

/// [`render_display_image`] plus a depth plane (row-major, one `f32` per LCD pixel): the mean
/// world distance (mm, along each camera ray from its start on the reference plane) over the
/// pixel's rays that hit something, `+inf` when none did. For LC and PC with one sample per
/// pixel that is the distance of the pixel's one ray; for LA and multi-sample pixels it is the
/// mean over the hitting rays (misses do not count). `None` when the field does not know
/// depths (fields that only implement `radiance`, such as the fused planar kernel).
///
/// Rays are traced in blocks of a display row's pixels through [`RadianceField::sample_many`],
/// ordered sub-sample by sub-sample with the block's pixels consecutive (coherent runs for packets);
/// every pixel still sums its samples in the same order as a per-pixel loop would.
pub fn render_display_image_with_depth<R: RadianceField + ?Sized>(
    display: &Display,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
) -> Result<(RgbImage, Option<Vec<f32>>)> {
    if method == Method::PupilCenter {
        check_pupil_center(display, settings.eye_position)?;
    }
    if settings.samples_per_pixel == 0 || settings.samples_per_pixel > 64 {
        return Err(Error::invalid("display render settings", "samples_per_pixel", "must be between 1 and 64"));
    }
    if let Method::LensletAverage { grid } = method {
        if grid == 0 || grid > 64 {
            return Err(Error::invalid(
                "display render settings",
                "la_grid",
                format!("must be between 1 and 64, got {grid}"),
            ));
        }
    }
    let lcd = display.lcd;
    let (nx, ny) = (lcd.columns(), lcd.rows());
    let pixel_samples = stratified(settings.samples_per_pixel);
    // LA's samples p = c + offset give camera rays that differ from the LC ray (p = c) by a
    // constant start and slope shift per offset (eq. (1b) is affine in p):
    // slope += offset (1/f - 1/v2), start += offset (1 - (1/f - 1/v2) L), L = v1 - z_ref.
    // With a single offset of exactly zero (k = 1) the rays are LC's, bit for bit.
    let z_ref = settings.reference_plane_z;
    let gain = display.lenslet_power() - 1.0 / display.lenslets_to_lcd;
    let reach = display.lenslet_z() - z_ref;
    let lenslet_shifts: Vec<(DVec2, DVec2)> = match method {
        Method::LensletAverage { grid } => stratified(grid)
            .into_iter()
            .map(|f| {
                let off = display.lenslets.matrix * (f - DVec2::splat(0.5));
                (off - off * gain * reach, off * gain)
            })
            .collect(),
        _ => vec![(DVec2::ZERO, DVec2::ZERO)],
    };
    let eye = settings.eye_position;
    let inv_count = 1.0 / (pixel_samples.len() * lenslet_shifts.len()) as f64;

    let per_pixel = pixel_samples.len() * lenslet_shifts.len();
    let mut image = RgbImage::new(nx, ny);
    let mut depth = vec![0f32; nx * ny];
    let depth_known = std::sync::atomic::AtomicBool::new(true);
    let block = if tracer.prefers_batches() { BLOCK } else { 1 };
    image.pixels.par_chunks_mut(nx).zip(depth.par_chunks_mut(nx)).enumerate().for_each(|(row, (out, zout))| {
        let mut rays = Vec::with_capacity(per_pixel * block);
        let mut samples = Vec::with_capacity(per_pixel * block);
        for col0 in (0..nx).step_by(block) {
            let cols = block.min(nx - col0);
            // rays[s * cols + c]: sample s of pixel col0 + c, s = (pixel sample, lenslet shift).
            rays.clear();
            rays.resize(per_pixel * cols, Ray { origin: DVec3::ZERO, dir: DVec3::Z });
            for c in 0..cols {
                let col = col0 + c;
                let center = lcd.pixel_center(row, col);
                let lenslet_center = display.lenslets.center(display.elemental_image_of(center));
                for (f, frac) in pixel_samples.iter().enumerate() {
                    let x3 = lcd.pixel_point(row, col, *frac);
                    let p = match method {
                        Method::PupilCenter => pupil_center_point(display, x3, lenslet_center, eye),
                        _ => lenslet_center,
                    };
                    let base = camera_ray(display, x3, lenslet_center, p, z_ref);
                    let (start, slope) = (base.origin.truncate(), base.dir.truncate());
                    for (k, (d_start, d_slope)) in lenslet_shifts.iter().enumerate() {
                        let s = f * lenslet_shifts.len() + k;
                        rays[s * cols + c] =
                            Ray { origin: (start + *d_start).extend(z_ref), dir: (slope + *d_slope).extend(1.0) };
                    }
                }
            }
            samples.clear();
            samples.resize(rays.len(), Sample::default());
            tracer.sample_many(&rays, &mut samples);
            let block = out[col0..col0 + cols].iter_mut().zip(zout[col0..col0 + cols].iter_mut());
            for (c, (px, z)) in block.enumerate() {
                let mut sum = DVec3::ZERO;
                let (mut zsum, mut hits) = (0.0, 0usize);
                for s in 0..per_pixel {
                    let sample = &samples[s * cols + c];
                    sum += sample.radiance;
                    if sample.depth.is_finite() {
                        zsum += sample.depth;
                        hits += 1;
                    } else if sample.depth.is_nan() {
                        depth_known.store(false, std::sync::atomic::Ordering::Relaxed);
                    }
                }
                let v = sum * inv_count;
                *px = [v.x as f32, v.y as f32, v.z as f32];
                *z = if hits > 0 { (zsum / hits as f64) as f32 } else { f32::INFINITY };
            }
        }
        progress.inc(1);
    });
    let depth = depth_known.into_inner().then_some(depth);
    Ok((image, depth))
}
