//! Hostile inputs (issue: never crash, never hang, never eat the machine): small crafted files
//! that claim huge sizes, FIFOs, closed pipes. Each must end with one clear line naming the file,
//! within a small memory cap, never a panic or an abort.

use std::path::Path;
use std::process::{Command, Output, Stdio};

fn inimtrace() -> &'static str {
    env!("CARGO_BIN_EXE_inimtrace")
}

/// Runs `inimtrace args` with its address space capped at `cap_mb` MB (`ulimit -v`), so that an
/// allocation the estimate should have refused aborts the child instead of passing unnoticed.
fn run_capped(cap_mb: u64, args: &[&str]) -> Output {
    let mut cmd = String::from("ulimit -v ");
    cmd.push_str(&(cap_mb * 1024).to_string());
    cmd.push_str("; exec \"$0\" \"$@\"");
    Command::new("bash").arg("-c").arg(cmd).arg(inimtrace()).args(args).output().expect("run inimtrace")
}

/// `ground-truth` of a 16 x 16 pinhole retina of `scene`, written to `out`.
fn gt_args<'a>(scene: &'a Path, out: &'a Path) -> Vec<&'a str> {
    inimtrace::fixtures::pinhole_ground_truth_args(scene, out)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_clean_failure(o: &Output, must_name: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "expected a clean error exit, got {:?}: {e}", o.status);
    assert!(!e.contains("panicked") && !e.contains("memory allocation"), "{e}");
    assert!(e.contains(must_name), "error does not name {must_name}: {e}");
}

#[test]
fn an_exr_header_claiming_a_huge_image_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let bomb = dir.path().join("bomb.exr");
    std::fs::write(&bomb, inimtrace::fixtures::exr_header_bomb(1_000_000_000, 1_000_000_000)).unwrap();
    assert!(std::fs::metadata(&bomb).unwrap().len() < 1000);
    let p = bomb.to_str().unwrap();
    let o = run_capped(1024, &["compare", p, p]);
    assert_clean_failure(&o, "bomb.exr");
    assert!(stderr(&o).contains("memory limit"), "{}", stderr(&o));
    // A plausible size whose pixels are simply not in the file: truncated, not allocated.
    let small = dir.path().join("claims.exr");
    std::fs::write(&small, inimtrace::fixtures::exr_header_bomb(4000, 4000)).unwrap();
    let s = small.to_str().unwrap();
    let o = run_capped(1024, &["simulate", s, "--pinhole", "--out", dir.path().join("x.exr").to_str().unwrap()]);
    assert_clean_failure(&o, "claims.exr");
}

#[test]
fn a_fifo_as_input_is_an_error_not_a_hang() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("display.exr");
    if !Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false) {
        eprintln!("skipped: mkfifo is not available on this machine");
        return;
    }
    let p = fifo.to_str().unwrap();
    let o = Command::new("timeout").args(["20", inimtrace(), "compare", p, p]).output().unwrap();
    assert_ne!(o.status.code(), Some(124), "inimtrace hung on a FIFO");
    assert_clean_failure(&o, "display.exr");
}

#[test]
fn a_closed_stdout_ends_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.exr");
    let img = inimtrace::raster::RgbImage::filled(16, 16, [0.5, 0.25, 1.0]);
    inimtrace::io::exr::write_rgb(&a, &img, None, &[]).unwrap();
    let p = a.to_str().unwrap();
    // `inimtrace info --print paper-scene | true`: the reader is gone before the writer writes.
    for args in [vec!["compare", p, p], vec!["info", "--print", "paper-experiment"]] {
        let mut child =
            Command::new(inimtrace()).args(&args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let code = o.status.code();
        assert!(code == Some(0) || code == Some(141), "{args:?}: exit {:?}: {}", o.status, stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    }
    let _ = Path::new(p);
}

/// The ring of assimp's test models in spirit: one concave polygon (a "C": an outer arc out and
/// an inner arc back) facing the eye at 100 mm, written as OBJ and PLY.
fn ring_polygon() -> Vec<[f64; 2]> {
    let (gap, n) = (0.4, 24);
    let arc = |r: f64, i: usize| {
        let phi = gap + (std::f64::consts::TAU - 2.0 * gap) * i as f64 / n as f64;
        [r * phi.cos(), r * phi.sin()]
    };
    let mut p: Vec<[f64; 2]> = (0..=n).map(|i| arc(25.0, i)).collect();
    p.extend((0..=n).rev().map(|i| arc(12.0, i)));
    p
}

/// Even-odd point-in-polygon: the exact reference of which pixel centres see the ring.
fn inside(poly: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut odd = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            odd = !odd;
        }
    }
    odd
}

