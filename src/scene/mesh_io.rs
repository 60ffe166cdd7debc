//! Loading triangle meshes from files (Wavefront OBJ, Stanford PLY) and placing them in the
//! world with a scale/rotate/translate [`Transform`].
//!
//! The paper's scenes (Sec. 3.1) are planar rectangles; meshes extend the scene so that the
//! display simulation can be run on real 3-D objects through the mesh backends (Embree, BVH,
//! brute force). Everything here is input handling: every malformed file gives an [`Error`]
//! that names the file and the line or element, never a panic.
//!
//! Formats:
//! * `.obj` through the `tobj` crate (triangulated, single index). A validation pass of our own
//!   runs first so that bad numbers, out-of-range indices and non-finite vertices are reported
//!   with their line number (tobj's errors carry none). Multi-object files are merged into one
//!   [`Mesh`]. The diffuse texture (`map_Kd`) of the first material that has one is returned,
//!   resolved relative to the OBJ file; a missing `.mtl` file is not an error (no texture).
//! * `.ply` ASCII, binary little endian and binary big endian, read by the hand-written reader
//!   below. Crates were considered: `ply-rs` 0.1.3 is unmaintained (last release 2020, old
//!   `peg`), and its maintained fork `ply-rs-bw` 4 needs Rust 1.87 (this crate: 1.80) and reports
//!   a truncated binary body as a bare end-of-file I/O error without the element index. We only
//!   need vertices and faces, which the reader below covers in a few hundred lines with precise
//!   error locations. Polygons are fan-triangulated `(0, i, i + 1)`, like tobj does for OBJ.
//!
//! Attribute conventions:
//! * Per-vertex normals, uvs and colours are kept when the file gives them for every vertex
//!   (for merged OBJ objects: for every object); otherwise the attribute is `None`.
//! * UVs are as stored in the file (OBJ/PLY convention: `v = 0` is the bottom of the image).
//! * Colours are taken to be sRGB-encoded (what MeshLab and scanners write) and are linearised
//!   with the sRGB transfer function. PLY integer colours are first divided by their type's
//!   maximum (`uchar` by 255); PLY float and OBJ (`v x y z r g b`) colours are used as given in
//!   `[0, 1]`. So the same 8-bit colour written to a PLY file and, as `c / 255`, to an OBJ file
//!   loads to the same linear value.
//! * Zero-area triangles are removed and counted in [`MeshLoad::dropped_degenerate`]; the caller
//!   warns with the count.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

/// A mesh read from a file.
#[derive(Clone, Debug)]
pub struct MeshLoad {
    /// The mesh in file coordinates (apply a [`Transform`] to place it), degenerate triangles
    /// already removed.
    pub mesh: Mesh,
    /// How many zero-area triangles were removed.
    pub dropped_degenerate: usize,
    /// The OBJ material's diffuse texture, resolved relative to the OBJ file (not checked for
    /// existence: the caller opens it and reports a missing file).
    pub texture: Option<PathBuf>,
}

/// Loads a triangle mesh, choosing the format from the extension (`.obj`, `.ply`, any case).
///
/// Errors (all name the file): missing file or directory ([`Error::Io`]); unknown extension
/// ([`Error::Unsupported`]); malformed content, index out of range, non-finite vertex, or no
/// triangles left ([`Error::Parse`], with the line or element).
pub fn load_mesh(path: &Path) -> Result<MeshLoad> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::io(path, std::io::Error::other("is a directory, expected a mesh file (.obj or .ply)")));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let (mut mesh, texture) = match ext.as_deref() {
        Some("obj") => load_obj(path, &bytes)?,
        Some("ply") => (load_ply(path, &bytes)?, None),
        _ => {
            return Err(Error::Unsupported(format!(
                "{}: unknown mesh format (expected extension .obj or .ply)",
                path.display()
            )))
        }
    };
    let dropped_degenerate = mesh.remove_degenerate();
    if mesh.triangles.is_empty() {
        let why = if dropped_degenerate > 0 {
            format!("contains no triangles (all {dropped_degenerate} have zero area)")
        } else {
            "contains no triangles (empty mesh)".to_string()
        };
        return Err(Error::parse(path, why));
    }
    // The readers already checked everything; this is a cheap guard that they did.
    mesh.validate(&path.display().to_string())?;
    Ok(MeshLoad { mesh, dropped_degenerate, texture })
}

