//! Image textures on meshes, looked up by the mesh's per-vertex texture coordinates. Not part of
//! the paper (its scene is bar charts on planes, Sec. 4.1); this lets textured meshes from
//! files (OBJ `map_Kd`, or a PNG named in the scene file) be shown on the simulated display.
//!
//! Conventions:
//! * UVs are OBJ/PLY texture coordinates: `u = 0` is the image's left edge, `u = 1` its right
//!   edge, `v = 0` its **bottom** row and `v = 1` its top row. Images are stored row 0 at top,
//!   so the lookup flips `v`: image row coordinate `y = (1 - v) * height`.
//! * Texel `(i, j)` covers `[i, i + 1] x [j, j + 1]` in pixel coordinates; its centre is at
//!   `i + 0.5`. Nearest filtering returns the texel containing the point; bilinear filtering
//!   blends the four texels whose centres surround it.
//! * UVs outside `[0, 1]`: [`Wrap::Repeat`] (default) keeps the fractional part (tiling);
//!   [`Wrap::Clamp`] uses the nearest edge texel. A NaN or infinite UV (which finite meshes do
//!   not produce, but a broken file may) gives the texture's mean colour, so no NaN ever
//!   reaches an image.
//! * PNG files (8 or 16 bit, grey or colour, with or without alpha; alpha is ignored) and JPEG
//!   files (what glTF files embed) are taken to be sRGB-encoded and are linearised with the sRGB
//!   transfer function on load. The format is told by the file's content, not its name.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::raster::srgb_to_linear;

/// Texture filtering.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Filter {
    /// The nearest texel.
    Nearest,
    /// Bilinear interpolation of the four nearest texels.
    #[default]
    Bilinear,
}

/// What happens to UVs outside `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Wrap {
    /// The texture tiles the plane.
    #[default]
    Repeat,
    /// UVs are clamped to the edge texels.
    Clamp,
}

/// A texture's texels as stored: row-major, row 0 at top.
#[derive(Clone, Debug)]
enum Texels {
    /// Linear RGB as given ([`ImageTexture::new`]).
    Linear(Vec<DVec3>),
    /// sRGB-encoded samples as decoded, `channels` a texel (1 grey, 2 grey and alpha, 3 RGB, 4
    /// RGBA; alpha is ignored), each `bytes` bytes (1: `u8`, 2: native-endian `u16`, 4:
    /// native-endian `f32`). 8- and 16-bit samples are linearised through `table`, floats by
    /// [`srgb_to_linear`] at each lookup.
    Encoded { data: Vec<u8>, channels: usize, bytes: usize, table: Option<&'static [f64]> },
}

/// An image texture: linear RGB when sampled, stored at the precision of its file (8-bit
/// samples take one byte each, not the 24 bytes of a linear `DVec3` texel).
#[derive(Clone, Debug)]
pub struct ImageTexture {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Shared by every copy (a texture used by many materials is decoded and held once).
    texels: std::sync::Arc<Texels>,
    /// Filtering.
    pub filter: Filter,
    /// What UVs outside [0, 1] do.
    pub wrap: Wrap,
    /// Every texel is multiplied by this when looked up ([`ImageTexture::scaled`]).
    factor: DVec3,
    /// Mean of all (unscaled) texels, computed at the first non-finite UV.
    mean: std::sync::OnceLock<DVec3>,
    /// The decoded samples' bytes, counted against `--max-memory` once while any copy lives.
    _held: Option<std::sync::Arc<crate::budget::Held>>,
}

/// The linear value of each 8-bit (256 entries) or 16-bit (65536 entries) sample of an image of
/// colour type `color`: the sample as `image` converts that colour type to RGB `f32`,
/// linearised in `f64` (what decoding to RGB `f32` and then linearising each texel gives, bit
/// for bit; `image` converts some colour types by division and others by multiplication, so
/// each has its own table). `None` for float samples.
fn table(color: image::ColorType) -> Option<&'static [f64]> {
    use image::{ColorType as C, DynamicImage as D, ImageBuffer};
    use std::sync::OnceLock;
    static TABLES: [OnceLock<Vec<f64>>; 8] = [const { OnceLock::new() }; 8];
    let slot =
        [C::L8, C::La8, C::Rgb8, C::Rgba8, C::L16, C::La16, C::Rgb16, C::Rgba16].iter().position(|c| *c == color)?;
    let t = TABLES[slot].get_or_init(|| {
        let (n8, n16) = (256u32, 65536u32);
        let img = match color {
            C::L8 => D::ImageLuma8(ImageBuffer::from_fn(n8, 1, |x, _| image::Luma([x as u8]))),
            C::La8 => D::ImageLumaA8(ImageBuffer::from_fn(n8, 1, |x, _| image::LumaA([x as u8; 2]))),
            C::Rgb8 => D::ImageRgb8(ImageBuffer::from_fn(n8, 1, |x, _| image::Rgb([x as u8; 3]))),
            C::Rgba8 => D::ImageRgba8(ImageBuffer::from_fn(n8, 1, |x, _| image::Rgba([x as u8; 4]))),
            C::L16 => D::ImageLuma16(ImageBuffer::from_fn(n16, 1, |x, _| image::Luma([x as u16]))),
            C::La16 => D::ImageLumaA16(ImageBuffer::from_fn(n16, 1, |x, _| image::LumaA([x as u16; 2]))),
            C::Rgb16 => D::ImageRgb16(ImageBuffer::from_fn(n16, 1, |x, _| image::Rgb([x as u16; 3]))),
            _ => D::ImageRgba16(ImageBuffer::from_fn(n16, 1, |x, _| image::Rgba([x as u16; 4]))),
        };
        img.to_rgb32f().pixels().map(|p| srgb_to_linear(p[0] as f64)).collect()
    });
    Some(t)
}

