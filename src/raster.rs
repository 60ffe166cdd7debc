//! In-memory RGB images: the common currency between renderers, metrics and file I/O.
//!
//! Storage convention (README "Conventions"): row 0 is the top row, pixels are row-major,
//! values are linear radiance (no gamma) in `f32`. Renderers compute in `f64` and store `f32`.

/// A linear-light RGB image, row 0 at the top, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width * height` linear RGB pixels, row-major from the top-left.
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Self {
        Self { width, height, pixels: vec![[0.0; 3]; width * height] }
    }

    /// A black image allocated fallibly: a refused allocation is an error naming `what` and its
    /// size (one line), not an abort.
    pub fn try_new(width: usize, height: usize, what: &str) -> crate::error::Result<Self> {
        let pixels = crate::budget::try_vec(width.saturating_mul(height), [0.0; 3], what)?;
        Ok(Self { width, height, pixels })
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

    /// Sets the pixel at (row, column).
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

/// A read-only view of an RGB image whose pixels lie `stride` floats apart in a larger buffer
/// (one image of an interleaved stack, see [`crate::render::retina::DisplayStack`]), or
/// contiguous (an [`RgbImage`]). Writers take views so that an image is never copied to be
/// written.
#[derive(Clone, Copy, Debug)]
pub struct RgbView<'a> {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    values: &'a [f32],
    stride: usize,
    offset: usize,
}

impl<'a> RgbView<'a> {
    /// Pixel `i` (row-major) is `values[i * stride + offset..][..3]`. `None` when `values` is too
    /// short for `width x height` pixels or `offset + 3 > stride`.
    pub fn strided(width: usize, height: usize, values: &'a [f32], stride: usize, offset: usize) -> Option<Self> {
        let pixels = width.checked_mul(height)?;
        let needed = pixels.checked_mul(stride)?;
        (offset + 3 <= stride && values.len() >= needed).then_some(Self { width, height, values, stride, offset })
    }

    /// Pixel `i`, row-major.
    #[inline(always)]
    pub fn pixel(&self, i: usize) -> [f32; 3] {
        let p = &self.values[i * self.stride + self.offset..][..3];
        [p[0], p[1], p[2]]
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// True when the view has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the buffer holds all `width x height` pixels (always, for [`RgbView::strided`]).
    pub fn is_complete(&self) -> bool {
        self.values.len() >= self.len() * self.stride
    }

    /// A copy as an [`RgbImage`].
    pub fn to_image(&self) -> RgbImage {
        RgbImage { width: self.width, height: self.height, pixels: (0..self.len()).map(|i| self.pixel(i)).collect() }
    }
}

impl<'a> From<&'a RgbImage> for RgbView<'a> {
    fn from(img: &'a RgbImage) -> Self {
        // Writers check `is_complete` (an image whose pixel count disagrees with its size).
        let values = img.pixels.as_flattened();
        Self { width: img.width, height: img.height, values, stride: 3, offset: 0 }
    }
}

/// What is wrong with a linear RGB sample read from outside (an EXR file, a NumPy array):
/// "NaN", "infinite" or "negative"; `None` when it is finite and non-negative. The one rule for
/// every input image.
pub fn bad_sample(v: f32) -> Option<&'static str> {
    if v.is_nan() {
        Some("NaN")
    } else if v.is_infinite() {
        Some("infinite")
    } else if v < 0.0 {
        Some("negative")
    } else {
        None
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
