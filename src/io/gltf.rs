//! glTF 2.0 meshes (`.gltf` with embedded `data:` or external buffers, and binary `.glb`): the
//! format most modelled and many scanned meshes arrive in. The `gltf` crate parses and validates
//! the JSON document (index ranges, required extensions); buffers and accessors are read here so
//! that every malformed file gives one line naming the file and the element
//! (`meshes[0].primitives[1].indices: ...`), never a panic.
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
use glam::{DMat3, DMat4, DQuat, DVec2, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::gltf_accessor::{Elements, Reader, FLOAT, UNORM16, UNORM8};
use super::input::Reach;
use super::mesh::{FileMaterial, FileTexture, Loaded, MeshPart, TextureSource};
use crate::error::{Error, Result};
use crate::scene::image_texture::{Filter, Wrap};
use crate::scene::mesh::Mesh;

/// Most mesh instances a node hierarchy may expand to (guards against exponential node graphs).
const MAX_INSTANCES: usize = 1_000_000;

pub(super) fn load_gltf(path: &Path, bytes: &[u8], reach: &Reach) -> Result<Loaded> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| Error::parse(path, format!("not a readable glTF/GLB file: {e}")))?;
    let doc = &gltf.document;
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
                "contains no triangles ({} node(s) with a mesh in the scene, {} mesh(es) in the file)",
                instances.iter().filter(|(n, _)| n.mesh().is_some()).count(),
                doc.meshes().count()
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
    let more =
        if problems.len() > 1 { format!(" (and {} more problem(s))", problems.len() - 1) } else { String::new() };
    match problems.first() {
        None => Ok(()),
        Some((p, V::Unsupported)) => {
            Err(Error::parse(path, format!("{p}: required extension not supported by inimtrace{more}")))
        }
        Some((p, e)) => Err(Error::parse(path, format!("invalid glTF: {p}: {e}{more}"))),
    }
}

/// The bytes of a `data:` URI, or the file a relative URI names.
enum UriTarget {
    Data(Vec<u8>),
    File(PathBuf),
}

fn resolve_uri(path: &Path, base: &Path, reach: &Reach, at: &str, uri: &str) -> Result<UriTarget> {
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

/// The nodes the scene starts from: the default scene's (else the first scene's; else every
/// node that is no other node's child).
fn roots(doc: &gltf::Document) -> Vec<gltf::Node<'_>> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().count()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    }
}

/// What a node's subtree expands to: mesh instances, triangles and vertices.
#[derive(Clone, Copy, Default)]
struct Expanded {
    instances: u64,
    triangles: u64,
    vertices: u64,
}

impl Expanded {
    fn add(self, o: Expanded) -> Expanded {
        Expanded {
            instances: self.instances.saturating_add(o.instances),
            triangles: self.triangles.saturating_add(o.triangles),
            vertices: self.vertices.saturating_add(o.vertices),
        }
    }
}

/// The triangles and vertices of one instance of `mesh`, from its accessors' counts.
fn mesh_size(mesh: &gltf::Mesh) -> Expanded {
    let mut e = Expanded { instances: 1, ..Default::default() };
    for prim in mesh.primitives() {
        let vertices = prim.get(&gltf::Semantic::Positions).map_or(0, |a| a.count() as u64);
        let corners = prim.indices().map_or(vertices, |a| a.count() as u64);
        let triangles = match prim.mode() {
            Mode::Triangles => corners / 3,
            Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
            _ => 0,
        };
        e.triangles = e.triangles.saturating_add(triangles);
        e.vertices = e.vertices.saturating_add(vertices);
    }
    e
}

