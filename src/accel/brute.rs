//! Brute-force triangle intersection: every ray is tested against every triangle of every mesh
//! (paper Sec. 3.1, "each ray is traversed until it hits an object", done the slow way).
//!
//! This backend is the obviously correct reference that every faster mesh backend (the
//! pure-Rust BVH, Embree) is tested against. It uses the shared watertight triangle test and
//! nearest-hit rule of [`super::triangle`].

use glam::DVec3;

use super::triangle::{NearestHit, WatertightRay};
use crate::error::Result;
use crate::ray::{Hit, Intersector, Ray};
use crate::scene::mesh::Mesh;

/// One triangle with its world-space corners, ready for testing.
#[derive(Clone, Copy, Debug)]
struct Tri {
    p: [DVec3; 3],
    object: u32,
    index: u32,
}

/// Tests every ray against every triangle. Slow (O(triangles) per ray), exact in its tie-breaking,
/// and meant as the reference for faster backends and for tiny scenes.
#[derive(Clone, Debug)]
pub struct BruteForce {
    tris: Vec<Tri>,
}

impl BruteForce {
    /// Copies the triangles of `meshes`; each entry is `(scene object index, mesh)`, and the
    /// object index is what [`Hit::object`] reports. Every mesh is validated first (indices in
    /// range, finite positions); an empty list gives a backend that hits nothing.
    pub fn new(meshes: &[(u32, &Mesh)]) -> Result<Self> {
        let mut tris = Vec::new();
        for &(object, mesh) in meshes {
            mesh.validate(&format!("scene object {object}"))?;
            tris.extend((0..mesh.triangles.len()).map(|i| Tri {
                p: mesh.triangle_positions(i),
                object,
                index: i as u32,
            }));
        }
        Ok(BruteForce { tris })
    }

    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }
}

impl Intersector for BruteForce {
    fn name(&self) -> &'static str {
        "brute"
    }

    /// Nearest hit with `0 < t < t_max`. Equal `t` is broken deterministically: lowest object
    /// index, then lowest triangle index.
    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        let wray = WatertightRay::new(ray)?;
        let mut best = NearestHit::default();
        for tri in &self.tris {
            // The original t_max, not the best t so far, so that exact ties are seen.
            if let Some((t, bary)) = wray.intersect(tri.p[0], tri.p[1], tri.p[2], t_max) {
                best.offer(t, tri.object, tri.index, bary);
            }
        }
        best.hit()
    }

    fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        let Some(wray) = WatertightRay::new(ray) else {
            return false;
        };
        self.tris.iter().any(|tri| wray.intersect(tri.p[0], tri.p[1], tri.p[2], t_max).is_some())
    }
}
