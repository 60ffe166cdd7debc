//! Mesh objects of a scene file (`type = "mesh"`): the mesh file loaded through
//! [`super::mesh::load_mesh`], placed in the eye's frame (Sec. 4.1's world, mm) by a
//! `transform` or a `fit`, and given a material: the scene file's `material` when it has one,
//! else the file's own materials ([`super::mesh::MeshPart`]), one scene object per material,
//! else a neutral grey ([`DEFAULT_ALBEDO`]). A file material's texture that is missing or
//! unreadable is a warning, and the material's base colour is used.
//!
//! `fit = { size = 100.0, center = [0, 0, 400], rotation_deg = [0, 0, 0] }` rotates the mesh
//! (optional, as in [`Transform`]), then scales it uniformly so that the largest side of its
//! axis-aligned bounding box is `size` mm and moves the box's centre to `center`: a model in
//! metres, centimetres or inches arrives at a known size without working out its scale.

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::mesh::{load_mesh_within, remove_degenerate_in_parts, FileMaterial, MeshPart, TextureSource};
use super::scene_file::ObjectInput;
use crate::error::{Error, Result};
use crate::scene::image_texture::{Filter, ImageTexture, Wrap};
use crate::scene::{BarChart, Material, Mesh, Object, Shape, Transform};

/// Albedo of objects without a material of their own: a neutral 0.8 grey.
pub const DEFAULT_ALBEDO: DVec3 = DVec3::splat(0.8);

/// A mesh object's largest extent (mm) below which loading warns that it may be in metres.
const TINY_MM: f64 = 1.0;

/// `fit = { size, center, rotation_deg }`: see the module comment.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    /// Largest side of the bounding box after fitting, mm.
    pub size: f64,
    /// Centre of the bounding box after fitting, mm.
    pub center: [f64; 3],
    /// XYZ Euler angles in degrees applied before fitting (as in [`Transform`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_deg: Option<[f64; 3]>,
}

impl FitSpec {
    /// The transform that fits `mesh`; errors name `field` of `src`.
    pub fn transform(&self, mesh: &Mesh, src: &str, field: &str) -> Result<Transform> {
        if !(self.size.is_finite() && self.size > 0.0) {
            return Err(Error::invalid(
                src,
                format!("{field}.size"),
                format!("must be positive and finite, got {}", self.size),
            ));
        }
        if !self.center.iter().all(|c| c.is_finite()) {
            return Err(Error::invalid(
                src,
                format!("{field}.center"),
                format!("must be finite, got {:?}", self.center),
            ));
        }
        let rotation_deg = DVec3::from_array(self.rotation_deg.unwrap_or([0.0; 3]));
        if !rotation_deg.is_finite() {
            return Err(Error::invalid(src, format!("{field}.rotation_deg"), "must be finite"));
        }
        let rotated = Transform { rotation_deg, ..Transform::default() };
        let r = rotated.rotation();
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(r * *p), hi.max(r * *p)));
        let extent = (hi - lo).max_element();
        if !(extent.is_finite() && extent > 0.0) {
            return Err(Error::invalid(
                src,
                field,
                format!("the mesh has no extent to fit (bounding box {lo} to {hi})"),
            ));
        }
        let s = self.size / extent;
        Ok(Transform {
            scale: DVec3::splat(s),
            rotation_deg,
            translation: DVec3::from_array(self.center) - s * 0.5 * (lo + hi),
        })
    }
}

/// The image files a scene's textures come from, each decoded once for the whole scene (by the
/// file it is, after links): every material that uses one shares its texels, and the memory
/// budget counts them once.
#[derive(Default)]
pub(super) struct SceneTextures(std::cell::RefCell<Vec<(std::path::PathBuf, Arc<ImageTexture>)>>);

impl SceneTextures {
    /// The texture in the image file `path`, sampled with `filter` and `wrap`: decoded at its
    /// first use, shared after.
    pub(super) fn load(&self, path: &Path, filter: Filter, wrap: Wrap) -> Result<ImageTexture> {
        let key = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        let found = self.0.borrow().iter().find(|(k, _)| *k == key).map(|(_, t)| t.clone());
        let image = match found {
            Some(image) => image,
            None => {
                let image = Arc::new(crate::io::png::load_texture(path, filter, wrap)?);
                self.0.borrow_mut().push((key, image.clone()));
                image
            }
        };
        Ok(sampled(&image, filter, wrap))
    }
}

/// A copy of `image` (its texels shared) sampled with `filter` and `wrap`.
fn sampled(image: &ImageTexture, filter: Filter, wrap: Wrap) -> ImageTexture {
    let mut t = image.clone();
    t.filter = filter;
    t.wrap = wrap;
    t
}