/// Refuses a node graph whose expansion (every mesh instance as triangles) would not fit in
/// the memory budget, or has over [`MAX_INSTANCES`] nodes. The graph is walked with counts
/// (each node's subtree summed once, children first), never expanded: a graph that instances a
/// mesh 2^18 times through doubling nodes costs one step per node and edge.
fn check_expanded_size(path: &Path, doc: &gltf::Document) -> Result<()> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut size: Vec<Option<Expanded>> = vec![None; nodes.len()];
    let mut on_path = vec![false; nodes.len()];
    let mut total = Expanded::default();
    for root in roots(doc) {
        // Iterative depth-first walk: (node, whether its children are done).
        let mut stack = vec![(root.index(), false)];
        while let Some((i, children_done)) = stack.pop() {
            if children_done {
                on_path[i] = false;
                let own = nodes[i].mesh().map_or(Expanded { instances: 1, ..Default::default() }, |m| mesh_size(&m));
                let sum = nodes[i].children().fold(own, |acc, c| acc.add(size[c.index()].unwrap_or_default()));
                size[i] = Some(sum);
                continue;
            }
            if size[i].is_some() {
                continue;
            }
            if on_path[i] {
                return Err(Error::parse(
                    path,
                    format!("nodes[{i}]: is its own ancestor (the node hierarchy has a cycle)"),
                ));
            }
            on_path[i] = true;
            stack.push((i, true));
            for c in nodes[i].children() {
                if on_path[c.index()] {
                    return Err(Error::parse(
                        path,
                        format!("nodes[{}]: is its own ancestor (the node hierarchy has a cycle)", c.index()),
                    ));
                }
                if size[c.index()].is_none() {
                    stack.push((c.index(), false));
                }
            }
        }
        total = total.add(size[root.index()].unwrap_or_default());
    }
    if total.instances > MAX_INSTANCES as u64 {
        return Err(Error::parse(
            path,
            format!("nodes: the node hierarchy expands to over {MAX_INSTANCES} nodes ({} counted)", total.instances),
        ));
    }
    let mut estimate = crate::budget::Estimate::default();
    let what = format!(
        "the meshes of every node instance expanded ({} triangles, {} vertices)",
        total.triangles, total.vertices
    );
    estimate.add(what.clone(), "nodes", total.triangles, crate::budget::MESH_BYTES_PER_TRIANGLE);
    estimate.add(what, "nodes", total.vertices, crate::budget::MESH_BYTES_PER_VERTEX);
    estimate.check_memory(&crate::budget::memory_budget(), &path.display().to_string())
}

/// Every node of the scene with its world matrix, depth first.
fn instances<'a>(path: &Path, doc: &'a gltf::Document) -> Result<Vec<(gltf::Node<'a>, DMat4)>> {
    let roots = roots(doc);
    let mut out = Vec::new();
    let mut on_path = vec![false; doc.nodes().count()];
    for root in roots {
        visit(path, root, DMat4::IDENTITY, &mut on_path, &mut out)?;
    }
    Ok(out)
}

fn visit<'a>(
    path: &Path,
    node: gltf::Node<'a>,
    parent: DMat4,
    on_path: &mut [bool],
    out: &mut Vec<(gltf::Node<'a>, DMat4)>,
) -> Result<()> {
    let i = node.index();
    if on_path[i] {
        return Err(Error::parse(path, format!("nodes[{i}]: is its own ancestor (the node hierarchy has a cycle)")));
    }
    if out.len() >= MAX_INSTANCES {
        return Err(Error::parse(
            path,
            format!("nodes[{i}]: the node hierarchy expands to over {MAX_INSTANCES} nodes"),
        ));
    }
    let local = node_matrix(path, &node)?;
    let world = parent * local;
    on_path[i] = true;
    let children: Vec<gltf::Node<'a>> = node.children().collect();
    out.push((node, world));
    for child in children {
        visit(path, child, world, on_path, out)?;
    }
    on_path[i] = false;
    Ok(())
}

/// A node's local matrix in `f64`: its `matrix`, or `T * R * S`.
fn node_matrix(path: &Path, node: &gltf::Node) -> Result<DMat4> {
    let i = node.index();
    let f = |v: f32| f64::from(v);
    let m = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|col| col.map(f))),
        gltf::scene::Transform::Decomposed { translation: t, rotation: r, scale: s } => {
            let q = DQuat::from_xyzw(f(r[0]), f(r[1]), f(r[2]), f(r[3]));
            if !(q.is_finite() && q.length() > 0.0) {
                return Err(Error::parse(
                    path,
                    format!("nodes[{i}].rotation: not a finite non-zero quaternion: {r:?}"),
                ));
            }
            DMat4::from_scale_rotation_translation(
                DVec3::new(f(s[0]), f(s[1]), f(s[2])),
                q.normalize(),
                DVec3::new(f(t[0]), f(t[1]), f(t[2])),
            )
        }
    };
    if !m.is_finite() {
        return Err(Error::parse(path, format!("nodes[{i}]: transform has a non-finite value")));
    }
    Ok(m)
}