/// Decodes an sRGB-encoded component in `[0, 1]` to linear.
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

// ---------------------------------------------------------------------------------------------
// Transform
// ---------------------------------------------------------------------------------------------

/// Places a mesh in the world: `p' = translation + R (scale * p)` with
/// `R = Rz * Ry * Rx` (XYZ Euler angles in degrees, right-handed, applied X first, then Y, then
/// Z). Deserialises with defaults (scale 1, rotation 0, translation 0) and rejects unknown
/// fields; vectors are written as `[x, y, z]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Transform {
    pub scale: DVec3,
    /// XYZ Euler angles in degrees, applied X then Y then Z.
    pub rotation_deg: DVec3,
    /// Millimetres.
    pub translation: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform { scale: DVec3::ONE, rotation_deg: DVec3::ZERO, translation: DVec3::ZERO }
    }
}

impl Transform {
    /// Checks that every component is finite and no scale component is zero (which would
    /// flatten the mesh and make normals undefined). `source_name` names the config file.
    pub fn validate(&self, source_name: &str) -> Result<()> {
        for (field, v) in
            [("scale", self.scale), ("rotation_deg", self.rotation_deg), ("translation", self.translation)]
        {
            if !v.is_finite() {
                return Err(Error::invalid(
                    source_name,
                    field,
                    format!("must be finite, got [{}, {}, {}]", v.x, v.y, v.z),
                ));
            }
        }
        if self.scale.cmpeq(DVec3::ZERO).any() {
            return Err(Error::invalid(
                source_name,
                "scale",
                format!("components must be non-zero, got [{}, {}, {}]", self.scale.x, self.scale.y, self.scale.z),
            ));
        }
        Ok(())
    }

    /// The rotation matrix `Rz * Ry * Rx`.
    pub fn rotation(&self) -> DMat3 {
        let r = self.rotation_deg * (std::f64::consts::PI / 180.0);
        DMat3::from_rotation_z(r.z) * DMat3::from_rotation_y(r.y) * DMat3::from_rotation_x(r.x)
    }

    /// Transforms one point.
    pub fn apply_point(&self, p: DVec3) -> DVec3 {
        self.translation + self.rotation() * (self.scale * p)
    }

    /// Transforms positions (scale, rotate, translate) and normals (by the inverse transpose of
    /// the linear part, `R * diag(1 / scale)`, then renormalised). When the scale mirrors the
    /// mesh (odd number of negative components) the triangle winding is reversed so that
    /// geometric normals keep agreeing with the shading normals. Call [`Transform::validate`]
    /// first: a zero scale gives zero normals.
    pub fn apply(&self, mesh: &mut Mesh) {
        let rot = self.rotation();
        let linear = rot * DMat3::from_diagonal(self.scale);
        for p in &mut mesh.positions {
            *p = self.translation + linear * *p;
        }
        if let Some(normals) = &mut mesh.normals {
            let inv_scale = DVec3::ONE / self.scale;
            for n in normals.iter_mut() {
                *n = (rot * (inv_scale * *n)).normalize_or_zero();
            }
        }
        if self.scale.x * self.scale.y * self.scale.z < 0.0 {
            for tri in &mut mesh.triangles {
                tri.swap(1, 2);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ
// ---------------------------------------------------------------------------------------------

/// Converts tobj's float (f64 with the `use_f64` feature, f32 without) to f64.
fn tf<F: Into<f64>>(x: F) -> f64 {
    x.into()
}

fn load_obj(path: &Path, bytes: &[u8]) -> Result<(Mesh, Option<PathBuf>)> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count();
        Error::parse(path, format!("line {line}: not valid UTF-8 text"))
    })?;
    validate_obj_text(path, text)?;

    // tobj's optional features ("merging", "reordering") add fields that must stay false.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
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
    for model in &models {
        let m = &model.mesh;
        let nv = m.positions.len() / 3;
        let offset = mesh.positions.len();
        let offset_u32 =
            u32::try_from(offset).map_err(|_| Error::parse(path, "more than 2^32 vertices are not supported"))?;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|c| DVec3::new(tf(c[0]), tf(c[1]), tf(c[2]))));
        mesh.triangles
            .extend(m.indices.chunks_exact(3).map(|c| [c[0] + offset_u32, c[1] + offset_u32, c[2] + offset_u32]));
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
    Ok((mesh, texture))
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

// ---------------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlyFormat {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Largest value of an integer type (used to normalise integer colours).
    fn int_max(self) -> f64 {
        match self {
            Scalar::I8 => 127.0,
            Scalar::U8 => 255.0,
            Scalar::I16 => 32767.0,
            Scalar::U16 => 65535.0,
            Scalar::I32 => 2147483647.0,
            Scalar::U32 => 4294967295.0,
            Scalar::F32 | Scalar::F64 => 1.0,
        }
    }
}

