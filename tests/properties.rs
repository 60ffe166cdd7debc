//! Property tests over random displays, eyes and rays (proptest): ray transfer is reversible,
//! lenslet ownership is consistent, outputs are finite, a uniform scene looks uniform.
#![deny(unsafe_code)]

use glam::{DMat2, DVec2, DVec3};
use proptest::prelude::*;

use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::optics::transfer::{eye_to_lcd, lcd_to_eye};
use inimtrace::optics::{Display, Eye, Focus, Lattice, Retina};
use inimtrace::progress::Progress;
use inimtrace::render::retina::simulate;
use inimtrace::render::{render_display_image, DisplayRenderSettings, Method, SceneTracer};
use inimtrace::scene::{Material, Object, Rect, Scene, Shape};

/// A random but physically possible display: square, rectangular, hexagonal or tilted lenslets.
fn display() -> impl Strategy<Value = Display> {
    (10.0..40.0f64, 2.0..10.0f64, 2.0..12.0f64, 0.3..3.0f64, 0..4u8, -1.0..1.0f64, 4usize..40).prop_filter_map(
        "lattice",
        |(v1, v2, f, pitch, layout, angle, res)| {
            let m = match layout {
                0 => DMat2::from_diagonal(DVec2::splat(pitch)),
                1 => DMat2::from_diagonal(DVec2::new(pitch, 1.3 * pitch)),
                2 => DMat2::from_cols(DVec2::new(pitch, 0.0), DVec2::new(pitch / 2.0, pitch * 3f64.sqrt() / 2.0)),
                _ => DMat2::from_angle(angle) * DMat2::from_diagonal(DVec2::splat(pitch)),
            };
            let scale = (v1 + v2) / v1;
            let mut d = Display::paper();
            d.eye_to_lenslets = v1;
            d.lenslets_to_lcd = v2;
            d.focal_length = f;
            d.lenslets = Lattice::new(DVec2::new(0.1, -0.05), m)?;
            d.elemental_images = Lattice::new(DVec2::new(0.1, -0.05) * scale, m * scale)?;
            d.lcd.resolution = [res, res];
            Some(d)
        },
    )
}

fn eye() -> impl Strategy<Value = Eye> {
    (
        0.5..8.0f64,
        prop_oneof![(100.0..5000.0f64).prop_map(Focus::Millimetres), Just(Focus::Diopters(0.0))],
        -2.0..2.0f64,
        -2.0..2.0f64,
        2usize..6,
    )
        .prop_map(|(pupil, focus, ex, ey, n)| {
            let mut e = Eye::thin_lens(pupil, focus, n);
            e.position = DVec3::new(ex, ey, 0.0);
            e
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn transfer_is_reversible_and_finite(d in display(), e in eye(), tx in -0.4..0.4f64, ty in -0.4..0.4f64, sx in -1.0..1.0f64, sy in -1.0..1.0f64) {
        let t = DVec2::new(tx, ty);
        let s = DVec2::new(sx, sy) * 0.5 * 0.5;
        let fwd = eye_to_lcd(&d, &e, t, s);
        prop_assert!(fwd.lcd.is_finite() && fwd.lenslet.slope.is_finite());
        let (pupil, retina) = lcd_to_eye(&d, &e, fwd.lcd, fwd.lenslet.position);
        let scale = 1.0 + fwd.lcd.length();
        prop_assert!((pupil.position - fwd.pupil.position).length() < 1e-9 * scale);
        prop_assert!((retina - fwd.retina).length() < 1e-9 * scale);
    }

    #[test]
    fn lenslet_ownership_is_consistent(d in display(), x in -15.0..15.0f64, y in -15.0..15.0f64) {
        let p = DVec2::new(x, y);
        let n = d.lenslets.nearest(p);
        prop_assert_eq!(n, d.lenslets.nearest_brute_force(p, 4));
        // The owner's centre is at least as close as every other centre nearby.
        let c = d.lenslets.center(n);
        for dj in -2..=2 {
            for di in -2..=2 {
                let other = d.lenslets.center(n + glam::IVec2::new(di, dj));
                prop_assert!((c - p).length() <= (other - p).length() + 1e-12);
            }
        }
    }

    #[test]
    fn a_uniform_scene_looks_uniform(d in display(), e in eye(), grey in 0.0..1.0f64) {
        let scene = Scene {
            name: "uniform".into(),
            objects: vec![Object { name: "wall".into(), shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, 700.0), 1e6, 1e6)), material: Material::Albedo(DVec3::splat(grey)) }],
            background: DVec3::splat(grey),
            light: None,
            warnings: Vec::new(),
        };
        let backend = AnalyticRects::new(&scene).unwrap();
        let field = SceneTracer { scene: &scene, backend: &backend };
        let s = DisplayRenderSettings { eye_position: e.position, ..DisplayRenderSettings::default() };
        let g = grey as f32;
        let mut images = Vec::new();
        for m in [Method::LensletCenter, Method::LensletAverage { grid: 2 }, Method::PupilCenter] {
            match render_display_image(&d, m, &s, &field, &Progress::hidden()) {
                Ok(img) => {
                    prop_assert!(img.pixels.iter().all(|p| (p[0] - g).abs() <= 1e-6 && p[0] == p[1] && p[1] == p[2]));
                    images.push(img);
                }
                Err(err) => prop_assert!(m == Method::PupilCenter && err.to_string().contains("PupilCenter")),
            }
        }
        let retina = Retina { resolution: 8, half_tangent: 0.3, samples_per_pixel: 1 };
        let sims = simulate(&d, &e, &retina, &images.iter().collect::<Vec<_>>(), &Progress::hidden()).unwrap();
        for sim in &sims {
            // Uniform wherever rays land; darker only where some miss the LCD; never NaN.
            prop_assert!(sim.all_finite());
            prop_assert!(sim.pixels.iter().all(|p| p[0] >= 0.0 && p[0] <= g + 1e-6));
        }
    }
}
