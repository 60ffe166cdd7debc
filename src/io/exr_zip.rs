//! ZIP and ZIPS compression of the OpenEXR files that hold the paper's display images and
//! simulated retinal images (Sec. 4, Fig. 2): the pixel blocks are compressed here, with a
//! fast deflate, while the header, the offset table and the attributes are still written by the
//! `exr` crate ([`super::exr`] builds the header and calls [`write`]).
//!
//! A block holds 16 scan lines (ZIP) or one (ZIPS); the last block of an image may hold fewer.
//! Its bytes are laid out as OpenEXR specifies: per scan line, per channel in the header's
//! channel order, the line's samples as little-endian `f32`. ZIP then
//! 1. splits these bytes into those at even positions followed by those at odd positions,
//! 2. replaces every byte but the first by its difference to the byte before it, plus 128
//!    (modulo 256),
//! 3. deflates the result into a zlib stream.
//!
//! A block whose zlib stream would not be smaller than its raw bytes is stored raw (the
//! unsplit little-endian samples): readers recognise it by its size.
//!
//! Blocks are compressed in parallel one batch at a time while the batch before is written, in
//! increasing y, so at most two batches of compressed blocks are held, never the whole image.

use std::cell::RefCell;
use std::io::BufWriter;
use std::ops::Range;
use std::path::Path;

use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
use exr::block::writer::ChunksWriter;
use exr::meta::attribute::SampleType;
use exr::meta::header::Header;
use exr::meta::{BlockDescription, Headers};
use exr::prelude::Compression;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::raster::RgbView;

/// The zlib level: 1 is zlib-rs's fastest. On the paper's 2160 x 2160 display images it
/// deflates a block several times faster than the `exr` crate's level 4, for files about a
/// tenth to a fifth larger.
const ZLIB_LEVEL: i32 = 1;

/// Raw bytes of the blocks compressed in one batch (at least four blocks per thread).
const BATCH_BYTES: usize = 2 << 20;

/// Where the samples of one channel come from.
#[derive(Clone, Copy)]
enum Plane<'a> {
    /// Component `.1` (0 = R, 1 = G, 2 = B) of the view's pixels.
    Rgb(RgbView<'a>, usize),
    /// One value per pixel, row-major.
    Depth(&'a [f32]),
}

/// The blocks of one scan-line layer and where their samples come from.
struct Layout<'a> {
    width: usize,
    height: usize,
    /// Scan lines per block (16 for ZIP, 1 for ZIPS).
    lines: usize,
    /// The channels in the header's order.
    planes: Vec<Plane<'a>>,
    /// The y coordinate of the first scan line (the data window's top).
    top: i32,
}

impl<'a> Layout<'a> {
    /// The layout of `header`'s blocks with samples from `img` and `depth`; an error message
    /// for a header this module does not write (not ZIP/ZIPS scan lines of `f32` R, G, B and Z).
    fn new(header: &Header, img: RgbView<'a>, depth: Option<&'a [f32]>) -> std::result::Result<Self, String> {
        if !matches!(header.compression, Compression::ZIP1 | Compression::ZIP16) {
            return Err(format!("compression {} is not ZIP or ZIPS", header.compression));
        }
        if header.blocks != BlockDescription::ScanLines || header.deep {
            return Err("only flat scan-line images are written here".into());
        }
        let (width, height) = (header.layer_size.0, header.layer_size.1);
        if (width, height) != (img.width, img.height) || width * height > img.len() {
            return Err(format!("header size {width}x{height} differs from the image's"));
        }
        let mut planes = Vec::new();
        for channel in &header.channels.list {
            let name = channel.name.to_string();
            if channel.sample_type != SampleType::F32 || channel.sampling.0 != 1 || channel.sampling.1 != 1 {
                return Err(format!("channel {name} is not an unsampled f32 channel"));
            }
            planes.push(match (name.as_str(), depth) {
                ("R", _) => Plane::Rgb(img, 0),
                ("G", _) => Plane::Rgb(img, 1),
                ("B", _) => Plane::Rgb(img, 2),
                ("Z", Some(z)) if z.len() == width * height => Plane::Depth(z),
                _ => return Err(format!("no samples for channel {name}")),
            });
        }
        Ok(Self {
            width,
            height,
            lines: header.compression.scan_lines_per_block(),
            planes,
            top: header.own_attributes.layer_position.1,
        })
    }

    fn block_count(&self) -> usize {
        self.height.div_ceil(self.lines)
    }

