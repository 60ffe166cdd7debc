//! The pure-Rust BVH backend against its slow twin (brute force) and against Embree: identical
//! hits on random rays over random meshes and a closed icosphere, no ray escaping a closed mesh
//! through shared edges and vertices, misses for parallel and receding rays, `occluded` and
//! `intersect_many` consistent with `intersect`, and >= 99.99% hit/miss agreement with Embree on
//! a million rays over the Stanford bunny.
#![deny(unsafe_code)]

use glam::{DVec2, DVec3};
use inimtrace::accel::brute::BruteForce;
use inimtrace::accel::bvh::{BvhIntersector, BvhLayout};
use inimtrace::fixtures::Rng;
use inimtrace::ray::{Hit, Intersector, Ray, Surface};
use inimtrace::scene::mesh::Mesh;

const LAYOUTS: [BvhLayout; 3] = [BvhLayout::Bvh4, BvhLayout::Cwbvh, BvhLayout::Bvh2];

fn ray(origin: DVec3, dir: DVec3) -> Ray {
    Ray { origin, dir }
}

/// Icosahedron subdivided `levels` times, vertices on a sphere of `radius` around `centre`.
fn icosphere(levels: usize, centre: DVec3, radius: f64) -> Mesh {
    inimtrace::scene::procedural::icosphere(levels, centre, radius)
}

/// `n` random triangles (a "triangle soup") in [-1, 1]^3, sizes from tiny to large.
fn soup(rng: &mut Rng, n: usize) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for i in 0..n {
        let c = rng.vec(-1.0, 1.0);
        let size = 10f64.powf(rng.range(-3.0, -0.3));
        for _ in 0..3 {
            positions.push(c + size * rng.vec(-1.0, 1.0));
        }
        let k = 3 * i as u32;
        triangles.push([k, k + 1, k + 2]);
    }
    Mesh { positions, triangles, ..Default::default() }
}

fn assert_same(a: Option<Hit>, b: Option<Hit>, what: &str) {
    match (a, b) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            assert_eq!(a.object, b.object, "{what}: object");
            let (Surface::Triangle { index: ia, bary: ba }, Surface::Triangle { index: ib, bary: bb }) =
                (a.surface, b.surface)
            else {
                panic!("{what}: not triangle hits");
            };
            assert_eq!(ia, ib, "{what}: triangle");
            assert!((a.t - b.t).abs() <= 1e-9 * b.t.abs(), "{what}: t {} vs {}", a.t, b.t);
            assert!((ba - bb).abs().max_element() <= 1e-9, "{what}: bary {ba} vs {bb}");
        }
        (a, b) => panic!("{what}: bvh {a:?} vs brute {b:?}"),
    }
}

/// Checks intersect, occluded and intersect_many of `bvh` against `brute` on `rays`.
fn check_agreement(bvh: &BvhIntersector, brute: &BruteForce, rays: &[Ray], t_max: f64) -> usize {
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let a = bvh.intersect(r, t_max);
        let b = brute.intersect(r, t_max);
        assert_same(a, b, &format!("ray {i} {r:?}"));
        assert_eq!(bvh.occluded(r, t_max), a.is_some(), "ray {i}: occluded vs intersect");
        hits += usize::from(a.is_some());
    }
    if t_max == f64::INFINITY {
        let mut many = vec![None; rays.len()];
        bvh.intersect_many(rays, &mut many);
        for (i, (m, r)) in many.iter().zip(rays).enumerate() {
            assert_eq!(*m, bvh.intersect(r, f64::INFINITY), "ray {i}: intersect_many vs intersect");
        }
    }
    hits
}

