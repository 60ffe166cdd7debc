//! Files named by other files (glTF buffers and images, OBJ `mtllib` and `map_Kd`, a scene's
//! meshes) and by `--set`: every one goes through the input gate. Absolute paths and paths that
//! leave the scene's folder are refused unless the scene says `allow_outside_paths = true`;
//! devices, FIFOs and system files are refused by name, never read; the content of a file that
//! is not what it should be is never echoed.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn inimtrace() -> &'static str {
    env!("CARGO_BIN_EXE_inimtrace")
}

/// Runs `inimtrace args` with a 20 s timeout (a read that blocks fails the test instead of
/// hanging it) and its address space capped at 1 GB.
fn run(args: &[&str]) -> Output {
    Command::new("bash")
        .arg("-c")
        .arg("ulimit -v 1048576; exec timeout 20 \"$0\" \"$@\"")
        .arg(inimtrace())
        .args(args)
        .output()
        .expect("run inimtrace")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit 1 with one error line that holds every one of `words`.
fn assert_refused(o: &Output, words: &[&str]) {
    let e = stderr(o);
    assert_ne!(o.status.code(), Some(124), "inimtrace hung: {e}");
    assert_eq!(o.status.code(), Some(1), "expected a refusal, got {:?}: {e}", o.status);
    assert!(!e.contains("panicked"), "{e}");
    for w in words {
        assert!(e.contains(w), "the error does not say `{w}`: {e}");
    }
}

fn info_scene(scene: &Path) -> Output {
    run(&["info", "--scene", scene.to_str().unwrap()])
}

/// A glTF triangle at z = 400 mm whose buffer is the file `uri` (36 bytes: three positions)
/// and whose material's base colour image is `image` (a URI, or none).
fn gltf(uri: &str, image: Option<&str>) -> String {
    let material = match image {
        Some(img) => format!(
            r#", "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}],
  "textures": [{{"source": 0}}], "images": [{{"uri": "{img}"}}]"#
        ),
        None => String::new(),
    };
    let uv = if image.is_some() { r#", "TEXCOORD_0": 1"# } else { "" };
    let mat = if image.is_some() { r#", "material": 0"# } else { "" };
    let uv_accessor =
        if image.is_some() { r#", {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"}"# } else { "" };
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0{uv}}}{mat}}}]}}],
  "buffers": [{{"byteLength": 36, "uri": "{uri}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}}{uv_accessor}]{material}}}"#
    )
}

fn triangle_bin() -> Vec<u8> {
    [0.0f32, 0.0, 400.0, 50.0, 0.0, 400.0, 0.0, 50.0, 400.0].iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// `dir/scene/` with `scene.toml` naming the mesh `mesh` (relative to the scene), the scene
/// allowing outside paths when `allow`; returns the scene file.
fn scene(dir: &Path, mesh: &str, allow: bool) -> PathBuf {
    let folder = dir.join("scene");
    std::fs::create_dir_all(&folder).unwrap();
    let path = folder.join("scene.toml");
    let allow = if allow { "allow_outside_paths = true\n" } else { "" };
    std::fs::write(
        &path,
        format!("name = \"s\"\n{allow}[[objects]]\ntype = \"mesh\"\nfile = \"{mesh}\"\nmaterial = {{ albedo = [1, 1, 1] }}\n"),
    )
    .unwrap();
    path
}

fn mkfifo(path: &Path) -> bool {
    Command::new("mkfifo").arg(path).status().map(|s| s.success()).unwrap_or(false)
}

#[test]
fn gltf_buffers_outside_the_folder_devices_and_fifos_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "m.gltf", false);
    let folder = s.parent().unwrap();
    std::fs::write(folder.join("tri.bin"), triangle_bin()).unwrap();
    std::fs::write(dir.path().join("outside.bin"), triangle_bin()).unwrap();
    // The reference inside the folder loads.
    std::fs::write(folder.join("m.gltf"), gltf("tri.bin", None)).unwrap();
    let o = info_scene(&s);
    assert!(o.status.success(), "{}", stderr(&o));
    // Absolute, climbing out, climbing out to a real file, and a device.
    for (uri, says) in [
        ("/etc/hostname", "absolute path"),
        ("../../../../../../../../../etc/hostname", "outside the scene's folder"),
        ("../outside.bin", "outside the scene's folder"),
        ("/dev/zero", "absolute path"),
        ("%2Fdev%2Fzero", "absolute path"),
    ] {
        std::fs::write(folder.join("m.gltf"), gltf(uri, None)).unwrap();
        let o = info_scene(&s);
        assert_refused(&o, &["m.gltf", "buffers[0]", "allow_outside_paths = true", says, "scene.toml"]);
    }
    // A link inside the folder that leads out.
    std::os::unix::fs::symlink(dir.path().join("outside.bin"), folder.join("link.bin")).unwrap();
    std::fs::write(folder.join("m.gltf"), gltf("link.bin", None)).unwrap();
    assert_refused(&info_scene(&s), &["buffers[0]", "through a link", "allow_outside_paths = true"]);
    // Allowed outside: the file outside loads; a device or a FIFO is still refused by name.
    let s = scene(dir.path(), "m.gltf", true);
    std::fs::write(folder.join("m.gltf"), gltf("../outside.bin", None)).unwrap();
    let o = info_scene(&s);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(folder.join("m.gltf"), gltf("/dev/zero", None)).unwrap();
    assert_refused(&info_scene(&s), &["buffers[0]", "/dev/zero", "character device"]);
    if mkfifo(&folder.join("fifo.bin")) {
        std::fs::write(folder.join("m.gltf"), gltf("fifo.bin", None)).unwrap();
        assert_refused(&info_scene(&s), &["buffers[0]", "fifo.bin", "FIFO"]);
    }
    std::fs::write(folder.join("m.gltf"), gltf("/proc/self/status", None)).unwrap();
    let o = info_scene(&s);
    assert_refused(&o, &["buffers[0]", "/proc/self/status", "system state"]);
    assert!(!stderr(&o).contains("VmRSS"), "{}", stderr(&o));
}

