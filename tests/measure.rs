//! The converged measurement against answers known in closed form: a straight edge
//! seen by the pinhole eye (a pixel's value is the covered fraction of its square) and by a
//! defocused thin-lens eye (the edge blurred by the uniform pupil disk: a disk segment's area).
//! Its 95% intervals must cover the exact PSNR and SSIM, be calibrated over many seeds, agree
//! with the grid estimator at very high settings, and give the same bits at any thread count.

use std::path::PathBuf;

use glam::{DMat2, DVec2, DVec3};
use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::experiment::converged::{measure, naive_scores};
use inimtrace::experiment::{Experiment, ExperimentSpec};
use inimtrace::measure::adaptive::{measure_case, CaseMeasurement, Precision};
use inimtrace::measure::estimator::{DisplaySource, EyeSample, EyeToLcd, PairedSource, Replicates};
use inimtrace::measure::stats::gram_matrices;
use inimtrace::metrics::{self, SsimConstants};
use inimtrace::optics::transfer::eye_scene_ray;
use inimtrace::optics::transfer::eye_to_lcd;
use inimtrace::optics::transfer::FastTransfer;
use inimtrace::optics::{Display, Eye, Focus, Lattice, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::retina::{simulate, DisplayStack};
use inimtrace::render::{
    ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, RadianceField, SceneTracer,
};
use inimtrace::scene::{Material, Object, Rect, Scene, Shape};

/// Distance of the edge plane (mm).
const Z: f64 = 500.0;
/// Albedo of the white side: three different channels.
const ALBEDO: [f64; 3] = [1.0, 0.6, 0.3];

/// A plane at `Z` that is `ALBEDO` where the tangent seen from the pupil centre has
/// `tx >= edge`, black elsewhere (and behind).
fn edge_scene(edge: f64) -> Scene {
    let x0 = edge * Z;
    Scene {
        name: "edge".into(),
        objects: vec![Object {
            name: "white half".into(),
            shape: Shape::Rect(Rect::facing_eye(DVec3::new(x0 + 5e3, 0.0, Z), 1e4, 1e4)),
            material: Material::Albedo(DVec3::from_array(ALBEDO)),
        }],
        background: DVec3::ZERO,
        light: None,
        warnings: Vec::new(),
    }
}

/// Fraction of the unit disk with `x >= h` integrated from `h` to infinity:
/// `A(h) = int_h^inf F(u) du`, `F(u) = (acos u - u sqrt(1 - u^2)) / pi` on [-1, 1].
fn disk_tail_integral(h: f64) -> f64 {
    if h >= 1.0 {
        0.0
    } else if h <= -1.0 {
        1.0 + (-1.0 - h)
    } else {
        let s = (1.0 - h * h).sqrt();
        -(h * h.acos() - s + s * s * s / 3.0) / std::f64::consts::PI
    }
}

/// The exact value of retina column `col` (of `n`, field +-`t`) looking at the edge at tangent
/// `edge`, blurred by a uniform disk of tangent radius `rho` (0: the pinhole eye), times the
/// albedo: the pixel average of the covered fraction.
fn exact_column(col: usize, n: usize, t: f64, edge: f64, rho: f64) -> f64 {
    let step = 2.0 * t / n as f64;
    let (lo, hi) = (-t + col as f64 * step, -t + (col + 1) as f64 * step);
    if rho == 0.0 {
        ((hi - edge) / step).clamp(0.0, 1.0)
    } else {
        rho / step * (disk_tail_integral((edge - hi) / rho) - disk_tail_integral((edge - lo) / rho))
    }
}

fn exact_image(n: usize, t: f64, edge: f64, rho: f64) -> RgbImage {
    let mut img = RgbImage::new(n, n);
    for (p, px) in img.pixels.iter_mut().enumerate() {
        let v = exact_column(p % n, n, t, edge, rho);
        *px = ALBEDO.map(|a| (a * v) as f32);
    }
    img
}

/// Two views of edge scenes through the same eye rays: image 0 by `reference` (pinhole: the
/// chief ray), image 1 by `scored`.
struct TwoViews<'a> {
    reference: (&'a Eye, &'a dyn RadianceField),
    scored: (&'a Eye, &'a dyn RadianceField),
}

fn view(eye: &Eye, field: &dyn RadianceField, s: &EyeSample) -> [f64; 3] {
    let pupil = if eye.aperture == inimtrace::optics::Aperture::Pinhole { DVec2::ZERO } else { s.pupil };
    field.radiance(&eye_scene_ray(eye, s.tangent, pupil)).to_array()
}

impl PairedSource for TwoViews<'_> {
    fn images(&self) -> usize {
        2
    }
    fn eval(&self, samples: &[EyeSample], out: &mut [[f64; 3]]) {
        for (o, s) in out.chunks_exact_mut(2).zip(samples) {
            o[0] = view(self.reference.0, self.reference.1, s);
            o[1] = view(self.scored.0, self.scored.1, s);
        }
    }
}

fn retina(n: usize, t: f64) -> Retina {
    Retina { resolution: n, half_tangent: t, samples_per_pixel: 1 }
}

fn fixed_samples(replicates: usize, per_replicate: u32) -> Precision {
    Precision {
        psnr_ci95_db: 1e-9,
        ssim_ci95: 1e-9,
        max_samples_per_pixel: replicates as u64 * u64::from(per_replicate),
        deadline: None,
        initial_samples: per_replicate,
        replicates,
    }
}

fn to_target(psnr: f64, ssim: f64) -> Precision {
    Precision {
        psnr_ci95_db: psnr,
        ssim_ci95: ssim,
        max_samples_per_pixel: 8 * 4096,
        deadline: None,
        initial_samples: 4,
        replicates: 8,
    }
}

