//! A fused intersection-and-shading kernel for scenes made only of eye-facing, axis-aligned
//! rectangles with constant or chart materials: the paper's scene (Sec. 4.1). It is the fast
//! path of every render of such a scene; the generic path ([`SceneTracer`] over
//! [`AnalyticRects`]) is its slow twin, and tests check they return identical radiance (the
//! kernel uses the same arithmetic as `AnalyticRects`' own fast path, so bit for bit).

use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::display_image::{RadianceField, SceneTracer};
use crate::accel::analytic::AnalyticRects;
use crate::accel::Ray;
use crate::scene::{BarChart, Material, Scene, Shape};

#[derive(Clone, Debug)]
enum FlatMaterial {
    Albedo(DVec3),
    Chart { chart: Arc<BarChart>, bar: DVec3, backing: DVec3 },
}

#[derive(Clone, Debug)]
struct FlatRect {
    z: f64,
    cx: f64,
    cy: f64,
    inv_hx: f64,
    inv_hy: f64,
    material: FlatMaterial,
}

/// The fused kernel. Rays it cannot take (not travelling toward +z from in front of every
/// rectangle) go to the generic path.
pub struct FacingPlanes<'a> {
    rects: Vec<FlatRect>,
    min_z: f64,
    background: DVec3,
    fallback: SceneTracer<'a, AnalyticRects>,
}

impl<'a> FacingPlanes<'a> {
    /// `None` when the scene is not made only of eye-facing axis-aligned rectangles with albedo
    /// or chart materials.
    pub fn new(scene: &'a Scene, backend: &'a AnalyticRects) -> Option<Self> {
        let mut rects = Vec::with_capacity(scene.objects.len());
        for (k, o) in scene.objects.iter().enumerate() {
            let Shape::Rect(r) = &o.shape else { return None };
            if !(r.half_u.y == 0.0 && r.half_u.z == 0.0 && r.half_v.x == 0.0 && r.half_v.z == 0.0) {
                return None;
            }
            let material = match &o.material {
                Material::Albedo(a) => FlatMaterial::Albedo(*a),
                Material::Chart { chart, bar, backing } => {
                    FlatMaterial::Chart { chart: chart.clone(), bar: *bar, backing: *backing }
                }
                Material::VertexColor | Material::Texture(_) => return None,
            };
            rects.push((
                k,
                FlatRect {
                    z: r.center.z,
                    cx: r.center.x,
                    cy: r.center.y,
                    inv_hx: 1.0 / r.half_u.x,
                    inv_hy: 1.0 / r.half_v.y,
                    material,
                },
            ));
        }
        // Same order as AnalyticRects: by z, then object index.
        rects.sort_by(|a, b| a.1.z.total_cmp(&b.1.z).then(a.0.cmp(&b.0)));
        let min_z = rects.iter().map(|r| r.1.z).fold(f64::INFINITY, f64::min);
        Some(Self {
            rects: rects.into_iter().map(|r| r.1).collect(),
            min_z,
            background: scene.background,
            fallback: SceneTracer { scene, backend },
        })
    }
}

impl RadianceField for FacingPlanes<'_> {
    #[inline]
    fn radiance(&self, ray: &Ray) -> DVec3 {
        if !(ray.dir.z > 0.0 && ray.origin.z < self.min_z) {
            return self.fallback.radiance(ray);
        }
        // Camera and eye rays have dz = 1; (z - oz) * (1/1) is (z - oz) exactly, so skipping the
        // division changes no bit.
        let inv_dz = if ray.dir.z == 1.0 { 1.0 } else { 1.0 / ray.dir.z };
        for r in &self.rects {
            let t = (r.z - ray.origin.z) * inv_dz;
            let u = (ray.origin.x + t * ray.dir.x - r.cx) * r.inv_hx;
            let v = (ray.origin.y + t * ray.dir.y - r.cy) * r.inv_hy;
            if u.abs() <= 1.0 && v.abs() <= 1.0 {
                return match &r.material {
                    FlatMaterial::Albedo(a) => *a,
                    FlatMaterial::Chart { chart, bar, backing } => {
                        if chart.is_bar(DVec2::new(u, v)) {
                            *bar
                        } else {
                            *backing
                        }
                    }
                };
            }
        }
        self.background
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fused_kernel_equals_the_generic_path_bit_for_bit() {
        let scene = Scene::paper();
        let backend = AnalyticRects::new(&scene).unwrap();
        let fast = FacingPlanes::new(&scene, &backend).unwrap();
        let slow = SceneTracer { scene: &scene, backend: &backend };
        let mut s = 99u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut dark = 0;
        for _ in 0..300_000 {
            let ray = Ray {
                origin: DVec3::new(next() * 20.0 - 10.0, next() * 20.0 - 10.0, next() * 40.0 - 20.0),
                dir: DVec3::new(next() * 0.7 - 0.35, next() * 0.7 - 0.35, next() * 1.1 - 0.1),
            };
            let a = fast.radiance(&ray);
            assert_eq!(a, slow.radiance(&ray), "{ray:?}");
            dark += (a == DVec3::ZERO) as usize;
        }
        assert!(dark > 1000, "bars and misses are exercised: {dark}");
    }
}
