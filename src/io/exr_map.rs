//! Distortion maps as files: the per-pixel values of a perceptual score (ColorVideoVDP's
//! `1 - JOD_pixel / 10`, FLIP's error, `crate::perception`) as a one-channel `f32` OpenEXR file
//! (channel `Y`, row 0 at the top, typed header attributes as every other image) and as a PNG
//! heatmap in the Magma colour map FLIP uses (0 black, 1 light yellow; values clamped).

use std::path::Path;

use exr::prelude::*;

use super::exr::{exr_error, header_attributes, Attributes, ExrCompression};
use crate::error::{Error, Result};

/// Writes `values` (`width * height`, finite) as a one-channel EXR with `attributes`.
pub fn write_map_exr(
    path: &Path,
    width: usize,
    height: usize,
    values: &[f32],
    attributes: &Attributes,
    compression: ExrCompression,
) -> Result<()> {
    check(path, width, height, values)?;
    let layer_attributes = header_attributes(path, attributes)?;
    let encoding =
        Encoding { compression: compression.to_exr(), blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let channels = SpecificChannels::build()
        .with_channel::<f32>("Y")
        .with_pixel_fn(|p: Vec2<usize>| (values[p.y() * width + p.x()],));
    let image = Image::from_layer(Layer::new(Vec2(width, height), layer_attributes, encoding, channels));
    image.write().to_file(path).map_err(|e| exr_error(path, e))
}

/// Writes `values` as a PNG heatmap (Magma; values clamped to `[0, 1]`).
pub fn write_map_png(path: &Path, width: usize, height: usize, values: &[f32]) -> Result<()> {
    check(path, width, height, values)?;
    let rgb: Vec<u8> = values
        .iter()
        .flat_map(|v| flip_rs::MAGMA[(v.clamp(0.0, 1.0) * 255.0 + 0.5) as usize].map(|c| (c * 255.0 + 0.5) as u8))
        .collect();
    super::png::write_rgb8(path, width, height, &rgb)
}

fn check(path: &Path, width: usize, height: usize, values: &[f32]) -> Result<()> {
    if width == 0 || height == 0 || values.len() != width * height {
        return Err(Error::invalid(
            path.display().to_string(),
            "map size",
            format!("{} values do not form a non-empty {width}x{height} map", values.len()),
        ));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            path.display().to_string(),
            format!("pixel (row {}, col {})", i / width, i % width),
            "refusing to write a non-finite map value",
        ));
    }
    Ok(())
}