#[derive(Clone, Debug)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: PropKind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

struct PlyHeader {
    format: PlyFormat,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body_start: usize,
    /// Number of header lines (the ASCII body starts on the next line).
    header_lines: usize,
}

fn parse_ply_header(path: &Path, bytes: &[u8]) -> Result<PlyHeader> {
    let bad = |line: usize, msg: String| Error::parse(path, format!("bad PLY header: line {line}: {msg}"));
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(Error::parse(path, "bad PLY header: no 'end_header' line before the end of the file"));
        }
        let end = bytes[pos..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |i| pos + i);
        let raw = &bytes[pos..end];
        pos = (end + 1).min(bytes.len());
        line_no += 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(bad(line_no, "not ASCII text".into()));
        };
        let text = text.trim_end_matches('\r');
        let words: Vec<&str> = text.split_whitespace().collect();
        if line_no == 1 {
            if text.trim() != "ply" {
                return Err(bad(1, format!("expected the magic word 'ply', found '{}'", text.trim())));
            }
            continue;
        }
        match words.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if words.len() != 3 {
                    return Err(bad(line_no, format!("expected 'format <type> 1.0', found '{text}'")));
                }
                format = Some(match words[1] {
                    "ascii" => PlyFormat::Ascii,
                    "binary_little_endian" => PlyFormat::BinaryLe,
                    "binary_big_endian" => PlyFormat::BinaryBe,
                    other => return Err(bad(line_no, format!("unknown format '{other}'"))),
                });
                if words[2] != "1.0" {
                    return Err(bad(line_no, format!("unsupported version '{}' (expected 1.0)", words[2])));
                }
            }
            Some("element") => {
                if words.len() != 3 {
                    return Err(bad(line_no, format!("expected 'element <name> <count>', found '{text}'")));
                }
                let count =
                    words[2].parse::<usize>().map_err(|_| bad(line_no, format!("bad element count '{}'", words[2])))?;
                elements.push(Element { name: words[1].to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err(bad(line_no, "property before any element".into()));
                };
                let scalar = |name: &str| {
                    Scalar::from_name(name).ok_or_else(|| bad(line_no, format!("unknown property type '{name}'")))
                };
                let prop = match words.as_slice() {
                    ["property", "list", count, item, name] => {
                        let count = scalar(count)?;
                        if count.is_float() {
                            return Err(bad(line_no, format!("list count type of '{name}' must be an integer type")));
                        }
                        Property { name: name.to_string(), kind: PropKind::List { count, item: scalar(item)? } }
                    }
                    ["property", ty, name] => Property { name: name.to_string(), kind: PropKind::Scalar(scalar(ty)?) },
                    _ => return Err(bad(line_no, format!("malformed property line '{text}'"))),
                };
                element.props.push(prop);
            }
            Some("end_header") => break,
            Some(other) => return Err(bad(line_no, format!("unexpected keyword '{other}'"))),
        }
    }
    let Some(format) = format else {
        return Err(Error::parse(path, "bad PLY header: no 'format' line"));
    };
    Ok(PlyHeader { format, elements, body_start: pos, header_lines: line_no })
}