#[test]
fn a_concave_polygon_renders_as_itself_not_as_its_fan() {
    use inimtrace::optics::{Eye, Retina};
    use inimtrace::progress::Progress;
    use inimtrace::render::{ground_truth, with_fields, BackendChoice};
    let dir = tempfile::tempdir().unwrap();
    let poly = ring_polygon();
    let n = poly.len();
    let mut obj = String::new();
    for p in &poly {
        obj.push_str(&format!("v {} {} 100\n", p[0], p[1]));
    }
    obj.push('f');
    for i in 1..=n {
        obj.push_str(&format!(" {i}"));
    }
    obj.push('\n');
    std::fs::write(dir.path().join("ring.obj"), obj).unwrap();
    let mut ply = format!("ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n");
    for p in &poly {
        ply.push_str(&format!("{} {} 100\n", p[0], p[1]));
    }
    ply.push_str(&format!("{n}"));
    for i in 0..n {
        ply.push_str(&format!(" {i}"));
    }
    ply.push('\n');
    std::fs::write(dir.path().join("ring.ply"), ply).unwrap();

    let retina = Retina { resolution: 64, half_tangent: 0.3, samples_per_pixel: 1 };
    let eye = Eye::pinhole();
    let mut exact = inimtrace::raster::RgbImage::new(64, 64);
    for r in 0..64 {
        for c in 0..64 {
            let t = retina.tangent(r, c, glam::DVec2::splat(0.5));
            if inside(&poly, 100.0 * t.x, 100.0 * t.y) {
                exact.set(r, c, [1.0, 1.0, 1.0]);
            }
        }
    }
    for file in ["ring.obj", "ring.ply"] {
        let scene_path = dir.path().join("scene.toml");
        std::fs::write(
            &scene_path,
            format!("name = \"ring\"\n[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\nmaterial = {{ albedo = [1, 1, 1] }}\n"),
        )
        .unwrap();
        let scene = inimtrace::io::load_scene(&scene_path.to_string_lossy(), Path::new("")).unwrap();
        let img =
            with_fields(&scene, BackendChoice::Bvh, |f| Ok(ground_truth(&eye, &retina, f.shade, &Progress::hidden())))
                .unwrap();
        let differing = img.pixels.iter().zip(&exact.pixels).filter(|(a, b)| (a[0] - b[0]).abs() > 1e-6).count();
        // Pixel centres exactly on an edge may go either way; a filled fan differs by hundreds.
        assert!(differing <= 2, "{file}: {differing} of 4096 pixels differ from the exact ring");
        let hole = img.get(32, 32);
        assert_eq!(hole, [0.0, 0.0, 0.0], "{file}: the ring's hole is filled");
    }
}

fn write_experiment(dir: &Path, name: &str, extra: &str) -> std::path::PathBuf {
    let p = dir.join("exp.toml");
    std::fs::write(
        &p,
        format!(
            "name = \"{name}\"\nscene = \"builtin:paper\"\ndisplay = \"builtin:paper\"\nmethods = [\"LC\"]\n\
             [eye]\nretina_resolution = 16\n{extra}\n[[eye_cases]]\nname = \"Pin\"\npinhole = true\n"
        ),
    )
    .unwrap();
    p
}

#[test]
fn names_cannot_write_outside_the_output_folder() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["../escape", "/tmp/abs", "a/b", "..", ""] {
        let exp = write_experiment(dir.path(), name, "");
        let o = Command::new(inimtrace())
            .current_dir(dir.path())
            .args(["--quiet", "assess", exp.to_str().unwrap()])
            .output()
            .unwrap();
        assert_clean_failure(&o, "name");
    }
    assert!(!dir.path().join("escape").exists() && !dir.path().parent().unwrap().join("escape").exists());
}

