//! Numerical hard cases of the optics and rendering (docs/NUMERICS.md has the table: case, what
//! could go wrong, what inimtrace does, how this file checks it). Across all of them no NaN or
//! infinity may reach an output image.
#![deny(unsafe_code)]

use glam::{DMat2, DVec2, DVec3};
use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::fixtures::{self, Lcg};
use inimtrace::metrics;
use inimtrace::optics::transfer::eye_to_lcd;
use inimtrace::optics::transfer::FastTransfer;
use inimtrace::optics::transfer::{camera_ray, check_pupil_center, pupil_center_point};
use inimtrace::optics::{Display, Eye, Focus, Lattice, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::retina::simulate;
use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, SceneTracer};
use inimtrace::scene::{Material, Object, Rect, Scene, Shape};

fn hidden() -> Progress {
    Progress::hidden()
}

fn small(res: usize) -> Display {
    let mut d = Display::paper();
    d.lcd.resolution = [res, res];
    d
}

fn render_all(display: &Display, scene: &Scene, settings: &DisplayRenderSettings) -> Vec<RgbImage> {
    let backend = AnalyticRects::new(scene).unwrap();
    let field = SceneTracer { scene, backend: &backend };
    [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }]
        .iter()
        .map(|m| render_display_image(display, *m, settings, &field, &hidden()).unwrap())
        .collect()
}

/// Case 1: PupilCenter approaching the singular configuration stays finite and exact; at it, an
/// error names the cause.
#[test]
fn pupil_center_near_the_singularity() {
    let base = Display::paper();
    let v2_singular = 1.0 / (1.0 / base.focal_length - 1.0 / base.eye_to_lenslets);
    let mut rng = Lcg(1);
    for rel in [1e-2, 1e-4, 1e-6, 1e-7] {
        let mut d = base.clone();
        // 1/L + 1/v2 - 1/f = rel * (1/L + 1/v2 + 1/f), solved for v2.
        let (l, f) = (d.eye_to_lenslets, d.focal_length);
        let inv_v2 = (1.0 / f - 1.0 / l + rel * (1.0 / l + 1.0 / f)) / (1.0 - rel);
        d.lenslets_to_lcd = 1.0 / inv_v2;
        assert!((d.lenslets_to_lcd - v2_singular).abs() < 1e-1 * v2_singular);
        check_pupil_center(&d, DVec3::ZERO).unwrap();
        for _ in 0..1000 {
            let x3 = DVec2::new(rng.range(-10.8, 10.8), rng.range(-10.8, 10.8));
            let xc = d.lenslets.center(d.elemental_image_of(x3));
            let p = pupil_center_point(&d, x3, xc, DVec3::ZERO);
            assert!(p.is_finite());
            let ray = camera_ray(&d, x3, xc, p, 0.0);
            // The ray still passes through the pupil centre, to rounding relative to |p|.
            assert!(ray.origin.truncate().length() <= 1e-9 * (1.0 + p.length()), "rel {rel}: {:?}", ray.origin);
        }
        let mut tiny = d.clone();
        tiny.lcd.resolution = [24, 24];
        let img = &render_all(&tiny, &Scene::paper(), &DisplayRenderSettings::default())[1];
        assert!(img.all_finite());
    }
    let mut d = base.clone();
    d.lenslets_to_lcd = v2_singular;
    let e = check_pupil_center(&d, DVec3::ZERO).unwrap_err().to_string();
    assert!(e.contains("pupil centre onto the LCD"), "{e}");
    // Below the threshold (1e-9 relative) it is refused too.
    let (l, f) = (d.eye_to_lenslets, d.focal_length);
    d.lenslets_to_lcd = 1.0 / ((1.0 / f - 1.0 / l + 1e-11 * (1.0 / l + 1.0 / f)) / (1.0 - 1e-11));
    assert!(check_pupil_center(&d, DVec3::ZERO).is_err());
}

