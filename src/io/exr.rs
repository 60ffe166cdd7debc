//! OpenEXR files of linear RGB images: the rendered display images (elemental-image arrays) and
//! the simulated retinal images that the paper compares (its Figures 3–4 and Table 1 are made
//! from them). Written and read with the `exr` crate, except that the pixel blocks of ZIP and
//! ZIPS files are compressed by `exr_zip.rs` with a faster deflate (the same samples, header
//! and attributes; files a tenth to a fifth larger than the crate's).
//!
//! **Writing** ([`write_rgb_with`], [`write_rgb`]): one layer with `f32` channels `R`, `G`, `B`
//! and, when a depth plane is given, `Z` (the hit distance per pixel); scan-line blocks in
//! increasing-Y line order, so row 0 of the [`RgbImage`] is the top row of the file (OpenEXR's y
//! axis points down). Compression is lossless ZIP by default ([`ExrCompression`]). Custom
//! attributes (for example `"inimtrace:method" = "LC"`, `"inimtrace:focus_mm" = 300.0`) go into
//! the header typed ([`AttrValue`]: `string`, `double`, `float`, `int`); names and text must be
//! Latin-1 and names may not be OpenEXR's reserved attribute names. Every file also carries
//! `inimtrace:version`, `inimtrace:git_revision` and the standard `software` attribute
//! ([`crate::version`]). Sample values are written as given.
//!
//! **Reading** ([`read_rgb`], [`read_rgb_depth`], [`read_input`], by `exr_read.rs`): one part
//! with `R`, `G` and `B` channels (named by `--part` in a multipart file, or the only such part,
//! with a note); each stored as `f16` or `f32` (`u32` is refused: integers are not radiance) and
//! converted to `f32`. Its data window must be its display window, and every block must be
//! present once and intact (ZIP blocks' Adler-32 checked). `Z` is returned by
//! [`read_rgb_depth`] (`+inf` allowed: no hit); other channels are ignored.
//!
//! **Input policy:** every `R`, `G`, `B` sample read must be finite and non-negative (a linear
//! radiance). A `NaN`, infinite or negative sample is not clamped or repaired: reading fails
//! with an error that names the file, the pixel `(row, col)` (row 0 at the top) and the channel.
//! A missing file, a directory, an empty, truncated or non-EXR file, a file without `R`/`G`/`B`
//! channels, or subsampled channels also give an error naming the file, never a panic.

use std::collections::HashMap;
use std::path::Path;

use exr::image::write::layers::WritableLayers;
use exr::image::{Encoding, Image, Layer, SpecificChannels};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, Text};
use exr::meta::header::{standard_names, LayerAttributes};
use exr::prelude::{Blocks, Compression, LineOrder, WritableImage};

pub use super::exr_attributes::{AttrValue, Attributes};
pub use super::exr_read::ExrInput;
use crate::error::{Error, Result};
use crate::raster::{RgbImage, RgbView};

/// Compression of written files (`--exr-compression`). Every choice but `pxr24` is lossless.
///
/// Rendered display images are mostly flat regions and compress well: the paper's 2160 x 2160
/// display image with its `Z` channel is 74.7 MB uncompressed and 7.8-8.0 MB with ZIP (LA, LC;
/// 19 MB for PC); a 512 x 512 retinal image 3.15 MB and 0.1-0.4 MB. Fine noise compresses little
/// with ZIP (22 % with PIZ, at 2-3 s per 2160 x 2160 image); `none` writes fastest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExrCompression {
    /// Uncompressed scan lines (largest, fastest).
    None,
    /// Run-length encoding (lossless; flat areas only).
    Rle,
    /// ZIP (deflate) per scan line (lossless).
    Zips,
    /// ZIP (deflate) per 16 scan lines (lossless; the default).
    #[default]
    Zip,
    /// Wavelet + Huffman (lossless; best on noisy images).
    Piz,
    /// Rounds f32 samples to 24 bits, then ZIP (lossy for f32).
    Pxr24,
}

