//! Embree throughput on the bunny scene (scenes/bunny.toml, 69,670 triangles): BVH build time,
//! and rays per second on (a) the LC display image's camera rays (coherent: adjacent pixels of
//! one LCD row) and (b) the ground truth's eye rays (one retina row per batch, laid out
//! [pupil sample][column] as `ground_truth` does), on 1 and 2 threads. Each ray set is traced
//! by a bare loop over the raw Embree calls (`Scene::intersect1`, `Scene::intersect16` on
//! pre-converted `f32` rays) and by our pipeline (`EmbreeIntersector::intersect_many` on `f64`
//! rays, and `SceneTracer::sample_many`, which adds shading and depth), side by side, so that
//! the pipeline's overhead can be read off one run:
//!
//! ```text
//! cargo bench --bench embree
//! ```
//!
//! Needs glmark2-data (`/usr/share/glmark2/models/bunny.obj`); the light is removed so that
//! every path traces exactly one ray per sample.
#![deny(unsafe_code)]

use std::path::Path;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use glam::DVec3;
use inimtrace::accel::embree::{BuildQuality, EmbreeIntersector, RawRay};
use inimtrace::fixtures::{bunny_display_rays as display_rays, bunny_eye_rays as eye_rays};
use inimtrace::io;
use inimtrace::ray::{Intersector, Ray};
use inimtrace::render::backend::scene_meshes;
use inimtrace::render::{RadianceField, Sample, SceneTracer};
use inimtrace::scene::{Mesh, Scene};
use rayon::prelude::*;

fn bunny() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.toml");
    let mut scene = io::load_scene(&path.to_string_lossy(), Path::new("")).expect("scenes/bunny.toml");
    scene.light = None;
    scene
}

fn raw(rays: &[Ray]) -> Vec<RawRay> {
    rays.iter()
        .map(|r| RawRay {
            org: r.origin.as_vec3().to_array(),
            dir: r.dir.as_vec3().to_array(),
            tnear: 0.0,
            tfar: f32::INFINITY,
        })
        .collect()
}

/// Batches of this many rays: one LCD row (2160) or one retina row's rays of a few pupil samples.
const BATCH: usize = 2160;

fn benches(c: &mut Criterion) {
    if !Path::new("/usr/share/glmark2/models/bunny.obj").exists() {
        eprintln!("skipped: install glmark2-data for the bunny");
        return;
    }
    let scene = bunny();
    let meshes = scene_meshes(&scene);
    let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();

    let mut g = c.benchmark_group("bunny_build");
    g.sample_size(10);
    for q in [BuildQuality::Low, BuildQuality::Medium, BuildQuality::High] {
        g.bench_function(format!("{q:?}"), |b| {
            b.iter_batched(|| (), |_| EmbreeIntersector::new(&refs, q).unwrap(), BatchSize::PerIteration)
        });
    }
    g.finish();

    let embree = EmbreeIntersector::new(&refs, BuildQuality::Medium).unwrap();
    let raw_scene = embree.scene();
    let tracer = SceneTracer { scene: &scene, backend: &embree };
    let pools: Vec<(usize, rayon::ThreadPool)> =
        [1usize, 2].iter().map(|&n| (n, rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap())).collect();

    for (name, rays) in [("lc_display_rays", display_rays(32)), ("ground_truth_eye_rays", eye_rays(2))] {
        let raws = raw(&rays);
        let hit_count = {
            let mut hits = vec![None; rays.len()];
            embree.intersect_many(&rays, &mut hits);
            hits.iter().filter(|h| h.is_some()).count()
        };
        eprintln!("{name}: {} rays, {hit_count} hit the scene", rays.len());
        let mut g = c.benchmark_group(format!("bunny_{name}"));
        g.sample_size(10);
        g.measurement_time(std::time::Duration::from_secs(3));
        g.warm_up_time(std::time::Duration::from_secs(1));
        g.throughput(Throughput::Elements(rays.len() as u64));
        for (threads, pool) in &pools {
            g.bench_function(format!("raw_intersect1/{threads}t"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        raws.par_chunks(BATCH)
                            .map(|chunk| chunk.iter().filter(|r| raw_scene.intersect1(r).is_some()).count())
                            .sum::<usize>()
                    })
                })
            });
            g.bench_function(format!("raw_intersect16/{threads}t"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        raws.par_chunks(BATCH)
                            .map(|chunk| {
                                let mut hits = [None; 16];
                                let mut n = 0;
                                for p in chunk.chunks(16) {
                                    raw_scene.intersect16(p, &mut hits[..p.len()], true);
                                    n += hits[..p.len()].iter().filter(|h| h.is_some()).count();
                                }
                                n
                            })
                            .sum::<usize>()
                    })
                })
            });
            g.bench_function(format!("pipeline_intersect_many/{threads}t"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        rays.par_chunks(BATCH)
                            .map(|chunk| {
                                let mut hits = vec![None; chunk.len()];
                                embree.intersect_many(chunk, &mut hits);
                                hits.iter().filter(|h| h.is_some()).count()
                            })
                            .sum::<usize>()
                    })
                })
            });
            g.bench_function(format!("pipeline_sample_many/{threads}t"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        rays.par_chunks(BATCH)
                            .map(|chunk| {
                                let mut out = vec![Sample::default(); chunk.len()];
                                tracer.sample_many(chunk, &mut out);
                                out.iter().map(|s| s.radiance).sum::<DVec3>().x
                            })
                            .sum::<f64>()
                    })
                })
            });
        }
        g.finish();
    }
}

criterion_group!(embree_benches, benches);
criterion_main!(embree_benches);
