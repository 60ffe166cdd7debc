//! The physics of the assessment pipeline (issue: "What must be true").
#![deny(unsafe_code)]

use glam::{DVec2, DVec3};
use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::fixtures::{self, Lcg};
use inimtrace::io;
use inimtrace::metrics;
use inimtrace::optics::transfer::FastTransfer;
use inimtrace::optics::transfer::{eye_ray, eye_to_lcd, lcd_to_eye};
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::retina::simulate;
use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, SceneTracer};
use inimtrace::scene::{Material, Object, Rect, Scene, Shape};
use std::path::Path;

fn small_display(res: usize) -> Display {
    let mut d = Display::paper();
    d.lcd.resolution = [res, res];
    d
}

#[test]
fn ray_transfer_is_reversible() {
    let mut rng = Lcg(1);
    let display = Display::paper();
    for focus in [Focus::Millimetres(300.0), Focus::Diopters(0.0), Focus::Millimetres(385.0)] {
        let mut eye = Eye::thin_lens(5.0, focus, 8);
        eye.position = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0);
        for _ in 0..20_000 {
            let t = DVec2::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
            let s = DVec2::new(rng.range(-2.5, 2.5), rng.range(-2.5, 2.5));
            let fwd = eye_to_lcd(&display, &eye, t, s);
            let (pupil, retina) = lcd_to_eye(&display, &eye, fwd.lcd, fwd.lenslet.position);
            assert!((pupil.position - fwd.pupil.position).length() < 1e-9, "pupil {:?} vs {:?}", pupil, fwd.pupil);
            assert!((pupil.slope - fwd.pupil.slope).length() < 1e-12);
            assert!((retina - fwd.retina).length() < 1e-9, "retina {retina:?} vs {:?}", fwd.retina);
            assert!((fwd.retina - (-eye.retina_distance * t)).length() < 1e-12);
        }
    }
}

#[test]
fn fast_transfer_agrees_with_eye_to_lcd() {
    let display = Display::paper();
    let mut rng = Lcg(2);
    for eye in [
        Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8),
        Eye::pinhole(),
        Eye::thin_lens(2.0, Focus::Diopters(0.0), 5),
    ] {
        let pupil = eye.pupil_samples();
        let fast = FastTransfer::new(&display, &eye, &pupil);
        for _ in 0..5_000 {
            let t = DVec2::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
            for (k, s) in pupil.iter().enumerate() {
                let slow = eye_to_lcd(&display, &eye, t, *s).lcd;
                assert!((fast.lcd_point(t, k) - slow).length() < 1e-12);
            }
        }
    }
}

#[test]
fn focal_plane_points_image_to_one_retina_point() {
    let mut rng = Lcg(3);
    for (a, b) in [(Focus::Millimetres(400.0), Focus::Diopters(2.5)), (Focus::Millimetres(250.0), Focus::Diopters(4.0))]
    {
        let ea = Eye::thin_lens(5.0, a, 8);
        let eb = Eye::thin_lens(5.0, b, 8);
        let z = a.distance_mm();
        for _ in 0..1000 {
            let t = DVec2::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
            for s in ea.pupil_samples() {
                let ra = eye_ray(&ea, t, s);
                let rb = eye_ray(&eb, t, s);
                // Every pupil sample reaches the same focal-plane point, t * z.
                assert!((ra.propagate(z).position - t * z).length() < 1e-9);
                assert!((ra.slope - rb.slope).length() < 1e-15, "diopters and mm disagree");
            }
        }
    }
    // 0 D: all rays from one retina point leave parallel (they meet at infinity).
    let inf = Eye::thin_lens(5.0, Focus::Diopters(0.0), 8);
    let t = DVec2::new(0.1, -0.05);
    for s in inf.pupil_samples() {
        assert!((eye_ray(&inf, t, s).slope - t).length() < 1e-15);
    }
}

#[test]
fn lensletaverage_1x1_is_exactly_lensletcenter() {
    let display = small_display(540);
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = FacingPlanes::new(&scene, &backend).unwrap();
    let s = DisplayRenderSettings::default();
    let lc = render_display_image(&display, Method::LensletCenter, &s, &field, &Progress::hidden()).unwrap();
    let la =
        render_display_image(&display, Method::LensletAverage { grid: 1 }, &s, &field, &Progress::hidden()).unwrap();
    assert!(lc == la);
    let la3 =
        render_display_image(&display, Method::LensletAverage { grid: 3 }, &s, &field, &Progress::hidden()).unwrap();
    assert!(lc != la3);
}

