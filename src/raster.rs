//! In-memory RGB images: the common currency between renderers, metrics and file I/O.
//!
//! Storage convention (README "Conventions"): row 0 is the top row, pixels are row-major,
//! values are linear radiance (no gamma) in `f32`. Renderers compute in `f64` and store `f32`.

/// A linear-light RGB image, row 0 at the top, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Self {
        Self { width, height, pixels: vec![[0.0; 3]; width * height] }
    }

    /// An image with every pixel set to `value`.
    pub fn filled(width: usize, height: usize, value: [f32; 3]) -> Self {
        Self { width, height, pixels: vec![value; width * height] }
    }

    /// Pixel at (row, column).
    #[inline]
    pub fn get(&self, row: usize, col: usize) -> [f32; 3] {
        self.pixels[row * self.width + col]
    }

    #[inline]
    pub fn set(&mut self, row: usize, col: usize, value: [f32; 3]) {
        self.pixels[row * self.width + col] = value;
    }

    /// One channel (0 = R, 1 = G, 2 = B) as a row-major `f64` plane.
    pub fn channel(&self, c: usize) -> Vec<f64> {
        self.pixels.iter().map(|p| p[c] as f64).collect()
    }

    /// True when every sample is finite (no NaN, no infinity).
    pub fn all_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.iter().all(|v| v.is_finite()))
    }
}

/// Decodes an sRGB-encoded component in `[0, 1]` to linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