/// A triangle primitive's vertex attributes, read and checked against its `POSITION` count.
struct Attributes {
    positions: Elements,
    normals: Option<Elements>,
    /// The `TEXCOORD_n` set the base colour texture uses, and its coordinates.
    uv_set: u32,
    uvs: Option<Elements>,
    colors: Option<Elements>,
    /// Vertex indices, each checked to be below the vertex count.
    indices: Vec<u32>,
}

impl Attributes {
    /// Reads `prim`'s attributes and indices (`at` names it in errors: `meshes[0].primitives[1]`).
    fn read(r: &Reader, at: &str, prim: &gltf::Primitive) -> Result<Self> {
        let path = r.path;
        let position = prim
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| Error::parse(path, format!("{at}: has no POSITION attribute")))?;
        let positions =
            r.read(&format!("{at}.attributes.POSITION"), &position, &[Dimensions::Vec3], &[FLOAT], "VEC3 of FLOAT")?;
        let n = positions.len();
        let same_count = |name: &str, len: usize| -> Result<()> {
            if len == n {
                Ok(())
            } else {
                Err(Error::parse(path, format!("{at}.attributes.{name}: {len} elements, but POSITION has {n}")))
            }
        };
        let normals = match prim.get(&gltf::Semantic::Normals) {
            Some(a) => {
                let v =
                    r.read(&format!("{at}.attributes.NORMAL"), &a, &[Dimensions::Vec3], &[FLOAT], "VEC3 of FLOAT")?;
                same_count("NORMAL", v.len())?;
                Some(v)
            }
            None => None,
        };
        let material = prim.material();
        let pbr = material.pbr_metallic_roughness();
        let tex_info = pbr.base_color_texture();
        let set = tex_info.as_ref().map_or(0, |t| t.tex_coord());
        let uvs = match prim.get(&gltf::Semantic::TexCoords(set)) {
            Some(a) => {
                let name = format!("TEXCOORD_{set}");
                let v = r.read(
                    &format!("{at}.attributes.{name}"),
                    &a,
                    &[Dimensions::Vec2],
                    &[FLOAT, UNORM8, UNORM16],
                    "VEC2 of FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT",
                )?;
                same_count(&name, v.len())?;
                Some(v)
            }
            None => None,
        };
        let colors = match prim.get(&gltf::Semantic::Colors(0)) {
            Some(a) => {
                let v = r.read(
                    &format!("{at}.attributes.COLOR_0"),
                    &a,
                    &[Dimensions::Vec3, Dimensions::Vec4],
                    &[FLOAT, UNORM8, UNORM16],
                    "VEC3/VEC4 of FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT",
                )?;
                same_count("COLOR_0", v.len())?;
                Some(v)
            }
            None => None,
        };
        let indices: Vec<u32> = match prim.indices() {
            Some(a) => {
                let at_i = format!("{at}.indices");
                let v = r.read(
                    &at_i,
                    &a,
                    &[Dimensions::Scalar],
                    &[(DataType::U8, false), (DataType::U16, false), (DataType::U32, false)],
                    "SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                )?;
                let mut out = Vec::with_capacity(v.len());
                for (k, x) in v.iter().enumerate() {
                    let idx = x[0];
                    if idx >= n as f64 {
                        return Err(Error::parse(
                            path,
                            format!("{at_i}: index {idx} (element {k}) is out of range (POSITION has {n} vertices)"),
                        ));
                    }
                    out.push(idx as u32);
                }
                out
            }
            None => {
                (0..u32::try_from(n).map_err(|_| Error::parse(path, format!("{at}: over 2^32 vertices")))?).collect()
            }
        };
        Ok(Attributes { positions, normals, uv_set: set, uvs, colors, indices })
    }
}

/// The merged mesh being built, and its parts keyed by material index.
#[derive(Default)]
struct Builder {
    mesh: Mesh,
    parts: Vec<(Option<usize>, MeshPart)>,
    has_normals: bool,
    has_uvs: bool,
    has_colors: bool,
}

