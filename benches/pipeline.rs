//! Criterion benchmarks of the assessment pipeline's hot kernels (small sizes; the full-size
//! experiment is timed by `scripts/bench-assess.sh`, speed against error by `inimtrace bench`):
//! display images, simulation and ground truth, SSIM, USAF chart and image-texture lookups, and
//! eq. (1) lenslet refraction. Ray-scene intersection per backend: `benches/bvh.rs`,
//! `benches/embree.rs`.
#![deny(unsafe_code)]

use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DVec2, DVec3};
use std::hint::black_box;

use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::metrics::{ssim, SsimConstants};
use inimtrace::optics::transfer::eye_to_lcd;
use inimtrace::optics::transfer::FastTransfer;
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::retina::{simulate_stack, DisplayStack};
use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, SceneTracer};
use inimtrace::scene::image_texture::{Filter, Wrap};
use inimtrace::scene::{usaf, ImageTexture, Scene};

fn kernels(c: &mut Criterion) {
    let mut display = Display::paper();
    display.lcd.resolution = [540, 540];
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let fused = FacingPlanes::new(&scene, &backend).unwrap();
    let generic = SceneTracer { scene: &scene, backend: &backend };
    let s = DisplayRenderSettings::default();
    let hidden = Progress::hidden();
    let mut g = c.benchmark_group("display_540");
    g.sample_size(10);
    g.bench_function("LC fused", |b| {
        b.iter(|| render_display_image(&display, Method::LensletCenter, &s, &fused, &hidden))
    });
    g.bench_function("LA5 fused", |b| {
        b.iter(|| render_display_image(&display, Method::LensletAverage { grid: 5 }, &s, &fused, &hidden))
    });
    g.bench_function("LA5 generic", |b| {
        b.iter(|| render_display_image(&display, Method::LensletAverage { grid: 5 }, &s, &generic, &hidden))
    });
    g.finish();

    let images: Vec<RgbImage> = [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 5 }]
        .iter()
        .map(|m| render_display_image(&display, *m, &s, &fused, &hidden).unwrap())
        .collect();
    let stack = DisplayStack::new(&display, &images.iter().collect::<Vec<_>>()).unwrap();
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8);
    let retina = Retina { resolution: 128, ..Retina::default() };
    let mut g = c.benchmark_group("retina_128_52_samples");
    g.sample_size(10);
    g.bench_function("simulate 3 methods", |b| b.iter(|| simulate_stack(&display, &eye, &retina, &stack, &hidden)));
    g.bench_function("ground truth fused", |b| b.iter(|| ground_truth(&eye, &retina, &fused, &hidden)));
    g.finish();

    let a = ground_truth(&eye, &Retina::default(), &fused, &hidden);
    let bimg = ground_truth(&Eye::pinhole(), &Retina::default(), &fused, &hidden);
    c.bench_function("ssim 512x512 rgb", |b| b.iter(|| ssim(&a, &bimg, SsimConstants::Wang2004)));

    let chart = usaf::framework_chart();
    let pts: Vec<DVec2> =
        (0..4096).map(|i| DVec2::new((i % 64) as f64 / 32.0 - 1.0, (i / 64) as f64 / 32.0 - 1.0)).collect();
    c.bench_function("chart lookup grid x4096", |b| {
        b.iter(|| pts.iter().filter(|p| chart.is_bar(black_box(**p))).count())
    });
    c.bench_function("chart lookup scan x4096", |b| {
        b.iter(|| pts.iter().filter(|p| chart.is_bar_brute_force(black_box(**p))).count())
    });
}

/// Eq. (1): retina -> pupil -> lenslet plane -> refraction at the nearest lenslet -> LCD, for
/// 4096 (retina direction, pupil point) pairs: the reference `eye_to_lcd` and the simulation's
/// `FastTransfer` (per-eye constants folded in).
fn lenslet_refraction(c: &mut Criterion) {
    let display = Display::paper();
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8);
    let pupil = eye.pupil_samples();
    let fast = FastTransfer::new(&display, &eye, &pupil);
    let rays: Vec<(DVec2, usize)> = (0..4096)
        .map(|i| (DVec2::new((i % 64) as f64 / 64.0 * 0.6 - 0.3, (i / 64) as f64 / 64.0 * 0.6 - 0.3), i % pupil.len()))
        .collect();
    let mut g = c.benchmark_group("lenslet_refraction_x4096");
    g.bench_function("eye_to_lcd", |b| {
        b.iter(|| {
            rays.iter().fold(DVec2::ZERO, |acc, (t, k)| acc + eye_to_lcd(&display, &eye, black_box(*t), pupil[*k]).lcd)
        })
    });
    g.bench_function("FastTransfer::lcd_point", |b| {
        b.iter(|| rays.iter().fold(DVec2::ZERO, |acc, (t, k)| acc + fast.lcd_point(black_box(*t), *k)))
    });
    g.finish();
}

/// Image-texture lookups (textured meshes): 4096 UVs, some outside [0, 1] (wrapping), on a
/// 256 x 256 texture, nearest and bilinear.
fn texture_lookup(c: &mut Criterion) {
    let n = 256;
    let texels: Vec<DVec3> = (0..n * n)
        .map(|i| DVec3::new((i % n) as f64 / n as f64, (i / n) as f64 / n as f64, ((i * 7) % 13) as f64 / 13.0))
        .collect();
    let uvs: Vec<DVec2> =
        (0..4096).map(|i| DVec2::new((i % 64) as f64 * 0.0371 - 0.5, (i / 64) as f64 * 0.0293 - 0.3)).collect();
    let mut g = c.benchmark_group("image_texture_x4096");
    for (name, filter) in [("nearest", Filter::Nearest), ("bilinear", Filter::Bilinear)] {
        let tex = ImageTexture::new(n, n, texels.clone(), filter, Wrap::Repeat).unwrap();
        g.bench_function(name, |b| b.iter(|| uvs.iter().fold(DVec3::ZERO, |acc, uv| acc + tex.sample(black_box(*uv)))));
    }
    g.finish();
}

criterion_group!(benches, kernels, lenslet_refraction, texture_lookup);
criterion_main!(benches);
