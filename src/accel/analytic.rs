//! The exact analytic backend: ray/rectangle intersection in `f64` for scenes made only of
//! planar rectangles, such as the paper's (Sec. 4.1: three chart squares and a background).
//!
//! Fast path: when every rectangle faces the eye with its edges along x and y (as in the paper)
//! and a ray travels toward +z from in front of all of them, the rectangles are tried in order
//! of increasing z with a few multiplications each, and the first hit is the nearest.
//! [`AnalyticRects::intersect_all_rects`] is the slow twin that tries every rectangle with the
//! general plane test and keeps the nearest; tests check they agree (same object, `t` and `uv`
//! to 1e-12 relative, and the same answer away from edges).

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};
use crate::ray::{Hit, Intersector, Ray, Surface};
use crate::scene::{Scene, Shape};

#[derive(Clone, Copy, Debug)]
struct PreparedRect {
    object: u32,
    center: DVec3,
    normal: DVec3,
    /// half_u / |half_u|^2, so that `u = dot(p - center, u_axis)` is in [-1, 1] on the rectangle.
    u_axis: DVec3,
    v_axis: DVec3,
}

impl PreparedRect {
    /// Hit with `0 < t < t_max`, the same arithmetic in both paths.
    #[inline(always)]
    fn hit(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        let denom = ray.dir.dot(self.normal);
        if denom == 0.0 {
            return None; // parallel to the plane
        }
        let t = (self.center - ray.origin).dot(self.normal) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let p = ray.origin + t * ray.dir - self.center;
        let uv = DVec2::new(p.dot(self.u_axis), p.dot(self.v_axis));
        if uv.x.abs() <= 1.0 && uv.y.abs() <= 1.0 {
            Some(Hit { t, object: self.object, surface: Surface::Analytic { uv } })
        } else {
            None
        }
    }
}

/// A rectangle facing the eye with edges along x and y, for the fast path.
#[derive(Clone, Copy, Debug)]
struct FacingRect {
    object: u32,
    z: f64,
    cx: f64,
    cy: f64,
    /// 1 / half width and 1 / half height (signed, following `half_u.x` and `half_v.y`).
    inv_hx: f64,
    inv_hy: f64,
}

/// Exact `f64` intersection with a scene's rectangles.
#[derive(Clone, Debug)]
pub struct AnalyticRects {
    /// In object order.
    rects: Vec<PreparedRect>,
    /// When every rectangle faces the eye with edges along x and y: sorted by plane z (then
    /// object index).
    z_sorted: Option<Vec<FacingRect>>,
    /// Smallest plane z (fast path applies to rays starting strictly in front of it).
    min_z: f64,
}

impl AnalyticRects {
    /// Builds the backend. Errors when the scene holds anything but rectangles, or a rectangle
    /// is degenerate.
    pub fn new(scene: &Scene) -> Result<Self> {
        let mut rects = Vec::with_capacity(scene.objects.len());
        for (k, object) in scene.objects.iter().enumerate() {
            let Shape::Rect(r) = &object.shape else {
                return Err(Error::Backend {
                    scene: scene.name.clone(),
                    message: format!(
                        "the analytic backend intersects only rectangles; object {k} (`{}`) is a mesh: use --backend embree",
                        object.name
                    ),
                });
            };
            let n = r.half_u.cross(r.half_v);
            if !(n.length() > 0.0 && n.is_finite() && r.center.is_finite()) {
                return Err(Error::invalid(
                    format!("scene `{}`", scene.name),
                    format!("object {k} (`{}`)", object.name),
                    "rectangle is degenerate (zero or non-finite size) or its centre is not finite",
                ));
            }
            rects.push(PreparedRect {
                object: k as u32,
                center: r.center,
                normal: n.normalize(),
                u_axis: r.half_u / r.half_u.length_squared(),
                v_axis: r.half_v / r.half_v.length_squared(),
            });
        }
        let facing = scene.objects.iter().all(|o| match &o.shape {
            Shape::Rect(r) => r.half_u.y == 0.0 && r.half_u.z == 0.0 && r.half_v.x == 0.0 && r.half_v.z == 0.0,
            Shape::Mesh(_) => false,
        });
        let z_sorted = facing.then(|| {
            let mut fr: Vec<FacingRect> = scene
                .objects
                .iter()
                .enumerate()
                .filter_map(|(k, o)| match &o.shape {
                    Shape::Rect(r) => Some(FacingRect {
                        object: k as u32,
                        z: r.center.z,
                        cx: r.center.x,
                        cy: r.center.y,
                        inv_hx: 1.0 / r.half_u.x,
                        inv_hy: 1.0 / r.half_v.y,
                    }),
                    Shape::Mesh(_) => None,
                })
                .collect();
            fr.sort_by(|a, b| a.z.total_cmp(&b.z).then(a.object.cmp(&b.object)));
            fr
        });
        let min_z = rects.iter().map(|r| r.center.z).fold(f64::INFINITY, f64::min);
        Ok(Self { rects, z_sorted, min_z })
    }

    /// Slow twin: every rectangle, keep the nearest (earliest object on equal `t`).
    pub fn intersect_all_rects(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        for r in &self.rects {
            if let Some(h) = r.hit(ray, limit) {
                limit = h.t;
                best = Some(h);
            }
        }
        best
    }
}