impl ImageTexture {
    /// A texture from linear texels (row 0 at top). `None` when the size does not match or is 0.
    pub fn new(width: usize, height: usize, texels: Vec<DVec3>, filter: Filter, wrap: Wrap) -> Option<Self> {
        if width == 0 || height == 0 || texels.len() != width * height {
            return None;
        }
        Some(Self::with(width, height, Texels::Linear(texels), filter, wrap, None))
    }

    fn with(width: usize, height: usize, texels: Texels, filter: Filter, wrap: Wrap, held: Option<u64>) -> Self {
        let held = held.map(|b| std::sync::Arc::new(crate::budget::Held::new(b)));
        let texels = std::sync::Arc::new(texels);
        Self { width, height, texels, filter, wrap, factor: DVec3::ONE, mean: Default::default(), _held: held }
    }

    /// The bytes the texels take.
    pub fn bytes(&self) -> u64 {
        match self.texels.as_ref() {
            Texels::Linear(t) => (t.len() * std::mem::size_of::<DVec3>()) as u64,
            Texels::Encoded { data, .. } => data.len() as u64,
        }
    }

    /// Decodes a PNG or JPEG image held in memory (sRGB-encoded), e.g. one embedded in a glTF
    /// file, keeping its samples at their stored precision. The decoded size (from the header:
    /// width x height x channels x bytes a sample) is checked against the memory budget before
    /// anything is decoded, and the buffer is allocated fallibly. Errors name `source` (the file
    /// and the image within it).
    pub fn decode(bytes: &[u8], source: &str, filter: Filter, wrap: Wrap) -> Result<Self> {
        use image::ImageDecoder;
        let format = image::guess_format(bytes)
            .ok()
            .filter(|f| matches!(f, image::ImageFormat::Png | image::ImageFormat::Jpeg))
            .ok_or_else(|| Error::parse(source, "texture is not a PNG or JPEG image"))?;
        let not_readable =
            |e: image::ImageError| Error::parse(source, format!("not a readable {format:?} texture: {e}"));
        let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
        // The decoder's own buffers (rows, the compressed stream) stay small; the image itself
        // goes into the buffer allocated here.
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(64 << 20);
        reader.limits(limits);
        let decoder = reader.into_decoder().map_err(not_readable)?;
        let (w, h) = decoder.dimensions();
        let color = decoder.color_type();
        // The size in the header is checked against the memory budget before anything is
        // decoded: a small file claiming a huge image is an error naming it, not an allocation.
        let need = decoder.total_bytes();
        // A JPEG decoder keeps working buffers as large again (a progressive file's coefficients,
        // two bytes a sample).
        let working = if format == image::ImageFormat::Jpeg { need.saturating_mul(2) } else { 0 };
        let budget = crate::budget::memory_budget();
        if need.saturating_add(working) > budget.bytes {
            return Err(Error::parse(
                source,
                format!(
                    "image header claims {w} x {h} pixels ({color:?}), which would need {} as a texture, more than \
                     the memory limit of {budget}",
                    crate::budget::Bytes(need.saturating_add(working)),
                ),
            ));
        }
        let mut data = crate::budget::try_vec(need as usize, 0u8, &format!("the texture {source} ({w} x {h})"))?;
        decoder.read_image(&mut data).map_err(not_readable)?;
        Self::from_samples(w as usize, h as usize, data, color, filter, wrap).ok_or_else(|| {
            Error::parse(source, format!("texture image is empty or of an unsupported kind ({color:?})"))
        })
    }

