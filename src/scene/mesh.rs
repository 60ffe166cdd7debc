//! Triangle meshes: the geometry that the mesh backends (Embree, pure-Rust BVH) intersect.
//!
//! Positions are `f64` millimetres in world space (transforms already applied). Backends that
//! work in `f32` (Embree) convert at their own boundary.
//!
//! Besides the data type this file owns the mesh-level checks (bounds, validation, removal of
//! zero-area triangles) and [`tessellate_rect`], which turns the paper's planar rectangular
//! scene objects (Sec. 3.1) into triangles so that mesh backends can be checked against the
//! analytic one.

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};

/// An indexed triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, world mm.
    pub positions: Vec<DVec3>,
    /// Vertex indices of each triangle.
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

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `tri`. Panics if `tri` or its indices are out of
    /// range (call [`Mesh::validate`] on untrusted meshes first).
    pub fn triangle_positions(&self, tri: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[tri];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Axis-aligned bounds `(min, max)` of all vertex positions. An empty mesh gives the empty
    /// box `(+inf, -inf)`.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
    }

    /// Checks that the mesh can be intersected and shaded: at least one triangle, every index in
    /// range, finite positions, and per-vertex attributes (when present) with one finite entry
    /// per position. Errors name `source_name` and the offending triangle or vertex.
    pub fn validate(&self, source_name: &str) -> Result<()> {
        if self.triangles.is_empty() {
            return Err(Error::invalid(source_name, "triangles", "mesh has no triangles"));
        }
        let n = self.positions.len();
        for (i, p) in self.positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(Error::invalid(
                    source_name,
                    format!("vertex {i}"),
                    format!("non-finite position ({}, {}, {})", p.x, p.y, p.z),
                ));
            }
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            for (k, &idx) in tri.iter().enumerate() {
                if idx as usize >= n {
                    return Err(Error::invalid(
                        source_name,
                        format!("triangle {t}"),
                        format!("corner {k} has vertex index {idx}, out of range (mesh has {n} vertices)"),
                    ));
                }
            }
        }
        fn check_attr<T>(
            source_name: &str,
            name: &str,
            attr: &Option<Vec<T>>,
            n: usize,
            finite: impl Fn(&T) -> bool,
        ) -> Result<()> {
            if let Some(values) = attr {
                if values.len() != n {
                    return Err(Error::invalid(
                        source_name,
                        name,
                        format!("{} entries for {n} vertices", values.len()),
                    ));
                }
                if let Some(i) = values.iter().position(|v| !finite(v)) {
                    return Err(Error::invalid(source_name, format!("{name} of vertex {i}"), "non-finite value"));
                }
            }
            Ok(())
        }
        check_attr(source_name, "normals", &self.normals, n, |v| v.is_finite())?;
        check_attr(source_name, "uvs", &self.uvs, n, |v| v.is_finite())?;
        check_attr(source_name, "colors", &self.colors, n, |v| v.is_finite())?;
        Ok(())
    }

    /// True when triangle `tri` has zero area as computed in `f64`: a repeated vertex index or
    /// a cross product of its edges that is exactly zero. Such triangles cannot be hit by a
    /// ray (the watertight test rejects them as parallel) and have no defined normal.
    pub fn is_degenerate(&self, tri: usize) -> bool {
        let [a, b, c] = self.triangles[tri];
        if a == b || b == c || a == c {
            return true;
        }
        let [p0, p1, p2] = self.triangle_positions(tri);
        (p1 - p0).cross(p2 - p0) == DVec3::ZERO
    }

    /// Removes zero-area triangles (see [`Mesh::is_degenerate`]), keeping the order of the
    /// others, and returns how many were removed. Vertices are kept as they are.
    pub fn remove_degenerate(&mut self) -> usize {
        let before = self.triangles.len();
        let keep: Vec<bool> = (0..before).map(|t| !self.is_degenerate(t)).collect();
        let mut k = keep.iter();
        self.triangles.retain(|_| *k.next().unwrap_or(&true));
        before - self.triangles.len()
    }
}

/// Tessellates the planar rectangle `center + s * half_u + t * half_v`, `s, t` in `[-1, 1]`, into
/// an `n x n` grid of quads, two triangles each (`n` below 1 is taken as 1).
///
/// Vertex `(i, j)` (`i` along `half_u`, `j` along `half_v`, both `0..=n`) has index
/// `j * (n + 1) + i`, uv `(s, t) = (2 i / n - 1, 2 j / n - 1)` (the analytic rectangle's local
/// coordinates, so interpolating uvs at a hit recovers them exactly up to rounding) and normal
/// `normalize(half_u x half_v)`. Triangles wind counter-clockwise in `(s, t)`, so their geometric
/// normal points along `half_u x half_v` too.
pub fn tessellate_rect(center: DVec3, half_u: DVec3, half_v: DVec3, n: usize) -> Mesh {
    let n = n.max(1);
    let side = n + 1;
    let normal = half_u.cross(half_v).normalize_or_zero();
    let mut positions = Vec::with_capacity(side * side);
    let mut uvs = Vec::with_capacity(side * side);
    for j in 0..side {
        let t = 2.0 * j as f64 / n as f64 - 1.0;
        for i in 0..side {
            let s = 2.0 * i as f64 / n as f64 - 1.0;
            positions.push(center + s * half_u + t * half_v);
            uvs.push(DVec2::new(s, t));
        }
    }
    let mut triangles = Vec::with_capacity(2 * n * n);
    let idx = |i: usize, j: usize| (j * side + i) as u32;
    for j in 0..n {
        for i in 0..n {
            let (v00, v10, v11, v01) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            triangles.push([v00, v10, v11]);
            triangles.push([v00, v11, v01]);
        }
    }
    let normals = vec![normal; positions.len()];
    Mesh { positions, triangles, normals: Some(normals), uvs: Some(uvs), colors: None }
}
