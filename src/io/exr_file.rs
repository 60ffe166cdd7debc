//! An OpenEXR input file read once, through the input gate ([`super::input`]): its bytes are read
//! whole by the handle the gate checked (a regular file outside `/proc` and `/sys`, within the
//! memory budget), and every header, part and attribute then comes from those bytes, never from
//! the path again, so a file swapped after the check is not read and the provenance of a run
//! (the gate's log, [`super::input_log`]) records the SHA-256 of exactly the image it used.
//!
//! [`ExrFile::input`] applies the strict reader (`super::exr_read`) and the input policy of
//! [`super::exr`] (finite, non-negative radiance; depth non-negative or `+inf`) after refusing
//! headers that claim more pixels than the memory limit or than the file holds.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use exr::meta::MetaData;
use exr::prelude::Compression;

use super::exr::{exr_error, AttrValue, ExrCompression, EXACT_SUFFIX};
use super::exr_read::ExrInput;
use crate::error::{Error, Result};

/// An OpenEXR file's bytes, read through the input gate (see the module comment).
#[derive(Clone, Debug)]
pub struct ExrFile {
    path: PathBuf,
    bytes: Vec<u8>,
}

impl ExrFile {
    /// Reads `path` through the input gate: a regular, non-empty file within the memory budget.
    pub fn open(path: &Path) -> Result<Self> {
        let bytes = super::input::read_regular(path)?;
        if bytes.is_empty() {
            return Err(Error::parse(path, "file is empty, not an OpenEXR file"));
        }
        Ok(Self { path: path.to_path_buf(), bytes })
    }

    /// The path it was read from (for messages).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Its headers, read from its bytes.
    pub fn meta(&self) -> Result<MetaData> {
        MetaData::read_from_buffered(Cursor::new(&self.bytes[..]), false).map_err(|e| exr_error(&self.path, e))
    }

    /// Part `part` (by name), or the only part with R, G and B (see `super::exr_read`), with
    /// the input policy applied.
    pub fn input(&self, part: Option<&str>) -> Result<ExrInput> {
        let path = &self.path;
        self.check_claimed_size()?;
        let ExrInput { image: img, depth, note } = super::exr_read::read(path, &self.bytes, part)?;
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

    /// Refuses headers whose data windows would need more memory to decode than the memory
    /// limit ([`crate::budget::memory_limit`]), or whose uncompressed pixels cannot fit in the
    /// file: a few bytes of header must not make the reader allocate.
    fn check_claimed_size(&self) -> Result<()> {
        let (path, file_size) = (&self.path, self.bytes.len() as u64);
        let meta = self.meta()?;
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

    /// The attributes in its headers as text, `(name, value)` pairs sorted by name: the custom
    /// ones written by [`super::exr::write_rgb_with`] (numbers printed as Rust prints them, `300`,
    /// `2.5925`) and the standard text attributes `owner`, `comments`, `capDate` and `software`
    /// when present.
    pub fn attributes(&self) -> Result<Vec<(String, String)>> {
        Ok(self.typed_attributes()?.into_iter().map(|(k, v)| (k, v.to_string())).collect())
    }

    /// Like [`ExrFile::attributes`], keeping each value's type (`string`, `double`, `float`,
    /// `int`; other OpenEXR attribute types are left out).
    pub fn typed_attributes(&self) -> Result<Vec<(String, AttrValue)>> {
        let meta = self.meta()?;
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

    /// The compression of its first header (`None` for one this crate does not write).
    pub fn compression(&self) -> Result<Option<ExrCompression>> {
        let c = self.meta()?.headers.first().map(|h| h.compression);
        Ok(ExrCompression::ALL.into_iter().find(|x| Some(x.to_exr()) == c))
    }

    /// The names of its parts, in order (`None` for a part without one).
    pub fn part_names(&self) -> Result<Vec<Option<String>>> {
        Ok(self.meta()?.headers.iter().map(|h| h.own_attributes.layer_name.as_ref().map(|t| t.to_string())).collect())
    }
}

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