#[test]
fn gltf_images_outside_the_folder_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "m.gltf", false);
    let folder = s.parent().unwrap();
    std::fs::write(folder.join("tri.bin"), triangle_bin()).unwrap();
    std::fs::write(dir.path().join("outside.png"), b"not an image").unwrap();
    for (uri, says) in [("/etc/hostname", "absolute path"), ("../outside.png", "outside the scene's folder")] {
        std::fs::write(folder.join("m.gltf"), gltf("tri.bin", Some(uri))).unwrap();
        // The scene's own material is left out so that the file's material (and image) is used.
        std::fs::write(&s, "name = \"s\"\n[[objects]]\ntype = \"mesh\"\nfile = \"m.gltf\"\n").unwrap();
        assert_refused(&info_scene(&s), &["images[0]", says, "allow_outside_paths = true"]);
    }
}

#[test]
fn obj_material_libraries_and_textures_outside_the_folder_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("scene");
    std::fs::create_dir_all(&folder).unwrap();
    let s = folder.join("scene.toml");
    std::fs::write(&s, "name = \"s\"\n[[objects]]\ntype = \"mesh\"\nfile = \"m.obj\"\n").unwrap();
    std::fs::write(dir.path().join("outside.mtl"), "newmtl Red\nKd 1 0 0\n").unwrap();
    let obj = |mtllib: &str| {
        format!(
            "mtllib {mtllib}\nv 0 0 400\nv 50 0 400\nv 0 50 400\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl Red\nf 1/1 2/2 3/3\n"
        )
    };
    for (lib, says) in [
        ("../outside.mtl", "outside the scene's folder"),
        ("../../../../../../../../../etc/hostname", "outside the scene's folder"),
        ("/etc/hostname", "absolute path"),
        ("/dev/zero", "absolute path"),
    ] {
        std::fs::write(folder.join("m.obj"), obj(lib)).unwrap();
        assert_refused(&info_scene(&s), &["m.obj", "mtllib", says, "allow_outside_paths = true", "scene.toml"]);
    }
    // map_Kd outside the folder, and a Windows-style climb.
    std::fs::write(folder.join("m.obj"), obj("m.mtl")).unwrap();
    for (map, says) in [("/etc/hostname", "absolute path"), ("..\\..\\outside.png", "outside the scene's folder")] {
        std::fs::write(folder.join("m.mtl"), format!("newmtl Red\nmap_Kd {map}\n")).unwrap();
        assert_refused(&info_scene(&s), &["m.obj", "map_Kd", says, "allow_outside_paths = true"]);
    }
    // Inside the folder: a FIFO material library is a warning naming it, not a hang.
    if mkfifo(&folder.join("fifo.mtl")) {
        std::fs::write(folder.join("m.obj"), obj("fifo.mtl")).unwrap();
        let o = info_scene(&s);
        assert!(o.status.success(), "{}", stderr(&o));
        let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
        assert!(all.contains("fifo.mtl") && all.contains("FIFO"), "{all}");
    }
    // Allowed outside: the library outside is read.
    std::fs::write(&s, "name = \"s\"\nallow_outside_paths = true\n[[objects]]\ntype = \"mesh\"\nfile = \"m.obj\"\n")
        .unwrap();
    std::fs::write(folder.join("m.obj"), obj("../outside.mtl")).unwrap();
    let o = info_scene(&s);
    assert!(o.status.success() && !stderr(&o).contains("outside.mtl"), "{:?}: {}", o.status, stderr(&o));
}