#[test]
fn fused_kernel_and_generic_backend_render_the_same_images() {
    let display = small_display(216);
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let fast = FacingPlanes::new(&scene, &backend).unwrap();
    let slow = SceneTracer { scene: &scene, backend: &backend };
    let s = DisplayRenderSettings::default();
    for m in [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }] {
        let a = render_display_image(&display, m, &s, &fast, &Progress::hidden()).unwrap();
        let b = render_display_image(&display, m, &s, &slow, &Progress::hidden()).unwrap();
        assert!(a == b, "{m}");
    }
    // The fused kernel's ground truth takes whole pixels at once where their rays meet one colour
    // (`RadianceField::uniform`); the generic path traces every ray.
    let mut off_axis = Eye::thin_lens(5.0, Focus::Millimetres(450.0), 6);
    off_axis.position = glam::DVec3::new(1.5, -2.0, 3.0);
    let eyes = [
        Eye::thin_lens(5.0, Focus::Millimetres(300.0), 4),
        Eye::thin_lens(5.0, Focus::Millimetres(600.0), 8),
        Eye::thin_lens(3.0, Focus::Diopters(0.0), 5),
        Eye::pinhole(),
        off_axis,
    ];
    for eye in &eyes {
        for samples_per_pixel in [1, 2] {
            let retina = Retina { resolution: 96, samples_per_pixel, ..Retina::default() };
            let a = ground_truth(eye, &retina, &fast, &Progress::hidden());
            let b = ground_truth(eye, &retina, &slow, &Progress::hidden());
            assert!(a == b, "{eye:?} {samples_per_pixel}");
        }
    }
}

#[test]
fn uniform_white_scene_looks_white_wherever_rays_land_on_the_lcd() {
    let display = small_display(432);
    let scene = fixtures::white_wall();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = SceneTracer { scene: &scene, backend: &backend };
    let s = DisplayRenderSettings::default();
    let images: Vec<RgbImage> = [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }]
        .iter()
        .map(|m| render_display_image(&display, *m, &s, &field, &Progress::hidden()).unwrap())
        .collect();
    for img in &images {
        assert!(img.pixels.iter().all(|p| *p == [1.0; 3]), "display image of a white scene is white");
    }
    // Wide field so that some rays miss the LCD.
    let retina = Retina { resolution: 96, half_tangent: 0.6, samples_per_pixel: 1 };
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 6);
    let sims = simulate(&display, &eye, &retina, &images.iter().collect::<Vec<_>>(), &Progress::hidden()).unwrap();
    let pupil = eye.pupil_samples();
    let fast = FastTransfer::new(&display, &eye, &pupil);
    let (mut all_on, mut partly) = (0, 0);
    for row in 0..96 {
        for col in 0..96 {
            let t = retina.tangent(row, col, DVec2::splat(0.5));
            let landed = (0..pupil.len()).filter(|&k| fast.pixel_index(t, k).is_some()).count();
            for sim in &sims {
                let v = sim.get(row, col);
                let expect = landed as f32 / pupil.len() as f32;
                assert!(
                    (v[0] - expect).abs() < 1e-6 && v[0] == v[1] && v[1] == v[2],
                    "({row},{col}): {v:?} vs {expect}"
                );
            }
            if landed == pupil.len() {
                all_on += 1;
            } else if landed > 0 {
                partly += 1;
            }
        }
    }
    assert!(all_on > 1000 && partly > 100, "both cases exercised: {all_on} {partly}");
}

