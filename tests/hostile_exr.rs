//! EXR inputs read strictly (issue #30, round two), with files crafted by the `exr` crate and
//! patched byte by byte: `UINT` channels are refused as radiance; a data window that is not the
//! display window is refused (a shifted copy never compares as identical); a multipart file
//! needs `--part NAME` unless one part alone has R, G and B (then a one-line note names it);
//! and a damaged block, block coordinate or offset table is an error, never a silently
//! different image.

use std::path::Path;
use std::process::{Command, Output};

use exr::image::{AnyChannel, AnyChannels, FlatSamples, Layers};
use exr::prelude::*;

fn inimtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("run inimtrace")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn zip() -> Encoding {
    Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing }
}

/// A smooth RGB pattern, different per `seed`.
fn value(x: usize, y: usize, seed: usize) -> (f32, f32, f32) {
    let v = ((x * 7 + y * 13 + seed * 5) % 17) as f32 / 17.0;
    (v, v * 0.5, 1.0 - v)
}

/// A single-part RGB file of `w` x `h`, ZIP, with its data window at `at` and its display window
/// at (0, 0) of the same size.
fn write_rgb(path: &Path, w: usize, h: usize, at: (i32, i32)) {
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| value(p.x(), p.y(), 0));
    let mut attributes = LayerAttributes::named("beauty");
    attributes.layer_position = Vec2(at.0, at.1);
    let layer = Layer::new((w, h), attributes, zip(), channels);
    Image::new(ImageAttributes::with_size((w, h)), layer).write().to_file(path).unwrap();
}

/// A part named `name` holding the named `f32` channels (each a pattern of its own).
fn part(name: &str, w: usize, h: usize, channels: &[&str], seed: usize) -> Layer<AnyChannels<FlatSamples>> {
    let list = channels
        .iter()
        .enumerate()
        .map(|(c, n)| {
            let samples = (0..w * h).map(|i| value(i % w, i / w, seed + c).0).collect();
            AnyChannel::new(*n, FlatSamples::F32(samples))
        })
        .collect();
    Layer::new((w, h), LayerAttributes::named(name), zip(), AnyChannels::sort(list))
}

fn write_parts(path: &Path, layers: Vec<Layer<AnyChannels<FlatSamples>>>) {
    let size = layers[0].size;
    let layers: Layers<AnyChannels<FlatSamples>> = layers.into_iter().collect();
    Image::from_layers(ImageAttributes::with_size(size), layers).write().to_file(path).unwrap();
}

#[test]
fn uint_channels_are_refused_as_radiance() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("uint.exr");
    let channels = SpecificChannels::build()
        .with_channel::<u32>("R")
        .with_channel::<u32>("G")
        .with_channel::<u32>("B")
        .with_pixel_fn(|p: Vec2<usize>| (p.x() as u32, 1u32, 2u32));
    Image::from_layer(Layer::new((16, 16), LayerAttributes::default(), zip(), channels))
        .write()
        .to_file(&path)
        .unwrap();
    let p = path.to_str().unwrap();
    let o = inimtrace(&["compare", p, p]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("uint.exr") && e.contains("channel B") && e.contains("UINT"), "{e}");
    assert_eq!(e.trim().lines().count(), 1, "{e}");
}