    /// The rows of block `b`.
    fn rows(&self, b: usize) -> Range<usize> {
        b * self.lines..((b + 1) * self.lines).min(self.height)
    }

    /// The uncompressed size of block `b` in bytes.
    fn raw_len(&self, b: usize) -> usize {
        self.rows(b).len() * self.width * self.planes.len() * 4
    }

    /// Step 1 for block `b`: the little-endian bytes of sample `k` (in file order) are written
    /// to `split`, bytes 0 and 2 at `2k` and `2k + 1` of its first half, bytes 1 and 3 at the same
    /// places of its second half (the even and odd positions of the unsplit bytes).
    fn split(&self, b: usize, split: &mut [u8]) {
        let half = split.len() / 2;
        let (even, odd) = split.split_at_mut(half);
        let mut out = even.chunks_exact_mut(2).zip(odd.chunks_exact_mut(2));
        let mut put = |v: f32| {
            if let Some((e, o)) = out.next() {
                let [b0, b1, b2, b3] = v.to_le_bytes();
                e.copy_from_slice(&[b0, b2]);
                o.copy_from_slice(&[b1, b3]);
            }
        };
        for y in self.rows(b) {
            let row = y * self.width..(y + 1) * self.width;
            for plane in &self.planes {
                match *plane {
                    Plane::Rgb(img, c) => row.clone().for_each(|i| put(img.pixel(i)[c])),
                    Plane::Depth(z) => z[row.clone()].iter().for_each(|&v| put(v)),
                }
            }
        }
    }
}

/// Step 2: `out[0] = split[0]`, `out[i] = split[i] - split[i - 1] + 128` (modulo 256).
fn predict(split: &[u8], out: &mut [u8]) {
    if let (Some(first), Some(o)) = (split.first(), out.first_mut()) {
        *o = *first;
    }
    // Three plain slices rather than `windows(2)`, so that the loop is vectorised.
    let n = split.len().min(out.len());
    if n > 1 {
        for ((o, a), b) in out[1..n].iter_mut().zip(&split[1..n]).zip(&split[..n - 1]) {
            *o = a.wrapping_sub(*b).wrapping_add(128);
        }
    }
}

/// The unsplit bytes back from the halves of step 1 (for a block stored raw).
fn unsplit(split: &[u8]) -> Vec<u8> {
    let (even, odd) = split.split_at(split.len() / 2);
    even.chunks_exact(2).zip(odd.chunks_exact(2)).flat_map(|(e, o)| [e[0], o[0], e[1], o[1]]).collect()
}

