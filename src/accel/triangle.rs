//! The watertight ray/triangle test and the nearest-hit rule shared by every inimtrace triangle
//! backend: the brute-force reference ([`super::brute::BruteForce`]) and both BVH layouts
//! ([`super::bvh`], [`super::bvh4`]) (paper Sec. 3.1: each ray is traversed until it hits an
//! object; this is the "hits" part for triangles).
//!
//! The test is the watertight algorithm of Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection" (JCGT 2(1), 2013), implemented here in `f64` from the paper's description:
//!
//! 1. Per ray: choose the dominant axis `kz` of the direction (largest `|d|`), the other two
//!    `kx, ky` cyclically after it, swapped when `d[kz] < 0` to keep the winding; and a shear
//!    `Sx = d[kx] / d[kz]`, `Sy = d[ky] / d[kz]`, `Sz = 1 / d[kz]` that maps the ray to the +z
//!    axis through the origin.
//! 2. Per triangle: translate the vertices by the ray origin, shear them into that ray space,
//!    and evaluate the three 2-D edge functions `U, V, W` (twice the signed areas of the
//!    sub-triangles seen from the ray) at the origin. An edge function that rounds to exactly
//!    zero is recomputed with an error-free (FMA-based) difference of products, which has the
//!    correct sign and is zero only when exactly zero; this plays the role of the paper's
//!    fall-back to higher precision. The decision is made per edge (not per triangle, as in the
//!    paper) so that both triangles sharing an edge always use the same evaluation of it.
//! 3. The ray hits when all of `U, V, W` are `>= 0` or all `<= 0` (two-sided) and their sum
//!    `det` is non-zero (a zero `det` means the ray is parallel to the triangle's plane). Then
//!    `t = (U Az + V Bz + W Cz) / det`, with the range test done before the division.
//!
//! Watertightness: a shared edge's two endpoints are transformed identically for both
//! triangles, and its edge function is computed from the same two products with the operands
//! in the opposite order, so the two triangles see exactly opposite values: a ray through the
//! edge is inside at least one of them, and a ray through the edge exactly (value 0) is inside
//! both. No ray falls through a closed mesh.

use glam::{DVec2, DVec3};

use crate::ray::{Hit, Ray, Surface};

/// The nearest hit found so far, with the deterministic tie-break shared by every triangle
/// backend: smaller `t` wins; at equal `t`, the lower object index, then the lower triangle index.
#[derive(Clone, Copy, Debug, Default)]
pub struct NearestHit(Option<(f64, u32, u32, DVec2)>);

impl NearestHit {
    /// Offers a hit; returns whether it became the nearest.
    #[inline(always)]
    pub fn offer(&mut self, t: f64, object: u32, index: u32, bary: DVec2) -> bool {
        let better = match self.0 {
            None => true,
            Some((bt, bo, bi, _)) => t < bt || (t == bt && (object, index) < (bo, bi)),
        };
        if better {
            self.0 = Some((t, object, index, bary));
        }
        better
    }

    /// The nearest hit kept, if any.
    pub fn hit(self) -> Option<Hit> {
        self.0.map(|(t, object, index, bary)| Hit { t, object, surface: Surface::Triangle { index, bary } })
    }
}

/// A ray prepared for the watertight test (axis permutation and shear, computed once per ray).
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: DVec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f64,
    sy: f64,
    sz: f64,
}

impl WatertightRay {
    /// Prepares `ray`; `None` when the direction is zero or not finite, or the origin is not
    /// finite (such a ray hits nothing).
    pub fn new(ray: &Ray) -> Option<Self> {
        let d = ray.dir;
        if !d.is_finite() || !ray.origin.is_finite() || d == DVec3::ZERO {
            return None;
        }
        let a = d.abs();
        // (kx, ky, kz): kz is the dominant axis; kx, ky the other two, swapped when d[kz] < 0 to
        // keep the winding.
        let (kx, ky, kz) = if a.x >= a.y && a.x >= a.z {
            if d.x < 0.0 {
                (2, 1, 0)
            } else {
                (1, 2, 0)
            }
        } else if a.y >= a.z {
            if d.y < 0.0 {
                (0, 2, 1)
            } else {
                (2, 0, 1)
            }
        } else if d.z < 0.0 {
            (1, 0, 2)
        } else {
            (0, 1, 2)
        };
        let d = d.to_array();
        Some(WatertightRay { origin: ray.origin, kx, ky, kz, sx: d[kx] / d[kz], sy: d[ky] / d[kz], sz: 1.0 / d[kz] })
    }

    /// Intersects triangle `(p0, p1, p2)` (either side). Returns `(t, bary)` when
    /// `0 < t < t_max`, with Embree's barycentrics: hit point = `(1 - u - v) p0 + u p1 + v p2`.
    /// Rays parallel to the triangle's plane (including rays inside the plane) miss.
    #[inline(always)]
    pub fn intersect(&self, p0: DVec3, p1: DVec3, p2: DVec3, t_max: f64) -> Option<(f64, DVec2)> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        // Arrays rather than DVec3 for the permuted reads (indexing a DVec3 is a branch chain).
        let a = (p0 - self.origin).to_array();
        let b = (p1 - self.origin).to_array();
        let c = (p2 - self.origin).to_array();
        // Shear and scale the vertices into ray space (the ray becomes the +z axis).
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];

        // Edge functions: U for edge (b, c) weights vertex a, V for (c, a) weights b, W for (a, b)
        // weights c.
        // All three have the form E(p -> q) = q.x p.y - q.y p.x, so the neighbour across an edge,
        // which runs it the other way, computes exactly the negated value.
        let u = edge_function(bx, by, cx, cy);
        let v = edge_function(cx, cy, ax, ay);
        let w = edge_function(ax, ay, bx, by);
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // Scaled hit distance, tested against (0, t_max) before dividing by det.
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        if det > 0.0 {
            if t_scaled <= 0.0 || t_scaled > t_max * det {
                return None;
            }
        } else if t_scaled >= 0.0 || t_scaled < t_max * det {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        Some((t, DVec2::new(v * inv_det, w * inv_det)))
    }
}

/// The 2-D edge function `E(p -> q) = q.x p.y - q.y p.x` (twice the signed area of the triangle
/// `(origin, p, q)`), recomputed with an error-free difference of products when the plain
/// evaluation rounds to zero. Swapping `p` and `q` negates the plain result exactly and the
/// fallback's sign exactly, and both swaps take the same path.
#[inline]
fn edge_function(px: f64, py: f64, qx: f64, qy: f64) -> f64 {
    let e = qx * py - qy * px;
    if e != 0.0 {
        e
    } else {
        diff_of_products(qx, py, qy, px)
    }
}

/// `a * b - c * d` with an error-free transformation (Kahan's algorithm with FMA): the result
/// has a relative error of at most two units in the last place (barring underflow), so its sign
/// is exact and it is zero only when the exact value is zero.
fn diff_of_products(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let cd = c * d;
    let err = (-c).mul_add(d, cd); // cd - c*d exactly
    let dop = a.mul_add(b, -cd); // a*b - cd, rounded once
    dop + err
}
