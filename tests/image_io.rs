//! Tests of image file I/O (src/io/exr.rs, src/io/png.rs, src/io/figure.rs): bit-exact EXR
//! round trips with attributes and depth, row 0 at the top, the input policy for malformed
//! files and bad samples, exact sRGB codes, and montage geometry and colours.
#![deny(unsafe_code)]

use std::path::Path;

use inimtrace::io::exr::{read_attributes, read_rgb, read_rgb_depth, write_rgb};
use inimtrace::io::figure::{cell_origin, montage_size, write_montage, CELL_SIZE};
use inimtrace::io::png::{srgb_encode, write_preview};
use inimtrace::raster::RgbImage;

/// A 7x5 image whose samples are distinct f32 bit patterns (including values that a lossy or
/// f16 path would change: subnormal, tiny, huge, many mantissa bits).
fn awkward_image() -> RgbImage {
    let (w, h) = (7, 5);
    let mut img = RgbImage::new(w, h);
    let special = [0.0f32, 1.0e-40, 1.0e-30, 0.1, 1.0 / 3.0, 65_504.0, 3.0e38, 0.999_999_9];
    let mut k = 0usize;
    for r in 0..h {
        for c in 0..w {
            let mut p = [0.0f32; 3];
            for v in &mut p {
                *v = if k.is_multiple_of(3) {
                    special[k / 3 % special.len()]
                } else {
                    f32::from_bits(0x3e00_0000 + (k as u32).wrapping_mul(2_654_435_761) % 0x0180_0000)
                };
                k += 1;
            }
            img.set(r, c, p);
        }
    }
    img
}

#[test]
fn exr_round_trip_is_bit_exact_with_attributes_and_depth() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("display.exr");
    let img = awkward_image();
    let depth: Vec<f32> = (0..img.width * img.height).map(|i| 250.0 + i as f32 * 0.123_456_7).collect();
    let mut depth = depth;
    depth[3] = f32::INFINITY; // a ray that hit nothing
    let attrs = [("inimtrace:method", "LC".to_string()), ("inimtrace:units", "mm; café".to_string())];
    write_rgb(&path, &img, Some(&depth), &attrs).unwrap();

    let (back, z) = read_rgb_depth(&path).unwrap();
    assert_eq!((back.width, back.height), (img.width, img.height));
    for (a, b) in back.pixels.iter().zip(&img.pixels) {
        for c in 0..3 {
            assert_eq!(a[c].to_bits(), b[c].to_bits());
        }
    }
    let z = z.expect("Z channel");
    assert!(z.iter().zip(&depth).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(read_rgb(&path).unwrap(), img);

    let read = read_attributes(&path).unwrap();
    for (k, v) in &attrs {
        assert!(read.contains(&(k.to_string(), v.clone())), "{k} missing from {read:?}");
    }

    // Without depth there is no Z.
    let p2 = dir.path().join("nodepth.exr");
    write_rgb(&p2, &img, None, &[]).unwrap();
    assert_eq!(read_rgb_depth(&p2).unwrap().1, None);
}

#[test]
fn exr_row_zero_is_the_top_row_of_the_file() {
    // Read the file with the exr crate itself: OpenEXR's y axis points down, so the first
    // stored scan line (y = data window minimum) must be our row 0.
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rows.exr");
    let mut img = RgbImage::new(3, 4);
    for r in 0..4 {
        for c in 0..3 {
            img.set(r, c, [r as f32, c as f32, 0.5]);
        }
    }
    write_rgb(&path, &img, None, &[]).unwrap();
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    assert_eq!(meta.headers[0].line_order, LineOrder::Increasing);
    let file = read_all_flat_layers_from_file(&path).unwrap();
    let layer = &file.layer_data[0];
    assert_eq!(layer.size, Vec2(3, 4));
    let red = layer.channel_data.list.iter().find(|c| c.name == *"R").unwrap();
    let values: Vec<f32> = red.sample_data.values_as_f32().collect();
    // Flat index = y * width + x, y = 0 at the top.
    assert_eq!(values, vec![0., 0., 0., 1., 1., 1., 2., 2., 2., 3., 3., 3.]);
}

#[test]
fn exr_accepts_f16_channels() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("half.exr");
    let vals = |s: f32| FlatSamples::F16((0..6).map(|i| f16::from_f32(s * i as f32)).collect());
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("R", vals(0.5)),
        AnyChannel::new("G", vals(0.25)),
        AnyChannel::new("B", vals(2.0)),
    ]));
    Image::from_channels((3, 2), channels).write().to_file(&path).unwrap();
    let img = read_rgb(&path).unwrap();
    assert_eq!((img.width, img.height), (3, 2));
    assert_eq!(img.get(1, 2), [2.5, 1.25, 10.0]); // flat index 5
}

