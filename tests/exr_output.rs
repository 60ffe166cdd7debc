//! EXR output for downstream tools (issue "compressed, typed EXR"): lossless compression round
//! trips bit for bit, numeric header attributes keep their types, the paper's display image
//! shrinks to at most a third of its uncompressed size, and OpenEXR's own Python bindings read
//! back the same pixels, types and values.

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::io::exr::{
    read_compression, read_rgb_depth, read_typed_attributes, write_rgb_with, AttrValue, Attributes, ExrCompression,
};
use inimtrace::optics::Display;
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::{render_display_image_with_depth, with_fields, BackendChoice, DisplayRenderSettings, Method};
use inimtrace::scene::Scene;

/// A smooth image with flat regions and noise-like mantissas, and a depth plane with misses.
fn image(w: usize, h: usize) -> (RgbImage, Vec<f32>) {
    let mut img = RgbImage::new(w, h);
    let mut depth = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            let k = (r * w + c) as u32;
            let noise = f32::from_bits(0x3e00_0000 + k.wrapping_mul(2_654_435_761) % 0x0080_0000);
            img.set(r, c, if c < w / 3 { [0.2, 0.7, 0.8] } else { [noise, (r as f32) / h as f32, 1.0e-30] });
            depth.push(if r == 0 { f32::INFINITY } else { 300.0 + 0.01 * k as f32 });
        }
    }
    (img, depth)
}

fn typed() -> Attributes {
    let mut a = Attributes::new();
    a.set("inimtrace:focus_mm", 300.0f64)
        .set("inimtrace:focus_diopters", 1000.0 / 300.0)
        .set("inimtrace:half_float_note", 0.25f32)
        .set("inimtrace:pupil_samples", 52i32)
        .set("inimtrace:method", "LA (5x5)");
    a
}

#[test]
fn every_lossless_compression_round_trips_bit_for_bit_with_typed_attributes() {
    let dir = tempfile::tempdir().unwrap();
    let (img, depth) = image(67, 41);
    for c in [ExrCompression::None, ExrCompression::Rle, ExrCompression::Zips, ExrCompression::Zip, ExrCompression::Piz]
    {
        let path = dir.path().join(format!("{c}.exr"));
        write_rgb_with(&path, &img, Some(&depth), &typed(), c).unwrap();
        assert_eq!(read_compression(&path).unwrap(), Some(c));
        let (back, z) = read_rgb_depth(&path).unwrap();
        assert!(back.pixels.iter().zip(&img.pixels).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)), "{c}");
        assert!(z.unwrap().iter().zip(&depth).all(|(a, b)| a.to_bits() == b.to_bits()), "{c}: Z");
        let attrs = read_typed_attributes(&path).unwrap();
        let get = |k: &str| attrs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        assert_eq!(get("inimtrace:focus_mm"), Some(AttrValue::F64(300.0)));
        assert_eq!(get("inimtrace:focus_diopters"), Some(AttrValue::F64(1000.0 / 300.0)));
        assert_eq!(get("inimtrace:half_float_note"), Some(AttrValue::F32(0.25)));
        assert_eq!(get("inimtrace:pupil_samples"), Some(AttrValue::I32(52)));
        assert_eq!(get("inimtrace:method"), Some(AttrValue::Text("LA (5x5)".into())));
        assert_eq!(get("inimtrace:version"), Some(AttrValue::Text(inimtrace::version::VERSION.into())));
        assert_eq!(get("inimtrace:git_revision"), Some(AttrValue::Text(inimtrace::version::GIT_REVISION.into())));
        assert_eq!(get("software"), Some(AttrValue::Text(inimtrace::version::software())));
    }
    // PXR24 is lossy for f32: within its 24-bit precision, not exact.
    let path = dir.path().join("pxr24.exr");
    write_rgb_with(&path, &img, None, &typed(), ExrCompression::Pxr24).unwrap();
    let (back, _) = read_rgb_depth(&path).unwrap();
    let mut exact = true;
    for (a, b) in back.pixels.iter().zip(&img.pixels) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-4 * b[k].abs() + 1e-38, "{a:?} vs {b:?}");
            exact &= a[k] == b[k];
        }
    }
    assert!(!exact, "pxr24 rounds f32 mantissas");
}

