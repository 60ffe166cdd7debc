//! Replicate sets: the R independent replicate images behind one converged retinal image (the
//! converged estimator of Table 1, `src/measure/`), as one multipart OpenEXR file with a part
//! per replicate, named `replicate 0` ... `replicate R-1`, each with `f32` channels `R`, `G`,
//! `B` (the replicate's per-pixel mean, exactly as the estimator holds it). `assess
//! --keep-replicates` writes them; `compare` and `inimtrace.compare` read two of them and give
//! the table's de-biased scores and intervals (`src/measure/stats.rs`, `src/measure/ssim.rs`).
//!
//! Every part carries the image's attributes plus `inimtrace:replicate` (its index) and
//! `inimtrace:samples_per_replicate`. Reading goes through the strict reader (`exr_read.rs`),
//! one part at a time by name.

use std::path::Path;

use exr::image::{Encoding, Image, Layer, SpecificChannels};
use exr::math::Vec2;
use exr::meta::attribute::IntegerBounds;
use exr::meta::attribute::Text;
use exr::meta::header::ImageAttributes;
use exr::prelude::{Blocks, LineOrder, WritableImage};

use super::exr::{exr_error, header_attributes, AttrValue, Attributes, ExrCompression, ExrFile};
use crate::error::{Error, Result};
use crate::measure::estimator::Replicates;
use crate::raster::RgbImage;

/// The name of replicate `r`'s part.
pub fn part_name(r: usize) -> String {
    format!("replicate {r}")
}

/// Writes image `k` of `reps` (0: the ground truth, then one per method) as a replicate set.
pub fn write(
    path: &Path,
    reps: &Replicates,
    k: usize,
    attributes: &Attributes,
    compression: ExrCompression,
) -> Result<()> {
    let n = reps.resolution();
    let encoding =
        Encoding { compression: compression.to_exr(), blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let layers = (0..reps.replicates())
        .map(|r| {
            let mut a = attributes.clone();
            a.0.push(("inimtrace:replicate".into(), AttrValue::count(r)));
            a.0.push((
                "inimtrace:samples_per_replicate".into(),
                AttrValue::count(reps.samples_per_replicate() as usize),
            ));
            let mut header = header_attributes(path, &a)?;
            header.layer_name = Text::new_or_none(part_name(r));
            let planes = [reps.plane(r, k, 0), reps.plane(r, k, 1), reps.plane(r, k, 2)];
            if let Some(i) = (0..n * n).find(|&i| planes.iter().any(|p| !p[i].is_finite())) {
                return Err(Error::invalid(
                    path.display().to_string(),
                    format!("replicate {r}, pixel (row {}, col {})", i / n, i % n),
                    "refusing to write a non-finite value (this is a bug in the estimator)",
                ));
            }
            let channels = SpecificChannels::build()
                .with_channel::<f32>("R")
                .with_channel::<f32>("G")
                .with_channel::<f32>("B")
                .with_pixel_fn(move |p: Vec2<usize>| {
                    let i = p.y() * n + p.x();
                    (planes[0][i], planes[1][i], planes[2][i])
                });
            Ok(Layer::new(Vec2(n, n), header, encoding, channels))
        })
        .collect::<Result<Vec<_>>>()?;
    let bounds = IntegerBounds::from_dimensions(Vec2(n, n));
    Image::from_layers(ImageAttributes::new(bounds), layers).write().to_file(path).map_err(|e| exr_error(path, e))
}

/// How many replicate parts `path` has when it is a replicate set (at least two parts, named
/// `replicate 0` ... in order), else `None` (a plain image). Reads the file through the input
/// gate ([`ExrFile`]).
pub fn count(path: &Path) -> Result<Option<usize>> {
    count_of(&ExrFile::open(path)?)
}

/// [`count`] of a file already read.
pub fn count_of(file: &ExrFile) -> Result<Option<usize>> {
    let names = file.part_names()?;
    let set = names.len() >= 2 && names.iter().enumerate().all(|(r, n)| n.as_deref() == Some(part_name(r).as_str()));
    Ok(set.then_some(names.len()))
}

/// Reads the `replicates` replicate images of a set (see [`count`]), each by the strict reader
/// and the input policy of [`ExrFile::input`], from one read of the file.
pub fn read(path: &Path, replicates: usize) -> Result<Vec<RgbImage>> {
    read_of(&ExrFile::open(path)?, replicates)
}

/// [`read`] of a file already read.
pub fn read_of(file: &ExrFile, replicates: usize) -> Result<Vec<RgbImage>> {
    (0..replicates).map(|r| file.input(Some(&part_name(r))).map(|input| input.image)).collect()
}

/// The replicates of two sets as the estimator's storage: image 0 from `a`, image 1 from `b`
/// (replicate `r` of each paired), `samples` samples per pixel in each replicate. The sets
/// (each named for errors: a file or an argument) must have the same number of replicates, at
/// least 2, and square images of one size.
pub fn pair(a: (&str, &[RgbImage]), b: (&str, &[RgbImage]), samples: u32) -> Result<Replicates> {
    let (ra, rb) = (a.1.len(), b.1.len());
    if ra != rb {
        return Err(Error::invalid(
            b.0,
            "replicates",
            format!("has {rb} replicates, {} has {ra}: replicate sets to compare must have the same number", a.0),
        ));
    }
    if ra < 2 {
        return Err(Error::invalid(a.0, "replicates", "a replicate set needs at least 2 replicates"));
    }
    let n = a.1[0].width;
    for (name, set) in [a, b] {
        if let Some(img) = set.iter().find(|i| i.width != n || i.height != n) {
            return Err(Error::invalid(
                name,
                "size",
                format!(
                    "is {} x {}; replicate sets compare square images of one size ({n} x {n})",
                    img.width, img.height
                ),
            ));
        }
    }
    Ok(Replicates::from_fn(
        n,
        ra,
        2,
        samples,
        |p, r, k, c| if k == 0 { a.1[r].pixels[p][c] } else { b.1[r].pixels[p][c] },
    ))
}
