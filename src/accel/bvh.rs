//! [`BvhIntersector`]: the pure-Rust triangle-mesh backend (paper Sec. 3.1, "each ray is traversed
//! until it hits an object"), with no C dependency. It intersects exactly the triangles that the
//! Embree backend is given, and its hits are those of the brute-force reference
//! ([`crate::accel::brute::BruteForce`]): same triangle, same `t`, same barycentrics, same
//! tie-breaking.
//!
//! The hierarchy is inimtrace's own 4-wide BVH ([`crate::accel::bvh4`], the default
//! [`BvhLayout::Bvh4`]); the `obvhs` crate's CWBVH and BVH2 are kept as [`BvhLayout`]s for
//! comparison (docs/BVH.md has the measurements behind the default). Precision, deliberately
//! split:
//!
//! * The tree stores `f32` boxes and is traversed with an `f32` copy of the ray. This is only
//!   used to *cull*: it never decides a hit. Every triangle box is padded by
//!   `PAD_REL` times the scene scale `S` (the largest vertex coordinate magnitude or scene
//!   diagonal), which is far more than the rounding of the `f32` ray and box arithmetic
//!   (a few `2^-24 S`), so a box that holds a triangle the exact ray hits is never culled.
//!   To keep the `f32` origin near the scene (so that its rounding stays ~`2^-24 S`), a ray whose
//!   origin is farther than `2 S` from the coordinate origin (or, for the obvhs layouts, every
//!   ray) is culled from where it enters the padded scene box instead.
//! * Every triangle test is the shared watertight test [`WatertightRay`] in `f64` on the
//!   original `f64` vertices and ray, and the nearest-hit bookkeeping ([`NearestHit`]) is done
//!   in `f64`.

use std::time::Instant;

use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use obvhs::ray::{Ray as CullRay, RayHit};
use rayon::prelude::*;

use crate::accel::bvh4::{self, Bvh4};
use crate::accel::triangle::{NearestHit, WatertightRay};
use crate::error::{Error, Result};
use crate::ray::{Hit, Intersector, Ray};
use crate::scene::mesh::Mesh;

/// Padding of every triangle's `f32` box, relative to the scene scale `S` (2^-16 ~ 1.5e-5).
/// Covers the rounding of the `f32` culling ray (origin within ~`S` of the scene,
/// direction rounded to `f32`), of the `f32` slab tests and of the conversions of `t`.
const PAD_REL: f64 = 1.0 / 65536.0;

/// Length of the culling ray's direction relative to `S`. obvhs's CWBVH node test ignores
/// boxes that end before `t = 1e-4`; with a direction of length `S / 256` that is
/// `4e-7 S` of world distance, well inside the padding.
const CULL_DIR_REL: f64 = 1.0 / 256.0;

/// CWBVH traversal in obvhs uses a fixed 32-entry stack; deeper trees fall back to BVH2,
/// whose stack grows as needed.
const CWBVH_MAX_DEPTH: usize = 30;

/// Tree layout of a [`BvhIntersector`] (see docs/BVH.md for their measured speeds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BvhLayout {
    /// inimtrace's own 4-wide BVH ([`crate::accel::bvh4::Bvh4`]: binned SAH, up to 4 triangles
    /// per leaf, SSE node test).
    #[default]
    Bvh4,
    /// obvhs's compressed 8-wide BVH (Ylitie et al. 2017), up to 3 triangles per leaf.
    Cwbvh,
    /// obvhs's binary BVH with leaf collapsing.
    Bvh2,
}

/// One triangle in tree order, with its world-space corners in `f64`.
#[derive(Clone, Copy, Debug)]
struct Tri {
    p: [DVec3; 3],
    object: u32,
    index: u32,
}

enum Tree {
    Empty,
    Own(Bvh4),
    Cw(CwBvh),
    Bin(Bvh2),
}

/// A bounding-volume hierarchy over triangle meshes, with `f64` watertight triangle tests.
pub struct BvhIntersector {
    tree: Tree,
    /// Triangles in the order of the tree's primitive slots.
    tris: Vec<Tri>,
    /// Scene box padded by twice the triangle padding (f64), for the culling ray's start.
    lo: DVec3,
    hi: DVec3,
    /// Scene scale `S` (mm).
    scale: f64,
    build_seconds: f64,
}