#[test]
fn agrees_with_brute_force_on_random_soups() {
    let mut rng = Rng(0x5eed_0001);
    let a = soup(&mut rng, 400);
    let b = soup(&mut rng, 300);
    let meshes = [(3, &a), (1, &b)];
    let brute = BruteForce::new(&meshes).unwrap();
    let mut rays = Vec::new();
    for i in 0..3000 {
        let origin = if i % 3 == 0 { rng.vec(-1.0, 1.0) } else { rng.vec(-4.0, 4.0) };
        let dir = if i % 2 == 0 { rng.vec(-1.0, 1.0) } else { rng.vec(-0.5, 0.5) - origin };
        rays.push(ray(origin, dir * rng.range(0.01, 100.0)));
    }
    for layout in LAYOUTS {
        let bvh = BvhIntersector::with_layout(&meshes, layout).unwrap();
        assert_eq!(bvh.layout(), Some(layout));
        assert_eq!(bvh.triangle_count(), 700);
        assert!(bvh.build_seconds() >= 0.0);
        let hits = check_agreement(&bvh, &brute, &rays, f64::INFINITY);
        assert!(hits > 800 && hits < 2900, "{layout:?}: {hits} hits");
        // A finite t_max cuts hits in the same place.
        check_agreement(&bvh, &brute, &rays[..1000], 0.05);
    }
}

#[test]
fn agrees_with_brute_force_on_closed_icosphere() {
    // Scene far from the origin and in millimetres, as in the pipeline.
    let centre = DVec3::new(12.0, -7.0, 250.0);
    let m = icosphere(3, centre, 40.0);
    let brute = BruteForce::new(&[(0, &m)]).unwrap();
    let mut rng = Rng(77);
    let mut rays = Vec::new();
    for _ in 0..1500 {
        // From the eye (near the world origin) towards the sphere, and from inside it.
        let eye = rng.vec(-2.0, 2.0);
        rays.push(ray(eye, centre + rng.vec(-45.0, 45.0) - eye));
        rays.push(ray(centre + rng.vec(-20.0, 20.0), rng.vec(-1.0, 1.0)));
    }
    for layout in LAYOUTS {
        let bvh = BvhIntersector::with_layout(&[(0, &m)], layout).unwrap();
        let hits = check_agreement(&bvh, &brute, &rays, f64::INFINITY);
        assert!(hits > 2000, "{layout:?}: {hits} hits");
    }
}

#[test]
fn far_origins_axis_parallel_and_extreme_length_rays_agree_with_brute_force() {
    // The own tree's culling ray has two set-ups: the ray rounded to f32 as it is (origin within
    // 2 S of the coordinate origin, moderate direction length) and the clipped, rescaled ray
    // (far origins, tiny or huge directions). Axis-parallel rays give infinite inverse
    // directions. All must find the brute-force hits.
    let centre = DVec3::new(3.0, -2.0, 300.0);
    let m = icosphere(3, centre, 30.0);
    let brute = BruteForce::new(&[(0, &m)]).unwrap();
    let mut rng = Rng(4242);
    let mut rays = Vec::new();
    for i in 0..1200 {
        let target = centre + rng.vec(-32.0, 32.0);
        let origin = match i % 4 {
            0 => centre + rng.vec(-1.0, 1.0).normalize() * 1e5, // far: clipped path
            1 => rng.vec(-2.0, 2.0),
            2 => centre + rng.vec(-10.0, 10.0), // inside the sphere
            _ => rng.vec(-1.0, 1.0) * 1e3,
        };
        let scale = [1e-9, 1e-3, 1.0, 1e4, 1e9][i % 5];
        rays.push(ray(origin, (target - origin) * scale));
        // Axis-parallel through the sphere (zero direction components), both directions.
        let p = centre + rng.vec(-25.0, 25.0);
        let axis = [DVec3::X, DVec3::Y, DVec3::Z][i % 3] * if i % 2 == 0 { 1.0 } else { -1.0 };
        rays.push(ray(p - axis * 100.0, axis));
    }
    for layout in LAYOUTS {
        let bvh = BvhIntersector::with_layout(&[(0, &m)], layout).unwrap();
        let hits = check_agreement(&bvh, &brute, &rays, f64::INFINITY);
        assert!(hits > 1500, "{layout:?}: {hits} hits");
    }
}