impl Intersector for AnalyticRects {
    fn name(&self) -> &'static str {
        "analytic"
    }

    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        if let Some(order) = &self.z_sorted {
            if ray.dir.z > 0.0 && ray.origin.z < self.min_z {
                let inv_dz = 1.0 / ray.dir.z;
                for r in order {
                    let t = (r.z - ray.origin.z) * inv_dz;
                    if t >= t_max || t.is_nan() {
                        return None; // sorted: every later plane is farther still
                    }
                    let u = (ray.origin.x + t * ray.dir.x - r.cx) * r.inv_hx;
                    let v = (ray.origin.y + t * ray.dir.y - r.cy) * r.inv_hy;
                    if u.abs() <= 1.0 && v.abs() <= 1.0 {
                        return Some(Hit { t, object: r.object, surface: Surface::Analytic { uv: DVec2::new(u, v) } });
                    }
                }
                return None;
            }
        }
        self.intersect_all_rects(ray, t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Object, Rect};

    #[test]
    fn fast_path_agrees_with_trying_every_rectangle() {
        let scene = Scene::paper();
        let a = AnalyticRects::new(&scene).unwrap();
        assert!(a.z_sorted.is_some());
        let mut s = 7u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut hits = 0;
        let mut edge_cases = 0;
        for _ in 0..200_000 {
            let o = DVec3::new(next() * 40.0 - 20.0, next() * 40.0 - 20.0, next() * 30.0 - 10.0);
            let d = DVec3::new(next() * 0.8 - 0.4, next() * 0.8 - 0.4, next() * 1.2 - 0.2);
            let ray = Ray { origin: o, dir: d };
            let t_max = if next() < 0.2 { next() * 800.0 } else { f64::INFINITY };
            let fast = a.intersect(&ray, t_max);
            let slow = a.intersect_all_rects(&ray, t_max);
            match (fast, slow) {
                (Some(f), Some(s)) if f.object == s.object => {
                    assert!((f.t - s.t).abs() <= 1e-12 * s.t, "{ray:?}");
                    let (Surface::Analytic { uv: fu }, Surface::Analytic { uv: su }) = (f.surface, s.surface) else {
                        panic!()
                    };
                    assert!((fu - su).abs().max_element() <= 1e-12, "{ray:?}");
                }
                (None, None) => {}
                (f, s) => {
                    // Only allowed within rounding of an edge or of t_max.
                    let h = f.or(s).unwrap();
                    let Surface::Analytic { uv } = h.surface else { panic!() };
                    let near_edge = (uv.abs().max_element() - 1.0).abs() < 1e-12;
                    assert!(near_edge || (h.t - t_max).abs() < 1e-9 * t_max, "{ray:?}: {f:?} vs {s:?}");
                    edge_cases += 1;
                }
            }
            hits += fast.is_some() as usize;
        }
        assert!(hits > 50_000, "{hits}");
        assert!(edge_cases < 5, "{edge_cases}");
    }

    #[test]
    fn analytic_answers() {
        let scene = Scene::paper();
        let a = AnalyticRects::new(&scene).unwrap();
        // Straight ahead is the near chart's corner (0, 0, 300): closed edges, so it is hit.
        let h = a.intersect(&Ray { origin: DVec3::ZERO, dir: DVec3::Z }, f64::INFINITY).unwrap();
        assert_eq!((h.t, h.object), (300.0, 0));
        assert_eq!(h.surface, Surface::Analytic { uv: DVec2::ONE });
        // Slightly right of it: the centre chart's centre region at z = 400.
        let h = a.intersect(&Ray { origin: DVec3::new(1e-9, 0.0, 0.0), dir: DVec3::Z }, f64::INFINITY).unwrap();
        assert_eq!((h.t, h.object), (400.0, 1));
        // t_max excludes farther hits.
        assert!(a.intersect(&Ray { origin: DVec3::new(1e-9, 0.0, 0.0), dir: DVec3::Z }, 399.0).is_none());
        let h = a
            .intersect(&Ray { origin: DVec3::new(0.0, 0.0, 0.0), dir: DVec3::new(-0.15, -0.15, 1.0) }, f64::INFINITY)
            .unwrap();
        assert_eq!(h.object, 0);
        assert!((h.t - 300.0).abs() < 1e-12);
        // Away from the scene, and parallel to every plane.
        assert!(a.intersect(&Ray { origin: DVec3::ZERO, dir: -DVec3::Z }, f64::INFINITY).is_none());
        assert!(a.intersect(&Ray { origin: DVec3::new(0.0, 0.0, 300.0), dir: DVec3::X }, f64::INFINITY).is_none());
    }

    #[test]
    fn tilted_rectangles_use_the_general_path() {
        let mut scene = Scene::paper();
        scene.objects.push(Object {
            name: "tilted".into(),
            shape: Shape::Rect(Rect {
                center: DVec3::new(0.0, 0.0, 200.0),
                half_u: DVec3::new(10.0, 0.0, 5.0),
                half_v: DVec3::new(0.0, 10.0, 0.0),
            }),
            material: Material::Albedo(DVec3::ONE),
        });
        let a = AnalyticRects::new(&scene).unwrap();
        assert!(a.z_sorted.is_none());
        let h = a.intersect(&Ray { origin: DVec3::ZERO, dir: DVec3::Z }, f64::INFINITY).unwrap();
        assert_eq!((h.t, h.object), (200.0, 4));
    }
}
