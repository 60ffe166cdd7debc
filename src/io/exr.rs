//! OpenEXR files of linear RGB images: the rendered display images (elemental-image arrays) and
//! the simulated retinal images that the paper compares (its Figures 3–4 and Table 1 are made
//! from them). Written and read with the `exr` crate.
//!
//! **Writing** ([`write_rgb`]): one layer with `f32` channels `R`, `G`, `B` and, when a depth
//! plane is given, `Z` (the hit distance per pixel); scan-line blocks in increasing-Y line
//! order, so row 0 of the [`RgbImage`] is the top row of the file (OpenEXR's y axis points
//! down). Compression is [`COMPRESSION`]. Custom text attributes (for example
//! `"inimtrace:method" = "LC"`) go into the header; names and values must be Latin-1 and names
//! may not be OpenEXR's reserved attribute names. Sample values are written as given.
//!
//! **Reading** ([`read_rgb`], [`read_rgb_depth`]): the first layer that has `R`, `G` and `B`
//! channels; each may be stored as `f16`, `f32` or `u32` and is converted to `f32`. `Z` is
//! returned by [`read_rgb_depth`] (`+inf` allowed: no hit); other channels are ignored.
//!
//! **Input policy:** every `R`, `G`, `B` sample read must be finite and non-negative (a linear
//! radiance). A `NaN`, infinite or negative sample is not clamped or repaired: reading fails
//! with an error that names the file, the pixel `(row, col)` (row 0 at the top) and the channel.
//! A missing file, a directory, an empty, truncated or non-EXR file, a file without `R`/`G`/`B`
//! channels, or subsampled channels also give an error naming the file, never a panic.

use std::collections::HashMap;
use std::path::Path;

use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, Text};
use exr::meta::header::{standard_names, LayerAttributes};
use exr::prelude::{read, Blocks, Compression, LineOrder, ReadChannels, ReadLayers, SmallVec, WritableImage};

use crate::error::{Error, Result};
use crate::raster::RgbImage;

/// Compression of written files: uncompressed scan lines. Measured on a 2160×2160 RGB `f32`
/// image with fine noise (release build, 2 busy cores): uncompressed 56 MB in 0.11–0.2 s;
/// RLE saved nothing at 0.4–1.2 s; ZIP1/ZIP16 saved 2–6 % at 2–3.5 s; PIZ saved 22 % at
/// ~2.3 s. Lossless codecs gain little on noisy `f32` radiance, so speed wins.
pub const COMPRESSION: Compression = Compression::Uncompressed;

fn encoding() -> Encoding {
    Encoding { compression: COMPRESSION, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing }
}