fn paper_display_image(display: &Display) -> (RgbImage, Option<Vec<f32>>) {
    let scene = Scene::paper();
    with_fields(&scene, BackendChoice::Analytic, |f| {
        render_display_image_with_depth(
            display,
            Method::LensletCenter,
            &DisplayRenderSettings::default(),
            f.with_depth,
            &Progress::hidden(),
        )
    })
    .unwrap()
}

#[test]
fn the_papers_display_image_compresses_to_under_a_third() {
    // The issue's case: the paper's 2160 x 2160 LC display image with its Z channel.
    let display = Display::paper();
    let (img, depth) = paper_display_image(&display);
    let dir = tempfile::tempdir().unwrap();
    let size = |c: ExrCompression| {
        let p = dir.path().join(format!("display_{c}.exr"));
        write_rgb_with(&p, &img, depth.as_deref(), &typed(), c).unwrap();
        std::fs::metadata(&p).unwrap().len()
    };
    let (none, zip) = (size(ExrCompression::None), size(ExrCompression::Zip));
    // Four f32 channels: the uncompressed file is the samples plus a small header.
    assert!(none >= (2160 * 2160 * 16) as u64 && none < (2160 * 2160 * 16 + 200_000) as u64, "{none}");
    assert!(3 * zip <= none, "ZIP {zip} bytes is over a third of {none}");
    eprintln!("display_LC.exr: {none} bytes uncompressed, {zip} bytes ZIP ({:.1} %)", 100.0 * zip as f64 / none as f64);
}

/// The Python with OpenEXR's bindings: `$INIMTRACE_PYTHON`, the venv that
/// `scripts/install-deps.sh` makes under `target/`, `/tmp/venv-exr`, or `python3`.
fn python_with_openexr() -> Result<PathBuf, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut candidates: Vec<PathBuf> = std::env::var_os("INIMTRACE_PYTHON").map(PathBuf::from).into_iter().collect();
    candidates.extend([root.join("target/venv-exr/bin/python"), PathBuf::from("/tmp/venv-exr/bin/python")]);
    candidates.push(PathBuf::from("python3"));
    let mut tried = Vec::new();
    for py in candidates {
        match Command::new(&py).args(["-c", "import OpenEXR, numpy"]).output() {
            Ok(o) if o.status.success() => return Ok(py),
            Ok(_) => tried.push(format!("{} (no OpenEXR/numpy module)", py.display())),
            Err(e) => tried.push(format!("{} ({e})", py.display())),
        }
    }
    Err(format!("no python with OpenEXR and numpy: tried {}", tried.join(", ")))
}

const READER: &str = r#"
import json, sys
import numpy as np
import OpenEXR
f = OpenEXR.File(sys.argv[1])
h = f.header()
out = {}
for k, v in h.items():
    if not k.startswith("inimtrace:") and k != "software":
        continue
    if isinstance(v, str):
        out[k] = ["string", v]
    elif isinstance(v, int):
        out[k] = ["int", v]
    elif isinstance(v, float):
        out[k] = ["float", v]
    elif isinstance(v, np.ndarray) and v.dtype == np.float64 and v.size == 1:
        out[k] = ["double", float(v[0])]
    else:
        out[k] = ["other", repr(v)]
out["compression"] = ["compression", str(h["compression"])]
ch = f.channels()
rgb = ch["RGB"].pixels
out["rgb_shape"] = ["shape", list(rgb.shape)]
out["rgb_dtype"] = ["dtype", str(rgb.dtype)]
open(sys.argv[2], "wb").write(np.ascontiguousarray(rgb, dtype=np.float32).tobytes())
print(json.dumps(out))
"#;