/// Buffers reused by the blocks a thread compresses.
#[derive(Default)]
struct Scratch {
    split: Vec<u8>,
    predicted: Vec<u8>,
    deflated: Vec<u8>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// The bytes stored for block `b`: its zlib stream, or its raw bytes when that is not smaller.
fn encode_block(layout: &Layout<'_>, b: usize, s: &mut Scratch) -> Vec<u8> {
    let len = layout.raw_len(b);
    s.split.resize(len, 0);
    s.predicted.resize(len, 0);
    layout.split(b, &mut s.split);
    predict(&s.split, &mut s.predicted);
    // Room for a stream one byte shorter than the raw bytes: a longer one fails early
    // (`BufError`) instead of being finished and thrown away.
    s.deflated.resize(len.saturating_sub(1), 0);
    let (stream, code) =
        zlib_rs::compress_slice(&mut s.deflated, &s.predicted, zlib_rs::DeflateConfig::new(ZLIB_LEVEL));
    if code == zlib_rs::ReturnCode::Ok && stream.len() < len {
        stream.to_vec()
    } else {
        unsplit(&s.split)
    }
}

/// The stored bytes of blocks `range`, compressed in parallel.
fn encode_blocks(layout: &Layout<'_>, range: Range<usize>) -> Vec<Vec<u8>> {
    range.into_par_iter().map(|b| SCRATCH.with(|s| encode_block(layout, b, &mut s.borrow_mut()))).collect()
}

/// Writes the image with `headers` (one ZIP or ZIPS scan-line layer of `f32` channels, as
/// [`super::exr`] builds it) to `path`: `img`'s pixels and `depth` as the `Z` channel. A file
/// left incomplete by an error is removed. Errors name `path`.
pub(super) fn write(path: &Path, headers: Headers, img: RgbView<'_>, depth: Option<&[f32]>) -> Result<()> {
    let invalid = |message: String| Error::invalid(path.display().to_string(), "OpenEXR header", message);
    let header = headers.first().ok_or_else(|| invalid("no layer".into()))?;
    let layout = Layout::new(header, img, depth).map_err(invalid)?;
    if headers.len() != 1 {
        return Err(invalid(format!("{} layers, expected one", headers.len())));
    }
    let count = layout.block_count();
    let batch = (BATCH_BYTES / layout.raw_len(0).max(1)).max(4 * rayon::current_num_threads());
    let written = exr::io::attempt_delete_file_on_write_error(path, |file| {
        exr::block::write(BufWriter::new(file), headers, true, |_, writer| {
            let mut start = 0;
            let mut ready = encode_blocks(&layout, 0..batch.min(count));
            while !ready.is_empty() {
                // A cancelled run (`crate::progress`) stops between batches; the file is removed.
                if crate::progress::cancelled() {
                    return Err(exr::error::Error::Aborted);
                }
                let next = start + ready.len();
                let (stored, following) = rayon::join(
                    || {
                        for (b, bytes) in (start..).zip(ready) {
                            let y = i32::try_from(layout.rows(b).start)
                                .ok()
                                .and_then(|y| y.checked_add(layout.top))
                                .ok_or_else(|| exr::error::Error::Invalid("scan line y coordinate".into()))?;
                            let block = CompressedScanLineBlock { y_coordinate: y, compressed_pixels_le: bytes };
                            writer.write_chunk(
                                b,
                                Chunk { layer_index: 0, compressed_block: CompressedBlock::ScanLine(block) },
                            )?;
                        }
                        Ok::<_, exr::error::Error>(())
                    },
                    || encode_blocks(&layout, next..(next + batch).min(count)),
                );
                stored?;
                (start, ready) = (next, following);
            }
            Ok(())
        })
    });
    written.map_err(|e| match e {
        exr::error::Error::Io(e) => Error::io(path, e),
        exr::error::Error::Aborted => Error::Cancelled,
        other => invalid(format!("cannot write OpenEXR file: {other}")),
    })
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use exr::meta::MetaData;
    use exr::prelude::{read, ReadChannels, ReadLayers};

    use super::*;
    use crate::io::exr::{read_typed_attributes, write_view_by, AttrValue, Attributes, ExrCompression};
    use crate::raster::RgbImage;

    /// SplitMix64: deterministic test data without a dependency.
    fn rng(mut state: u64) -> impl FnMut() -> u64 {
        move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
    }

    /// Any finite `f32`: random bits with the exponent of an infinity or NaN made finite.
    fn finite_bits(r: u64) -> f32 {
        let v = f32::from_bits(r as u32);
        if v.is_finite() {
            v
        } else {
            f32::from_bits(r as u32 ^ 0x4000_0000)
        }
    }

    /// Samples of every kind: zeros of both signs, negatives, the largest finite values,
    /// subnormals and random finite bit patterns.
    fn random_sample(next: &mut impl FnMut() -> u64) -> f32 {
        let r = next();
        match r % 8 {
            0 => 0.0,
            1 => -0.0,
            2 => -(((r >> 8) % 1000) as f32) * 0.37,
            3 => f32::MAX,
            4 => -3.0e38,
            5 => f32::from_bits((r >> 8) as u32 & 0x007f_ffff),
            _ => finite_bits(r >> 3),
        }
    }

    struct Case {
        name: String,
        img: RgbImage,
        depth: Option<Vec<f32>>,
    }

    fn random_case(w: usize, h: usize, seed: u64, with_depth: bool) -> Case {
        let mut next = rng(seed);
        let mut img = RgbImage::new(w, h);
        for px in &mut img.pixels {
            *px = [random_sample(&mut next), random_sample(&mut next), random_sample(&mut next)];
        }
        // Depth as rendered: distances, misses (+inf) and zeros.
        let depth = with_depth.then(|| {
            (0..w * h)
                .map(|_| match next() % 5 {
                    0 => f32::INFINITY,
                    1 => 0.0,
                    r => 250.0 + r as f32 * 0.125 + (next() % 4096) as f32 / 4096.0,
                })
                .collect()
        });
        Case { name: format!("random {w}x{h} depth {with_depth}"), img, depth }
    }

    fn constant_case(w: usize, h: usize, with_depth: bool) -> Case {
        let mut img = RgbImage::new(w, h);
        img.pixels.iter_mut().for_each(|p| *p = [0.25, 0.5, 1.0e-3]);
        let depth = with_depth.then(|| vec![300.0; w * h]);
        Case { name: format!("constant {w}x{h} depth {with_depth}"), img, depth }
    }

    /// The images of the round-trip tests: widths of no special size and heights that are not
    /// multiples of 16 (one line, fewer than a block, a block and a line), with and without Z.
    fn cases() -> Vec<Case> {
        vec![
            random_case(1, 1, 1, false),
            random_case(13, 17, 2, true),
            random_case(67, 41, 3, false),
            random_case(3, 33, 4, true),
            random_case(101, 16, 5, true),
            random_case(1, 40, 6, true),
            constant_case(29, 35, true),
            constant_case(200, 7, false),
        ]
    }

    fn attributes() -> Attributes {
        let mut a = Attributes::new();
        a.set("inimtrace:focus_mm", 300.0f64)
            .set("inimtrace:half_float_note", 0.25f32)
            .set("inimtrace:pupil_samples", 52i32)
            .set("inimtrace:method", "LA (5x5)");
        a
    }

    fn write(dir: &Path, case: &Case, compression: ExrCompression, own_zip: bool) -> PathBuf {
        let path = dir.join(format!("{}-{compression}-{own_zip}.exr", case.name.replace(' ', "_")));
        write_view_by(&path, RgbView::from(&case.img), case.depth.as_deref(), &attributes(), compression, own_zip)
            .unwrap();
        path
    }

    /// The channels of a file as its reader decodes them: names and sample bits.
    fn decode(path: &Path) -> Vec<(String, Vec<u32>)> {
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .from_file(path)
            .unwrap();
        assert_eq!(image.layer_data.len(), 1);
        let layer = &image.layer_data[0];
        layer
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().map(f32::to_bits).collect()))
            .collect()
    }

    /// The channels the file must hold: B, G, R and Z (when given), sorted by name.
    fn expected(case: &Case) -> Vec<(String, Vec<u32>)> {
        let plane = |c: usize| case.img.pixels.iter().map(|p| p[c].to_bits()).collect();
        let mut out = vec![("B".into(), plane(2)), ("G".into(), plane(1)), ("R".into(), plane(0))];
        if let Some(z) = &case.depth {
            out.push(("Z".into(), z.iter().map(|v| v.to_bits()).collect()));
        }
        out
    }

    /// `(stored bytes, raw bytes)` of every block of a scan-line file, in file order.
    fn block_sizes(path: &Path) -> Vec<(usize, usize)> {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let reader = exr::block::read(file, true).unwrap();
        let header = reader.headers()[0].clone();
        let lines = header.compression.scan_lines_per_block();
        let line_bytes = header.layer_size.0 * header.channels.bytes_per_pixel;
        reader
            .all_chunks(true)
            .unwrap()
            .map(|chunk| match chunk.unwrap().compressed_block {
                CompressedBlock::ScanLine(b) => {
                    let y = b.y_coordinate as usize;
                    (b.compressed_pixels_le.len(), (lines.min(header.layer_size.1 - y)) * line_bytes)
                }
                other => panic!("not a scan-line block: {other:?}"),
            })
            .collect()
    }

    #[test]
    fn zip_blocks_decode_to_the_written_bits_with_the_header_and_attributes() {
        let dir = tempfile::tempdir().unwrap();
        for case in cases() {
            for (c, kind) in [(ExrCompression::Zip, Compression::ZIP16), (ExrCompression::Zips, Compression::ZIP1)] {
                let path = write(dir.path(), &case, c, true);
                assert!(decode(&path) == expected(&case), "{}, {c}: other samples decoded", case.name);
                let meta = MetaData::read_from_file(&path, true).unwrap();
                assert_eq!(meta.headers[0].compression, kind, "{}", case.name);
                let attrs = read_typed_attributes(&path).unwrap();
                let get = |k: &str| attrs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
                assert_eq!(get("inimtrace:focus_mm"), Some(AttrValue::F64(300.0)));
                assert_eq!(get("inimtrace:half_float_note"), Some(AttrValue::F32(0.25)));
                assert_eq!(get("inimtrace:pupil_samples"), Some(AttrValue::I32(52)));
                assert_eq!(get("inimtrace:method"), Some(AttrValue::Text("LA (5x5)".into())));
                assert_eq!(get("inimtrace:version"), Some(AttrValue::Text(crate::version::VERSION.into())));
                assert_eq!(get("software"), Some(AttrValue::Text(crate::version::software())));
            }
        }
    }

    #[test]
    fn the_exr_crates_own_zip_writer_makes_the_same_header_and_samples() {
        let dir = tempfile::tempdir().unwrap();
        for case in cases() {
            for c in [ExrCompression::Zip, ExrCompression::Zips] {
                let ours = write(dir.path(), &case, c, true);
                let theirs = write(dir.path(), &case, c, false);
                assert!(decode(&ours) == decode(&theirs), "{}, {c}", case.name);
                let header = |p: &Path| MetaData::read_from_file(p, true).unwrap().headers;
                assert_eq!(header(&ours), header(&theirs), "{}, {c}", case.name);
                assert_eq!(read_typed_attributes(&ours).unwrap(), read_typed_attributes(&theirs).unwrap());
            }
        }
    }

    #[test]
    fn a_block_that_does_not_deflate_is_stored_raw_and_the_others_compressed() {
        // Rows 0-15 random bit patterns (incompressible), rows 16-39 one smooth colour.
        let dir = tempfile::tempdir().unwrap();
        let mut case = random_case(37, 40, 7, true);
        for (i, p) in case.img.pixels.iter_mut().enumerate().skip(16 * 37) {
            *p = [0.5, 0.25, (i / 37) as f32 / 40.0];
        }
        let mut next = rng(8);
        for (i, z) in case.depth.as_mut().unwrap().iter_mut().enumerate() {
            *z = if i < 16 * 37 { finite_bits(next()) } else { 300.0 };
        }
        case.img.pixels.iter_mut().take(16 * 37).for_each(|p| *p = p.map(|_| finite_bits(next())));
        for (c, noisy_blocks) in [(ExrCompression::Zip, 1), (ExrCompression::Zips, 16)] {
            let path = write(dir.path(), &case, c, true);
            let sizes = block_sizes(&path);
            assert_eq!(sizes.len(), if c == ExrCompression::Zip { 3 } else { 40 });
            for (b, (stored, raw)) in sizes.iter().enumerate() {
                if b < noisy_blocks {
                    assert_eq!(stored, raw, "{c}: noisy block {b} is stored raw");
                } else {
                    assert!(stored < raw, "{c}: smooth block {b} is compressed ({stored} of {raw} bytes)");
                }
            }
            assert!(decode(&path) == expected(&case), "{c}");
        }
    }

    #[test]
    fn block_bytes_are_openexrs_zip_layout() {
        // Undo by the specification: inflate, undo the predictor, interleave the halves, read
        // per line, per channel (B, G, R, Z) the little-endian samples.
        let dir = tempfile::tempdir().unwrap();
        let case = constant_case(5, 3, true);
        let path = write(dir.path(), &case, ExrCompression::Zips, true);
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        for (y, chunk) in exr::block::read(file, true).unwrap().all_chunks(true).unwrap().enumerate() {
            let CompressedBlock::ScanLine(block) = chunk.unwrap().compressed_block else { panic!("scan lines") };
            assert_eq!(block.y_coordinate, y as i32);
            let mut predicted = vec![0u8; 5 * 16];
            let (inflated, code) = zlib_rs::decompress_slice(
                &mut predicted,
                &block.compressed_pixels_le,
                zlib_rs::InflateConfig::default(),
            );
            assert_eq!((code, inflated.len()), (zlib_rs::ReturnCode::Ok, 80));
            let mut split = predicted.clone();
            for i in 1..split.len() {
                split[i] = split[i - 1].wrapping_add(predicted[i]).wrapping_sub(128);
            }
            let (even, odd) = split.split_at(40);
            let bytes: Vec<u8> = (0..80).map(|i| if i % 2 == 0 { even[i / 2] } else { odd[i / 2] }).collect();
            let samples: Vec<f32> = bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
            let line: Vec<f32> = [1.0e-3, 0.5, 0.25, 300.0].iter().flat_map(|&v| [v; 5]).collect();
            assert_eq!(samples, line, "line {y}");
        }
    }

    #[test]
    fn the_predictor_stores_differences_plus_128() {
        let mut out = [0u8; 4];
        predict(&[0x10, 0x05, 0xff, 0x00], &mut out);
        assert_eq!(out, [0x10, 0x75, 0x7a, 0x81]);
        // The halves: bytes 0 and 2 of each sample first, then bytes 1 and 3.
        assert_eq!(unsplit(&[1, 3, 5, 7, 2, 4, 6, 8]), [1, 2, 3, 4, 5, 6, 7, 8]);
    }
}