impl Builder {
    fn add_primitive(
        &mut self,
        r: &Reader,
        at: &str,
        prim: &gltf::Primitive,
        world: DMat4,
        warnings: &mut Vec<String>,
    ) -> Result<()> {
        let path = r.path;
        let Attributes { positions, normals, uv_set: set, uvs, colors, indices } = Attributes::read(r, at, prim)?;
        let n = positions.len();
        let material = prim.material();
        let corners = unroll(prim.mode(), &indices);
        if corners.len() * 3 != indices.len() && prim.mode() == Mode::Triangles {
            warnings.push(format!(
                "{}: {at}: {} indices is not a multiple of 3; the last {} ignored",
                path.display(),
                indices.len(),
                indices.len() % 3
            ));
        }

        // Transform into the file's world frame.
        let linear = DMat3::from_mat4(world);
        let mirror = linear.determinant() < 0.0;
        let normal_matrix = if linear.determinant().abs() > 0.0 { linear.inverse().transpose() } else { DMat3::ZERO };
        let offset = self.mesh.positions.len();
        let base =
            u32::try_from(offset + n).map(|_| offset as u32).map_err(|_| Error::parse(path, "over 2^32 vertices"))?;
        for (k, p) in positions.iter().enumerate() {
            let w = world.transform_point3(DVec3::new(p[0], p[1], p[2]));
            if !w.is_finite() {
                return Err(Error::parse(
                    path,
                    format!(
                        "{at}.attributes.POSITION: vertex {k} is not finite ({}, {}, {}) in the scene frame",
                        p[0], p[1], p[2]
                    ),
                ));
            }
            self.mesh.positions.push(w);
        }
        let normals_out = self.mesh.normals.get_or_insert_with(Vec::new);
        normals_out.resize(offset, DVec3::ZERO);
        match &normals {
            Some(v) => {
                self.has_normals = true;
                for (k, x) in v.iter().enumerate() {
                    let nn = DVec3::new(x[0], x[1], x[2]);
                    if !nn.is_finite() {
                        return Err(Error::parse(path, format!("{at}.attributes.NORMAL: element {k} is not finite")));
                    }
                    normals_out.push((normal_matrix * nn).normalize_or_zero());
                }
            }
            // Zero normals: shading falls back to the geometric normal.
            None => normals_out.resize(offset + n, DVec3::ZERO),
        }
        let uvs_out = self.mesh.uvs.get_or_insert_with(Vec::new);
        uvs_out.resize(offset, DVec2::ZERO);
        match &uvs {
            Some(v) => {
                self.has_uvs = true;
                for (k, x) in v.iter().enumerate() {
                    if !(x[0].is_finite() && x[1].is_finite()) {
                        return Err(Error::parse(
                            path,
                            format!("{at}.attributes.TEXCOORD_{set}: element {k} is not finite"),
                        ));
                    }
                    uvs_out.push(DVec2::new(x[0], 1.0 - x[1]));
                }
            }
            None => uvs_out.resize(offset + n, DVec2::ZERO),
        }
        let colors_out = self.mesh.colors.get_or_insert_with(Vec::new);
        colors_out.resize(offset, DVec3::ONE);
        match &colors {
            Some(v) => {
                self.has_colors = true;
                for (k, x) in v.iter().enumerate() {
                    let c = DVec3::new(x[0], x[1], x[2]);
                    if !c.is_finite() || c.min_element() < 0.0 {
                        return Err(Error::parse(
                            path,
                            format!("{at}.attributes.COLOR_0: element {k} is not a finite colour >= 0"),
                        ));
                    }
                    colors_out.push(c);
                }
            }
            None => colors_out.resize(offset + n, DVec3::ONE),
        }
        let first = self.mesh.triangles.len();
        for [a, b, c] in corners {
            let t = [base + a, base + b, base + c];
            self.mesh.triangles.push(if mirror { [t[0], t[2], t[1]] } else { t });
        }
        let range = first..self.mesh.triangles.len();
        if range.is_empty() {
            return Ok(());
        }
        let key = material.index();
        match self.parts.last_mut() {
            Some((k, part)) if *k == key && part.material.vertex_colors == colors.is_some() => {
                part.triangles.end = range.end;
            }
            _ => {
                let file_material = file_material(r, at, &material, colors.is_some(), uvs.is_some(), warnings)?;
                self.parts.push((key, MeshPart { triangles: range, material: file_material }));
            }
        }
        Ok(())
    }
}