/// The defocused eye of the tests: 4 mm pupil focused at 300 mm, so an edge at `Z` = 500 mm is
/// blurred by a disk of tangent radius `2 |1/500 - 1/300|`.
fn defocused() -> (Eye, f64) {
    let eye = Eye::thin_lens(4.0, Focus::Millimetres(300.0), 8);
    (eye, 2.0 * (1.0 / Z - 1.0 / 300.0).abs())
}

#[test]
fn the_closed_form_disk_segment_matches_quadrature() {
    // The pixel average of the blurred edge by a fine midpoint rule over the pixel of the
    // disk-segment fraction F: the closed form must agree to 1e-10.
    let f = |u: f64| {
        if u <= -1.0 {
            1.0
        } else if u >= 1.0 {
            0.0
        } else {
            (u.acos() - u * (1.0 - u * u).sqrt()) / std::f64::consts::PI
        }
    };
    let (n, t, edge, rho) = (32, 0.02, 0.0013, 0.0027);
    let step = 2.0 * t / n as f64;
    for col in 0..n {
        let lo = -t + col as f64 * step;
        let m = 200_000;
        let q: f64 =
            (0..m).map(|i| f((edge - (lo + (i as f64 + 0.5) * step / m as f64)) / rho)).sum::<f64>() / m as f64;
        assert!((q - exact_column(col, n, t, edge, rho)).abs() < 1e-10, "{col}: {q}");
    }
    // Far from the edge: 0 and 1.
    assert_eq!(exact_column(0, n, t, edge, rho), 0.0);
    assert!((exact_column(n - 1, n, t, edge, rho) - 1.0).abs() < 1e-12);
}

/// Checks that the intervals of several seeds cover `exact` (at least 4 of 5, all within 3
/// half-widths) with half-widths below `max_hw`.
fn assert_covers(name: &str, runs: &[(f64, f64)], exact: f64, max_hw: f64) {
    let covered = runs.iter().filter(|(v, h)| (v - exact).abs() <= *h).count();
    for (v, h) in runs {
        assert!(*h > 0.0 && *h <= max_hw, "{name}: half-width {h} (value {v}, exact {exact})");
        assert!((v - exact).abs() <= 3.0 * h, "{name}: {v} +- {h} is far from the exact {exact}");
    }
    assert!(covered >= runs.len() - 1, "{name}: only {covered} of {} intervals cover {exact}: {runs:?}", runs.len());
}

#[test]
fn pinhole_edges_exact_psnr_and_ssim_are_covered() {
    let (n, t) = (32, 0.02);
    let (ea, eb) = (0.0013, 0.0021);
    let (sa, sb) = (edge_scene(ea), edge_scene(eb));
    let (ba, bb) = (AnalyticRects::new(&sa).unwrap(), AnalyticRects::new(&sb).unwrap());
    let (fa, fb) = (SceneTracer { scene: &sa, backend: &ba }, SceneTracer { scene: &sb, backend: &bb });
    let eye = Eye::pinhole();
    let source = TwoViews { reference: (&eye, &fa), scored: (&eye, &fb) };
    let (xa, xb) = (exact_image(n, t, ea, 0.0), exact_image(n, t, eb, 0.0));
    let psnr = metrics::psnr(&xb, &xa).unwrap();
    let ssim = metrics::ssim(&xb, &xa, SsimConstants::Wang2004).unwrap();
    let mut runs = (Vec::new(), Vec::new(), Vec::new());
    for seed in 1..=5 {
        let m = measure(&source, seed, 0, &eye, &retina(n, t), SsimConstants::Wang2004, &to_target(0.02, 0.002));
        let c = m.cells[0];
        assert!(c.target_met, "{c:?}");
        runs.0.push((c.psnr.mean, c.psnr.ci95.unwrap()));
        runs.1.push((c.ssim.mean, c.ssim.ci95.unwrap()));
        runs.2.push((c.psnr.channels[2], c.psnr.channels_ci95.unwrap()[2]));
    }
    assert_covers("PSNR", &runs.0, psnr.mean, 0.02);
    assert_covers("SSIM", &runs.1, ssim.mean, 0.002);
    assert_covers("PSNR (B)", &runs.2, psnr.channels[2], 0.05);
}

#[test]
fn a_defocused_edge_against_the_pinhole_edge_is_covered() {
    let (n, t, edge) = (32, 0.02, 0.0013);
    let scene = edge_scene(edge);
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = SceneTracer { scene: &scene, backend: &backend };
    let (eye, rho) = defocused();
    let pin = Eye::pinhole();
    let source = TwoViews { reference: (&pin, &field), scored: (&eye, &field) };
    let (sharp, blurred) = (exact_image(n, t, edge, 0.0), exact_image(n, t, edge, rho));
    let psnr = metrics::psnr(&blurred, &sharp).unwrap();
    let ssim = metrics::ssim(&blurred, &sharp, SsimConstants::Wang2004).unwrap();
    assert!(psnr.mean < 30.0 && ssim.mean < 0.99, "a visible blur: {psnr:?} {ssim:?}");
    let mut runs = (Vec::new(), Vec::new());
    for seed in 11..=15 {
        let m = measure(&source, seed, 1, &eye, &retina(n, t), SsimConstants::Wang2004, &to_target(0.02, 0.002));
        let c = m.cells[0];
        assert!(c.target_met, "{c:?}");
        runs.0.push((c.psnr.mean, c.psnr.ci95.unwrap()));
        runs.1.push((c.ssim.mean, c.ssim.ci95.unwrap()));
        // The measured images are the exact ones up to the noise.
        let gt = m.replicates.mean_image(0);
        let img = m.replicates.mean_image(1);
        assert!(metrics::psnr(&gt, &sharp).unwrap().mean > 40.0);
        assert!(metrics::psnr(&img, &blurred).unwrap().mean > 35.0);
    }
    assert_covers("PSNR", &runs.0, psnr.mean, 0.02);
    assert_covers("SSIM", &runs.1, ssim.mean, 0.002);
}

