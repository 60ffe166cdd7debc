//! Wavefront OBJ meshes, read through the `tobj` crate (single index; polygons triangulated by
//! [`crate::scene::polygon::triangulate`]: convex faces as a fan, concave ones by ear clipping). A validation
//! pass of our own runs first so that bad numbers, out-of-range indices and non-finite vertices
//! are reported with their line number (tobj's errors carry none). Multi-object files are merged
//! into one [`Mesh`]; each object's material (`usemtl`: `map_Kd` resolved relative to the OBJ
//! file, else `Kd` as a linear colour) becomes a [`MeshPart`]. The diffuse texture of the first
//! material that has one is also returned on its own (`texture = "mtl"` in a scene file). A
//! missing `.mtl` file is not an error (no materials). Shared conventions (colours, degenerate
//! triangles): [`super::mesh`].

use std::cell::RefCell;
use std::io::Cursor;
use std::path::Path;

use glam::{DVec2, DVec3};

use super::input::Reach;
use super::mesh::{srgb_to_linear, FileMaterial, FileTexture, Loaded, MeshPart, TextureSource};
use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

/// Converts tobj's float (f64 with the `use_f64` feature, f32 without) to f64.
fn tf<F: Into<f64>>(x: F) -> f64 {
    x.into()
}

pub(super) fn load_obj(path: &Path, bytes: &[u8], reach: &Reach) -> Result<Loaded> {
    let mut warnings = Vec::new();
    let text = obj_text(path, bytes, &mut warnings)?;
    let refs =
        References { reach, base_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(), refused: None.into() };
    let (models, materials) = parse_with_tobj(path, &text, &refs, &mut warnings)?;
    let texture_path = |t: &str| refs.resolve("map_Kd", texture_file_name(t));

    let mut builder = MeshBuilder::new();
    let mut texture = None;
    let mut parts: Vec<(Option<usize>, MeshPart)> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let first = builder.mesh.triangles.len();
        let range = first..first + m.indices.len() / 3;
        match parts.last_mut() {
            Some((id, part)) if *id == m.material_id => part.triangles.end = range.end,
            _ => {
                let material =
                    m.material_id.and_then(|id| materials.get(id)).map(|mat| file_material(mat, texture_path));
                parts.push((m.material_id, MeshPart { triangles: range, material: material.unwrap_or_default() }));
            }
        }
        builder.append(path, m)?;
        if texture.is_none() {
            texture = m
                .material_id
                .and_then(|id| materials.get(id))
                .and_then(|mat| mat.diffuse_texture.as_deref())
                .map(texture_path);
        }
    }
    let mesh = builder.finish();
    let mut parts: Vec<MeshPart> = parts.into_iter().map(|(_, p)| p).filter(|p| !p.triangles.is_empty()).collect();
    for p in &mut parts {
        p.material.vertex_colors = mesh.colors.is_some();
    }
    if let Some(why) = refs.refused.into_inner() {
        return Err(Error::parse(path, why));
    }
    Ok(Loaded { mesh, parts, texture, warnings })
}

/// The OBJ's text as tobj is given it: decoded ([`decode_text`]), checked line by line
/// ([`validate_obj_text`]; vertex colours that tobj would misread dropped, with a warning), and
/// unnamed `usemtl` lines dropped.
fn obj_text(path: &Path, bytes: &[u8], warnings: &mut Vec<String>) -> Result<String> {
    let text = decode_text(path, bytes, warnings)?;
    let text = match validate_obj_text(path, &text)? {
        None => text,
        Some(why) => {
            warnings.push(format!("{}: {why}; the mesh is shown without vertex colours", path.display()));
            drop_vertex_colors(&text)
        }
    };
    Ok(drop_unnamed_usemtl(path, text, warnings))
}

/// The files an OBJ names (`mtllib`, `map_Kd`), resolved relative to its folder within the reach.
struct References<'a> {
    reach: &'a Reach,
    base_dir: std::path::PathBuf,
    /// The first reference that leaves the reach: the load's error.
    refused: RefCell<Option<String>>,
}

