//! Rays, hits and the scene-intersection interface: the bottom layer that the optics, the scene,
//! the intersection backends and the renderers all share (paper Sec. 3.1: "each ray is traversed
//! until it hits an object"). It depends on nothing else in the crate.

use glam::{DVec2, DVec3};

/// A ray `origin + t * dir`, `t > 0`. `dir` need not be unit length; `t` is in units of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point, world mm.
    pub origin: DVec3,
    /// Direction (any length; `t` counts in its units).
    pub dir: DVec3,
}

/// Where on a surface a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// An analytic primitive: `uv` are its own surface coordinates (for a rectangle, local
    /// coordinates in [-1, 1]^2 along its two half-edge vectors).
    Analytic {
        /// The primitive's surface coordinates.
        uv: DVec2,
    },
    /// Triangle `index` of a mesh, with Embree-convention barycentrics `bary = (u, v)`:
    /// point = (1 - u - v) p0 + u p1 + v p2.
    Triangle {
        /// The triangle's index in its mesh.
        index: u32,
        /// Barycentrics `(u, v)`.
        bary: DVec2,
    },
}

/// The nearest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (world distance = t * |dir|).
    pub t: f64,
    /// Index of the scene object that was hit (`Scene::objects`).
    pub object: u32,
    /// What was hit where.
    pub surface: Surface,
}

/// A scene intersection backend. Implementations are immutable after construction and shared
/// across rayon threads.
pub trait Intersector: Send + Sync {
    /// Short name for reports ("analytic", "embree", "bvh").
    fn name(&self) -> &'static str;

    /// Nearest hit with `0 < t < t_max`, or `None`.
    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit>;

    /// Nearest hits for many rays (`hits.len() == rays.len()`), unbounded `t_max`.
    /// Backends override this to use packets or streams on coherent rays.
    fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = self.intersect(ray, f64::INFINITY);
        }
    }

    /// Whether [`Intersector::intersect_many`] is faster on long runs of neighbouring rays than
    /// one ray at a time (packets or streams). Renderers batch rays only for such backends.
    fn prefers_batches(&self) -> bool {
        false
    }

    /// True when anything blocks the ray with `0 < t < t_max` (shadow rays).
    fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.intersect(ray, t_max).is_some()
    }
}

/// A family of rays, all starting on the plane `z = origin.z` with unit z slope, whose start and
/// slope move together (in exact arithmetic; the rays themselves may be computed otherwise, with
/// rounding far below what fields allow for):
///
/// ```text
/// start(q, e) = origin.xy + alpha q,   slope(q, e) = dir + beta q + e,
/// q in [q_lo, q_hi], e in [e_lo, e_hi] (component-wise)
/// ```
///
/// At `t` past the start plane the rays cover `origin.xy + t dir + (alpha + beta t) q + t e`.
/// LensletAverage's rays of one pixel are such a family (q: the point in the lenslet cell, eq.
/// (1b) is affine in it), and so are an eye's rays of one retina pixel (q: the pupil point, e:
/// the point in the pixel's square; eq. (1a)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineRays {
    /// Start point of the bundle's central ray (at q = 0, e = 0), world mm.
    pub origin: DVec3,
    /// Slope (dx/dz, dy/dz) of the central ray.
    pub dir: DVec2,
    /// Lower corner of the q box.
    pub q_lo: DVec2,
    /// Upper corner of the q box.
    pub q_hi: DVec2,
    /// How the start point moves with q.
    pub alpha: f64,
    /// How the slope moves with q.
    pub beta: f64,
    /// Lower corner of the e box (slope offsets).
    pub e_lo: DVec2,
    /// Upper corner of the e box.
    pub e_hi: DVec2,
}

impl AffineRays {
    /// The bounds (component-wise) of the family's points at `t >= 0` past its start plane.
    #[inline(always)]
    pub fn bounds_at(&self, t: f64) -> (DVec2, DVec2) {
        let g = self.alpha + self.beta * t;
        let (a, b) = (self.q_lo * g, self.q_hi * g);
        let centre = self.origin.truncate() + self.dir * t;
        (centre + a.min(b) + self.e_lo * t, centre + a.max(b) + self.e_hi * t)
    }

    /// A size (per axis) of the numbers from which the rays' points at `t` are computed: their
    /// rounding errors are a few units of 1e-16 of it.
    #[inline(always)]
    pub fn magnitude_at(&self, t: f64) -> DVec2 {
        let q = self.q_lo.abs().max(self.q_hi.abs());
        let e = self.e_lo.abs().max(self.e_hi.abs());
        self.origin.truncate().abs() + (self.dir.abs() + e) * t + q * (self.alpha.abs() + self.beta.abs() * t)
    }
}
