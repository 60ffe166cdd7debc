//! Proptest-driven fuzzing of every file reader: the shipped example files, mutated (bytes
//! flipped, lines dropped or duplicated, numbers replaced by NaN / huge / negative values,
//! truncation), must load or fail with an error naming the file — never panic. The ordinary test
//! run tries a few hundred cases per reader; `scripts/fuzz.sh` runs many more for a bounded time
//! (set `PROPTEST_CASES`). Every crash found is kept below as a regression test.
#![deny(unsafe_code)]

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use proptest::prelude::*;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[derive(Clone, Debug)]
enum Mutation {
    Flip(usize, u8),
    Truncate(usize),
    DropLine(usize),
    DuplicateLine(usize),
    ReplaceToken(usize, &'static str),
    Insert(usize, &'static str),
}

const TOKENS: [&str; 14] =
    ["nan", "inf", "-inf", "-1", "0", "1e400", "-1e20", "[", "]", "\"", "=", "\n", "18446744073709551616", "[[x]]"];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Flip(i, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        any::<usize>().prop_map(Mutation::DropLine),
        any::<usize>().prop_map(Mutation::DuplicateLine),
        (any::<usize>(), prop::sample::select(TOKENS.to_vec())).prop_map(|(i, t)| Mutation::ReplaceToken(i, t)),
        (any::<usize>(), prop::sample::select(TOKENS.to_vec())).prop_map(|(i, t)| Mutation::Insert(i, t)),
    ]
}

fn apply(mut bytes: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        let n = bytes.len().max(1);
        match m {
            Mutation::Flip(i, b) => {
                if !bytes.is_empty() {
                    bytes[i % n] ^= b | 1;
                }
            }
            Mutation::Truncate(i) => bytes.truncate(i % n),
            Mutation::DropLine(i) | Mutation::DuplicateLine(i) => {
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let mut lines: Vec<&str> = text.lines().collect();
                if !lines.is_empty() {
                    let k = i % lines.len();
                    if matches!(m, Mutation::DropLine(_)) {
                        lines.remove(k);
                    } else {
                        lines.insert(k, lines[k]);
                    }
                }
                bytes = lines.join("\n").into_bytes();
            }
            Mutation::ReplaceToken(i, t) => {
                // Replace the i-th number-like token.
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let spans: Vec<(usize, usize)> = text
                    .char_indices()
                    .filter(|(_, c)| c.is_ascii_digit())
                    .map(|(p, _)| p)
                    .fold(Vec::new(), |mut acc: Vec<(usize, usize)>, p| {
                        match acc.last_mut() {
                            Some(last) if last.1 == p => last.1 = p + 1,
                            _ => acc.push((p, p + 1)),
                        }
                        acc
                    });
                if !spans.is_empty() {
                    let (a, b) = spans[i % spans.len()];
                    bytes = format!("{}{}{}", &text[..a], t, &text[b..]).into_bytes();
                }
            }
            Mutation::Insert(i, t) => {
                let k = i % (bytes.len() + 1);
                bytes.splice(k..k, t.bytes());
            }
        }
    }
    bytes
}

/// Writes the mutated file beside a copy of its neighbours (so relative paths still resolve)
/// and runs `load`; it must not panic, and an error must name the file.
fn check(seed: &Path, muts: &[Mutation], load: impl Fn(&Path) -> Result<(), String>) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let name = seed.file_name().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, apply(std::fs::read(seed).unwrap(), muts)).unwrap();
    // Neighbours the file may reference (textures, materials).
    if let Some(parent) = seed.parent() {
        for entry in std::fs::read_dir(parent).unwrap().flatten() {
            let p = entry.path();
            if p.is_file() && p.file_name() != Some(name) {
                let _ = std::fs::copy(&p, dir.path().join(p.file_name().unwrap()));
            }
        }
    }
    let outcome = catch_unwind(AssertUnwindSafe(|| load(&path)));
    match outcome {
        Err(_) => Err(TestCaseError::fail(format!("panicked on {muts:?}"))),
        Ok(Err(msg)) => {
            prop_assert!(
                msg.contains(name.to_str().unwrap()) || msg.contains("built-in"),
                "error must name the file: {msg}"
            );
            Ok(())
        }
        Ok(Ok(())) => Ok(()),
    }
}

