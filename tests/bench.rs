//! `inimtrace::bench` at tiny sizes on a scene with a triangle mesh: only the mesh backends can
//! render it, each reports its build, and they agree. (`tests/cli.rs` runs `bench --quick` on the
//! paper's scene.)
#![deny(unsafe_code)]

use std::sync::Arc;

use glam::DVec3;
use inimtrace::bench::{run, BenchOptions, Estimator, Sizes, PRECISION_TARGETS_DB};
use inimtrace::scene::procedural::icosphere;
use inimtrace::scene::{Material, Object, Rect, Scene, Shape};

fn tiny() -> Sizes {
    Sizes {
        lcd_resolution: 108,
        retina_resolution: 32,
        display_samples: vec![1, 2],
        reference_display_samples: 3,
        reference_la_grid: 6,
        reference_pupil_grid: 10,
        reference_retina_samples: 3,
        la_grids: vec![1, 2, 3],
        la_grid_reference: 6,
        pupil_grids: vec![2, 4],
        pupil_grid_reference: 8,
        retina_samples: vec![1, 2],
        retina_samples_reference: 4,
        precision_reference_db: 0.02,
        precision_reference_max_samples: 1 << 14,
        precision_reference_seconds: 60.0,
        precision_grids: vec![(4, 1), (8, 2)],
        precision_samples: vec![2, 8, 32],
    }
}

#[test]
fn mesh_scene_runs_on_the_mesh_backends_only() {
    let scene = Scene {
        name: "ball".into(),
        objects: vec![
            Object {
                name: "ball".into(),
                // Off the display's central depth plane (~386 mm), where every LA bundle would
                // converge to a point and LA would equal LC.
                shape: Shape::Mesh(Arc::new(icosphere(2, DVec3::new(10.0, -5.0, 250.0), 40.0))),
                material: Material::Albedo(DVec3::new(0.9, 0.5, 0.2)),
            },
            Object {
                name: "wall".into(),
                shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, 700.0), 600.0, 600.0)),
                material: Material::Albedo(DVec3::new(0.2, 0.7, 0.8)),
            },
        ],
        background: DVec3::ZERO,
        light: None,
        warnings: Vec::new(),
    };
    let dir = tempfile::tempdir().unwrap();
    let opts = BenchOptions { sizes: tiny(), mode: "tiny".into(), out: dir.path().to_path_buf(), quiet: true };
    let report = run(&opts, &scene, "ball").unwrap();

    let mut expected = Vec::new();
    if cfg!(feature = "embree") {
        expected.push("embree");
    }
    expected.push("bvh");
    assert_eq!(report.backends, expected);
    assert_eq!(report.builds.len(), expected.len());
    for b in &report.builds {
        assert_eq!(b.triangles, 320 + 2, "{b:?}");
        assert!(b.build_seconds >= 0.0 && b.constructor_seconds >= b.build_seconds * 0.5, "{b:?}");
    }
    assert!(report.checks.la_k1_equals_lc);
    for f in ["bench.csv", "builds.csv", "bench.json", "bench.md", "summary.md", "speed_psnr.svg", "la_grid.png"] {
        assert!(dir.path().join(f).is_file(), "missing {f}");
    }

    let method_rows: Vec<_> = report.rows.iter().filter(|r| r.series == "method").collect();
    // backends x 3 methods x 2 sample counts x (display + 3 focused eye cases)
    assert_eq!(method_rows.len(), expected.len() * 3 * 2 * 4);
    for r in &method_rows {
        assert!(r.psnr_db.is_finite() && r.psnr_db > 5.0 && r.psnr_db < 200.0, "{r:?}");
        assert_eq!(r.scene, "ball");
        // Both backends trace the same triangles: their images agree.
        let first = method_rows
            .iter()
            .find(|o| {
                o.backend == expected[0]
                    && o.method == r.method
                    && o.eye_case == r.eye_case
                    && o.parameter == r.parameter
            })
            .unwrap();
        assert!((r.psnr_db - first.psnr_db).abs() < 0.05, "{r:?} vs {first:?}");
    }
    // More samples per display pixel: closer to the reference display image.
    for b in &expected {
        for m in ["LC", "PC", "LA"] {
            let p = |k: usize| {
                method_rows
                    .iter()
                    .find(|r| &r.backend == b && r.method == m && r.quantity == "display" && r.parameter == k)
                    .unwrap()
                    .psnr_db
            };
            assert!(p(2) > p(1) + 1.0, "{b} {m}: {} vs {}", p(2), p(1));
        }
    }
    // Convergence runs on the first backend, one summary per series.
    assert_eq!(report.convergence.len(), 3);
    for c in &report.convergence {
        assert_eq!(c.backend, expected[0]);
        assert!(c.rate.is_some_and(|p| p < 0.0), "{c:?}");
    }
    // So does the cost of precision: the reference and every estimator, 3 methods x 4 eye cases
    // per point, each point's error the largest over those 12 cells.
    let p = &report.precision;
    assert!(p.reference_ci95_db <= 0.02 && p.reference_samples_per_pixel > 0, "{p:?}");
    assert_eq!(p.reference_stopped_by, "target met");
    assert_eq!(report.precision_rows(Estimator::Reference).count(), 12);
    let counts = [(Estimator::Grid, 2), (Estimator::Random, 3), (Estimator::RqmcNaive, 3), (Estimator::Rqmc, 3)];
    for (e, n) in counts {
        let pts: Vec<_> = p.points.iter().filter(|q| q.estimator == e).collect();
        assert_eq!(pts.len(), n, "{e}");
        assert_eq!(report.precision_rows(e).count(), 12 * n, "{e}");
        for r in report.precision_rows(e) {
            assert!(r.psnr_db.is_finite() && r.psnr_db > 3.0 && r.scene == "ball" && r.backend == expected[0], "{r:?}");
            let reference = report
                .precision_rows(Estimator::Reference)
                .find(|x| x.eye_case == r.eye_case && x.method == r.method)
                .unwrap();
            let pt = pts.iter().find(|q| q.samples_per_pixel == r.samples as u64).unwrap();
            assert!((r.psnr_db - reference.psnr_db).abs() <= pt.max_psnr_error_db + 1e-9, "{r:?}");
        }
        assert!(pts.iter().all(|q| q.seconds > 0.0 && q.max_psnr_error_db.is_finite()), "{pts:?}");
        // More samples: more seconds.
        assert!(pts.windows(2).all(|w| w[1].seconds > w[0].seconds && w[1].samples_per_pixel > w[0].samples_per_pixel));
    }
    // The naive RQMC PSNR is biased low by the noise; the de-biased one is not, so it is closer
    // to the converged Table 1 at the same samples (the fewest: where the bias is largest).
    let at = |e: Estimator| p.points.iter().find(|q| q.estimator == e).unwrap();
    assert!(
        at(Estimator::Rqmc).max_psnr_error_db < at(Estimator::RqmcNaive).max_psnr_error_db,
        "{:?} vs {:?}",
        at(Estimator::Rqmc),
        at(Estimator::RqmcNaive)
    );
    assert_eq!(p.reached.len(), 4 * PRECISION_TARGETS_DB.len());
    assert!(dir.path().join("precision.svg").is_file() && dir.path().join("precision.png").is_file());
}