impl References<'_> {
    /// The path of the file `name` (a reference of kind `what`); one that leaves the reach is
    /// remembered as refused (the first only) and joined to the folder as given.
    fn resolve(&self, what: &str, name: &str) -> std::path::PathBuf {
        let file = super::mesh::file_name_path(Path::new(""), name);
        self.reach.resolve(&self.base_dir, &file).unwrap_or_else(|why| {
            self.refused.borrow_mut().get_or_insert_with(|| format!("{what}: {why}"));
            self.base_dir.join(file)
        })
    }
}

/// tobj's models (polygons whole, points and lines ignored) and materials of the OBJ `text`. A
/// missing or broken .mtl loses its materials, with a warning; an `mtllib` that leaves the
/// reach is an error.
fn parse_with_tobj(
    path: &Path,
    text: &str,
    refs: &References,
    warnings: &mut Vec<String>,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>)> {
    // tobj's optional features ("merging", "reordering") add fields that must stay false.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mtl_warnings = RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(&mut Cursor::new(text.as_bytes()), &options, |mtl| {
        let file = refs.resolve("mtllib", &mtl.to_string_lossy());
        if refs.refused.borrow().is_some() {
            return Err(tobj::LoadError::OpenFileFailed);
        }
        load_mtl(path, &file, &mut mtl_warnings.borrow_mut())
    })
    .map_err(|e| Error::parse(path, format!("OBJ: {e}")))?;
    if let Some(why) = refs.refused.borrow_mut().take() {
        return Err(Error::parse(path, why));
    }
    warnings.extend(mtl_warnings.into_inner());
    Ok((models, materials.unwrap_or_default()))
}

/// A tobj material as a mesh part's material: `Kd` as a linear colour, `map_Kd` (resolved by
/// `texture_path`) as its texture.
fn file_material(mat: &tobj::Material, texture_path: impl Fn(&str) -> std::path::PathBuf) -> FileMaterial {
    let kd = mat.diffuse.map(|d| DVec3::new(tf(d[0]), tf(d[1]), tf(d[2])));
    let texture = mat.diffuse_texture.as_deref().map(|t| FileTexture {
        source: TextureSource::File(texture_path(t)),
        filter: None,
        wrap: None,
    });
    FileMaterial {
        name: Some(mat.name.clone()),
        // With a texture, `map_Kd` alone gives the colour (exporters write a
        // placeholder `Kd` beside it, e.g. Blender's 0.8); `Kd` is the colour
        // when the texture cannot be read.
        base_color: kd.filter(|_| texture.is_none()),
        untextured_color: kd.filter(|_| texture.is_some()),
        texture,
        vertex_colors: false,
    }
}

/// The file's objects merged into one mesh: positions and triangles, and the per-vertex
/// normals, texture coordinates and colours, each kept only if every object has them.
struct MeshBuilder {
    mesh: Mesh,
    normals: Option<Vec<DVec3>>,
    uvs: Option<Vec<DVec2>>,
    colors: Option<Vec<DVec3>>,
    /// Faces counted across the file's objects, from 0, for errors.
    face: usize,
}

impl MeshBuilder {
    fn new() -> Self {
        MeshBuilder {
            mesh: Mesh::default(),
            normals: Some(Vec::new()),
            uvs: Some(Vec::new()),
            colors: Some(Vec::new()),
            face: 0,
        }
    }