#[test]
fn rays_through_shared_edges_and_vertices_never_escape() {
    let centre = DVec3::new(0.5, 0.25, 100.0);
    let m = icosphere(3, centre, 10.0);
    let brute = BruteForce::new(&[(0, &m)]).unwrap();
    let mut rng = Rng(0xabcd);
    let mut origins = vec![centre];
    for _ in 0..3 {
        origins.push(centre + rng.vec(-4.0, 4.0));
    }
    // Targets: every vertex and every edge midpoint (as rounded).
    let mut targets: Vec<DVec3> = m.positions.clone();
    for tri in &m.triangles {
        for k in 0..3 {
            let (a, c) = (m.positions[tri[k] as usize], m.positions[tri[(k + 1) % 3] as usize]);
            targets.push((a + c) * 0.5);
        }
    }
    for layout in LAYOUTS {
        let bvh = BvhIntersector::with_layout(&[(0, &m)], layout).unwrap();
        for origin in &origins {
            for target in &targets {
                let r = ray(*origin, *target - *origin);
                let hit = bvh.intersect(&r, f64::INFINITY);
                assert!(hit.is_some(), "{layout:?}: {origin} -> {target} escaped");
                assert_eq!(hit, brute.intersect(&r, f64::INFINITY), "{layout:?}: {origin} -> {target}");
                // From outside, through the target, towards the inside point: enters there.
                let outside = *target + 3.0 * (*target - *origin);
                let r = ray(outside, *origin - outside);
                let hit = bvh.intersect(&r, f64::INFINITY).unwrap_or_else(|| panic!("{outside} -> {target} missed"));
                assert!((hit.t - 0.75).abs() < 1e-9, "{layout:?}: {outside} -> {target}: t = {}", hit.t);
            }
        }
    }
}

#[test]
fn parallel_and_receding_rays_miss() {
    // Unit right triangle in the plane z = 5, and a sphere.
    let tri = Mesh {
        positions: vec![DVec3::new(0.0, 0.0, 5.0), DVec3::new(1.0, 0.0, 5.0), DVec3::new(0.0, 1.0, 5.0)],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    };
    let sphere = icosphere(2, DVec3::new(0.0, 0.0, 20.0), 3.0);
    for layout in LAYOUTS {
        let bvh = BvhIntersector::with_layout(&[(0, &tri), (1, &sphere)], layout).unwrap();
        // Exact analytic hit, as the brute-force twin gives it.
        let hit = bvh.intersect(&ray(DVec3::new(0.25, 0.125, 0.0), DVec3::Z), f64::INFINITY).unwrap();
        assert_eq!((hit.t, hit.object), (5.0, 0));
        assert_eq!(hit.surface, Surface::Triangle { index: 0, bary: DVec2::new(0.25, 0.125) });
        // In the triangle's plane, and just above it.
        assert!(bvh.intersect(&ray(DVec3::new(-1.0, 0.25, 5.0), DVec3::X), f64::INFINITY).is_none());
        assert!(bvh.intersect(&ray(DVec3::new(-1.0, 0.25, 5.001), DVec3::X), f64::INFINITY).is_none());
        // Away from everything: behind the triangle and the sphere, and sideways.
        assert!(bvh.intersect(&ray(DVec3::new(0.25, 0.25, 30.0), DVec3::Z), f64::INFINITY).is_none());
        assert!(bvh.intersect(&ray(DVec3::new(0.25, 0.25, 0.0), -DVec3::Z), f64::INFINITY).is_none());
        assert!(!bvh.occluded(&ray(DVec3::new(0.25, 0.25, 0.0), -DVec3::Z), f64::INFINITY));
        assert!(bvh.intersect(&ray(DVec3::new(10.0, 0.0, 20.0), DVec3::X), f64::INFINITY).is_none());
        // t range is the open interval (0, t_max).
        let r = ray(DVec3::new(0.25, 0.25, 0.0), DVec3::Z);
        assert!(bvh.intersect(&r, 5.0).is_none());
        assert!(!bvh.occluded(&r, 5.0));
        assert!(bvh.occluded(&r, 5.0 + 1e-12));
        // Degenerate rays and t_max hit nothing.
        assert!(bvh.intersect(&ray(DVec3::ZERO, DVec3::ZERO), f64::INFINITY).is_none());
        assert!(bvh.intersect(&ray(DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 1.0)), f64::INFINITY).is_none());
        assert!(bvh.intersect(&r, f64::NAN).is_none() && bvh.intersect(&r, -1.0).is_none());
    }
}

