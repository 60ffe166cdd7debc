//! Mesh files as exporters write them (issue 24): `scripts/make-mesh-corpus.sh` writes OBJ, MTL,
//! PLY and glTF files with Windows-style `\` paths, texture options, missing and unreadable
//! textures and libraries, unusable vertex colours and odd text encodings. Each must load, with
//! one warning per problem naming the mesh file (and the material and image where there is one),
//! and show the material's base colour where its texture or colours could not be used.
#![deny(unsafe_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use inimtrace::io;
use inimtrace::scene::{Material, Scene, Shape};

/// Runs the corpus script into a fresh temporary folder.
fn corpus() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/make-mesh-corpus.sh");
    let out = Command::new("sh").arg(&script).arg(dir.path()).output().expect("running make-mesh-corpus.sh");
    assert!(out.status.success(), "make-mesh-corpus.sh failed: {}", String::from_utf8_lossy(&out.stderr));
    dir
}

/// A scene holding the mesh file `file` of `dir` (fitted to 100 mm at 400 mm), and its path.
fn scene_file(dir: &Path, file: &str) -> PathBuf {
    let path = dir.join(format!("{file}.toml"));
    std::fs::write(
        &path,
        format!("[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\nfit = {{ size = 100.0, center = [0, 0, 400] }}\n"),
    )
    .unwrap();
    path
}

fn scene(dir: &Path, file: &str) -> Scene {
    let path = scene_file(dir, file);
    io::load_scene(&path.to_string_lossy(), Path::new("")).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn albedo(m: &Material) -> DVec3 {
    match m {
        Material::Albedo(a) => *a,
        _ => panic!("expected a base colour, got {}", kind(m)),
    }
}

fn kind(m: &Material) -> &'static str {
    match m {
        Material::Albedo(_) => "albedo",
        Material::Texture(_) => "texture",
        Material::VertexColor => "vertex colours",
        _ => "another material",
    }
}

/// The four texels of a 2 x 2 texture, sampled at their centres.
fn texel_centres(t: &inimtrace::scene::ImageTexture) -> [DVec3; 4] {
    [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)].map(|(u, v)| t.sample(glam::DVec2::new(u, v)))
}

/// Every texel of the object's texture is linear red (the corpus's `textures/red.png`).
fn assert_red_texture(s: &Scene, what: &str) {
    assert_eq!(s.objects.len(), 1, "{what}");
    match &s.objects[0].material {
        Material::Texture(t) => {
            assert_eq!((t.width, t.height), (2, 2), "{what}");
            assert_eq!(texel_centres(t), [DVec3::new(1.0, 0.0, 0.0); 4], "{what}");
        }
        m => panic!("{what}: expected the red texture, got {}", kind(m)),
    }
}

/// `s` has exactly `n` warnings, and each contains all of `words` of one entry of `each`.
fn assert_warnings(s: &Scene, each: &[&[&str]], what: &str) {
    assert_eq!(s.warnings.len(), each.len(), "{what}: {:#?}", s.warnings);
    for words in each {
        assert!(
            s.warnings.iter().any(|w| words.iter().all(|x| w.contains(x))),
            "{what}: no warning with {words:?} in {:#?}",
            s.warnings
        );
    }
}

#[test]
fn backslash_paths_and_texture_options_find_the_texture() {
    let dir = corpus();
    for file in ["backslash.obj", "options.obj"] {
        let s = scene(dir.path(), file);
        assert_red_texture(&s, file);
        assert!(s.warnings.is_empty(), "{file}: {:?}", s.warnings);
    }
    // The scene file's `texture = "mtl"` resolves the same way.
    let path = dir.path().join("mtl.toml");
    std::fs::write(
        &path,
        "[[objects]]\ntype = \"mesh\"\nfile = \"backslash.obj\"\ntransform = { translation = [0, 0, 400] }\n\
         material = { texture = \"mtl\" }\n",
    )
    .unwrap();
    let s = io::load_scene(&path.to_string_lossy(), Path::new("")).unwrap();
    assert_red_texture(&s, "texture = \"mtl\"");
}

#[test]
fn missing_and_unreadable_textures_warn_and_show_the_base_colour() {
    let dir = corpus();
    let s = scene(dir.path(), "bad-textures.obj");
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        ["bad-textures [Missing]", "bad-textures [Folder]", "bad-textures [Garbage]", "bad-textures [Truncated]"]
    );
    // Kd of each material; the one without Kd gets the default grey.
    let colours: Vec<DVec3> = s.objects.iter().map(|o| albedo(&o.material)).collect();
    assert_eq!(
        colours,
        [DVec3::new(0.2, 0.4, 0.6), DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.3, 0.2, 0.1), DVec3::splat(0.8)]
    );
    assert_warnings(
        &s,
        &[
            &["bad-textures.obj", "material 'Missing'", "not-there.jpg", "No such file", "base colour"],
            &["bad-textures.obj", "material 'Folder'", "folder.png", "directory", "base colour"],
            &["bad-textures.obj", "material 'Garbage'", "garbage.png", "not a PNG or JPEG", "base colour"],
            &["bad-textures.obj", "material 'Truncated'", "truncated.png", "base colour"],
        ],
        "bad-textures.obj",
    );
    assert!(s.warnings.iter().all(|w| !w.contains('\n')), "one line each: {:#?}", s.warnings);
    // A `\` in a missing texture's name is a separator too: the warning names `./not-there.jpg`.
    assert!(s.warnings[0].contains("/./not-there.jpg"), "{}", s.warnings[0]);
}

