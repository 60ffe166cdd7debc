//! Reading an OpenEXR input image (a display image to simulate, or either image to compare:
//! the paper's Sec. 4 compares linear RGB images) strictly: one part, checked before and while
//! its blocks are decoded, so that a file is either read as its writer meant it or refused.
//!
//! - **The part.** A single-part file is read as it is. In a multipart file, `--part NAME`
//!   chooses a part by its `name` attribute; without it, the only part with `R`, `G` and `B`
//!   channels is read and a note says which (several such parts need `--part`). Only the chosen
//!   part's blocks are decoded.
//! - **The windows.** The part's data window must be its display window: pixels outside the
//!   data window have no defined value, so a shifted or cropped data window is refused rather
//!   than read as if it were the whole image.
//! - **The channels.** `R`, `G`, `B` (and `Z`, when present) must be `HALF` or `FLOAT` and not
//!   subsampled; `UINT` samples are integers, not radiance. Other channels are skipped.
//! - **The blocks.** Every block of the part's first resolution level must be present exactly
//!   once (a corrupt offset table or block coordinate would otherwise leave rows black or read
//!   one block twice) and decode to exactly its size. ZIP and ZIPS blocks are inflated by the
//!   `exr` crate with `zune-inflate`, which verifies each zlib stream's Adler-32 checksum (RFC
//!   1950), so a flipped byte in compressed data is an error too.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use exr::block::reader::ChunksReader;
use exr::block::UncompressedBlock;
use exr::math::Vec2;
use exr::meta::attribute::SampleType;
use exr::meta::header::Header;
use exr::prelude::f16;

use crate::error::{Error, Result};
use crate::raster::RgbImage;

/// An image read from an OpenEXR file.
#[derive(Clone, Debug)]
pub struct ExrInput {
    /// The `R`, `G`, `B` samples, row 0 at the top.
    pub image: RgbImage,
    /// The `Z` samples, row-major, when the part has a `Z` channel.
    pub depth: Option<Vec<f32>>,
    /// A note for the terminal when the file had several parts and one was chosen without
    /// `--part`.
    pub note: Option<String>,
}

/// The name of a part (`#INDEX` when it has none).
fn part_name(header: &Header, index: usize) -> String {
    header.own_attributes.layer_name.as_ref().map(|n| n.to_string()).unwrap_or_else(|| format!("#{index}"))
}

fn channel(header: &Header, name: &str) -> Option<usize> {
    header.channels.list.iter().position(|c| c.name == *name)
}

fn has_rgb(header: &Header) -> bool {
    !header.deep && ["R", "G", "B"].iter().all(|n| channel(header, n).is_some())
}

/// The part to read: `part` by name, else the only one, else the only one with R, G and B;
/// with the note to print when a part was chosen among several without being named.
fn choose_part(path: &Path, headers: &[Header], part: Option<&str>) -> Result<(usize, Option<String>)> {
    let names: Vec<String> = headers.iter().enumerate().map(|(i, h)| part_name(h, i)).collect();
    let list =
        |ix: &mut dyn Iterator<Item = usize>| ix.map(|i| format!("`{}`", names[i])).collect::<Vec<_>>().join(", ");
    if let Some(want) = part {
        let i = names.iter().position(|n| n == want).ok_or_else(|| {
            Error::invalid(
                "command line",
                "--part",
                format!("{} has no part named `{want}` (its parts: {})", path.display(), list(&mut (0..headers.len()))),
            )
        })?;
        if !has_rgb(&headers[i]) {
            return Err(no_rgb(path, &headers[i..=i]));
        }
        return Ok((i, None));
    }
    let rgb: Vec<usize> = (0..headers.len()).filter(|&i| has_rgb(&headers[i])).collect();
    match rgb[..] {
        [] => Err(no_rgb(path, headers)),
        [i] if headers.len() == 1 => Ok((i, None)),
        [i] => Ok((
            i,
            Some(format!(
                "note: {} has {} parts; reading `{}`, its only part with R, G and B (--part NAME chooses another)",
                path.display(),
                headers.len(),
                names[i]
            )),
        )),
        _ => Err(Error::invalid(
            path.display().to_string(),
            "parts",
            format!(
                "{} of its {} parts have R, G and B channels ({}): choose one with --part NAME",
                rgb.len(),
                headers.len(),
                list(&mut rgb.iter().copied())
            ),
        )),
    }
}

