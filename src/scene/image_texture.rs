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

/// A linear-RGB image texture.
#[derive(Clone, Debug)]
pub struct ImageTexture {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major, row 0 at top, linear RGB.
    pub texels: Vec<DVec3>,
    /// Filtering.
    pub filter: Filter,
    /// What UVs outside [0, 1] do.
    pub wrap: Wrap,
    /// Mean of all texels: the fallback colour for non-finite UVs.
    pub mean: DVec3,
}

impl ImageTexture {
    /// A texture from linear texels (row 0 at top). `None` when the size does not match or is 0.
    pub fn new(width: usize, height: usize, texels: Vec<DVec3>, filter: Filter, wrap: Wrap) -> Option<Self> {
        if width == 0 || height == 0 || texels.len() != width * height {
            return None;
        }
        let mean = texels.iter().copied().sum::<DVec3>() / texels.len() as f64;
        Some(Self { width, height, texels, filter, wrap, mean })
    }

    /// Decodes a PNG or JPEG image held in memory (sRGB-encoded), e.g. one embedded in a glTF
    /// file. Errors name `source` (the file and the image within it).
    pub fn decode(bytes: &[u8], source: &str, filter: Filter, wrap: Wrap) -> Result<Self> {
        let format = image::guess_format(bytes)
            .ok()
            .filter(|f| matches!(f, image::ImageFormat::Png | image::ImageFormat::Jpeg))
            .ok_or_else(|| Error::parse(source, "texture is not a PNG or JPEG image"))?;
        let not_readable =
            |e: image::ImageError| Error::parse(source, format!("not a readable {format:?} texture: {e}"));
        let reader = || image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
        // The size in the header is checked against the memory limit before anything is decoded:
        // a small file claiming a huge image is an error naming it, not an allocation.
        let (w, h) = reader().into_dimensions().map_err(not_readable)?;
        // Decoded 32-bit float RGB(A) (16 bytes) plus our linear f64 texels (24 bytes) per texel.
        let need = (w as u64).saturating_mul(h as u64).saturating_mul(40);
        let limit = crate::budget::memory_limit();
        if need > limit {
            return Err(Error::parse(
                source,
                format!(
                    "image header claims {w} x {h} pixels, which would need {} as a texture, more than the memory \
                     limit of {} (--max-memory)",
                    crate::budget::Bytes(need),
                    crate::budget::Bytes(limit)
                ),
            ));
        }
        let mut decoder = reader();
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(need.max(1 << 20));
        decoder.limits(limits);
        let img = decoder.decode().map_err(not_readable)?;
        let path = std::path::Path::new(source);
        let rgb = img.to_rgb32f();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        let texels = rgb
            .pixels()
            .map(|p| DVec3::new(srgb_to_linear(p[0] as f64), srgb_to_linear(p[1] as f64), srgb_to_linear(p[2] as f64)))
            .collect();
        Self::new(w, h, texels, filter, wrap).ok_or_else(|| Error::parse(path, "texture image is empty"))
    }

    /// The texture with every texel multiplied by `factor` (a glTF `baseColorFactor` or MTL
    /// `Kd` applied to its texture).
    pub fn scaled(mut self, factor: DVec3) -> Self {
        for t in &mut self.texels {
            *t *= factor;
        }
        self.mean *= factor;
        self
    }

    fn texel(&self, i: i64, j: i64) -> DVec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let (i, j) = match self.wrap {
            Wrap::Repeat => (i.rem_euclid(w), j.rem_euclid(h)),
            Wrap::Clamp => (i.clamp(0, w - 1), j.clamp(0, h - 1)),
        };
        self.texels[j as usize * self.width + i as usize]
    }

    /// The colour at texture coordinates `uv` (see the module comment for the conventions).
    pub fn sample(&self, uv: DVec2) -> DVec3 {
        if !uv.is_finite() {
            return self.mean;
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
}