    /// A texture from decoded sRGB-encoded samples (see [`Texels::Encoded`]).
    fn from_samples(
        width: usize,
        height: usize,
        data: Vec<u8>,
        color: image::ColorType,
        filter: Filter,
        wrap: Wrap,
    ) -> Option<Self> {
        let channels = color.channel_count() as usize;
        let bytes = color.bytes_per_pixel() as usize / channels;
        let table = table(color);
        let float = matches!(color, image::ColorType::Rgb32F | image::ColorType::Rgba32F);
        let fits = width.checked_mul(height)?.checked_mul(channels * bytes)? == data.len();
        if width == 0 || height == 0 || !(table.is_some() || float) || !fits {
            return None;
        }
        let held = data.len() as u64;
        Some(Self::with(width, height, Texels::Encoded { data, channels, bytes, table }, filter, wrap, Some(held)))
    }

    /// The texture with every texel multiplied by `factor` (a glTF `baseColorFactor` or MTL
    /// `Kd` applied to its texture), at lookup. (Scaling twice multiplies by the product.)
    pub fn scaled(mut self, factor: DVec3) -> Self {
        self.factor *= factor;
        self
    }

    /// The mean colour of all texels: the colour of a point with no or non-finite UVs.
    pub fn mean(&self) -> DVec3 {
        let n = self.width * self.height;
        *self.mean.get_or_init(|| (0..n).map(|k| self.unscaled(k)).fold(DVec3::ZERO, |a, b| a + b) / n as f64)
            * self.factor
    }