fn no_rgb(path: &Path, headers: &[Header]) -> Error {
    let names: Vec<String> = headers.iter().flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string())).collect();
    Error::parse(path, format!("no layer with R, G and B channels (channels found: {})", names.join(", ")))
}

/// The header checks: not deep, data window = display window, R/G/B/Z float and unsampled,
/// no subsampled channel (the block layout would differ), at least one pixel.
fn check_header(path: &Path, h: &Header) -> Result<()> {
    let bad = |field: &str, message: String| Err(Error::invalid(path.display().to_string(), field, message));
    if h.deep {
        return bad("parts", "deep data is not supported".into());
    }
    let (pos, size) = (h.own_attributes.layer_position, h.layer_size);
    let display = h.shared_attributes.display_window;
    if pos != display.position || size != display.size {
        let window = |p: Vec2<i32>, s: Vec2<usize>| {
            format!("({}, {})-({}, {})", p.0, p.1, p.0 as i64 + s.0 as i64 - 1, p.1 as i64 + s.1 as i64 - 1)
        };
        return bad(
            "dataWindow",
            format!(
                "the data window {} differs from the display window {}: only images whose data window is the whole \
                 display window are read (pixels outside it would have no value)",
                window(pos, size),
                window(display.position, display.size)
            ),
        );
    }
    for c in &h.channels.list {
        let name = c.name.to_string();
        let ours = matches!(name.as_str(), "R" | "G" | "B" | "Z");
        if c.sampling != Vec2(1, 1) {
            return bad(
                &format!("channel {name}"),
                format!("is subsampled ({} x {}); subsampled channels are not supported", c.sampling.0, c.sampling.1),
            );
        }
        if ours && c.sample_type == SampleType::U32 {
            let what = if name == "Z" { "depth" } else { "linear radiance" };
            return bad(
                &format!("channel {name}"),
                format!("holds unsigned integers (UINT), not {what}: R, G, B and Z must be HALF or FLOAT"),
            );
        }
    }
    if size.area() == 0 {
        return Err(Error::parse(path, "image has no pixels"));
    }
    Ok(())
}

/// Where the samples of one channel go.
#[derive(Clone, Copy)]
enum Target {
    Rgb(usize),
    Depth,
    Skip,
}