/// `bench --backends` on a small generated mesh scene, with `--also` naming this same binary:
/// every backend is measured, in repeated timed passes, Embree and the BVH find the same hits,
/// and the other binary's Embree row scores its LA image as identical to this one's.
#[test]
#[cfg(feature = "embree")]
fn backends_comparison_measures_every_backend_and_the_other_binary() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("spheres.toml");
    std::fs::write(
        &scene,
        "name = \"spheres\"\nbackground = [0.0, 0.0, 0.0]\n[light]\ntype = \"distant\"\ndirection = [0.3, -0.4, 1.0]\n\
         radiance = [1.0, 1.0, 1.0]\n[[objects]]\nname = \"spheres\"\ntype = \"sphere-grid\"\ncenter = [0.0, 0.0, 420.0]\n\
         count = [3, 3]\nspacing = 20.0\nradius = 9.0\nsegments = 16\nmaterial = { albedo = [0.9, 0.85, 0.7] }\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let bin = env!("CARGO_BIN_EXE_inimtrace");
    let o = std::process::Command::new(bin)
        .args(["--quiet", "bench", "--backends", "--quick", "--scene"])
        .arg(&scene)
        .arg("--also")
        .arg(bin)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("backends.json")).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    let backends: Vec<&str> = rows.iter().map(|r| r["backend"].as_str().unwrap()).collect();
    assert_eq!(backends, ["embree", "bvh", "brute", "embree"]);
    let hits = |i: usize| rows[i]["hits"].as_u64().unwrap();
    let rays = rows[0]["rays"].as_u64().unwrap();
    assert!(hits(0) > rays / 20 && hits(0) < rays, "the spheres are seen, not everywhere: {} of {rays}", hits(0));
    // f32 (Embree) and f64 (BVH) tests may differ only on grazing rays.
    assert!(hits(0).abs_diff(hits(1)) * 1000 <= rays, "embree {} vs bvh {}", hits(0), hits(1));
    assert_eq!(hits(0), hits(3), "the same binary twice");
    assert!(rows[0]["library"].as_str().unwrap().starts_with("Embree "), "{}", rows[0]);
    assert!(rows[2]["la_process_s"].is_null(), "brute renders no LA image");
    assert!(rows[0]["la_process_s"].as_f64().unwrap() > 0.0);
    assert_eq!(rows[3]["la_identical_to_this_embree"], true, "{}", rows[3]);
    assert!(rows[0]["la_identical_to_this_embree"].is_null(), "{}", rows[0]);
    // Each query is timed in repeated passes: the first (cold) one and at least 5 more, whose
    // median is the rate. The brute-force twin's pass is short at this size, so it repeats too.
    for r in rows {
        for q in ["nearest", "occluded"] {
            let passes = r[format!("{q}_passes")].as_u64().unwrap();
            assert!(passes >= 6, "{q}: {passes} passes in {r}");
            for rate in [format!("{q}_rays_per_s"), format!("{q}_cold_rays_per_s")] {
                assert!(r[&rate].as_f64().unwrap() > 0.0, "{rate} in {r}");
            }
        }
    }
    for name in ["backends.csv", "backends.md"] {
        assert!(out.join(name).is_file(), "{name}");
    }
}

