//! PNG files: 8-bit sRGB previews of linear RGB images (quick looks at display and retinal images,
//! and the pixel encoding of the paper-style figures in [`super::figure`]).
//!
//! Linear values are clamped to `[0, 1]` (`NaN` counts as 0) and encoded with the exact sRGB
//! transfer function of IEC 61966-2-1 (linear segment `12.92 v` below 0.0031308, otherwise
//! `1.055 v^(1/2.4) − 0.055`), not a plain gamma of 2.2, then rounded to the nearest of 256
//! levels. [`srgb_encode`] is the formula itself; whole images use a lookup table built from it
//! that gives bit-identical results (see the unit test) at a fraction of the cost. Files are
//! written with the `image` crate's fast deflate setting.
//! Textures ([`load_texture`]) are read here too, with their claimed size checked first.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::sync::OnceLock;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::raster::{RgbImage, RgbView};
use crate::scene::image_texture::{Filter, ImageTexture, Wrap};

/// The 8-bit sRGB code of a linear value: clamp to `[0, 1]` (`NaN` → 0), apply the sRGB
/// transfer function, round to nearest. `srgb_encode(0.5) == 188`.
pub fn srgb_encode(linear: f32) -> u8 {
    let v = if linear.is_nan() { 0.0 } else { (linear as f64).clamp(0.0, 1.0) };
    let e = if v <= 0.0031308 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (e * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Bucket of a float in `(0, 1)`: its bit pattern without the low `BUCKET_SHIFT` bits. A bucket
/// spans a relative width of 2^-11, over which the 8-bit sRGB code changes by at most one step.
const BUCKET_SHIFT: u32 = 12;

struct SrgbTable {
    /// `threshold[k]` is the smallest `f32` whose code is at least `k` (`threshold[0] = 0`);
    /// `threshold[256] = +inf`.
    threshold: [f32; 257],
    /// Code of the lowest value of each bucket.
    bucket: Vec<u8>,
}

fn table() -> &'static SrgbTable {
    static TABLE: OnceLock<SrgbTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut threshold = [0.0f32; 257];
        threshold[256] = f32::INFINITY;
        for (k, t) in threshold.iter_mut().enumerate().take(256).skip(1) {
            // Bisection over the bit patterns of positive floats, which order like the values.
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if srgb_encode(f32::from_bits(mid)) as usize >= k {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *t = f32::from_bits(hi);
        }
        let buckets = (1.0f32.to_bits() >> BUCKET_SHIFT) as usize + 1;
        let bucket = (0..buckets).map(|b| srgb_encode(f32::from_bits((b as u32) << BUCKET_SHIFT))).collect();
        SrgbTable { threshold, bucket }
    })
}

/// Same result as [`srgb_encode`], by table lookup.
#[inline]
fn srgb_encode_fast(t: &SrgbTable, v: f32) -> u8 {
    if v.is_nan() || v <= 0.0 {
        0
    } else if v >= 1.0 {
        255
    } else {
        let code = t.bucket[(v.to_bits() >> BUCKET_SHIFT) as usize];
        code + (v >= t.threshold[code as usize + 1]) as u8
    }
}

/// The image as interleaved 8-bit sRGB RGB bytes, row 0 first.
pub fn to_srgb8(img: &RgbImage) -> Vec<u8> {
    view_to_srgb8(RgbView::from(img))
}

/// [`to_srgb8`] of an image seen through a view (pixels read where they are).
pub fn view_to_srgb8(img: RgbView<'_>) -> Vec<u8> {
    let t = table();
    let mut out = vec![0u8; img.len() * 3];
    out.par_chunks_mut(3 * 4096).enumerate().for_each(|(chunk, o)| {
        for (j, o) in o.chunks_exact_mut(3).enumerate() {
            let p = img.pixel(chunk * 4096 + j);
            for c in 0..3 {
                o[c] = srgb_encode_fast(t, p[c]);
            }
        }
    });
    out
}

/// Writes interleaved 8-bit RGB bytes (`width * height * 3`, row 0 at top) as a PNG with fast
/// compression. Errors name `path`.
pub fn write_rgb8(path: &Path, width: usize, height: usize, rgb: &[u8]) -> Result<()> {
    if width == 0 || height == 0 || rgb.len() != width * height * 3 {
        return Err(Error::invalid(
            path.display().to_string(),
            "image size",
            format!("{} bytes do not form a non-empty {width}x{height} RGB image", rgb.len()),
        ));
    }
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(Error::invalid(path.display().to_string(), "image size", "too large for PNG")),
    };
    let file = File::create(path).map_err(|e| Error::io(path, e))?;
    let mut writer = BufWriter::new(file);
    PngEncoder::new_with_quality(&mut writer, CompressionType::Fast, FilterType::Adaptive)
        .write_image(rgb, w, h, ExtendedColorType::Rgb8)
        .map_err(|e| match e {
            image::ImageError::IoError(e) => Error::io(path, e),
            other => Error::parse(path, format!("PNG encoding failed: {other}")),
        })?;
    use std::io::Write;
    writer.flush().map_err(|e| Error::io(path, e))
}

