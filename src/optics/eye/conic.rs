//! A rotationally symmetric conic surface about the z axis, its exact ray intersection and its
//! normal.
//!
//! Sag `z(r) = c r² / (1 + sqrt(1 - (1+Q) c² r²))` (c = 1/R, Q the conic constant; Q = 0 sphere,
//! -1 < Q < 0 prolate ellipsoid, Q = -1 paraboloid, Q < -1 hyperboloid): W. T. Welford,
//! "Aberrations of Optical Systems" (Hilger, 1986), Sec. 2.4. The surface is the zero set of
//! `F = c (x² + y²) + c (1+Q) z'² - 2 z'` (z' = z - vertex); a ray `p + s d` meets it where a
//! quadratic in s vanishes, solved without cancellation by the form `s = C / q` with
//! `q = -(B + sign(B) sqrt(B² - AC))` (Press et al., "Numerical Recipes", 3rd ed., Sec. 5.6), as
//! in the general ray-tracing procedure of G. H. Spencer & M. V. R. K. Murty, JOSA 52:672 (1962).
//! The quadratic's roots lie on both sheets of the conic (or both halves of a sphere); the sheet
//! through the vertex is the one where `g = 1 - (1+Q) c z' >= 0` (then `g` is the square root of
//! the sag formula). [`Conic::intersect_by_root_finding`] is the slow twin the tests compare
//! against: the sag equation solved along the ray by scanning and bisection.
//!
//! The frame here is the lens-design frame of [`super::schematic`]: z from the cornea vertex
//! toward the retina.

use glam::DVec3;

/// A conic surface of revolution about the z axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conic {
    /// z of the vertex, mm.
    pub vertex: f64,
    /// Curvature c = 1/R at the vertex, 1/mm (0: a plane). Positive: centre of curvature at +z.
    pub curvature: f64,
    /// Conic constant Q (k).
    pub conic: f64,
    /// Semi-diameter: rays meeting the surface farther than this from the axis are blocked, mm.
    pub semi_diameter: f64,
}

/// Where a ray meets a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter: `point = p + s d`.
    pub s: f64,
    /// The intersection point.
    pub point: DVec3,
}

impl Conic {
    /// A conic from its signed radius of curvature (0 or infinite: a plane).
    pub fn from_radius(vertex: f64, radius: f64, conic: f64, semi_diameter: f64) -> Self {
        let curvature = if radius == 0.0 || radius.is_infinite() { 0.0 } else { 1.0 / radius };
        Self { vertex, curvature, conic, semi_diameter }
    }

    /// Sag z'(r²) of the vertex sheet, or None beyond its edge (`(1+Q) c² r² > 1`).
    #[inline]
    pub fn sag(&self, r2: f64) -> Option<f64> {
        let c = self.curvature;
        let u = 1.0 - (1.0 + self.conic) * c * c * r2;
        if u < 0.0 {
            return None;
        }
        Some(c * r2 / (1.0 + u.sqrt()))
    }

    /// The first intersection (s > 0) of the ray `p + s d` with the vertex sheet, or None when the
    /// ray misses it, meets it only on the other sheet, or meets it beyond the semi-diameter.
    #[inline]
    pub fn intersect(&self, p: DVec3, d: DVec3) -> Option<Hit> {
        let c = self.curvature;
        let k1 = 1.0 + self.conic;
        let pz = p.z - self.vertex;
        let a = c * (d.x * d.x + d.y * d.y + k1 * d.z * d.z);
        let b = c * (p.x * d.x + p.y * d.y + k1 * pz * d.z) - d.z;
        let cc = c * (p.x * p.x + p.y * p.y + k1 * pz * pz) - 2.0 * pz;
        let disc = b * b - a * cc;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let q = -(b + disc.sqrt().copysign(b));
        let r1 = if q != 0.0 { cc / q } else { f64::NAN };
        let r2 = if a != 0.0 { q / a } else { f64::NAN };
        let (lo, hi) = if r1 <= r2 || r2.is_nan() { (r1, r2) } else { (r2, r1) };
        for s in [lo, hi] {
            if s.is_nan() || s <= 0.0 {
                continue;
            }
            let point = p + s * d;
            let g = 1.0 - k1 * c * (point.z - self.vertex);
            if g < 0.0 {
                continue; // the other sheet
            }
            let r2 = point.x * point.x + point.y * point.y;
            if r2 > self.semi_diameter * self.semi_diameter {
                return None;
            }
            return Some(Hit { s, point });
        }
        None
    }

    /// The unit normal at a point of the vertex sheet, (0, 0, 1) at the vertex.
    #[inline]
    pub fn normal(&self, point: DVec3) -> DVec3 {
        let c = self.curvature;
        let g = 1.0 - (1.0 + self.conic) * c * (point.z - self.vertex);
        DVec3::new(-c * point.x, -c * point.y, g).normalize()
    }

