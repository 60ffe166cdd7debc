//! Criterion benchmarks of the pure-Rust BVH backend against Embree (when the `embree` feature
//! is on), one thread: nearest-hit queries on the pipeline's own rays of scenes/bunny.toml (LC
//! display rays and ground-truth eye rays, the speed targets), and on the bare Stanford
//! bunny for coherent camera rays
//! (a pinhole image traced row by row, like the display rays), eye-like rays (random points of
//! a 4 mm pupil towards random points around the bunny) and incoherent rays (random origins
//! around the bunny, random directions); and the build time of both on a 2-million-triangle
//! sphere (Embree at BuildQuality::High).
//!
//! Run: `cargo bench --bench bvh` (bunny from /usr/share/glmark2/models/bunny.obj; the ray
//! groups are skipped when it is absent). Single-thread numbers: rays are traced in a plain loop
//! on the bench thread; the builds use all cores (both libraries build in parallel).
#![deny(unsafe_code)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use glam::DVec3;
use inimtrace::accel::bvh::{BvhIntersector, BvhLayout};
use inimtrace::fixtures::{self, Rng};
use inimtrace::ray::{Intersector, Ray};
use inimtrace::scene::mesh::Mesh;

/// The bunny, 60 mm tall, centred 300 mm in front of the eye.
fn bunny() -> Option<Mesh> {
    let path = std::path::Path::new("/usr/share/glmark2/models/bunny.obj");
    let mut mesh = inimtrace::io::load_mesh(path).ok()?.mesh;
    let (lo, hi) = mesh.bounds();
    let size = (hi - lo).max_element();
    let mid = (lo + hi) * 0.5;
    for p in &mut mesh.positions {
        *p = (*p - mid) * (60.0 / size) + DVec3::new(0.0, 0.0, 300.0);
    }
    Some(mesh)
}

const SIDE: usize = 256;

/// The three ray sets of `SIDE * SIDE` rays each.
fn ray_sets() -> Vec<(&'static str, Vec<Ray>)> {
    let n = SIDE * SIDE;
    let camera: Vec<Ray> = (0..n)
        .map(|i| {
            let (x, y) = ((i % SIDE) as f64 + 0.5, (i / SIDE) as f64 + 0.5);
            let target = DVec3::new(-35.0 + 70.0 * x / SIDE as f64, 35.0 - 70.0 * y / SIDE as f64, 300.0);
            Ray { origin: DVec3::ZERO, dir: target }
        })
        .collect();
    let mut rng = Rng(12345);
    let eye: Vec<Ray> = (0..n)
        .map(|_| {
            let o = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
            Ray { origin: o, dir: DVec3::new(rng.range(-35.0, 35.0), rng.range(-35.0, 35.0), 300.0) - o }
        })
        .collect();
    let random: Vec<Ray> = (0..n)
        .map(|_| {
            let o = DVec3::new(rng.range(-40.0, 40.0), rng.range(-40.0, 40.0), 300.0 + rng.range(-40.0, 40.0));
            Ray { origin: o, dir: DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) }
        })
        .collect();
    vec![("coherent", camera), ("eye", eye), ("incoherent", random)]
}