    /// Appends one of tobj's meshes (an object of the file): its vertices, its faces
    /// triangulated, and its vertex attributes.
    fn append(&mut self, path: &Path, m: &tobj::Mesh) -> Result<()> {
        let mesh = &mut self.mesh;
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
            crate::scene::polygon::triangulate(&mesh.positions, &corners, &mut mesh.triangles)
                .map_err(|m| Error::parse(path, format!("face {}: {m}", self.face)))?;
            self.face += 1;
        }
        self.append_attributes(m, nv);
        Ok(())
    }

    /// The normals, texture coordinates and colours of one of tobj's meshes of `nv` vertices;
    /// one it lacks (or has not for every vertex) is dropped for the whole file.
    fn append_attributes(&mut self, m: &tobj::Mesh, nv: usize) {
        if m.normals.len() == 3 * nv {
            if let Some(n) = &mut self.normals {
                n.extend(m.normals.chunks_exact(3).map(|c| DVec3::new(tf(c[0]), tf(c[1]), tf(c[2]))));
            }
        } else {
            self.normals = None;
        }
        if m.texcoords.len() == 2 * nv {
            if let Some(t) = &mut self.uvs {
                t.extend(m.texcoords.chunks_exact(2).map(|c| DVec2::new(tf(c[0]), tf(c[1]))));
            }
        } else {
            self.uvs = None;
        }
        if m.vertex_color.len() == 3 * nv {
            if let Some(col) = &mut self.colors {
                col.extend(
                    m.vertex_color.chunks_exact(3).map(|c| {
                        DVec3::new(srgb_to_linear(tf(c[0])), srgb_to_linear(tf(c[1])), srgb_to_linear(tf(c[2])))
                    }),
                );
            }
        } else {
            self.colors = None;
        }
    }

    /// The mesh, with the attributes every object had (none if no vertex has one).
    fn finish(self) -> Mesh {
        let mut mesh = self.mesh;
        mesh.normals = nonempty(self.normals);
        mesh.uvs = nonempty(self.uvs);
        mesh.colors = nonempty(self.colors);
        mesh
    }
}

/// The text of an OBJ or MTL file: UTF-8 (a byte-order mark dropped), UTF-16 with a byte-order
/// mark, or, when the bytes are not UTF-8, Latin-1 with a warning (old Windows exporters write
/// material names that way; numbers are ASCII in every case).
fn decode_text(path: &Path, bytes: &[u8], warnings: &mut Vec<String>) -> Result<String> {
    let utf16 = |big_endian: bool| -> Result<String> {
        let units: Vec<u16> = bytes[2..]
            .chunks(2)
            .map(|c| {
                let pair = [c[0], c.get(1).copied().unwrap_or(0)];
                if big_endian {
                    u16::from_be_bytes(pair)
                } else {
                    u16::from_le_bytes(pair)
                }
            })
            .collect();
        String::from_utf16(&units)
            .map_err(|_| Error::parse(path, "not valid UTF-16 text (the file starts with a UTF-16 byte-order mark)"))
    };
    match bytes {
        [0xEF, 0xBB, 0xBF, rest @ ..] => std::str::from_utf8(rest)
            .map(str::to_owned)
            .map_err(|_| Error::parse(path, "not valid UTF-8 text (the file starts with a UTF-8 byte-order mark)")),
        [0xFE, 0xFF, ..] => utf16(true),
        [0xFF, 0xFE, ..] => utf16(false),
        _ => match std::str::from_utf8(bytes) {
            Ok(text) => Ok(text.to_owned()),
            Err(e) => {
                let line = 1 + bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count();
                warnings.push(format!(
                    "{}: line {line}: not UTF-8 text; the file is read as Latin-1 (names may show other characters)",
                    path.display()
                ));
                Ok(bytes.iter().map(|&b| char::from(b)).collect())
            }
        },
    }
}

/// The OBJ text with the colours of `v x y z r g b` lines left out (`v x y z`); every line
/// stays where it was, so line numbers do not change.
fn drop_vertex_colors(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for l in text.split_inclusive('\n') {
        let words: Vec<&str> = l.split_whitespace().collect();
        if words.len() == 7 && words[0] == "v" {
            out.push_str(&words[..4].join(" "));
            out.push('\n');
        } else {
            out.push_str(l);
        }
    }
    out
}

/// Turns `usemtl` lines without a material name (Blender 2.61 wrote them) into comments, with a
/// warning: tobj refuses them, Assimp and Blender read "no material".
fn drop_unnamed_usemtl(path: &Path, text: String, warnings: &mut Vec<String>) -> String {
    let unnamed = |l: &str| l.trim() == "usemtl";
    let lines: Vec<usize> = text.lines().enumerate().filter(|(_, l)| unnamed(l)).map(|(i, _)| i + 1).collect();
    if lines.is_empty() {
        return text;
    }
    warnings.push(format!(
        "{}: line {}: `usemtl` without a material name; read as no material{}",
        path.display(),
        lines[0],
        if lines.len() > 1 {
            format!(" (and {})", crate::count::count(lines.len() - 1, "more such line"))
        } else {
            String::new()
        }
    ));
    let mut out = String::with_capacity(text.len() + lines.len());
    for l in text.split_inclusive('\n') {
        if unnamed(l) {
            out.push('#');
        }
        out.push_str(l);
    }
    out
}