impl ExrCompression {
    /// The name used on the command line and in headers.
    pub fn name(self) -> &'static str {
        match self {
            ExrCompression::None => "none",
            ExrCompression::Rle => "rle",
            ExrCompression::Zips => "zips",
            ExrCompression::Zip => "zip",
            ExrCompression::Piz => "piz",
            ExrCompression::Pxr24 => "pxr24",
        }
    }

    pub(super) fn to_exr(self) -> Compression {
        match self {
            ExrCompression::None => Compression::Uncompressed,
            ExrCompression::Rle => Compression::RLE,
            ExrCompression::Zips => Compression::ZIP1,
            ExrCompression::Zip => Compression::ZIP16,
            ExrCompression::Piz => Compression::PIZ,
            ExrCompression::Pxr24 => Compression::PXR24,
        }
    }
}

impl std::fmt::Display for ExrCompression {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl ExrCompression {
    /// Every choice, in the order `--help` lists them.
    pub const ALL: [ExrCompression; 6] = [
        ExrCompression::None,
        ExrCompression::Rle,
        ExrCompression::Zips,
        ExrCompression::Zip,
        ExrCompression::Piz,
        ExrCompression::Pxr24,
    ];
}

impl std::str::FromStr for ExrCompression {
    type Err = String;
    /// Parses a name of [`ExrCompression::name`] (case-insensitive).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let lower = s.trim().to_ascii_lowercase();
        ExrCompression::ALL
            .into_iter()
            .find(|c| c.name() == lower)
            .ok_or_else(|| format!("unknown EXR compression `{s}`: expected none, rle, zips, zip, piz or pxr24"))
    }
}

