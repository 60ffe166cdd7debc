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