#[test]
fn deterministic_ties_like_brute_force() {
    let near = [DVec3::new(0.0, 0.0, 5.0), DVec3::new(1.0, 0.0, 5.0), DVec3::new(0.0, 1.0, 5.0)];
    let single = Mesh { positions: near.to_vec(), triangles: vec![[0, 1, 2]], ..Default::default() };
    // The same triangle twice within one mesh, and in two objects.
    let twice = Mesh { positions: near.to_vec(), triangles: vec![[0, 1, 2], [0, 1, 2]], ..Default::default() };
    let r = ray(DVec3::new(0.25, 0.25, 0.0), DVec3::Z);
    for layout in LAYOUTS {
        for order in [[(7, &single), (3, &twice)], [(3, &twice), (7, &single)]] {
            let bvh = BvhIntersector::with_layout(&order, layout).unwrap();
            let brute = BruteForce::new(&order).unwrap();
            let hit = bvh.intersect(&r, f64::INFINITY).unwrap();
            assert_eq!(hit.object, 3);
            assert!(matches!(hit.surface, Surface::Triangle { index: 0, .. }));
            assert_eq!(Some(hit), brute.intersect(&r, f64::INFINITY));
        }
    }
}

#[test]
fn empty_scenes_and_invalid_meshes() {
    let empty = BvhIntersector::new(&[]).unwrap();
    assert_eq!(empty.triangle_count(), 0);
    assert_eq!(empty.name(), "bvh");
    assert_eq!(empty.intersect(&ray(DVec3::ZERO, DVec3::Z), f64::INFINITY), None);
    assert!(!empty.occluded(&ray(DVec3::ZERO, DVec3::Z), f64::INFINITY));
    let no_tris = Mesh::default();
    let bvh = BvhIntersector::new(&[(0, &no_tris)]).unwrap();
    assert_eq!(bvh.intersect(&ray(DVec3::ZERO, DVec3::Z), f64::INFINITY), None);
    let mut hits = [Some(Hit { t: 1.0, object: 0, surface: Surface::Triangle { index: 0, bary: DVec2::ZERO } })];
    bvh.intersect_many(&[ray(DVec3::ZERO, DVec3::Z)], &mut hits);
    assert_eq!(hits, [None]);
    let bad = Mesh { positions: vec![DVec3::ZERO; 3], triangles: vec![[0, 1, 3]], ..Default::default() };
    let err = BvhIntersector::new(&[(5, &bad)]).unwrap_err().to_string();
    assert!(err.contains("scene object 5") && err.contains("triangle 0"), "{err}");
}

#[test]
fn bvh_is_shareable_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<BvhIntersector>();
}