#[test]
fn intervals_are_calibrated_and_the_naive_estimate_is_biased() {
    // Few samples (8 replicates x 4), so the noise is large; 200 seeds.
    let (n, t, edge) = (24, 0.015, 0.0011);
    let scene = edge_scene(edge);
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = SceneTracer { scene: &scene, backend: &backend };
    let (eye, rho) = defocused();
    let pin = Eye::pinhole();
    let source = TwoViews { reference: (&pin, &field), scored: (&eye, &field) };
    let (sharp, blurred) = (exact_image(n, t, edge, 0.0), exact_image(n, t, edge, rho));
    let exact_psnr = metrics::psnr(&blurred, &sharp).unwrap();
    let exact_ssim = metrics::ssim(&blurred, &sharp, SsimConstants::Wang2004).unwrap();
    // The exact MSE of the green channel, in f64 (the f32 images round it by ~1e-8).
    let exact_mse: f64 = (0..n * n)
        .map(|p| {
            let d = ALBEDO[1] * (exact_column(p % n, n, t, edge, rho) - exact_column(p % n, n, t, edge, 0.0));
            d * d
        })
        .sum::<f64>()
        / (n * n) as f64;
    let seeds = 200u64;
    let (mut psnr_in, mut ssim_in) = (0, 0);
    let (mut mse, mut naive_mse, mut naive_ssim, mut ssim_est) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for seed in 0..seeds {
        let m = measure(&source, 1000 + seed, 0, &eye, &retina(n, t), SsimConstants::Wang2004, &fixed_samples(8, 4));
        assert_eq!(m.samples_per_pixel(), 32);
        let c = m.cells[0];
        psnr_in += ((c.psnr.mean - exact_psnr.mean).abs() <= c.psnr.ci95.unwrap()) as usize;
        ssim_in += ((c.ssim.mean - exact_ssim.mean).abs() <= c.ssim.ci95.unwrap()) as usize;
        ssim_est.push(c.ssim.mean);
        let g = &gram_matrices(&m.replicates)[0];
        mse.push(g.mse(1, |_| true));
        naive_mse.push(g.naive_mse(1));
        naive_ssim.push(naive_scores(&m.replicates, SsimConstants::Wang2004).unwrap()[0].1.mean);
    }
    let mean_se = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64;
        (m, (var / v.len() as f64).sqrt())
    };
    let (psnr_cov, ssim_cov) = (psnr_in as f64 / seeds as f64, ssim_in as f64 / seeds as f64);
    println!("coverage of the 95% intervals over {seeds} seeds: PSNR {psnr_cov:.3}, SSIM {ssim_cov:.3}");
    assert!(psnr_cov >= 0.90, "PSNR coverage {psnr_cov}");
    assert!(ssim_cov >= 0.90, "SSIM coverage {ssim_cov}");
    // Unbiased: the cross-replicate MSE averages to the exact MSE.
    let (m, se) = mean_se(&mse);
    println!("MSE (G): exact {exact_mse:.6e}, cross-replicate {m:.6e} +- {se:.1e}");
    assert!((m - exact_mse).abs() < 3.0 * se, "cross-replicate MSE {m} +- {se} vs exact {exact_mse}");
    // Negative control: the MSE of the replicates' mean image carries the noise's variance, so
    // it is too large (PSNR too low) by far more than its own standard error.
    let (nm, nse) = mean_se(&naive_mse);
    println!("MSE (G): naive {nm:.6e} +- {nse:.1e}");
    assert!(nm - exact_mse > 10.0 * nse, "naive MSE {nm} +- {nse} should exceed the exact {exact_mse}");
    // The naive SSIM is biased too (noise adds local variance: SSIM too low); the
    // cross-replicate one is not, within its standard error.
    let (ns, nsse) = mean_se(&naive_ssim);
    let (cs, csse) = mean_se(&ssim_est);
    println!("SSIM: exact {:.5}, cross-replicate {cs:.5} +- {csse:.1e}, naive {ns:.5} +- {nsse:.1e}", exact_ssim.mean);
    assert!(exact_ssim.mean - ns > 5.0 * nsse, "naive SSIM {ns} +- {nsse} vs exact {}", exact_ssim.mean);
    assert!((cs - exact_ssim.mean).abs() < 3.0 * csse, "cross-replicate SSIM {cs} +- {csse} vs {}", exact_ssim.mean);

    // Adaptive sampling stops when the estimated half-width meets the target, which favours runs
    // whose half-width is underestimated; the intervals must stay calibrated all the same.
    let (mut psnr_in, mut ssim_in, mut spp) = (0, 0, Vec::new());
    for seed in 0..200 {
        let m = measure(&source, 5000 + seed, 0, &eye, &retina(n, t), SsimConstants::Wang2004, &to_target(0.05, 0.002));
        let c = m.cells[0];
        assert!(c.target_met);
        psnr_in += ((c.psnr.mean - exact_psnr.mean).abs() <= c.psnr.ci95.unwrap()) as usize;
        ssim_in += ((c.ssim.mean - exact_ssim.mean).abs() <= c.ssim.ci95.unwrap()) as usize;
        spp.push(m.samples_per_pixel());
    }
    spp.sort();
    println!(
        "adaptive (PSNR +-0.05 dB): coverage PSNR {psnr_in}/200, SSIM {ssim_in}/200; samples per pixel {}..{} (median {})",
        spp[0],
        spp[199],
        spp[100]
    );
    // 95% nominal (the same intervals at a fixed sample count cover 94.5-96% here); 200 seeds have
    // a binomial standard error of 1.5 points: 88% allows for the small loss that stopping on an
    // estimated half-width costs, and fails an interval that is really too narrow.
    assert!(psnr_in >= 176 && ssim_in >= 176, "adaptive coverage: PSNR {psnr_in}/200, SSIM {ssim_in}/200");
    assert!(spp[0] > 32, "the target needs more than the first round");
}