fn assert_err_names(result: Result<impl std::fmt::Debug, inimtrace::Error>, path: &Path, what: &str) {
    let e = result.expect_err(what).to_string();
    assert!(e.contains(&path.display().to_string()), "{what}: error `{e}` does not name the path");
}

#[test]
fn malformed_exr_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.exr");
    std::fs::write(&empty, b"").unwrap();
    let text = dir.path().join("text.exr");
    std::fs::write(&text, "this is not an image\n".repeat(20)).unwrap();
    let good = dir.path().join("good.exr");
    write_rgb(&good, &RgbImage::filled(64, 64, [0.2, 0.3, 0.4]), None, &[]).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.path().join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let header_only = dir.path().join("header_cut.exr");
    std::fs::write(&header_only, &bytes[..40]).unwrap();
    let subdir = dir.path().join("a_directory.exr");
    std::fs::create_dir(&subdir).unwrap();
    let missing = dir.path().join("missing.exr");

    for p in [&empty, &text, &truncated, &header_only, &subdir, &missing] {
        assert_err_names(read_rgb(p), p, "read_rgb");
    }
    // read_attributes reads only the header, which survives in `truncated`.
    for p in [&empty, &text, &header_only, &subdir, &missing] {
        assert_err_names(read_attributes(p), p, "read_attributes");
    }
    assert!(read_attributes(&truncated).is_ok());
}

#[test]
fn exr_without_rgb_is_an_error() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rg.exr");
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("R", FlatSamples::F32(vec![0.5; 4])),
        AnyChannel::new("G", FlatSamples::F32(vec![0.5; 4])),
    ]));
    Image::from_channels((2, 2), channels).write().to_file(&path).unwrap();
    let e = read_rgb(&path).unwrap_err().to_string();
    assert!(e.contains("rg.exr") && e.contains("R, G and B"), "{e}");
}

#[test]
fn bad_samples_in_exr_name_pixel_and_channel() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    for (value, kind) in [(f32::NAN, "NaN"), (f32::INFINITY, "infinite"), (-0.25, "negative")] {
        let path = dir.path().join(format!("bad_{kind}.exr"));
        // Written with the exr crate directly: our writer refuses non-finite values.
        let mut g = vec![0.5f32; 24];
        g[2 * 6 + 5] = value;
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            AnyChannel::new("R", FlatSamples::F32(vec![0.5; 24])),
            AnyChannel::new("G", FlatSamples::F32(g)),
            AnyChannel::new("B", FlatSamples::F32(vec![0.5; 24])),
        ]));
        Image::from_channels((6, 4), channels).write().to_file(&path).unwrap();
        if value.is_nan() || value.is_infinite() {
            let mut img = RgbImage::filled(6, 4, [0.5; 3]);
            img.set(2, 5, [0.5, value, 0.5]);
            let w = write_rgb(&dir.path().join("refused.exr"), &img, None, &[]).unwrap_err().to_string();
            assert!(w.contains("row 2, col 5") && w.contains("non-finite"), "{w}");
        }
        let e = read_rgb(&path).unwrap_err().to_string();
        for needle in [path.display().to_string(), "row 2".into(), "col 5".into(), "channel G".into(), kind.into()] {
            assert!(e.contains(&needle), "`{e}` lacks `{needle}`");
        }
    }
    // NaN depth is rejected too.
    let path = dir.path().join("bad_z.exr");
    let img = RgbImage::filled(3, 3, [0.5; 3]);
    let mut z = vec![1.0f32; 9];
    z[4] = f32::NAN;
    write_rgb(&path, &img, Some(&z), &[]).unwrap();
    let e = read_rgb_depth(&path).unwrap_err().to_string();
    assert!(e.contains("row 1") && e.contains("col 1") && e.contains("channel Z"), "{e}");
}

#[test]
fn exr_write_rejects_bad_requests() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.exr");
    let img = RgbImage::filled(4, 4, [0.1; 3]);
    assert!(write_rgb(&path, &img, Some(&[1.0; 15]), &[]).is_err());
    assert!(write_rgb(&path, &img, None, &[("channels", "x".into())]).is_err());
    assert!(write_rgb(&path, &img, None, &[("inimtrace:note", "π".into())]).is_err());
    assert!(write_rgb(&path, &RgbImage::new(0, 0), None, &[]).is_err());
    let no_dir = dir.path().join("no/such/dir/x.exr");
    assert_err_names(write_rgb(&no_dir, &img, None, &[]), &no_dir, "write into missing dir");
}