#[test]
fn scene_files_outside_the_folder_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("outside.obj"), "v 0 0 400\nv 50 0 400\nv 0 50 400\nf 1 2 3\n").unwrap();
    for (mesh, says) in [
        ("../outside.obj", "outside the scene's folder"),
        ("/dev/zero", "absolute path"),
        ("../../../../../../../../etc/hostname", "outside the scene's folder"),
    ] {
        let s = scene(dir.path(), mesh, false);
        assert_refused(&info_scene(&s), &["scene.toml", "objects[0].file", says, "allow_outside_paths = true"]);
    }
    let s = scene(dir.path(), "../outside.obj", true);
    let o = info_scene(&s);
    assert!(o.status.success(), "{}", stderr(&o));
    // Textures and bar lists too.
    let folder = s.parent().unwrap();
    std::fs::write(dir.path().join("bars.txt"), "0 0 1 1\n").unwrap();
    std::fs::write(
        &s,
        "name = \"s\"\n[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 400]\nsize = [10, 10]\n\
         material = { chart = \"file\", file = \"../bars.txt\" }\n",
    )
    .unwrap();
    assert_refused(&info_scene(&s), &["objects[0].material.file", "outside the scene's folder"]);
    let _ = folder;
}

#[test]
fn files_named_by_set_are_gated_and_never_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let secret = dir.path().join("secret.toml");
    std::fs::write(&secret, "root:x:0:0:hunter2:/root:/bin/bash\npassword = \"hunter2\"\n").unwrap();
    let s = secret.to_str().unwrap();
    let cases: Vec<(String, Vec<&str>)> = vec![
        ("display=/proc/self/status".into(), vec!["/proc/self/status", "system state"]),
        ("scene=/proc/self/environ".into(), vec!["/proc/self/environ", "system state"]),
        ("display=/dev/zero".into(), vec!["/dev/zero", "character device"]),
        (format!("display={s}"), vec!["secret.toml", "line 1"]),
        (format!("scene={s}"), vec!["secret.toml", "line 1"]),
    ];
    for (set, words) in cases {
        let o = run(&["render-display", "--set", &set, "--out", out]);
        let o = if o.status.code() == Some(2) {
            // Commands that take no --set: the experiment runner does.
            run(&["assess", "experiments/paper.toml", "--set", &set, "--out", out])
        } else {
            o
        };
        assert_refused(&o, &words);
        let e = stderr(&o);
        for leak in ["VmRSS", "Name:", "hunter2", "root:x", "PATH="] {
            assert!(!e.contains(leak), "{set}: the error echoes the file ({leak}): {e}");
        }
    }
}

/// Runs `inimtrace args` under `prlimit --as=4G` with `--max-memory 3G`, with a 60 s timeout.
fn run_budget(args: &[&str]) -> Output {
    Command::new("prlimit")
        .args(["--as=4294967296", "timeout", "60", inimtrace(), "--max-memory", "3G"])
        .args(args)
        .output()
        .expect("run inimtrace under prlimit")
}

/// A glTF whose node graph instances one mesh of `triangles` triangles `2^depth` times
/// through doubling nodes (node k has node k + 1 twice as its child), its buffer in `mesh.bin`.
fn doubling_gltf(folder: &Path, triangles: usize, depth: usize) {
    let positions: Vec<u8> = (0..triangles)
        .flat_map(|t| {
            let x = t as f32 * 0.01;
            [x, 0.0, 400.0, x + 0.01, 0.0, 400.0, x, 0.01, 400.0]
        })
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(folder.join("mesh.bin"), &positions).unwrap();
    let mut nodes: Vec<String> = (0..depth).map(|k| format!("{{\"children\": [{}, {}]}}", k + 1, k + 1)).collect();
    nodes.push("{\"mesh\": 0}".into());
    let doc = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "buffers": [{{"byteLength": {n}, "uri": "mesh.bin"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": {n}}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": {v}, "type": "VEC3"}}]}}"#,
        nodes.join(", "),
        n = positions.len(),
        v = 3 * triangles
    );
    std::fs::write(folder.join("m.gltf"), doc).unwrap();
}