/// The paper's display with a quarter of its LCD pixels per side (faster display images).
fn small_display() -> Display {
    let mut d = Display::paper();
    d.lcd.resolution = [540, 540];
    d
}

#[test]
fn the_eye_to_lcd_transfer_is_eq_1() {
    let display = Display::paper();
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8);
    let t = EyeToLcd::new(&display, &eye);
    for k in 0..2000 {
        let f = k as f64 / 2000.0;
        let tangent = DVec2::new(0.3 * (f * 7.1).sin(), 0.3 * (f * 3.3).cos());
        let pupil = DVec2::new(2.5 * f * (f * 40.0).cos(), 2.5 * f * (f * 40.0).sin());
        let slow = eye_to_lcd(&display, &eye, tangent, pupil).lcd;
        assert!((t.lcd_point(tangent, pupil) - slow).length() < 1e-12, "{tangent} {pupil}");
    }
}

#[test]
fn eye_to_lcd_and_fast_transfer_agree_bit_for_bit() {
    // At every pupil-grid point, for an eye off the axis and off the pupil plane, on square and
    // tilted lenslets: the same LCD point (to the bit) and the same pixels, one ray or batched.
    let mut tilted = Display::paper();
    let p = tilted.lenslets.matrix.x_axis.x;
    tilted.lenslets =
        Lattice::new(DVec2::new(0.13, -0.07), DMat2::from_angle(0.3) * DMat2::from_diagonal(DVec2::splat(p))).unwrap();
    for display in [Display::paper(), tilted] {
        let mut eye = Eye::thin_lens(5.0, Focus::Millimetres(350.0), 8);
        eye.position = DVec3::new(0.7, -0.4, 1.5);
        let pupil = eye.pupil_samples();
        let fast = FastTransfer::new(&display, &eye, &pupil);
        let t = EyeToLcd::new(&display, &eye);
        let tangents: Vec<DVec2> = (0..400)
            .map(|k| {
                let f = k as f64 / 400.0;
                DVec2::new(0.3 * (f * 7.1).sin(), 0.3 * (f * 3.3).cos())
            })
            .collect();
        let (mut scratch, mut batch_fast, mut batch_t) =
            (Vec::new(), vec![0u32; tangents.len()], vec![0u32; tangents.len()]);
        let mut hits = 0;
        for (k, &s) in pupil.iter().enumerate() {
            for &tangent in &tangents {
                let (a, b) = (fast.lcd_point(tangent, k), t.lcd_point(tangent, s));
                assert_eq!((a.x.to_bits(), a.y.to_bits()), (b.x.to_bits(), b.y.to_bits()), "{tangent} {s}");
                assert_eq!(fast.pixel_index(tangent, k), t.pixel_index(tangent, s));
                hits += usize::from(t.pixel_index(tangent, s).is_some());
            }
            fast.pixel_indices(&tangents, k, &mut scratch, &mut batch_fast);
            let samples: Vec<EyeSample> = tangents
                .iter()
                .map(|&tangent| EyeSample { tangent, pupil: s, spectral: 0.0, diffraction: [0.0; 4] })
                .collect();
            t.pixel_indices(&samples, &mut batch_t);
            assert_eq!(batch_fast, batch_t, "pupil sample {k}");
        }
        assert!(hits > pupil.len() * tangents.len() / 2, "most rays meet the LCD: {hits}");
    }
}

#[test]
fn batched_lcd_pixels_are_the_single_ray_pixels() {
    // The paper's square lenslets and a tilted lattice (the generic nearest-cell path); rays
    // that land on lenslet borders, off the LCD, and NaN.
    let mut tilted = Display::paper();
    let p = tilted.lenslets.matrix.x_axis.x;
    tilted.lenslets =
        Lattice::new(DVec2::new(0.13, -0.07), DMat2::from_angle(0.3) * DMat2::from_diagonal(DVec2::splat(p))).unwrap();
    for display in [Display::paper(), tilted] {
        let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8);
        let t = EyeToLcd::new(&display, &eye);
        let mut samples: Vec<EyeSample> = (0..5000)
            .map(|k| {
                let f = k as f64 / 5000.0;
                EyeSample {
                    tangent: DVec2::new(0.3 * (f * 7.1).sin(), 0.3 * (f * 3.3).cos()),
                    pupil: DVec2::new(2.5 * f * (f * 40.0).cos(), 2.5 * f * (f * 40.0).sin()),
                    spectral: 0.0,
                    diffraction: [0.0; 4],
                }
            })
            .collect();
        samples.push(EyeSample {
            tangent: DVec2::new(f64::NAN, 0.0),
            pupil: DVec2::ZERO,
            spectral: 0.0,
            diffraction: [0.0; 4],
        });
        samples.push(EyeSample {
            tangent: DVec2::splat(10.0),
            pupil: DVec2::ZERO,
            spectral: 0.0,
            diffraction: [0.0; 4],
        });
        let mut batch = vec![0u32; samples.len()];
        t.pixel_indices(&samples, &mut batch);
        let (mut on, mut off) = (0, 0);
        for (s, &b) in samples.iter().zip(&batch) {
            let one = t.pixel_index(s.tangent, s.pupil).map_or(u32::MAX, |i| i as u32);
            assert_eq!(b, one, "{s:?}");
            if one == u32::MAX {
                off += 1;
            } else {
                on += 1;
            }
        }
        assert!(on > 4000 && off >= 2, "{on} on the LCD, {off} off");
    }
}

/// The paper's scene and LC's display image of it (on a 540 x 540 LCD); around tangent 0 the eye
/// sees the near chart's corner in front of the centre chart.
struct Corner {
    scene: Scene,
    display: Display,
    /// 5 mm pupil focused at 400 mm.
    eye: Eye,
    lc: RgbImage,
}