fn experiment(p: &Path) -> Result<(), String> {
    inimtrace::experiment::Experiment::load(p).map(|_| ()).map_err(|e| e.to_string())
}
fn display(p: &Path) -> Result<(), String> {
    inimtrace::io::load_display(&p.to_string_lossy(), Path::new("")).map(|_| ()).map_err(|e| e.to_string())
}
fn scene(p: &Path) -> Result<(), String> {
    inimtrace::io::load_scene(&p.to_string_lossy(), Path::new("")).map(|_| ()).map_err(|e| e.to_string())
}
fn mesh(p: &Path) -> Result<(), String> {
    inimtrace::io::load_mesh(p).map(|_| ()).map_err(|e| e.to_string())
}
/// A few hundred cases per reader in the ordinary test run; `PROPTEST_CASES` for more.
fn config() -> ProptestConfig {
    ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

fn exr(p: &Path) -> Result<(), String> {
    inimtrace::io::exr::read_rgb(p).map(|_| ()).map_err(|e| e.to_string())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn fuzz_experiment_toml(m in prop::collection::vec(mutation(), 1..4)) {
        // The experiment names scene and display files relative to itself: point them at built-ins.
        let dir = tempfile::tempdir().unwrap();
        let seed = dir.path().join("paper.toml");
        let text = std::fs::read_to_string(root().join("experiments/paper.toml")).unwrap()
            .replace("../scenes/paper.toml", "builtin:paper").replace("../displays/paper.toml", "builtin:paper");
        std::fs::write(&seed, text).unwrap();
        check(&seed, &m, experiment)?;
    }

    #[test]
    fn fuzz_display_toml(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("displays/paper.toml"), &m, display)?;
    }

    #[test]
    fn fuzz_display_yaml(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("data/lensletdisplay.yaml"), &m, display)?;
    }

    #[test]
    fn fuzz_scene_toml(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("scenes/paper.toml"), &m, scene)?;
    }

    #[test]
    fn fuzz_obj(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid.obj"), &m, mesh)?;
    }

    #[test]
    fn fuzz_ply_ascii(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid_ascii.ply"), &m, mesh)?;
    }

    #[test]
    fn fuzz_ply_binary(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid_le.ply"), &m, mesh)?;
    }

    #[test]
    fn fuzz_gltf(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid.gltf"), &m, mesh)?;
    }

    #[test]
    fn fuzz_glb(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid.glb"), &m, mesh)?;
    }

    #[test]
    fn fuzz_stl_ascii(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid_ascii.stl"), &m, mesh)?;
    }

    #[test]
    fn fuzz_stl_binary(m in prop::collection::vec(mutation(), 1..4)) {
        check(&root().join("tests/data/meshes/pyramid_binary.stl"), &m, mesh)?;
    }

    #[test]
    fn fuzz_exr(m in prop::collection::vec(mutation(), 1..3)) {
        let dir = tempfile::tempdir().unwrap();
        let seed = dir.path().join("seed.exr");
        let img = inimtrace::raster::RgbImage::filled(7, 5, [0.25, 0.5, 0.75]);
        inimtrace::io::exr::write_rgb(&seed, &img, None, &[("inimtrace:kind", "fuzz seed".into())]).unwrap();
        check(&seed, &m, exr)?;
    }
}

