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
    /// A uniform number in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    /// A vector of three uniform numbers in [lo, hi).
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
    /// A uniform number in [lo, hi).
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

/// A few hundred bytes: an OpenEXR header (R, G, B float channels, no compression) whose data
/// window claims `w` x `h` pixels, and no pixel data.
pub fn exr_header_bomb(w: i32, h: i32) -> Vec<u8> {
    fn attr(out: &mut Vec<u8>, name: &str, ty: &str, value: &[u8]) {
        out.extend_from_slice(name.as_bytes());
        out.push(0);
        out.extend_from_slice(ty.as_bytes());
        out.push(0);
        out.extend_from_slice(&(value.len() as i32).to_le_bytes());
        out.extend_from_slice(value);
    }
    let mut b = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    let mut channels = Vec::new();
    for name in ["B", "G", "R"] {
        channels.extend_from_slice(name.as_bytes());
        channels.push(0);
        channels.extend_from_slice(&2i32.to_le_bytes()); // FLOAT
        channels.extend_from_slice(&[0, 0, 0, 0]); // pLinear + reserved
        channels.extend_from_slice(&1i32.to_le_bytes());
        channels.extend_from_slice(&1i32.to_le_bytes());
    }
    channels.push(0);
    attr(&mut b, "channels", "chlist", &channels);
    attr(&mut b, "compression", "compression", &[0]);
    let window: Vec<u8> = [0, 0, w - 1, h - 1].iter().flat_map(|v: &i32| v.to_le_bytes()).collect();
    attr(&mut b, "dataWindow", "box2i", &window);
    attr(&mut b, "displayWindow", "box2i", &window);
    attr(&mut b, "lineOrder", "lineOrder", &[0]);
    attr(&mut b, "pixelAspectRatio", "float", &1f32.to_le_bytes());
    attr(&mut b, "screenWindowCenter", "v2f", &[0; 8]);
    attr(&mut b, "screenWindowWidth", "float", &1f32.to_le_bytes());
    b.push(0);
    b
}

/// Writes `quad.obj` (a 100 mm square at z = 400 mm facing the eye, with texture coordinates)
/// and `scene.toml` (that square textured with the image `texture`, a file name in `dir`) into
/// `dir`, and returns the scene file's path.
pub fn textured_quad_scene(dir: &std::path::Path, name: &str, texture: &str) -> std::io::Result<std::path::PathBuf> {
    std::fs::write(
        dir.join("quad.obj"),
        "v -50 -50 400\nv 50 -50 400\nv 50 50 400\nv -50 50 400\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n",
    )?;
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!(
            "name = \"{name}\"\n[[objects]]\ntype = \"mesh\"\nfile = \"quad.obj\"\nmaterial = {{ texture = \"{texture}\" }}\n"
        ),
    )?;
    Ok(scene)
}

/// The CLI arguments of `ground-truth` for a 16 x 16 pinhole retina of `scene`, written to `out`
/// (the smallest run that loads a scene and its textures).
pub fn pinhole_ground_truth_args<'a>(scene: &'a std::path::Path, out: &'a std::path::Path) -> Vec<&'a str> {
    let text = |p: &'a std::path::Path| p.to_str().expect("a UTF-8 test path");
    vec!["--quiet", "ground-truth", "--pinhole", "--retina", "16", "--scene", text(scene), "--out", text(out)]
}

/// A 57-byte PNG whose header claims `w` x `h` RGB pixels (and whose one data chunk is empty).
pub fn png_header_bomb(w: u32, h: u32) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        crc.update(data);
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        out.extend_from_slice(&crc.finalize().to_be_bytes());
    }
    let mut b = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]); // 8-bit RGB, deflate, no filter, no interlace
    chunk(&mut b, b"IHDR", &ihdr);
    chunk(&mut b, b"IDAT", &[]);
    chunk(&mut b, b"IEND", &[]);
    b
}
