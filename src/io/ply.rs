//! Stanford PLY meshes: ASCII, binary little endian and binary big endian, read by the
//! hand-written reader below. Crates were considered: `ply-rs` 0.1.3 is unmaintained (last
//! release 2020, old `peg`), and its maintained fork `ply-rs-bw` 4 needs Rust 1.87 (this crate:
//! 1.80) and reports a truncated binary body as a bare end-of-file I/O error without the element
//! index. We only need vertices and faces, which the reader below covers in a few hundred lines
//! with precise error locations. Polygons are triangulated by [`crate::scene::polygon::triangulate`]
//! (convex: the fan `(0, i, i + 1)`; concave: ear clipping). A header line with an unknown keyword
//! (Blender 2.47 wrote its "Created by Blender3D" banner without `comment`) is skipped with a
//! warning, as other readers do; malformed `format`, `element` and `property` lines stay errors.
//! Shared conventions (colours, degenerate triangles): [`super::mesh`].

use std::path::Path;

use glam::{DVec2, DVec3};

use super::mesh::{srgb_to_linear, Loaded};
use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

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
    /// Skipped header lines, as warnings naming the file and line.
    warnings: Vec<String>,
}

fn parse_ply_header(path: &Path, bytes: &[u8]) -> Result<PlyHeader> {
    let bad = |line: usize, msg: String| Error::parse(path, format!("bad PLY header: line {line}: {msg}"));
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    // (element number, property name) of every property declared so far.
    let mut property_names = std::collections::HashSet::new();
    let mut warnings = Vec::new();
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
                let elements_seen = elements.len();
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
                if !property_names.insert((elements_seen, prop.name.clone())) {
                    return Err(bad(
                        line_no,
                        format!("element '{}' declares property '{}' twice", element.name, prop.name),
                    ));
                }
                element.props.push(prop);
            }
            Some("end_header") => break,
            Some(_) => warnings.push(format!(
                "{}: PLY header line {line_no}: skipped a line with an unknown keyword: '{}'",
                path.display(),
                text.trim()
            )),
        }
    }
    let Some(format) = format else {
        return Err(Error::parse(path, "bad PLY header: no 'format' line"));
    };
    Ok(PlyHeader { format, elements, body_start: pos, header_lines: line_no, warnings })
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
    /// Columns of red, green, blue and the type of each (integers are divided by their type's
    /// maximum).
    color: Option<([usize; 3], [Scalar; 3])>,
}

/// Where the vertex element's properties are. Vertex colours that cannot be used (some of
/// `red green blue` missing, or given as lists) are a warning, and the mesh has no colours.
fn vertex_layout(path: &Path, element: &Element, warnings: &mut Vec<String>) -> Result<VertexLayout> {
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
    let channels = ["red", "green", "blue"];
    /// A colour channel's column and type, `Err` when it is a list.
    type Channel = Option<std::result::Result<(usize, Scalar), ()>>;
    let scalar_at = |name: &str| -> Channel {
        let i = element.props.iter().position(|p| p.name == name)?;
        Some(match element.props[i].kind {
            PropKind::Scalar(t) => Ok((i, t)),
            PropKind::List { .. } => Err(()),
        })
    };
    let found: Vec<_> = channels.iter().map(|c| scalar_at(c)).collect();
    let color = match found.as_slice() {
        [Some(Ok((r, tr))), Some(Ok((g, tg))), Some(Ok((b, tb)))] => Some(([*r, *g, *b], [*tr, *tg, *tb])),
        [None, None, None] => None,
        _ => {
            let named = |f: fn(&Channel) -> bool| -> Vec<&str> {
                channels.iter().zip(&found).filter(|(_, x)| f(x)).map(|(c, _)| *c).collect()
            };
            let lists = named(|x| matches!(x, Some(Err(()))));
            let missing = named(|x| x.is_none());
            let why = if !lists.is_empty() {
                format!("{} given as a list", lists.join(", "))
            } else {
                format!("no {}", missing.join(", "))
            };
            warnings.push(format!(
                "{}: vertex colours cannot be used ({why}); the mesh is shown without them",
                path.display()
            ));
            None
        }
    };
    Ok(VertexLayout { xyz, normal, uv, color })
}