impl std::fmt::Debug for BvhIntersector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let layout = match self.tree {
            Tree::Empty => "empty",
            Tree::Own(_) => "bvh4",
            Tree::Cw(_) => "cwbvh",
            Tree::Bin(_) => "bvh2",
        };
        f.debug_struct("BvhIntersector")
            .field("layout", &layout)
            .field("triangles", &self.tris.len())
            .field("build_seconds", &self.build_seconds)
            .finish_non_exhaustive()
    }
}

/// Depth (levels) of a BVH2, iteratively.
fn bvh2_depth(bvh: &Bvh2) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut max_depth = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        max_depth = max_depth.max(d);
        let node = &bvh.nodes[i];
        if !node.is_leaf() {
            let c = node.first_index as usize;
            stack.push((c, d + 1));
            stack.push((c + 1, d + 1));
        }
    }
    max_depth
}

/// The non-empty meshes of a scene, validated, each with the global index of its first triangle.
struct MeshParts<'a> {
    /// (scene object index, mesh, first triangle), in the caller's order.
    parts: Vec<(u32, &'a Mesh, usize)>,
    /// Triangles over all meshes.
    n: usize,
    /// The bounds of every mesh's positions.
    lo: DVec3,
    hi: DVec3,
}

impl<'a> MeshParts<'a> {
    fn of(meshes: &[(u32, &'a Mesh)]) -> Result<Self> {
        let mut parts: Vec<(u32, &Mesh, usize)> = Vec::new();
        let mut n = 0usize;
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &(object, mesh) in meshes {
            if mesh.triangles.is_empty() {
                continue;
            }
            mesh.validate(&format!("scene object {object}"))?;
            let (mesh_lo, mesh_hi) = mesh.bounds();
            lo = lo.min(mesh_lo);
            hi = hi.max(mesh_hi);
            parts.push((object, mesh, n));
            n += mesh.triangles.len();
        }
        Ok(MeshParts { parts, n, lo, hi })
    }
}

/// Triangle `i` over all meshes, in the caller's order.
fn tri_of(parts: &[(u32, &Mesh, usize)], i: usize) -> Tri {
    let k = parts.partition_point(|p| p.2 <= i) - 1;
    let (object, mesh, first) = parts[k];
    Tri { p: mesh.triangle_positions(i - first), object, index: (i - first) as u32 }
}

/// The scene's scale (its largest coordinate or extent, 1 for a point), which sets the boxes'
/// padding; coordinates beyond the range of the f32 boxes are an error.
fn coordinate_scale(lo: DVec3, hi: DVec3) -> Result<f64> {
    let scale = {
        let s = lo.abs().max(hi.abs()).max_element().max((hi - lo).length());
        if s > 0.0 {
            s
        } else {
            1.0
        }
    };
    if scale > f64::from(f32::MAX) / 4.0 {
        return Err(Error::invalid(
            "scene meshes",
            "positions",
            format!("coordinates up to {scale:e} mm exceed the single-precision range of the BVH boxes"),
        ));
    }
    Ok(scale)
}

/// A triangle's culling box in f32, padded by `pad`: f64 -> f32 for the tree's boxes only, the
/// padding far more than the rounding of the conversion.
fn padded_box(t: &Tri, pad: f64) -> (Vec3A, Vec3A) {
    let mn = t.p[0].min(t.p[1]).min(t.p[2]) - pad;
    let mx = t.p[0].max(t.p[1]).max(t.p[2]) + pad;
    (Vec3A::from(mn.as_vec3()), Vec3A::from(mx.as_vec3()))
}

/// The obvhs tree of `layout` (CWBVH, or BVH2) over `tris`. PLOC with the smallest search
/// distance and no reinsertion pass: on the bunny this traced as fast as obvhs's "medium"
/// preset (search distance Medium, reinsertion 0.05) or faster, and builds faster
/// (docs/BVH.md). The BVH2 is kept so that its depth can be checked before converting to CWBVH;
/// one too deep for obvhs's CWBVH traversal stays a (collapsed, reinserted) BVH2.
fn obvhs_tree(tris: &[Tri], pad: f64, layout: BvhLayout) -> Tree {
    let aabbs: Vec<Aabb> = tris
        .par_iter()
        .map(|t| {
            let (lo, hi) = padded_box(t, pad);
            Aabb::new(lo, hi)
        })
        .collect();
    let n = aabbs.len();
    let mut bvh2 = PlocBuilder::with_capacity(n).build(
        PlocSearchDistance::Minimum,
        &aabbs,
        (0..n as u32).collect(),
        SortPrecision::U64,
        3,
    );
    let depth = bvh2_depth(&bvh2);
    if layout == BvhLayout::Cwbvh && depth <= CWBVH_MAX_DEPTH {
        Tree::Cw(bvh2_to_cwbvh(&bvh2, 3, true, false))
    } else {
        obvhs::bvh2::leaf_collapser::collapse(&mut bvh2, 8, 3.0);
        ReinsertionOptimizer::default().run(&mut bvh2, 0.1, None);
        bvh2.max_depth = bvh2_depth(&bvh2).max(depth) + 2;
        Tree::Bin(bvh2)
    }
}

impl BvhIntersector {
    /// Builds the default layout ([`BvhLayout::Cwbvh`]) over `meshes`, each paired with the
    /// scene object index that hits on it report as [`Hit::object`]. Triangle indices in hits
    /// are indices into that mesh's `triangles`.
    ///
    /// Every non-empty mesh is validated as for [`crate::accel::brute::BruteForce`]
    /// (indices in range, finite positions); meshes without triangles contribute nothing, and
    /// an empty list gives a backend that hits nothing.
    pub fn new(meshes: &[(u32, &Mesh)]) -> Result<BvhIntersector> {
        BvhIntersector::with_layout(meshes, BvhLayout::default())
    }

    /// As [`BvhIntersector::new`], with a chosen tree layout.
    pub fn with_layout(meshes: &[(u32, &Mesh)], layout: BvhLayout) -> Result<BvhIntersector> {
        let start = Instant::now();
        let MeshParts { parts, n, lo, hi } = MeshParts::of(meshes)?;
        if n == 0 {
            return Ok(BvhIntersector {
                tree: Tree::Empty,
                tris: Vec::new(),
                lo: DVec3::INFINITY,
                hi: DVec3::NEG_INFINITY,
                scale: 1.0,
                build_seconds: start.elapsed().as_secs_f64(),
            });
        }
        let scale = coordinate_scale(lo, hi)?;
        let pad = PAD_REL * scale;
        let tri = |i: usize| tri_of(&parts, i);
        let (tree, tris) = if layout == BvhLayout::Bvh4 {
            if n > bvh4::MAX_PRIMITIVES {
                return Err(Error::invalid(
                    "scene meshes",
                    "triangles",
                    format!("{n} triangles exceed the BVH's limit of {}", bvh4::MAX_PRIMITIVES),
                ));
            }
            let tree = Bvh4::build_with(n, |i| {
                let (lo, hi) = padded_box(&tri(i), pad);
                bvh4::Aabb { lo, hi }
            });
            // The f64 triangles, copied once, straight into tree order.
            let tris = tree.slots().par_iter().map(|&i| tri(i as usize)).collect();
            (Tree::Own(tree), tris)
        } else {
            let tris: Vec<Tri> = (0..n).into_par_iter().map(tri).collect();
            let tree = obvhs_tree(&tris, pad, layout);
            let order = match &tree {
                Tree::Cw(t) => &t.primitive_indices,
                Tree::Bin(t) => &t.primitive_indices,
                Tree::Own(_) | Tree::Empty => unreachable!("obvhs layouts only"),
            };
            let tris: Vec<Tri> = order.par_iter().map(|&i| tris[i as usize]).collect();
            (tree, tris)
        };
        Ok(BvhIntersector {
            tree,
            tris,
            lo: lo - 2.0 * pad,
            hi: hi + 2.0 * pad,
            scale,
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Wall-clock seconds that the constructor took: copying the triangles and building the tree.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The layout actually built (`None` for an empty scene). [`BvhLayout::Cwbvh`] falls back to
    /// [`BvhLayout::Bvh2`] for trees deeper than obvhs's CWBVH traversal stack.
    pub fn layout(&self) -> Option<BvhLayout> {
        match self.tree {
            Tree::Empty => None,
            Tree::Own(_) => Some(BvhLayout::Bvh4),
            Tree::Cw(_) => Some(BvhLayout::Cwbvh),
            Tree::Bin(_) => Some(BvhLayout::Bvh2),
        }
    }

    /// Sets up the culling ray of the own 4-wide tree. When the origin is within `2 S` of the
    /// coordinate origin (so its `f32` rounding and that of the slab differences stay a few
    /// `2^-24 S`, far below the box padding) and the direction's length is moderate, this is
    /// just `ray` rounded to `f32`, in `ray`'s units of `t` (no division, no square root);
    /// otherwise the clipped, rescaled ray of [`BvhIntersector::cull_ray`].
    #[inline]
    fn cull_ray4(&self, ray: &Ray, t_max: f64) -> Option<(bvh4::CullRay, f64, f64)> {
        if t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        let len2 = ray.dir.length_squared();
        if ray.origin.abs().max_element() <= 2.0 * self.scale && (1e-20..=1e20).contains(&len2) {
            // f64 -> f32 for the culling ray only (never for a hit decision); `t_max` is
            // rounded up so that no box before it is culled.
            let tmax = if t_max.is_finite() { (t_max as f32) * (1.0 + 1e-6) } else { f32::INFINITY };
            return Some((bvh4::CullRay::new(ray.origin.as_vec3a(), ray.dir.as_vec3a(), tmax), 0.0, 1.0));
        }
        let (cull, t0, to_cull) = self.cull_ray(ray, t_max)?;
        Some((bvh4::CullRay::new(cull.origin, cull.direction, cull.tmax), t0, to_cull))
    }

    /// [`Intersector::intersect`] over the own 4-wide tree (same hits as the other layouts).
    #[inline]
    fn intersect_bvh4(&self, bvh: &Bvh4, ray: &Ray, t_max: f64) -> Option<Hit> {
        let wray = WatertightRay::new(ray)?;
        let (cull, t0, to_cull) = self.cull_ray4(ray, t_max)?;
        let mut best = NearestHit::default();
        bvh.traverse(&cull, |first, count, mut t_cull| {
            for tri in &self.tris[first..first + count] {
                // The original t_max, not the best t so far, so that exact ties are seen.
                let Some((t, bary)) = wray.intersect(tri.p[0], tri.p[1], tri.p[2], t_max) else {
                    continue;
                };
                if best.offer(t, tri.object, tri.index, bary) {
                    // Boxes reaching t are entered at least the padding earlier, so rounding
                    // here cannot cull one.
                    t_cull = t_cull.min(((t - t0) * to_cull) as f32);
                }
            }
            t_cull
        });
        best.hit()
    }

    /// Sets up the `f32` culling ray for `ray` with `0 < t < t_max`: `None` when the ray
    /// misses the padded scene box within that range. Returns the ray, the `t` (in `ray`'s
    /// units) of its start, and the factor from `ray`'s `t` to the culling ray's `t`.
    fn cull_ray(&self, ray: &Ray, t_max: f64) -> Option<(CullRay, f64, f64)> {
        if t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        // Entry and exit of the padded scene box, in units of ray.dir.
        let (mut t0, mut t1) = (0.0f64, t_max);
        for k in 0..3 {
            let (o, d) = (ray.origin[k], ray.dir[k]);
            if d == 0.0 {
                if o < self.lo[k] || o > self.hi[k] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d;
            let (a, b) = ((self.lo[k] - o) * inv, (self.hi[k] - o) * inv);
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            t0 = t0.max(a);
            t1 = t1.min(b);
        }
        // Also refuses NaN (non-finite rays).
        if !matches!(t0.partial_cmp(&t1), Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)) {
            return None;
        }
        let len = ray.dir.length();
        let unit = self.scale * CULL_DIR_REL;
        // f64 -> f32 for the culling ray only (never for a hit decision).
        let origin = Vec3A::from((ray.origin + t0 * ray.dir).as_vec3());
        // -0.0 components become +0.0: obvhs's CWBVH takes the ray's octant from the sign
        // test `d < 0`, which must agree with the sign of the (clamped) inverse below.
        let dir = (ray.dir / len * unit).as_vec3().map(|c| if c == 0.0 { 0.0 } else { c });
        let inv = |d: f32| {
            if d == 0.0 {
                1e30f32.copysign(d)
            } else {
                (1.0 / d).clamp(-1e30, 1e30)
            }
        };
        let to_cull = len / unit;
        let tmax = if t_max.is_finite() { ((t_max - t0) * to_cull) as f32 * (1.0 + 1e-6) } else { f32::INFINITY };
        let cull = CullRay {
            origin,
            direction: Vec3A::from(dir),
            inv_direction: Vec3A::new(inv(dir.x), inv(dir.y), inv(dir.z)),
            tmin: 0.0,
            tmax,
        };
        Some((cull, t0, to_cull))
    }
}

impl Intersector for BvhIntersector {
    fn name(&self) -> &'static str {
        "bvh"
    }

    /// Nearest hit with `0 < t < t_max`. Equal `t` is broken as in
    /// [`crate::accel::brute::BruteForce`]: lowest object index, then lowest triangle index.
    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        if let Tree::Own(bvh) = &self.tree {
            return self.intersect_bvh4(bvh, ray, t_max);
        }
        let wray = WatertightRay::new(ray)?;
        let (cull, t0, to_cull) = self.cull_ray(ray, t_max)?;
        let mut best = NearestHit::default();
        let mut test = |_: &CullRay, slot: usize| -> f32 {
            let tri = &self.tris[slot];
            // The original t_max, not the best t so far, so that exact ties are seen.
            let Some((t, bary)) = wray.intersect(tri.p[0], tri.p[1], tri.p[2], t_max) else {
                return f32::INFINITY;
            };
            if !best.offer(t, tri.object, tri.index, bary) {
                return f32::INFINITY;
            }
            // Shrinks the culling range; boxes reaching t are entered at least the padding
            // earlier, so the rounding here cannot cull one.
            ((t - t0) * to_cull) as f32
        };
        let mut raw = RayHit::none();
        match &self.tree {
            Tree::Empty => return None,
            Tree::Own(_) => unreachable!("handled by intersect_bvh4"),
            Tree::Cw(bvh) => {
                bvh.ray_traverse(cull, &mut raw, &mut test);
            }
            Tree::Bin(bvh) => {
                bvh.ray_traverse(cull, &mut raw, &mut test);
            }
        }
        best.hit()
    }

    /// One ray at a time (same hits as [`Intersector::intersect`]).
    fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        debug_assert_eq!(rays.len(), hits.len(), "intersect_many: rays and hits differ in length");
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = self.intersect(ray, f64::INFINITY);
        }
    }

    /// Any hit with `0 < t < t_max`; stops at the first one found.
    fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        let Some(wray) = WatertightRay::new(ray) else {
            return false;
        };
        if let Tree::Own(bvh) = &self.tree {
            let Some((cull, _, _)) = self.cull_ray4(ray, t_max) else {
                return false;
            };
            let mut hit = false;
            bvh.traverse(&cull, |first, count, t_cull| {
                if self.tris[first..first + count]
                    .iter()
                    .any(|tri| wray.intersect(tri.p[0], tri.p[1], tri.p[2], t_max).is_some())
                {
                    hit = true;
                    return -1.0;
                }
                t_cull
            });
            return hit;
        }
        let Some((cull, _, _)) = self.cull_ray(ray, t_max) else {
            return false;
        };
        let test = |_: &CullRay, slot: usize| -> f32 {
            let tri = &self.tris[slot];
            match wray.intersect(tri.p[0], tri.p[1], tri.p[2], t_max) {
                Some(_) => -1.0, // below any culling tmax: ends the traversal
                None => f32::INFINITY,
            }
        };
        match &self.tree {
            Tree::Empty => false,
            Tree::Own(_) => unreachable!("handled above"),
            Tree::Cw(bvh) => !bvh.ray_traverse_miss(cull, test),
            Tree::Bin(bvh) => !bvh.ray_traverse_miss(cull, test),
        }
    }
}