/// Case 2: points exactly on lenslet and pixel borders have one deterministic owner, the same
/// in every path.
#[test]
fn borders_have_one_owner() {
    let d = Display::paper();
    // Exact ties (pitch 2 mm: borders at odd millimetres, exact in binary) go to the upper cell,
    // in the fast path and in the slow twin.
    let two = Lattice::square(2.0).unwrap();
    for p in [DVec2::new(1.0, 0.0), DVec2::new(-1.0, 1.0), DVec2::new(3.0, -3.0)] {
        let n = two.nearest(p);
        assert_eq!(n, two.nearest_brute_force(p, 3));
        assert_eq!(n, two.nearest(p + DVec2::splat(1e-12)), "upper cell at {p:?}");
    }
    // The paper's 1.2 mm lattice at its (inexact) borders: fast path and twin agree.
    let lat = d.lenslets;
    for k in -9..=9 {
        for p in [DVec2::new(0.6 + 1.2 * k as f64, 0.0), DVec2::new(0.3, -0.6 + 1.2 * k as f64)] {
            assert_eq!(lat.nearest(p), lat.nearest_brute_force(p, 3), "{p:?}");
        }
    }
    // LCD borders: every point of a fine grid that includes all pixel borders maps to exactly one
    // pixel, and the pixel contains it (within rounding).
    let lcd = small(60).lcd;
    let pitch = lcd.pixel_pitch();
    let mut counts = vec![0usize; lcd.pixel_count()];
    for j in 0..=120 {
        for i in 0..=120 {
            let p = DVec2::new(-10.8 + i as f64 * pitch.x / 2.0, 10.8 - j as f64 * pitch.y / 2.0);
            let idx = lcd.pixel_index(p).expect("on the closed panel");
            let (r, c) = (idx / 60, idx % 60);
            let centre = lcd.pixel_center(r, c);
            assert!((p - centre).abs().max_element() <= 0.5 * pitch.max_element() + 1e-9, "{p:?} -> ({r},{c})");
            counts[idx] += 1;
        }
    }
    // Every point has exactly one owner (none lost off the closed panel), every pixel owns at
    // least its centre, and border points go to one of the two pixels they touch (checked above).
    assert_eq!(counts.iter().sum::<usize>(), 121 * 121);
    assert!(counts.iter().all(|&k| (1..=9).contains(&k)), "no pixel is skipped or flooded");
    for r in 0..60 {
        for c in 0..60 {
            assert_eq!(lcd.pixel_index(lcd.pixel_center(r, c)), Some(r * 60 + c));
        }
    }
    // Simulation and the reference transfer agree on the owner of the same ray.
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8);
    let pupil = eye.pupil_samples();
    let fast = FastTransfer::new(&d, &eye, &pupil);
    let mut rng = Lcg(2);
    for _ in 0..20_000 {
        let t = DVec2::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
        let k = (rng.next() * pupil.len() as f64) as usize;
        assert_eq!(fast.pixel_index(t, k), d.lcd.pixel_index(eye_to_lcd(&d, &eye, t, pupil[k]).lcd));
    }
}

/// Case 3: the LCD's outer edge is on the panel; beyond it is off; nothing indexes out of range,
/// and a pixel whose rays all miss the LCD is black, not NaN.
#[test]
fn lcd_outer_edge_and_all_miss_pixels() {
    let lcd = Display::paper().lcd;
    for (p, want) in [
        (DVec2::new(10.8, 10.8), Some(2159)),
        (DVec2::new(10.8, -10.8), Some(2160 * 2160 - 1)),
        (DVec2::new(-10.8, -10.8), Some(2159 * 2160)),
        (DVec2::new(10.8 + 1e-12, 0.0), None),
        (DVec2::new(0.0, f64::INFINITY), None),
        (DVec2::new(f64::NAN, f64::NAN), None),
    ] {
        assert_eq!(lcd.pixel_index(p), want, "{p:?}");
    }
    // A retina looking far outside the display: every ray misses the LCD.
    let d = small(32);
    let img = RgbImage::filled(32, 32, [1.0; 3]);
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 4);
    let retina = Retina { resolution: 16, half_tangent: 50.0, samples_per_pixel: 1 };
    let sim = simulate(&d, &eye, &retina, &[&img], &hidden()).unwrap();
    assert!(sim[0].all_finite());
    assert_eq!(sim[0].get(0, 0), [0.0; 3]);
}

