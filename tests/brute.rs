//! The brute-force backend and its watertight ray/triangle test: exact analytic answers,
//! no ray falling through closed meshes at shared edges and vertices, agreement with an
//! independent Möller–Trumbore test away from edges, deterministic tie-breaking.
#![deny(unsafe_code)]

use glam::{DVec2, DVec3};
use inimtrace::accel::brute::BruteForce;
use inimtrace::accel::triangle::WatertightRay;
use inimtrace::fixtures::Rng;
use inimtrace::ray::{Hit, Intersector, Ray, Surface};
use inimtrace::scene::mesh::Mesh;

fn ray(origin: DVec3, dir: DVec3) -> Ray {
    Ray { origin, dir }
}

fn tri_mesh(p: [DVec3; 3]) -> Mesh {
    Mesh { positions: p.to_vec(), triangles: vec![[0, 1, 2]], ..Default::default() }
}

fn bary(hit: &Hit) -> (u32, DVec2) {
    match hit.surface {
        Surface::Triangle { index, bary } => (index, bary),
        other => panic!("expected a triangle hit, got {other:?}"),
    }
}

/// Unit right triangle in the plane z = 5.
fn unit_triangle() -> [DVec3; 3] {
    [DVec3::new(0.0, 0.0, 5.0), DVec3::new(1.0, 0.0, 5.0), DVec3::new(0.0, 1.0, 5.0)]
}

#[test]
fn analytic_hit_is_exact() {
    let m = tri_mesh(unit_triangle());
    let b = BruteForce::new(&[(4, &m)]).unwrap();
    // Straight down the z axis at (0.25, 0.125): t = 5, u (weight of p1) = x, v (of p2) = y.
    let hit = b.intersect(&ray(DVec3::new(0.25, 0.125, 0.0), DVec3::Z), f64::INFINITY).unwrap();
    assert_eq!(hit.t, 5.0);
    assert_eq!(hit.object, 4);
    assert_eq!(bary(&hit), (0, DVec2::new(0.25, 0.125)));
    // t is in units of dir.
    let hit = b.intersect(&ray(DVec3::new(0.25, 0.125, 0.0), DVec3::new(0.0, 0.0, 2.0)), 1e9).unwrap();
    assert_eq!(hit.t, 2.5);
    // Two-sided: from behind.
    let hit = b.intersect(&ray(DVec3::new(0.5, 0.25, 9.0), -DVec3::Z), f64::INFINITY).unwrap();
    assert_eq!(hit.t, 4.0);
    assert_eq!(bary(&hit).1, DVec2::new(0.5, 0.25));
    // Oblique ray from the origin to the point with barycentrics (u, v) = (0.3, 0.6).
    let (u, v) = (0.3, 0.6);
    let [p0, p1, p2] = unit_triangle();
    let target = (1.0 - u - v) * p0 + u * p1 + v * p2;
    let hit = b.intersect(&ray(DVec3::ZERO, target * 0.5), f64::INFINITY).unwrap();
    assert!((hit.t - 2.0).abs() < 1e-15, "t = {}", hit.t);
    assert!((bary(&hit).1 - DVec2::new(u, v)).abs().max_element() < 1e-15);
}

#[test]
fn t_range_is_open_interval() {
    let m = tri_mesh(unit_triangle());
    let b = BruteForce::new(&[(0, &m)]).unwrap();
    let r = ray(DVec3::new(0.25, 0.25, 0.0), DVec3::Z);
    assert!(b.intersect(&r, 5.0).is_none(), "t must be < t_max");
    assert!(b.intersect(&r, 5.0 + 1e-12).is_some());
    assert!(!b.occluded(&r, 5.0));
    assert!(b.occluded(&r, 6.0));
    // Triangle behind the origin, and origin exactly on the triangle (t = 0).
    assert!(b.intersect(&ray(DVec3::new(0.25, 0.25, 6.0), DVec3::Z), f64::INFINITY).is_none());
    assert!(b.intersect(&ray(DVec3::new(0.25, 0.25, 5.0), DVec3::Z), f64::INFINITY).is_none());
    // Outside the triangle (u + v > 1) and outside an edge (u < 0).
    assert!(b.intersect(&ray(DVec3::new(0.6, 0.6, 0.0), DVec3::Z), f64::INFINITY).is_none());
    assert!(b.intersect(&ray(DVec3::new(-0.01, 0.5, 0.0), DVec3::Z), f64::INFINITY).is_none());
    // Degenerate rays hit nothing.
    assert!(b.intersect(&ray(DVec3::new(0.25, 0.25, 0.0), DVec3::ZERO), f64::INFINITY).is_none());
    assert!(b.intersect(&ray(DVec3::new(0.25, 0.25, 0.0), DVec3::new(f64::NAN, 0.0, 1.0)), 9.0).is_none());
}

