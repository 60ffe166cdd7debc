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
//!   centre, in closed form ([`pupil_center_point`]); the point may lie outside the lenslet's aperture (the lens is
//!   treated as extended), exactly as the closed form implies;
//! - LensletAverage (LA): `p` on a k x k grid of cell centres over the lenslet's pitch cell
//!   (paper: 5 x 5), averaged. With k = 1 this is exactly LC.
//!
//! The fourth method, Optimized (OPT), traces no camera rays of its own: its image is the
//! least-squares best over a set of eye states (`crate::optimize`, docs/OPTIMAL.md), started
//! from LA's, and `crate::methods` routes it; this renderer refuses it.
//!
//! The camera ray itself is eq. (1) and lives with it ([`camera_ray`]); the scene is read
//! through a [`RadianceField`]. A display with real lenslets renders through them
//! ([`super::display_thick`]).

use std::fmt;
use std::str::FromStr;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::field::{BundleSum, RadianceField, RayBundle, Sample};
use crate::error::{Error, Result};
use crate::optics::eye::stratified;
use crate::optics::transfer::{camera_ray, check_eye_in_front, check_pupil_center, pupil_center_point};
use crate::optics::Display;
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::ray::Ray;

/// A display-image rendering method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// LC: each pixel's ray through the centre of its lenslet.
    LensletCenter,
    /// PC: each pixel's ray through the point of its lenslet whose refracted ray passes through the
    /// pupil centre (the eye position the settings give).
    PupilCenter,
    /// LA: the mean of `grid` x `grid` rays over the lenslet's pitch cell.
    LensletAverage {
        /// k: samples per side of the lenslet cell (1 to 64; 1 is LC).
        grid: usize,
    },
    /// OPT: the display image that minimises the squared error of the perceived images over a
    /// set of eye states, within [0, 1] (`crate::optimize`; without an experiment's `[optimize]`
    /// table, the paper's four eye states).
    Optimized,
}

/// The paper's LensletAverage grid (Sec. 4.1: 5 x 5): what `LA` means without a `k`.
pub const PAPER_LA_GRID: usize = 5;

impl Method {
    /// The method's name in results, tables, file names and Python: "LC", "PC", "LA" for the
    /// paper's 5 x 5 LensletAverage and `LA<k>` for any other k x k grid ("LA3", "LA7"), so
    /// methods that differ have different names. It parses back to the same method.
    pub fn name(&self) -> String {
        match self {
            Method::LensletCenter => "LC".into(),
            Method::PupilCenter => "PC".into(),
            Method::LensletAverage { grid: PAPER_LA_GRID } => "LA".into(),
            Method::LensletAverage { grid } => format!("LA{grid}"),
            Method::Optimized => "OPT".into(),
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
            m => f.write_str(&m.name()),
        }
    }
}