/// Case 6: the pinhole limit. As the pupil shrinks the focused eye's image converges to the
/// pinhole image; a one-sample pupil is the pinhole exactly; 1 x 1 retinas and displays work.
#[test]
fn pinhole_limit() {
    let d = small(540);
    let scene = Scene::paper();
    let images = render_all(&d, &scene, &DisplayRenderSettings::default());
    let refs: Vec<&RgbImage> = images.iter().collect();
    let retina = Retina { resolution: 96, ..Retina::default() };
    let pin = simulate(&d, &Eye::pinhole(), &retina, &refs, &hidden()).unwrap();
    let mut last = 0.0;
    let mut sequence = Vec::new();
    for pupil in [1.0, 1e-1, 1e-2, 1e-3, 1e-6] {
        let eye = Eye::thin_lens(pupil, Focus::Millimetres(400.0), 4);
        let sim = simulate(&d, &eye, &retina, &refs, &hidden()).unwrap();
        let p = metrics::psnr(&sim[0], &pin[0]).unwrap().mean;
        sequence.push((pupil, p));
        assert!(p >= last - 1e-9, "PSNR to the pinhole image must not drop as the pupil shrinks: {sequence:?}");
        last = p;
    }
    assert!(last > 60.0, "{sequence:?}");
    // One pupil sample (grid 1) is the chief ray: exactly the pinhole.
    let one = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 1);
    assert_eq!(one.pupil_samples(), vec![DVec2::ZERO]);
    assert!(simulate(&d, &one, &retina, &refs, &hidden()).unwrap() == pin);
    // 1 x 1 retina and 1 x 1 display.
    let tiny_retina = Retina { resolution: 1, ..Retina::default() };
    let one_px = small(1);
    let imgs = render_all(&one_px, &scene, &DisplayRenderSettings::default());
    assert!(imgs.iter().all(|i| i.width == 1 && i.all_finite()));
    let sims = simulate(
        &one_px,
        &Eye::thin_lens(5.0, Focus::Diopters(0.0), 8),
        &tiny_retina,
        &imgs.iter().collect::<Vec<_>>(),
        &hidden(),
    )
    .unwrap();
    assert!(sims.iter().all(|s| s.all_finite()));
}

fn hexagonal_display() -> Display {
    let mut d = small(540);
    let p = 1.2;
    let m = DMat2::from_cols(DVec2::new(p, 0.0), DVec2::new(p / 2.0, p * 3f64.sqrt() / 2.0));
    let scale = (d.eye_to_lenslets + d.lenslets_to_lcd) / d.eye_to_lenslets;
    d.lenslets = Lattice::new(DVec2::new(0.05, -0.1), m).unwrap();
    d.elemental_images = Lattice::new(DVec2::new(0.05, -0.1) * scale, m * scale).unwrap();
    d
}

fn tilted_display() -> Display {
    let mut d = small(540);
    let r = DMat2::from_angle(0.3);
    let scale = (d.eye_to_lenslets + d.lenslets_to_lcd) / d.eye_to_lenslets;
    d.lenslets = Lattice::new(DVec2::ZERO, r * DMat2::from_diagonal(DVec2::splat(1.2))).unwrap();
    d.elemental_images = Lattice::new(DVec2::ZERO, r * DMat2::from_diagonal(DVec2::splat(1.2 * scale))).unwrap();
    d
}

/// Case 7: hexagonal and tilted lenslet arrays, elemental images that do not cover the LCD, an
/// off-axis eye near the edge of the eye box with PupilCenter.
#[test]
fn hexagonal_tilted_partial_and_off_axis() {
    let white = fixtures::white_wall();
    let mut partial = small(540);
    // EIs only cover the central half of the LCD: pixels outside still belong to the nearest EI
    // (ownership is a nearest-centre rule, it never fails), lenslets beyond the array's nominal
    // extent are simply further lattice cells.
    partial.elemental_images = Lattice::new(DVec2::ZERO, DMat2::from_diagonal(DVec2::splat(0.79))).unwrap();
    let eye_box_edge = DVec3::new(3.5, -2.0, 0.0);
    for (name, d) in [("hexagonal", hexagonal_display()), ("tilted", tilted_display()), ("partial EIs", partial)] {
        let settings = DisplayRenderSettings { eye_position: eye_box_edge, ..DisplayRenderSettings::default() };
        let images = render_all(&d, &white, &settings);
        for img in &images {
            assert!(img.pixels.iter().all(|p| *p == [1.0; 3]), "{name}: a white scene renders white");
        }
        let mut eye = Eye::thin_lens(5.0, Focus::Millimetres(350.0), 6);
        eye.position = eye_box_edge;
        let retina = Retina { resolution: 48, half_tangent: 0.2, samples_per_pixel: 2 };
        let sims = simulate(&d, &eye, &retina, &images.iter().collect::<Vec<_>>(), &hidden()).unwrap();
        for s in &sims {
            assert!(s.all_finite(), "{name}");
            assert!(s.pixels.iter().all(|p| p[0] <= 1.0 + 1e-6 && p[0] >= 0.0), "{name}");
        }
        // The fast transfer agrees with the reference trace on these lattices too.
        let pupil = eye.pupil_samples();
        let fast = FastTransfer::new(&d, &eye, &pupil);
        let mut rng = Lcg(3);
        for _ in 0..5000 {
            let t = DVec2::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
            let k = (rng.next() * pupil.len() as f64) as usize;
            assert!((fast.lcd_point(t, k) - eye_to_lcd(&d, &eye, t, pupil[k]).lcd).length() < 1e-12, "{name}");
        }
        // PupilCenter rays from the off-axis eye pass through its pupil centre.
        check_pupil_center(&d, eye_box_edge).unwrap();
        for _ in 0..1000 {
            let x3 = DVec2::new(rng.range(-10.8, 10.8), rng.range(-10.8, 10.8));
            let xc = d.lenslets.center(d.elemental_image_of(x3));
            let ray = camera_ray(&d, x3, xc, pupil_center_point(&d, x3, xc, eye_box_edge), 0.0);
            assert!((ray.origin.truncate() - eye_box_edge.truncate()).length() < 1e-9, "{name}");
        }
    }
}

