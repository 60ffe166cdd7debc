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
pub use super::exr_file::ExrFile;
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
    // The same policy as reading: no NaN or infinite radiance ever leaves inimtrace. The last
    // guard: the causes are refused where they arise; this names the inputs behind the image.
    if let Some(i) = (0..n).find(|&i| img.pixel(i).iter().any(|v| !v.is_finite())) {
        return Err(Error::invalid(
            source,
            "pixels",
            format!(
                "refusing to write the non-finite value {:?} at pixel (row {}, col {}); the image comes from {}: \
                 check those settings",
                img.pixel(i),
                i / img.width,
                i % img.width,
                inputs_of(attributes)
            ),
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

/// The inputs an image's attributes name (experiment, scene, eye case, method, eye model,
/// Stiles-Crawford, spectrum, source image), for an error about its values.
fn inputs_of(attributes: &Attributes) -> String {
    const NAMED: [(&str, &str); 9] = [
        ("inimtrace:experiment", "experiment"),
        ("inimtrace:experiment_path", "experiment file"),
        ("inimtrace:scene", "scene"),
        ("inimtrace:eye_case", "eye case"),
        ("inimtrace:method", "method"),
        ("inimtrace:eye_model", "eye model"),
        ("inimtrace:stiles_crawford_rho", "Stiles-Crawford rho"),
        ("inimtrace:spectrum", "spectrum"),
        ("inimtrace:source", "input image"),
    ];
    let named: Vec<String> = NAMED
        .iter()
        .filter_map(|(key, what)| attributes.0.iter().find(|(k, _)| k == key).map(|(_, v)| format!("{what} `{v}`")))
        .collect();
    if named.is_empty() {
        "settings its header does not name".into()
    } else {
        named.join(", ")
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
/// was named. The file is read once through the input gate ([`ExrFile`]).
pub fn read_input(path: &Path, part: Option<&str>) -> Result<ExrInput> {
    ExrFile::open(path)?.input(part)
}

/// The attributes in the headers of an OpenEXR file as text, `(name, value)` pairs sorted by
/// name (see [`ExrFile::attributes`]). Errors name the file.
pub fn read_attributes(path: &Path) -> Result<Vec<(String, String)>> {
    ExrFile::open(path)?.attributes()
}

/// Like [`read_attributes`], keeping each value's type ([`ExrFile::typed_attributes`]).
pub fn read_typed_attributes(path: &Path) -> Result<Vec<(String, AttrValue)>> {
    ExrFile::open(path)?.typed_attributes()
}

/// A `double` as this module writes it: the attribute `NAME` as a `float` and `NAME` followed by
/// this suffix as a `string` holding the exact value (Rust's shortest round-trip form, which
/// Python's `float()` reads to the same bits).
pub const EXACT_SUFFIX: &str = ".exact";

/// The compression of the first header of an OpenEXR file (`None` for one this crate does not
/// write, e.g. DWAA). Errors name the file.
pub fn read_compression(path: &Path) -> Result<Option<ExrCompression>> {
    ExrFile::open(path)?.compression()
}
