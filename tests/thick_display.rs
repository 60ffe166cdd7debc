//! Real (thick) lenslets' display images and their display stack: the fast paths against their
//! slow twins (shared camera-ray traces against per-pixel traces; the 32-bit palette against the
//! dense stack).

use glam::{DVec2, DVec3};
use inimtrace::optics::display::Lcd;
use inimtrace::optics::lenslet::{LensletOptics, Material, ThickLenslet};
use inimtrace::optics::Display;
use inimtrace::raster::{RgbImage, RgbView};
use inimtrace::ray::Ray;
use inimtrace::render::display_stack::{DisplayStack, StackBuilder};
use inimtrace::render::display_thick::{lattice_period, render_with, Sharing};
use inimtrace::render::{DisplayRenderSettings, Method, RadianceField, Sample};

/// A scene whose radiance and depth vary smoothly with the ray, so images differ by about as much
/// as their rays do.
struct Smooth;

impl RadianceField for Smooth {
    fn radiance(&self, ray: &Ray) -> DVec3 {
        let p = ray.origin.truncate() + ray.dir.truncate() * 300.0;
        DVec3::new(0.5 + 0.02 * p.x, 0.5 + 0.02 * p.y, 0.5 + 0.4 * (0.3 * p.x + 0.2 * p.y).sin())
    }
    fn sample(&self, ray: &Ray) -> Sample {
        Sample { radiance: self.radiance(ray), depth: 300.0 * ray.dir.length() }
    }
}

/// The paper's display with PMMA plano-convex lenslets (as displays/paper-pmma.toml) on an LCD of
/// `n` x `n` pixels of 0.01 mm.
fn pmma_display(n: usize) -> Display {
    let mut d = Display::paper();
    d.lenslet = LensletOptics::Thick(Box::new(ThickLenslet::plano_convex(Material::pmma(), 6.427, 1.0)));
    d.lenslets_to_lcd = 5.6451;
    d.lcd = Lcd { size: DVec2::splat(n as f64 * 0.01), resolution: [n, n] };
    d
}

#[test]
fn shared_camera_rays_render_what_per_pixel_traces_render() {
    // The shared traces differ from the per-pixel ones by rounding only (the same lens moved by a
    // lenslet's centre): on a smooth scene the images agree to 1e-6.
    for (n, method, spp) in [
        (480, Method::LensletAverage { grid: 3 }, 1),
        (480, Method::LensletCenter, 1),
        (250, Method::LensletAverage { grid: 2 }, 2),
    ] {
        let d = pmma_display(n);
        assert_eq!(lattice_period(&d), Some((120, 120)));
        let lens = d.thick_lenslet().unwrap();
        let settings = DisplayRenderSettings { samples_per_pixel: spp, ..Default::default() };
        let fast = render_with(&d, lens, method, &settings, &Smooth, Sharing::Shared).unwrap();
        let slow = render_with(&d, lens, method, &settings, &Smooth, Sharing::PerPixel).unwrap();
        let mut worst = 0f32;
        for (a, b) in fast.pixels.iter().zip(&slow.pixels) {
            for c in 0..3 {
                assert_eq!(a[c] == 0.0, b[c] == 0.0, "{method}: blocked rays differ");
                worst = worst.max((a[c] - b[c]).abs());
            }
        }
        assert!(worst <= 1e-6, "{method} on {n} x {n}: {worst}");
    }
    // A pitch that is not a whole number of pixels shares nothing (and renders per pixel).
    let mut d = pmma_display(480);
    d.lcd.resolution = [479, 479];
    assert_eq!(lattice_period(&d), None);
}

fn image(n: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> RgbImage {
    let mut img = RgbImage::new(n, n);
    for r in 0..n {
        for c in 0..n {
            img.pixels[r * n + c] = f(r, c);
        }
    }
    img
}

#[test]
fn more_tuples_than_16_bits_take_32_bit_indices_with_the_same_values() {
    let n = 600;
    let d = pmma_display(n);
    // 80,000 distinct tuples in 360,000 pixels: beyond 16 bits, within a quarter of the pixels.
    let a = image(n, |r, c| [((r * n + c) % 80_000) as f32, 0.5, 0.25]);
    // A second image whose values repeat with the first's, so the pairs stay 80,000.
    let b = image(n, |r, c| {
        let i = (r * n + c) % 80_000;
        [(i % 4) as f32 * 0.25, if i % 7 == 0 { -0.0 } else { 0.0 }, 1.0]
    });
    let build = |imgs: &[&RgbImage]| {
        let mut s = StackBuilder::new(&d, imgs.len());
        for img in imgs {
            s.push(RgbView::from(*img)).unwrap();
        }
        s.finish().unwrap()
    };
    for imgs in [vec![&b, &a], vec![&a, &b], vec![&a]] {
        let dense = DisplayStack::new(&d, &imgs).unwrap();
        let packed = build(&imgs);
        assert!(packed.is_wide() && packed.bytes() < dense.bytes(), "{} images", imgs.len());
        for i in 0..n * n {
            let (x, y) = (dense.pixel(i), packed.pixel(i));
            assert!(x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()), "pixel {i}: {x:?} vs {y:?}");
        }
        for (k, img) in imgs.iter().enumerate() {
            assert!(packed
                .image(k)
                .pixels
                .iter()
                .zip(&img.pixels)
                .all(|(p, q)| (0..3).all(|c| p[c].to_bits() == q[c].to_bits())));
        }
    }
    // 100,000 distinct tuples: more than a quarter of the pixels, so dense.
    let many = image(n, |r, c| [((r * n + c) % 100_000) as f32, 0.5, 0.25]);
    assert!(!build(&[&b, &many]).is_palette());
}

#[test]
fn pupil_centers_lockstep_solves_render_the_one_ray_solves_bit_for_bit() {
    // PupilCenter shares no trace between pixels: its fast path differs from the slow twin only
    // by tracing a pixel's rays side by side and its channels' solves in lockstep, which changes
    // no bit.
    let d = pmma_display(360);
    let lens = d.thick_lenslet().unwrap();
    for spp in [1, 2] {
        let settings = DisplayRenderSettings { samples_per_pixel: spp, ..Default::default() };
        let fast = render_with(&d, lens, Method::PupilCenter, &settings, &Smooth, Sharing::Shared).unwrap();
        let slow = render_with(&d, lens, Method::PupilCenter, &settings, &Smooth, Sharing::PerPixel).unwrap();
        let same = fast.pixels.iter().zip(&slow.pixels).all(|(a, b)| (0..3).all(|c| a[c].to_bits() == b[c].to_bits()));
        assert!(same, "{spp} samples per pixel");
    }
}