fn corner() -> Corner {
    let scene = Scene::paper();
    let display = small_display();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = SceneTracer { scene: &scene, backend: &backend };
    let lc = render_display_image(
        &display,
        Method::LensletCenter,
        &DisplayRenderSettings::default(),
        &field,
        &Progress::hidden(),
    )
    .unwrap();
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8);
    Corner { scene, display, eye, lc }
}

/// The converged PSNR and SSIM of LC's perceived image of the corner against its ground truth,
/// and the grid estimator's at two levels: `(k x k per retina pixel, pupil grid n)`.
fn converged_and_grid(c: &Corner, eye: &Eye, retina: Retina, levels: [(usize, usize); 2]) -> [(f64, f64, f64, f64); 3] {
    let backend = AnalyticRects::new(&c.scene).unwrap();
    let field = SceneTracer { scene: &c.scene, backend: &backend };
    let grid = |k: usize, n: usize| {
        let eye = Eye { pupil_grid: n, ..eye.clone() };
        let r = Retina { samples_per_pixel: k, ..retina };
        let gt = ground_truth(&eye, &r, &field, &Progress::hidden());
        let sim = simulate(&c.display, &eye, &r, &[&c.lc], &Progress::hidden()).unwrap().remove(0);
        let (p, s) = (metrics::psnr(&sim, &gt).unwrap(), metrics::ssim(&sim, &gt, SsimConstants::Wang2004).unwrap());
        (p.mean, 0.0, s.mean, 0.0)
    };
    let stack = DisplayStack::new(&c.display, &[&c.lc]).unwrap();
    let source = DisplaySource::new(&c.display, eye, &field, &stack);
    let m = measure(&source, 7, 2, eye, &retina, SsimConstants::Wang2004, &to_target(0.02, 0.002));
    let cell = m.cells[0];
    assert!(cell.target_met);
    let conv = (cell.psnr.mean, cell.psnr.ci95.unwrap(), cell.ssim.mean, cell.ssim.ci95.unwrap());
    [conv, grid(levels[0].0, levels[0].1), grid(levels[1].0, levels[1].1)]
}

/// `converged` agrees with the grid's higher level within its 95% half-width plus the grid's
/// own error, stated as the change between the grid's two levels.
fn assert_agree(name: &str, [conv, coarse, fine]: [(f64, f64, f64, f64); 3]) {
    println!(
        "{name}: converged PSNR {:.4} +- {:.4}, SSIM {:.5} +- {:.5}; grid {coarse:?} then {fine:?}",
        conv.0, conv.1, conv.2, conv.3
    );
    let (psnr_err, ssim_err) = ((fine.0 - coarse.0).abs(), (fine.2 - coarse.2).abs());
    assert!((conv.0 - fine.0).abs() <= conv.1 + psnr_err, "{name} PSNR: {conv:?} vs {fine:?} (grid error {psnr_err})");
    assert!((conv.2 - fine.2).abs() <= conv.3 + ssim_err, "{name} SSIM: {conv:?} vs {fine:?} (grid error {ssim_err})");
    assert!(conv.0 < 30.0, "{name}: not a trivial image");
}

#[test]
fn converged_agrees_with_the_grid_estimator_at_high_settings() {
    // Pinhole: 32 x 32 and 64 x 64 samples per retina pixel (the grid then moves by 0.004 dB).
    let c = corner();
    assert_agree("pinhole", converged_and_grid(&c, &Eye::pinhole(), retina(24, 0.012), [(32, 1), (64, 1)]));
    // Thin lens (2 mm pupil, focused at 400 mm): 12 x 12 samples x pupil grid 24 and 16 x 16 x
    // pupil grid 32 (812 pupil samples). Regular grids alias with the display's pixel and
    // lenslet structure, so even these levels differ by about 0.35 dB (PSNR) and 0.009 (SSIM)
    // here; at 24 x 24 x 48 (too slow for the suite) the grid is 21.064 dB / 0.8777, within
    // 0.02 dB / 0.0002 of the converged value.
    let eye = Eye::thin_lens(2.0, Focus::Millimetres(400.0), 8);
    assert_agree("thin lens", converged_and_grid(&c, &eye, retina(16, 0.008), [(12, 24), (16, 32)]));
}