/// Reads the material library `mtl` named by the OBJ file `obj`. A file that is missing or
/// cannot be parsed gives a warning naming both, and no materials.
fn load_mtl(obj: &Path, mtl: &Path, warnings: &mut Vec<String>) -> tobj::MTLLoadResult {
    let parsed = crate::io::input::read_regular(mtl).map_err(|e| e.to_string()).and_then(|bytes| {
        let text = decode_text(mtl, &bytes, warnings).map_err(|e| e.to_string())?;
        tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes())).map_err(|e| format!("{}: {e}", mtl.display()))
    });
    parsed.map_err(|why| {
        warnings.push(format!(
            "{}: material library cannot be read ({why}); its materials are ignored (the base colour is used)",
            obj.display()
        ));
        tobj::LoadError::OpenFileFailed
    })
}

/// The file name of an MTL texture statement (`map_Kd [options] file`): the options of the MTL
/// specification (`-blendu on`, `-s 1 1 1`, `-mm 0 1`, ...) before the name are skipped.
fn texture_file_name(spec: &str) -> &str {
    let mut rest = spec.trim();
    while let Some(opt) = rest.strip_prefix('-') {
        let name_end = opt.find(char::is_whitespace).unwrap_or(opt.len());
        let (values_min, values_max) = match &opt[..name_end] {
            "blendu" | "blendv" | "bm" | "boost" | "cc" | "clamp" | "imfchan" | "texres" | "type" => (1, 1),
            "mm" => (2, 2),
            "o" | "s" | "t" => (1, 3),
            _ => break, // not an option: a file name that starts with '-'
        };
        let mut after = opt[name_end..].trim_start();
        for k in 0..values_max {
            let end = after.find(char::is_whitespace).unwrap_or(after.len());
            let word = &after[..end];
            let numeric = word.parse::<f64>().is_ok();
            if word.is_empty() || (k >= values_min && !numeric) {
                break;
            }
            after = after[end..].trim_start();
        }
        rest = after;
    }
    rest
}

/// `None` for an absent or empty attribute.
fn nonempty<T>(v: Option<Vec<T>>) -> Option<Vec<T>> {
    v.filter(|v| !v.is_empty())
}

/// Checks an OBJ file line by line before tobj reads it, so that errors carry line numbers:
/// numbers in `v`/`vt`/`vn` lines, finite vertex positions, and face indices (`v`, `v/vt`,
/// `v//vn`, `v/vt/vn`; negative = relative to the count so far) within the counts in the file.
/// Vertex colours that cannot be used (given for some vertices only, or not finite) are not an
/// error: the answer is `Some(why)`, and the caller drops the colours.
fn validate_obj_text(path: &Path, text: &str) -> Result<Option<String>> {
    let err = |line: usize, msg: String| Error::parse(path, format!("line {line}: {msg}"));
    let parse_numbers = |line: usize, what: &str, words: std::str::SplitWhitespace| -> Result<Vec<f64>> {
        words.map(|w| w.parse::<f64>().map_err(|_| err(line, format!("bad number '{w}' in {what}")))).collect()
    };
    // Pass 1: attribute lines; counts of positions, texcoords, normals.
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    let mut colored: Option<bool> = None;
    let mut color_problem: Option<String> = None;
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
                    Some(c) if c != has_color && color_problem.is_none() => {
                        color_problem = Some(format!(
                            "line {line}: vertex {nv} {} a colour but the first vertex {}: colours must be given for \
                             all vertices or none",
                            if has_color { "has" } else { "lacks" },
                            if c { "has one" } else { "does not" }
                        ))
                    }
                    Some(_) => {}
                }
                if has_color && color_problem.is_none() && vals[3..].iter().any(|v| !v.is_finite()) {
                    color_problem = Some(format!("line {line}: vertex {nv} has a non-finite colour"));
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
    Ok(color_problem)
}
