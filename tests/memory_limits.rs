//! The memory budget against the limits the system enforces (issue 24): a run under an
//! address-space limit (`prlimit --as`, as Slurm, containers and CI runners set limits) is
//! refused with one line naming RLIMIT_AS, never aborted; a huge but valid 8-bit texture is kept
//! at one byte a texel and renders within a small peak memory.

use std::path::Path;
use std::process::{Command, Output};

fn inimtrace() -> &'static str {
    env!("CARGO_BIN_EXE_inimtrace")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `/usr/bin/time -v` under `prlimit --as=<bytes>` running inimtrace `args`: the output and the
/// peak resident memory in bytes (the capped process is the timed one's child, which `time`
/// waits for, so its figure is inimtrace's).
fn run_limited(address_space: u64, args: &[&str]) -> (Output, u64) {
    for tool in ["/usr/bin/prlimit", "/usr/bin/time"] {
        assert!(Path::new(tool).exists(), "{tool} is missing: run scripts/install-deps.sh (util-linux, time)");
    }
    let o = Command::new("/usr/bin/time")
        .arg("-v")
        .arg("/usr/bin/prlimit")
        .arg(format!("--as={address_space}"))
        .arg(inimtrace())
        .args(args)
        .output()
        .expect("run inimtrace");
    let e = stderr(&o);
    let kib: u64 = e
        .lines()
        .find_map(|l| l.trim().strip_prefix("Maximum resident set size (kbytes):"))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no peak memory from /usr/bin/time: {e}"));
    (o, kib * 1024)
}

/// inimtrace's own lines of stderr (without `time`'s report, which follows them; a signal shows
/// there as "Command terminated by signal").
fn own_lines(o: &Output) -> Vec<String> {
    let time = |l: &str| {
        l.starts_with("Command exited") || l.starts_with("Command terminated") || l.contains("Command being timed")
    };
    stderr(o).lines().take_while(|l| !time(l)).map(str::to_string).collect()
}

/// A `w x h` 8-bit grey PNG written row by row (a few hundred kB for 23000 x 23000).
fn write_grey_png(path: &Path, w: u32, h: u32) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, w, h);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    let mut row = vec![0u8; w as usize];
    for y in 0..h {
        // Bands of grey, so the render shows the texture (not one flat value).
        row.fill(if (y / 1000) % 2 == 0 { 200 } else { 40 });
        std::io::Write::write_all(&mut stream, &row).unwrap();
    }
    stream.finish().unwrap();
}

#[test]
fn a_23000_squared_grey_png_texture_renders_in_little_memory_under_an_8_gib_address_space() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("big.png");
    write_grey_png(&png, 23000, 23000);
    let size = std::fs::metadata(&png).unwrap().len();
    assert!(size < 4 << 20, "the PNG is {size} bytes");
    let scene = inimtrace::fixtures::textured_quad_scene(dir.path(), "big texture", "big.png").unwrap();
    let out = dir.path().join("gt.exr");
    let args = inimtrace::fixtures::pinhole_ground_truth_args(&scene, &out);
    let (o, peak) = run_limited(8 << 30, &args);
    eprintln!("23000 x 23000 grey texture: exit {:?}, peak RSS {} MiB", o.status.code(), peak >> 20);
    let lines = own_lines(&o);
    match o.status.code() {
        // Rendered: the texture at one byte a texel (529 MB), not 24 (12.7 GB).
        Some(0) => {
            assert!(peak < 2 << 30, "peak RSS {peak} bytes");
            assert!(out.exists());
            let img = inimtrace::io::exr::read_rgb(&out).unwrap();
            let px: Vec<f32> = img.pixels.iter().map(|p| p[0]).collect();
            let (lo, hi) = px.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            // Both bands of grey show: sRGB 40 and 200, linearised.
            assert!(lo < 0.03 && hi > 0.5, "retina values {lo}..{hi}");
        }
        // Or refused before decoding: one line, exit 1, not a signal.
        Some(1) => {
            assert_eq!(lines.len(), 1, "{lines:?}");
            assert!(lines[0].starts_with("error: ") && lines[0].contains("big.png"), "{lines:?}");
            assert!(peak < 1 << 30, "refused after decoding? peak RSS {peak} bytes");
        }
        c => panic!("ended by {c:?} / {:?}: {}", o.status, stderr(&o)),
    }
}

#[test]
fn the_default_budget_under_an_address_space_limit_refuses_a_paper_sized_run_naming_rlimit_as() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper");
    // The paper's experiment (the built-in default) needs about 375 MiB (and runs under
    // `prlimit --as=512M`); 300 MB of address space, about 60 MB of it mapped at the start, leaves
    // less. Without reading RLIMIT_AS the budget would be MemAvailable, the run would start and
    // the allocator would abort.
    let (o, _) = run_limited(300_000_000, &["--quiet", "assess", "--out", out.to_str().unwrap()]);
    let lines = own_lines(&o);
    assert_eq!(o.status.code(), Some(1), "{:?}: {}", o.status, stderr(&o));
    assert_eq!(lines.len(), 1, "{lines:?}");
    let line = &lines[0];
    assert!(line.starts_with("error: ") && line.contains("RLIMIT_AS") && line.contains("prlimit --as"), "{line}");
    assert!(line.contains("would need about"), "{line}");
    assert!(!out.join("results.json").exists());
}