/// `bench --backends --embree-input DIR` writes what Embree was given for each scene, in the
/// layout `scripts/embree-bare.c` reads: every geometry's vertices and in-range triangles adding
/// up to the scene's triangle count, every traced ray (finite, `tnear = 0`, `tfar = inf`), and
/// one packet-plan byte per run of 16 rays.
#[test]
#[cfg(feature = "embree")]
fn backends_embree_input_holds_the_scene_and_the_rays_traced() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("spheres.toml");
    std::fs::write(
        &scene,
        "name = \"spheres\"\nbackground = [0.0, 0.0, 0.0]\n[[objects]]\nname = \"spheres\"\ntype = \"sphere-grid\"\n\
         center = [0.0, 0.0, 420.0]\ncount = [2, 2]\nspacing = 20.0\nradius = 9.0\nsegments = 8\n\
         material = { albedo = [0.9, 0.85, 0.7] }\n",
    )
    .unwrap();
    let (out, input) = (dir.path().join("out"), dir.path().join("input"));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "bench", "--backends", "--quick", "--embree-only", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .arg("--embree-input")
        .arg(&input)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("backends.json")).unwrap()).unwrap();
    let bytes = std::fs::read(input.join("spheres.embree-input")).unwrap();
    assert_eq!(&bytes[..8], b"INIMEMB1");
    let mut at = 8;
    let mut word = || {
        let w = [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
        at += 4;
        w
    };
    let u32s = |w: [u8; 4]| u32::from_le_bytes(w) as usize;
    let geometries = u32s(word());
    let mut triangles = 0;
    for _ in 0..geometries {
        let (nv, nt) = (u32s(word()), u32s(word()));
        for _ in 0..3 * nv {
            assert!(f32::from_le_bytes(word()).is_finite());
        }
        for _ in 0..3 * nt {
            assert!(u32s(word()) < nv, "a triangle index past the vertex count");
        }
        triangles += nt;
    }
    assert_eq!(triangles as u64, rows[0]["triangles"].as_u64().unwrap());
    let rays = u32s(word());
    assert_eq!(rays as u64, rows[0]["rays"].as_u64().unwrap());
    for _ in 0..rays {
        let r: Vec<f32> = (0..8).map(|_| f32::from_le_bytes(word())).collect();
        assert!(r[..6].iter().all(|c| c.is_finite()) && r[6] == 0.0 && r[7] == f32::INFINITY, "{r:?}");
    }
    let plan = &bytes[at..];
    assert_eq!(plan.len(), rays.div_ceil(16), "one plan byte per run of 16 rays, nothing after");
    assert!(plan.iter().all(|&p| p <= 1));
}