fn region_psnr(a: &RgbImage, b: &RgbImage, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> f64 {
    let mut se = 0.0;
    let mut n = 0.0;
    for r in rows {
        for c in cols.clone() {
            for ch in 0..3 {
                let d = a.get(r, c)[ch] as f64 - b.get(r, c)[ch] as f64;
                se += d * d;
                n += 1.0;
            }
        }
    }
    -10.0 * (se / n).log10()
}

/// The paper's display at full resolution with a smaller retina (the physics at stake, focus
/// cues and LC against PC, lives in the display's pixel pitch).
#[test]
fn focus_cues_and_lc_beats_pc_when_the_eye_focuses() {
    let display = Display::paper();
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = FacingPlanes::new(&scene, &backend).unwrap();
    let s = DisplayRenderSettings::default();
    let methods = [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }];
    let images: Vec<RgbImage> =
        methods.iter().map(|m| render_display_image(&display, *m, &s, &field, &Progress::hidden()).unwrap()).collect();
    let refs: Vec<&RgbImage> = images.iter().collect();
    let n = 256;
    let retina = Retina { resolution: n, ..Retina::default() };
    // Each square's own ground truth is how it looks in focus: the pinhole (all-in-focus) image.
    let sharp = ground_truth(&Eye::pinhole(), &retina, &field, &Progress::hidden());
    let mut by_focus = Vec::new();
    for z in [300.0, 400.0, 600.0] {
        let eye = Eye::thin_lens(5.0, Focus::Millimetres(z), 8);
        let gt = ground_truth(&eye, &retina, &field, &Progress::hidden());
        let sims = simulate(&display, &eye, &retina, &refs, &Progress::hidden()).unwrap();
        let lc = metrics::psnr(&sims[0], &gt).unwrap().mean;
        let pc = metrics::psnr(&sims[1], &gt).unwrap().mean;
        assert!(lc > pc + 1.0, "focus {z}: LC {lc:.2} dB should beat PC {pc:.2} dB clearly");
        // Near chart: tangents x, y in [-0.3, 0] (bottom-left quadrant). Far chart, unoccluded:
        // tangents x, y in [0.16, 0.3] (top-right corner).
        let near = region_psnr(&sims[2], &sharp, n / 2 + 4..n - 4, 4..n / 2 - 4);
        let far = region_psnr(
            &sims[2],
            &sharp,
            4..(n as f64 * (0.3 - 0.16) / 0.6) as usize,
            (n as f64 * (0.3 + 0.16) / 0.6) as usize..n - 4,
        );
        by_focus.push((near, far));
    }
    let (near_300, far_300) = by_focus[0];
    let (near_600, far_600) = by_focus[2];
    assert!(
        near_300 > near_600 + 0.5,
        "near chart against its in-focus image: {near_300:.2} dB focused near vs {near_600:.2} dB focused far"
    );
    assert!(
        far_600 > far_300 + 0.5,
        "far chart against its in-focus image: {far_600:.2} dB focused far vs {far_300:.2} dB focused near"
    );
}

#[test]
fn framework_yaml_equals_our_toml_and_the_builtin_display() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let yaml = io::load_display("data/lensletdisplay.yaml", root).unwrap();
    let toml = io::load_display("displays/paper.toml", root).unwrap();
    let builtin = Display::paper();
    for d in [&yaml, &toml] {
        assert_eq!(d.eye_to_lenslets, builtin.eye_to_lenslets);
        assert_eq!(d.lenslets_to_lcd, builtin.lenslets_to_lcd);
        assert_eq!(d.focal_length, builtin.focal_length);
        assert_eq!(d.lenslets, builtin.lenslets);
        assert_eq!(d.elemental_images, builtin.elemental_images);
        assert_eq!(d.lcd, builtin.lcd);
    }
    let z = yaml.central_depth_plane().unwrap();
    assert!((z - 385.8).abs() < 0.5, "{z}");
}