/// The BVH in each of `layouts`, then Embree at its high build quality (with the feature).
fn backends(
    meshes: &[(u32, &Mesh)],
    layouts: &[(&'static str, BvhLayout)],
) -> Vec<(&'static str, Box<dyn Intersector>)> {
    #[cfg_attr(not(feature = "embree"), allow(unused_mut))]
    let mut out: Vec<(&'static str, Box<dyn Intersector>)> = layouts
        .iter()
        .map(|&(name, layout)| {
            (name, Box::new(BvhIntersector::with_layout(meshes, layout).unwrap()) as Box<dyn Intersector>)
        })
        .collect();
    #[cfg(feature = "embree")]
    {
        use inimtrace::accel::embree::{BuildQuality, EmbreeIntersector};
        out.push(("embree", Box::new(EmbreeIntersector::new(meshes, BuildQuality::High).unwrap())));
    }
    out
}

fn trace_all(backend: &dyn Intersector, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| backend.intersect(r, f64::INFINITY).is_some()).count()
}

/// The speed targets are on the pipeline's own rays: scenes/bunny.toml (bunny and a
/// tessellated USAF square), LC display rays of 32 LCD rows and ground-truth eye rays of 2 retina
/// rows (the ray sets of benches/embree.rs), one ray at a time on one thread.
fn bench_pipeline_rays(c: &mut Criterion) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.toml");
    let Ok(scene) = inimtrace::io::load_scene(&path.to_string_lossy(), std::path::Path::new("")) else {
        eprintln!("scenes/bunny.toml could not be loaded (glmark2-data missing?): skipping the pipeline rays");
        return;
    };
    let meshes = inimtrace::render::backend::scene_meshes(&scene);
    let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
    let backends = backends(&refs, &[("bvh-bvh4", BvhLayout::Bvh4), ("bvh-cwbvh", BvhLayout::Cwbvh)]);
    for (set, rays) in [("display", fixtures::bunny_display_rays(32)), ("eye", fixtures::bunny_eye_rays(2))] {
        let mut group = c.benchmark_group(format!("bunny_scene_{set}"));
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.sample_size(30);
        for (name, backend) in &backends {
            group.bench_function(*name, |b| b.iter(|| trace_all(black_box(backend.as_ref()), black_box(&rays))));
        }
        group.finish();
    }
}

fn bench_rays(c: &mut Criterion) {
    let Some(mesh) = bunny() else {
        eprintln!("bunny.obj not found: skipping the ray benchmarks");
        return;
    };
    let meshes = [(0, &mesh)];
    let backends = backends(
        &meshes,
        &[("bvh-bvh4", BvhLayout::Bvh4), ("bvh-cwbvh", BvhLayout::Cwbvh), ("bvh-bvh2", BvhLayout::Bvh2)],
    );
    for (set, rays) in ray_sets() {
        let mut group = c.benchmark_group(format!("bunny_{set}"));
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.sample_size(20);
        for (name, backend) in &backends {
            group.bench_function(*name, |b| b.iter(|| trace_all(black_box(backend.as_ref()), black_box(&rays))));
        }
        group.finish();
    }
}

/// A UV sphere of radius 50 mm with `2 * rings * segments` triangles (about 2 million here).
fn fine_sphere(rings: u32, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..=rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            positions.push(
                50.0 * DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
                    + DVec3::new(0.0, 0.0, 300.0),
            );
        }
    }
    let mut triangles = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let a = i * segments + j;
            let b = i * segments + (j + 1) % segments;
            let (c, d) = (a + segments, b + segments);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    Mesh { positions, triangles, ..Default::default() }
}

fn bench_build(c: &mut Criterion) {
    let mesh = fine_sphere(1000, 1000);
    let meshes = [(0, &mesh)];
    let mut group = c.benchmark_group("build_2m_triangles");
    group.sample_size(10);
    for (name, layout) in
        [("bvh-bvh4", BvhLayout::Bvh4), ("bvh-cwbvh", BvhLayout::Cwbvh), ("bvh-bvh2", BvhLayout::Bvh2)]
    {
        group.bench_function(name, |b| {
            b.iter_batched(|| (), |_| BvhIntersector::with_layout(&meshes, layout).unwrap(), BatchSize::PerIteration)
        });
    }
    #[cfg(feature = "embree")]
    {
        use inimtrace::accel::embree::{BuildQuality, EmbreeIntersector};
        group.bench_function("embree-high", |b| {
            b.iter_batched(
                || (),
                |_| EmbreeIntersector::new(&meshes, BuildQuality::High).unwrap(),
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_pipeline_rays, bench_rays, bench_build);
criterion_main!(benches);