#[test]
fn settings_outside_the_valid_ranges_are_errors_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    // A focus of 1e-310 mm made every image black and scored PSNR inf; a retina distance of
    // 1e-12 mm or a reference plane at -1e12 mm silently changed images.
    for (extra, field) in [
        ("retina_distance = 1e-12", "retina_distance"),
        ("[display_render]\nreference_plane_z = -1e12", "reference_plane_z"),
    ] {
        let exp = write_experiment(dir.path(), "r", extra);
        let o = Command::new(inimtrace())
            .current_dir(dir.path())
            .args(["--quiet", "assess", exp.to_str().unwrap()])
            .output()
            .unwrap();
        assert_clean_failure(&o, field);
    }
    let o = Command::new(inimtrace())
        .current_dir(dir.path())
        .args(["--quiet", "ground-truth", "--focus-mm", "1e-310", "--retina", "16", "--out", "gt.exr"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "focus_mm");
    assert!(!dir.path().join("gt.exr").exists());
}

#[test]
fn absurd_thread_counts_and_misnamed_outputs_are_refused_before_work() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(inimtrace()).args(["--threads", "100000", "info"]).output().unwrap();
    assert_clean_failure(&o, "--threads");
    let png = dir.path().join("x.png");
    let o = Command::new(inimtrace())
        .args(["--quiet", "render-display", "--method", "LC", "--out", png.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(".exr"), "{}", stderr(&o));
    assert!(!png.exists(), "the PNG preview path was written");
}

#[test]
fn a_png_texture_claiming_a_huge_image_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bomb.png"), inimtrace::fixtures::png_header_bomb(200_000, 200_000)).unwrap();
    let scene = inimtrace::fixtures::textured_quad_scene(dir.path(), "bomb", "bomb.png").unwrap();
    let out = dir.path().join("gt.exr");
    let o = run_capped(1024, &[&["--max-memory", "8G"][..], &gt_args(&scene, &out)].concat());
    assert_clean_failure(&o, "bomb.png");
    assert!(stderr(&o).contains("memory limit"), "{}", stderr(&o));
}

#[test]
fn generated_and_mesh_geometry_cannot_overflow_or_loop() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    // 2^32 x 2^32 spheres wraps to 0 in unchecked 64-bit arithmetic.
    std::fs::write(
        &scene,
        "name = \"s\"\n[[objects]]\ntype = \"sphere-grid\"\ncenter = [0, 0, 400]\ncount = [4294967296, 4294967296]\n\
         spacing = 1.0\nradius = 0.4\nmaterial = { albedo = [1, 1, 1] }\n",
    )
    .unwrap();
    let out = dir.path().join("gt.exr");
    let args = gt_args(&scene, &out);
    let o = run_capped(1024, &args);
    assert_clean_failure(&o, "count");
    // Within the triangle cap but over a small memory limit: refused, naming the setting.
    std::fs::write(
        &scene,
        "name = \"s\"\n[[objects]]\ntype = \"sphere-grid\"\ncenter = [0, 0, 400]\ncount = [1000, 1000]\n\
         spacing = 1.0\nradius = 0.4\nsegments = 8\nmaterial = { albedo = [1, 1, 1] }\n",
    )
    .unwrap();
    let mut limited = vec!["--max-memory", "200M"];
    limited.extend_from_slice(&args);
    let o = run_capped(1024, &limited);
    assert_clean_failure(&o, "count");
    assert!(stderr(&o).contains("memory"), "{}", stderr(&o));
    // A PLY header claiming 10^12 vertices (or an element with no properties) in a tiny file.
    for header in [
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
        "ply\nformat binary_little_endian 1.0\nelement junk 1000000000000\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
    ] {
        let ply = dir.path().join("bomb.ply");
        std::fs::write(&ply, header).unwrap();
        let e = inimtrace::io::load_mesh(&ply).unwrap_err().to_string();
        assert!(e.contains("bomb.ply") && (e.contains("truncated") || e.contains("no properties")), "{e}");
    }
}