/// Writes a linear RGB image as an 8-bit sRGB PNG preview (clamped to `[0, 1]`, row 0 at top).
pub fn write_preview(path: &Path, img: &RgbImage) -> Result<()> {
    if img.pixels.len() != img.width * img.height {
        return Err(Error::invalid(
            path.display().to_string(),
            "pixels",
            format!("image has {} pixels, expected {}x{}", img.pixels.len(), img.width, img.height),
        ));
    }
    write_preview_view(path, RgbView::from(img))
}

/// [`write_preview`] of an image seen through a view (for example one image of a stack).
pub fn write_preview_view(path: &Path, img: RgbView<'_>) -> Result<()> {
    if !img.is_complete() {
        return Err(Error::invalid(
            path.display().to_string(),
            "pixels",
            format!("image buffer holds fewer than {}x{} pixels", img.width, img.height),
        ));
    }
    let (w, h) = match (u32::try_from(img.width), u32::try_from(img.height)) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => (w, h),
        _ => return Err(Error::invalid(path.display().to_string(), "image size", "empty or too large for PNG")),
    };
    let fail = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => Error::io(path, e),
        other => Error::parse(path, format!("PNG encoding failed: {other}")),
    };
    let file = File::create(path).map_err(|e| Error::io(path, e))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().map_err(fail)?;
    let mut stream = writer.stream_writer().map_err(fail)?;
    // Bands of rows encoded in parallel and streamed: no full 8-bit copy of a large image.
    let t = table();
    let row = img.width * 3;
    let mut band = vec![0u8; PREVIEW_BAND_ROWS * row];
    for y0 in (0..img.height).step_by(PREVIEW_BAND_ROWS) {
        // A cancelled run (`crate::progress`) stops between bands.
        crate::progress::check_cancelled()?;
        let rows = PREVIEW_BAND_ROWS.min(img.height - y0);
        band[..rows * row].par_chunks_mut(row).enumerate().for_each(|(dy, o)| {
            let first = (y0 + dy) * img.width;
            for (x, o) in o.chunks_exact_mut(3).enumerate() {
                let p = img.pixel(first + x);
                for c in 0..3 {
                    o[c] = srgb_encode_fast(t, p[c]);
                }
            }
        });
        std::io::Write::write_all(&mut stream, &band[..rows * row]).map_err(|e| Error::io(path, e))?;
    }
    stream.finish().map_err(fail)?;
    // The end chunk, then a checked flush of the buffered file.
    writer.finish().map_err(fail)
}

/// Rows of a streamed preview ([`write_preview_view`]) converted at once.
const PREVIEW_BAND_ROWS: usize = 64;

/// Loads a PNG or JPEG texture (sRGB-encoded) from a regular file; its claimed size is checked
/// against the memory limit before decoding ([`ImageTexture::decode`]). Errors name the file.
pub fn load_texture(path: &Path, filter: Filter, wrap: Wrap) -> Result<ImageTexture> {
    let bytes = crate::io::input::read_regular(path)?;
    ImageTexture::decode(&bytes, &path.display().to_string(), filter, wrap)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_streamed_preview_holds_the_pixels_of_the_whole_image_conversion() {
        // Several bands of rows, a last band cut short, and a strided view (one image of three
        // interleaved, as a display stack holds them).
        let (w, h) = (131, 2 * PREVIEW_BAND_ROWS + 9);
        let values: Vec<f32> = (0..w * h * 9).map(|i| ((i * 7919) % 1201) as f32 / 1000.0 - 0.1).collect();
        let view = RgbView::strided(w, h, &values, 9, 3).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        write_preview_view(&path, view).unwrap();
        let decoded = image::open(&path).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (w as u32, h as u32));
        assert!(decoded.into_raw() == view_to_srgb8(view));
    }

    #[test]
    fn table_matches_formula() {
        let t = table();
        // Around every threshold, and a sweep over all floats in [0, 1] with a prime stride.
        for k in 1..256 {
            let b = t.threshold[k].to_bits();
            for bits in b - 3..=b + 3 {
                let v = f32::from_bits(bits);
                assert_eq!(srgb_encode_fast(t, v), srgb_encode(v), "v = {v:e}");
            }
        }
        let mut bits = 0u32;
        while bits <= 1.0f32.to_bits() {
            let v = f32::from_bits(bits);
            assert_eq!(srgb_encode_fast(t, v), srgb_encode(v), "v = {v:e}");
            bits += 1009;
        }
        for v in [f32::NAN, -1.0, -0.0, 0.0, 1.0, 1.5, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE] {
            assert_eq!(srgb_encode_fast(t, v), srgb_encode(v), "v = {v:e}");
        }
    }
}
