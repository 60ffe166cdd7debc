//! Wavefront OBJ meshes, read through the `tobj` crate (single index; polygons triangulated by
//! [`crate::scene::polygon::triangulate`]: convex faces as a fan, concave ones by ear clipping). A validation
//! pass of our own runs first so that bad numbers, out-of-range indices and non-finite vertices
//! are reported with their line number (tobj's errors carry none). Multi-object files are merged
//! into one [`Mesh`]; each object's material (`usemtl`: `map_Kd` resolved relative to the OBJ
//! file, else `Kd` as a linear colour) becomes a [`MeshPart`]. The diffuse texture of the first
//! material that has one is also returned on its own (`texture = "mtl"` in a scene file). A
//! missing `.mtl` file is not an error (no materials). Shared conventions (colours, degenerate
//! triangles): [`super::mesh`].

use std::io::Cursor;
use std::path::Path;

use glam::{DVec2, DVec3};

use super::mesh::{srgb_to_linear, FileMaterial, FileTexture, Loaded, MeshPart, TextureSource};
use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

/// Converts tobj's float (f64 with the `use_f64` feature, f32 without) to f64.
fn tf<F: Into<f64>>(x: F) -> f64 {
    x.into()
}

pub(super) fn load_obj(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count();
        Error::parse(path, format!("line {line}: not valid UTF-8 text"))
    })?;
    validate_obj_text(path, text)?;

    // tobj's optional features ("merging", "reordering") add fields that must stay false.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (models, materials) =
        tobj::load_obj_buf(&mut Cursor::new(text), &options, |mtl| tobj::load_mtl(base_dir.join(mtl)))
            .map_err(|e| Error::parse(path, format!("OBJ: {e}")))?;
    // A missing or broken .mtl only loses the texture.
    let materials = materials.unwrap_or_default();

    let mut mesh = Mesh::default();
    let (mut normals, mut uvs, mut colors) = (Some(Vec::new()), Some(Vec::new()), Some(Vec::new()));
    let mut texture = None;
    let mut parts: Vec<(Option<usize>, MeshPart)> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let first = mesh.triangles.len();
        let range = first..first + m.indices.len() / 3;
        match parts.last_mut() {
            Some((id, part)) if *id == m.material_id => part.triangles.end = range.end,
            _ => {
                let material = m.material_id.and_then(|id| materials.get(id)).map(|mat| FileMaterial {
                    name: Some(mat.name.clone()),
                    // With a texture, `map_Kd` alone gives the colour (exporters write a
                    // placeholder `Kd` beside it, e.g. Blender's 0.8).
                    base_color: mat
                        .diffuse
                        .filter(|_| mat.diffuse_texture.is_none())
                        .map(|d| DVec3::new(tf(d[0]), tf(d[1]), tf(d[2]))),
                    texture: mat.diffuse_texture.as_deref().map(|t| FileTexture {
                        source: TextureSource::File(base_dir.join(t.trim())),
                        filter: None,
                        wrap: None,
                    }),
                    vertex_colors: false,
                });
                parts.push((m.material_id, MeshPart { triangles: range, material: material.unwrap_or_default() }));
            }
        }
        let nv = m.positions.len() / 3;
        let offset = mesh.positions.len();
        let offset_u32 =
            u32::try_from(offset).map_err(|_| Error::parse(path, "more than 2^32 vertices are not supported"))?;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|c| DVec3::new(tf(c[0]), tf(c[1]), tf(c[2]))));
        // tobj keeps polygons whole (`triangulate: false`): convex faces become the fan that
        // tobj would have made, concave ones are cut into ears.
        let mut start = 0;
        let arities: Box<dyn Iterator<Item = usize>> = if m.face_arities.is_empty() {
            Box::new(std::iter::repeat_n(3, m.indices.len() / 3))
        } else {
            Box::new(m.face_arities.iter().map(|&a| a as usize))
        };
        let mut corners = Vec::new();
        for arity in arities {
            corners.clear();
            corners.extend(m.indices[start..start + arity].iter().map(|&i| i + offset_u32));
            start += arity;
            crate::scene::polygon::triangulate(&mesh.positions, &corners, &mut mesh.triangles);
        }
        if m.normals.len() == 3 * nv {
            if let Some(n) = &mut normals {
                n.extend(m.normals.chunks_exact(3).map(|c| DVec3::new(tf(c[0]), tf(c[1]), tf(c[2]))));
            }
        } else {
            normals = None;
        }
        if m.texcoords.len() == 2 * nv {
            if let Some(t) = &mut uvs {
                t.extend(m.texcoords.chunks_exact(2).map(|c| DVec2::new(tf(c[0]), tf(c[1]))));
            }
        } else {
            uvs = None;
        }
        if m.vertex_color.len() == 3 * nv {
            if let Some(col) = &mut colors {
                col.extend(
                    m.vertex_color.chunks_exact(3).map(|c| {
                        DVec3::new(srgb_to_linear(tf(c[0])), srgb_to_linear(tf(c[1])), srgb_to_linear(tf(c[2])))
                    }),
                );
            }
        } else {
            colors = None;
        }
        if texture.is_none() {
            texture = m
                .material_id
                .and_then(|id| materials.get(id))
                .and_then(|mat| mat.diffuse_texture.as_deref())
                .map(|tex| base_dir.join(tex.trim()));
        }
    }
    mesh.normals = nonempty(normals);
    mesh.uvs = nonempty(uvs);
    mesh.colors = nonempty(colors);
    let mut parts: Vec<MeshPart> = parts.into_iter().map(|(_, p)| p).filter(|p| !p.triangles.is_empty()).collect();
    for p in &mut parts {
        p.material.vertex_colors = mesh.colors.is_some();
    }
    Ok(Loaded { mesh, parts, texture, warnings: Vec::new() })
}