pub(super) fn load_ply(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let header = parse_ply_header(path, bytes)?;
    let vertex_el = header.elements.iter().find(|e| e.name == "vertex");
    let Some(vertex_el) = vertex_el else {
        return Err(Error::parse(path, "bad PLY header: no 'vertex' element"));
    };
    let mut warnings = header.warnings.clone();
    let layout = vertex_layout(path, vertex_el, &mut warnings)?;
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
    check_claimed_counts(path, &header, body.len())?;
    let mesh = match header.format {
        PlyFormat::Ascii => {
            let text = std::str::from_utf8(body).map_err(|_| Error::parse(path, "ASCII PLY body is not valid text"))?;
            let mut reader = AsciiBody {
                lines: text.lines().enumerate(),
                first_line: header.header_lines + 1,
                line: header.header_lines,
                words: "".split_whitespace(),
            };
            read_ply_body(path, &header.elements, &layout, face_prop, &mut reader, &mut warnings)?
        }
        PlyFormat::BinaryLe | PlyFormat::BinaryBe => {
            let mut reader = BinaryBody { bytes: body, pos: 0, big_endian: header.format == PlyFormat::BinaryBe };
            read_ply_body(path, &header.elements, &layout, face_prop, &mut reader, &mut warnings)?
        }
    };
    let vertex_colors = mesh.colors.is_some();
    let mut loaded = Loaded::plain(mesh);
    loaded.warnings = warnings;
    if vertex_colors {
        let material = super::mesh::FileMaterial { vertex_colors: true, ..Default::default() };
        loaded.parts = vec![super::mesh::MeshPart { triangles: 0..loaded.mesh.triangles.len(), material }];
    }
    Ok(loaded)
}

/// Refuses a header whose element counts cannot fit in the body: every element instance takes
/// at least its fixed-size properties (binary) or one character per property plus a separator
/// (ASCII), and an element without properties is refused outright. A few bytes of header must
/// not make the reader loop or allocate for billions of elements.
fn check_claimed_counts(path: &Path, header: &PlyHeader, body_bytes: usize) -> Result<()> {
    let mut need: u64 = 0;
    for element in &header.elements {
        if element.count > 0 && element.props.is_empty() {
            return Err(Error::parse(
                path,
                format!(
                    "bad PLY header: element '{}' claims {} instances but has no properties",
                    element.name, element.count
                ),
            ));
        }
        let each: u64 = element
            .props
            .iter()
            .map(|p| match (header.format, &p.kind) {
                (PlyFormat::Ascii, _) => 2,
                (_, PropKind::Scalar(s)) => s.size() as u64,
                (_, PropKind::List { count, .. }) => count.size() as u64,
            })
            .sum();
        need = need.saturating_add((element.count as u64).saturating_mul(each));
    }
    if need > body_bytes as u64 + 1 {
        let counts: Vec<String> = header.elements.iter().map(|e| format!("{} {}", e.count, e.name)).collect();
        return Err(Error::parse(
            path,
            format!(
                "header claims {} but the body has only {body_bytes} bytes, fewer than the {need} those need (truncated file?)",
                counts.join(", ")
            ),
        ));
    }
    Ok(())
}

/// The mesh of a PLY body: every element read in order (the vertex element's positions and
/// attributes kept, the face element's polygons triangulated, other elements skipped), then the
/// vertex attributes checked.
fn read_ply_body(
    path: &Path,
    elements: &[Element],
    layout: &VertexLayout,
    face_prop: usize,
    body: &mut dyn PlyBody,
    warnings: &mut Vec<String>,
) -> Result<Mesh> {
    let mut mesh = Mesh::default();
    let mut attributes = VertexAttributes::default();
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
                            faces.push((index, face_indices(path, index, &polygon)?));
                        }
                    }
                }
            }
            loc.property = "";
            body.end_element(path, &loc)?;
            if is_vertex {
                attributes.push_vertex(path, index, &scalars, layout, &mut mesh)?;
            }
        }
    }
    triangulate_faces(path, &faces, &mut mesh)?;
    attributes.attach(path, layout, &mut mesh, warnings)?;
    Ok(mesh)
}

