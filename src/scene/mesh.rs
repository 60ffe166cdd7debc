//! Triangle meshes: the geometry that the mesh backends (Embree, pure-Rust BVH) intersect.
//!
//! Positions are `f64` millimetres in world space (transforms already applied). Backends that
//! work in `f32` (Embree) convert at their own boundary.

use glam::{DVec2, DVec3};

/// An indexed triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex shading normals, when known.
    pub normals: Option<Vec<DVec3>>,
    /// Per-vertex texture coordinates, when known.
    pub uvs: Option<Vec<DVec2>>,
    /// Per-vertex linear RGB colours, when known.
    pub colors: Option<Vec<DVec3>>,
}

impl Mesh {
    /// Interpolates a per-vertex attribute at barycentric coordinates (u, v) of triangle `tri`:
    /// value = (1 - u - v) a0 + u a1 + v a2 (Embree's convention).
    pub fn interpolate<T>(&self, attr: &[T], tri: u32, bary: DVec2) -> T
    where
        T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
    {
        let [i0, i1, i2] = self.triangles[tri as usize];
        attr[i0 as usize] * (1.0 - bary.x - bary.y) + attr[i1 as usize] * bary.x + attr[i2 as usize] * bary.y
    }
}
