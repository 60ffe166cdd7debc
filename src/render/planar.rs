//! A fused intersection-and-shading kernel for scenes made only of eye-facing, axis-aligned
//! rectangles with constant, chart or target (grating, slanted edge) materials: the paper's
//! scene (Sec. 4.1) and the resolution targets. It is the fast
//! path of every render of such a scene; the generic path ([`SceneTracer`] over
//! [`AnalyticRects`]) is its slow twin, and tests check they return identical radiance (the
//! kernel uses the same arithmetic as `AnalyticRects`' own fast path, so bit for bit).

use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::field::{AffineRays, BundleSum, RadianceField, RayBundle, Sample};
use super::tracer::SceneTracer;
use crate::accel::analytic::AnalyticRects;
use crate::ray::Ray;
use crate::scene::target::hit_tangent;
use crate::scene::{BarChart, Grating, Material, Scene, Shape, SlantedEdge};

#[derive(Clone, Debug)]
enum FlatMaterial {
    Albedo(DVec3),
    Chart { chart: Arc<BarChart>, bar: DVec3, backing: DVec3 },
    Grating(Grating),
    Edge(SlantedEdge),
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
    /// `None` when the scene is not made only of eye-facing axis-aligned rectangles with albedo,
    /// chart, grating or edge materials.
    pub fn new(scene: &'a Scene, backend: &'a AnalyticRects) -> Option<Self> {
        if scene.light.is_some() {
            return None; // shading needs normals and shadow rays: the generic path
        }
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
                Material::Grating(g) => FlatMaterial::Grating(*g),
                Material::Edge(e) => FlatMaterial::Edge(*e),
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

impl FlatRect {
    /// Radiance of the hit of `ray` at parameter `t`, rectangle coordinates `u`, `v`. Targets
    /// locate the hit with [`hit_tangent`], the formula `Scene::radiance` uses (bit for bit).
    #[inline(always)]
    fn shade(&self, ray: &Ray, t: f64, u: f64, v: f64) -> DVec3 {
        match &self.material {
            FlatMaterial::Grating(g) => g.at(hit_tangent(ray, t)),
            FlatMaterial::Edge(e) => e.at(hit_tangent(ray, t)),
            FlatMaterial::Albedo(a) => *a,
            FlatMaterial::Chart { chart, bar, backing } => {
                if chart.is_bar(DVec2::new(u, v)) {
                    *bar
                } else {
                    *backing
                }
            }
        }
    }
}

/// How a ray bundle meets one rectangle.
#[derive(Clone, Copy, PartialEq)]
enum Cover {
    /// No ray of the bundle can hit it.
    None,
    /// Every ray of the bundle hits it.
    All,
    /// Some may: test each ray.
    Some,
}

impl FlatRect {
    /// Bounds (world x, y) of the points where the rays of `rays` meet this rectangle's plane, at
    /// `t` past their start, widened by far more than the rounding of the rays' own arithmetic.
    #[inline(always)]
    fn footprint(&self, rays: &AffineRays, t: f64) -> (DVec2, DVec2) {
        let (lo, hi) = rays.bounds_at(t);
        let slack = (rays.magnitude_at(t) + DVec2::new(self.cx.abs(), self.cy.abs())) * 1e-12;
        (lo - slack, hi + slack)
    }

    /// How a footprint `[lo, hi]` (world x, y on this plane) meets the rectangle, with its bounds
    /// in the rectangle's `[-1, 1]` coordinates (NaN bounds give `Some`).
    #[inline(always)]
    fn cover(&self, lo: DVec2, hi: DVec2) -> (Cover, (f64, f64), (f64, f64)) {
        let (u0, u1) = ((lo.x - self.cx) * self.inv_hx, (hi.x - self.cx) * self.inv_hx);
        let (v0, v1) = ((lo.y - self.cy) * self.inv_hy, (hi.y - self.cy) * self.inv_hy);
        let (umin, umax) = (u0.min(u1), u0.max(u1));
        let (vmin, vmax) = (v0.min(v1), v0.max(v1));
        let m = BUNDLE_MARGIN;
        let cover = if umin > 1.0 + m || umax < -1.0 - m || vmin > 1.0 + m || vmax < -1.0 - m {
            Cover::None
        } else if umin >= -1.0 + m && umax <= 1.0 - m && vmin >= -1.0 + m && vmax <= 1.0 - m {
            Cover::All
        } else {
            Cover::Some
        };
        (cover, (umin, vmin), (umax, vmax))
    }
}

/// Margin (in the rectangle's [-1, 1] coordinates) by which a bundle's bounds must clear an
/// edge before all its rays are declared in or out: far above the rounding of `u`, `v`
/// (about 1e-13 here), far below a texel of the chart.
const BUNDLE_MARGIN: f64 = 1e-9;

impl FacingPlanes<'_> {
    /// Radiance and hit parameter `t` of a ray the fast path can take (`None` for a miss).
    #[inline(always)]
    fn trace_fast(&self, ray: &Ray) -> (DVec3, Option<f64>) {
        // Camera and eye rays have dz = 1; (z - oz) * (1/1) is (z - oz) exactly, so skipping the
        // division changes no bit.
        let inv_dz = if ray.dir.z == 1.0 { 1.0 } else { 1.0 / ray.dir.z };
        for r in &self.rects {
            let t = (r.z - ray.origin.z) * inv_dz;
            let u = (ray.origin.x + t * ray.dir.x - r.cx) * r.inv_hx;
            let v = (ray.origin.y + t * ray.dir.y - r.cy) * r.inv_hy;
            if u.abs() <= 1.0 && v.abs() <= 1.0 {
                return (r.shade(ray, t, u, v), Some(t));
            }
        }
        (self.background, None)
    }

    #[inline(always)]
    fn takes(&self, ray: &Ray) -> bool {
        ray.dir.z > 0.0 && ray.origin.z < self.min_z
    }
}

/// World distance of a hit at parameter `t` (as [`SceneTracer`] reports it), `+inf` for a miss.
#[inline(always)]
fn distance(ray: &Ray, t: Option<f64>) -> f64 {
    t.map_or(f64::INFINITY, |t| t * ray.dir.length())
}

impl RadianceField for FacingPlanes<'_> {
    #[inline(always)]
    fn radiance(&self, ray: &Ray) -> DVec3 {
        if !self.takes(ray) {
            return self.fallback.radiance(ray);
        }
        self.trace_fast(ray).0
    }