/// Far geometry and far focus in the analytic f64 path: squares at 1e4..1e6 mm and focus at 0 D
/// stay finite and hit where expected.
#[test]
fn far_planes_and_infinite_focus() {
    for z in [1e4, 1e5, 1e6] {
        let scene = Scene {
            name: "far".into(),
            objects: vec![Object {
                name: "square".into(),
                shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, z), 0.3 * z, 0.3 * z)),
                material: Material::Albedo(DVec3::ONE),
            }],
            background: DVec3::ZERO,
            light: None,
            warnings: Vec::new(),
        };
        let backend = AnalyticRects::new(&scene).unwrap();
        let fused = FacingPlanes::new(&scene, &backend).unwrap();
        let retina = Retina { resolution: 40, half_tangent: 0.3, samples_per_pixel: 1 };
        let gt = ground_truth(&Eye::thin_lens(5.0, Focus::Diopters(0.0), 4), &retina, &fused, &hidden());
        // The square spans tangents +-0.15: retina columns 10..30 are inside, 0..9 outside (the
        // 5 mm pupil is negligible at these distances).
        for c in 0..40 {
            let v = gt.get(20, c)[0];
            let t = -0.3 + (c as f64 + 0.5) * 0.015;
            if t.abs() < 0.149 {
                assert_eq!(v, 1.0, "z {z} col {c}");
            } else if t.abs() > 0.151 {
                assert_eq!(v, 0.0, "z {z} col {c}");
            }
        }
    }
}

/// Case 5 with Embree: the f32 mesh path against the f64 analytic path for squares at 1e4, 1e5
/// and 1e6 mm, focus at 0 D. Both agree within one retina pixel at every distance (f32's
/// relative precision, ~6e-8, is an angle of ~6e-8 rad against a retina pixel of ~1e-3 rad), so
/// no re-basing of ray origins is needed; the test shows it.
#[cfg(feature = "embree")]
#[test]
fn far_planes_embree_f32_agrees_with_analytic_f64() {
    use inimtrace::render::backend::{with_fields, BackendChoice};
    for z in [1e4, 1e5, 1e6] {
        let scene = Scene {
            name: "far".into(),
            objects: vec![Object {
                name: "square".into(),
                shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.1 * z, -0.05 * z, z), 0.3 * z, 0.3 * z)),
                material: Material::Chart {
                    chart: std::sync::Arc::new(inimtrace::scene::usaf::framework_chart()),
                    bar: DVec3::ZERO,
                    backing: DVec3::ONE,
                },
            }],
            background: DVec3::splat(0.5),
            light: None,
            warnings: Vec::new(),
        };
        let retina = Retina { resolution: 96, half_tangent: 0.3, samples_per_pixel: 1 };
        let eye = Eye::thin_lens(5.0, Focus::Diopters(0.0), 4);
        let render =
            |choice| with_fields(&scene, choice, |f| Ok(ground_truth(&eye, &retina, f.shade, &hidden()))).unwrap();
        let exact = render(BackendChoice::Analytic);
        let f32_path = render(BackendChoice::Embree);
        assert!(f32_path.all_finite());
        // Every differing pixel must have an identical neighbour in the other image (an edge
        // moved by less than one retina pixel).
        let mut differing = 0;
        for r in 0..96 {
            for c in 0..96 {
                if exact.get(r, c) != f32_path.get(r, c) {
                    differing += 1;
                    let near = (r.saturating_sub(1)..=(r + 1).min(95))
                        .flat_map(|rr| (c.saturating_sub(1)..=(c + 1).min(95)).map(move |cc| (rr, cc)))
                        .any(|(rr, cc)| exact.get(rr, cc) == f32_path.get(r, c));
                    assert!(near, "z {z}: pixel ({r},{c}) differs by more than an edge shift");
                }
            }
        }
        eprintln!("z {z}: {differing} of 9216 retina pixels differ between f32 Embree and f64 analytic");
        assert!(differing <= 96, "z {z}: {differing} pixels differ");
    }
}
