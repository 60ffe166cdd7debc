//! glTF 2.0 meshes (`.gltf` with embedded `data:` or external buffers, and binary `.glb`): the
//! format most modelled and many scanned meshes arrive in. The `gltf` crate parses and validates
//! the JSON document (index ranges, required extensions); buffers and accessors are read here so
//! that every malformed file gives one line naming the file and the element
//! (`meshes[0].primitives[1].indices: ...`), never a panic. This file reads the document and its
//! buffers; `gltf_nodes.rs` walks the node hierarchy, `gltf_primitive.rs` reads triangle
//! primitives, `gltf_material.rs` their materials and `gltf_accessor.rs` the accessors.
//!
//! What is read:
//! * the default scene (else the first; else every node that is no other node's child), its node
//!   hierarchy with each node's `matrix` or translation/rotation/scale composed in `f64`; a node
//!   that is its own ancestor is an error;
//! * triangle primitives (`TRIANGLES`, and `TRIANGLE_STRIP` / `TRIANGLE_FAN` unrolled to
//!   triangles in the specification's order); points and lines are skipped with a warning;
//! * `POSITION` (float `VEC3`), `NORMAL` (float `VEC3`, transformed by the inverse transpose),
//!   `TEXCOORD_n` (float or normalised integer `VEC2`; `v` flipped to the OBJ convention) for the
//!   set the material's base colour texture uses, and `COLOR_0` (float or normalised integer
//!   `VEC3`/`VEC4`, linear, alpha dropped);
//! * each primitive's material as a [`FileMaterial`]: `baseColorFactor` (linear), `baseColorTexture`
//!   (PNG or JPEG, sRGB; file, `data:` URI or buffer view), sampler filter and `wrapS` (mirrored
//!   repeat read as repeat, with a warning).
//!
//! Everything else (animations, skins, morph targets, cameras, other textures, PBR parameters,
//! alpha) is ignored; extensions the file uses are named in a warning, and a file that
//! *requires* one is refused. Sparse accessors are refused. Coordinates are used as they are
//! (taken as millimetres, where glTF means metres): see [`super::mesh`].

use std::path::{Path, PathBuf};

use base64::Engine;
use gltf::mesh::Mode;

use super::gltf_accessor::Reader;
use super::gltf_nodes::{check_expanded_size, instances};
use super::gltf_primitive::Builder;
use super::input::Reach;
use super::mesh::Loaded;
use crate::count::count;
use crate::error::{Error, Result};

pub(super) fn load_gltf(path: &Path, bytes: &[u8], reach: &Reach) -> Result<Loaded> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| Error::parse(path, format!("not a readable glTF/GLB file: {e}")))?;
    let doc = &gltf.document;
    refuse_required_extensions(path, doc)?;
    validate(path, doc)?;
    let base = path.parent().unwrap_or(Path::new(""));
    let mut warnings: Vec<String> = doc
        .extensions_used()
        .map(|ext| format!("{}: glTF extension {ext} is used by the file and ignored", path.display()))
        .collect();
    let buffers = doc
        .buffers()
        .map(|b| load_buffer(path, base, reach, &b, gltf.blob.as_deref()))
        .collect::<Result<Vec<Vec<u8>>>>()?;
    let reader = Reader { path, buffers: &buffers, reach };

    check_expanded_size(path, doc)?;
    let instances = instances(path, doc)?;
    let mut out = Builder::default();
    for (node, world) in &instances {
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            let at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let mode = prim.mode();
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                warnings.push(format!(
                    "{}: {at}: mode {mode:?} draws points or lines, not triangles; skipped",
                    path.display()
                ));
                continue;
            }
            out.add_primitive(&reader, &at, &prim, *world, &mut warnings)?;
        }
    }
    if out.mesh.triangles.is_empty() {
        return Err(Error::parse(
            path,
            format!(
                "contains no triangles ({} with a mesh in the scene, {} in the file)",
                count(instances.iter().filter(|(n, _)| n.mesh().is_some()).count(), "node"),
                count(doc.meshes().count(), "mesh")
            ),
        ));
    }
    let Builder { mut mesh, parts, has_normals, has_uvs, has_colors, .. } = out;
    if !has_normals {
        mesh.normals = None;
    }
    if !has_uvs {
        mesh.uvs = None;
    }
    if !has_colors {
        mesh.colors = None;
    }
    let parts = parts.into_iter().map(|(_, p)| p).collect();
    Ok(Loaded { mesh, parts, texture: None, warnings })
}