/// Reads part `part` (by name; see the module comment for the choice) of the OpenEXR file
/// `bytes` (read from `path` by [`super::exr_file::ExrFile`]; `path` names it in errors): its
/// `R`, `G`, `B` samples and its `Z` samples when present, unchecked for value (the caller
/// applies the input policy).
pub fn read(path: &Path, bytes: &[u8], part: Option<&str>) -> Result<ExrInput> {
    let exr_error = |e: exr::error::Error| super::exr::exr_error(path, e);
    let reader = exr::block::read(Cursor::new(bytes), false).map_err(exr_error)?;
    let (index, note) = choose_part(path, reader.headers(), part)?;
    let header = reader.headers()[index].clone();
    check_header(path, &header)?;
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    let n = width * height;
    let targets: Vec<Target> = header
        .channels
        .list
        .iter()
        .map(|c| match c.name.to_string().as_str() {
            "R" => Target::Rgb(0),
            "G" => Target::Rgb(1),
            "B" => Target::Rgb(2),
            "Z" => Target::Depth,
            _ => Target::Skip,
        })
        .collect();
    let bytes_per_pixel: usize = header.channels.list.iter().map(|c| c.sample_type.bytes_per_sample()).sum();

    // Every block of the first level, by its top-left pixel: (its size, seen yet).
    let mut blocks: HashMap<(usize, usize), (Vec2<usize>, bool)> = HashMap::new();
    for tile in header.blocks_increasing_y_order() {
        if tile.location.level_index != Vec2(0, 0) {
            continue;
        }
        let b = header.get_absolute_block_pixel_coordinates(tile.location).map_err(exr_error)?;
        let at = b.position.to_usize("block position").map_err(exr_error)?;
        blocks.insert((at.0, at.1), (b.size, false));
    }

    let mut image = RgbImage::new(width, height);
    let mut depth = channel(&header, "Z").map(|_| vec![0.0f32; n]);
    let mut line = Vec::<f32>::new();
    let mut half = Vec::<f16>::new();
    let mut problem: Option<String> = None;
    let mut insert = |block: UncompressedBlock| -> std::result::Result<(), String> {
        let at = block.index.pixel_position;
        if block.index.layer != index || block.index.level != Vec2(0, 0) {
            return Err(format!("a block at ({}, {}) belongs to another part or level", at.0, at.1));
        }
        let Some((size, seen)) = blocks.get_mut(&(at.0, at.1)) else {
            return Err(format!("a block starts at ({}, {}), where no block of the image starts", at.0, at.1));
        };
        if *seen {
            return Err(format!("the block at ({}, {}) appears twice", at.0, at.1));
        }
        if *size != block.index.pixel_size || block.data.len() != size.area() * bytes_per_pixel {
            return Err(format!("the block at ({}, {}) does not decode to its size", at.0, at.1));
        }
        *seen = true;
        for l in block.lines(&header.channels) {
            let (x, y, count) = (l.location.position.0, l.location.position.1, l.location.sample_count);
            let target = targets[l.location.channel];
            if matches!(target, Target::Skip) {
                continue;
            }
            line.resize(count, 0.0);
            match header.channels.list[l.location.channel].sample_type {
                SampleType::F32 => l.read_samples_into_slice(&mut line[..]).map_err(|e| e.to_string())?,
                SampleType::F16 => {
                    half.resize(count, f16::ZERO);
                    l.read_samples_into_slice(&mut half[..]).map_err(|e| e.to_string())?;
                    line.iter_mut().zip(&half).for_each(|(v, h)| *v = h.to_f32());
                }
                SampleType::U32 => unreachable!("UINT R, G, B and Z are refused by check_header"),
            }
            let row = y * width + x..y * width + x + count;
            match target {
                Target::Rgb(c) => image.pixels[row].iter_mut().zip(&line).for_each(|(p, &v)| p[c] = v),
                Target::Depth => {
                    if let Some(z) = depth.as_mut() {
                        z[row].copy_from_slice(&line);
                    }
                }
                Target::Skip => {}
            }
        }
        Ok(())
    };
    let chunks = reader
        .filter_chunks(false, |_, tile, block| block.layer == index && tile.level_index == Vec2(0, 0))
        .map_err(exr_error)?;
    let decoded = chunks.decompress_parallel(false, |_, block| {
        insert(block).map_err(|m| {
            problem = Some(m);
            exr::error::Error::Aborted
        })
    });
    if let Some(m) = problem {
        return Err(Error::parse(path, format!("corrupt file: {m}")));
    }
    decoded.map_err(exr_error)?;
    let mut missing: Vec<(usize, usize)> = blocks.iter().filter(|(_, (_, seen))| !seen).map(|(&at, _)| at).collect();
    if !missing.is_empty() {
        missing.sort_by_key(|&(x, y)| (y, x));
        return Err(Error::parse(
            path,
            format!(
                "corrupt file: {} missing, the first at ({}, {}) (a damaged offset table or block header)",
                crate::count::count(missing.len(), "block"),
                missing[0].0,
                missing[0].1
            ),
        ));
    }
    Ok(ExrInput { image, depth, note })
}