/// The textures of one mesh file already read (or found unreadable: `Err`), by source: a
/// texture that many parts use is decoded, or warned about, once.
#[derive(Default)]
struct TextureCache(Vec<(TextureKey, CachedTexture)>);

/// An image.
type TextureKey = TextureSource;
/// A texture read, or `Err` when it could not be (the warning is already given).
type CachedTexture = std::result::Result<Arc<ImageTexture>, ()>;

impl TextureCache {
    fn get(&self, key: &TextureKey) -> Option<&CachedTexture> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    fn push(&mut self, entry: (TextureKey, CachedTexture)) {
        self.0.push(entry);
    }
}

/// A mesh with only the triangles `range` of `mesh` and the vertices they use (in order of
/// first use), with their attributes.
fn submesh(mesh: &Mesh, range: std::ops::Range<usize>) -> Mesh {
    let mut map = vec![u32::MAX; mesh.positions.len()];
    let mut used: Vec<usize> = Vec::new();
    let triangles = mesh.triangles[range]
        .iter()
        .map(|tri| {
            tri.map(|v| {
                let slot = &mut map[v as usize];
                if *slot == u32::MAX {
                    *slot = used.len() as u32;
                    used.push(v as usize);
                }
                *slot
            })
        })
        .collect();
    fn pick<T: Copy>(attr: &Option<Vec<T>>, used: &[usize]) -> Option<Vec<T>> {
        attr.as_ref().map(|a| used.iter().map(|&i| a[i]).collect())
    }
    Mesh {
        positions: used.iter().map(|&i| mesh.positions[i]).collect(),
        triangles,
        normals: pick(&mesh.normals, &used),
        uvs: pick(&mesh.uvs, &used),
        colors: pick(&mesh.colors, &used),
    }
}