/// Regression (found by `fuzz_experiment_toml`): a mistyped `builtin:paper` became a missing
/// relative path and the error named only that path; it now names the experiment and field too.
#[test]
fn regression_mistyped_builtin_names_the_experiment_field() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("exp.toml");
    std::fs::write(&p, "name = \"x\"\nscene = \"cuiltin:paper\"\n[[eye_cases]]\nname = \"A\"\npinhole = true\n")
        .unwrap();
    let e = inimtrace::experiment::Experiment::load(&p).unwrap_err().to_string();
    assert!(e.contains("exp.toml") && e.contains("`scene`") && e.contains("cuiltin:paper"), "{e}");
}

/// Regression (found by `fuzz_experiment_toml`): an eye beyond the lenslets made PupilCenter's
/// check fail with a message that named neither the experiment file nor the field.
#[test]
fn regression_pupil_center_check_names_the_experiment_field() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("exp.toml");
    std::fs::write(
        &p,
        "name = \"x\"\nmethods = [\"PC\"]\n[eye]\nposition = [0.0, 0.0, 1e19]\n[[eye_cases]]\nname = \"A\"\npinhole = true\n",
    )
    .unwrap();
    let e = inimtrace::experiment::Experiment::load(&p).unwrap_err().to_string();
    assert!(e.contains("exp.toml") && e.contains("eye.position"), "{e}");
}

/// Regression (found by `fuzz_glb`): a POSITION accessor index past the end made gltf-json's
/// validation index out of bounds and panic; it is now an error naming the attribute.
#[test]
fn regression_gltf_position_accessor_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("tests/data/meshes/pyramid.gltf")).unwrap();
    let p = dir.path().join("bad.gltf");
    std::fs::write(&p, text.replacen("\"POSITION\": 0", "\"POSITION\": 9", 1)).unwrap();
    let e = inimtrace::io::load_mesh(&p).unwrap_err().to_string();
    assert!(e.contains("bad.gltf") && e.contains("attributes.POSITION") && e.contains("accessor 9"), "{e}");
}

// Header bombs: a few bytes claiming huge sizes. Every reader must refuse them (naming the file)
// before allocating: the memory limit is set to 256 MiB here, so an allocation of the claimed
// size would not pass unnoticed.
proptest! {
    #![proptest_config(config())]

    #[test]
    fn fuzz_exr_header_bombs(w in 1i32..i32::MAX, h in 1i32..i32::MAX, cut in 0usize..400) {
        inimtrace::budget::set_memory_limit(256 << 20);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bomb.exr");
        let mut bytes = inimtrace::fixtures::exr_header_bomb(w, h);
        bytes.truncate(bytes.len().max(cut) - cut.min(bytes.len() / 2));
        std::fs::write(&p, bytes).unwrap();
        let r = catch_unwind(AssertUnwindSafe(|| exr(&p)));
        let r = r.map_err(|_| TestCaseError::fail(format!("panic on a {w} x {h} header")))?;
        // Small claims may be readable (all-zero pixels are not in the file, so still an error).
        prop_assert!(r.is_err(), "a pixel-less header was read as an image");
        let e = r.unwrap_err();
        prop_assert!(e.contains("bomb.exr"), "{}", e);
    }

    #[test]
    fn fuzz_png_header_bombs(w in 1u32..u32::MAX / 2, h in 1u32..u32::MAX / 2) {
        inimtrace::budget::set_memory_limit(256 << 20);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bomb.png");
        std::fs::write(&p, inimtrace::fixtures::png_header_bomb(w, h)).unwrap();
        let r = catch_unwind(AssertUnwindSafe(|| {
            inimtrace::io::png::load_texture(&p, Default::default(), Default::default()).map(|_| ())
        }))
        .map_err(|_| TestCaseError::fail(format!("panic on a {w} x {h} PNG header")))?;
        let e = r.expect_err("a PNG without pixel data was decoded").to_string();
        prop_assert!(e.contains("bomb.png"), "{}", e);
    }

    #[test]
    fn fuzz_ply_count_bombs(vertices in 0u64..u64::MAX / 2, faces in 0u64..u64::MAX / 2, binary in any::<bool>()) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bomb.ply");
        let format = if binary { "binary_little_endian" } else { "ascii" };
        std::fs::write(
            &p,
            format!(
                "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n\
                 element face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
            ),
        )
        .unwrap();
        let r = catch_unwind(AssertUnwindSafe(|| mesh(&p)))
            .map_err(|_| TestCaseError::fail(format!("panic on {vertices} vertices, {faces} faces")))?;
        let e = r.expect_err("an empty body was read as a mesh");
        prop_assert!(e.contains("bomb.ply"), "{}", e);
    }
}

