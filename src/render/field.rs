//! The radiance-field interface every renderer reads the scene through (paper Sec. 3.1: the
//! colour a camera ray brings back from the 3-D scene; Sec. 4.1: the same for the ground truth's
//! eye rays): [`RadianceField`], what one ray sees ([`Sample`]), and the bundles of rays that
//! LensletAverage traces per display pixel ([`RayBundle`], [`BundleSum`]). Implementations are
//! the generic [`super::tracer::SceneTracer`] and fused kernels such as
//! [`super::FacingPlanes`].

use glam::{DVec2, DVec3};

pub use crate::ray::AffineRays;
use crate::ray::Ray;

/// What one ray sees: its radiance and the distance to what it hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Linear RGB radiance.
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
    /// The linear RGB radiance along `ray`.
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

    /// The radiance that every ray of `rays` brings back, when the field can tell that it is one
    /// value for all of them (they all meet first the same part of the scene, of one colour),
    /// with the parameter `t` of that hit (`None`: every ray misses). It must then be exactly
    /// what [`RadianceField::sample`] returns for each ray; `None` when the field cannot tell
    /// (the default).
    fn uniform(&self, rays: &AffineRays) -> Option<(DVec3, Option<f64>)> {
        let _ = rays;
        None
    }

    /// Sums over the rays of `bundle` around `base`: radiance, hit distance of the rays that
    /// hit, their count, and whether every depth was known. Fields may override this with a
    /// faster path that must return exactly the same sums.
    fn sample_sum(&self, base: &Ray, bundle: &RayBundle) -> BundleSum {
        let mut acc = BundleSum::default();
        for k in 0..bundle.shifts.len() {
            acc.add(self.sample(&bundle.ray(base, k)));
        }
        acc
    }
}

/// Sums over a bundle of rays ([`RadianceField::sample_sum`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BundleSum {
    /// Sum of the rays' radiance.
    pub radiance: DVec3,
    /// Sum of the finite hit distances.
    pub depth: f64,
    /// Number of rays that hit something.
    pub hits: usize,
    /// False when some ray's depth was unknown (NaN).
    pub depth_known: bool,
}

impl Default for BundleSum {
    fn default() -> Self {
        Self { radiance: DVec3::ZERO, depth: 0.0, hits: 0, depth_known: true }
    }
}

impl BundleSum {
    /// Adds another bundle's sums (renderers sum each pixel sample's bundle, then the bundles).
    #[inline(always)]
    pub fn merge(&mut self, other: BundleSum) {
        self.radiance += other.radiance;
        self.depth += other.depth;
        self.hits += other.hits;
        self.depth_known &= other.depth_known;
    }

    /// Adds one ray's sample.
    #[inline(always)]
    pub fn add(&mut self, s: Sample) {
        self.radiance += s.radiance;
        if s.depth.is_finite() {
            self.depth += s.depth;
            self.hits += 1;
        } else if s.depth.is_nan() {
            self.depth_known = false;
        }
    }
}

/// Rays that differ from a base ray by constant shifts of their start (x, y) and slope
/// (x, y): LensletAverage's samples of one pixel (eq. (1b) is affine in the lenslet point).
#[derive(Clone, Debug, PartialEq)]
pub struct RayBundle {
    /// (start shift, slope shift) per ray.
    pub shifts: Vec<(DVec2, DVec2)>,
    /// Component-wise bounds of the start and slope shifts.
    pub start_min: DVec2,
    /// Upper bound of the start shifts.
    pub start_max: DVec2,
    /// Lower bound of the slope shifts.
    pub slope_min: DVec2,
    /// Upper bound of the slope shifts.
    pub slope_max: DVec2,
    /// For bundles made by [`RayBundle::lenslet_points`]: the bounds of the points `q` and the
    /// factors `alpha`, `beta` such that every shift is `(alpha q, beta q)` (see
    /// [`RayBundle::affine_around`]).
    affine: Option<(DVec2, DVec2, f64, f64)>,
}

/// Component-wise bounds `(low, high)` of `points` (`(+inf, -inf)` for none).
pub fn bounds(points: impl IntoIterator<Item = DVec2>) -> (DVec2, DVec2) {
    let inf = DVec2::splat(f64::INFINITY);
    points.into_iter().fold((inf, -inf), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

impl RayBundle {
    /// A bundle of rays shifted from a base ray by `(start offset, slope offset)` pairs.
    pub fn new(shifts: Vec<(DVec2, DVec2)>) -> Self {
        let (start_min, start_max) = bounds(shifts.iter().map(|s| s.0));
        let (slope_min, slope_max) = bounds(shifts.iter().map(|s| s.1));
        Self { shifts, start_min, start_max, slope_min, slope_max, affine: None }
    }

    /// LensletAverage's bundle: for each point `q` (offsets from the lenslet centre), the shift
    /// `(q - q gain reach, q gain)` of a camera ray refracted at the lenslet with `gain = 1/f -
    /// 1/v2` and started `reach` before the lenslet plane (eq. (1b) is affine in the lenslet
    /// point). The bundle remembers that its shifts are `(alpha q, beta q)` with `alpha = 1 -
    /// gain reach`, `beta = gain`.
    pub fn lenslet_points(points: &[DVec2], gain: f64, reach: f64) -> Self {
        let mut bundle = Self::new(points.iter().map(|&q| (q - q * gain * reach, q * gain)).collect());
        let (lo, hi) = bounds(points.iter().copied());
        if lo.is_finite() && hi.is_finite() && gain.is_finite() && reach.is_finite() {
            bundle.affine = Some((lo, hi, 1.0 - gain * reach, gain));
        }
        bundle
    }

    /// The bundle around `base` (which must have unit z slope) as an [`AffineRays`] family, when
    /// it was made by [`RayBundle::lenslet_points`].
    #[inline(always)]
    pub fn affine_around(&self, base: &Ray) -> Option<AffineRays> {
        let (q_lo, q_hi, alpha, beta) = self.affine?;
        (base.dir.z == 1.0).then_some(AffineRays {
            origin: base.origin,
            dir: base.dir.truncate(),
            q_lo,
            q_hi,
            alpha,
            beta,
            e_lo: DVec2::ZERO,
            e_hi: DVec2::ZERO,
        })
    }

    /// Ray `k` of the bundle around `base` (only x and y are shifted).
    #[inline(always)]
    pub fn ray(&self, base: &Ray, k: usize) -> Ray {
        let (ds, dw) = self.shifts[k];
        Ray {
            origin: DVec3::new(base.origin.x + ds.x, base.origin.y + ds.y, base.origin.z),
            dir: DVec3::new(base.dir.x + dw.x, base.dir.y + dw.y, base.dir.z),
        }
    }
}