#[test]
fn a_missing_or_broken_material_library_warns_and_loads_the_geometry() {
    let dir = corpus();
    let s = scene(dir.path(), "missing-mtl.obj");
    assert_eq!(albedo(&s.objects[0].material), DVec3::splat(0.8));
    assert_warnings(
        &s,
        &[&["missing-mtl.obj", "material library", "./no-such-library.mtl", "No such file"]],
        "missing-mtl.obj",
    );
    let s = scene(dir.path(), "unnamed-mtl.obj");
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(albedo(&s.objects[0].material), DVec3::splat(0.8));
    assert_warnings(
        &s,
        &[
            &["unnamed-mtl.obj", "line 10", "`usemtl` without a material name", "1 more"],
            &["unnamed-mtl.obj", "material library", "unnamed.mtl"],
        ],
        "unnamed-mtl.obj",
    );
}

#[test]
fn unusable_vertex_colours_warn_and_show_the_base_colour() {
    let dir = corpus();
    let cases: [(&str, DVec3, &[&str]); 6] = [
        ("partial-colors.obj", DVec3::new(0.1, 0.1, 0.9), &["partial-colors.obj", "line 3", "vertex 2 lacks a colour"]),
        ("nan-colors.obj", DVec3::splat(0.8), &["nan-colors.obj", "line 1", "non-finite colour"]),
        ("ply-two-channels.ply", DVec3::splat(0.8), &["ply-two-channels.ply", "vertex colours", "no blue"]),
        ("ply-list-color.ply", DVec3::splat(0.8), &["ply-list-color.ply", "vertex colours", "red given as a list"]),
        ("ply-nan-color.ply", DVec3::splat(0.8), &["ply-nan-color.ply", "vertex 0", "non-finite colour"]),
        ("latin1.obj", DVec3::new(0.25, 0.5, 0.75), &["latin1.obj", "line 5", "Latin-1"]),
    ];
    for (file, colour, words) in cases {
        let s = scene(dir.path(), file);
        assert_eq!(s.objects.len(), 1, "{file}");
        assert_eq!(albedo(&s.objects[0].material), colour, "{file}");
        let Shape::Mesh(m) = &s.objects[0].shape else { panic!("{file}: not a mesh") };
        assert!(m.colors.is_none(), "{file}: colours dropped");
        let extra: &[&str] = &["latin1.mtl", "Latin-1"];
        if file == "latin1.obj" {
            // The library's material name is in Latin-1 as well, and matches the OBJ's.
            assert_warnings(&s, &[words, extra], file);
        } else {
            assert_warnings(&s, &[words], file);
        }
    }
    // Channels of different PLY types are each divided by their own type's maximum.
    let s = scene(dir.path(), "ply-mixed-types.ply");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(matches!(s.objects[0].material, Material::VertexColor));
    let Shape::Mesh(m) = &s.objects[0].shape else { panic!() };
    assert!(m.colors.as_ref().unwrap().iter().all(|&c| c == DVec3::new(1.0, 0.0, 0.0)), "{:?}", m.colors);
    // UTF-16 (with its byte-order mark) is read as text.
    let s = scene(dir.path(), "utf16.obj");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.triangle_count(), 1);
}

#[test]
fn gltf_images_that_cannot_be_read_warn_and_show_the_base_colour_factor() {
    let dir = corpus();
    let factor = DVec3::new(0.1f32 as f64, 0.5f32 as f64, 0.9f32 as f64);
    for (file, words) in [
        ("gltf-missing-image.gltf", &["gltf-missing-image.gltf", "'Painted'", "not-there.png", "No such file"][..]),
        ("gltf-bad-data-uri.gltf", &["gltf-bad-data-uri.gltf", "'Painted'", "images[0]", "base64"][..]),
        ("gltf-garbage-image.gltf", &["gltf-garbage-image.gltf", "'Painted'", "garbage.png", "not a PNG or JPEG"][..]),
    ] {
        let s = scene(dir.path(), file);
        assert_eq!(albedo(&s.objects[0].material), factor, "{file}");
        assert_warnings(&s, &[words], file);
        assert!(s.warnings[0].contains("base colour"), "{file}: {}", s.warnings[0]);
    }
    // The same file with its image present is textured (times the factor).
    let s = scene(dir.path(), "gltf-good-image.gltf");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let Material::Texture(t) = &s.objects[0].material else { panic!("expected a texture") };
    assert_eq!((t.width, t.height), (2, 2));
    assert_eq!(texel_centres(t), [DVec3::new(factor.x, 0.0, 0.0); 4]);
}

#[test]
fn the_command_line_renders_a_file_with_missing_textures_and_prints_one_warning_each() {
    let dir = corpus();
    let scene = scene_file(dir.path(), "bad-textures.obj");
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["-q", "ground-truth", "--pinhole", "--retina", "16", "--pupil-grid", "1", "--backend", "bvh"])
        .arg("--scene")
        .arg(&scene)
        .arg("--out")
        .arg(dir.path().join("gt.exr"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 4, "{stderr}");
    assert!(lines.iter().all(|l| l.starts_with("warning: ") && l.contains("bad-textures.obj")), "{stderr}");
    assert!(dir.path().join("gt.exr").is_file());
}