#[test]
fn every_error_names_its_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    // A radiance that overflows 32-bit float images: refused where it is set, not reported
    // later as "a bug in the renderer" at a pixel.
    let scene = dir.path().join("bright.toml");
    std::fs::write(
        &scene,
        "name = \"b\"\nbackground = [1e308, 1e308, 1e308]\n[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 400]\n\
         size = [10, 10]\nmaterial = { albedo = [1, 1, 1] }\n",
    )
    .unwrap();
    let out = dir.path().join("gt.exr");
    let o = Command::new(inimtrace()).args(gt_args(&scene, &out)).output().unwrap();
    assert_clean_failure(&o, "bright.toml");
    assert!(stderr(&o).contains("background"), "{}", stderr(&o));
    // PupilCenter exactly singular: the experiment file, the method and the display are named.
    let display = dir.path().join("singular.toml");
    let v2 = 1.0 / (1.0 / 6.427 - 1.0 / 20.0);
    std::fs::write(
        &display,
        format!(
            "name = \"s\"\neye_to_lenslets = 20.0\nlenslets_to_lcd = {v2}\n[lenslets]\nfocal_length = 6.427\nshift = [0.0, 0.0]\n\
             pitch = 1.2\n[elemental_images]\nshift = [0.0, 0.0]\npitch = 1.58\n[lcd]\nsize = [21.6, 21.6]\nresolution = [64, 64]\n"
        ),
    )
    .unwrap();
    let exp = dir.path().join("pc.toml");
    std::fs::write(
        &exp,
        "name = \"pc\"\nscene = \"builtin:paper\"\ndisplay = \"singular.toml\"\nmethods = [\"LC\", \"PC\"]\n[eye]\nretina_resolution = 16\n\
         [[eye_cases]]\nname = \"Pin\"\npinhole = true\n",
    )
    .unwrap();
    let o = Command::new(inimtrace())
        .current_dir(dir.path())
        .args(["--quiet", "assess", exp.to_str().unwrap()])
        .output()
        .unwrap();
    assert_clean_failure(&o, "pc.toml");
    let e = stderr(&o);
    assert!(e.contains("methods[1]") && e.contains("singular.toml") && e.contains("PupilCenter"), "{e}");
}

fn paper_grid() -> String {
    format!("{}/experiments/paper.toml", env!("CARGO_MANIFEST_DIR"))
}

/// Every final-named file in `dir` is complete: EXRs and PNGs decode; and `results.json`, when
/// present, lists files that match their sizes and checksums.
fn assert_no_incomplete_files(dir: &Path) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let p = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        match p.extension().and_then(|e| e.to_str()) {
            Some("exr") => {
                inimtrace::io::exr::read_rgb(&p).unwrap_or_else(|e| panic!("incomplete EXR under its final name: {e}"));
            }
            Some("png") => {
                image::open(&p).unwrap_or_else(|e| panic!("incomplete PNG {name}: {e}"));
            }
            _ => {}
        }
    }
    if let Ok(text) = std::fs::read_to_string(dir.join("results.json")) {
        let v: serde_json::Value = serde_json::from_str(&text).expect("results.json is complete JSON");
        let files: Vec<inimtrace::io::output::OutputFile> = serde_json::from_value(v["files"].clone()).unwrap();
        assert!(files.len() > 30, "the manifest lists every file");
        inimtrace::io::output::verify(dir, &files).unwrap();
    }
}

#[test]
fn a_killed_run_leaves_nothing_that_looks_complete() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let exp = paper_grid();
    let mut killed_mid_run = 0;
    for delay_ms in [50u64, 300, 800, 1500, 2200] {
        let mut child = Command::new(inimtrace())
            .args(["--quiet", "assess", &exp, "--out", out.to_str().unwrap()])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let finished = child.try_wait().unwrap().is_some();
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        if !finished {
            killed_mid_run += 1;
            // A results.json left by an earlier complete run is removed before anything else
            // is written, so a killed run never stands next to one that does not describe it.
            if out.join(".inimtrace.lock").exists() && out.join("display_LC.exr").exists() {
                let report = std::fs::read_to_string(out.join("results.json")).unwrap_or_default();
                assert!(report.is_empty() || report.contains("\"files\""), "stale report");
            }
        }
        assert_no_incomplete_files(&out);
    }
    assert!(killed_mid_run >= 3, "only {killed_mid_run} kills happened while the run was working");
}

