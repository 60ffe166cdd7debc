//! Tests of the parent module: its fast paths against their slow twins and exact answers.
use glam::DMat2;

use super::*;
use crate::optics::eye::Focus;
use crate::optics::lattice::Lattice;

/// Deterministic uniform inputs (64-bit LCG, top 53 bits).
struct Inputs(u64);

impl Inputs {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn point(&mut self, half: f64) -> DVec2 {
        DVec2::new(self.uniform(-half, half), self.uniform(-half, half))
    }
}

/// The paper's display and one with a tilted, shifted lenslet lattice (so that the nearest
/// lenslet is not a per-axis rounding).
fn displays() -> [Display; 2] {
    let mut tilted = Display::paper();
    let m = DMat2::from_cols(DVec2::new(1.1, 0.2), DVec2::new(-0.3, 1.25));
    tilted.lenslets = Lattice::new(DVec2::new(0.17, -0.05), m).expect("valid lattice");
    [Display::paper(), tilted]
}

/// Eyes with the pupil centre off the axis and off the z = 0 plane, in and out of focus.
fn eyes() -> Vec<Eye> {
    let mut eyes = vec![
        Eye::pinhole(),
        Eye::thin_lens(5.0, Focus::Millimetres(300.0), 6),
        Eye::thin_lens(3.0, Focus::Diopters(0.0), 4),
    ];
    eyes[1].position = DVec3::new(1.3, -0.8, 0.0);
    eyes[2].position = DVec3::new(-2.1, 0.6, 4.5);
    eyes
}

#[test]
fn fast_transfer_lands_where_eye_to_lcd_does() {
    let mut rng = Inputs(0x5eed);
    for display in displays() {
        for eye in eyes() {
            let pupil = eye.pupil_samples();
            let fast = FastTransfer::new(&display, &eye, &pupil);
            let mut inside = 0;
            for _ in 0..3_000 {
                let tangent = rng.point(0.3);
                for (k, s) in pupil.iter().enumerate() {
                    let slow = eye_to_lcd(&display, &eye, tangent, *s).lcd;
                    let got = fast.lcd_point(tangent, k);
                    assert!((got - slow).length() < 1e-12, "fast {got:?} vs slow {slow:?}");
                    // The pixel read is the pixel of the fast point, with the LCD's own rule.
                    let pixel = fast.pixel_index(tangent, k);
                    assert_eq!(pixel, display.lcd.pixel_index(got));
                    inside += usize::from(pixel.is_some());
                }
            }
            assert!(inside > 0, "some rays must land on the LCD");
            // The batched pixels are the single-ray pixels, for every pupil sample.
            let mut tangents: Vec<DVec2> = (0..500).map(|_| rng.point(0.3)).collect();
            tangents.extend([DVec2::new(f64::NAN, 0.0), DVec2::splat(5.0)]);
            let (mut out, mut scratch) = (vec![0u32; tangents.len()], Vec::new());
            for k in 0..pupil.len() {
                fast.pixel_indices(&tangents, k, &mut scratch, &mut out);
                for (t, o) in tangents.iter().zip(&out) {
                    assert_eq!(*o, fast.pixel_index(*t, k).map_or(u32::MAX, |i| i as u32), "{t} {k}");
                }
            }
        }
    }
}

#[test]
fn camera_ray_is_the_eye_side_of_lcd_to_eye_and_traces_back_to_its_pixel() {
    let mut rng = Inputs(0xca11);
    for display in displays() {
        for eye in eyes() {
            for _ in 0..3_000 {
                let lcd = rng.point(10.0);
                let p = lcd + rng.point(1.5);
                let center = display.lenslets.center(display.lenslets.nearest(p));
                let ray = camera_ray(&display, lcd, center, p, eye.position.z);
                let (pupil, retina) = lcd_to_eye(&display, &eye, lcd, p);
                // The same line: it starts on the pupil plane where the slow trace crosses it,
                // with the slow trace's slope and a unit z step.
                assert_eq!(ray.origin.z, eye.position.z);
                assert_eq!(ray.dir.z, 1.0);
                assert!((ray.origin.truncate() - pupil.position).length() < 1e-12);
                assert!((ray.dir.truncate() - pupil.slope).length() < 1e-14);
                // Reversed through the eye, that light comes back to the LCD point it left.
                let tangent = -retina / eye.retina_distance;
                let offset = pupil.position - eye.position.truncate();
                let back = eye_to_lcd(&display, &eye, tangent, offset);
                assert_eq!(display.lenslets.center(back.lenslet_index), center);
                assert!((back.lcd - lcd).length() < 1e-9, "{:?} vs {lcd:?}", back.lcd);
            }
        }
    }
}

#[test]
fn pupil_center_point_sends_the_reverse_trace_through_the_pupil_centre() {
    let mut rng = Inputs(0xbc);
    for display in displays() {
        for eye in eyes() {
            check_pupil_center(&display, eye.position).expect("these displays are not singular");
            for _ in 0..2_000 {
                let lcd = rng.point(10.0);
                // The lenslet of the point's elemental image, as the renderer pairs them.
                let center = display.lenslets.center(display.elemental_image_of(lcd));
                let p = pupil_center_point(&display, lcd, center, eye.position);
                // Eq. (1) run backwards step by step (as in `lcd_to_eye`, but refracted by
                // `center`: the point usually lies outside that lenslet's cell).
                let w2 = (lcd - p) / display.lenslets_to_lcd;
                let before = PlaneRay { position: p, slope: w2 }.unrefract(center, display.lenslet_power());
                let at_pupil = before.propagate(-(display.lenslet_z() - eye.position.z));
                assert!((at_pupil.position - eye.position.truncate()).length() < 1e-9, "{at_pupil:?}");
                // And the camera ray from the pupil plane starts at the pupil centre.
                let ray = camera_ray(&display, lcd, center, p, eye.position.z);
                assert!((ray.origin - eye.position).length() < 1e-9, "{ray:?}");
            }
        }
    }
}

#[test]
fn refraction_undoes_itself() {
    let r = PlaneRay { position: DVec2::new(0.3, -0.7), slope: DVec2::new(0.01, 0.02) };
    let back = r.refract(DVec2::new(0.1, 0.2), 0.15).unrefract(DVec2::new(0.1, 0.2), 0.15);
    assert!((back.slope - r.slope).length() < 1e-15);
}

#[test]
fn eye_ray_through_pupil_centre_keeps_the_retina_direction() {
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8);
    let t = DVec2::new(0.1, -0.2);
    let r = eye_ray(&eye, t, DVec2::ZERO);
    assert!((r.slope - t).length() < 1e-15);
}