/// Triangle corners (indices into the primitive's vertices) of a triangle primitive.
fn unroll(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::Triangles => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        // Specification: triangle i is {v_i, v_(i + 1 + i % 2), v_(i + 2 - i % 2)}.
        Mode::TriangleStrip => {
            (0..idx.len().saturating_sub(2)).map(|i| [idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]]).collect()
        }
        // Specification: triangle i is {v_(i + 1), v_(i + 2), v_0}.
        Mode::TriangleFan => (0..idx.len().saturating_sub(2)).map(|i| [idx[i + 1], idx[i + 2], idx[0]]).collect(),
        _ => Vec::new(),
    }
}

/// A primitive's material as the mesh layer describes it.
fn file_material(
    r: &Reader,
    at: &str,
    material: &gltf::Material,
    vertex_colors: bool,
    has_uvs: bool,
    warnings: &mut Vec<String>,
) -> Result<FileMaterial> {
    let path = r.path;
    let Some(index) = material.index() else {
        return Ok(FileMaterial { vertex_colors, ..Default::default() });
    };
    let pbr = material.pbr_metallic_roughness();
    let [cr, cg, cb, _] = pbr.base_color_factor().map(f64::from);
    let base_color = DVec3::new(cr, cg, cb);
    let at_m = format!("materials[{index}]");
    if !base_color.is_finite() || base_color.min_element() < 0.0 {
        return Err(Error::parse(path, format!("{at_m}.baseColorFactor: must be finite and >= 0, got {base_color}")));
    }
    let texture = match pbr.base_color_texture() {
        None => None,
        Some(_) if !has_uvs => {
            warnings.push(format!(
                "{}: {at}: {at_m} has a base colour texture but the primitive has no texture coordinates; texture ignored",
                path.display()
            ));
            None
        }
        Some(info) => {
            let tex = info.texture();
            let image = tex.source();
            let at_img = format!("images[{}]", image.index());
            // The image's bytes or file; an image that cannot be had loses the texture, with a
            // warning (the base colour is used), as a missing image file does later.
            let source = match image.source() {
                gltf::image::Source::View { view, .. } => {
                    let buffer = &r.buffers[view.buffer().index()];
                    match buffer.get(view.offset()..view.offset() + view.length()) {
                        Some(bytes) => Ok(TextureSource::Embedded { name: at_img.clone(), bytes: bytes.to_vec() }),
                        None => Err(format!("bufferViews[{}] runs past the end of its buffer", view.index())),
                    }
                }
                gltf::image::Source::Uri { uri, .. } => {
                    match resolve_uri(path, path.parent().unwrap_or(Path::new("")), r.reach, &at_img, uri) {
                        Ok(UriTarget::Data(bytes)) => Ok(TextureSource::Embedded { name: at_img.clone(), bytes }),
                        Ok(UriTarget::File(file)) => Ok(TextureSource::File(file)),
                        // A file outside the scene's folder is refused, not lost with a warning.
                        Err(e @ Error::Parse { .. }) if !uri.starts_with("data:") && !uri.contains("://") => {
                            return Err(e)
                        }
                        Err(Error::Parse { message, .. }) => Err(message),
                        Err(e) => Err(e.to_string()),
                    }
                }
            };
            match source {
                Err(why) => {
                    warnings.push(format!(
                        "{}: {at_m}{}: the base colour texture cannot be read ({why}); the base colour is used",
                        path.display(),
                        material.name().map(|n| format!(" ('{n}')")).unwrap_or_default()
                    ));
                    None
                }
                Ok(source) => {
                    let sampler = tex.sampler();
                    let filter = match sampler.mag_filter() {
                        Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
                        _ => Filter::Bilinear,
                    };
                    let wrap = match sampler.wrap_s() {
                        gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
                        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
                        gltf::texture::WrappingMode::MirroredRepeat => {
                            warnings.push(format!(
                                "{}: {at_m}: mirrored-repeat texture wrapping is read as repeat",
                                path.display()
                            ));
                            Wrap::Repeat
                        }
                    };
                    Some(FileTexture { source, filter: Some(filter), wrap: Some(wrap) })
                }
            }
        }
    };
    Ok(FileMaterial {
        name: material.name().map(String::from),
        base_color: Some(base_color),
        texture,
        untextured_color: None,
        vertex_colors,
    })
}
