//! Exact (real-ray) tracing through a schematic eye, both ways, and ray aiming.
//!
//! Sequential tracing: conic intersection ([`super::conic`], Spencer & Murty, JOSA 52:672, 1962)
//! and vector Snell refraction ([`super::refract`]) surface by surface. Ray aiming
//! ([`EyeAtWavelength::ray_out`]) finds the ray from a retina point through a given iris point:
//! a 2-D root find in the ray's direction tangents in the vitreous, started from the paraxial
//! solution of the y-nu matrices ([`super::paraxial`]) and solved by a quasi-Newton iteration
//! whose Jacobian starts as the paraxial one and is refined by Broyden's rank-one updates
//! (C. G. Broyden, Math. Comp. 19:577, 1965; Dennis & Schnabel, "Numerical Methods for
//! Unconstrained Optimization and Nonlinear Equations", 1983, Ch. 8), to 1e-11 mm at the iris;
//! a step that leaves the optics is halved up to eight times.

use glam::{DVec2, DVec3};

use super::paraxial::Abcd;
use super::refract::refract;
use super::schematic::{SchematicEye, MAX_SURFACES};
use crate::optics::PlaneRay;

/// Iris residual at which ray aiming stops, mm.
const AIM_TOLERANCE: f64 = 1e-11;
/// Rays crossing the iris this far beyond its radius still pass `ray_in`, mm.
const IRIS_SLACK: f64 = 1e-9;
/// How far (mm along the ray) the iris plane may lie behind the last surface point, for the
/// rounding of a crossing at a vertex that lies in the iris plane.
const PLANE_SLACK: f64 = 1e-9;
/// Iterations before ray aiming gives up.
const AIM_ITERATIONS: usize = 40;
/// The object-space start plane of inward rays, mm in front of the cornea vertex.
const START_T: f64 = -60.0;

/// One refraction along a recorded trace ([`EyeAtWavelength::recorded_in`]), lens-design frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Refraction {
    /// Where the ray meets the surface.
    pub point: DVec3,
    /// The unit direction before the surface.
    pub before: DVec3,
    /// The unit direction after it.
    pub after: DVec3,
}

/// A schematic eye with its indices evaluated at one wavelength (build once per wavelength,
/// then trace many rays).
#[derive(Clone, Debug)]
pub struct EyeAtWavelength<'a> {
    eye: &'a SchematicEye,
    wavelength_nm: f64,
    /// `n[0]` air, `n[i + 1]` after surface i.
    n: [f64; MAX_SURFACES + 1],
    /// Paraxial matrix from the iris plane to the last surface's vertex.
    iris_to_last: Abcd,
}

impl SchematicEye {
    /// The eye at one wavelength, for tracing many rays.
    pub fn at(&self, wavelength_nm: f64) -> EyeAtWavelength<'_> {
        let v = self.indices(wavelength_nm);
        let mut n = [1.0; MAX_SURFACES + 1];
        n[..v.len()].copy_from_slice(&v);
        EyeAtWavelength { eye: self, wavelength_nm, n, iris_to_last: self.iris_to_last(&v) }
    }

    /// The ray from retina point `retina` (this frame) through iris point `iris` (x, y in the
    /// iris plane, mm from its centre), traced out of the eye at `wavelength_nm`, as the
    /// object-space line at the plane z = 0. None when it is blocked (semi-diameter, iris, TIR,
    /// a missed surface) or the aim does not converge. See [`EyeAtWavelength::ray_out`].
    pub fn ray_out(&self, retina: DVec3, iris: DVec2, wavelength_nm: f64) -> Option<PlaneRay> {
        self.at(wavelength_nm).ray_out(retina, iris)
    }

    /// An object-space ray (the line at z = 0, travelling toward -z into the eye) traced in to
    /// the retina: (retina point, iris crossing point), or None if it is blocked.
    pub fn ray_in(&self, ray: PlaneRay, wavelength_nm: f64) -> Option<(DVec3, DVec2)> {
        self.at(wavelength_nm).ray_in(ray)
    }
}