pub(super) fn exr_error(path: &Path, err: exr::error::Error) -> Error {
    match err {
        exr::error::Error::Io(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => Error::io(path, e),
        other => {
            let hint = if other.to_string().contains("missing bytes") { " (truncated file?)" } else { "" };
            Error::parse(path, format!("not a readable OpenEXR file: {other}{hint}"))
        }
    }
}

fn latin1_text(path: &Path, what: &str, s: &str) -> Result<Text> {
    Text::new_or_none(s).ok_or_else(|| {
        Error::invalid(
            path.display().to_string(),
            "attributes",
            format!("{what} `{s}` has characters outside Latin-1, which OpenEXR text cannot hold"),
        )
    })
}

/// Writes `img` (linear RGB, row 0 at top) as an `f32` OpenEXR file with the default
/// compression (ZIP) and the given text attributes: [`write_rgb_with`] for typed attributes and
/// another compression.
pub fn write_rgb(path: &Path, img: &RgbImage, depth: Option<&[f32]>, attributes: &[(&str, String)]) -> Result<()> {
    let typed = Attributes(attributes.iter().map(|(k, v)| (k.to_string(), AttrValue::Text(v.clone()))).collect());
    write_rgb_with(path, img, depth, &typed, ExrCompression::default())
}

/// Writes `img` (linear RGB, row 0 at top) as an `f32` OpenEXR file, with an `f32` `Z` channel
/// when `depth` is given (row-major, one value per pixel), the given typed attributes plus the
/// version attributes in the header, and `compression`. See the module comment for the layout.
///
/// Errors: image or depth size mismatch, empty image, non-Latin-1 or reserved attribute names,
/// and file-system failures (naming `path`).
pub fn write_rgb_with(
    path: &Path,
    img: &RgbImage,
    depth: Option<&[f32]>,
    attributes: &Attributes,
    compression: ExrCompression,
) -> Result<()> {
    if img.pixels.len() != img.width * img.height {
        return Err(Error::invalid(
            path.display().to_string(),
            "pixels",
            format!("image has {} pixels, expected {}x{}", img.pixels.len(), img.width, img.height),
        ));
    }
    write_view(path, RgbView::from(img), depth, attributes, compression)
}

/// [`write_rgb_with`] for an image seen through a [`RgbView`] (for example one display image of
/// an interleaved stack): the pixels are read where they are, never copied into planes first.
pub fn write_view(
    path: &Path,
    img: RgbView<'_>,
    depth: Option<&[f32]>,
    attributes: &Attributes,
    compression: ExrCompression,
) -> Result<()> {
    write_view_by(path, img, depth, attributes, compression, true)
}

/// [`write_view`]; with `own_zip` false, ZIP and ZIPS blocks are compressed by the `exr` crate
/// itself (slower, smaller; the same decoded samples).
pub(super) fn write_view_by(
    path: &Path,
    img: RgbView<'_>,
    depth: Option<&[f32]>,
    attributes: &Attributes,
    compression: ExrCompression,
    own_zip: bool,
) -> Result<()> {
    let source = path.display().to_string();
    let n = img.len();
    if n == 0 {
        return Err(Error::invalid(
            source,
            "image size",
            format!("cannot write an empty {}x{} image", img.width, img.height),
        ));
    }
    if !img.is_complete() {
        return Err(Error::invalid(
            source,
            "pixels",
            format!("image buffer holds fewer than {}x{} pixels", img.width, img.height),
        ));
    }
    if let Some(z) = depth {
        if z.len() != n {
            return Err(Error::invalid(
                source,
                "Z",
                format!("depth plane has {} values, expected {}x{}", z.len(), img.width, img.height),
            ));
        }
    }
    // The same policy as reading: no NaN or infinite radiance ever leaves inimtrace.
    if let Some(i) = (0..n).find(|&i| img.pixel(i).iter().any(|v| !v.is_finite())) {
        return Err(Error::invalid(
            source,
            format!("pixel (row {}, col {})", i / img.width, i % img.width),
            format!("refusing to write a non-finite value {:?} (this is a bug in the renderer)", img.pixel(i)),
        ));
    }

    let layer_attributes = header_attributes(path, attributes)?;

    let encoding =
        Encoding { compression: compression.to_exr(), blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let size = Vec2(img.width, img.height);
    let width = img.width;
    // ZIP and ZIPS blocks are compressed by `exr_zip` (a faster deflate) unless `own_zip` is
    // false; the header is the one the crate makes for the same image either way.
    let zip = (own_zip && matches!(compression, ExrCompression::Zip | ExrCompression::Zips)).then_some((img, depth));
    // The pixels are read from `img` (and `depth`) block by block as the file is compressed:
    // no copy of the image is made. The crate sorts the channels by name (B, G, R, Z).
    match depth {
        Some(z) => {
            let channels = SpecificChannels::build()
                .with_channel::<f32>("R")
                .with_channel::<f32>("G")
                .with_channel::<f32>("B")
                .with_channel::<f32>("Z")
                .with_pixel_fn(|p: Vec2<usize>| {
                    let i = p.y() * width + p.x();
                    let [r, g, b] = img.pixel(i);
                    (r, g, b, z[i])
                });
            finish(path, &Image::from_layer(Layer::new(size, layer_attributes, encoding, channels)), zip)
        }
        None => {
            let channels = SpecificChannels::build()
                .with_channel::<f32>("R")
                .with_channel::<f32>("G")
                .with_channel::<f32>("B")
                .with_pixel_fn(|p: Vec2<usize>| {
                    let [r, g, b] = img.pixel(p.y() * width + p.x());
                    (r, g, b)
                });
            finish(path, &Image::from_layer(Layer::new(size, layer_attributes, encoding, channels)), zip)
        }
    }
}

/// The header attributes of a written file: the version attributes, then `attributes` (typed,
/// Latin-1, no reserved names), and the standard `software` attribute.
pub(super) fn header_attributes(path: &Path, attributes: &Attributes) -> Result<LayerAttributes> {
    let source = path.display().to_string();
    let mut layer_attributes = LayerAttributes::default();
    let mut other = HashMap::new();
    let version = [
        ("inimtrace:version".to_string(), AttrValue::from(crate::version::VERSION)),
        ("inimtrace:git_revision".to_string(), AttrValue::from(crate::version::GIT_REVISION)),
    ];
    for (name, value) in version.iter().chain(&attributes.0) {
        if name.is_empty() || standard_names::ALL.contains(&name.as_bytes()) {
            return Err(Error::invalid(
                source,
                "attributes",
                format!("`{name}` is not allowed as a custom attribute name (empty or reserved by OpenEXR)"),
            ));
        }
        let key = latin1_text(path, "name", name)?;
        if let AttrValue::F64(v) = value {
            // A `float` (read as a number by every OpenEXR reader, the classic Python API
            // included) and its exact value as text (module documentation).
            let exact = latin1_text(path, "name", &format!("{name}{EXACT_SUFFIX}"))?;
            other.insert(key, AttributeValue::F32(*v as f32));
            other.insert(exact, AttributeValue::Text(latin1_text(path, "value", &format!("{v:?}"))?));
            continue;
        }
        let val = value.to_exr().ok_or_else(|| {
            Error::invalid(
                path.display().to_string(),
                "attributes",
                format!("value of `{name}` `{value}` has characters outside Latin-1, which OpenEXR text cannot hold"),
            )
        })?;
        other.insert(key, val);
    }
    layer_attributes.other = other;
    layer_attributes.software_name = Text::new_or_none(crate::version::software());
    Ok(layer_attributes)
}

/// Writes `image` to `path`: by the `exr` crate, or with the crate's header and the blocks
/// compressed by [`super::exr_zip`] from `zip`'s pixels and depth (the same as `image`'s).
fn finish<'i, L: WritableLayers<'i>>(
    path: &Path,
    image: &'i Image<L>,
    zip: Option<(RgbView<'_>, Option<&[f32]>)>,
) -> Result<()> {
    let writer = image.write();
    match zip {
        Some((img, depth)) => super::exr_zip::write(path, writer.infer_meta_data(), img, depth),
        None => writer.to_file(path).map_err(|e| exr_error(path, e)),
    }
}

/// A regular, non-empty file; returns its size.
fn check_readable_file(path: &Path) -> Result<u64> {
    let size = crate::io::input::check_regular(path)?;
    if size == 0 {
        return Err(Error::parse(path, "file is empty, not an OpenEXR file"));
    }
    Ok(size)
}

/// Reads the headers alone and refuses a file whose data windows would need more memory to
/// decode than the memory limit ([`crate::budget::memory_limit`]), or whose uncompressed
/// pixels cannot fit in the file: a few bytes of header must not make the reader allocate.
fn check_claimed_size(path: &Path, file_size: u64) -> Result<()> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
    let limit = crate::budget::memory_limit();
    // Every part is decoded: their sizes are summed, not checked one by one.
    let mut all_parts = 0u64;
    for header in &meta.headers {
        let (w, h) = (header.layer_size.0 as u64, header.layer_size.1 as u64);
        let pixels = w.saturating_mul(h);
        let channels = header.channels.list.len() as u64;
        // Decoded samples are f32 (4 bytes each); our image and depth add 16 bytes per pixel.
        let decoded = pixels.saturating_mul(channels.saturating_mul(4).saturating_add(16));
        all_parts = all_parts.saturating_add(decoded);
        if decoded > limit {
            return Err(Error::parse(
                path,
                format!(
                    "header claims a {w} x {h} pixel data window with {}, which would need {} to \
                     decode, more than the memory limit of {} (--max-memory)",
                    crate::count::count(channels, "channel"),
                    crate::budget::Bytes(decoded),
                    crate::budget::Bytes(limit)
                ),
            ));
        }
        let stored: u64 = header.channels.list.iter().map(|c| c.sample_type.bytes_per_sample() as u64).sum();
        if header.compression == Compression::Uncompressed && pixels.saturating_mul(stored) > file_size {
            return Err(Error::parse(
                path,
                format!(
                    "header claims {w} x {h} uncompressed pixels ({} of samples) but the file has only {} \
                     (truncated file?)",
                    crate::budget::Bytes(pixels.saturating_mul(stored)),
                    crate::budget::Bytes(file_size)
                ),
            ));
        }
    }
    if all_parts > limit {
        return Err(Error::parse(
            path,
            format!(
                "its {} parts would need {} to decode together, more than the memory limit of {} (--max-memory)",
                meta.headers.len(),
                crate::budget::Bytes(all_parts),
                crate::budget::Bytes(limit)
            ),
        ));
    }
    Ok(())
}

/// Reads the `R`, `G`, `B` channels of an OpenEXR file as a linear [`RgbImage`] (row 0 at top).
/// See the module comment for accepted files and the input policy (finite, non-negative).
pub fn read_rgb(path: &Path) -> Result<RgbImage> {
    read_rgb_depth(path).map(|(img, _)| img)
}

/// Like [`read_rgb`], and also the `Z` channel of the same layer when there is one (row-major,
/// one value per pixel, as written by [`write_rgb`]). `Z` samples may be `+inf` (no hit) but
/// not `NaN` or negative; such a sample is an error naming the file, pixel and channel.
pub fn read_rgb_depth(path: &Path) -> Result<(RgbImage, Option<Vec<f32>>)> {
    read_input(path, None).map(|input| (input.image, input.depth))
}

/// [`read_rgb_depth`] of part `part` (by name) of a multipart file, or of the only part with
/// R, G and B; the returned note says which part was read when the file had several and none
/// was named. See [`super::exr_read`] for the part choice and the checks of windows, channel
/// types and blocks, and the module comment for the input policy.
pub fn read_input(path: &Path, part: Option<&str>) -> Result<ExrInput> {
    let size = check_readable_file(path)?;
    check_claimed_size(path, size)?;
    let ExrInput { image: img, depth, note } = super::exr_read::read(path, part)?;
    let width = img.width;
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        for (i, px) in img.pixels.iter().enumerate() {
            let v = px[c];
            if let Some(kind) = crate::raster::bad_sample(v) {
                return Err(Error::parse(
                    path,
                    format!(
                        "pixel (row {}, col {}) channel {name} is {kind} ({v}); linear RGB samples must be finite and non-negative",
                        i / width,
                        i % width
                    ),
                ));
            }
        }
    }
    if let Some(z) = &depth {
        if let Some(i) = z.iter().position(|v| v.is_nan() || *v < 0.0) {
            return Err(Error::parse(
                path,
                format!(
                    "pixel (row {}, col {}) channel Z is {}; depth must be non-negative (+inf for no hit)",
                    i / width,
                    i % width,
                    z[i]
                ),
            ));
        }
    }
    Ok(ExrInput { image: img, depth, note })
}

/// The attributes in the headers of an OpenEXR file as text, `(name, value)` pairs sorted by
/// name: the custom ones written by [`write_rgb_with`] (numbers printed as Rust prints them,
/// `300`, `2.5925`) and the standard text attributes `owner`, `comments`, `capDate` and
/// `software` when present. Errors name the file.
pub fn read_attributes(path: &Path) -> Result<Vec<(String, String)>> {
    Ok(read_typed_attributes(path)?.into_iter().map(|(k, v)| (k, v.to_string())).collect())
}

/// Like [`read_attributes`], keeping each value's type (`string`, `double`, `float`, `int`;
/// other OpenEXR attribute types are left out).
pub fn read_typed_attributes(path: &Path) -> Result<Vec<(String, AttrValue)>> {
    check_readable_file(path)?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
    let mut out = Vec::new();
    for header in &meta.headers {
        let own = &header.own_attributes;
        for (name, value) in [
            ("owner", &own.owner),
            ("comments", &own.comments),
            ("capDate", &own.capture_date),
            ("software", &own.software_name),
        ] {
            if let Some(v) = value {
                out.push((name.to_string(), AttrValue::Text(v.to_string())));
            }
        }
        for map in [&own.other, &header.shared_attributes.other] {
            for (name, value) in map {
                if let Some(v) = AttrValue::from_exr(value) {
                    out.push((name.to_string(), v));
                }
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out.dedup();
    Ok(merge_exact(out))
}

/// A `double` as this module writes it: the attribute `NAME` as a `float` and `NAME` followed by
/// this suffix as a `string` holding the exact value (Rust's shortest round-trip form, which
/// Python's `float()` reads to the same bits).
pub const EXACT_SUFFIX: &str = ".exact";

/// `NAME` (`float`) with `NAME.exact` (`string`) as the one `double` they encode; `NAME.exact`
/// is dropped. Any other attribute, an old file's `double` included, is kept as it is.
fn merge_exact(attrs: Vec<(String, AttrValue)>) -> Vec<(String, AttrValue)> {
    let exact = |name: &str| {
        attrs.iter().find_map(|(n, v)| match v {
            AttrValue::Text(s) if n.strip_suffix(EXACT_SUFFIX) == Some(name) => s.parse::<f64>().ok(),
            _ => None,
        })
    };
    let merged: Vec<(String, AttrValue)> = attrs
        .iter()
        .map(|(n, v)| match (v, exact(n)) {
            (AttrValue::F32(f), Some(x)) if x as f32 == *f || (x.is_nan() && f.is_nan()) => {
                (n.clone(), AttrValue::F64(x))
            }
            _ => (n.clone(), v.clone()),
        })
        .collect();
    merged
        .iter()
        .filter(|(n, _)| {
            !n.strip_suffix(EXACT_SUFFIX)
                .is_some_and(|base| merged.iter().any(|(m, v)| m == base && matches!(v, AttrValue::F64(_))))
        })
        .cloned()
        .collect()
}

/// The compression of the first header of an OpenEXR file (`None` for one this crate does not
/// write, e.g. DWAA). Errors name the file.
pub fn read_compression(path: &Path) -> Result<Option<ExrCompression>> {
    check_readable_file(path)?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
    let c = meta.headers.first().map(|h| h.compression);
    Ok(ExrCompression::ALL.into_iter().find(|x| Some(x.to_exr()) == c))
}
