//! Tests of the Embree backend against a brute-force `f64` ray/triangle intersection written
//! here (the slow, obviously-correct twin), plus its safety properties: watertight closed
//! meshes, packet path == single-ray path, no leaked Embree objects, Embree errors surfaced as
//! `Error::Embree`, invalid meshes rejected with the element named.

#![cfg(feature = "embree")]
#![deny(unsafe_code)]

use std::collections::HashMap;
use std::sync::{RwLock, RwLockReadGuard, RwLockWriteGuard};

use glam::{DVec2, DVec3};
use inimtrace::accel::embree::{
    embree_error, live_objects, BuildQuality, Device, EmbreeIntersector, RawRay, SceneBuilder, TriangleGeometry,
};
use inimtrace::fixtures::Rng;
use inimtrace::ray::{Hit, Intersector, Ray, Surface};
use inimtrace::scene::mesh::Mesh;
use inimtrace::Error;
use rayon::prelude::*;

/// `live_objects()` is process-wide and tests run in parallel: ordinary tests hold this lock
/// shared while they own Embree objects; the leak test holds it exclusively.
static EMBREE: RwLock<()> = RwLock::new(());

fn shared() -> RwLockReadGuard<'static, ()> {
    EMBREE.read().unwrap_or_else(|e| e.into_inner())
}

fn exclusive() -> RwLockWriteGuard<'static, ()> {
    EMBREE.write().unwrap_or_else(|e| e.into_inner())
}

// ---------------------------------------------------------------------------------------------
// The slow twin: Möller–Trumbore in f64 over every triangle of every mesh.

/// Unconstrained intersection of the ray's line with a triangle's plane: (t, u, v) with
/// point = (1-u-v) p0 + u p1 + v p2 = o + t d. `None` only when the ray is parallel to the plane.
fn ray_plane(o: DVec3, d: DVec3, p: [DVec3; 3]) -> Option<(f64, f64, f64)> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return None;
    }
    let tv = o - p[0];
    let u = tv.dot(pv) / det;
    let qv = tv.cross(e1);
    let v = d.dot(qv) / det;
    let t = e2.dot(qv) / det;
    Some((t, u, v))
}

#[derive(Clone, Copy, Debug)]
struct BruteHit {
    t: f64,
    object: u32,
    tri: u32,
    u: f64,
    v: f64,
}

fn tri_points(mesh: &Mesh, tri: usize) -> [DVec3; 3] {
    let [a, b, c] = mesh.triangles[tri];
    [mesh.positions[a as usize], mesh.positions[b as usize], mesh.positions[c as usize]]
}

fn brute(meshes: &[(u32, &Mesh)], ray: &Ray, t_max: f64) -> Option<BruteHit> {
    let mut best: Option<BruteHit> = None;
    for &(object, mesh) in meshes {
        for tri in 0..mesh.triangles.len() {
            if let Some((t, u, v)) = ray_plane(ray.origin, ray.dir, tri_points(mesh, tri)) {
                let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
                if inside && t > 0.0 && t < t_max && best.is_none_or(|b| t < b.t) {
                    best = Some(BruteHit { t, object, tri: tri as u32, u, v });
                }
            }
        }
    }
    best
}

/// The same f64 -> f32 rounding the backend does, for `Scene`-level queries.
fn raw_ray(ray: &Ray) -> RawRay {
    RawRay { org: ray.origin.as_vec3().to_array(), dir: ray.dir.as_vec3().to_array(), tnear: 0.0, tfar: f32::INFINITY }
}