impl EyeAtWavelength<'_> {
    /// The wavelength, nm.
    pub fn wavelength(&self) -> f64 {
        self.wavelength_nm
    }

    /// Through surfaces `from..to` toward the retina (lens-design frame).
    #[inline]
    fn forward(&self, mut p: DVec3, mut d: DVec3, from: usize, to: usize) -> Option<(DVec3, DVec3)> {
        for i in from..to {
            let s = &self.eye.surfaces[i];
            p = s.intersect(p, d)?.point;
            d = refract(d, s.normal(p), self.n[i], self.n[i + 1])?;
        }
        Some((p, d))
    }

    /// Through surfaces `to..from` in reverse order, toward the cornea.
    #[inline]
    fn backward(&self, mut p: DVec3, mut d: DVec3, from: usize, to: usize) -> Option<(DVec3, DVec3)> {
        for i in (to..from).rev() {
            let s = &self.eye.surfaces[i];
            p = s.intersect(p, d)?.point;
            d = refract(d, s.normal(p), self.n[i + 1], self.n[i])?;
        }
        Some((p, d))
    }

    /// The crossing of the iris plane, checked against the iris opening.
    #[inline]
    fn iris_crossing(&self, p: DVec3, d: DVec3) -> Option<DVec3> {
        let s = (self.eye.iris_t - p.z) / d.z;
        // The iris lies in the plane of the lens's front vertex: an axial ray meets both at once,
        // and rounding may put the plane a hair behind the surface point.
        if !(s >= -PLANE_SLACK && s.is_finite()) {
            return None;
        }
        let q = p + s * d;
        if let Some(r) = self.eye.iris_radius {
            // The slack lets a ray aimed at the iris edge (to 1e-11 mm) back in.
            let r = r + IRIS_SLACK;
            if q.x * q.x + q.y * q.y > r * r {
                return None;
            }
        }
        Some(q)
    }

    /// The object-space ray (at z = 0 of the frame, toward -z) traced in: the retina point and
    /// the iris crossing, or None if blocked.
    pub fn ray_in(&self, ray: PlaneRay) -> Option<(DVec3, DVec2)> {
        let eye = self.eye;
        let d = DVec3::new(-ray.slope.x, -ray.slope.y, 1.0).normalize();
        let p0 = DVec3::new(ray.position.x, ray.position.y, eye.origin_t);
        let p = p0 + (START_T - p0.z) / d.z * d;
        if !p.is_finite() {
            return None;
        }
        let (p, d) = self.forward(p, d, 0, eye.iris_after + 1)?;
        let q = self.iris_crossing(p, d)?;
        // On from before the iris plane: it may touch the next surface's vertex.
        let (p, d) = self.forward(p, d, eye.iris_after + 1, eye.surfaces.len())?;
        let hit = eye.retina.intersect(p, d)?;
        Some((eye.flip(hit.point), DVec2::new(q.x, q.y)))
    }

    /// From a lens-frame retina point in direction `(u.x, u.y, -1)` to the iris plane.
    #[inline]
    fn to_iris(&self, p: DVec3, u: DVec2) -> Option<(DVec3, DVec3)> {
        let d = DVec3::new(u.x, u.y, -1.0).normalize();
        let (p, d) = self.backward(p, d, self.eye.surfaces.len(), self.eye.iris_after + 1)?;
        let s = (self.eye.iris_t - p.z) / d.z;
        (s >= -PLANE_SLACK).then(|| (p + s * d, d))
    }

    /// Ray aiming: the ray from retina point `retina` (this frame) through iris point `iris`,
    /// traced out into the air and returned as the line at z = 0 (slope dx/dz, dy/dz, toward
    /// +z). None when blocked or not converged (1e-11 mm at the iris within 40 iterations).
    pub fn ray_out(&self, retina: DVec3, iris: DVec2) -> Option<PlaneRay> {
        let eye = self.eye;
        if let Some(r) = eye.iris_radius {
            // A relative 1e-12 forgives the rounding of a point put at the edge by hand.
            if iris.length() > r * (1.0 + 1e-12) {
                return None;
            }
        }
        let p0 = eye.flip(retina);
        if !(p0.is_finite() && iris.is_finite()) {
            return None;
        }
        // Paraxial start: y_iris = D y_r + B n_v u for the matrix F from the iris to the retina
        // point's plane (u the tangent of the reversed ray).
        let last = eye.surfaces.len();
        let nv = self.n[last];
        let f = self.iris_to_last.then(Abcd::transfer(p0.z - eye.surfaces[last - 1].vertex, nv));
        let yr = DVec2::new(p0.x, p0.y);
        let mut u = (iris - f.d * yr) / (f.b * nv);
        let residual = |u: DVec2| self.to_iris(p0, u).map(|(q, d)| (DVec2::new(q.x, q.y) - iris, q, d));
        let (mut r, mut q, mut d) = residual(u)?;
        // Jacobian: the paraxial one at the start, Broyden updates after.
        let j0 = f.b * nv;
        let mut jac = [DVec2::new(j0, 0.0), DVec2::new(0.0, j0)]; // columns
        let mut iterations = 0;
        while r.length_squared() > AIM_TOLERANCE * AIM_TOLERANCE {
            iterations += 1;
            if iterations > AIM_ITERATIONS {
                return None;
            }
            let det = jac[0].x * jac[1].y - jac[1].x * jac[0].y;
            if det.is_nan() || det.abs() <= 1e-300 {
                return None;
            }
            let step = -DVec2::new(jac[1].y * r.x - jac[1].x * r.y, -jac[0].y * r.x + jac[0].x * r.y) / det;
            let mut step = step;
            let mut next = None;
            for _ in 0..8 {
                if let Some(v) = residual(u + step) {
                    next = Some(v);
                    break;
                }
                step *= 0.5;
            }
            let (r1, q1, d1) = next?;
            let dr = r1 - r;
            let s2 = step.length_squared();
            let progress = r1.length_squared() <= 0.25 * r.length_squared();
            u += step;
            (r, q, d) = (r1, q1, d1);
            if !progress {
                // Broyden's secant update stalls when a step is poor (seen near the axis, where
                // the rank-one updates lose one direction): start again from the Jacobian by
                // central differences at the new point, which makes the next step Newton's.
                let h = 1e-6;
                let col = |e: DVec2| -> Option<DVec2> {
                    let (a, _, _) = residual(u + e * h)?;
                    let (b, _, _) = residual(u - e * h)?;
                    Some((a - b) / (2.0 * h))
                };
                jac = [col(DVec2::X)?, col(DVec2::Y)?];
            } else if s2 > 0.0 {
                let js = jac[0] * step.x + jac[1] * step.y;
                let corr = (dr - js) / s2;
                jac[0] += corr * step.x;
                jac[1] += corr * step.y;
            }
        }
        let (p, d) = self.backward(q, d, eye.iris_after + 1, 0)?;
        // Into the frame: z = origin_t - t, so the direction's z flips.
        let pf = eye.flip(p);
        let dz = -d.z;
        if dz.is_nan() || dz <= 0.0 {
            return None;
        }
        let slope = DVec2::new(d.x, d.y) / dz;
        Some(PlaneRay { position: DVec2::new(pf.x, pf.y) - slope * pf.z, slope })
    }

    /// The index `n[i]` at this wavelength: 0 the air, `i + 1` the medium after surface i.
    pub(crate) fn index(&self, i: usize) -> f64 {
        self.n[i]
    }

    /// [`EyeAtWavelength::ray_in`] with every refraction recorded (the iris opening is not
    /// checked): the refractions, cornea first, and the retina hit, in the lens-design frame.
    pub(crate) fn recorded_in(&self, ray: PlaneRay) -> Option<(Vec<Refraction>, DVec3)> {
        let eye = self.eye;
        let mut d = DVec3::new(-ray.slope.x, -ray.slope.y, 1.0).normalize();
        let p0 = DVec3::new(ray.position.x, ray.position.y, eye.origin_t);
        let mut p = p0 + (START_T - p0.z) / d.z * d;
        if !p.is_finite() {
            return None;
        }
        let mut path = Vec::with_capacity(eye.surfaces.len());
        for (i, s) in eye.surfaces.iter().enumerate() {
            p = s.intersect(p, d)?.point;
            let after = refract(d, s.normal(p), self.n[i], self.n[i + 1])?;
            path.push(Refraction { point: p, before: d, after });
            d = after;
        }
        let hit = eye.retina.intersect(p, d)?;
        Some((path, hit.point))
    }

    /// The chief ray of object tangent `tangent` (through the iris centre): its retina point and
    /// its position at z = 0. None if blocked or not converged.
    pub(crate) fn chief_ray(&self, tangent: DVec2) -> Option<(DVec3, DVec2)> {
        let tau = tangent.length();
        if !tau.is_finite() {
            return None;
        }
        if tau == 0.0 {
            let ray = PlaneRay { position: DVec2::ZERO, slope: DVec2::ZERO };
            return self.ray_in(ray).map(|(p, _)| (p, DVec2::ZERO));
        }
        let e = tangent / tau;
        // The iris crossing along e of the ray through h e at z = 0 (ignores the iris opening).
        let g = |h: f64| -> Option<(f64, DVec3)> {
            let ray = PlaneRay { position: e * h, slope: tangent };
            let d = DVec3::new(-ray.slope.x, -ray.slope.y, 1.0).normalize();
            let p0 = DVec3::new(ray.position.x, ray.position.y, self.eye.origin_t);
            let p = p0 + (START_T - p0.z) / d.z * d;
            let (p, d) = self.forward(p, d, 0, self.eye.iris_after + 1)?;
            let s = (self.eye.iris_t - p.z) / d.z;
            let q = p + s * d;
            Some((DVec2::new(q.x, q.y).dot(e), d))
        };
        let (mut h0, mut f0) = (0.0, g(0.0)?.0);
        let mut h1 = -f0 * 1.1;
        let mut f1 = g(h1)?.0;
        for _ in 0..60 {
            if f1.abs() < 1e-14 || f1 == f0 {
                break;
            }
            let h2 = h1 - f1 * (h1 - h0) / (f1 - f0);
            (h0, f0) = (h1, f1);
            h1 = h2;
            f1 = g(h1)?.0;
        }
        if f1.is_nan() || f1.abs() >= 1e-12 {
            return None;
        }
        let ray = PlaneRay { position: e * h1, slope: tangent };
        let (p, _) = self.ray_in(ray)?;
        Some((p, e * h1))
    }
}