impl FromStr for Method {
    type Err = String;
    /// "LC", "PC", "LA" (5 x 5), "LA3" / "LA:3" for a 3 x 3 grid, or "OPT"; case-insensitive. Also
    /// reads what `Display` writes ("LA (3x3)") and what [`Method::name`] writes.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let u = s.trim().to_ascii_uppercase();
        if let Some((a, b)) = u.strip_prefix("LA (").and_then(|r| r.strip_suffix(')')).and_then(|r| r.split_once('X')) {
            if a == b {
                return format!("LA{a}").parse();
            }
        }
        match u.as_str() {
            "LC" | "LENSLETCENTER" => Ok(Method::LensletCenter),
            "PC" | "PUPILCENTER" => Ok(Method::PupilCenter),
            "LA" | "LENSLETAVERAGE" => Ok(Method::LensletAverage { grid: PAPER_LA_GRID }),
            "OPT" | "OPTIMIZED" => Ok(Method::Optimized),
            _ => {
                let rest = u.strip_prefix("LA").map(|r| r.trim_start_matches([':', '-', '_']));
                match rest.and_then(|r| r.parse::<usize>().ok()) {
                    Some(k) if (1..=64).contains(&k) => Ok(Method::LensletAverage { grid: k }),
                    _ => Err(format!("unknown method `{s}`: expected LC, PC, LA, LA<k> with 1 <= k <= 64, or OPT")),
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
    let mut image = RgbImage::try_new(display.lcd.columns(), display.lcd.rows(), "the display image")?;
    let (depth, known) = render_into(display, method, settings, tracer, progress, &mut image.pixels, Vec::new())?;
    Ok((image, known.then_some(depth)))
}

/// [`render_display_image_with_depth`] into `image` (which must have the LCD's size) and `depth`
/// (resized to one value per LCD pixel): one pair of buffers can serve every method in turn.
/// Returns whether the depths are known (see [`render_display_image_with_depth`]).
pub fn render_display_image_into<R: RadianceField + ?Sized>(
    display: &Display,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
    image: &mut RgbImage,
    depth: &mut Vec<f32>,
) -> Result<bool> {
    let lcd = display.lcd;
    if image.width != lcd.columns() || image.height != lcd.rows() || image.pixels.len() != lcd.pixel_count() {
        return Err(Error::Mismatch(format!(
            "a {} x {} image cannot hold a display image of the display's {} x {} LCD",
            image.width,
            image.height,
            lcd.columns(),
            lcd.rows()
        )));
    }
    let (d, known) =
        render_into(display, method, settings, tracer, progress, &mut image.pixels, std::mem::take(depth))?;
    *depth = d;
    Ok(known)
}

/// The base camera ray (LC or PC, or LA's centre ray) of pixel sample `frac` of LCD pixel
/// (row, col): the one-ray twin of [`RowRays::find`].
#[inline(always)]
fn base_ray(display: &Display, method: Method, eye: DVec3, z_ref: f64, row: usize, col: usize, frac: DVec2) -> Ray {
    let lcd = display.lcd;
    let center = lcd.pixel_center(row, col);
    let lenslet_center = display.lenslets.center(display.elemental_image_of(center));
    let x3 = lcd.pixel_point(row, col, frac);
    let p = match method {
        Method::PupilCenter => pupil_center_point(display, x3, lenslet_center, eye),
        _ => lenslet_center,
    };
    camera_ray(display, x3, lenslet_center, p, z_ref)
}

/// One LCD row's base camera rays and their pixels' running sums (reused row after row).
#[derive(Default)]
struct RowRays {
    x3: Vec<DVec2>,
    lenslet_centers: Vec<DVec2>,
    rays: Vec<Ray>,
    sums: Vec<BundleSum>,
}

impl RowRays {
    /// `rays[col]` = [`base_ray`] of every pixel of the row, in passes over the row (the points
    /// on the LCD; their lenslets' centres, [`crate::optics::Lattice::nearest_centers_in`]; the
    /// rays), each a loop without data-dependent branches; the same arithmetic, so the same
    /// bits (tested).
    #[inline(always)]
    fn find(&mut self, display: &Display, method: Method, eye: DVec3, z_ref: f64, row: usize, frac: DVec2) {
        let (lcd, nx) = (display.lcd, display.lcd.columns());
        self.x3.clear();
        self.x3.extend((0..nx).map(|col| lcd.pixel_point(row, col, frac)));
        self.lenslet_centers.clear();
        self.lenslet_centers.extend((0..nx).map(|col| lcd.pixel_center(row, col)));
        display.elemental_images.nearest_centers_in(&display.lenslets, &mut self.lenslet_centers);
        self.rays.clear();
        let pairs = self.x3.iter().zip(&self.lenslet_centers);
        match method {
            Method::PupilCenter => self.rays.extend(
                pairs.map(|(&x3, &c)| camera_ray(display, x3, c, pupil_center_point(display, x3, c, eye), z_ref)),
            ),
            _ => self.rays.extend(pairs.map(|(&x3, &c)| camera_ray(display, x3, c, c, z_ref))),
        }
    }
}

/// The display image's pixel `i` (row-major) goes to `dst[i]`, its depth to `depth[i]` (`depth` is resized, every value written); returns `depth` and whether the
/// depths are known.
#[allow(clippy::too_many_arguments)]
fn render_into<R: RadianceField + ?Sized>(
    display: &Display,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
    dst: &mut [[f32; 3]],
    mut depth: Vec<f32>,
) -> Result<(Vec<f32>, bool)> {
    check_render_settings(display, method, settings)?;
    if let Some(lens) = display.thick_lenslet() {
        return super::display_thick::render_into(display, lens, method, settings, tracer, progress, dst, depth);
    }
    let (nx, ny) = (display.lcd.columns(), display.lcd.rows());
    let z_ref = settings.reference_plane_z;
    let bundle = lenslet_bundle(display, method, z_ref);
    let pixel_samples = stratified(settings.samples_per_pixel);
    let inv_count = 1.0 / (pixel_samples.len() * bundle.shifts.len()) as f64;
    let render = ParaxialRender { display, method, eye: settings.eye_position, z_ref, pixel_samples, bundle };
    debug_assert!(dst.len() == nx * ny);
    depth.resize(nx * ny, 0.0);
    let depth_known = std::sync::atomic::AtomicBool::new(true);
    let finish = |acc: BundleSum, px: &mut [f32; 3], z: &mut f32| {
        if !acc.depth_known {
            depth_known.store(false, std::sync::atomic::Ordering::Relaxed);
        }
        let v = acc.radiance * inv_count;
        *px = [v.x as f32, v.y as f32, v.z as f32];
        *z = if acc.hits > 0 { (acc.depth / acc.hits as f64) as f32 } else { f32::INFINITY };
    };
    if tracer.prefers_batches() {
        render.batched(tracer, progress, dst, &mut depth, &finish);
    } else {
        render.ray_by_ray(tracer, progress, dst, &mut depth, &finish);
    }
    // A cancelled render skipped rows: its image is not returned.
    progress.check()?;
    Ok((depth, depth_known.into_inner()))
}

/// Refuses what no method can render: OPT (solved, not traced), an eye behind the display, PC
/// with its pupil where eq. (1) has no solution, sample counts out of range.
fn check_render_settings(display: &Display, method: Method, settings: &DisplayRenderSettings) -> Result<()> {
    if method == Method::Optimized {
        // OPT traces no camera rays: its image is solved for (`crate::methods` routes it).
        return Err(Error::Mismatch(
            "OPT's display image is solved for, not traced: render it through inimtrace::methods".into(),
        ));
    }
    check_eye_in_front(display, settings.eye_position.z, "display render settings", "eye_position")?;
    if method == Method::PupilCenter && display.thick_lenslet().is_none() {
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
    Ok(())
}

/// The lenslet points of a pixel's camera rays as shifts of the LC ray: LA's samples p = c +
/// offset give camera rays that differ from the LC ray (p = c) by a constant start and slope
/// shift per offset (eq. (1b) is affine in p): slope += offset (1/f - 1/v2), start += offset
/// (1 - (1/f - 1/v2) L), L = v1 - z_ref. With a single offset of exactly zero (k = 1) the rays
/// are LC's, bit for bit; every other method has that one.
fn lenslet_bundle(display: &Display, method: Method, z_ref: f64) -> RayBundle {
    let gain = display.lenslet_power() - 1.0 / display.lenslets_to_lcd;
    let reach = display.lenslet_z() - z_ref;
    match method {
        Method::LensletAverage { grid } => {
            let offsets: Vec<DVec2> = stratified(grid)
                .into_iter()
                .map(|f| display.lenslets.reduced_matrix() * (f - DVec2::splat(0.5)))
                .collect();
            RayBundle::lenslet_points(&offsets, gain, reach)
        }
        _ => RayBundle::new(vec![(DVec2::ZERO, DVec2::ZERO)]),
    }
}

/// What a paraxial display image's rows share: the method's camera rays of every pixel sample
/// and lenslet point.
struct ParaxialRender<'a> {
    display: &'a Display,
    method: Method,
    eye: DVec3,
    z_ref: f64,
    pixel_samples: Vec<DVec2>,
    bundle: RayBundle,
}

impl ParaxialRender<'_> {
    /// Blocks of a row's pixels, ordered sample-major, so that packets see neighbouring rays.
    fn batched<R: RadianceField + ?Sized>(
        &self,
        tracer: &R,
        progress: &Progress,
        dst: &mut [[f32; 3]],
        depth: &mut [f32],
        finish: &(impl Fn(BundleSum, &mut [f32; 3], &mut f32) + Sync),
    ) {
        let nx = self.display.lcd.columns();
        let (pixel_samples, bundle) = (&self.pixel_samples, &self.bundle);
        let per_pixel = pixel_samples.len() * bundle.shifts.len();
        let base_ray = |row: usize, col: usize, frac: DVec2| {
            base_ray(self.display, self.method, self.eye, self.z_ref, row, col, frac)
        };
        dst.par_chunks_mut(nx).zip(depth.par_chunks_mut(nx)).enumerate().for_each(|(row, (out, zout))| {
            if progress.cancelled() {
                return;
            }
            let mut rays = Vec::with_capacity(per_pixel * BLOCK);
            let mut samples = Vec::with_capacity(per_pixel * BLOCK);
            for col0 in (0..nx).step_by(BLOCK) {
                let cols = BLOCK.min(nx - col0);
                // rays[s * cols + c]: sample s of pixel col0 + c, s = (pixel sample, lenslet shift).
                rays.clear();
                rays.resize(per_pixel * cols, Ray { origin: DVec3::ZERO, dir: DVec3::Z });
                for c in 0..cols {
                    for (f, frac) in pixel_samples.iter().enumerate() {
                        let base = base_ray(row, col0 + c, *frac);
                        for k in 0..bundle.shifts.len() {
                            rays[(f * bundle.shifts.len() + k) * cols + c] = bundle.ray(&base, k);
                        }
                    }
                }
                samples.clear();
                samples.resize(rays.len(), Sample::default());
                tracer.sample_many(&rays, &mut samples);
                let block = out[col0..col0 + cols].iter_mut().zip(zout[col0..col0 + cols].iter_mut());
                for (c, (px, z)) in block.enumerate() {
                    let mut acc = BundleSum::default();
                    for f in 0..pixel_samples.len() {
                        let mut part = BundleSum::default();
                        for k in 0..bundle.shifts.len() {
                            part.add(samples[(f * bundle.shifts.len() + k) * cols + c]);
                        }
                        acc.merge(part);
                    }
                    finish(acc, px, z);
                }
            }
            progress.inc(1);
        });
    }

    /// Ray by ray; each pixel sample's lenslet rays go to the field as one bundle, which fast
    /// fields cull as a whole. A row's base rays are found in passes over the row
    /// ([`RowRays::find`]); every pixel sums its samples in the same order as the batched path.
    fn ray_by_ray<R: RadianceField + ?Sized>(
        &self,
        tracer: &R,
        progress: &Progress,
        dst: &mut [[f32; 3]],
        depth: &mut [f32],
        finish: &(impl Fn(BundleSum, &mut [f32; 3], &mut f32) + Sync),
    ) {
        let nx = self.display.lcd.columns();
        let bundle = &self.bundle;
        let single = bundle.shifts.len() == 1;
        dst.par_chunks_mut(nx).zip(depth.par_chunks_mut(nx)).enumerate().for_each_init(
            RowRays::default,
            |s, (row, (out, zout))| {
                if progress.cancelled() {
                    return;
                }
                s.sums.clear();
                s.sums.resize(nx, BundleSum::default());
                for frac in &self.pixel_samples {
                    s.find(self.display, self.method, self.eye, self.z_ref, row, *frac);
                    for (acc, base) in s.sums.iter_mut().zip(&s.rays) {
                        let part = if single {
                            let mut one = BundleSum::default();
                            one.add(tracer.sample(&bundle.ray(base, 0)));
                            one
                        } else {
                            tracer.sample_sum(base, bundle)
                        };
                        acc.merge(part);
                    }
                }
                for ((acc, px), z) in s.sums.iter().zip(out.iter_mut()).zip(zout.iter_mut()) {
                    finish(*acc, px, z);
                }
                progress.inc(1);
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use glam::DMat2;

    use super::*;
    use crate::optics::Lattice;

    #[test]
    fn method_names_keep_the_grid_and_parse_back() {
        let la = |grid| Method::LensletAverage { grid };
        assert_eq!(la(PAPER_LA_GRID).name(), "LA");
        assert_eq!(la(3).name(), "LA3");
        assert_eq!(la(7).name(), "LA7");
        assert_eq!(la(1).name(), "LA1");
        assert_eq!(Method::LensletCenter.name(), "LC");
        assert_eq!(Method::PupilCenter.name(), "PC");
        assert_eq!(Method::Optimized.name(), "OPT");
        assert_eq!("opt".parse::<Method>(), Ok(Method::Optimized));
        for m in [Method::LensletCenter, Method::PupilCenter, Method::Optimized].into_iter().chain((1..=64).map(la)) {
            assert_eq!(m.name().parse::<Method>(), Ok(m), "{}", m.name());
            assert_eq!(m.to_string().parse::<Method>(), Ok(m), "{m}");
        }
        assert_eq!("la3".parse::<Method>(), Ok(la(3)));
        assert_eq!("LA:3".parse::<Method>(), Ok(la(3)));
        assert_eq!("LA5".parse::<Method>(), Ok(la(5)));
        assert!("LA0".parse::<Method>().is_err());
        assert!("LA65".parse::<Method>().is_err());
    }

    #[test]
    fn a_rows_base_rays_are_the_single_pixel_rays_bit_for_bit() {
        let paper = Display::paper();
        let mut odd = Display::paper();
        // Tilted lenslets over hexagonal elemental images: the batch's fallback loop.
        odd.lenslets =
            Lattice::new(DVec2::new(0.05, -0.02), DMat2::from_angle(0.3) * DMat2::from_diagonal(DVec2::splat(1.1)))
                .unwrap();
        odd.elemental_images =
            Lattice::new(DVec2::new(-0.01, 0.03), DMat2::from_cols(DVec2::new(1.5, 0.0), DVec2::new(0.75, 1.3)))
                .unwrap();
        let mut s = RowRays::default();
        for display in [paper, odd] {
            let rows = display.lcd.rows();
            for method in [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 5 }] {
                for (eye, z_ref) in [(DVec3::ZERO, 0.0), (DVec3::new(0.7, -1.1, 2.0), 5.0)] {
                    for frac in [DVec2::splat(0.5), DVec2::new(0.125, 0.875)] {
                        for row in [0, 1, rows / 3, rows / 2, rows - 1] {
                            s.find(&display, method, eye, z_ref, row, frac);
                            assert_eq!(s.rays.len(), display.lcd.columns());
                            for (col, ray) in s.rays.iter().enumerate() {
                                let want = base_ray(&display, method, eye, z_ref, row, col, frac);
                                let bits = |r: &Ray| {
                                    (r.origin.to_array().map(f64::to_bits), r.dir.to_array().map(f64::to_bits))
                                };
                                assert_eq!(bits(ray), bits(&want), "{method} row {row} col {col}");
                            }
                        }
                    }
                }
            }
        }
    }
}
