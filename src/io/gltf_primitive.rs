//! glTF 2.0 triangle primitives (glTF 2.0 specification, sec. 3.7.2 "Meshes"): `POSITION`,
//! `NORMAL`, `TEXCOORD_n` and `COLOR_0` read and checked against the vertex count, indices
//! checked, `TRIANGLE_STRIP` / `TRIANGLE_FAN` unrolled in the specification's order, and every
//! primitive of every node instance merged into one mesh with one part per material.

use glam::{DMat3, DMat4, DVec2, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::gltf_accessor::{Elements, Reader, FLOAT, UNORM16, UNORM8};
use super::gltf_material::file_material;
use super::mesh::MeshPart;
use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

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
pub(super) struct Builder {
    pub(super) mesh: Mesh,
    pub(super) parts: Vec<(Option<usize>, MeshPart)>,
    pub(super) has_normals: bool,
    pub(super) has_uvs: bool,
    pub(super) has_colors: bool,
}

impl Builder {
    pub(super) fn add_primitive(
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