/// `None` for an absent or empty attribute.
fn nonempty<T>(v: Option<Vec<T>>) -> Option<Vec<T>> {
    v.filter(|v| !v.is_empty())
}

/// Checks an OBJ file line by line before tobj reads it, so that errors carry line numbers:
/// numbers in `v`/`vt`/`vn` lines, finite vertex positions, and face indices (`v`, `v/vt`,
/// `v//vn`, `v/vt/vn`; negative = relative to the count so far) within the counts in the file.
fn validate_obj_text(path: &Path, text: &str) -> Result<()> {
    let err = |line: usize, msg: String| Error::parse(path, format!("line {line}: {msg}"));
    let parse_numbers = |line: usize, what: &str, words: std::str::SplitWhitespace| -> Result<Vec<f64>> {
        words.map(|w| w.parse::<f64>().map_err(|_| err(line, format!("bad number '{w}' in {what}")))).collect()
    };
    // Pass 1: attribute lines; counts of positions, texcoords, normals.
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    let mut colored: Option<bool> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => {
                let vals = parse_numbers(line, "vertex", words)?;
                let (p, has_color) = match vals.len() {
                    3 => ([vals[0], vals[1], vals[2]], false),
                    4 if vals[3] == 0.0 => {
                        return Err(err(line, "vertex has homogeneous coordinate w = 0".to_string()))
                    }
                    4 => ([vals[0] / vals[3], vals[1] / vals[3], vals[2] / vals[3]], false),
                    6 => ([vals[0], vals[1], vals[2]], true),
                    n => {
                        return Err(err(
                            line,
                            format!("vertex needs 3 (x y z), 4 (x y z w) or 6 (x y z r g b) numbers, found {n}"),
                        ))
                    }
                };
                nv += 1;
                match colored {
                    None => colored = Some(has_color),
                    Some(c) if c != has_color => {
                        return Err(err(
                            line,
                            format!(
                                "vertex {nv} {} a colour but the first vertex {}: colours must be given for all vertices or none",
                                if has_color { "has" } else { "lacks" },
                                if c { "has one" } else { "does not" }
                            ),
                        ))
                    }
                    Some(_) => {}
                }
                if p.iter().any(|v| !v.is_finite()) {
                    return Err(err(
                        line,
                        format!("vertex {nv} has a non-finite coordinate ({}, {}, {})", p[0], p[1], p[2]),
                    ));
                }
            }
            Some("vt") => {
                let vals = parse_numbers(line, "texture coordinate", words)?;
                if vals.len() < 2 {
                    return Err(err(line, format!("texture coordinate needs 2 values, found {}", vals.len())));
                }
                nvt += 1;
            }
            Some("vn") => {
                let vals = parse_numbers(line, "normal", words)?;
                if vals.len() < 3 {
                    return Err(err(line, format!("normal needs 3 values, found {}", vals.len())));
                }
                nvn += 1;
            }
            _ => {}
        }
    }
    // Pass 2: faces, with running counts for relative (negative) indices.
    let (mut cv, mut cvt, mut cvn) = (0usize, 0usize, 0usize);
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => cv += 1,
            Some("vt") => cvt += 1,
            Some("vn") => cvn += 1,
            Some("f") => {
                for (corner, word) in words.enumerate() {
                    let parts: Vec<&str> = word.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(err(line, format!("bad face vertex '{word}' (corner {})", corner + 1)));
                    }
                    let kinds = [
                        ("vertex", "vertices", cv, nv),
                        ("texture coordinate", "texture coordinates", cvt, nvt),
                        ("normal", "normals", cvn, nvn),
                    ];
                    for (part, (kind, kinds, so_far, total)) in parts.iter().zip(kinds) {
                        if part.is_empty() {
                            continue;
                        }
                        let idx: i64 = part.parse().map_err(|_| {
                            err(line, format!("bad face index '{part}' in '{word}' (corner {})", corner + 1))
                        })?;
                        let resolved = if idx < 0 { so_far as i64 + idx } else { idx - 1 };
                        if idx == 0 || resolved < 0 || resolved >= total as i64 {
                            return Err(err(
                                line,
                                format!(
                                    "face corner {} '{word}': {kind} index {idx} out of range (file has {total} {kinds})",
                                    corner + 1
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}