/// Hit/miss agreement with Embree on >= 1,000,000 rays over the Stanford bunny (scaled to
/// millimetres and placed in front of the eye): camera rays from the eye and random rays
/// from around and inside the bunny.
#[cfg(feature = "embree")]
#[test]
fn agrees_with_embree_on_bunny() {
    use inimtrace::accel::embree::{BuildQuality, EmbreeIntersector};
    use rayon::prelude::*;

    let path = std::path::Path::new("/usr/share/glmark2/models/bunny.obj");
    if !path.exists() {
        eprintln!("skipping: {} not found (install glmark2-data)", path.display());
        return;
    }
    let mut mesh = inimtrace::io::load_mesh(path).unwrap().mesh;
    let (lo, hi) = mesh.bounds();
    let size = (hi - lo).max_element();
    let mid = (lo + hi) * 0.5;
    for p in &mut mesh.positions {
        *p = (*p - mid) * (60.0 / size) + DVec3::new(0.0, 0.0, 300.0);
    }
    let meshes = [(0, &mesh)];
    let bvh = BvhIntersector::new(&meshes).unwrap();
    let embree = EmbreeIntersector::new(&meshes, BuildQuality::High).unwrap();
    assert_eq!(bvh.triangle_count(), embree.triangle_count());

    const N: usize = 1 << 20;
    let make_ray = |i: usize| -> Ray {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ (i as u64).wrapping_mul(0x2545_F491_4F6C_DD1D));
        rng.next();
        if i.is_multiple_of(2) {
            // Camera-like: from within a 4 mm pupil towards a 70 mm square around the bunny.
            let o = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
            ray(o, DVec3::new(rng.range(-35.0, 35.0), rng.range(-35.0, 35.0), 300.0) - o)
        } else {
            // Incoherent: from anywhere in a box around the bunny, in any direction.
            let o = DVec3::new(0.0, 0.0, 300.0) + rng.vec(-40.0, 40.0);
            ray(o, rng.vec(-1.0, 1.0))
        }
    };
    let (agree, hits) = (0..N)
        .into_par_iter()
        .map(|i| {
            let r = make_ray(i);
            let a = bvh.intersect(&r, f64::INFINITY);
            let b = embree.intersect(&r, f64::INFINITY);
            (usize::from(a.is_some() == b.is_some()), usize::from(a.is_some()))
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
    let fraction = agree as f64 / N as f64;
    eprintln!("bunny: {agree} of {N} rays agree on hit/miss ({:.5}%), {hits} hits", 100.0 * fraction);
    assert!(hits > N / 10 && hits < N * 9 / 10, "{hits} hits");
    assert!(fraction >= 0.9999, "hit/miss agreement {:.5}% < 99.99%", 100.0 * fraction);
}

/// The paper's scene, tessellated, through the pure-Rust BVH matches the exact analytic backend
/// (issue: "pure-Rust and Embree display and simulated images agree to PSNR >= 50 dB").
#[test]
fn paper_scene_through_bvh_matches_analytic() {
    use inimtrace::optics::{Display, Eye, Focus, Retina};
    use inimtrace::progress::Progress;
    use inimtrace::render::backend::{with_fields, BackendChoice};
    use inimtrace::render::retina::simulate;
    use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, Method};
    let scene = inimtrace::scene::Scene::paper();
    let mut display = Display::paper();
    display.lcd.resolution = [270, 270];
    let retina = Retina { resolution: 64, ..Retina::default() };
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 4);
    let run = |choice| {
        with_fields(&scene, choice, |f| {
            let s = DisplayRenderSettings::default();
            let d: Vec<_> = [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }]
                .iter()
                .map(|m| render_display_image(&display, *m, &s, f.shade, &Progress::hidden()).unwrap())
                .collect();
            let sims = simulate(&display, &eye, &retina, &d.iter().collect::<Vec<_>>(), &Progress::hidden()).unwrap();
            Ok((d, sims, ground_truth(&eye, &retina, f.shade, &Progress::hidden())))
        })
        .unwrap()
    };
    let (da, sa, ga) = run(BackendChoice::Analytic);
    let (db, sb, gb) = run(BackendChoice::Bvh);
    for (a, b) in da.iter().chain(&sa).chain(std::iter::once(&ga)).zip(db.iter().chain(&sb).chain(std::iter::once(&gb)))
    {
        let p = inimtrace::metrics::psnr(a, b).unwrap().mean;
        assert!(p >= 50.0, "bvh vs analytic: {p} dB");
    }
}
