//! The generic radiance field: a scene and the backend that intersects it (paper Sec. 3.1: each
//! ray is traversed until it hits an object, and the object's colour is what the ray sees), with
//! the shading of what it hits ([`shade`]), which traces shadow rays when the scene has a light.

use glam::DVec3;

use super::field::{RadianceField, Sample};
use crate::ray::{Hit, Intersector, Ray};
use crate::scene::Scene;

/// A scene and the backend that intersects it. Generic so that hot loops inline a concrete
/// backend; `SceneTracer<'_, dyn Intersector>` works for any backend chosen at run time.
pub struct SceneTracer<'a, I: Intersector + ?Sized = dyn Intersector> {
    /// The scene: materials, light and background.
    pub scene: &'a Scene,
    /// The backend that intersects the scene's geometry.
    pub backend: &'a I,
}

impl<I: Intersector + ?Sized> Clone for SceneTracer<'_, I> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<I: Intersector + ?Sized> Copy for SceneTracer<'_, I> {}

/// World distance of a hit at ray parameter `t` (`+inf` for a miss).
#[inline]
fn hit_distance(ray: &Ray, t: Option<f64>) -> f64 {
    t.map_or(f64::INFINITY, |t| t * ray.dir.length())
}

impl<I: Intersector + ?Sized> RadianceField for SceneTracer<'_, I> {
    #[inline]
    fn radiance(&self, ray: &Ray) -> DVec3 {
        shade(self.scene, ray, self.backend.intersect(ray, f64::INFINITY).as_ref(), self.backend)
    }

    #[inline]
    fn sample(&self, ray: &Ray) -> Sample {
        let hit = self.backend.intersect(ray, f64::INFINITY);
        Sample {
            radiance: shade(self.scene, ray, hit.as_ref(), self.backend),
            depth: hit_distance(ray, hit.map(|h| h.t)),
        }
    }

    fn prefers_batches(&self) -> bool {
        self.backend.prefers_batches()
    }

    /// Intersects the whole batch with [`Intersector::intersect_many`] (packets on coherent
    /// runs for backends that have them), then shades.
    fn sample_many(&self, rays: &[Ray], out: &mut [Sample]) {
        // Chunks of 256 (a multiple of the 16-ray packet) with the hits on the stack.
        const CHUNK: usize = 256;
        let mut hits = [None; CHUNK];
        for (rays, out) in rays.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let hits = &mut hits[..rays.len()];
            self.backend.intersect_many(rays, hits);
            for ((ray, hit), o) in rays.iter().zip(hits.iter()).zip(out.iter_mut()) {
                *o = Sample {
                    radiance: shade(self.scene, ray, hit.as_ref(), self.backend),
                    depth: hit_distance(ray, hit.map(|h| h.t)),
                };
            }
        }
    }
}

/// Radiance leaving the hit of `ray` in `scene` toward the ray's origin. Without a light it is the
/// albedo ([`Scene::radiance`]), exactly. With a distant light it is
/// `albedo * light.radiance * max(0, dot(n, -light.direction))` with `n` the normal facing
/// the ray ([`Scene::normal`]), or zero when a shadow ray toward the light (through
/// `backend.occluded`) is blocked. The shadow ray starts a small distance off the surface
/// along `n` (1e-4 of the hit point's largest coordinate, at least 1e-4 mm) so that
/// rounding of the hit point (f32 in Embree) does not shadow the surface itself.
pub fn shade<I: Intersector + ?Sized>(scene: &Scene, ray: &Ray, hit: Option<&Hit>, backend: &I) -> DVec3 {
    let albedo = scene.radiance(ray, hit);
    let (Some(light), Some(hit)) = (scene.light, hit) else { return albedo };
    let n = scene.normal(ray, hit);
    let to_light = -light.direction;
    let cos = n.dot(to_light);
    if cos.is_nan() || cos <= 0.0 {
        return DVec3::ZERO;
    }
    let p = ray.origin + hit.t * ray.dir;
    let eps = 1e-4 * p.abs().max_element().max(1.0);
    let shadow = Ray { origin: p + eps * n, dir: to_light };
    if backend.occluded(&shadow, f64::INFINITY) {
        return DVec3::ZERO;
    }
    albedo * light.radiance * cos
}
