//! [`EmbreeIntersector`]: the Embree backend of [`Intersector`] for inimtrace's triangle meshes
//! (paper Sec. 3.1, tracing rays into the 3D scene). This is where the `f64` optics meets
//! Embree's `f32`: positions and rays are rounded to single precision on the way in, and hit
//! parameters are widened back to `f64` on the way out.

use std::time::Instant;

use glam::{DVec2, DVec3};

use super::device::Device;
use super::geometry::TriangleGeometry;
use super::ray::{RawHit, RawRay};
use super::scene::{BuildQuality, Scene, SceneBuilder};
use crate::error::Result;
use crate::ray::{Hit, Intersector, Ray, Surface};
use crate::scene::mesh::Mesh;

/// Rays per packet in [`Intersector::intersect_many`].
const PACKET: usize = 16;

/// A 16-ray chunk is traced as a packet when its rays' spread, measured as the largest
/// distance between unit directions plus the largest origin distance over the scene's
/// diagonal, is below this. Measured on Embree 3.13.5 (1024-pixel camera rows over a 360k
/// triangle sphere): packets win ~2.3x at a spread of 0.008 and lose from ~0.1 on (incoherent
/// rays: ~2x slower than single rays).
const COHERENT_SPREAD: f64 = 0.06;

/// Triangle meshes in one committed Embree scene.
pub struct EmbreeIntersector {
    scene: Scene,
    /// Scene object index for each Embree geometry ID (`u32::MAX` for unused IDs).
    objects: Vec<u32>,
    /// Diagonal of the scenes's bounding box (mm), the length scale for ray coherence.
    extent: f64,
    build_seconds: f64,
}

impl std::fmt::Debug for EmbreeIntersector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmbreeIntersector")
            .field("scene", &self.scene)
            .field("build_seconds", &self.build_seconds)
            .finish_non_exhaustive()
    }
}

impl EmbreeIntersector {
    /// Builds one Embree scene (on a new device) from `meshes`, each paired with the scene
    /// object index that hits on it report as [`Hit::object`].
    ///
    /// Errors name the object and the element: a vertex that is NaN, infinite or beyond the
    /// `f32` range, a triangle index past the vertex count ([`crate::Error::Invalid`]), or
    /// anything Embree itself rejects ([`crate::Error::Embree`]).
    pub fn new(meshes: &[(u32, &Mesh)], quality: BuildQuality) -> Result<EmbreeIntersector> {
        let device = Device::new()?;
        EmbreeIntersector::with_device(&device, meshes, quality)
    }

