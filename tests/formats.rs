//! Mesh file formats as a user brings them (issue "glTF 2.0, STL, robust PLY"): one small object
//! written as OBJ, glTF (embedded buffers and texture), GLB, STL (ASCII and binary) and PLY must
//! render the same image bit for bit through every mesh backend; malformed glTF and STL files
//! give one line naming the file and the element; the scene file's defaults (material, name,
//! fit, light) do what the documentation says.

use std::path::{Path, PathBuf};

use base64::Engine;
use glam::DVec3;
use inimtrace::io::{self, load_mesh};
use inimtrace::optics::{Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::{ground_truth, with_fields, BackendChoice};
use inimtrace::scene::{Material, Scene, Shape};
use serde_json::{json, Value};

/// A square pyramid with its (off-centre) apex toward the eye: 5 vertices, 4 sides and a
/// 2-triangle base. Dyadic coordinates, so f32 files hold them exactly.
const P: [[f32; 3]; 5] = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [0.5, 0.25, -1.0]];
/// OBJ convention (v = 0 at the bottom of the image).
const UV: [[f32; 2]; 5] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]];
const TRIS: [[u16; 3]; 6] = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 3, 2], [0, 2, 1]];

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn obj_text(with_uv: bool) -> String {
    let mut s = String::new();
    for p in P {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    if with_uv {
        for t in UV {
            s += &format!("vt {} {}\n", t[0], t[1]);
        }
    }
    for t in TRIS {
        let [a, b, c] = t.map(|i| i + 1);
        s += &if with_uv { format!("f {a}/{a} {b}/{b} {c}/{c}\n") } else { format!("f {a} {b} {c}\n") };
    }
    s
}

fn ply_text() -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
         element face 6\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for p in P {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for t in TRIS {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    s
}

fn stl_ascii() -> String {
    let mut s = String::from("solid pyramid\n");
    for t in TRIS {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for i in t {
            let p = P[i as usize];
            s += &format!("      vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid pyramid\n"
}

fn stl_binary(count_in_header: u32, triangles: &[[u16; 3]]) -> Vec<u8> {
    // The header starts with "solid", as many exporters write it.
    let mut b = b"solid written by a binary exporter".to_vec();
    b.resize(80, b' ');
    b.extend(count_in_header.to_le_bytes());
    for t in triangles {
        b.extend([0u8; 12]);
        for i in t {
            for c in P[*i as usize] {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

/// A 2 x 2 sRGB PNG: red, green / blue, white.
fn png_bytes() -> Vec<u8> {
    let img = image::RgbImage::from_raw(2, 2, vec![200, 30, 30, 30, 200, 30, 30, 30, 200, 250, 250, 250]).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// The pyramid's binary buffer: positions, uvs (glTF convention, v = 0 at the top), indices.
fn gltf_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for p in P {
        for c in p {
            b.extend(c.to_le_bytes());
        }
    }
    for t in UV {
        b.extend(t[0].to_le_bytes());
        b.extend((1.0 - t[1]).to_le_bytes());
    }
    for t in TRIS {
        for i in t {
            b.extend(i.to_le_bytes());
        }
    }
    b
}

const POS_BYTES: usize = 5 * 12;
const UV_BYTES: usize = 5 * 8;
const IDX_BYTES: usize = 18 * 2;

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!("data:{mime};base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A glTF document for the pyramid: a parent node translated by `parent_t` holding a child
/// scaled by `child_s` that holds the mesh; a base colour texture when `image` is given.
fn gltf_doc(buffer: Value, image: Option<Value>, extra_views: Vec<Value>, parent_t: [f32; 3], child_s: f32) -> Value {
    let mut views = vec![
        json!({"buffer": 0, "byteOffset": 0, "byteLength": POS_BYTES}),
        json!({"buffer": 0, "byteOffset": POS_BYTES, "byteLength": UV_BYTES}),
        json!({"buffer": 0, "byteOffset": POS_BYTES + UV_BYTES, "byteLength": IDX_BYTES}),
    ];
    views.extend(extra_views);
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"translation": parent_t, "children": [1]}, {"scale": [child_s, child_s, child_s], "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0]}}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 18, "type": "SCALAR"}
        ],
        "bufferViews": views,
        "buffers": [buffer],
    });
    if let Some(image) = image {
        doc["images"] = json!([image]);
        doc["textures"] = json!([{"source": 0}]);
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    }
    doc
}

fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Writes the pyramid in every format into `dir`; returns the file names.
fn write_all_formats(dir: &Path) -> Vec<&'static str> {
    let buf = gltf_buffer();
    let png = png_bytes();
    write(dir, "pyramid.obj", obj_text(true));
    write(dir, "pyramid.ply", ply_text());
    write(dir, "pyramid_ascii.stl", stl_ascii());
    write(dir, "pyramid_binary.stl", stl_binary(6, &TRIS));
    write(dir, "tex.png", &png);
    // .gltf: buffer and texture as data URIs; identity node transforms.
    let doc = gltf_doc(
        json!({"byteLength": buf.len(), "uri": data_uri("application/octet-stream", &buf)}),
        Some(json!({"uri": data_uri("image/png", &png)})),
        vec![],
        [0.0; 3],
        1.0,
    );
    write(dir, "pyramid.gltf", serde_json::to_vec_pretty(&doc).unwrap());
    // .glb: buffer in the binary chunk, texture in a buffer view of it.
    let mut bin = buf.clone();
    let png_offset = bin.len();
    bin.extend(&png);
    let doc = gltf_doc(
        json!({"byteLength": bin.len()}),
        Some(json!({"bufferView": 3, "mimeType": "image/png"})),
        vec![json!({"buffer": 0, "byteOffset": png_offset, "byteLength": png.len()})],
        [0.0; 3],
        1.0,
    );
    write(dir, "pyramid.glb", glb(&doc, &bin));
    vec!["pyramid.obj", "pyramid.gltf", "pyramid.glb", "pyramid_ascii.stl", "pyramid_binary.stl", "pyramid.ply"]
}

fn scene(dir: &Path, file: &str, material: &str) -> Scene {
    let text = format!(
        "[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\ntransform = {{ scale = [40, 40, 40], rotation_deg = [0, 0, 0], \
         translation = [5, -3, 400] }}\n{material}\n"
    );
    let path = write(dir, &format!("{file}.toml"), text);
    io::load_scene(&path.to_string_lossy(), Path::new("")).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn backends() -> Vec<BackendChoice> {
    let mut b = vec![BackendChoice::Bvh, BackendChoice::Brute];
    if cfg!(feature = "embree") {
        b.insert(0, BackendChoice::Embree);
    }
    b
}

fn render(scene: &Scene, backend: BackendChoice) -> RgbImage {
    let eye = Eye::thin_lens(4.0, Focus::Millimetres(380.0), 3);
    let retina = Retina { resolution: 48, half_tangent: 0.14, samples_per_pixel: 1 };
    with_fields(scene, backend, |f| Ok(ground_truth(&eye, &retina, f.shade, &Progress::hidden()))).unwrap()
}

#[test]
fn one_object_in_every_format_renders_the_same_image_on_every_backend() {
    let dir = tempfile::tempdir().unwrap();
    let files = write_all_formats(dir.path());
    let albedo = "material = { albedo = [0.7, 0.5, 0.3] }";
    for backend in backends() {
        let reference = render(&scene(dir.path(), files[0], albedo), backend);
        // The default light from the eye shades the four sides differently: not a silhouette.
        let mut levels: Vec<u32> = reference.pixels.iter().map(|p| p[0].to_bits()).collect();
        levels.sort();
        levels.dedup();
        assert!(levels.len() >= 4, "{backend}: expected shaded faces and background, got {} levels", levels.len());
        for file in &files[1..] {
            let s = scene(dir.path(), file, albedo);
            assert_eq!(s.triangle_count(), 6, "{file}");
            assert!(render(&s, backend) == reference, "{file} through {backend} differs from the OBJ");
        }
        // The file's own texture (glTF, no `material`) equals the OBJ with the same PNG.
        let obj_textured = render(&scene(dir.path(), "pyramid.obj", "material = { texture = \"tex.png\" }"), backend);
        let distinct: std::collections::HashSet<[u32; 3]> =
            obj_textured.pixels.iter().map(|p| p.map(f32::to_bits)).collect();
        assert!(distinct.len() > 20, "{backend}: the texture shows ({} colours)", distinct.len());
        for file in ["pyramid.gltf", "pyramid.glb"] {
            let s = scene(dir.path(), file, "");
            assert!(
                matches!(s.objects[0].material, Material::Texture(_)),
                "{file}: the file's texture is the material"
            );
            assert!(render(&s, backend) == obj_textured, "{file} textured through {backend} differs from the OBJ");
        }
    }
}

#[test]
fn gltf_node_hierarchy_composes_transforms() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "pyramid.obj", obj_text(false));
    let buf = gltf_buffer();
    let doc = gltf_doc(json!({"byteLength": buf.len(), "uri": "pyramid.bin"}), None, vec![], [5.0, -3.0, 400.0], 40.0);
    let mut doc = doc;
    doc["meshes"][0]["primitives"][0].as_object_mut().unwrap().remove("material");
    // POSITION without the `min` and `max` the specification asks for: read all the same.
    doc["accessors"][0].as_object_mut().unwrap().remove("min");
    doc["accessors"][0].as_object_mut().unwrap().remove("max");
    write(dir.path(), "pyramid.bin", &buf);
    write(dir.path(), "nested.gltf", serde_json::to_vec(&doc).unwrap());
    let g = load_mesh(&dir.path().join("nested.gltf")).unwrap();
    let o = load_mesh(&dir.path().join("pyramid.obj")).unwrap();
    let corners = |m: &inimtrace::scene::Mesh| -> Vec<DVec3> {
        m.triangles.iter().flatten().map(|&i| m.positions[i as usize]).collect()
    };
    let want: Vec<DVec3> = corners(&o.mesh).iter().map(|p| *p * 40.0 + DVec3::new(5.0, -3.0, 400.0)).collect();
    assert_eq!(corners(&g.mesh), want);
    // External buffer found relative to the file; no material in the file: default grey.
    let s = scene(dir.path(), "nested.gltf", "");
    assert!(matches!(s.objects[0].material, Material::Albedo(a) if a == DVec3::splat(0.8)));
}

/// The first line of the error, which must be the only one.
fn one_line_error(path: &Path) -> String {
    let e = match load_mesh(path) {
        Ok(_) => panic!("{} loaded without error", path.display()),
        Err(e) => e.to_string(),
    };
    assert!(!e.contains('\n'), "one line: {e}");
    assert!(e.contains(&path.display().to_string()), "names the file: {e}");
    e
}

#[test]
fn malformed_gltf_names_the_file_and_element() {
    let dir = tempfile::tempdir().unwrap();
    let buf = gltf_buffer();
    let embedded = || json!({"byteLength": buf.len(), "uri": data_uri("application/octet-stream", &buf)});
    let base = || gltf_doc(embedded(), None, vec![], [0.0; 3], 1.0);
    let mut cases: Vec<(&str, Value, Vec<&str>)> = Vec::new();

    // An index past the last vertex.
    let mut bad_idx = buf.clone();
    bad_idx[POS_BYTES + UV_BYTES + 2 * 7..POS_BYTES + UV_BYTES + 2 * 8].copy_from_slice(&9u16.to_le_bytes());
    let mut doc = base();
    doc["buffers"][0]["uri"] = json!(data_uri("application/octet-stream", &bad_idx));
    cases.push(("index", doc, vec!["meshes[0].primitives[0].indices", "index 9", "5 vertices"]));

    // A missing external buffer file.
    let mut doc = base();
    doc["buffers"][0]["uri"] = json!("missing.bin");
    cases.push(("buffer", doc, vec!["buffers[0]", "missing.bin"]));

    // An accessor index that does not exist (gltf-json's own validation would panic on it).
    let mut doc = base();
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    cases.push(("accessor_index", doc, vec!["attributes.POSITION", "accessor 7 does not exist"]));

    // A buffer index that does not exist.
    let mut doc = base();
    doc["bufferViews"][0]["buffer"] = json!(3);
    cases.push(("buffer_index", doc, vec!["bufferViews[0].buffer"]));

    // Nodes that are their own ancestors.
    let mut doc = base();
    doc["nodes"][1]["children"] = json!([0]);
    cases.push(("recursive", doc, vec!["nodes[0]", "ancestor"]));

    // POSITION as VEC2, and indices as floats.
    let mut doc = base();
    doc["accessors"][0]["type"] = json!("VEC2");
    cases.push(("vec2", doc, vec!["attributes.POSITION", "VEC2", "expected VEC3"]));
    let mut doc = base();
    doc["accessors"][2]["componentType"] = json!(5126);
    doc["accessors"][2]["count"] = json!(9);
    cases.push(("float_indices", doc, vec!["primitives[0].indices", "FLOAT"]));

    // An accessor past the end of its view.
    let mut doc = base();
    doc["accessors"][0]["count"] = json!(50);
    cases.push(("overrun", doc, vec!["attributes.POSITION", "run past"]));

    // Infinities: in a vertex, and in a node's scale.
    let mut inf = buf.clone();
    inf[0..4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let mut doc = base();
    doc["buffers"][0]["uri"] = json!(data_uri("application/octet-stream", &inf));
    cases.push(("inf_vertex", doc, vec!["attributes.POSITION", "vertex 0", "not finite"]));
    let mut doc = base();
    doc["nodes"][1]["scale"] = json!([1e39, 1.0, 1.0]); // beyond f32: infinite
    cases.push(("inf_scale", doc, vec!["nodes[1]", "non-finite"]));

    // A required extension, and a point-only file.
    let mut doc = base();
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    cases.push((
        "required",
        doc,
        vec!["required.gltf", "extensionsRequired", "KHR_draco_mesh_compression", "does not support"],
    ));
    // One the `gltf` crate can parse (with a feature) but this reader would ignore, beside another.
    let mut doc = base();
    doc["extensionsUsed"] = json!(["KHR_texture_transform", "EXT_meshopt_compression"]);
    doc["extensionsRequired"] = json!(["KHR_texture_transform", "EXT_meshopt_compression"]);
    cases.push((
        "required2",
        doc,
        vec!["required2.gltf", "extensions `KHR_texture_transform`, `EXT_meshopt_compression`", "does not support"],
    ));
    let mut doc = base();
    doc["meshes"][0]["primitives"][0]["mode"] = json!(0);
    cases.push(("points", doc, vec!["no triangles"]));

    for (name, doc, needles) in cases {
        let path = write(dir.path(), &format!("{name}.gltf"), serde_json::to_vec(&doc).unwrap());
        let e = one_line_error(&path);
        for n in needles {
            assert!(e.contains(n), "{name}: `{e}` lacks `{n}`");
        }
    }
    // Not JSON at all, a truncated GLB, and a GLB without its binary chunk.
    let e = one_line_error(&write(dir.path(), "text.gltf", "this is not json"));
    assert!(e.contains("glTF"), "{e}");
    let g = glb(&base(), &buf);
    let e = one_line_error(&write(dir.path(), "cut.glb", &g[..g.len() / 2]));
    assert!(e.contains("glTF"), "{e}");
    // A binary file that requires an extension: refused alike.
    let mut doc = base();
    doc["buffers"][0] = json!({"byteLength": buf.len()});
    doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let e = one_line_error(&write(dir.path(), "required.glb", glb(&doc, &buf)));
    assert!(
        e.contains("required.glb") && e.contains("`KHR_mesh_quantization`") && e.contains("does not support"),
        "{e}"
    );
    let mut doc = base();
    doc["buffers"][0] = json!({"byteLength": buf.len()});
    let e = one_line_error(&write(dir.path(), "noblob.gltf", serde_json::to_vec(&doc).unwrap()));
    assert!(e.contains("buffers[0]") && e.contains("binary chunk"), "{e}");
}

#[test]
fn gltf_warns_about_what_it_skips() {
    let dir = tempfile::tempdir().unwrap();
    let buf = gltf_buffer();
    let mut doc = gltf_doc(
        json!({"byteLength": buf.len(), "uri": data_uri("application/octet-stream", &buf)}),
        None,
        vec![],
        [0.0; 3],
        1.0,
    );
    doc["extensionsUsed"] = json!(["KHR_materials_clearcoat"]);
    let mut lines = doc["meshes"][0]["primitives"][0].clone();
    lines["mode"] = json!(1);
    doc["meshes"][0]["primitives"].as_array_mut().unwrap().push(lines);
    let path = write(dir.path(), "w.gltf", serde_json::to_vec(&doc).unwrap());
    let l = load_mesh(&path).unwrap();
    assert_eq!(l.mesh.triangles.len(), 6);
    assert!(l.warnings.iter().any(|w| w.contains("KHR_materials_clearcoat")), "{:?}", l.warnings);
    assert!(l.warnings.iter().any(|w| w.contains("primitives[1]") && w.contains("skipped")), "{:?}", l.warnings);
}

#[test]
fn malformed_stl_names_the_file_and_facet() {
    let dir = tempfile::tempdir().unwrap();
    // Binary: truncated in the middle of a triangle; a header count larger and smaller than the body.
    let full = stl_binary(6, &TRIS);
    let e = one_line_error(&write(dir.path(), "cut.stl", &full[..full.len() - 20]));
    assert!(e.contains("announces 6 triangles") && e.contains("5 whole triangles") && e.contains("truncated"), "{e}");
    let e = one_line_error(&write(dir.path(), "more.stl", stl_binary(9, &TRIS)));
    assert!(e.contains("announces 9 triangles") && e.contains("6 whole triangles"), "{e}");
    let e = one_line_error(&write(dir.path(), "fewer.stl", stl_binary(2, &TRIS)));
    assert!(e.contains("announces 2 triangles"), "{e}");
    // ASCII: a broken vertex line in the third facet, a file cut short, an infinite coordinate.
    let text = stl_ascii();
    let nth_vertex = text.match_indices("vertex").nth(7).unwrap().0;
    let mut broken = text.clone();
    broken.replace_range(nth_vertex..nth_vertex + 6, "vertx");
    let e = one_line_error(&write(dir.path(), "broken.stl", broken));
    assert!(e.contains("ASCII STL, facet 2"), "{e}");
    let e = one_line_error(&write(dir.path(), "short.stl", &text[..text.len() / 2]));
    assert!(e.contains("ASCII STL, facet"), "{e}");
    let e = one_line_error(&write(dir.path(), "inf.stl", text.replacen("vertex 1 -1 0", "vertex 1 -1 inf", 1)));
    assert!(e.contains("facet 0"), "{e}");
    // An empty file.
    let e = one_line_error(&write(dir.path(), "empty.stl", ""));
    assert!(e.contains("not an STL file"), "{e}");
    // An unnamed ASCII solid is fine.
    let l = load_mesh(&write(dir.path(), "unnamed.stl", text.replacen("solid pyramid", "solid", 1))).unwrap();
    assert_eq!(l.mesh.triangles.len(), 6);
    assert_eq!(l.mesh.positions.len(), 5, "shared vertices are merged");
}

#[test]
fn ply_with_a_non_standard_header_line_loads_with_a_warning() {
    // Blender 2.47 wrote its banner without `comment` (assimp's Wuson.ply).
    let dir = tempfile::tempdir().unwrap();
    let text = ply_text().replacen(
        "format ascii 1.0\n",
        "format ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: \n",
        1,
    );
    let path = write(dir.path(), "blender247.ply", text);
    let l = load_mesh(&path).unwrap();
    assert_eq!(l.mesh.triangles.len(), 6);
    assert_eq!(l.warnings.len(), 1, "{:?}", l.warnings);
    assert!(l.warnings[0].contains("blender247.ply") && l.warnings[0].contains("line 3"), "{:?}", l.warnings);
    // Through a scene, the warning reaches the user with the object named.
    let s = scene(dir.path(), "blender247.ply", "");
    assert!(s.warnings.iter().any(|w| w.contains("line 3") && w.contains("objects[0]")), "{:?}", s.warnings);
}

#[test]
fn scene_defaults_name_material_fit_and_light() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "pyramid.obj", obj_text(false));
    let path = write(
        dir.path(),
        "my-scene.toml",
        "[[objects]]\ntype = \"mesh\"\nfile = \"pyramid.obj\"\nfit = { size = 100.0, center = [10, 0, 400] }\n\
         [[objects]]\ntype = \"rect\"\ncenter = [0, 0, 900]\nsize = [50, 50]\n",
    );
    let s = io::load_scene(&path.to_string_lossy(), Path::new("")).unwrap();
    assert_eq!(s.name, "my-scene");
    assert_eq!(s.objects[0].name, "pyramid");
    assert!(matches!(s.objects[0].material, Material::Albedo(a) if a == DVec3::splat(0.8)));
    assert!(matches!(s.objects[1].material, Material::Albedo(a) if a == DVec3::splat(0.8)));
    assert_eq!(s.light, Some(io::scene_file::DEFAULT_LIGHT));
    let Shape::Mesh(m) = &s.objects[0].shape else { panic!() };
    let (lo, hi) = m.bounds();
    // The pyramid is 2 x 2 x 1: its largest side becomes 100 mm, its box centred on (10, 0, 400).
    assert_eq!(hi - lo, DVec3::new(100.0, 100.0, 50.0));
    assert_eq!(0.5 * (lo + hi), DVec3::new(10.0, 0.0, 400.0));
    // `fit` and `transform` together, and a bad size, are errors naming the field.
    for (extra, field) in [
        ("fit = { size = 1.0, center = [0, 0, 1] }\ntransform = { scale = [1, 1, 1] }", "objects[0].fit"),
        ("fit = { size = -1.0, center = [0, 0, 1] }", "objects[0].fit.size"),
        ("fit = { size = 1.0, centre = [0, 0, 1] }", "centre"),
    ] {
        let p =
            write(dir.path(), "bad.toml", format!("[[objects]]\ntype = \"mesh\"\nfile = \"pyramid.obj\"\n{extra}\n"));
        let e = io::load_scene(&p.to_string_lossy(), Path::new("")).unwrap_err().to_string();
        assert!(e.contains("bad.toml") && e.contains(field), "{e}");
    }
    // `type = "none"` turns the default light off; rect-only scenes have no light.
    let p = write(
        dir.path(),
        "unlit.toml",
        "[light]\ntype = \"none\"\n[[objects]]\ntype = \"mesh\"\nfile = \"pyramid.obj\"\ntransform = { translation = [0, 0, 100] }\n",
    );
    assert_eq!(io::load_scene(&p.to_string_lossy(), Path::new("")).unwrap().light, None);
    let p = write(dir.path(), "rects.toml", "[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 900]\nsize = [50, 50]\n");
    assert_eq!(io::load_scene(&p.to_string_lossy(), Path::new("")).unwrap().light, None);
    // A model in metres (here 2 mm wide after a 1e-3 scale) is reported as tiny.
    let p = write(
        dir.path(),
        "tiny.toml",
        "[[objects]]\ntype = \"mesh\"\nfile = \"pyramid.obj\"\ntransform = { scale = [0.001, 0.001, 0.001], translation = [0, 0, 100] }\n",
    );
    let s = io::load_scene(&p.to_string_lossy(), Path::new("")).unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("spans only") && w.contains("fit")), "{:?}", s.warnings);
}

#[test]
fn multi_material_files_become_one_object_per_material() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "two.mtl", "newmtl red\nKd 0.5 0.1 0.1\nnewmtl blue\nKd 0.1 0.1 0.5\n");
    let mut obj = String::from("mtllib two.mtl\n");
    for p in P {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    obj += "usemtl red\nf 1 2 5\nf 2 3 5\nusemtl blue\nf 3 4 5\nf 4 1 5\nf 1 4 3\nf 1 3 2\n";
    write(dir.path(), "two.obj", obj);
    let s = scene(dir.path(), "two.obj", "");
    assert_eq!(s.objects.len(), 2);
    assert_eq!(s.objects[0].name, "two [red]");
    assert!(matches!(s.objects[0].material, Material::Albedo(a) if a == DVec3::new(0.5, 0.1, 0.1)));
    assert!(matches!(s.objects[1].material, Material::Albedo(a) if a == DVec3::new(0.1, 0.1, 0.5)));
    assert_eq!(s.triangle_count(), 6);
    // An explicit material keeps the file as one object.
    assert_eq!(scene(dir.path(), "two.obj", "material = { albedo = [1, 1, 1] }").objects.len(), 1);
}

#[test]
fn shipped_fixtures_in_every_format_hold_the_same_triangles() {
    let data = |f: &str| Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(f);
    let corners = |m: &inimtrace::scene::Mesh| -> Vec<DVec3> {
        m.triangles.iter().flatten().map(|&i| m.positions[i as usize]).collect()
    };
    let ply = load_mesh(&data("pyramid_ascii.ply")).unwrap().mesh;
    let ply_uvs: Vec<_> = ply.triangles.iter().flatten().map(|&i| ply.uvs.as_ref().unwrap()[i as usize]).collect();
    for f in ["pyramid.gltf", "pyramid.glb", "pyramid_ascii.stl", "pyramid_binary.stl"] {
        let l = load_mesh(&data(f)).unwrap_or_else(|e| panic!("{e}"));
        assert!(l.warnings.is_empty(), "{f}: {:?}", l.warnings);
        assert_eq!(corners(&l.mesh), corners(&ply), "{f}");
        if f.contains("gl") {
            let uvs: Vec<_> =
                l.mesh.triangles.iter().flatten().map(|&i| l.mesh.uvs.as_ref().unwrap()[i as usize]).collect();
            assert_eq!(uvs, ply_uvs, "{f}: uvs in the OBJ/PLY convention");
            let n = l.mesh.normals.as_ref().unwrap();
            assert!(n.iter().all(|v| (v.length() - 1.0).abs() < 1e-12), "{f}: unit normals");
        }
    }
}