fn tri_bary(hit: &Hit) -> (u32, DVec2) {
    match hit.surface {
        Surface::Triangle { index, bary } => (index, bary),
        other => panic!("Embree returned a non-triangle surface {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Test geometry.

fn mesh(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    Mesh { positions, triangles, ..Mesh::default() }
}

/// Unit icosphere: a closed, convex, watertight mesh whose vertices have irrational coordinates.
fn icosphere(subdivisions: u32) -> Mesh {
    inimtrace::scene::procedural::icosphere(subdivisions as usize, DVec3::ZERO, 1.0)
}

/// Cube [-1, 1]^3 with each face split into an n x n grid of quads (two triangles each), all
/// vertices shared between neighbouring triangles and faces.
fn grid_cube(n: u32) -> Mesh {
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    let mut vertex = |p: DVec3, pos: &mut Vec<DVec3>| -> u32 {
        let key = [(p.x * 1e6).round() as i64, (p.y * 1e6).round() as i64, (p.z * 1e6).round() as i64];
        *index.entry(key).or_insert_with(|| {
            pos.push(p);
            (pos.len() - 1) as u32
        })
    };
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            let at = |i: u32, j: u32| {
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[a1] = -1.0 + 2.0 * f64::from(i) / f64::from(n);
                p[a2] = -1.0 + 2.0 * f64::from(j) / f64::from(n);
                DVec3::from_array(p)
            };
            for i in 0..n {
                for j in 0..n {
                    let v00 = vertex(at(i, j), &mut pos);
                    let v10 = vertex(at(i + 1, j), &mut pos);
                    let v01 = vertex(at(i, j + 1), &mut pos);
                    let v11 = vertex(at(i + 1, j + 1), &mut pos);
                    tris.push([v00, v10, v11]);
                    tris.push([v00, v11, v01]);
                }
            }
        }
    }
    mesh(pos, tris)
}

/// A bumpy icosphere (radially perturbed vertices, so neighbouring triangles are not coplanar)
/// plus a soup of random, possibly intersecting triangles around it.
fn random_scene(seed: u64) -> (Mesh, Mesh) {
    let mut rng = Rng(seed);
    let mut bumpy = icosphere(2);
    for p in &mut bumpy.positions {
        *p *= 2.0 * rng.range(0.9, 1.1);
    }
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for k in 0..200u32 {
        let c = rng.vec(-4.0, 4.0);
        for _ in 0..3 {
            pos.push(c + rng.vec(-0.6, 0.6));
        }
        tris.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    (bumpy, mesh(pos, tris))
}

// ---------------------------------------------------------------------------------------------

#[test]
fn single_triangle_hit_t_barycentrics_object_and_misses() {
    let _g = shared();
    let tri =
        mesh(vec![DVec3::new(0.0, 0.0, 10.0), DVec3::new(4.0, 0.0, 10.0), DVec3::new(0.0, 4.0, 10.0)], vec![[0, 1, 2]]);
    let acc = EmbreeIntersector::new(&[(7, &tri)], BuildQuality::Medium).unwrap();
    assert_eq!(acc.name(), "embree");
    assert_eq!(acc.triangle_count(), 1);
    assert!(acc.build_seconds() >= 0.0);

    // Unnormalised direction (length 2): the plane z = 10 is reached at t = 5 in units of dir.
    let ray = Ray { origin: DVec3::new(1.0, 2.0, 0.0), dir: DVec3::new(0.0, 0.0, 2.0) };
    let hit = acc.intersect(&ray, f64::INFINITY).expect("ray through the triangle must hit");
    assert!((hit.t - 5.0).abs() < 1e-6, "t = {}", hit.t);
    assert_eq!(hit.object, 7);
    let (index, bary) = tri_bary(&hit);
    assert_eq!(index, 0);
    // point (1, 2) = u * (4, 0) + v * (0, 4)  =>  u = 0.25, v = 0.5
    assert!((bary - DVec2::new(0.25, 0.5)).length() < 1e-6, "bary = {bary}");
    let b = brute(&[(7, &tri)], &ray, f64::INFINITY).unwrap();
    assert!((b.t - hit.t).abs() < 1e-6 && (b.u - bary.x).abs() < 1e-6 && (b.v - bary.y).abs() < 1e-6);

    // t_max bounds the search on both sides of the hit, and `occluded` agrees.
    assert!(acc.intersect(&ray, 4.999).is_none());
    assert!(acc.intersect(&ray, 5.001).is_some());
    assert!(!acc.occluded(&ray, 4.999));
    assert!(acc.occluded(&ray, 5.001));
    assert!(acc.occluded(&ray, f64::INFINITY));

    // Parallel to the triangle's plane (just below it), pointing away, beside it: all miss.
    let parallel = Ray { origin: DVec3::new(-1.0, 1.0, 9.999), dir: DVec3::new(1.0, 0.0, 0.0) };
    let away = Ray { origin: DVec3::new(1.0, 1.0, 0.0), dir: DVec3::new(0.0, 0.0, -1.0) };
    let beside = Ray { origin: DVec3::new(3.0, 3.0, 0.0), dir: DVec3::new(0.0, 0.0, 1.0) };
    for r in [parallel, away, beside] {
        assert!(acc.intersect(&r, f64::INFINITY).is_none(), "{r:?} should miss");
        assert!(!acc.occluded(&r, f64::INFINITY), "{r:?} should not be occluded");
        assert!(brute(&[(7, &tri)], &r, f64::INFINITY).is_none());
    }
    // From behind the triangle it is hit too (no back-face culling), at t = 10.
    let behind = Ray { origin: DVec3::new(1.0, 1.0, 20.0), dir: DVec3::new(0.0, 0.0, -1.0) };
    assert!((acc.intersect(&behind, f64::INFINITY).unwrap().t - 10.0).abs() < 1e-5);

    // Invalid rays and limits are "no hit", never a crash.
    let nan = Ray { origin: DVec3::new(f64::NAN, 0.0, 0.0), dir: DVec3::Z };
    let inf_dir = Ray { origin: DVec3::new(1.0, 1.0, 0.0), dir: DVec3::new(0.0, 0.0, f64::INFINITY) };
    assert!(acc.intersect(&nan, f64::INFINITY).is_none());
    assert!(acc.intersect(&inf_dir, f64::INFINITY).is_none());
    assert!(acc.intersect(&ray, f64::NAN).is_none());
    assert!(acc.intersect(&ray, 0.0).is_none());
    assert!(acc.intersect(&ray, -1.0).is_none());
    assert!(!acc.occluded(&nan, f64::INFINITY));
}

/// Every ray aimed at a point of a shared edge or a shared vertex of a closed mesh must hit,
/// from inside and from outside, at the expected distance.
fn assert_watertight(surface: &Mesh, what: &str) {
    let acc = EmbreeIntersector::new(&[(3, surface)], BuildQuality::High).unwrap();
    let mut targets: Vec<DVec3> = surface.positions.clone();
    let mut edges = std::collections::HashSet::new();
    for t in &surface.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    for &(a, b) in &edges {
        let (pa, pb) = (surface.positions[a as usize], surface.positions[b as usize]);
        for f in [0.5, 0.125, 0.8173] {
            targets.push(pa.lerp(pb, f));
        }
    }
    // Inside-out: from the centre towards the target, the surface point is at t = 1.
    // Outside-in: from 3x the target back through it, the surface point is at t = 2.
    let mut rays = Vec::new();
    let mut expected = Vec::new();
    for &p in &targets {
        rays.push(Ray { origin: DVec3::ZERO, dir: p });
        expected.push(1.0);
        rays.push(Ray { origin: 3.0 * p, dir: -p });
        expected.push(2.0);
    }
    let mut many = vec![None; rays.len()];
    acc.intersect_many(&rays, &mut many);
    // Force the 16-wide packet path for every ray too, coherent or not.
    let raw: Vec<RawRay> = rays.iter().map(raw_ray).collect();
    let mut packets = vec![None; rays.len()];
    acc.scene().intersect_packets(&raw, &mut packets);
    let mut holes = 0;
    for (((ray, &t), many_hit), packet_hit) in rays.iter().zip(&expected).zip(&many).zip(&packets) {
        match (acc.intersect(ray, f64::INFINITY), many_hit, packet_hit) {
            (Some(h), Some(hm), Some(hp)) => {
                assert_eq!(h.object, 3);
                assert!((h.t - t).abs() < 1e-5, "{what}: {ray:?} hit at t = {} instead of {t}", h.t);
                assert!((hm.t - t).abs() < 1e-5, "{what}: intersect_many {ray:?} hit at t = {} instead of {t}", hm.t);
                assert!(
                    (f64::from(hp.t) - t).abs() < 1e-5,
                    "{what}: packet {ray:?} hit at t = {} instead of {t}",
                    hp.t
                );
            }
            _ => holes += 1,
        }
    }
    assert_eq!(holes, 0, "{what}: {holes} of {} edge/vertex rays slipped through", rays.len());
}

#[test]
fn closed_meshes_have_no_holes_at_shared_edges_and_vertices() {
    let _g = shared();
    assert_watertight(&icosphere(3), "icosphere");
    assert_watertight(&grid_cube(6), "grid cube");
}

#[test]
fn agrees_with_brute_force_on_random_rays() {
    let _g = shared();
    let (bumpy, soup) = random_scene(0x5EED_1234);
    let meshes = [(0u32, &bumpy), (5u32, &soup)];
    let acc = EmbreeIntersector::new(&meshes, BuildQuality::High).unwrap();
    let mut rng = Rng(42);
    let n = 4000;
    let (mut hits, mut edge_cases) = (0, 0);
    for i in 0..n {
        let origin = rng.vec(-6.0, 6.0);
        // Aim at the scene most of the time; unnormalised directions test t's units.
        let target = if i % 4 == 0 { origin + rng.unit() } else { rng.vec(-3.0, 3.0) };
        let dir = (target - origin) * rng.range(0.05, 20.0);
        let ray = Ray { origin, dir };
        let t_max = if i % 5 == 0 { rng.range(0.0, 1.0) * 12.0 / dir.length() } else { f64::INFINITY };
        let e = acc.intersect(&ray, t_max);
        let b = brute(&meshes, &ray, t_max);
        assert_eq!(acc.occluded(&ray, t_max), e.is_some(), "occluded disagrees with intersect for {ray:?}");
        match (e, b) {
            (None, None) => {}
            (Some(e), Some(b)) => {
                hits += 1;
                let (index, bary) = tri_bary(&e);
                // Tolerance: f32 rounding (6e-8 relative) of coordinates up to ~6 mm, with a
                // safety factor of ~16; divided by the incidence cosine and |dir| it bounds the
                // error of t. (Measured worst case on this data: 1/5 of it, 2.5e-6 relative.)
                let mesh = if b.object == 0 { &bumpy } else { &soup };
                let [p0, p1, p2] = tri_points(mesh, b.tri as usize);
                let normal = (p1 - p0).cross(p2 - p0).normalize();
                let cos = normal.dot(dir.normalize()).abs().max(1e-3);
                let t_tol = 1e-6 * (1.0 + origin.length()) / (dir.length() * cos);
                if (e.object, index) == (b.object, b.tri) {
                    assert!((e.t - b.t).abs() <= t_tol, "t {} vs brute {} (tol {t_tol}) for {ray:?}", e.t, b.t);
                    let bary_err = (bary - DVec2::new(b.u, b.v)).abs().max_element();
                    assert!(bary_err < 1e-3 / cos, "bary {bary} vs brute ({}, {}) for {ray:?}", b.u, b.v);
                } else {
                    // A different triangle is acceptable only when it is at the same distance
                    // (a shared edge or a crossing of two soup triangles).
                    edge_cases += 1;
                    assert!(
                        (e.t - b.t).abs() <= 1e-4 * b.t.abs().max(t_tol),
                        "Embree hit object {} tri {index} at t = {}, brute force object {} tri {} at t = {} for {ray:?}",
                        e.object,
                        e.t,
                        b.object,
                        b.tri,
                        b.t
                    );
                }
            }
            (Some(e), None) => {
                // Embree found a hit the f64 test rejects: only allowed on a triangle's rim.
                edge_cases += 1;
                let (index, _) = tri_bary(&e);
                let mesh = if e.object == 0 { &bumpy } else { &soup };
                let (t, u, v) = ray_plane(origin, dir, tri_points(mesh, index as usize)).unwrap();
                let margin = u.min(v).min(1.0 - u - v);
                assert!(margin > -1e-4 && t > 0.0, "Embree-only hit {e:?} (margin {margin}) for {ray:?}");
            }
            (None, Some(b)) => {
                // Embree missed what the f64 test hits: only allowed on a triangle's rim or at
                // the t_max boundary.
                edge_cases += 1;
                let margin = b.u.min(b.v).min(1.0 - b.u - b.v);
                assert!(
                    margin < 1e-4 || (b.t - t_max).abs() < 1e-5 * b.t,
                    "Embree missed brute-force hit {b:?} (margin {margin}) for {ray:?}"
                );
            }
        }
    }
    assert!(hits > n / 3, "test rays should mostly hit the scene, got {hits} of {n}");
    assert!(edge_cases * 100 < n, "{edge_cases} edge cases among {n} rays is too many");
}

#[test]
fn intersect_many_equals_intersect_per_ray() {
    let _g = shared();
    packets_equal_single_rays(&Device::new().unwrap());
}

/// Where the device has no native 16-ray kernels (AVX2, here forced by the device's `isa`),
/// packets go as two 8-ray ones (`rtcIntersect8`), with the same hits as single rays.
#[test]
fn eight_ray_packets_equal_intersect_per_ray() {
    let _g = shared();
    let device = Device::with_config("isa=avx2").unwrap();
    let (bumpy, _) = random_scene(5);
    let acc = EmbreeIntersector::with_device(&device, &[(0u32, &bumpy)], BuildQuality::Low).unwrap();
    assert_eq!(acc.scene().packet_width(), 8, "an AVX2 device has no native 16-ray packets");
    packets_equal_single_rays(&device);
}

/// `intersect_many` and the raw packet path agree with single rays on `device`.
fn packets_equal_single_rays(device: &Device) {
    let (bumpy, soup) = random_scene(77);
    let meshes = [(1u32, &bumpy), (2u32, &soup)];
    let acc = EmbreeIntersector::with_device(device, &meshes, BuildQuality::Medium).unwrap();
    // A coherent pinhole-camera bundle (packets of 16 span < 0.03 rad, so `intersect_many`
    // uses packets; 97 x 29 is not a multiple of the packet size) ...
    let mut rays = Vec::new();
    let eye = DVec3::new(0.3, -0.2, -9.0);
    for row in 0..29 {
        for col in 0..97 {
            let x = -0.08 + 0.16 * f64::from(col) / 96.0;
            let y = 0.1 - 0.2 * f64::from(row) / 28.0;
            rays.push(Ray { origin: eye, dir: DVec3::new(x, y, 1.0) * 3.0 });
        }
    }
    // ... incoherent random rays, and invalid ones mixed into the same packets.
    let mut rng = Rng(9);
    for _ in 0..500 {
        rays.push(Ray { origin: rng.vec(-6.0, 6.0), dir: rng.unit() * rng.range(0.1, 5.0) });
    }
    rays.insert(100, Ray { origin: DVec3::new(f64::NAN, 0.0, 0.0), dir: DVec3::Z });
    rays.insert(200, Ray { origin: eye, dir: DVec3::new(0.0, 0.0, f64::INFINITY) });
    rays.insert(300, Ray { origin: eye, dir: DVec3::new(0.0, 0.0, 1e300) });

    let mut many = vec![None; rays.len()];
    acc.intersect_many(&rays, &mut many);
    let mut n_hits = 0;
    for (ray, packet) in rays.iter().zip(&many) {
        let single = acc.intersect(ray, f64::INFINITY);
        match (single, packet) {
            (None, None) => {}
            (Some(s), Some(p)) => {
                n_hits += 1;
                assert_eq!((s.object, tri_bary(&s).0), (p.object, tri_bary(p).0), "{ray:?}");
                assert!((s.t - p.t).abs() <= 1e-5 * s.t, "t {} vs {} for {ray:?}", s.t, p.t);
                assert!((tri_bary(&s).1 - tri_bary(p).1).abs().max_element() < 1e-4, "{ray:?}");
            }
            _ => panic!("single {single:?} vs packet {packet:?} for {ray:?}"),
        }
    }
    assert!(n_hits > rays.len() / 2, "only {n_hits} hits");
    assert!(many[100].is_none() && many[200].is_none() && many[300].is_none());

    // The raw packet path on every ray (incoherent ones included) agrees with single rays.
    let raw: Vec<RawRay> = rays.iter().map(raw_ray).collect();
    let mut packets = vec![None; raw.len()];
    acc.scene().intersect_packets(&raw, &mut packets);
    for (r, p) in raw.iter().zip(&packets) {
        let s = acc.scene().intersect1(r);
        assert_eq!(s.map(|h| (h.geom_id, h.prim_id)), p.map(|h| (h.geom_id, h.prim_id)), "{r:?}");
        if let (Some(s), Some(p)) = (s, p) {
            assert!((s.t - p.t).abs() <= 1e-5 * s.t && (s.u - p.u).abs() < 1e-4 && (s.v - p.v).abs() < 1e-4, "{r:?}");
        }
    }
}

#[test]
fn committed_scene_is_shared_across_rayon_threads() {
    let _g = shared();
    let (bumpy, soup) = random_scene(3);
    let meshes = [(0u32, &bumpy), (1u32, &soup)];
    let acc = EmbreeIntersector::new(&meshes, BuildQuality::Low).unwrap();
    let mut rng = Rng(5);
    let rays: Vec<Ray> = (0..3000).map(|_| Ray { origin: rng.vec(-6.0, 6.0), dir: rng.vec(-1.0, 1.0) }).collect();
    let sequential: Vec<Option<Hit>> = rays.iter().map(|r| acc.intersect(r, f64::INFINITY)).collect();
    let parallel: Vec<Option<Hit>> = rays.par_iter().map(|r| acc.intersect(r, f64::INFINITY)).collect();
    assert_eq!(sequential, parallel);
    let mut chunked = vec![None; rays.len()];
    chunked.par_chunks_mut(64).zip(rays.par_chunks(64)).for_each(|(h, r)| acc.intersect_many(r, h));
    let agree = chunked.iter().zip(&sequential).filter(|(a, b)| a.map(|h| h.object) == b.map(|h| h.object)).count();
    assert_eq!(agree, rays.len());
}

#[test]
fn creating_and_dropping_many_scenes_leaks_nothing() {
    let _g = exclusive();
    assert_eq!(live_objects(), 0, "another test left Embree objects alive");
    {
        let device = Device::new().unwrap();
        assert_eq!(live_objects(), 1);
        let tri = [[0.0f32, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
        let mut kept = Vec::new();
        for i in 0..1000 {
            let mut builder = SceneBuilder::new(&device, BuildQuality::Low).unwrap();
            if i % 2 == 0 {
                let geometry = TriangleGeometry::new(&device, &tri, &[[0, 1, 2]], BuildQuality::Low, "tri").unwrap();
                assert_eq!(builder.attach(geometry).unwrap(), 0);
            }
            if i % 3 == 0 {
                let scene = builder.commit().unwrap();
                let ray = RawRay { org: [0.2, 0.2, 0.0], dir: [0.0, 0.0, 1.0], tnear: 0.0, tfar: f32::INFINITY };
                assert_eq!(scene.intersect1(&ray).is_some(), i % 2 == 0);
                if i % 100 == 0 {
                    kept.push(scene);
                }
            }
        }
        // The device plus the ten kept scenes (their geometries are owned by Embree's scenes).
        assert_eq!(live_objects(), 1 + kept.len());
        drop(kept);
        assert_eq!(live_objects(), 1);
        let (bumpy, _) = random_scene(1);
        for _ in 0..20 {
            let acc = EmbreeIntersector::new(&[(0, &bumpy)], BuildQuality::Medium).unwrap();
            assert!(acc.intersect(&Ray { origin: DVec3::ZERO, dir: DVec3::X }, f64::INFINITY).is_some());
        }
        // A failed build releases what it created too.
        let bad = mesh(vec![DVec3::ZERO; 3], vec![[0, 1, 3]]);
        assert!(EmbreeIntersector::with_device(&device, &[(0, &bumpy), (1, &bad)], BuildQuality::Low).is_err());
        assert_eq!(live_objects(), 1);
    }
    assert_eq!(live_objects(), 0);
}

#[test]
fn embree_errors_become_error_embree() {
    let _g = shared();
    // A real failure inside Embree, reported through its error callback with its message.
    let a = Device::new().unwrap();
    let b = Device::new().unwrap();
    let geometry = TriangleGeometry::new(&a, &[[0.0; 3]; 3], &[[0, 1, 2]], BuildQuality::Low, "tri").unwrap();
    let mut builder = SceneBuilder::new(&b, BuildQuality::Low).unwrap();
    match builder.attach(geometry) {
        Err(Error::Embree { code, message }) => {
            assert_eq!(code, "RTC_ERROR_INVALID_ARGUMENT");
            assert!(message.contains("rtcAttachGeometry"), "{message}");
            assert!(message.contains("different devices"), "Embree's own message is kept: {message}");
        }
        other => panic!("expected Error::Embree, got {other:?}"),
    }
    // The builder is still usable after a refused call.
    assert!(builder.commit().is_ok());

    // A failed device construction (malformed config value).
    match Device::with_config("verbose=x") {
        Err(Error::Embree { code, message }) => {
            assert!(code.starts_with("RTC_ERROR_") && code != "RTC_ERROR_NONE", "{code}");
            assert!(message.contains("rtcNewDevice"), "{message}");
        }
        other => panic!("expected Error::Embree, got {other:?}"),
    }
    assert!(matches!(Device::with_config("verbose=0\0"), Err(Error::Invalid { .. })));

    // The conversion itself.
    match embree_error(2, Some("bad thing"), "rtcFoo") {
        Error::Embree { code, message } => {
            assert_eq!(code, "RTC_ERROR_INVALID_ARGUMENT");
            assert_eq!(message, "rtcFoo: bad thing");
        }
        other => panic!("{other:?}"),
    }
    match embree_error(42, None, "rtcBar") {
        Error::Embree { code, message } => {
            assert_eq!(code, "RTC_ERROR_UNRECOGNISED(42)");
            assert!(message.starts_with("rtcBar"));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        embree_error(4, None, "x").to_string(),
        "Embree error RTC_ERROR_OUT_OF_MEMORY: x: (Embree gave no message)"
    );
}

#[test]
fn invalid_meshes_are_rejected_naming_the_element() {
    let _g = shared();
    let ok = icosphere(0);
    let expect_invalid = |m: &Mesh, want_field: &str, want_msg: &str| match EmbreeIntersector::new(
        &[(0, &ok), (5, m)],
        BuildQuality::Low,
    ) {
        Err(Error::Invalid { source_name, field, message }) => {
            assert!(source_name.contains("object 5"), "{source_name}");
            assert_eq!(field, want_field);
            assert!(message.contains(want_msg), "{message}");
        }
        other => panic!("expected Error::Invalid for {want_field}, got {other:?}"),
    };
    for bad in [f64::NAN, f64::INFINITY, -f64::INFINITY, 1e300] {
        let mut m = icosphere(0);
        m.positions[3].y = bad;
        expect_invalid(&m, "positions[3]", "not finite");
    }
    let mut m = icosphere(0);
    m.triangles[1][2] = 12;
    expect_invalid(&m, "triangles[1]", "out of range");
    let mut m = icosphere(0);
    m.triangles[19][0] = u32::MAX;
    expect_invalid(&m, "triangles[19]", "out of range");

    // Empty meshes are fine and simply never hit.
    let empty = Mesh::default();
    let acc = EmbreeIntersector::new(&[(0, &empty)], BuildQuality::Low).unwrap();
    assert!(acc.intersect(&Ray { origin: DVec3::ZERO, dir: DVec3::Z }, f64::INFINITY).is_none());
    let acc = EmbreeIntersector::new(&[], BuildQuality::Low).unwrap();
    assert_eq!(acc.triangle_count(), 0);
}

#[test]
fn the_loaded_library_has_the_major_version_the_bindings_were_made_for() {
    let _guard = shared();
    let device = Device::new().expect("device");
    let version = device.version();
    assert_eq!(version / 10000, i64::from(inimtrace::accel::embree::EMBREE_MAJOR), "{}", device.version_text());
    if cfg!(feature = "embree4") {
        assert!(version >= 40000, "{version}");
    }
    assert_eq!(inimtrace::accel::embree::version_text(40400), "4.4.0");
    assert_eq!(inimtrace::accel::embree::version_text(31305), "3.13.5");
    // A library of another major version is refused in one line naming where it comes from.
    assert!(inimtrace::accel::embree::check_version(40400, 4).is_ok());
    assert!(inimtrace::accel::embree::check_version(31305, 3).is_ok());
    let variable = if cfg!(feature = "embree4") { "EMBREE4_DIR" } else { "EMBREE_DIR" };
    for (found, wanted) in [(31305, 4), (40400, 3), (50000, 4)] {
        let message = inimtrace::accel::embree::check_version(found, wanted).unwrap_err().to_string();
        assert_eq!(message.lines().count(), 1, "{message}");
        assert!(message.contains(variable) && message.contains(&format!("Embree {wanted}.x")), "{message}");
    }
}