#[test]
fn openexr_python_bindings_read_back_types_values_and_pixels() {
    let py = match python_with_openexr() {
        Ok(p) => p,
        Err(why) => {
            assert!(std::env::var_os("INIMTRACE_REQUIRE_OPENEXR").is_none(), "INIMTRACE_REQUIRE_OPENEXR is set: {why}");
            eprintln!("SKIPPED openexr_python_bindings_read_back_types_values_and_pixels: {why}");
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let (img, depth) = image(53, 29);
    let path = dir.path().join("typed.exr");
    write_rgb_with(&path, &img, Some(&depth), &typed(), ExrCompression::Zip).unwrap();
    let raw = dir.path().join("rgb.f32");
    let script = dir.path().join("read.py");
    std::fs::write(&script, READER).unwrap();
    let out = Command::new(&py).arg(&script).arg(&path).arg(&raw).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let get = |k: &str| (v[k][0].as_str().unwrap_or("missing").to_string(), v[k][1].clone());
    // An f64 is a `float` (its nearest f32) with its exact value beside it as text.
    assert_eq!(get("inimtrace:focus_mm"), ("float".into(), serde_json::json!(300.0)));
    assert_eq!(get("inimtrace:focus_mm.exact"), ("string".into(), serde_json::json!("300.0")));
    let third: f64 = 1000.0 / 300.0;
    assert_eq!(get("inimtrace:focus_diopters"), ("float".into(), serde_json::json!(third as f32 as f64)));
    let exact = get("inimtrace:focus_diopters.exact").1;
    assert_eq!(exact.as_str().unwrap().parse::<f64>().unwrap().to_bits(), third.to_bits(), "{exact}");
    assert_eq!(get("inimtrace:half_float_note"), ("float".into(), serde_json::json!(0.25)));
    assert_eq!(get("inimtrace:pupil_samples"), ("int".into(), serde_json::json!(52)));
    assert_eq!(get("inimtrace:method"), ("string".into(), serde_json::json!("LA (5x5)")));
    assert_eq!(get("inimtrace:git_revision"), ("string".into(), serde_json::json!(inimtrace::version::GIT_REVISION)));
    assert_eq!(get("software").1, serde_json::json!(inimtrace::version::software()));
    assert!(get("compression").1.as_str().unwrap().contains("ZIP"), "{v}");
    assert_eq!(get("rgb_shape").1, serde_json::json!([29, 53, 3]));
    // The pixels, row 0 at the top, bit for bit.
    let bytes = std::fs::read(&raw).unwrap();
    let ours: Vec<u8> = img.pixels.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    assert!(bytes == ours, "OpenEXR reads other pixels than inimtrace wrote");
}

#[test]
fn an_image_written_from_a_stack_view_equals_the_image_written_alone() {
    // `assess` writes display images straight from the interleaved stack: the file must hold
    // the same pixels (and Z) as writing the image itself.
    use inimtrace::raster::RgbView;
    let dir = tempfile::tempdir().unwrap();
    let (img, depth) = image(53, 29);
    let (other, _) = image(53, 29);
    // Interleave [other, img, other] per pixel: img is slot 1 of 3.
    let mut values = Vec::new();
    for (a, b) in other.pixels.iter().zip(&img.pixels) {
        values.extend_from_slice(a);
        values.extend_from_slice(b);
        values.extend_from_slice(&a.map(|v| v * 0.5));
    }
    let view = RgbView::strided(53, 29, &values, 9, 3).unwrap();
    assert!(RgbView::strided(53, 29, &values, 9, 7).is_none(), "offset + 3 beyond the stride");
    assert!(RgbView::strided(53, 30, &values, 9, 3).is_none(), "buffer too short");
    for c in [ExrCompression::None, ExrCompression::Zip, ExrCompression::Piz] {
        let a = dir.path().join(format!("view-{c}.exr"));
        let b = dir.path().join(format!("image-{c}.exr"));
        inimtrace::io::exr::write_view(&a, view, Some(&depth), &typed(), c).unwrap();
        write_rgb_with(&b, &img, Some(&depth), &typed(), c).unwrap();
        let (va, za) = read_rgb_depth(&a).unwrap();
        let (vb, zb) = read_rgb_depth(&b).unwrap();
        assert!(va == img && vb == img, "{c}");
        assert!(za.unwrap().iter().zip(zb.unwrap()).all(|(x, y)| x.to_bits() == y.to_bits()), "{c}: Z");
    }
    // A non-finite value in the view is refused, naming the pixel.
    let mut bad = values.clone();
    bad[(2 * 53 + 5) * 9 + 4] = f32::NAN;
    let view = RgbView::strided(53, 29, &bad, 9, 3).unwrap();
    let err = inimtrace::io::exr::write_view(&dir.path().join("bad.exr"), view, None, &typed(), ExrCompression::Zip)
        .unwrap_err()
        .to_string();
    assert!(err.contains("row 2, col 5"), "{err}");
}

const CHANNEL_DUMPER: &str = r#"
import json, os, sys
import numpy as np
import OpenEXR
f = OpenEXR.File(sys.argv[1], separate_channels=True)
h = f.header()
out = {"compression": str(h["compression"]), "channels": {}}
for name, ch in f.channels().items():
    px = ch.pixels
    out["channels"][name] = [str(px.dtype), list(px.shape)]
    open(os.path.join(sys.argv[2], name + ".f32"), "wb").write(np.ascontiguousarray(px, dtype="<f4").tobytes())
for k in ("inimtrace:focus_mm", "inimtrace:pupil_samples", "inimtrace:method"):
    v = h.get(k)
    out[k] = float(v[0]) if isinstance(v, np.ndarray) else v
print(json.dumps(out))
"#;

#[test]
fn openexr_python_bindings_read_inimtraces_zip_and_zips_blocks_bit_for_bit() {
    // inimtrace compresses ZIP and ZIPS blocks itself: OpenEXR's own reader must decode every
    // channel of them, Z included, to the written bits: odd sizes, heights that are not
    // multiples of 16, zeros, negatives and huge values, a constant image, incompressible
    // blocks stored raw.
    let py = match python_with_openexr() {
        Ok(p) => p,
        Err(why) => {
            assert!(std::env::var_os("INIMTRACE_REQUIRE_OPENEXR").is_none(), "INIMTRACE_REQUIRE_OPENEXR is set: {why}");
            eprintln!("SKIPPED openexr_python_bindings_read_inimtraces_zip_and_zips_blocks_bit_for_bit: {why}");
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("dump.py");
    std::fs::write(&script, CHANNEL_DUMPER).unwrap();
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut bits = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let v = f32::from_bits(state as u32);
        (state, if v.is_finite() { v } else { f32::from_bits(state as u32 ^ 0x4000_0000) })
    };
    let mut finite = |k: u64| {
        let (r, v) = bits();
        match (k + r) % 6 {
            0 => 0.0,
            1 => -1.5 * (r % 100) as f32,
            2 => f32::MAX,
            _ => v,
        }
    };
    let mut cases = Vec::new();
    for (w, h, depth) in [(67, 41, true), (1, 17, true), (130, 16, false), (5, 1, true)] {
        let mut img = RgbImage::new(w, h);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = [finite(k as u64), finite(k as u64 + 1), finite(k as u64 + 2)];
        }
        let z = depth.then(|| (0..w * h).map(|k| if k % 7 == 0 { f32::INFINITY } else { finite(k as u64) }).collect());
        cases.push((format!("random_{w}x{h}"), img, z));
    }
    // Random bit patterns do not deflate: these blocks are stored raw.
    let mut noise = RgbImage::new(40, 20);
    for p in noise.pixels.iter_mut() {
        *p = [bits().1, bits().1, bits().1];
    }
    cases.push(("noise_40x20".into(), noise, None));
    let (smooth, smooth_z) = image(53, 29);
    cases.push(("smooth_53x29".into(), smooth, Some(smooth_z)));
    let mut flat = RgbImage::new(31, 19);
    flat.pixels.iter_mut().for_each(|p| *p = [0.25, 0.5, 0.75]);
    cases.push(("constant_31x19".into(), flat, Some(vec![300.0; 31 * 19])));

    for (name, img, depth) in &cases {
        for (c, openexr_name) in [(ExrCompression::Zip, "ZIP_COMPRESSION"), (ExrCompression::Zips, "ZIPS_COMPRESSION")]
        {
            let path = dir.path().join(format!("{name}-{c}.exr"));
            write_rgb_with(&path, img, depth.as_deref(), &typed(), c).unwrap();
            if name.starts_with("noise") {
                // Stored raw, the file is the uncompressed file (one block per line) less the
                // offset and the chunk header (8 bytes each) of every line beyond one per block.
                let none = dir.path().join(format!("{name}-none.exr"));
                write_rgb_with(&none, img, depth.as_deref(), &typed(), ExrCompression::None).unwrap();
                let lines = if c == ExrCompression::Zip { 16 } else { 1 };
                let fewer = (img.height - img.height.div_ceil(lines)) as u64 * 16;
                let size = |p: &Path| std::fs::metadata(p).unwrap().len();
                assert_eq!(size(&path), size(&none) - fewer, "{name} {c}: blocks stored raw");
            }
            let out_dir = dir.path().join(format!("{name}-{c}"));
            std::fs::create_dir(&out_dir).unwrap();
            let out = Command::new(&py).arg(&script).arg(&path).arg(&out_dir).output().unwrap();
            assert!(out.status.success(), "{name} {c}: {}", String::from_utf8_lossy(&out.stderr));
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert!(v["compression"].as_str().unwrap().ends_with(openexr_name), "{name} {c}: {v}");
            assert_eq!(v["inimtrace:focus_mm"], serde_json::json!(300.0));
            assert_eq!(v["inimtrace:pupil_samples"], serde_json::json!(52));
            assert_eq!(v["inimtrace:method"], serde_json::json!("LA (5x5)"));
            let mut planes: Vec<(&str, Vec<f32>)> =
                (0..3).map(|k| (["R", "G", "B"][k], img.pixels.iter().map(|p| p[k]).collect())).collect();
            if let Some(z) = depth {
                planes.push(("Z", z.clone()));
            }
            let names: Vec<&str> = v["channels"].as_object().unwrap().keys().map(String::as_str).collect();
            assert_eq!(names.len(), planes.len(), "{name} {c}: channels {names:?}");
            for (channel, values) in planes {
                assert_eq!(
                    v["channels"][channel],
                    serde_json::json!(["float32", [img.height, img.width]]),
                    "{name} {c} {channel}"
                );
                let bytes = std::fs::read(out_dir.join(format!("{channel}.f32"))).unwrap();
                let ours: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
                assert!(bytes == ours, "{name} {c}: OpenEXR decodes other {channel} samples than inimtrace wrote");
            }
        }
    }
}

/// For every custom attribute of every file given: its classic `InputFile` type and value (an
/// `f64`'s value as its bits, to compare exactly) and, for `NAME.exact`, the bits of `float()`.
const CLASSIC_READER: &str = r#"
import json, struct, sys
import OpenEXR
bits = lambda x: struct.unpack("<Q", struct.pack("<d", x))[0]
out = {}
for path in sys.argv[1:]:
    h = OpenEXR.InputFile(path).header()
    rows = {}
    for k, v in h.items():
        if v is None:
            rows[k] = ["none", None]
        elif isinstance(v, bool):
            rows[k] = ["bool", v]
        elif isinstance(v, int):
            rows[k] = ["int", v]
        elif isinstance(v, float):
            rows[k] = ["float", bits(v)]
        elif isinstance(v, bytes) and k.endswith(".exact"):
            rows[k] = ["exact", bits(float(v.decode()))]
        elif isinstance(v, bytes):
            rows[k] = ["string", v.decode("latin-1")]
        else:
            rows[k] = ["other", type(v).__name__]
    out[path] = rows
print(json.dumps(out))
"#;

#[test]
fn the_classic_openexr_inputfile_api_reads_every_numeric_attribute_of_an_assess_run_as_a_number() {
    let py = match python_with_openexr() {
        Ok(p) => p,
        Err(why) => {
            assert!(std::env::var_os("INIMTRACE_REQUIRE_OPENEXR").is_none(), "INIMTRACE_REQUIRE_OPENEXR is set: {why}");
            eprintln!("SKIPPED the_classic_openexr_inputfile_api_reads_every_numeric_attribute: {why}");
            return;
        }
    };
    // A small converged run: display images, ground truth and retinal images with every
    // attribute `assess` writes (seed, replicates, budgets, provenance).
    let dir = tempfile::tempdir().unwrap();
    let files =
        small_assess_exrs(dir.path(), "paper-converged", &["LC", "LA"], &["measurement.max_samples_per_pixel=64"]);
    assert!(files.len() >= 5, "{files:?}");
    let script = dir.path().join("classic.py");
    std::fs::write(&script, CLASSIC_READER).unwrap();
    let out = Command::new(&py).arg(&script).args(&files).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut doubles = 0;
    for path in &files {
        let classic = &v[path.to_str().unwrap()];
        let kind = |k: &str| classic[k][0].as_str().unwrap_or("missing").to_string();
        // No attribute the classic API cannot read (it gives None for a type it does not know);
        // ours are numbers or strings (the standard ones are its own objects: channels, boxes).
        for (k, row) in classic.as_object().unwrap() {
            let ours = k.starts_with("inimtrace:") || k == "software";
            assert!(row[0] != "none" && !(ours && row[0] == "other"), "{}: {k} reads as {row}", path.display());
        }
        for (name, value) in read_typed_attributes(path).unwrap() {
            let at = format!("{}: {name}", path.display());
            match value {
                AttrValue::F64(x) => {
                    doubles += 1;
                    assert_eq!(kind(&name), "float", "{at}");
                    assert_eq!(classic[&name][1], serde_json::json!((x as f32 as f64).to_bits()), "{at}");
                    // The exact value: Python's float() of the text is the f64 inimtrace wrote.
                    assert_eq!(classic[format!("{name}.exact")][1], serde_json::json!(x.to_bits()), "{at}");
                }
                AttrValue::F32(x) => assert_eq!(classic[&name][1], serde_json::json!((x as f64).to_bits()), "{at}"),
                AttrValue::I32(x) => assert_eq!(classic[&name], serde_json::json!(["int", x]), "{at}"),
                AttrValue::Text(s) => assert_eq!(classic[&name], serde_json::json!(["string", s]), "{at}"),
            }
        }
    }
    assert!(doubles >= 5 * files.len(), "{doubles} f64 attributes in {} files", files.len());
}

/// OpenEXR's own `exrheader` (Debian's `openexr`, installed by `scripts/install-deps.sh`) reads
/// every f64 attribute inimtrace writes as a float, with its exact value as text beside it.
#[test]
fn openexrs_exrheader_reads_every_numeric_attribute_as_a_number() {
    let probe = Command::new("exrheader").arg("--version").output();
    if probe.is_err() {
        assert!(
            std::env::var_os("INIMTRACE_REQUIRE_OPENEXR").is_none(),
            "INIMTRACE_REQUIRE_OPENEXR is set: no exrheader"
        );
        eprintln!("SKIPPED openexrs_exrheader_reads_every_numeric_attribute_as_a_number: exrheader not found");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let files = small_assess_exrs(dir.path(), "paper", &["LA"], &[]);
    assert!(!files.is_empty());
    let mut doubles = 0;
    for path in &files {
        let out = Command::new("exrheader").arg(path).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8_lossy(&out.stdout);
        // `NAME (type TYPE): VALUE`, one line per attribute.
        let line = |name: &str| -> (String, String) {
            let head = format!("{name} (type ");
            let l = text
                .lines()
                .map(str::trim_start)
                .find(|l| l.starts_with(&head))
                .unwrap_or_else(|| panic!("{}: exrheader does not list {name}:\n{text}", path.display()));
            let rest = &l[head.len()..];
            let (ty, value) = rest.split_once("): ").unwrap();
            (ty.to_string(), value.trim().to_string())
        };
        for (name, value) in read_typed_attributes(path).unwrap() {
            if let AttrValue::F64(x) = value {
                doubles += 1;
                let (ty, shown) = line(&name);
                assert_eq!(ty, "float", "{}: {name}", path.display());
                let read: f64 = shown.parse().unwrap_or_else(|_| panic!("{name}: {shown}"));
                // exrheader prints six significant digits (printf's %g): the float within half a unit
                // of the sixth; the exact f64 is the text beside it.
                assert!((read - x).abs() <= 5e-6 * x.abs() + 1e-300, "{name}: {read} vs {x}");
                let (ty, exact) = line(&format!("{name}.exact"));
                assert_eq!(ty, "string");
                assert_eq!(exact.trim_matches('"').parse::<f64>().unwrap().to_bits(), x.to_bits(), "{name}.exact");
            }
        }
    }
    assert!(doubles >= 5 * files.len(), "{doubles} f64 attributes in {} files", files.len());
}

/// The EXR files, sorted, of a small `assess` of `experiments/EXPERIMENT.toml` into `dir/run`:
/// a 270 x 270 LCD, a 16 x 16 retina, one eye case focused at 2.5 D, `methods`, and `sets`.
fn small_assess_exrs(dir: &Path, experiment: &str, methods: &[&str], sets: &[&str]) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let methods = format!("methods=[{}]", methods.iter().map(|m| format!("\"{m}\"")).collect::<Vec<_>>().join(", "));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_inimtrace"));
    cmd.current_dir(root).args(["--quiet", "assess", &format!("experiments/{experiment}.toml"), "--out"]);
    cmd.arg(dir.join("run"));
    cmd.args(["--set", "display.lcd.resolution=[270, 270]", "--set", "eye.retina_resolution=16"]);
    cmd.args(["--set", "eye_cases=[{ name = \"Eye\", focus_diopters = 2.5 }]", "--set", &methods]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let out = cmd.output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join("run"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .collect();
    files.sort();
    files
}
