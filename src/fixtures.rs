//! Test and bench fixtures, not part of the API: deterministic random numbers, a white-wall
//! scene, and the display and eye rays of the paper's set-up (Sec. 4.1) that the BVH and Embree
//! benches trace. Shared by `tests/` and `benches/`; hidden from the documentation.

use glam::DVec3;

/// Small deterministic generator (xorshift64*), uniform in [0, 1), so tests need no RNG crate
/// and every run sees the same rays.
pub struct Rng(pub u64);

impl Rng {
    /// The next number (a sampler that never ends, not an iterator).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    pub fn vec(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    /// A random unit vector (rejection sampling in the unit ball).
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// A linear congruential generator, uniform in [0, 1): the optics tests' deterministic inputs.
pub struct Lcg(pub u64);

impl Lcg {
    /// The next number (a sampler that never ends, not an iterator).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// A white wall at z = 500 mm, 100 m wide: every camera and eye ray of a test sees radiance 1.
pub fn white_wall() -> crate::scene::Scene {
    use crate::scene::{Material, Object, Rect, Scene, Shape};
    Scene {
        name: "white".into(),
        objects: vec![Object {
            name: "wall".into(),
            shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, 500.0), 1e5, 1e5)),
            material: Material::Albedo(DVec3::ONE),
        }],
        background: DVec3::ZERO,
        light: None,
        warnings: Vec::new(),
    }
}

/// The pipeline's rays, as the benches trace them on scenes/bunny.toml: LC camera rays of `rows` LCD rows through the middle of the paper display, row-major.
pub fn bunny_display_rays(rows: usize) -> Vec<crate::ray::Ray> {
    let d = crate::optics::Display::paper();
    let r0 = d.lcd.rows() / 2 - rows / 2;
    let mut rays = Vec::with_capacity(rows * d.lcd.columns());
    for row in r0..r0 + rows {
        for col in 0..d.lcd.columns() {
            let x3 = d.lcd.pixel_center(row, col);
            let c = d.lenslets.center(d.elemental_image_of(x3));
            rays.push(crate::optics::transfer::camera_ray(&d, x3, c, c, 0.0));
        }
    }
    rays
}

/// Ground-truth eye rays (5 mm pupil, 8 x 8 grid, focus 386 mm) of `rows` retina rows
/// (512 px, +-0.3) through the middle, each row laid out [pupil sample][column].
pub fn bunny_eye_rays(rows: usize) -> Vec<crate::ray::Ray> {
    let eye = crate::optics::Eye::thin_lens(5.0, crate::optics::Focus::Millimetres(386.0), 8);
    let retina = crate::optics::Retina::default();
    let pupil = eye.pupil_samples();
    let r0 = retina.resolution / 2 - rows / 2;
    let mut rays = Vec::new();
    for row in r0..r0 + rows {
        for s in &pupil {
            for col in 0..retina.resolution {
                rays.push(crate::optics::transfer::eye_scene_ray(
                    &eye,
                    retina.tangent(row, col, glam::DVec2::splat(0.5)),
                    *s,
                ));
            }
        }
    }
    rays
}