#[test]
fn srgb_codes_are_exact() {
    assert_eq!(srgb_encode(0.0), 0);
    assert_eq!(srgb_encode(1.0), 255);
    // 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357 -> 187.52 -> 188 (gamma 2.2 would give 186).
    assert_eq!(srgb_encode(0.5), 188);
    // Linear segment: 12.92 * 0.002 * 255 = 6.59 -> 7.
    assert_eq!(srgb_encode(0.002), 7);
    // 0.18 (mid grey): 1.055 * 0.18^(1/2.4) - 0.055 = 0.46135 -> 117.6 -> 118.
    assert_eq!(srgb_encode(0.18), 118);
    // Clamping.
    assert_eq!(srgb_encode(-0.5), 0);
    assert_eq!(srgb_encode(7.0), 255);
    assert_eq!(srgb_encode(f32::INFINITY), 255);
    assert_eq!(srgb_encode(f32::NAN), 0);
    // Monotone over the whole range.
    let mut last = 0;
    for i in 0..=10_000 {
        let code = srgb_encode(i as f32 / 10_000.0);
        assert!(code >= last);
        last = code;
    }
}

#[test]
fn png_preview_pixels_and_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("preview.png");
    let mut img = RgbImage::new(5, 3);
    img.set(0, 0, [0.5, 0.0, 1.0]);
    img.set(2, 4, [2.0, -1.0, 0.18]);
    write_preview(&path, &img).unwrap();
    let png = image::open(&path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (5, 3));
    assert_eq!(png.get_pixel(0, 0).0, [188, 0, 255]); // (x, y) = (0, 0): top-left
    assert_eq!(png.get_pixel(4, 2).0, [255, 0, 118]);
    assert_eq!(png.get_pixel(1, 0).0, [0, 0, 0]);
    let missing_dir = dir.path().join("nope/p.png");
    assert_err_names(write_preview(&missing_dir, &img), &missing_dir, "png into missing dir");
}

#[test]
fn montage_layout_and_cell_colours() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("montage.png");
    let colours = [[0.5f32, 0.2, 0.8], [0.05, 0.9, 0.3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    // Different sizes: downscaled (300x300), upscaled (16x16), same size, and non-square.
    let imgs = [
        RgbImage::filled(300, 300, colours[0]),
        RgbImage::filled(16, 16, colours[1]),
        RgbImage::filled(CELL_SIZE, CELL_SIZE, colours[2]),
        RgbImage::filled(512, 256, colours[3]),
    ];
    let rows = vec![
        ("Emmetropic eye, focus 0.5 m", imgs.iter().collect::<Vec<_>>()),
        ("Myopic eye", imgs.iter().rev().collect::<Vec<_>>()),
    ];
    write_montage(&path, &rows, &["GT", "LC", "PC", "LA"]).unwrap();
    let png = image::open(&path).unwrap().to_rgb8();
    let (w, h) = montage_size(2, 4);
    assert_eq!((png.width() as usize, png.height() as usize), (w, h));
    let code = |c: [f32; 3]| [srgb_encode(c[0]), srgb_encode(c[1]), srgb_encode(c[2])];
    for (r, (_, row)) in rows.iter().enumerate() {
        for (c, img) in row.iter().enumerate() {
            let (x0, y0) = cell_origin(r, c);
            let centre = png.get_pixel((x0 + CELL_SIZE / 2) as u32, (y0 + CELL_SIZE / 2) as u32).0;
            assert_eq!(centre, code(img.pixels[0]), "cell ({r}, {c})");
            // Corner pixels: the colour, or black letterbox bars for the 2:1 image.
            let corner = png.get_pixel(x0 as u32, y0 as u32).0;
            let want = if img.width == img.height { code(img.pixels[0]) } else { [0, 0, 0] };
            assert_eq!(corner, want, "corner of cell ({r}, {c})");
            // Just outside the cell (separator) is white background.
            let gap = png.get_pixel((x0 + CELL_SIZE) as u32, (y0 + 10) as u32).0;
            assert_eq!(gap, [255, 255, 255]);
        }
    }
    // Some label text was drawn: dark pixels in the column-label strip and the row-label strip.
    let (x0, _) = cell_origin(0, 0);
    let dark = |xs: std::ops::Range<usize>, ys: std::ops::Range<usize>| {
        xs.flat_map(|x| ys.clone().map(move |y| (x, y)))
            .filter(|&(x, y)| png.get_pixel(x as u32, y as u32).0.iter().all(|&v| v < 100))
            .count()
    };
    assert!(dark(x0..x0 + CELL_SIZE, 0..cell_origin(0, 0).1) > 20, "no column label drawn");
    assert!(dark(0..x0, cell_origin(1, 0).1..cell_origin(1, 0).1 + CELL_SIZE) > 20, "no row label drawn");
}

#[test]
fn montage_rejects_ragged_rows() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.png");
    let a = RgbImage::filled(20, 20, [0.5; 3]);
    let rows = vec![("only one", vec![&a])];
    let e = write_montage(&path, &rows, &["GT", "LC"]).unwrap_err().to_string();
    assert!(e.contains("m.png") && e.contains("only one"), "{e}");
    assert!(write_montage(&path, &[], &["GT"]).is_err());
}