fn run_in_pool(threads: usize, f: impl FnOnce() -> CaseMeasurement + Send) -> CaseMeasurement {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

#[test]
fn the_same_seed_gives_the_same_bits_at_any_thread_count() {
    let c = corner();
    let backend = AnalyticRects::new(&c.scene).unwrap();
    let field = SceneTracer { scene: &c.scene, backend: &backend };
    let stack = DisplayStack::new(&c.display, &[&c.lc, &c.lc]).unwrap();
    let source = DisplaySource::new(&c.display, &c.eye, &field, &stack);
    let retina = retina(40, 0.02);
    let run = |threads| {
        run_in_pool(threads, || {
            measure(&source, 3, 0, &c.eye, &retina, SsimConstants::Wang2004, &to_target(0.05, 0.005))
        })
    };
    let (one, two, again) = (run(1), run(2), run(2));
    for other in [&two, &again] {
        assert!(one.replicates == other.replicates, "replicate images differ");
        assert_eq!(one.cells, other.cells);
        assert_eq!(one.samples_per_pixel(), other.samples_per_pixel());
    }
    // Two identical display images give identical scores; a different seed other numbers.
    assert_eq!(one.cells[0], one.cells[1]);
    let other = measure(&source, 4, 0, &c.eye, &retina, SsimConstants::Wang2004, &to_target(0.05, 0.005));
    assert_ne!(one.cells[0].psnr.mean, other.cells[0].psnr.mean);
}

#[test]
fn a_case_measured_in_recycled_storage_gives_the_same_bits() {
    // `assess` measures every eye case in the replicate buffer of the case before. Whatever that
    // buffer holds (another case's means, garbage, another size), the result is a fresh run's.
    let c = corner();
    let backend = AnalyticRects::new(&c.scene).unwrap();
    let field = SceneTracer { scene: &c.scene, backend: &backend };
    let stack = DisplayStack::new(&c.display, &[&c.lc, &c.lc]).unwrap();
    let source = DisplaySource::new(&c.display, &c.eye, &field, &stack);
    let (small, large) = (retina(24, 0.02), retina(40, 0.02));
    let sampler = inimtrace::experiment::converged::case_sampler(7, 1, &c.eye);
    let target = to_target(0.05, 0.005);
    let run = |retina: &Retina, storage| {
        measure_case(&source, &sampler, retina, SsimConstants::Wang2004, &target, &Progress::hidden(), storage)
    };
    let fresh = run(&small, None);
    let after_other_case = run(&large, None).replicates;
    let garbage =
        Replicates::from_fn(40, 8, 3, 5, |p, r, k, ch| if (p + r + k + ch) % 3 == 0 { f32::NAN } else { -7.5 });
    let too_small = Replicates::new(8, 3, 3);
    for storage in [after_other_case, garbage, too_small] {
        let again = run(&small, Some(storage));
        assert!(again.replicates == fresh.replicates, "replicate means differ");
        assert_eq!(again.cells, fresh.cells);
        assert_eq!(again.rounds.len(), fresh.rounds.len());
    }
}

#[test]
fn replicates_are_nested_and_misses_count_as_black() {
    // Extending 4 -> 8 samples equals taking 8 at once (up to the f32 rounding of the stored
    // means), and every sample of a ray that misses the LCD counts as black.
    let c = corner();
    let backend = AnalyticRects::new(&c.scene).unwrap();
    let field = SceneTracer { scene: &c.scene, backend: &backend };
    let white = RgbImage::filled(540, 540, [1.0; 3]);
    let stack = DisplayStack::new(&c.display, &[&white]).unwrap();
    let source = DisplaySource::new(&c.display, &c.eye, &field, &stack);
    // A field wider than the display: the outer pixels see past the LCD.
    let wide = retina(16, 0.6);
    let sampler = inimtrace::experiment::converged::case_sampler(5, 0, &c.eye);
    let mut a = Replicates::new(16, 3, 2);
    a.extend(&source, &sampler, &wide, 4, &Progress::hidden());
    a.extend(&source, &sampler, &wide, 8, &Progress::hidden());
    let mut b = Replicates::new(16, 3, 2);
    b.extend(&source, &sampler, &wide, 8, &Progress::hidden());
    let (mut inside, mut outside, mut partial) = (0, 0, 0);
    for p in 0..256 {
        for r in 0..3 {
            for ch in 0..3 {
                let (x, y) = (a.value(p, r, 1, ch), b.value(p, r, 1, ch));
                assert!((x - y).abs() <= 1e-6, "{p} {r}: {x} vs {y}");
            }
            let v = b.value(p, r, 1, 0);
            // Means of 8 samples of 0 or 1.
            assert!((v * 8.0 - (v * 8.0).round()).abs() < 1e-5, "{v}");
            if v == 1.0 {
                inside += 1;
            } else if v == 0.0 {
                outside += 1;
            } else {
                partial += 1;
            }
        }
    }
    assert!(inside > 50 && outside > 50, "{inside} {outside} {partial}");
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn the_shipped_converged_experiment_is_the_builtin_and_grid_settings_are_refused() {
    let loaded = Experiment::load(&root().join("experiments/paper-converged.toml")).unwrap();
    let builtin = ExperimentSpec::paper_converged();
    let spec = ExperimentSpec { scene: builtin.scene.clone(), display: builtin.display.clone(), ..loaded.spec.clone() };
    assert_eq!(spec, builtin);
    assert_eq!(loaded.measurement, inimtrace::measure::spec::MeasurementSpec::default());
    assert_eq!(Experiment::load(&root().join("experiments/paper.toml")).unwrap().measurement.estimator.name(), "grid");
    // The printed built-in loads back to itself.
    let dir = tempfile::tempdir().unwrap();
    let printed = dir.path().join("p.toml");
    std::fs::write(&printed, builtin.to_toml()).unwrap();
    assert_eq!(Experiment::load(&printed).unwrap().spec, builtin);
    // Grid-only settings under the converged estimator name the file and the field.
    let text = std::fs::read_to_string(root().join("experiments/paper-converged.toml"))
        .unwrap()
        .replace("retina_resolution = 512", "retina_resolution = 512\npupil_grid = 16")
        .replace("../scenes/paper.toml", "builtin:paper")
        .replace("../displays/paper.toml", "builtin:paper");
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, text).unwrap();
    let e = Experiment::load(&bad).unwrap_err().to_string();
    assert!(e.contains("bad.toml") && e.contains("eye.pupil_grid"), "{e}");
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(args)
        .arg("--quiet")
        .output()
        .expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn assess_that_misses_a_target_says_so_at_the_end_and_strict_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    let exp = root().join("experiments/paper-converged.toml");
    let out = dir.path().join("out");
    let args = |strict: bool| {
        let mut a: Vec<String> = ["assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        for set in [
            "display.lcd.resolution=[540, 540]",
            "eye.retina_resolution=32",
            "methods=[\"LC\"]",
            "eye_cases=[{ name = \"Eye\", focus_diopters = 2.5 }]",
            "measurement.max_seconds=0.000001",
        ] {
            a.extend(["--set".to_string(), set.to_string()]);
        }
        if strict {
            a.push("--strict".into());
        }
        std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(a).output().unwrap()
    };
    let o = args(false);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let note = stderr.lines().last().unwrap();
    assert!(note.starts_with("warning: 1 of 1 score missed their precision target (PSNR ± 0.02 dB"), "{stderr}");
    assert!(note.contains(&out.join("table.md").display().to_string()), "{stderr}");
    let table = std::fs::read_to_string(out.join("table.md")).unwrap();
    assert!(table.contains("NOT met in 1 of 1 cell ("), "{table}");
    let o = args(true);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("error: --strict: 1 score missed their precision target"), "{stderr}");
    assert!(out.join("results.json").is_file(), "the results are written all the same");
}