    /// As [`EmbreeIntersector::new`], on an existing device.
    pub fn with_device(device: &Device, meshes: &[(u32, &Mesh)], quality: BuildQuality) -> Result<EmbreeIntersector> {
        let start = Instant::now();
        let mut builder = SceneBuilder::new(device, quality)?;
        let mut objects = Vec::with_capacity(meshes.len());
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &(object, mesh) in meshes {
            // f64 -> f32 at the Embree boundary: Embree stores and intersects single-precision
            // vertices. World coordinates are millimetres, so rounding costs ~1e-7 relative.
            let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.as_vec3().to_array()).collect();
            let name = format!("mesh of scene object {object}");
            let geometry = TriangleGeometry::new(device, &positions, &mesh.triangles, quality, &name)?;
            let id = builder.attach(geometry)? as usize;
            if objects.len() <= id {
                objects.resize(id + 1, u32::MAX);
            }
            objects[id] = object;
            for p in &mesh.positions {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        let scene = builder.commit()?;
        let extent = if lo.cmple(hi).all() { (hi - lo).length() } else { 0.0 };
        Ok(EmbreeIntersector { scene, objects, extent, build_seconds: start.elapsed().as_secs_f64() })
    }

    /// Wall-clock seconds that [`EmbreeIntersector::new`] took after the device existed:
    /// converting and copying the meshes plus building the BVH.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// Total number of triangles in the scene.
    pub fn triangle_count(&self) -> usize {
        self.scene.triangle_count()
    }

    /// The underlying committed Embree scene (for `f32`-level queries).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Whether a chunk of rays is coherent enough for a packet to beat single rays. Only the
    /// middle and last rays are compared with the first (the pipeline's batches are runs of
    /// neighbouring pixels, so a chunk's spread shows at its ends); a wrong guess costs speed,
    /// never correctness, since packets and single rays give the same hits.
    fn coherent(&self, rays: &[Ray]) -> bool {
        let Some(first) = rays.first() else {
            return false;
        };
        // Spread of unit directions, |u - u0|^2 = 2 - 2 cos, and of origins.
        let u0 = first.dir.normalize_or_zero();
        let mut cos_min = 1.0f64;
        let mut origin_spread2 = 0.0f64;
        for r in [&rays[rays.len() / 2], &rays[rays.len() - 1]] {
            cos_min = cos_min.min(r.dir.dot(u0) / r.dir.length());
            origin_spread2 = origin_spread2.max((r.origin - first.origin).length_squared());
        }
        let dir_spread = (2.0 - 2.0 * cos_min).max(0.0).sqrt();
        let spread = dir_spread + origin_spread2.sqrt() / self.extent.max(f64::MIN_POSITIVE);
        // NaN (non-finite rays) compares false: such chunks go one ray at a time.
        spread < COHERENT_SPREAD
    }

    /// For each run of 16 consecutive rays of `rays` (the last run may be shorter), whether
    /// [`Intersector::intersect_many`] traces it as one packet (`true`) or one ray at a time.
    pub fn packet_plan(&self, rays: &[Ray]) -> Vec<bool> {
        rays.chunks(PACKET).map(|chunk| self.coherent(chunk)).collect()
    }

    fn to_hit(&self, raw: RawHit) -> Option<Hit> {
        let object = *self.objects.get(raw.geom_id as usize)?;
        Some(Hit {
            // f32 -> f64: `t` is in units of the ray's (unnormalised) `dir`, as for every backend.
            t: f64::from(raw.t),
            object,
            surface: Surface::Triangle { index: raw.prim_id, bary: DVec2::new(f64::from(raw.u), f64::from(raw.v)) },
        })
    }
}

/// The largest `f32` that is `<= x` (for `x > 0`), so that rounding never lets Embree look
/// past the caller's `t_max`. `+inf` stays `+inf`.
fn f32_at_most(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x && f > 0.0 {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f
    }
}

/// f64 -> f32 at the Embree boundary: origin and direction are rounded to single precision,
/// `dir` keeps its length so that Embree's `t` is in the caller's units; `tnear = 0`.
pub fn raw_ray(ray: &Ray, t_max: f64) -> RawRay {
    RawRay {
        org: ray.origin.as_vec3().to_array(),
        dir: ray.dir.as_vec3().to_array(),
        tnear: 0.0,
        tfar: f32_at_most(t_max),
    }
}

impl Intersector for EmbreeIntersector {
    fn name(&self) -> &'static str {
        "embree"
    }

    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        if t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        self.scene.intersect1(&raw_ray(ray, t_max)).and_then(|h| self.to_hit(h))
    }

    /// Traces each run of 16 consecutive rays as one packet (`rtcIntersect16` with the
    /// coherent-rays hint) when the run is coherent (similar directions, nearby origins), which
    /// is ~2x faster than `rtcIntersect1` per ray; incoherent runs, where packets are slower,
    /// go one ray at a time. Same hits either way.
    fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        debug_assert_eq!(rays.len(), hits.len(), "intersect_many: rays and hits differ in length");
        let n = rays.len().min(hits.len());
        let blank = RawRay { org: [0.0; 3], dir: [0.0; 3], tnear: 0.0, tfar: 0.0 };
        let mut packet = [blank; PACKET];
        let mut found: [Option<RawHit>; PACKET] = [None; PACKET];
        for (ray_chunk, hit_chunk) in rays[..n].chunks(PACKET).zip(hits[..n].chunks_mut(PACKET)) {
            let m = ray_chunk.len();
            if !self.coherent(ray_chunk) {
                for (hit, ray) in hit_chunk.iter_mut().zip(ray_chunk) {
                    *hit = self.intersect(ray, f64::INFINITY);
                }
                continue;
            }
            for (slot, ray) in packet.iter_mut().zip(ray_chunk) {
                *slot = raw_ray(ray, f64::INFINITY);
            }
            self.scene.intersect16(&packet[..m], &mut found[..m], true);
            for (hit, raw) in hit_chunk.iter_mut().zip(&found[..m]) {
                *hit = raw.and_then(|h| self.to_hit(h));
            }
        }
    }

    fn prefers_batches(&self) -> bool {
        true
    }

    fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        if t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        self.scene.occluded1(&raw_ray(ray, t_max))
    }
}

#[cfg(test)]
mod tests {
    use super::f32_at_most;

    #[test]
    fn f32_at_most_never_rounds_up() {
        for &x in &[0.1f64, 1.0 / 3.0, 1e-30, 12345.678901, 1e39, f64::MAX] {
            let f = f32_at_most(x);
            assert!(f64::from(f) <= x, "{x} -> {f}");
            assert!(f64::from(f32::from_bits(f.to_bits() + 1)) > x || f == f32::MAX, "{x} -> {f} not the largest");
        }
        assert_eq!(f32_at_most(f64::INFINITY), f32::INFINITY);
        assert_eq!(f32_at_most(2.0), 2.0);
    }
}