#[test]
fn parallel_rays_miss() {
    let m = tri_mesh(unit_triangle());
    let b = BruteForce::new(&[(0, &m)]).unwrap();
    // In the triangle's plane, crossing its interior.
    assert!(b.intersect(&ray(DVec3::new(-1.0, 0.25, 5.0), DVec3::X), f64::INFINITY).is_none());
    assert!(b.intersect(&ray(DVec3::new(0.25, -3.0, 5.0), DVec3::new(0.0, 1.0, 0.0)), 1e9).is_none());
    // Parallel, just above the plane.
    assert!(b.intersect(&ray(DVec3::new(-1.0, 0.25, 5.001), DVec3::X), f64::INFINITY).is_none());
}

/// Axis-aligned cube [-1, 1]^3, 12 triangles, outward winding; each face split along the
/// diagonal between its first and third corner.
fn cube() -> Mesh {
    let positions: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut triangles = Vec::new();
    for [a, b, c, d] in quads {
        triangles.push([a, b, c]);
        triangles.push([a, c, d]);
    }
    let m = Mesh { positions, triangles, ..Default::default() };
    // Outward winding check: the geometric normal of every triangle points away from the centre.
    for t in 0..m.triangles.len() {
        let [p0, p1, p2] = m.triangle_positions(t);
        assert!((p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2) > 0.0);
    }
    m
}

/// Icosahedron subdivided `levels` times, vertices on the unit sphere.
fn icosphere(levels: usize) -> Mesh {
    inimtrace::scene::procedural::icosphere(levels, DVec3::ZERO, 1.0)
}

/// Points exactly on the cube's edges and face diagonals (all coordinates dyadic).
fn cube_edge_targets() -> Vec<DVec3> {
    let mut targets = Vec::new();
    let steps: Vec<f64> = (-8..=8).map(|i| i as f64 / 8.0).collect();
    for &s in &steps {
        for (a, b) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
            // The 12 cube edges (8 vertices included at s = +-1).
            targets.push(DVec3::new(s, a, b));
            targets.push(DVec3::new(a, s, b));
            targets.push(DVec3::new(a, b, s));
        }
        for sign in [-1.0, 1.0] {
            // Both diagonals of every face (one is the shared edge of the face's triangles).
            targets.push(DVec3::new(sign, s, s));
            targets.push(DVec3::new(sign, s, -s));
            targets.push(DVec3::new(s, sign, s));
            targets.push(DVec3::new(s, sign, -s));
            targets.push(DVec3::new(s, s, sign));
            targets.push(DVec3::new(s, -s, sign));
        }
    }
    targets
}

#[test]
fn rays_through_cube_edges_and_vertices_never_fall_through() {
    let m = cube();
    let b = BruteForce::new(&[(0, &m)]).unwrap();
    let targets = cube_edge_targets();
    assert_eq!(targets.len(), 17 * 24);
    let origins =
        [DVec3::ZERO, DVec3::new(0.1, -0.3, 0.2), DVec3::new(-0.75, 0.5, 0.625), DVec3::new(0.999, 0.999, -0.999)];
    for origin in origins {
        for &target in &targets {
            // From inside: the exit point is the target, at t = 1.
            let r = ray(origin, target - origin);
            let hit = b.intersect(&r, f64::INFINITY).unwrap_or_else(|| panic!("{origin} -> {target} fell through"));
            assert!((hit.t - 1.0).abs() < 1e-12, "{origin} -> {target}: t = {}", hit.t);
            // Deterministic: the same ray gives the same hit.
            assert_eq!(b.intersect(&r, f64::INFINITY), Some(hit));
            // From outside through the target towards the inside point: enters at the target.
            let outside = target + 3.0 * (target - origin);
            let r = ray(outside, origin - outside);
            let hit = b.intersect(&r, f64::INFINITY).unwrap_or_else(|| panic!("{outside} -> {target} missed"));
            assert!((hit.t - 0.75).abs() < 1e-12, "{outside} -> {target}: t = {}", hit.t);
        }
    }
}

#[test]
fn rays_from_inside_icosphere_always_hit() {
    let m = icosphere(3);
    assert_eq!(m.triangles.len(), 1280);
    let b = BruteForce::new(&[(0, &m)]).unwrap();
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut origins = vec![DVec3::ZERO];
    for _ in 0..3 {
        origins.push(rng.vec(-0.4, 0.4));
    }
    // Targets: every vertex, every edge midpoint (as rounded), and random directions.
    let mut targets: Vec<DVec3> = m.positions.clone();
    for tri in &m.triangles {
        for k in 0..3 {
            let (a, c) = (m.positions[tri[k] as usize], m.positions[tri[(k + 1) % 3] as usize]);
            targets.push((a + c) * 0.5);
        }
    }
    for origin in &origins {
        for target in &targets {
            let r = ray(*origin, *target - *origin);
            assert!(b.intersect(&r, f64::INFINITY).is_some(), "{origin} -> {target} fell through");
        }
    }
    for _ in 0..2000 {
        let r = ray(origins[0], rng.vec(-1.0, 1.0));
        if r.dir == DVec3::ZERO {
            continue;
        }
        let hit = b.intersect(&r, f64::INFINITY).expect("random ray escaped");
        let p = r.origin + hit.t * r.dir;
        assert!(p.length() <= 1.0 + 1e-12 && p.length() > 0.98, "hit at radius {}", p.length());
    }
}