impl ObjectInput<'_> {
    /// `type = "mesh"`: the mesh file, placed by its `transform` or `fit`, as one object with the
    /// scene file's material, or one object per material of the file.
    pub(super) fn mesh_objects(
        &self,
        framework_chart: &mut Option<Arc<BarChart>>,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<Object>> {
        let (src, o, i) = (self.src, self.spec, self.index);
        let f = |name: &str| self.field(name);
        self.only(&["file", "transform", "fit"])?;
        let file = o.file.as_ref().ok_or_else(|| {
            Error::invalid(
                src,
                f("file"),
                "missing (a mesh needs `file = \"model.obj\"`: .obj, .ply, .stl, .gltf or .glb)",
            )
        })?;
        let path = self.reach.resolve(self.base, file).map_err(|why| Error::invalid(src, f("file"), why))?;
        // Name the scene file and field as well as the mesh file and its line/element.
        let loaded = load_mesh_within(&path, self.reach).map_err(|e| Error::in_field(src, f("file"), e))?;
        warnings.extend(loaded.warnings.iter().map(|w| format!("{w} (objects[{i}])")));
        if loaded.dropped_degenerate > 0 {
            warnings.push(format!(
                "{}: dropped {} of {} (objects[{i}])",
                src,
                crate::count::count(loaded.dropped_degenerate, "degenerate (zero-area) triangle"),
                path.display()
            ));
        }
        let transform = match (&o.transform, &o.fit) {
            (Some(_), Some(_)) => {
                return Err(Error::invalid(src, f("fit"), "give `transform` or `fit`, not both"));
            }
            (_, Some(fit)) => fit.transform(&loaded.mesh, src, &f("fit"))?,
            (t, None) => {
                let t = t.unwrap_or_default();
                t.validate(src).map_err(|e| match e {
                    Error::Invalid { source_name, field, message } => {
                        Error::invalid(source_name, f(&format!("transform.{field}")), message)
                    }
                    other => other,
                })?;
                t
            }
        };
        let mut mesh = loaded.mesh;
        transform.apply(&mut mesh);
        // A transform can push finite vertices past f64 range, or flatten triangles.
        mesh.validate(&format!("{} (objects[{i}], {} after transform)", src, path.display()))?;
        let mut parts = loaded.parts;
        let flattened = remove_degenerate_in_parts(&mut mesh, &mut parts);
        if mesh.triangles.is_empty() {
            return Err(Error::invalid(src, f("transform"), "leaves no triangle with non-zero area"));
        }
        if flattened > 0 {
            warnings.push(format!(
                "{src}: the transform of objects[{i}] made {} of {} degenerate; dropped",
                crate::count::count(flattened, "triangle"),
                path.display()
            ));
        }
        let (lo, hi) = mesh.bounds();
        let extent = (hi - lo).max_element();
        if extent < TINY_MM {
            warnings.push(format!(
                "{src}: objects[{i}] ({}) spans only {extent:.3} mm after its transform; coordinates are read as mm \
                 (glTF files are in metres): scale it with `transform` or give `fit = {{ size = ..., center = [...] }}`",
                path.display()
            ));
        }
        if hi.z < 0.0 {
            warnings.push(format!(
                "{src}: objects[{i}] ({}) lies behind the eye (z from {:.3} to {:.3} mm; the scene is at z > 0)",
                path.display(),
                lo.z,
                hi.z
            ));
        }
        let name = o.name.clone().unwrap_or_else(|| {
            Path::new(file)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| format!("object {i}"))
        });
        if !o.material.is_unset() {
            let shape = Shape::Mesh(Arc::new(mesh));
            let material = self.material(&shape, loaded.texture, framework_chart)?;
            return Ok(vec![Object { name, shape, material }]);
        }
        let single = parts.len() == 1;
        let mut objects = Vec::with_capacity(parts.len());
        let mut textures = TextureCache::default();
        for (k, MeshPart { triangles, material }) in parts.into_iter().enumerate() {
            let mut sub = if single { std::mem::take(&mut mesh) } else { submesh(&mesh, triangles) };
            let m = self.file_material(&material, &mut sub, &mut textures, warnings)?;
            let name = match (single, &material.name) {
                (true, _) => name.clone(),
                (false, Some(mat)) => format!("{name} [{mat}]"),
                (false, None) => format!("{name} [part {k}]"),
            };
            objects.push(Object { name, shape: Shape::Mesh(Arc::new(sub)), material: m });
        }
        Ok(objects)
    }

    /// The material a mesh file gives a part: its texture (times the base colour), else its
    /// vertex colours (times the base colour), else its base colour, else [`DEFAULT_ALBEDO`].
    /// A texture that is missing or cannot be decoded is a warning naming the mesh file, the
    /// material and the image; the part then shows what it would without the texture.
    fn file_material(
        &self,
        fm: &FileMaterial,
        mesh: &mut Mesh,
        textures: &mut TextureCache,
        warnings: &mut Vec<String>,
    ) -> Result<Material> {
        let (src, i) = (self.src, self.index);
        let factor = fm.base_color.unwrap_or(DVec3::ONE);
        let mesh_file = self.base.join(self.spec.file.as_deref().unwrap_or(Path::new("?")));
        if let Some(tex) = &fm.texture {
            if mesh.uvs.is_some() {
                let (filter, wrap) = (tex.filter.unwrap_or_default(), tex.wrap.unwrap_or_default());
                let key = tex.source.clone();
                let image = match textures.get(&key) {
                    Some(image) => image.clone(),
                    None => {
                        let image = match &tex.source {
                            TextureSource::File(p) => self.textures.load(p, filter, wrap),
                            TextureSource::Embedded { name, bytes } => {
                                ImageTexture::decode(bytes, &format!("{} ({name})", mesh_file.display()), filter, wrap)
                            }
                        };
                        // One warning per image, however many parts use it.
                        let image = image.map(Arc::new).map_err(|e| {
                            let material = fm.name.as_deref().map(|n| format!("material '{n}'"));
                            warnings.push(format!(
                                "{}: {}: texture {e}; the material's base colour is used instead (objects[{i}])",
                                mesh_file.display(),
                                material.as_deref().unwrap_or("the material"),
                            ));
                        });
                        textures.push((key, image.clone()));
                        image
                    }
                };
                match image {
                    Ok(image) if factor == DVec3::ONE && (image.filter, image.wrap) == (filter, wrap) => {
                        return Ok(Material::Texture(image))
                    }
                    Ok(image) => return Ok(Material::Texture(Arc::new(sampled(&image, filter, wrap).scaled(factor)))),
                    Err(()) => {
                        let untextured = FileMaterial {
                            texture: None,
                            base_color: fm.untextured_color.or(fm.base_color),
                            untextured_color: None,
                            ..fm.clone()
                        };
                        return self.file_material(&untextured, mesh, textures, warnings);
                    }
                }
            }
            warnings.push(format!(
                "{src}: objects[{i}]: the file's texture is ignored: the mesh has no texture coordinates"
            ));
        }
        if fm.vertex_colors {
            if let Some(colors) = &mut mesh.colors {
                for c in colors.iter_mut() {
                    *c *= factor;
                }
                return Ok(Material::VertexColor);
            }
        }
        Ok(Material::Albedo(fm.base_color.unwrap_or(DEFAULT_ALBEDO)))
    }
}