#[test]
fn assess_reports_intervals_samples_and_targets_and_is_thread_count_independent() {
    let dir = tempfile::tempdir().unwrap();
    let display =
        std::fs::read_to_string(root().join("displays/paper.toml")).unwrap().replace("[2160, 2160]", "[540, 540]");
    std::fs::write(dir.path().join("display.toml"), display).unwrap();
    let exp = std::fs::read_to_string(root().join("experiments/paper-converged.toml"))
        .unwrap()
        .replace("../scenes/paper.toml", "builtin:paper")
        .replace("../displays/paper.toml", "display.toml")
        .replace("retina_resolution = 512", "retina_resolution = 48")
        .replace("psnr_ci95_db = 0.02", "psnr_ci95_db = 0.1")
        .replace("ssim_ci95 = 0.002", "ssim_ci95 = 0.01")
        .replace("max_samples_per_pixel = 4096", "max_samples_per_pixel = 64")
        .replace("name = \"paper-converged\"", "name = \"small-converged\"");
    let path = dir.path().join("small.toml");
    std::fs::write(&path, exp).unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    let (ok, stdout, stderr) = inimtrace(&["assess", path.to_str().unwrap(), "--out", two.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let (ok, _, stderr) =
        inimtrace(&["assess", path.to_str().unwrap(), "--out", one.to_str().unwrap(), "--threads", "1"]);
    assert!(ok, "{stderr}");

    // table.md: value ± half-width in every cell, the estimator, samples and targets.
    let table = std::fs::read_to_string(two.join("table.md")).unwrap();
    assert_eq!(table, stdout);
    for case in ["Pin", "Near", "Cen", "Far"] {
        let row = table.lines().find(|l| l.starts_with(&format!("| {case} |"))).unwrap();
        assert_eq!(row.matches('±').count(), 6, "{row}");
    }
    for needle in ["Estimator: converged", "Samples per retina pixel (all replicates): Pin ", "Targets (PSNR ± 0.1 dB"]
    {
        assert!(table.contains(needle), "table.md lacks `{needle}`:\n{table}");
    }

    // results.json: intervals, samples, replicates, targets; the settings.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(two.join("results.json")).unwrap()).unwrap();
    let scores = json["scores"].as_array().unwrap();
    assert_eq!(scores.len(), 12);
    for s in scores {
        for metric in ["psnr", "ssim"] {
            let h = s[metric]["ci95"].as_f64().unwrap();
            assert!(h > 0.0 && h.is_finite(), "{s}");
            assert_eq!(s[metric]["channels_ci95"].as_array().unwrap().len(), 3);
        }
        let spp = s["samples_per_pixel"].as_u64().unwrap();
        assert!((32..=64).contains(&spp) && spp % 8 == 0, "{s}");
        assert_eq!(s["replicates"].as_u64(), Some(8));
        let met = s["target_met"].as_bool().unwrap();
        assert_eq!(met, s["psnr"]["ci95"].as_f64().unwrap() <= 0.1 && s["ssim"]["ci95"].as_f64().unwrap() <= 0.01);
    }
    let m = &json["settings"]["measurement"];
    assert_eq!(m["estimator"], "converged");
    assert_eq!(
        (m["seed"].as_u64(), m["replicates"].as_u64(), m["max_samples_per_pixel"].as_u64()),
        (Some(1), Some(8), Some(64))
    );
    assert_eq!((m["psnr_ci95_db"].as_f64(), m["ssim_ci95"].as_f64()), (Some(0.1), Some(0.01)));

    // results.csv: the two interval columns, filled for every score row; then the samples,
    // replicates and whether the targets were met, as in results.json.
    let csv = std::fs::read_to_string(two.join("results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(",psnr_ci95_db,ssim_ci95,samples_per_pixel,replicates,target_met"));
    for l in csv.lines().filter(|l| l.starts_with("score,")) {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), 14, "{l}");
        assert!(f[9].parse::<f64>().unwrap() > 0.0 && f[10].parse::<f64>().unwrap() > 0.0, "{l}");
        let s = scores.iter().find(|s| s["method"] == f[2] && s["eye_case"] == f[3]).unwrap();
        assert_eq!(f[11], s["samples_per_pixel"].as_u64().unwrap().to_string(), "{l}");
        assert_eq!(f[12], "8", "{l}");
        assert_eq!(f[13], s["target_met"].as_bool().unwrap().to_string(), "{l}");
    }

    // EXRs: the replicates' mean, with the estimator and samples in their headers.
    let attrs = inimtrace::io::exr::read_attributes(&two.join("sim_LA_Near.exr")).unwrap();
    let get = |k: &str| attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.clone()).unwrap_or_default();
    assert!(get("inimtrace:estimator").starts_with("converged"));
    let near = scores.iter().find(|s| s["eye_case"] == "Near").unwrap();
    assert_eq!(get("inimtrace:retina_samples_per_pixel"), near["samples_per_pixel"].as_u64().unwrap().to_string());
    assert_eq!(get("inimtrace:replicates"), "8");

    // One thread and two: the same numbers and images, bit for bit.
    let json1: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(one.join("results.json")).unwrap()).unwrap();
    assert_eq!(json1["scores"], json["scores"]);
    assert_eq!((json1["threads"].as_u64(), json["threads"].as_u64().map(|t| t >= 1)), (Some(1), Some(true)));
    for name in ["gt_Pin", "gt_Far", "sim_LC_Near", "sim_PC_Cen", "sim_LA_Far"] {
        let a = inimtrace::io::exr::read_rgb(&one.join(format!("{name}.exr"))).unwrap();
        let b = inimtrace::io::exr::read_rgb(&two.join(format!("{name}.exr"))).unwrap();
        assert!(a == b, "{name} differs between 1 and 2 threads");
    }
}

