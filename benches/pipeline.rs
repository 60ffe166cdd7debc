//! Criterion benchmarks of the assessment pipeline's hot kernels (small sizes; the full-size
//! experiment is timed by `scripts/bench-assess.sh`).

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec2;
use std::hint::black_box;

use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::metrics::{ssim, SsimConstants};
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::retina::{simulate_stack, DisplayStack};
use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, SceneTracer};
use inimtrace::scene::{usaf, Scene};

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

criterion_group!(benches, kernels);
criterion_main!(benches);