/// The CLI end to end: `assess` on a mutated experiment file (the paper's, at small sizes) with
/// one more `--set` of a random key to a hostile value. The process must end by itself within
/// its time, with exit code 0 or 1, never a signal (abort, segfault) or a panic (101); a failure
/// is one `error:` line that names the file or the `--set` it came from.
const SET_KEYS: [&str; 12] = [
    "eye.pupil_diameter",
    "eye.retina_distance",
    "eye.position",
    "eye.retina_half_tangent",
    "eye_cases[1].focus_mm",
    "display.eye_to_lenslets",
    "display.lenslets_to_lcd",
    "display.lenslets.pitch",
    "display.lenslets.focal_length",
    "display.elemental_images.pitch",
    "display.lcd.size",
    "scene.objects",
];
const SET_VALUES: [&str; 12] =
    ["nan", "inf", "-1", "0", "1e400", "1e-300", "[1e9, 0, 0]", "[[1, 2], [3, 4]]", "\"x\"", "[]", "{}", "1e30"];

fn cli_case(muts: &[Mutation], key: usize, value: usize) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let paper = std::fs::read_to_string(root().join("experiments/paper.toml")).unwrap();
    let seed = paper
        .replace("\"../scenes/paper.toml\"", "\"builtin:paper\"")
        .replace("\"../displays/paper.toml\"", "\"builtin:paper\"");
    let path = dir.path().join("fuzzed.toml");
    std::fs::write(&path, apply(seed.into_bytes(), muts)).unwrap();
    let set = format!("{}={}", SET_KEYS[key], SET_VALUES[value]);
    let small = [
        "display.lcd.resolution=[108, 108]",
        "eye.retina_resolution=32",
        "eye.pupil_grid=2",
        "eye.retina_samples=1",
        "display_render.la_grid=2",
        "display_render.samples_per_pixel=1",
        "measurement.estimator=\"grid\"",
    ];
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace"));
    cmd.args(["--quiet", "--threads", "1", "--max-memory", "2G", "assess"]).arg(&path);
    cmd.arg("--out").arg(dir.path().join("out"));
    for s in small.iter().copied().chain([set.as_str()]) {
        cmd.args(["--set", s]);
    }
    let mut child = cmd.stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > std::time::Duration::from_secs(120) {
            let _ = child.kill();
            let _ = child.wait();
            return Err(TestCaseError::fail(format!("still running after 120 s: {muts:?} --set {set}")));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    let what = format!("{muts:?} --set {set}: {stderr}");
    prop_assert!(matches!(status.code(), Some(0) | Some(1)), "ended with {status}: {what}");
    prop_assert!(!stderr.contains("panicked"), "panicked: {what}");
    if status.code() == Some(1) {
        let error = stderr.lines().find(|l| l.starts_with("error:"));
        prop_assert!(error.is_some(), "exit 1 without an error line: {what}");
        let error = error.unwrap();
        prop_assert!(
            error.contains("fuzzed.toml")
                || error.contains("--set")
                || error.contains("built-in")
                || error.contains("builtin:paper"),
            "the error names neither the file nor the override: {what}"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(24),
        ..config()
    })]

    #[test]
    fn fuzz_the_cli_on_a_mutated_experiment_and_a_hostile_set(
        m in prop::collection::vec(mutation(), 0..3),
        key in 0..SET_KEYS.len(),
        value in 0..SET_VALUES.len(),
    ) {
        cli_case(&m, key, value)?;
    }
}