/// Where in the body a value is being read, for error messages.
struct Loc<'a> {
    element: &'a str,
    index: usize,
    count: usize,
    property: &'a str,
}

/// A source of PLY body values (ASCII tokens or binary bytes).
trait PlyBody {
    /// Starts element `loc.index` (ASCII: moves to the next non-blank line).
    fn begin_element(&mut self, path: &Path, loc: &Loc) -> Result<()>;
    /// Ends the element (ASCII: the line must hold no more values).
    fn end_element(&mut self, path: &Path, loc: &Loc) -> Result<()>;
    fn read(&mut self, path: &Path, loc: &Loc, ty: Scalar) -> Result<f64>;
}

struct AsciiBody<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    first_line: usize,
    line: usize,
    words: std::str::SplitWhitespace<'a>,
}

impl PlyBody for AsciiBody<'_> {
    fn begin_element(&mut self, path: &Path, loc: &Loc) -> Result<()> {
        loop {
            match self.lines.next() {
                Some((i, text)) => {
                    if !text.trim().is_empty() {
                        self.line = self.first_line + i;
                        self.words = text.split_whitespace();
                        return Ok(());
                    }
                }
                None => {
                    return Err(Error::parse(
                        path,
                        format!(
                            "ASCII body ends before {} {} of {} (the header announced {})",
                            loc.element, loc.index, loc.count, loc.count
                        ),
                    ))
                }
            }
        }
    }

    fn end_element(&mut self, path: &Path, loc: &Loc) -> Result<()> {
        match self.words.next() {
            None => Ok(()),
            Some(w) => Err(Error::parse(
                path,
                format!(
                    "line {} ({} {}): unexpected extra value '{w}' after the last property",
                    self.line, loc.element, loc.index
                ),
            )),
        }
    }

    fn read(&mut self, path: &Path, loc: &Loc, ty: Scalar) -> Result<f64> {
        let Some(word) = self.words.next() else {
            return Err(Error::parse(
                path,
                format!(
                    "line {} ({} {}): missing value for property '{}'",
                    self.line, loc.element, loc.index, loc.property
                ),
            ));
        };
        let bad = || {
            Error::parse(
                path,
                format!(
                    "line {} ({} {}): bad number '{word}' for property '{}' ({})",
                    self.line,
                    loc.element,
                    loc.index,
                    loc.property,
                    ty.name()
                ),
            )
        };
        if ty.is_float() {
            word.parse::<f64>().map_err(|_| bad())
        } else {
            word.parse::<i64>().map(|v| v as f64).map_err(|_| bad())
        }
    }
}