/// The vertex indices of face `index`: at least three, each an integer.
fn face_indices(path: &Path, index: usize, polygon: &[f64]) -> Result<Vec<i64>> {
    if polygon.len() < 3 {
        return Err(Error::parse(
            path,
            format!("face {index}: has {} vertices, a face needs at least 3", polygon.len()),
        ));
    }
    let mut idx = Vec::with_capacity(polygon.len());
    for &v in polygon {
        if v.fract() != 0.0 || !v.is_finite() {
            return Err(Error::parse(path, format!("face {index}: vertex index {v} is not an integer")));
        }
        idx.push(v as i64);
    }
    Ok(idx)
}

/// The faces triangulated into `mesh` once all its vertices are known (each index checked against
/// them): convex faces as the fan (0, i, i + 1), concave ones by ear clipping.
fn triangulate_faces(path: &Path, faces: &[(usize, Vec<i64>)], mesh: &mut Mesh) -> Result<()> {
    let nv = mesh.positions.len();
    if u32::try_from(nv).is_err() {
        return Err(Error::parse(path, format!("{nv} vertices: more than 2^32 are not supported")));
    }
    for (face, idx) in faces {
        for (corner, &v) in idx.iter().enumerate() {
            if v < 0 || v as usize >= nv {
                return Err(Error::parse(
                    path,
                    format!("face {face}: corner {corner} has vertex index {v}, out of range (file has {nv} vertices)"),
                ));
            }
        }
        let corners: Vec<u32> = idx.iter().map(|&v| v as u32).collect();
        crate::scene::polygon::triangulate(&mesh.positions, &corners, &mut mesh.triangles)
            .map_err(|m| Error::parse(path, format!("face {face}: {m}")))?;
    }
    Ok(())
}

/// The vertex attributes the layout names, one per vertex read so far.
#[derive(Default)]
struct VertexAttributes {
    normals: Vec<DVec3>,
    uvs: Vec<DVec2>,
    colors: Vec<DVec3>,
}

impl VertexAttributes {
    /// Vertex `index` from its element's values `v`: its position into `mesh` (an error if not
    /// finite), its attributes here (colours of integer type scaled to [0, 1], then linear).
    fn push_vertex(
        &mut self,
        path: &Path,
        index: usize,
        v: &[f64],
        layout: &VertexLayout,
        mesh: &mut Mesh,
    ) -> Result<()> {
        let p = DVec3::new(v[layout.xyz[0]], v[layout.xyz[1]], v[layout.xyz[2]]);
        if !p.is_finite() {
            return Err(Error::parse(
                path,
                format!("vertex {index}: non-finite coordinate ({}, {}, {})", p.x, p.y, p.z),
            ));
        }
        mesh.positions.push(p);
        if let Some([i, j, k]) = layout.normal {
            self.normals.push(DVec3::new(v[i], v[j], v[k]));
        }
        if let Some([i, j]) = layout.uv {
            self.uvs.push(DVec2::new(v[i], v[j]));
        }
        if let Some(([i, j, k], [ti, tj, tk])) = layout.color {
            self.colors.push(DVec3::new(
                srgb_to_linear(v[i] / ti.int_max()),
                srgb_to_linear(v[j] / tj.int_max()),
                srgb_to_linear(v[k] / tk.int_max()),
            ));
        }
        Ok(())
    }

    /// The attributes the layout has, given to `mesh`: a non-finite normal or texture coordinate
    /// is an error; a non-finite colour drops the colours, with a warning.
    fn attach(self, path: &Path, layout: &VertexLayout, mesh: &mut Mesh, warnings: &mut Vec<String>) -> Result<()> {
        if layout.normal.is_some() {
            mesh.normals = Some(self.normals);
        }
        if layout.uv.is_some() {
            mesh.uvs = Some(self.uvs);
        }
        if layout.color.is_some() {
            mesh.colors = Some(self.colors);
        }
        if let Some(i) = mesh.normals.iter().flatten().position(|n| !n.is_finite()) {
            return Err(Error::parse(path, format!("vertex {i}: non-finite normal")));
        }
        if let Some(i) = mesh.uvs.iter().flatten().position(|t| !t.is_finite()) {
            return Err(Error::parse(path, format!("vertex {i}: non-finite texture coordinate")));
        }
        if let Some(i) = mesh.colors.iter().flatten().position(|c| !c.is_finite()) {
            warnings.push(format!(
                "{}: vertex {i}: non-finite colour; the mesh is shown without its vertex colours",
                path.display()
            ));
            mesh.colors = None;
        }
        Ok(())
    }
}
