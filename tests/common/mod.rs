//! Helpers shared by the integration tests and benches (`mod common;`, or
//! `#[path = "../tests/common/mod.rs"] mod common;` from a bench). Not every user needs every item.
#![allow(dead_code)]

use glam::DVec3;

/// Small deterministic generator (xorshift64*), uniform in [0, 1), so tests need no RNG crate
/// and every run sees the same rays.
pub struct Rng(pub u64);

impl Rng {
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
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// A white wall at z = 500 mm, 100 m wide: every camera and eye ray of a test sees radiance 1.
pub fn white_wall() -> inimtrace::scene::Scene {
    use inimtrace::scene::{Material, Object, Rect, Scene, Shape};
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