struct BinaryBody<'a> {
    bytes: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl PlyBody for BinaryBody<'_> {
    fn begin_element(&mut self, _: &Path, _: &Loc) -> Result<()> {
        Ok(())
    }

    fn end_element(&mut self, _: &Path, _: &Loc) -> Result<()> {
        Ok(())
    }

    fn read(&mut self, path: &Path, loc: &Loc, ty: Scalar) -> Result<f64> {
        let n = ty.size();
        if self.pos + n > self.bytes.len() {
            return Err(Error::parse(
                path,
                format!(
                    "truncated binary body: {} {} of {} (property '{}') runs past the end of the file",
                    loc.element, loc.index, loc.count, loc.property
                ),
            ));
        }
        let b = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        let mut buf = [0u8; 8];
        buf[..n].copy_from_slice(b);
        if self.big_endian {
            buf[..n].reverse();
        }
        // `buf[..n]` now holds the value in little-endian byte order.
        Ok(match ty {
            Scalar::I8 => f64::from(buf[0] as i8),
            Scalar::U8 => f64::from(buf[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([buf[0], buf[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([buf[0], buf[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::F64 => f64::from_le_bytes(buf),
        })
    }
}

/// Column indices of the vertex properties we use.
struct VertexLayout {
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
    uv: Option<[usize; 2]>,
    color: Option<([usize; 3], Scalar)>,
}

fn vertex_layout(path: &Path, element: &Element) -> Result<VertexLayout> {
    let find = |name: &str| -> Result<Option<usize>> {
        match element.props.iter().position(|p| p.name == name) {
            None => Ok(None),
            Some(i) => match element.props[i].kind {
                PropKind::Scalar(_) => Ok(Some(i)),
                PropKind::List { .. } => Err(Error::parse(
                    path,
                    format!("bad PLY header: vertex property '{name}' must be a scalar, not a list"),
                )),
            },
        }
    };
    let triple = |a: &str, b: &str, c: &str| -> Result<Option<[usize; 3]>> {
        Ok(match (find(a)?, find(b)?, find(c)?) {
            (Some(i), Some(j), Some(k)) => Some([i, j, k]),
            _ => None,
        })
    };
    let Some(xyz) = triple("x", "y", "z")? else {
        return Err(Error::parse(path, "bad PLY header: element 'vertex' lacks properties x, y, z"));
    };
    let normal = triple("nx", "ny", "nz")?;
    let mut uv = None;
    for (a, b) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")] {
        if let (Some(i), Some(j)) = (find(a)?, find(b)?) {
            uv = Some([i, j]);
            break;
        }
    }
    let color = triple("red", "green", "blue")?.map(|idx| {
        let ty = match element.props[idx[0]].kind {
            PropKind::Scalar(t) => t,
            PropKind::List { .. } => Scalar::F64, // unreachable: `find` rejects lists
        };
        (idx, ty)
    });
    Ok(VertexLayout { xyz, normal, uv, color })
}

fn load_ply(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let header = parse_ply_header(path, bytes)?;
    let vertex_el = header.elements.iter().find(|e| e.name == "vertex");
    let Some(vertex_el) = vertex_el else {
        return Err(Error::parse(path, "bad PLY header: no 'vertex' element"));
    };
    let layout = vertex_layout(path, vertex_el)?;
    let face_el = header.elements.iter().find(|e| e.name == "face");
    let face_prop = match face_el {
        None => return Err(Error::parse(path, "contains no triangles (no 'face' element)")),
        Some(el) => el
            .props
            .iter()
            .position(|p| {
                matches!(p.kind, PropKind::List { .. }) && (p.name == "vertex_indices" || p.name == "vertex_index")
            })
            .ok_or_else(|| {
                Error::parse(path, "bad PLY header: element 'face' has no list property 'vertex_indices'")
            })?,
    };

    let body = &bytes[header.body_start..];
    match header.format {
        PlyFormat::Ascii => {
            let text = std::str::from_utf8(body).map_err(|_| Error::parse(path, "ASCII PLY body is not valid text"))?;
            let mut reader = AsciiBody {
                lines: text.lines().enumerate(),
                first_line: header.header_lines + 1,
                line: header.header_lines,
                words: "".split_whitespace(),
            };
            read_ply_body(path, &header.elements, &layout, face_prop, &mut reader)
        }
        PlyFormat::BinaryLe | PlyFormat::BinaryBe => {
            let mut reader = BinaryBody { bytes: body, pos: 0, big_endian: header.format == PlyFormat::BinaryBe };
            read_ply_body(path, &header.elements, &layout, face_prop, &mut reader)
        }
    }
}

fn read_ply_body(
    path: &Path,
    elements: &[Element],
    layout: &VertexLayout,
    face_prop: usize,
    body: &mut dyn PlyBody,
) -> Result<Mesh> {
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut colors = Vec::new();
    // Faces as (face index, polygon); indices are checked once all vertices are known.
    let mut polygon: Vec<f64> = Vec::new();
    let mut faces: Vec<(usize, Vec<i64>)> = Vec::new();
    let mut scalars: Vec<f64> = Vec::new();
    for element in elements {
        let is_vertex = element.name == "vertex";
        let is_face = element.name == "face";
        for index in 0..element.count {
            let mut loc = Loc { element: &element.name, index, count: element.count, property: "" };
            body.begin_element(path, &loc)?;
            scalars.clear();
            for (pi, prop) in element.props.iter().enumerate() {
                loc.property = &prop.name;
                match prop.kind {
                    PropKind::Scalar(ty) => scalars.push(body.read(path, &loc, ty)?),
                    PropKind::List { count, item } => {
                        scalars.push(f64::NAN);
                        let n = body.read(path, &loc, count)?;
                        if n < 0.0 {
                            return Err(Error::parse(
                                path,
                                format!("{} {index}: negative list length {n} for '{}'", element.name, prop.name),
                            ));
                        }
                        polygon.clear();
                        for _ in 0..n as usize {
                            polygon.push(body.read(path, &loc, item)?);
                        }
                        if is_face && pi == face_prop {
                            if polygon.len() < 3 {
                                return Err(Error::parse(
                                    path,
                                    format!("face {index}: has {} vertices, a face needs at least 3", polygon.len()),
                                ));
                            }
                            let mut idx = Vec::with_capacity(polygon.len());
                            for &v in &polygon {
                                if v.fract() != 0.0 || !v.is_finite() {
                                    return Err(Error::parse(
                                        path,
                                        format!("face {index}: vertex index {v} is not an integer"),
                                    ));
                                }
                                idx.push(v as i64);
                            }
                            faces.push((index, idx));
                        }
                    }
                }
            }
            loc.property = "";
            body.end_element(path, &loc)?;
            if is_vertex {
                let p = DVec3::new(scalars[layout.xyz[0]], scalars[layout.xyz[1]], scalars[layout.xyz[2]]);
                if !p.is_finite() {
                    return Err(Error::parse(
                        path,
                        format!("vertex {index}: non-finite coordinate ({}, {}, {})", p.x, p.y, p.z),
                    ));
                }
                mesh.positions.push(p);
                if let Some([i, j, k]) = layout.normal {
                    normals.push(DVec3::new(scalars[i], scalars[j], scalars[k]));
                }
                if let Some([i, j]) = layout.uv {
                    uvs.push(DVec2::new(scalars[i], scalars[j]));
                }
                if let Some(([i, j, k], ty)) = layout.color {
                    let m = ty.int_max();
                    colors.push(DVec3::new(
                        srgb_to_linear(scalars[i] / m),
                        srgb_to_linear(scalars[j] / m),
                        srgb_to_linear(scalars[k] / m),
                    ));
                }
            }
        }
    }
    let nv = mesh.positions.len();
    if u32::try_from(nv).is_err() {
        return Err(Error::parse(path, format!("{nv} vertices: more than 2^32 are not supported")));
    }
    for (face, idx) in &faces {
        for (corner, &v) in idx.iter().enumerate() {
            if v < 0 || v as usize >= nv {
                return Err(Error::parse(
                    path,
                    format!("face {face}: corner {corner} has vertex index {v}, out of range (file has {nv} vertices)"),
                ));
            }
        }
        // Fan triangulation (0, i, i + 1).
        for i in 1..idx.len() - 1 {
            mesh.triangles.push([idx[0] as u32, idx[i] as u32, idx[i + 1] as u32]);
        }
    }
    if layout.normal.is_some() {
        mesh.normals = Some(normals);
    }
    if layout.uv.is_some() {
        mesh.uvs = Some(uvs);
    }
    if layout.color.is_some() {
        mesh.colors = Some(colors);
    }
    if let Some(i) = mesh.normals.iter().flatten().position(|n| !n.is_finite()) {
        return Err(Error::parse(path, format!("vertex {i}: non-finite normal")));
    }
    if let Some(i) = mesh.uvs.iter().flatten().position(|t| !t.is_finite()) {
        return Err(Error::parse(path, format!("vertex {i}: non-finite texture coordinate")));
    }
    if let Some(i) = mesh.colors.iter().flatten().position(|c| !c.is_finite()) {
        return Err(Error::parse(path, format!("vertex {i}: non-finite colour")));
    }
    Ok(mesh)
}