    #[inline(always)]
    fn sample(&self, ray: &Ray) -> Sample {
        if !self.takes(ray) {
            return self.fallback.sample(ray);
        }
        let (radiance, t) = self.trace_fast(ray);
        Sample { radiance, depth: distance(ray, t) }
    }

    /// Bounds on the family's footprint on each rectangle, in z order (with margins far above
    /// the rounding of the rays' own arithmetic): rectangles no ray can hit are passed; the first
    /// that might be hit must hold the whole footprint, inside one colour (an albedo, or a chart
    /// grid cell that is all bar or all backing, [`BarChart::uniform_in`]).
    fn uniform(&self, rays: &AffineRays) -> Option<(DVec3, Option<f64>)> {
        if rays.origin.z >= self.min_z || rays.origin.z.is_nan() {
            return None;
        }
        let m = BUNDLE_MARGIN;
        for r in &self.rects {
            let t = r.z - rays.origin.z;
            let (lo, hi) = r.footprint(rays, t);
            let (cover, (umin, vmin), (umax, vmax)) = r.cover(lo, hi);
            match cover {
                Cover::None => continue,    // no ray meets r
                Cover::Some => return None, // some rays may meet r, others not (or NaN)
                Cover::All => {}
            }
            let radiance = match &r.material {
                FlatMaterial::Albedo(a) => *a,
                FlatMaterial::Chart { chart, bar, backing } => {
                    let on = chart.uniform_in(DVec2::new(umin - m, vmin - m), DVec2::new(umax + m, vmax + m))?;
                    if on {
                        *bar
                    } else {
                        *backing
                    }
                }
                FlatMaterial::Grating(_) | FlatMaterial::Edge(_) => return None,
            };
            return Some((radiance, Some(t)));
        }
        Some((self.background, None))
    }