#[test]
fn a_second_run_into_the_same_folder_fails_at_once_and_the_first_completes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let exp = paper_grid();
    let first = Command::new(inimtrace())
        .args(["--quiet", "assess", &exp, "--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the first run owns the folder.
    let lock = out.join(".inimtrace.lock");
    for _ in 0..200 {
        if std::fs::read_to_string(&lock).map(|t| t.contains("inimtrace process")).unwrap_or(false) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let t = std::time::Instant::now();
    let second =
        Command::new(inimtrace()).args(["--quiet", "assess", &exp, "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(t.elapsed().as_secs_f64() < 1.5, "the second run did not fail at once");
    assert_clean_failure(&second, "in use by inimtrace process");
    let first = first.wait_with_output().unwrap();
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(out.join("results.json").exists());
    assert_no_incomplete_files(&out);
}

#[test]
fn a_full_filesystem_ends_with_an_error_and_no_report() {
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("small");
    std::fs::create_dir(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=3m", "tmpfs", mnt.to_str().unwrap()])
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !mounted {
        eprintln!("skipped: cannot mount a small tmpfs here (needs root; CI runs as root)");
        return;
    }
    let out = mnt.join("out");
    let o =
        Command::new(inimtrace()).args(["--quiet", "assess", &paper_grid(), "--out", out.to_str().unwrap()]).output();
    let listing: Vec<String> = std::fs::read_dir(&out)
        .map(|d| d.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    let complete_check = std::panic::catch_unwind(|| assert_no_incomplete_files(&out));
    let _ = Command::new("umount").arg(&mnt).status();
    let o = o.unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("No space left") && e.contains("out"), "{e}");
    assert!(!listing.iter().any(|n| n == "results.json"), "a results.json on a full disk: {listing:?}");
    assert!(!listing.iter().any(|n| n.starts_with(".inimtrace-tmp-")), "temporary files left: {listing:?}");
    complete_check.expect("a final-named file is incomplete");
}

#[test]
fn accepted_sizes_that_do_not_fit_in_memory_are_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let display = dir.path().join("huge.toml");
    std::fs::write(
        &display,
        "name = \"huge\"\neye_to_lenslets = 20.0\nlenslets_to_lcd = 6.316\n[lenslets]\nfocal_length = 6.427\nshift = [0.0, 0.0]\n\
         pitch = 1.2\n[elemental_images]\nshift = [0.0, 0.0]\npitch = 1.58\n[lcd]\nsize = [21.6, 21.6]\nresolution = [30000, 30000]\n",
    )
    .unwrap();
    let out = dir.path().join("d.exr");
    let o = run_capped(
        1024,
        &[
            "--quiet",
            "--max-memory",
            "2G",
            "render-display",
            "--display",
            display.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_clean_failure(&o, "lcd.resolution");
    let o = run_capped(
        1024,
        &[
            "--quiet",
            "--max-memory",
            "2G",
            "ground-truth",
            "--pinhole",
            "--retina",
            "32768",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_clean_failure(&o, "--retina");
    // The same display in an experiment: refused by `assess` before any work.
    let exp = dir.path().join("exp.toml");
    std::fs::write(&exp, "name = \"huge\"\ndisplay = \"huge.toml\"\n[[eye_cases]]\nname = \"Pin\"\npinhole = true\n")
        .unwrap();
    let o = run_capped(
        1024,
        &[
            "--quiet",
            "--max-memory",
            "2G",
            "assess",
            exp.to_str().unwrap(),
            "--out",
            dir.path().join("o").to_str().unwrap(),
        ],
    );
    assert_clean_failure(&o, "lcd.resolution");
    assert!(!dir.path().join("o").join("results.json").exists());
}