    /// The slow twin of [`Conic::intersect`]: the root of `z'(s) - sag(r(s))` along the ray,
    /// bracketed by scanning s over `(0, s_max]` in `steps` steps and refined by bisection.
    pub fn intersect_by_root_finding(&self, p: DVec3, d: DVec3, s_max: f64, steps: usize) -> Option<Hit> {
        let h = |s: f64| {
            let q = p + s * d;
            self.sag(q.x * q.x + q.y * q.y).map(|z| q.z - self.vertex - z)
        };
        let mut prev: Option<(f64, f64)> = None;
        for i in 0..=steps {
            let s = s_max * i as f64 / steps as f64;
            let v = h(s);
            if let (Some((s0, v0)), Some(v1)) = (prev, v) {
                if v0 == 0.0 && s0 > 0.0 {
                    return self.accept(p, d, s0);
                }
                if (v0 < 0.0) != (v1 < 0.0) || v1 == 0.0 {
                    let (mut lo, mut hi, mut flo) = (s0, s, v0);
                    for _ in 0..200 {
                        let mid = 0.5 * (lo + hi);
                        if mid <= lo || mid >= hi {
                            break;
                        }
                        match h(mid) {
                            Some(fm) if (fm < 0.0) == (flo < 0.0) && fm != 0.0 => {
                                lo = mid;
                                flo = fm;
                            }
                            Some(_) => hi = mid,
                            None => break,
                        }
                    }
                    return self.accept(p, d, 0.5 * (lo + hi));
                }
            }
            prev = v.map(|v| (s, v));
        }
        None
    }

    fn accept(&self, p: DVec3, d: DVec3, s: f64) -> Option<Hit> {
        let point = p + s * d;
        (point.x * point.x + point.y * point.y <= self.semi_diameter * self.semi_diameter).then_some(Hit { s, point })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator for test rays.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn analytic_and_root_finding_intersections_agree() {
        let mut rng = Lcg(7);
        let surfaces = [
            Conic::from_radius(0.0, 7.72, -0.26, 5.5),
            Conic::from_radius(0.5, 6.5, 0.0, 5.5),
            Conic::from_radius(3.6, 10.2, -3.1316, 4.5),
            Conic::from_radius(7.6, -6.0, -1.0, 4.5),
            Conic::from_radius(2.0, 12.0, -7.52, 4.5),
            Conic::from_radius(1.0, 0.0, 0.0, 5.0),
            Conic::from_radius(1.0, 1e9, 0.3, 5.0),
            Conic::from_radius(24.0, -12.0, 0.0, 12.0),
        ];
        let mut compared = 0;
        for surf in surfaces {
            for _ in 0..400 {
                let p =
                    DVec3::new(rng.next() * 6.0 - 3.0, rng.next() * 6.0 - 3.0, surf.vertex - 3.0 - rng.next() * 2.0);
                let d = DVec3::new(rng.next() - 0.5, rng.next() - 0.5, 1.0).normalize();
                let a = surf.intersect(p, d);
                let b = surf.intersect_by_root_finding(p, d, 40.0, 4000);
                match (a, b) {
                    (Some(a), Some(b)) => {
                        assert!((a.point - b.point).length() < 1e-10, "{surf:?} {p} {d}: {a:?} {b:?}");
                        let z = surf.sag(a.point.x.powi(2) + a.point.y.powi(2)).unwrap();
                        assert!((a.point.z - surf.vertex - z).abs() < 1e-12);
                        compared += 1;
                    }
                    (None, None) => {}
                    _ => panic!("{surf:?} {p} {d}: analytic {a:?} vs root finding {b:?}"),
                }
            }
        }
        assert!(compared > 2500, "{compared}");
    }

    #[test]
    fn misses_other_sheet_and_edges_give_none_without_nan() {
        // A sphere of radius 2: a ray passing beside it misses.
        let s = Conic::from_radius(0.0, 2.0, 0.0, 2.0);
        assert!(s.intersect(DVec3::new(3.0, 0.0, -1.0), DVec3::Z).is_none());
        // A ray starting inside the sphere, going +z, meets only the far half: the other sheet.
        assert!(s.intersect(DVec3::new(0.0, 0.0, 1.0), DVec3::Z).is_none());
        // Beyond the semi-diameter.
        let s = Conic::from_radius(0.0, 10.0, 0.0, 1.0);
        assert!(s.intersect(DVec3::new(1.5, 0.0, -1.0), DVec3::Z).is_none());
        // Hyperboloid (1+Q < 0) and paraboloid (1+Q = 0): the vertex sheet only.
        for q in [-1.0, -3.0, -7.5] {
            let h = Conic::from_radius(0.0, 5.0, q, 50.0);
            let hit = h.intersect(DVec3::new(1.0, 0.5, -2.0), DVec3::Z).unwrap();
            assert!((hit.point.z - h.sag(1.25).unwrap()).abs() < 1e-13);
            // From behind the vertex going -z the ray meets the same sheet (never the other).
            let back = h.intersect(DVec3::new(0.3, 0.0, 30.0), -DVec3::Z).unwrap();
            assert!((back.point.z - h.sag(0.09).unwrap()).abs() < 1e-12);
            assert!(h.normal(hit.point).is_finite());
        }
        // A ray parallel to a plane never meets it; a near-plane conic has no cancellation.
        let plane = Conic::from_radius(1.0, 0.0, 0.0, 10.0);
        assert!(plane.intersect(DVec3::ZERO, DVec3::X).is_none());
        let flat = Conic::from_radius(1.0, 1e12, 0.0, 10.0);
        let hit = flat.intersect(DVec3::new(2.0, 0.0, 0.0), DVec3::Z).unwrap();
        assert!((hit.point.z - 1.0 - 2e-12).abs() < 1e-15);
        assert_eq!(plane.normal(hit.point), DVec3::Z);
    }
}