    /// Bundle culling: bounds on the bundle's footprint on each rectangle (from the bounds of
    /// its start and slope shifts) show which rectangles no ray can hit and which one every ray
    /// hits first; each ray then computes `t`, `u`, `v` exactly as the single-ray path does,
    /// so the sums are the same bit for bit (tested).
    fn sample_sum(&self, base: &Ray, bundle: &RayBundle) -> BundleSum {
        let mut acc = BundleSum::default();
        let affine = bundle.affine_around(base);
        if let Some((radiance, t)) = affine.as_ref().and_then(|rays| self.uniform(rays)) {
            // Every ray brings back `radiance` from the same plane: only the distances differ,
            // found in passes that vectorise (their square roots dominate).
            let mut depths = [0.0; 64];
            for k0 in (0..bundle.shifts.len()).step_by(depths.len()) {
                let ks = k0..bundle.shifts.len().min(k0 + depths.len());
                for (d, k) in depths.iter_mut().zip(ks.clone()) {
                    *d = distance(&bundle.ray(base, k), t);
                }
                for &depth in &depths[..ks.len()] {
                    acc.add(Sample { radiance, depth });
                }
            }
            return acc;
        }
        if !(base.dir.z == 1.0 && base.origin.z < self.min_z) || self.rects.len() > 16 {
            for k in 0..bundle.shifts.len() {
                acc.add(self.sample(&bundle.ray(base, k)));
            }
            return acc;
        }
        let mut cover = [Cover::None; 16];
        let mut last = self.rects.len();
        for (i, r) in self.rects.iter().enumerate() {
            let t = r.z - base.origin.z; // > 0: the bundle starts in front of every plane
            let (lo, hi) = match &affine {
                // Tight: start and slope shifts move together.
                Some(rays) => r.footprint(rays, t),
                None => {
                    let start = DVec2::new(base.origin.x, base.origin.y);
                    let lo = start + bundle.start_min + (base.dir.truncate() + bundle.slope_min) * t;
                    let hi = start + bundle.start_max + (base.dir.truncate() + bundle.slope_max) * t;
                    (lo, hi)
                }
            };
            cover[i] = r.cover(lo, hi).0;
            if cover[i] == Cover::All {
                last = i + 1;
                break;
            }
        }
        'rays: for k in 0..bundle.shifts.len() {
            let ray = bundle.ray(base, k);
            for (r, c) in self.rects[..last].iter().zip(&cover[..last]) {
                if *c == Cover::None {
                    continue;
                }
                // dz = 1 here, so t needs no division (see trace_fast).
                let t = r.z - ray.origin.z;
                let u = (ray.origin.x + t * ray.dir.x - r.cx) * r.inv_hx;
                let v = (ray.origin.y + t * ray.dir.y - r.cy) * r.inv_hy;
                if *c == Cover::All || (u.abs() <= 1.0 && v.abs() <= 1.0) {
                    acc.add(Sample { radiance: r.shade(&ray, t, u, v), depth: distance(&ray, Some(t)) });
                    continue 'rays;
                }
            }
            acc.add(Sample { radiance: self.background, depth: f64::INFINITY });
        }
        acc
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
            assert_eq!(fast.sample(&ray), slow.sample(&ray), "{ray:?}");
            dark += (a == DVec3::ZERO) as usize;
        }
        assert!(dark > 1000, "bars and misses are exercised: {dark}");
    }

    #[test]
    fn bundle_culling_sums_exactly_what_single_rays_sum() {
        let scene = Scene::paper();
        let backend = AnalyticRects::new(&scene).unwrap();
        let fast = FacingPlanes::new(&scene, &backend).unwrap();
        let slow = SceneTracer { scene: &scene, backend: &backend };
        let mut s = 5u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        // The paper's LA 5 x 5 bundle (most footprints inside one chart cell: the uniform path),
        // the same without its affine form (bounds from the shifts only), one with ten times its
        // spread, and a 9 x 9 one (more rays than one pass of distances holds).
        let bundle = |k: usize, scale: f64| {
            let mut points = Vec::new();
            for j in 0..k {
                for i in 0..k {
                    points.push(DVec2::new(i as f64 - (k / 2) as f64, j as f64 - (k / 2) as f64) * 0.24 * scale);
                }
            }
            RayBundle::lenslet_points(&points, 1.0 / 6.427 - 1.0 / 6.316, 20.0)
        };
        let plain = RayBundle::new(bundle(5, 1.0).shifts);
        for bundle in [bundle(5, 1.0), plain, bundle(5, 10.0), bundle(9, 0.5)] {
            for _ in 0..60_000 {
                let base = Ray {
                    origin: DVec3::new(next() * 30.0 - 15.0, next() * 30.0 - 15.0, 0.0),
                    dir: DVec3::new(next() * 0.7 - 0.35, next() * 0.7 - 0.35, 1.0),
                };
                assert_eq!(fast.sample_sum(&base, &bundle), slow.sample_sum(&base, &bundle), "{base:?}");
            }
        }
    }

    #[test]
    fn fused_kernel_equals_the_generic_path_on_targets() {
        use crate::scene::{Object, Rect};
        let rect = |c: DVec3, w: f64, material| Object {
            name: "t".into(),
            shape: Shape::Rect(Rect::facing_eye(c, w, w)),
            material,
        };
        let g = Grating { frequency_cpd: 7.0, orientation_deg: 30.0, mean: 0.4, contrast: 0.9, phase_deg: 10.0 };
        let e = SlantedEdge { through: DVec2::new(0.01, -0.02), angle_deg: 5.0, low: 0.05, high: 0.95 };
        let scene = Scene {
            name: "targets".into(),
            objects: vec![
                rect(DVec3::new(-20.0, 0.0, 300.0), 60.0, Material::Grating(g)),
                rect(DVec3::new(20.0, 10.0, 500.0), 200.0, Material::Edge(e)),
                rect(DVec3::new(0.0, 0.0, 900.0), 2000.0, Material::Albedo(DVec3::splat(0.3))),
            ],
            background: DVec3::ZERO,
            light: None,
            warnings: Vec::new(),
        };
        let backend = AnalyticRects::new(&scene).unwrap();
        let fast = FacingPlanes::new(&scene, &backend).unwrap();
        let slow = SceneTracer { scene: &scene, backend: &backend };
        let mut rng = crate::fixtures::Lcg(17);
        let (mut grey, mut lit) = (0, 0);
        for _ in 0..200_000 {
            let ray = Ray {
                origin: DVec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-20.0, 20.0)),
                dir: DVec3::new(
                    rng.range(-0.3, 0.3),
                    rng.range(-0.3, 0.3),
                    if rng.next() < 0.5 { 1.0 } else { rng.range(0.5, 1.5) },
                ),
            };
            let a = fast.sample(&ray);
            assert_eq!(a, slow.sample(&ray), "{ray:?}");
            grey += (a.radiance.x != 0.3 && a.radiance.x != 0.05 && a.radiance.x != 0.95) as usize;
            lit += (a.radiance.x == 0.95) as usize;
        }
        assert!(grey > 1000 && lit > 1000, "both targets are exercised: {grey} {lit}");
        let shifts =
            (0..9).map(|i| (DVec2::new(i as f64 * 0.3 - 1.2, 0.1), DVec2::new(0.001 * i as f64, -0.002))).collect();
        let bundle = RayBundle::new(shifts);
        for _ in 0..20_000 {
            let base = Ray {
                origin: DVec3::new(rng.range(-10.0, 10.0), rng.range(-10.0, 10.0), 0.0),
                dir: DVec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 1.0),
            };
            assert_eq!(fast.sample_sum(&base, &bundle), slow.sample_sum(&base, &bundle), "{base:?}");
        }
    }
}