/// The scene tracer, asking for batches (as mesh backends do): the batched path of
/// `DisplaySource` must give the same bits as the one-ray path.
struct Batched<'a>(SceneTracer<'a, AnalyticRects>);

impl RadianceField for Batched<'_> {
    fn radiance(&self, ray: &inimtrace::ray::Ray) -> DVec3 {
        self.0.radiance(ray)
    }
    fn prefers_batches(&self) -> bool {
        true
    }
}

#[test]
fn batched_fields_give_the_same_bits_and_budgets_stop_sampling() {
    let c = corner();
    let backend = AnalyticRects::new(&c.scene).unwrap();
    let field = SceneTracer { scene: &c.scene, backend: &backend };
    let batched = Batched(SceneTracer { scene: &c.scene, backend: &backend });
    let stack = DisplayStack::new(&c.display, &[&c.lc]).unwrap();
    let r = retina(20, 0.01);
    let one = measure(
        &DisplaySource::new(&c.display, &c.eye, &field, &stack),
        9,
        1,
        &c.eye,
        &r,
        SsimConstants::Wang2004,
        &fixed_samples(4, 8),
    );
    let many = measure(
        &DisplaySource::new(&c.display, &c.eye, &batched, &stack),
        9,
        1,
        &c.eye,
        &r,
        SsimConstants::Wang2004,
        &fixed_samples(4, 8),
    );
    assert!(one.replicates == many.replicates);
    assert_eq!(one.cells, many.cells);
    // Budgets: out of samples, or out of time, with targets that cannot be met.
    assert_eq!(one.stopped_by, "sample budget");
    assert!(!one.cells[0].target_met);
    let source = DisplaySource::new(&c.display, &c.eye, &field, &stack);
    let late = Precision { deadline: Some(std::time::Instant::now()), ..to_target(1e-6, 1e-6) };
    let m = measure(&source, 9, 1, &c.eye, &r, SsimConstants::Wang2004, &late);
    assert_eq!((m.stopped_by, m.samples_per_pixel(), m.cells[0].target_met), ("time budget", 32, false));
    let m = measure(&source, 9, 1, &c.eye, &r, SsimConstants::Wang2004, &to_target(1.0, 1.0));
    assert_eq!((m.stopped_by, m.samples_per_pixel(), m.cells[0].target_met), ("target met", 32, true));
}

#[test]
fn pixels_whose_ground_truth_is_known_whole_give_the_same_bits_as_tracing_every_ray() {
    // The fused kernel tells `Replicates::extend` which pixels see one colour through the whole
    // pupil (`PairedSource::reference_over`); the generic path traces every ray.
    let c = corner();
    let backend = AnalyticRects::new(&c.scene).unwrap();
    let slow = SceneTracer { scene: &c.scene, backend: &backend };
    let fast = FacingPlanes::new(&c.scene, &backend).unwrap();
    let stack = DisplayStack::new(&c.display, &[&c.lc]).unwrap();
    let mut moved = Eye::thin_lens(3.0, Focus::Millimetres(700.0), 8);
    moved.position = DVec3::new(0.5, -0.8, 1.0);
    let mut rng = inimtrace::fixtures::Lcg(5);
    for (eye, half) in [(c.eye.clone(), 0.3), (c.eye.clone(), 0.04), (Eye::pinhole(), 0.1), (moved, 0.08)] {
        let (n, radius) = (
            96,
            match eye.aperture {
                inimtrace::optics::Aperture::ThinLens { pupil_diameter, .. } => pupil_diameter / 2.0,
                inimtrace::optics::Aperture::Pinhole => 0.0,
            },
        );
        let r = retina(n, half);
        let known = DisplaySource::new(&c.display, &eye, &fast, &stack);
        let traced = DisplaySource::new(&c.display, &eye, &slow, &stack);
        // Every pixel said to be one colour is that colour along rays through its corners and
        // the pupil's rim (the extremes of its footprints) and at random.
        let step = 2.0 * half / n as f64;
        let mut whole = 0;
        for p in 0..n * n {
            let lo = DVec2::new(-half + (p % n) as f64 * step, half - (p / n) as f64 * step);
            let hi = lo + DVec2::new(step, -step);
            let Some(value) = known.reference_over((lo, hi), radius) else { continue };
            whole += 1;
            let rim = (0..16).map(|a| DVec2::from_angle(a as f64 * std::f64::consts::PI / 8.0) * radius);
            let corners = [lo, hi, DVec2::new(lo.x, hi.y), DVec2::new(hi.x, lo.y)];
            let extremes = rim.flat_map(|s| corners.map(|t| (t, s)));
            let random = (0..16).map(|_| {
                let t = lo + (hi - lo) * DVec2::new(rng.next(), rng.next());
                (t, DVec2::from_angle(rng.range(0.0, 6.3)) * radius * rng.next().sqrt())
            });
            for (t, s) in extremes.chain(random) {
                assert_eq!(slow.radiance(&eye_scene_ray(&eye, t, s)).to_array(), value, "pixel {p} {t} {s}");
            }
        }
        assert!(whole > n * n / 20 && whole < n * n * 19 / 20, "both kinds of pixel: {whole} of {}", n * n);
        let a = measure(&known, 3, 1, &eye, &r, SsimConstants::Wang2004, &fixed_samples(4, 16));
        let b = measure(&traced, 3, 1, &eye, &r, SsimConstants::Wang2004, &fixed_samples(4, 16));
        assert!(a.replicates == b.replicates, "{eye:?}");
        assert_eq!(a.cells, b.cells);
    }
}