/// Möller–Trumbore (1997), the textbook test, written independently for comparison.
fn moller_trumbore(r: &Ray, p: [DVec3; 3]) -> Option<(f64, DVec2)> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let pvec = r.dir.cross(e2);
    let det = e1.dot(pvec);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = r.origin - p[0];
    let u = tvec.dot(pvec) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = r.dir.dot(qvec) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv;
    (t > 0.0).then_some((t, DVec2::new(u, v)))
}

#[test]
fn agrees_with_moller_trumbore_away_from_edges() {
    let mut rng = Rng(42);
    let (mut hits, mut misses) = (0, 0);
    for i in 0..20_000 {
        let p = [rng.vec(-2.0, 2.0), rng.vec(-2.0, 2.0), rng.vec(-2.0, 2.0)];
        let origin = rng.vec(-5.0, 5.0) + DVec3::new(0.0, 0.0, -10.0);
        // Half the rays aim into the triangle, half anywhere.
        let dir = if i % 2 == 0 {
            let (u, v) = (rng.next(), rng.next());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            (1.0 - u - v) * p[0] + u * p[1] + v * p[2] - origin
        } else {
            rng.vec(-1.0, 1.0)
        };
        let r = ray(origin, dir);
        let mt = moller_trumbore(&r, p);
        // Skip rays within 1e-7 (in barycentrics) of an edge, where rounding may decide.
        let (u, v) = {
            let e1 = p[1] - p[0];
            let e2 = p[2] - p[0];
            let pv = r.dir.cross(e2);
            let det = e1.dot(pv);
            let tv = r.origin - p[0];
            (tv.dot(pv) / det, r.dir.dot(tv.cross(e1)) / det)
        };
        if [u, v, 1.0 - u - v].iter().any(|x| x.abs() < 1e-7) {
            continue;
        }
        let wt = WatertightRay::new(&r).unwrap().intersect(p[0], p[1], p[2], f64::INFINITY);
        match (wt, mt) {
            (None, None) => misses += 1,
            (Some((t1, b1)), Some((t2, b2))) => {
                hits += 1;
                assert!((t1 - t2).abs() <= 1e-9 * t2.abs(), "ray {i}: t {t1} vs {t2}");
                assert!((b1 - b2).abs().max_element() < 1e-9, "ray {i}: bary {b1} vs {b2}");
                // The barycentrics reconstruct the hit point.
                let q = (1.0 - b1.x - b1.y) * p[0] + b1.x * p[1] + b1.y * p[2];
                assert!((q - (r.origin + t1 * r.dir)).length() < 1e-9, "ray {i}");
            }
            (a, b) => panic!("ray {i}: watertight {a:?} vs Möller–Trumbore {b:?}"),
        }
    }
    assert!(hits > 9_000 && misses > 5_000, "hits {hits}, misses {misses}");
}

#[test]
fn nearest_hit_and_deterministic_ties() {
    let near = unit_triangle();
    let far = near.map(|p| p + DVec3::new(0.0, 0.0, 1.0));
    // Within one object: the far triangle first, the near one twice (indices 1 and 2).
    let m = Mesh {
        positions: [far, near, near].concat(),
        triangles: vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]],
        ..Default::default()
    };
    let r = ray(DVec3::new(0.25, 0.25, 0.0), DVec3::Z);
    let b = BruteForce::new(&[(0, &m)]).unwrap();
    let hit = b.intersect(&r, f64::INFINITY).unwrap();
    assert_eq!((hit.t, bary(&hit).0), (5.0, 1));
    // Across objects: identical geometry in objects 7 and 3 -> object 3, whatever the order.
    let single = tri_mesh(near);
    for order in [[(7, &single), (3, &single)], [(3, &single), (7, &single)]] {
        let b = BruteForce::new(&order).unwrap();
        assert_eq!(b.intersect(&r, f64::INFINITY).unwrap().object, 3);
    }
    // A nearer object wins over a lower object index.
    let far_mesh = tri_mesh(far);
    let b = BruteForce::new(&[(0, &far_mesh), (9, &single)]).unwrap();
    let hit = b.intersect(&r, f64::INFINITY).unwrap();
    assert_eq!((hit.object, hit.t), (9, 5.0));
    // intersect_many equals intersect.
    let rays = [r, ray(DVec3::new(5.0, 5.0, 0.0), DVec3::Z)];
    let mut hits = [None; 2];
    b.intersect_many(&rays, &mut hits);
    assert_eq!(hits, [Some(hit), None]);
}

#[test]
fn invalid_meshes_are_rejected_not_panicking() {
    let bad = Mesh { positions: vec![DVec3::ZERO; 3], triangles: vec![[0, 1, 3]], ..Default::default() };
    let err = BruteForce::new(&[(5, &bad)]).unwrap_err().to_string();
    assert!(err.contains("scene object 5") && err.contains("triangle 0"), "{err}");
    let empty = BruteForce::new(&[]).unwrap();
    assert_eq!(empty.intersect(&ray(DVec3::ZERO, DVec3::Z), f64::INFINITY), None);
}

#[test]
fn brute_force_is_shareable_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<BruteForce>();
}