    /// Texel `k` (row-major index), linear, before the factor.
    #[inline]
    fn unscaled(&self, k: usize) -> DVec3 {
        match self.texels.as_ref() {
            Texels::Linear(t) => t[k],
            Texels::Encoded { data, channels, bytes, table } => {
                let (c, b) = (*channels, *bytes);
                let at = k * c * b;
                let sample = |ch: usize| -> f64 {
                    let o = at + ch * b;
                    match (b, table) {
                        (1, Some(t)) => t[data[o] as usize],
                        (2, Some(t)) => t[u16::from_ne_bytes([data[o], data[o + 1]]) as usize],
                        _ => {
                            srgb_to_linear(f32::from_ne_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]) as f64)
                        }
                    }
                };
                if c < 3 {
                    DVec3::splat(sample(0))
                } else {
                    DVec3::new(sample(0), sample(1), sample(2))
                }
            }
        }
    }

    fn texel(&self, i: i64, j: i64) -> DVec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let (i, j) = match self.wrap {
            Wrap::Repeat => (i.rem_euclid(w), j.rem_euclid(h)),
            Wrap::Clamp => (i.clamp(0, w - 1), j.clamp(0, h - 1)),
        };
        self.unscaled(j as usize * self.width + i as usize) * self.factor
    }

    /// The colour at texture coordinates `uv` (see the module comment for the conventions).
    pub fn sample(&self, uv: DVec2) -> DVec3 {
        if !uv.is_finite() {
            return self.mean();
        }
        let (u, v) = match self.wrap {
            Wrap::Repeat => (uv.x - uv.x.floor(), uv.y - uv.y.floor()),
            Wrap::Clamp => (uv.x.clamp(0.0, 1.0), uv.y.clamp(0.0, 1.0)),
        };
        // Pixel coordinates, v flipped (v = 0 is the bottom row).
        let x = u * self.width as f64;
        let y = (1.0 - v) * self.height as f64;
        match self.filter {
            Filter::Nearest => {
                // x == width (u == 1 after clamping) belongs to the last texel.
                let i = (x.floor() as i64).min(self.width as i64 - 1);
                let j = (y.floor() as i64).min(self.height as i64 - 1);
                self.texel(i, j)
            }
            Filter::Bilinear => {
                let (fx, fy) = (x - 0.5, y - 0.5);
                let (i0, j0) = (fx.floor(), fy.floor());
                let (ax, ay) = (fx - i0, fy - j0);
                let (i0, j0) = (i0 as i64, j0 as i64);
                let top = self.texel(i0, j0) * (1.0 - ax) + self.texel(i0 + 1, j0) * ax;
                let bottom = self.texel(i0, j0 + 1) * (1.0 - ax) + self.texel(i0 + 1, j0 + 1) * ax;
                top * (1.0 - ay) + bottom * ay
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> ImageTexture {
        // 2 x 2: top row red, green; bottom row blue, white.
        let t = vec![DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
        ImageTexture::new(2, 2, t, Filter::Nearest, Wrap::Repeat).unwrap()
    }

    #[test]
    fn v_is_flipped_and_repeat_tiles() {
        let t = checker();
        assert_eq!(t.sample(DVec2::new(0.25, 0.75)), DVec3::X); // top left
        assert_eq!(t.sample(DVec2::new(0.75, 0.75)), DVec3::Y); // top right
        assert_eq!(t.sample(DVec2::new(0.25, 0.25)), DVec3::Z); // bottom left
        assert_eq!(t.sample(DVec2::new(1.25, -0.75)), DVec3::Z); // tiled
        assert_eq!(t.sample(DVec2::new(f64::NAN, 0.5)), DVec3::splat(0.5)); // mean
    }

    #[test]
    fn clamp_and_bilinear() {
        let mut t = checker();
        t.wrap = Wrap::Clamp;
        assert_eq!(t.sample(DVec2::new(-3.0, 7.0)), DVec3::X);
        assert_eq!(t.sample(DVec2::new(1.0, 0.0)), DVec3::ONE);
        t.filter = Filter::Bilinear;
        // The image centre blends all four texels equally.
        assert!((t.sample(DVec2::new(0.5, 0.5)) - DVec3::splat(0.5)).length() < 1e-12);
        // A texel centre returns that texel.
        assert!((t.sample(DVec2::new(0.25, 0.75)) - DVec3::X).length() < 1e-12);
    }

    /// Today's conversion kept as the slow twin: the image decoded to RGB `f32` and linearised
    /// into `f64` texels.
    fn twin(img: &image::DynamicImage, filter: Filter, wrap: Wrap) -> ImageTexture {
        let rgb = img.to_rgb32f();
        let texels = rgb
            .pixels()
            .map(|p| DVec3::new(srgb_to_linear(p[0] as f64), srgb_to_linear(p[1] as f64), srgb_to_linear(p[2] as f64)))
            .collect();
        ImageTexture::new(rgb.width() as usize, rgb.height() as usize, texels, filter, wrap).unwrap()
    }

    fn encode(img: &image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, format).unwrap();
        out.into_inner()
    }

    /// Every sample the same bits: nearest and bilinear, repeat and clamp, scaled or not, on a
    /// grid of UVs inside, on and outside [0, 1], and the mean.
    fn assert_same(a: &ImageTexture, b: &ImageTexture, what: &str) {
        assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
        let factor = DVec3::new(0.9, 0.35, 1.7);
        for scale in [false, true] {
            let (a, b) =
                if scale { (a.clone().scaled(factor), b.clone().scaled(factor)) } else { (a.clone(), b.clone()) };
            assert_eq!(a.mean().to_array().map(f64::to_bits), b.mean().to_array().map(f64::to_bits), "{what}");
            for filter in [Filter::Nearest, Filter::Bilinear] {
                for wrap in [Wrap::Repeat, Wrap::Clamp] {
                    let (mut a, mut b) = (a.clone(), b.clone());
                    (a.filter, a.wrap, b.filter, b.wrap) = (filter, wrap, filter, wrap);
                    for i in -7..=47 {
                        for j in -7..=47 {
                            let uv = DVec2::new(i as f64 / 37.0, j as f64 / 41.0);
                            let (x, y) = (a.sample(uv), b.sample(uv));
                            assert_eq!(x.to_array().map(f64::to_bits), y.to_array().map(f64::to_bits), "{what} {uv}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn stored_precision_samples_the_same_bits_as_linear_f64_texels() {
        use image::{DynamicImage as D, ImageBuffer, ImageFormat};
        let (w, h) = (23u32, 17u32);
        let v8 = |x: u32, y: u32, c: u32| ((x * 37 + y * 101 + c * 71) % 256) as u8;
        let v16 = |x: u32, y: u32, c: u32| ((x * 2749 + y * 7919 + c * 12007) % 65536) as u16;
        let images = [
            ("grey 8", D::ImageLuma8(ImageBuffer::from_fn(w, h, |x, y| image::Luma([v8(x, y, 0)])))),
            (
                "grey-alpha 8",
                D::ImageLumaA8(ImageBuffer::from_fn(w, h, |x, y| image::LumaA([v8(x, y, 0), v8(x, y, 3)]))),
            ),
            ("RGB 8", D::ImageRgb8(ImageBuffer::from_fn(w, h, |x, y| image::Rgb([0, 1, 2].map(|c| v8(x, y, c)))))),
            (
                "RGBA 8",
                D::ImageRgba8(ImageBuffer::from_fn(w, h, |x, y| image::Rgba([0, 1, 2, 3].map(|c| v8(x, y, c))))),
            ),
            ("grey 16", D::ImageLuma16(ImageBuffer::from_fn(w, h, |x, y| image::Luma([v16(x, y, 0)])))),
            ("RGB 16", D::ImageRgb16(ImageBuffer::from_fn(w, h, |x, y| image::Rgb([0, 1, 2].map(|c| v16(x, y, c)))))),
            (
                "RGBA 16",
                D::ImageRgba16(ImageBuffer::from_fn(w, h, |x, y| image::Rgba([0, 1, 2, 3].map(|c| v16(x, y, c))))),
            ),
        ];
        for (what, img) in &images {
            let png = encode(img, ImageFormat::Png);
            let stored = ImageTexture::decode(&png, what, Filter::Bilinear, Wrap::Repeat).unwrap();
            let channels = img.color().channel_count() as usize;
            let bytes = img.color().bytes_per_pixel() as usize / channels;
            // Kept as decoded: one or two bytes a sample, alpha included.
            assert_eq!(stored.bytes(), (w * h) as u64 * (channels * bytes) as u64, "{what}");
            let decoded = image::load_from_memory(&png).unwrap();
            assert_same(&stored, &twin(&decoded, Filter::Bilinear, Wrap::Repeat), what);
        }
        // A JPEG (what glTF files embed), grey and colour.
        for (what, img) in [&images[0], &images[2]] {
            let jpeg = encode(img, ImageFormat::Jpeg);
            let stored = ImageTexture::decode(&jpeg, what, Filter::Bilinear, Wrap::Repeat).unwrap();
            let decoded = image::load_from_memory(&jpeg).unwrap();
            assert_same(&stored, &twin(&decoded, Filter::Bilinear, Wrap::Repeat), what);
        }
        // Float samples (no PNG or JPEG holds them; the storage takes them as they come).
        let f = |x: u32, y: u32, c: u32| (v16(x, y, c) as f32 / 50000.0) - 0.1; // some outside [0, 1]
        for channels in [3usize, 4] {
            let img = if channels == 3 {
                D::ImageRgb32F(ImageBuffer::from_fn(w, h, |x, y| image::Rgb([0, 1, 2].map(|c| f(x, y, c)))))
            } else {
                D::ImageRgba32F(ImageBuffer::from_fn(w, h, |x, y| image::Rgba([0, 1, 2, 3].map(|c| f(x, y, c)))))
            };
            let data: Vec<u8> = img.as_bytes().to_vec();
            let stored =
                ImageTexture::from_samples(w as usize, h as usize, data, img.color(), Filter::Bilinear, Wrap::Repeat)
                    .unwrap();
            assert_same(&stored, &twin(&img, Filter::Bilinear, Wrap::Repeat), "float");
        }
        // Sizes that do not add up are refused.
        use image::ColorType as C;
        let (n, r) = (Filter::Nearest, Wrap::Repeat);
        assert!(ImageTexture::from_samples(2, 2, vec![0; 11], C::Rgb8, n, r).is_none());
        assert!(ImageTexture::from_samples(2, 2, vec![0; 24], C::Rgb16, n, r).is_some());
        assert!(ImageTexture::from_samples(2, 2, vec![0; 8], C::La8, n, r).is_some());
        assert!(ImageTexture::from_samples(0, 2, vec![], C::L8, n, r).is_none());
    }

    #[test]
    fn a_texture_over_the_budget_is_refused_before_decoding() {
        let png = crate::fixtures::png_header_bomb(200_000, 200_000);
        let e = ImageTexture::decode(&png, "bomb.png", Filter::Nearest, Wrap::Repeat).unwrap_err().to_string();
        assert!(e.contains("bomb.png") && e.contains("200000 x 200000") && e.contains("memory limit of"), "{e}");
    }
}