#[test]
fn a_shifted_data_window_is_refused_and_never_compares_as_identical() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("shifted.exr"));
    write_rgb(&a, 32, 24, (0, 0));
    write_rgb(&b, 32, 24, (3, 2));
    let o = inimtrace(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "compared: {}", String::from_utf8_lossy(&o.stdout));
    assert!(e.contains("shifted.exr") && e.contains("dataWindow") && e.contains("(3, 2)-(34, 25)"), "{e}");
    assert!(e.contains("display window (0, 0)-(31, 23)"), "{e}");
    // The unshifted file reads as before.
    let o = inimtrace(&["compare", a.to_str().unwrap(), a.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_multipart_file_reads_its_only_rgb_part_with_a_note_or_needs_a_named_part() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24, 20);
    let single = dir.path().join("single.exr");
    write_parts(&single, vec![part("right", w, h, &["R", "G", "B"], 3)]);
    let one_rgb = dir.path().join("one_rgb.exr");
    write_parts(&one_rgb, vec![part("depth", w, h, &["Z"], 9), part("right", w, h, &["R", "G", "B"], 3)]);
    let two_rgb = dir.path().join("two_rgb.exr");
    write_parts(&two_rgb, vec![part("left", w, h, &["R", "G", "B"], 1), part("right", w, h, &["R", "G", "B"], 3)]);
    let (single, one_rgb, two_rgb) = (single.to_str().unwrap(), one_rgb.to_str().unwrap(), two_rgb.to_str().unwrap());

    // The only RGB part is read, and one note says which.
    let o = inimtrace(&["compare", "--json", one_rgb, single]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let notes: Vec<&str> = e.lines().filter(|l| l.starts_with("note:")).collect();
    assert_eq!(notes.len(), 1, "{e}");
    assert!(notes[0].contains("one_rgb.exr has 2 parts") && notes[0].contains("`right`"), "{e}");
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(json["psnr_db"]["mean"].is_null(), "not the `right` part: {json}");
    // A single-part file gets no note.
    let o = inimtrace(&["compare", single, single]);
    assert!(o.status.success() && !stderr(&o).contains("note:"), "{}", stderr(&o));

    // Two RGB parts: refused, naming both, until one is chosen.
    let o = inimtrace(&["compare", two_rgb, single]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("`left`") && e.contains("`right`") && e.contains("--part NAME"), "{e}");
    let o = inimtrace(&["compare", "--json", "--part", "right", two_rgb, single]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(json["psnr_db"]["mean"].is_null(), "--part right did not read `right`: {json}");
    let o = inimtrace(&["compare", "--json", "--part", "left", two_rgb, two_rgb]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = inimtrace(&["compare", "--json", "--part", "left", two_rgb, single]);
    assert_eq!(o.status.code(), Some(1), "`left` of one file against `right` alone of another");
    // A part that is not there, or has no RGB.
    let o = inimtrace(&["compare", "--part", "centre", two_rgb, two_rgb]);
    let e = stderr(&o);
    assert!(o.status.code() == Some(1) && e.contains("--part") && e.contains("no part named `centre`"), "{e}");
    let o = inimtrace(&["compare", "--part", "depth", one_rgb, one_rgb]);
    let e = stderr(&o);
    assert!(o.status.code() == Some(1) && e.contains("no layer with R, G and B"), "{e}");
}

/// Byte ranges of every chunk (its coordinate, size and compressed data) in the file.
fn chunks(path: &Path) -> Vec<std::ops::Range<usize>> {
    let bytes = std::fs::read(path).unwrap();
    let reader = exr::block::read(std::io::BufReader::new(std::fs::File::open(path).unwrap()), false).unwrap();
    let mut out = Vec::new();
    for chunk in reader.all_chunks(false).unwrap() {
        let data = match chunk.unwrap().compressed_block {
            exr::block::chunk::CompressedBlock::ScanLine(b) => b.compressed_pixels_le,
            _ => unreachable!("scan lines only"),
        };
        let at = bytes.windows(data.len()).position(|w| w == &data[..]).unwrap();
        out.push(at - 8..at + data.len());
    }
    out
}

#[test]
fn a_flipped_byte_anywhere_is_an_error_or_changes_nothing() {
    // 16 x 48 pixels in three ZIP blocks. Every byte of the file flipped in two ways: the
    // reader either refuses the file or reads exactly the original pixels (a flip in an unused
    // header bit, or in the last deflate byte's padding). Before the checks, flips in a block's
    // y coordinate or in the offset table read as a silently different image.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.exr");
    write_rgb(&path, 16, 48, (0, 0));
    let good = inimtrace::io::exr::read_rgb(&path).unwrap();
    let original = std::fs::read(&path).unwrap();
    let blocks = chunks(&path);
    assert_eq!(blocks.len(), 3);
    let (mut refused, mut same, mut in_data) = (0, 0, 0);
    for i in 0..original.len() {
        for mask in [0x01u8, 0x10] {
            let mut bytes = original.clone();
            bytes[i] ^= mask;
            std::fs::write(&path, &bytes).unwrap();
            match inimtrace::io::exr::read_rgb(&path) {
                Ok(img) => {
                    assert!(img.pixels == good.pixels, "byte {i} ^ {mask:#x} reads as a different image");
                    same += 1;
                }
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.contains("a.exr") && !e.contains('\n'), "{e}");
                    refused += 1;
                    in_data += usize::from(blocks.iter().any(|r| r.contains(&i)));
                }
            }
        }
    }
    // Nearly every flip inside the blocks is caught (by the zlib checksum, the block checks).
    let block_bytes: usize = blocks.iter().map(|r| r.len()).sum();
    assert!(in_data * 100 >= block_bytes * 2 * 98, "only {in_data} of {} flips in blocks refused", block_bytes * 2);
    assert!(refused > 0 && same > 0);
}

#[test]
fn a_block_coordinate_moved_onto_another_block_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("moved.exr");
    write_rgb(&path, 32, 48, (0, 0));
    let blocks = chunks(&path);
    let mut bytes = std::fs::read(&path).unwrap();
    // Block 1 (rows 16..32) claims to be block 0: rows 16..32 would be left black.
    bytes[blocks[1].start..blocks[1].start + 4].copy_from_slice(&0i32.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let p = path.to_str().unwrap();
    let o = inimtrace(&["compare", p, p]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("moved.exr") && e.contains("corrupt file") && e.contains("(0, 0) appears twice"), "{e}");
}