/// A file that lists extensions in `extensionsRequired` cannot be read correctly without them,
/// and this reader implements none: it is refused naming each one. (The `gltf` crate's own check
/// lets through the extensions its enabled features parse, which this reader would still ignore.)
fn refuse_required_extensions(path: &Path, doc: &gltf::Document) -> Result<()> {
    let required: Vec<&str> = doc.extensions_required().collect();
    if required.is_empty() {
        return Ok(());
    }
    let names = required.iter().map(|e| format!("`{e}`")).collect::<Vec<_>>().join(", ");
    Err(Error::parse(
        path,
        format!(
            "extensionsRequired: the file requires the glTF {} {names}, which inimtrace does not support \
             (it reads core glTF 2.0 only); export the mesh without {}",
            if required.len() == 1 { "extension" } else { "extensions" },
            if required.len() == 1 { "it" } else { "them" },
        ),
    ))
}

/// The `gltf` crate's validation (index ranges, required extensions, ...), less the rule that
/// `POSITION` accessors declare `min` and `max`, which this reader does not use and exporters
/// sometimes leave out. The first problem (with its JSON path) is the error, on one line.
fn validate(path: &Path, doc: &gltf::Document) -> Result<()> {
    use gltf::json::validation::{Checked, Error as V, Validate};
    let root = doc.as_json();
    // gltf-json 1.4's own check of POSITION indexes the accessors without a bounds check.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (k, prim) in mesh.primitives.iter().enumerate() {
            if let Some(i) = prim.attributes.get(&Checked::Valid(gltf::json::mesh::Semantic::Positions)) {
                if i.value() >= root.accessors.len() {
                    return Err(Error::parse(
                        path,
                        format!(
                            "meshes[{m}].primitives[{k}].attributes.POSITION: accessor {} does not exist (the file has {})",
                            i.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |p, e| {
        let p = p().to_string();
        if !(matches!(e, V::Missing) && (p.ends_with(".min") || p.ends_with(".max"))) {
            problems.push((p, e));
        }
    });
    let more = if problems.len() > 1 {
        format!(" (and {} more)", count(problems.len() - 1, "problem"))
    } else {
        String::new()
    };
    match problems.first() {
        None => Ok(()),
        Some((p, V::Unsupported)) => {
            Err(Error::parse(path, format!("{p}: required extension not supported by inimtrace{more}")))
        }
        Some((p, e)) => Err(Error::parse(path, format!("invalid glTF: {p}: {e}{more}"))),
    }
}

/// The bytes of a `data:` URI, or the file a relative URI names.
pub(super) enum UriTarget {
    Data(Vec<u8>),
    File(PathBuf),
}

pub(super) fn resolve_uri(path: &Path, base: &Path, reach: &Reach, at: &str, uri: &str) -> Result<UriTarget> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, data)) = rest.split_once(',') else {
            return Err(Error::parse(path, format!("{at}: malformed data URI (no comma)")));
        };
        if !header.ends_with(";base64") {
            return Err(Error::parse(path, format!("{at}: data URI is not base64-encoded")));
        }
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| Error::parse(path, format!("{at}: bad base64 in data URI: {e}")))?;
        return Ok(UriTarget::Data(bytes));
    }
    if uri.contains("://") {
        return Err(Error::parse(path, format!("{at}: URI `{uri}` is not a relative file path or data URI")));
    }
    let file = PathBuf::from(percent_decode(uri));
    reach.resolve(base, &file).map(UriTarget::File).map_err(|why| Error::parse(path, format!("{at}: {why}")))
}

/// Decodes `%XX` escapes of a URI path (invalid escapes are kept as they are).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn load_buffer(path: &Path, base: &Path, reach: &Reach, buffer: &gltf::Buffer, blob: Option<&[u8]>) -> Result<Vec<u8>> {
    let at = format!("buffers[{}]", buffer.index());
    let data = match buffer.source() {
        gltf::buffer::Source::Bin => blob
            .ok_or_else(|| Error::parse(path, format!("{at}: refers to the GLB binary chunk, which the file lacks")))?
            .to_vec(),
        gltf::buffer::Source::Uri(uri) => match resolve_uri(path, base, reach, &at, uri)? {
            UriTarget::Data(d) => d,
            UriTarget::File(file) => crate::io::input::read_regular(&file)
                .map_err(|e| Error::parse(path, format!("{at}: cannot read it: {e}")))?,
        },
    };
    if data.len() < buffer.length() {
        return Err(Error::parse(
            path,
            format!("{at}: holds {} bytes but the file declares byteLength {}", data.len(), buffer.length()),
        ));
    }
    Ok(data)
}