#[test]
fn shipped_scene_and_experiment_files_match_the_builtins() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = io::load_scene("scenes/paper.toml", root).unwrap();
    let builtin = Scene::paper();
    assert_eq!(scene.objects.len(), builtin.objects.len());
    for (a, b) in scene.objects.iter().zip(&builtin.objects) {
        match (&a.shape, &b.shape) {
            (Shape::Rect(x), Shape::Rect(y)) => assert_eq!(x, y),
            _ => panic!("shapes differ"),
        }
    }
    use inimtrace::experiment::{Experiment, ExperimentSpec};
    // The files name the scene and display files instead of the built-ins; all else is equal.
    for (file, builtin) in [
        ("experiments/paper.toml", ExperimentSpec::paper()),
        ("experiments/framework-2020.toml", ExperimentSpec::framework_2020()),
    ] {
        let loaded = Experiment::load(&root.join(file)).unwrap();
        let spec =
            ExperimentSpec { scene: builtin.scene.clone(), display: builtin.display.clone(), ..loaded.spec.clone() };
        assert_eq!(spec, builtin, "{file}");
        let d = Display::paper();
        assert_eq!(
            (loaded.display.lenslets, loaded.display.elemental_images, loaded.display.lcd),
            (d.lenslets, d.elemental_images, d.lcd)
        );
        assert_eq!(
            (loaded.display.eye_to_lenslets, loaded.display.lenslets_to_lcd, loaded.display.focal_length),
            (20.0, 6.316, 6.427)
        );
    }
    let paper = Experiment::load(&root.join("experiments/paper.toml")).unwrap();
    let fw = Experiment::load(&root.join("experiments/framework-2020.toml")).unwrap();
    assert_eq!(fw.cases[1].eye.pupil_samples().len(), 21);
    assert_eq!(paper.cases[1].eye.pupil_samples().len(), 52);
}

#[test]
fn pupil_center_rays_pass_through_the_pupil_centre_and_singularity_is_refused() {
    use inimtrace::optics::transfer::{camera_ray, check_pupil_center, pupil_center_point};
    let display = Display::paper();
    let lcd = display.lcd;
    let mut rng = Lcg(11);
    for eye in [DVec3::ZERO, DVec3::new(1.5, -0.7, 0.0), DVec3::new(-2.0, 1.0, 3.0)] {
        check_pupil_center(&display, eye).unwrap();
        for _ in 0..2000 {
            let (r, c) = ((rng.next() * 2160.0) as usize, (rng.next() * 2160.0) as usize);
            let x3 = lcd.pixel_center(r, c);
            let xc = display.lenslets.center(display.elemental_image_of(x3));
            let p = pupil_center_point(&display, x3, xc, eye);
            let ray = camera_ray(&display, x3, xc, p, 0.0);
            let at_eye = ray.origin + ray.dir * (eye.z - ray.origin.z);
            assert!((at_eye.truncate() - eye.truncate()).length() < 1e-9, "{at_eye:?} vs {eye:?}");
        }
    }
    let mut singular = Display::paper();
    singular.lenslets_to_lcd = 1.0 / (1.0 / singular.focal_length - 1.0 / singular.eye_to_lenslets);
    let e = check_pupil_center(&singular, DVec3::ZERO).unwrap_err().to_string();
    assert!(e.contains("PupilCenter") && e.contains("pupil centre onto the LCD"), "{e}");
    let s = DisplayRenderSettings::default();
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = SceneTracer { scene: &scene, backend: &backend };
    assert!(render_display_image(&singular, Method::PupilCenter, &s, &field, &Progress::hidden()).is_err());
    // LC and LA do not depend on the eye and still render.
    let mut small = singular.clone();
    small.lcd.resolution = [64, 64];
    assert!(render_display_image(&small, Method::LensletCenter, &s, &field, &Progress::hidden()).is_ok());
}

#[test]
fn the_reference_plane_moves_ray_starts_along_the_same_lines() {
    use inimtrace::optics::transfer::camera_ray;
    let display = Display::paper();
    let mut rng = Lcg(12);
    for _ in 0..1000 {
        let x3 = DVec2::new(rng.range(-10.8, 10.8), rng.range(-10.8, 10.8));
        let xc = display.lenslets.center(display.elemental_image_of(x3));
        let p = xc + DVec2::new(rng.range(-0.6, 0.6), rng.range(-0.6, 0.6));
        let a = camera_ray(&display, x3, xc, p, 0.0);
        let b = camera_ray(&display, x3, xc, p, 150.0);
        assert_eq!(a.dir, b.dir);
        let a_at_b = a.origin + a.dir * (150.0 - a.origin.z);
        assert!((a_at_b - b.origin).length() < 1e-9);
        // Both pass through p on the lenslet plane.
        let at_lenslets = a.origin + a.dir * (display.lenslet_z() - a.origin.z);
        assert!((at_lenslets.truncate() - p).length() < 1e-12);
    }
    // Geometry between the eye and the reference plane is skipped: a plane at z = 100 hides the
    // scene from rays starting at z = 0 but not from rays starting at z = 150.
    let scene = Scene {
        name: "occluder".into(),
        objects: vec![
            Object {
                name: "near".into(),
                shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, 100.0), 1e4, 1e4)),
                material: Material::Albedo(DVec3::ZERO),
            },
            Object {
                name: "far".into(),
                shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, 500.0), 1e4, 1e4)),
                material: Material::Albedo(DVec3::ONE),
            },
        ],
        background: DVec3::ZERO,
        light: None,
        warnings: Vec::new(),
    };
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = SceneTracer { scene: &scene, backend: &backend };
    let d = small_display(32);
    let near =
        render_display_image(&d, Method::LensletCenter, &DisplayRenderSettings::default(), &field, &Progress::hidden())
            .unwrap();
    let far_settings = DisplayRenderSettings { reference_plane_z: 150.0, ..DisplayRenderSettings::default() };
    let far = render_display_image(&d, Method::LensletCenter, &far_settings, &field, &Progress::hidden()).unwrap();
    assert!(near.pixels.iter().all(|p| *p == [0.0; 3]) && far.pixels.iter().all(|p| *p == [1.0; 3]));
}