fn exr_error(path: &Path, err: exr::error::Error) -> Error {
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

/// Writes `img` (linear RGB, row 0 at top) as an `f32` OpenEXR file, with an `f32` `Z` channel
/// when `depth` is given (row-major, one value per pixel) and the given text attributes in the
/// header. See the module comment for the layout.
///
/// Errors: image or depth size mismatch, empty image, non-Latin-1 or reserved attribute names,
/// and file-system failures (naming `path`).
pub fn write_rgb(path: &Path, img: &RgbImage, depth: Option<&[f32]>, attributes: &[(&str, String)]) -> Result<()> {
    let source = path.display().to_string();
    let n = img.width * img.height;
    if n == 0 {
        return Err(Error::invalid(
            source,
            "image size",
            format!("cannot write an empty {}x{} image", img.width, img.height),
        ));
    }
    if img.pixels.len() != n {
        return Err(Error::invalid(
            source,
            "pixels",
            format!("image has {} pixels, expected {}x{}", img.pixels.len(), img.width, img.height),
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
    if let Some(i) = img.pixels.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(Error::invalid(
            source,
            format!("pixel (row {}, col {})", i / img.width, i % img.width),
            format!("refusing to write a non-finite value {:?} (this is a bug in the renderer)", img.pixels[i]),
        ));
    }

    let mut layer_attributes = LayerAttributes::default();
    let mut other: HashMap<Text, AttributeValue> = HashMap::new();
    for (name, value) in attributes {
        if name.is_empty() || standard_names::ALL.contains(&name.as_bytes()) {
            return Err(Error::invalid(
                source,
                "attributes",
                format!("`{name}` is not allowed as a custom attribute name (empty or reserved by OpenEXR)"),
            ));
        }
        let key = latin1_text(path, "name", name)?;
        let val = latin1_text(path, &format!("value of `{name}`"), value)?;
        other.insert(key, AttributeValue::Text(val));
    }
    layer_attributes.other = other;

    let plane = |c: usize| FlatSamples::F32(img.pixels.iter().map(|p| p[c]).collect());
    let mut channels =
        vec![AnyChannel::new("R", plane(0)), AnyChannel::new("G", plane(1)), AnyChannel::new("B", plane(2))];
    if let Some(z) = depth {
        channels.push(AnyChannel::new("Z", FlatSamples::F32(z.to_vec())));
    }
    let layer = Layer::new(
        Vec2(img.width, img.height),
        layer_attributes,
        encoding(),
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    Image::from_layer(layer).write().to_file(path).map_err(|e| exr_error(path, e))
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
    for header in &meta.headers {
        let (w, h) = (header.layer_size.0 as u64, header.layer_size.1 as u64);
        let pixels = w.saturating_mul(h);
        let channels = header.channels.list.len() as u64;
        // Decoded samples are f32 (4 bytes each); our image and depth add 16 bytes per pixel.
        let decoded = pixels.saturating_mul(channels.saturating_mul(4).saturating_add(16));
        if decoded > limit {
            return Err(Error::parse(
                path,
                format!(
                    "header claims a {w} x {h} pixel data window with {channels} channel(s), which would need {} to \
                     decode, more than the memory limit of {} (--max-memory)",
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
    let size = check_readable_file(path)?;
    check_claimed_size(path, size)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| exr_error(path, e))?;

    let find = |layer: &Layer<AnyChannels<FlatSamples>>, name: &str| {
        layer.channel_data.list.iter().find(|c| c.name == *name).map(|c| c.sample_data.clone())
    };
    let layer =
        image.layer_data.iter().find(|l| ["R", "G", "B"].iter().all(|n| find(l, n).is_some())).ok_or_else(|| {
            let names: Vec<String> =
                image.layer_data.iter().flat_map(|l| l.channel_data.list.iter().map(|c| c.name.to_string())).collect();
            Error::parse(path, format!("no layer with R, G and B channels (channels found: {})", names.join(", ")))
        })?;
    let (width, height) = (layer.size.0, layer.size.1);
    let n = width * height;
    if n == 0 {
        return Err(Error::parse(path, "image has no pixels"));
    }
    let mut img = RgbImage::new(width, height);
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let samples = find(layer, name).expect("channel presence checked above");
        if samples.len() != n {
            return Err(Error::parse(
                path,
                format!(
                    "channel {name} has {} samples for {width}x{height} pixels (subsampled channels are not supported)",
                    samples.len()
                ),
            ));
        }
        let values: Vec<f32> = match samples {
            FlatSamples::F16(v) => v.into_iter().map(|h| h.to_f32()).collect(),
            FlatSamples::F32(v) => v,
            FlatSamples::U32(v) => v.into_iter().map(|u| u as f32).collect(),
        };
        for (i, (px, v)) in img.pixels.iter_mut().zip(values).enumerate() {
            if !v.is_finite() || v < 0.0 {
                let kind = if v.is_nan() {
                    "NaN"
                } else if v.is_infinite() {
                    "infinite"
                } else {
                    "negative"
                };
                return Err(Error::parse(
                    path,
                    format!(
                        "pixel (row {}, col {}) channel {name} is {kind} ({v}); linear RGB samples must be finite and non-negative",
                        i / width,
                        i % width
                    ),
                ));
            }
            px[c] = v;
        }
    }
    let depth = match find(layer, "Z") {
        None => None,
        Some(samples) => {
            if samples.len() != n {
                return Err(Error::parse(
                    path,
                    format!("channel Z has {} samples for {width}x{height} pixels", samples.len()),
                ));
            }
            let z: Vec<f32> = samples.values_as_f32().collect();
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
            Some(z)
        }
    };
    Ok((img, depth))
}

/// The text attributes in the headers of an OpenEXR file, as `(name, value)` pairs sorted by
/// name: the custom ones written by [`write_rgb`] and the standard text attributes `owner`,
/// `comments`, `capDate` and `software` when present. Errors name the file.
pub fn read_attributes(path: &Path) -> Result<Vec<(String, String)>> {
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
                out.push((name.to_string(), v.to_string()));
            }
        }
        for map in [&own.other, &header.shared_attributes.other] {
            for (name, value) in map {
                if let AttributeValue::Text(t) = value {
                    out.push((name.to_string(), t.to_string()));
                }
            }
        }
    }
    out.sort();
    out.dedup();
    Ok(out)
}