#[test]
fn a_node_graph_instancing_a_mesh_262144_times_is_counted_not_expanded() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "m.gltf", false);
    let folder = s.parent().unwrap();
    // 1,000 triangles x 2^18 instances: 262,144,000 triangles, tens of GB expanded.
    doubling_gltf(folder, 1000, 18);
    let o = run_budget(&["info", "--scene", s.to_str().unwrap()]);
    assert_refused(&o, &["m.gltf", "nodes", "262144000 triangles", "more than the limit"]);
    // The same graph 2^4 deep fits and loads, with every instance's triangles.
    doubling_gltf(folder, 1000, 4);
    let o = run_budget(&["info", "--scene", s.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("16000"), "{}", String::from_utf8_lossy(&o.stdout));
}

#[test]
fn one_large_texture_shared_by_40_materials_is_decoded_once() {
    use image::ImageEncoder;
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "m.gltf", false);
    let folder = s.parent().unwrap();
    // 12,000 x 12,000 RGB: 432 MB decoded; 40 copies would be 17 GB.
    let n = 12_000u32;
    let file = std::io::BufWriter::new(std::fs::File::create(folder.join("big.png")).unwrap());
    let encoder = image::codecs::png::PngEncoder::new_with_quality(
        file,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::NoFilter,
    );
    let pixels = vec![128u8; (n * n * 3) as usize];
    encoder.write_image(&pixels, n, n, image::ExtendedColorType::Rgb8).unwrap();
    drop(pixels);
    // 40 triangles, each its own primitive and material (its own base colour) on one image.
    let k = 40;
    let mut bin = Vec::new();
    for t in 0..k {
        let x = t as f32 * 2.0;
        for v in [x, 0.0, 400.0, x + 1.0, 0.0, 400.0, x, 1.0, 400.0] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    for v in [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(folder.join("m.bin"), &bin).unwrap();
    let prims: Vec<String> = (0..k)
        .map(|t| format!(r#"{{"attributes": {{"POSITION": {t}, "TEXCOORD_0": {k}}}, "material": {t}}}"#))
        .collect();
    let materials: Vec<String> = (0..k)
        .map(|t| {
            format!(
                r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [{}, 1, 1, 1], "baseColorTexture": {{"index": 0}}}}}}"#,
                (t + 1) as f64 / k as f64
            )
        })
        .collect();
    let mut views: Vec<String> =
        (0..k).map(|t| format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": 36}}"#, 36 * t)).collect();
    views.push(format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": 24}}"#, 36 * k));
    let mut accessors: Vec<String> = (0..k)
        .map(|t| format!(r#"{{"bufferView": {t}, "componentType": 5126, "count": 3, "type": "VEC3"}}"#))
        .collect();
    accessors.push(format!(r#"{{"bufferView": {k}, "componentType": 5126, "count": 3, "type": "VEC2"}}"#));
    let doc = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{}]}}], "materials": [{}],
  "textures": [{{"source": 0}}], "images": [{{"uri": "big.png"}}],
  "buffers": [{{"byteLength": {}, "uri": "m.bin"}}], "bufferViews": [{}], "accessors": [{}]}}"#,
        prims.join(", "),
        materials.join(", "),
        bin.len(),
        views.join(", "),
        accessors.join(", ")
    );
    std::fs::write(folder.join("m.gltf"), doc).unwrap();
    // The scene's own material is left out: the file's 40 materials are used.
    std::fs::write(&s, "name = \"s\"\n[[objects]]\ntype = \"mesh\"\nfile = \"m.gltf\"\n").unwrap();
    let o = run_budget(&["info", "--scene", s.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{:?}: {}", o.status, stderr(&o));
    assert!(out.contains("40 objects") && !out.contains("warning"), "{out}");
}

#[test]
fn a_sweep_of_a_million_points_is_estimated_before_it_is_expanded() {
    let dir = tempfile::tempdir().unwrap();
    let experiment = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let sweep = dir.path().join("big.toml");
    std::fs::write(
        &sweep,
        format!(
            "name = \"big\"\nexperiment = \"{}\"\n[[axes]]\n\"eye.pupil_diameter\" = {{ from = 1.0, to = 6.0, count = 1000 }}\n\
             [[axes]]\n\"eye.retina_resolution\" = {{ from = 100, to = 1099, count = 1000 }}\n",
            experiment.display()
        ),
    )
    .unwrap();
    let (sw, out) = (sweep.to_str().unwrap(), dir.path().join("out"));
    let out = out.to_str().unwrap();
    for args in [
        vec!["sweep", sw, "--collect", "--out", out],
        vec!["sweep", sw, "--slurm", "--dry-run", "--out", out],
        vec!["sweep", sw, "--out", out],
    ] {
        let o = run_budget(&args);
        assert_refused(&o, &["big.toml", "axes", "1000000 points", "more than the limit"]);
    }
}