#[test]
fn rendering_into_the_stack_equals_rendering_then_packing() {
    // The path `assess` uses (each display image rendered into one reused image buffer and
    // depth plane, then added to the stack image by image) against its slow twin (render every
    // image, then pack): bit for bit, with depth, on the fused kernel and the generic tracer, and
    // a tilted lattice.
    use inimtrace::render::render_display_image_with_depth;
    use inimtrace::render::retina::DisplayStack;
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let fast = FacingPlanes::new(&scene, &backend).unwrap();
    let slow = SceneTracer { scene: &scene, backend: &backend };
    let s = DisplayRenderSettings { samples_per_pixel: 2, ..DisplayRenderSettings::default() };
    let methods = [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }];
    let mut tilted = small_display(108);
    let r = glam::DMat2::from_angle(0.3);
    let scale = (tilted.eye_to_lenslets + tilted.lenslets_to_lcd) / tilted.eye_to_lenslets;
    let pitch = glam::DMat2::from_diagonal(DVec2::splat(1.2));
    tilted.lenslets = inimtrace::optics::Lattice::new(DVec2::ZERO, r * pitch).unwrap();
    tilted.elemental_images = inimtrace::optics::Lattice::new(DVec2::ZERO, r * pitch * scale).unwrap();
    for display in [small_display(108), tilted] {
        for field in [&fast as &dyn inimtrace::render::RadianceField, &slow] {
            let rendered: Vec<_> = methods
                .iter()
                .map(|m| render_display_image_with_depth(&display, *m, &s, field, &Progress::hidden()).unwrap())
                .collect();
            let images: Vec<&RgbImage> = rendered.iter().map(|(img, _)| img).collect();
            let packed = DisplayStack::new(&display, &images).unwrap();
            for (k, m) in methods.iter().enumerate() {
                assert!(packed.image(k) == rendered[k].0, "{m}: packed");
            }
            let (mut image, mut depth) = (RgbImage::new(display.lcd.columns(), display.lcd.rows()), Vec::new());
            let mut builder = inimtrace::render::display_stack::StackBuilder::new(&display, methods.len());
            for (k, m) in methods.iter().enumerate() {
                let known = inimtrace::render::render_display_image_into(
                    &display,
                    *m,
                    &s,
                    field,
                    &Progress::hidden(),
                    &mut image,
                    &mut depth,
                )
                .unwrap();
                assert_eq!(known.then(|| depth.clone()), rendered[k].1, "{m}: depth in the reused plane");
                assert!(image == rendered[k].0, "{m}: image in the reused buffer");
                builder.push((&image).into()).unwrap();
            }
            let built = builder.finish().unwrap();
            for i in 0..display.lcd.pixel_count() {
                assert_eq!(built.pixel(i), packed.pixel(i));
            }
        }
    }
    // An image buffer of another size than the LCD is an error, not a panic.
    let display = small_display(108);
    let mut wrong = RgbImage::new(107, 108);
    let err = inimtrace::render::render_display_image_into(
        &display,
        Method::LensletCenter,
        &s,
        &fast,
        &Progress::hidden(),
        &mut wrong,
        &mut Vec::new(),
    );
    assert!(err.is_err());
}
