//! Scene files (the scene of Sec. 4.1 and Fig. 3, and scenes beyond it): TOML read into a
//! [`Scene`]: rects (the paper's charts and backdrop), meshes from OBJ, PLY, STL and glTF files
//! (placed and coloured in `scene_mesh.rs`) and procedural sphere grids, each with a material,
//! plus a distant light. Every error names the scene file and the field (`objects[i].name`);
//! errors from a referenced mesh, texture or bar list file name that file as well.
//! `builtin:paper` names the paper's scene without a file.
//!
//! Defaults: the scene's `name` is the file's stem; an object without `material` takes the mesh
//! file's own materials, else [`DEFAULT_ALBEDO`] (0.8 grey); a scene with a mesh or sphere grid
//! and no `[light]` is lit by [`DEFAULT_LIGHT`], a light from the eye (travelling along +z), so
//! that surfaces facing the eye keep their albedo and turned ones darken with the cosine
//! (`[light] type = "none"` keeps radiance = albedo). Rect-only scenes (the paper's) stay unlit.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::input::Reach;
use super::scene_mesh::SceneTextures;
pub use super::scene_mesh::{FitSpec, DEFAULT_ALBEDO};
pub use super::scene_target::{EdgeSpec, GratingSpec};
use super::text::{read_text, toml_error};
use crate::error::{Error, Result};
use crate::scene::image_texture::{Filter, Wrap};
use crate::scene::usaf::{self, ChartScale};
use crate::scene::{procedural, BarChart, Light, Material, Object, Rect, Scene, Shape, Transform};

/// Which bar chart a `chart` material shows.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum ChartKind {
    /// The paper framework's chart (146 bars).
    Framework,
    /// A procedural MIL-STD-150A chart; see `groups` and `scale`.
    Usaf,
    /// Bars from a text file (`minx miny maxx maxy` per line), see `file`.
    File,
}

/// How a procedural chart is sized on its rectangle.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum ChartScaleSpec {
    /// Scaled to fill the rectangle.
    Fit,
    /// At the chart standard's physical size (millimetres).
    Physical,
}

/// An object's material: `albedo = [r, g, b]`, or a chart.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Linear RGB albedo in [0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<[f64; 3]>,
    /// A bar chart instead of a plain albedo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chart: Option<ChartKind>,
    /// Procedural chart: first and last group (inclusive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<[i32; 2]>,
    /// Procedural chart: fit the rectangle (default) or physical size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ChartScaleSpec>,
    /// Bar-list file for `chart = "file"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Bar albedo (default black) and backing albedo (default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bar_albedo: Option<[f64; 3]>,
    /// Albedo of the chart's backing (default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backing_albedo: Option<[f64; 3]>,
    /// Meshes: interpolate the file's per-vertex colours (`vertex_color = true`; the file must
    /// have colours).
    #[serde(default, alias = "vertex-color", skip_serializing_if = "Option::is_none")]
    pub vertex_color: Option<bool>,
    /// Meshes: a PNG texture looked up by the file's uvs (relative to the scene file), or
    /// `"mtl"` for the OBJ material's `map_Kd`. See [`crate::scene::image_texture`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<PathBuf>,
    /// Texture filter: "bilinear" (default) or "nearest".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub filter: Option<Filter>,
    /// UVs outside [0, 1]: "repeat" (default) or "clamp".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrap: Option<Wrap>,
    /// A sinusoidal grating (resolution target), any shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grating: Option<GratingSpec>,
    /// A slanted edge (resolution target), any shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge: Option<EdgeSpec>,
}

impl MaterialSpec {
    /// True when no field is given (`material` left out): the object's own or default colours.
    pub fn is_unset(&self) -> bool {
        *self == MaterialSpec::default()
    }
}

/// An object's `type`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    /// `"rect"`: a planar rectangle.
    Rect,
    /// `"mesh"`: a triangle mesh from a file.
    Mesh,
    /// `"sphere-grid"`: a procedural grid of UV spheres.
    SphereGrid,
}

/// One scene object.
/// - `type = "rect"`: facing the eye, given by `center` and `size` (width along x, height
///   along y); any other orientation by `center`, `half_u` and `half_v`.
/// - `type = "mesh"`: a triangle mesh from `file` (OBJ, PLY, STL, glTF or GLB, relative to the
///   scene file), placed by `transform = { scale, rotation_deg, translation }` (see
///   [`crate::scene::Transform`]) or `fit = { size, center }` ([`FitSpec`]).
/// - `type = "sphere-grid"`: `count = [nx, ny]` UV spheres of `radius` with `segments`
///   longitudes, `spacing` mm apart in the plane `z = center.z`, centred on `center`
///   ([`crate::scene::procedural::sphere_grid`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Default: the mesh file's stem, else the object's index.
    #[serde(default)]
    pub name: Option<String>,
    /// `type`: what the object is.
    #[serde(rename = "type")]
    pub kind: ShapeKind,
    /// Rectangle or sphere-grid centre, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    /// Mesh file (relative to the scene file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Mesh placement: scale, then rotation, then translation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<Transform>,
    /// Mesh placement by size and centre instead of a `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitSpec>,
    /// Sphere grid: spheres along x and y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<[usize; 2]>,
    /// Sphere grid: centre-to-centre distance, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f64>,
    /// Sphere grid: sphere radius, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Sphere grid: longitudes per sphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
    /// Eye-facing rectangle: width (x) and height (y), mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[f64; 2]>,
    /// Oriented rectangle: half of its first side, as a vector, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_u: Option<[f64; 3]>,
    /// Oriented rectangle: half of its second side, as a vector, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_v: Option<[f64; 3]>,
    /// Left out: the mesh file's own materials, else [`DEFAULT_ALBEDO`].
    #[serde(default, skip_serializing_if = "MaterialSpec::is_unset")]
    pub material: MaterialSpec,
}

/// A scene file (TOML): background, light and objects; millimetres, the eye's pupil at the origin.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Default: the scene file's stem.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Radiance of rays that hit nothing (default black).
    #[serde(default)]
    pub background: [f64; 3],
    /// `[light] type = "distant"` or `"none"`; left out: [`DEFAULT_LIGHT`] for scenes with a
    /// mesh or sphere grid, none for rect-only scenes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightSpec>,
    /// `[[objects]]`, in order.
    #[serde(rename = "objects")]
    pub objects: Vec<ObjectSpec>,
    /// Files the scene names (meshes, textures, bar lists, and the files a mesh names) may be
    /// outside the scene file's folder, or absolute paths (default `false`: refused).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_outside_paths: bool,
}

/// A `[light]`'s `type`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum LightKind {
    /// Parallel light along `direction`.
    Distant,
    /// No light: radiance = albedo.
    None,
}

/// `[light]`: a distant light travelling along `direction` (normalised on load) with linear
/// RGB `radiance` (default white), or `type = "none"`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    /// `type`: distant or none.
    #[serde(rename = "type")]
    pub kind: LightKind,
    /// Direction the light travels (normalised on load).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
    /// Linear RGB radiance (default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiance: Option<[f64; 3]>,
}

/// The light of a scene with meshes and no `[light]`: from the eye, travelling along +z, white.
pub const DEFAULT_LIGHT: Light = Light { direction: DVec3::Z, radiance: DVec3::ONE };

fn finite3(src: &str, field: &str, v: [f64; 3]) -> Result<DVec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from_array(v))
    } else {
        Err(Error::invalid(src, field, format!("must be finite, got {v:?}")))
    }
}

/// The largest albedo or radiance a scene may hold: images are written as f32, whose largest
/// value is about 3.4e38, and a lit pixel (albedo times light radiance) must stay far below it.
pub const MAX_RADIANCE: f64 = 1e15;

fn albedo3(src: &str, field: &str, v: [f64; 3]) -> Result<DVec3> {
    let a = finite3(src, field, v)?;
    if a.min_element() < 0.0 {
        return Err(Error::invalid(src, field, format!("albedo must be >= 0, got {v:?}")));
    }
    if a.max_element() > MAX_RADIANCE {
        return Err(Error::invalid(
            src,
            field,
            format!("must be at most {MAX_RADIANCE:e} (images are 32-bit float), got {v:?}"),
        ));
    }
    Ok(a)
}

impl SceneSpec {
    /// Builds the scene; `src` names the file (its stem is the default name), `base` resolves
    /// relative file paths.
    pub fn to_scene(&self, src: &str, base: &Path) -> Result<Scene> {
        let background = albedo3(src, "background", self.background)?;
        let mut objects = Vec::with_capacity(self.objects.len());
        let mut framework_chart = None;
        let mut warnings = Vec::new();
        let reach = Reach::for_scene(base, self.allow_outside_paths);
        let textures = SceneTextures::default();
        for (index, spec) in self.objects.iter().enumerate() {
            let o = ObjectInput { src, base, reach: &reach, textures: &textures, index, spec };
            let shape = match spec.kind {
                ShapeKind::Mesh => {
                    objects.extend(o.mesh_objects(&mut framework_chart, &mut warnings)?);
                    continue;
                }
                ShapeKind::Rect => o.rect_shape()?,
                ShapeKind::SphereGrid => o.sphere_grid_shape()?,
            };
            let material = if spec.material.is_unset() {
                Material::Albedo(DEFAULT_ALBEDO)
            } else {
                o.material(&shape, None, &mut framework_chart)?
            };
            objects.push(Object {
                name: spec.name.clone().unwrap_or_else(|| format!("object {index}")),
                shape,
                material,
            });
        }
        if objects.is_empty() {
            return Err(Error::invalid(src, "objects", "a scene needs at least one object"));
        }
        let light = match &self.light {
            None if self.objects.iter().any(|o| o.kind != ShapeKind::Rect) => Some(DEFAULT_LIGHT),
            None => None,
            Some(LightSpec { kind: LightKind::None, direction, radiance }) => {
                if direction.is_some() || radiance.is_some() {
                    return Err(Error::invalid(src, "light", "`type = \"none\"` takes no direction or radiance"));
                }
                None
            }
            Some(LightSpec { kind: LightKind::Distant, direction, radiance }) => {
                let direction = direction
                    .ok_or_else(|| Error::invalid(src, "light.direction", "missing (a distant light needs it)"))?;
                let d = finite3(src, "light.direction", direction)?;
                if d.length() == 0.0 {
                    return Err(Error::invalid(src, "light.direction", "must be non-zero"));
                }
                let radiance = albedo3(src, "light.radiance", radiance.unwrap_or([1.0; 3]))?;
                Some(Light { direction: d.normalize(), radiance })
            }
        };
        let name = self.name.clone().unwrap_or_else(|| {
            Path::new(src).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| src.to_string())
        });
        Ok(Scene { name, objects, background, light, warnings })
    }

    /// The paper's scene as a file (written to `scenes/paper.toml`).
    pub fn paper() -> Self {
        let chart = |name: &str, c: [f64; 3], w: f64| ObjectSpec {
            name: Some(name.into()),
            kind: ShapeKind::Rect,
            center: Some(c),
            size: Some([w, w]),
            material: MaterialSpec { chart: Some(ChartKind::Framework), ..Default::default() },
            ..ObjectSpec::rect_default()
        };
        SceneSpec {
            name: Some("paper".into()),
            background: [0.0; 3],
            light: None,
            allow_outside_paths: false,
            objects: vec![
                chart("near chart", [-45.0, -45.0, 300.0], 90.0),
                chart("centre chart", [0.0, 0.0, 400.0], 120.0),
                chart("far chart", [90.0, 90.0, 600.0], 180.0),
                ObjectSpec {
                    name: Some("background".into()),
                    kind: ShapeKind::Rect,
                    center: Some([200.0, 0.0, 1302.0]),
                    size: Some([2000.0, 2000.0]),
                    material: MaterialSpec { albedo: Some([0.2, 0.7, 0.8]), ..Default::default() },
                    ..ObjectSpec::rect_default()
                },
            ],
        }
    }
}

/// One `[[objects]]` entry being resolved into a shape and a material; names the scene file and
/// the entry's fields (`objects[i].field`) in its errors.
pub(super) struct ObjectInput<'a> {
    pub(super) src: &'a str,
    pub(super) base: &'a Path,
    /// Where the files the scene names may be.
    pub(super) reach: &'a Reach,
    /// The scene's image textures, each decoded once.
    pub(super) textures: &'a SceneTextures,
    pub(super) index: usize,
    pub(super) spec: &'a ObjectSpec,
}

impl ObjectInput<'_> {
    pub(super) fn field(&self, name: &str) -> String {
        format!("objects[{}].{name}", self.index)
    }

    /// Rejects shape fields that the object's kind does not use.
    pub(super) fn only(&self, allowed: &[&str]) -> Result<()> {
        let o = self.spec;
        let given = [
            ("center", o.center.is_some()),
            ("size", o.size.is_some()),
            ("half_u", o.half_u.is_some()),
            ("half_v", o.half_v.is_some()),
            ("file", o.file.is_some()),
            ("transform", o.transform.is_some()),
            ("fit", o.fit.is_some()),
            ("count", o.count.is_some()),
            ("spacing", o.spacing.is_some()),
            ("radius", o.radius.is_some()),
            ("segments", o.segments.is_some()),
        ];
        match given.iter().find(|(name, set)| *set && !allowed.contains(name)) {
            Some((name, _)) => Err(Error::invalid(
                self.src,
                self.field(name),
                format!("not a field of a `{:?}` object (allowed: {})", o.kind, allowed.join(", ")).to_lowercase(),
            )),
            None => Ok(()),
        }
    }

    /// `type = "rect"`.
    fn rect_shape(&self) -> Result<Shape> {
        let (src, o) = (self.src, self.spec);
        self.only(&["center", "size", "half_u", "half_v"])?;
        let center = finite3(
            src,
            &self.field("center"),
            o.center.ok_or_else(|| Error::invalid(src, self.field("center"), "missing (a rect needs `center`)"))?,
        )?;
        Ok(Shape::Rect(self.rect(center)?))
    }

    fn rect(&self, center: DVec3) -> Result<Rect> {
        let (src, o) = (self.src, self.spec);
        let f = |name: &str| self.field(name);
        Ok(match (o.size, o.half_u, o.half_v) {
            (Some([w, h]), None, None) => {
                if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
                    return Err(Error::invalid(
                        src,
                        f("size"),
                        format!("width and height must be positive and finite, got [{w}, {h}]"),
                    ));
                }
                Rect::facing_eye(center, w, h)
            }
            (None, Some(u), Some(v)) => {
                let (hu, hv) = (finite3(src, &f("half_u"), u)?, finite3(src, &f("half_v"), v)?);
                if hu.cross(hv).length() == 0.0 {
                    return Err(Error::invalid(
                        src,
                        f("half_u"),
                        "half_u and half_v must be non-zero and not parallel",
                    ));
                }
                Rect { center, half_u: hu, half_v: hv }
            }
            _ => {
                return Err(Error::invalid(
                    src,
                    f("size"),
                    "give either `size = [width, height]` (facing the eye) or both `half_u` and `half_v`",
                ))
            }
        })
    }

    /// `type = "sphere-grid"`.
    fn sphere_grid_shape(&self) -> Result<Shape> {
        let (src, o) = (self.src, self.spec);
        let f = |name: &str| self.field(name);
        self.only(&["center", "count", "spacing", "radius", "segments"])?;
        let center = finite3(src, &f("center"), o.center.ok_or_else(|| Error::invalid(src, f("center"), "missing"))?)?;
        let count = o.count.ok_or_else(|| Error::invalid(src, f("count"), "missing ([nx, ny])"))?;
        if count[0] == 0 || count[1] == 0 || count[0].checked_mul(count[1]).is_none_or(|n| n > 1_000_000) {
            return Err(Error::invalid(src, f("count"), format!("need 1..=1e6 spheres, got {count:?}")));
        }
        let positive = |name: &str, v: Option<f64>| -> Result<f64> {
            match v {
                Some(x) if x.is_finite() && x > 0.0 => Ok(x),
                Some(x) => Err(Error::invalid(src, f(name), format!("must be positive and finite, got {x}"))),
                None => Err(Error::invalid(src, f(name), "missing")),
            }
        };
        let radius = positive("radius", o.radius)?;
        let spacing = positive("spacing", o.spacing)?;
        let segments = o.segments.unwrap_or(32);
        if !(4..=4096).contains(&segments) {
            return Err(Error::invalid(src, f("segments"), format!("must be 4..=4096, got {segments}")));
        }
        // At most 1e6 spheres of at most 4096 segments: no overflow in u64.
        let tris = (count[0] * count[1]) as u64 * 2 * segments as u64 * (segments / 2 - 1) as u64;
        if tris > 100_000_000 {
            return Err(Error::invalid(src, f("count"), format!("{tris} triangles is over 1e8")));
        }
        // The mesh (indices, positions, normals, uvs) and an acceleration structure over it take
        // about 100 bytes per triangle.
        let mut estimate = crate::budget::Estimate::default();
        estimate.add("the sphere grid's triangles and their acceleration structure", f("count"), tris, 100);
        estimate.check_memory(&crate::budget::memory_budget(), src)?;
        Ok(Shape::Mesh(Arc::new(procedural::sphere_grid(center, count, spacing, radius, segments))))
    }

    /// `material`: exactly one of an albedo, vertex colours, an image texture, a chart, a
    /// grating or an edge.
    pub(super) fn material(
        &self,
        shape: &Shape,
        mesh_texture: Option<PathBuf>,
        framework_chart: &mut Option<Arc<BarChart>>,
    ) -> Result<Material> {
        let src = self.src;
        let m = &self.spec.material;
        let texture_fields = m.texture.is_some() || m.filter.is_some() || m.wrap.is_some();
        let vertex_color = m.vertex_color.unwrap_or(false);
        let field = self.field("material");
        let others = m.albedo.is_some() || m.chart.is_some() || vertex_color || texture_fields;
        match (&m.grating, &m.edge, others) {
            (Some(g), None, false) => return g.to_material(src, &field),
            (None, Some(e), false) => return e.to_material(src, &field),
            (None, None, _) => {}
            _ => {
                return Err(Error::invalid(src, field, "a `grating` or `edge` material takes no other material field"))
            }
        }
        match (&m.albedo, &m.chart, vertex_color, texture_fields) {
            (Some(a), None, false, false) => Ok(Material::Albedo(albedo3(src, &self.field("material.albedo"), *a)?)),
            (None, None, true, false) => self.vertex_color_material(shape),
            (None, None, false, true) => self.texture_material(shape, mesh_texture),
            (None, Some(kind), false, false) => self.chart_material(shape, kind, framework_chart),
            _ => Err(Error::invalid(
                src,
                self.field("material"),
                "give exactly one of `albedo = [r, g, b]`, `chart = \"framework\" | \"usaf\" | \"file\"` \
                 (rects), `vertex_color = true` or `texture = \"file.png\"` (meshes), `grating = { .. }` \
                 or `edge = { .. }`",
            )),
        }
    }

    fn vertex_color_material(&self, shape: &Shape) -> Result<Material> {
        let field = self.field("material.vertex_color");
        match shape {
            Shape::Mesh(mesh) if mesh.colors.is_some() => Ok(Material::VertexColor),
            Shape::Mesh(_) => {
                Err(Error::invalid(self.src, field, "the mesh has no per-vertex colours (give `albedo` instead)"))
            }
            Shape::Rect(_) => Err(Error::invalid(self.src, field, "only meshes have vertex colours")),
        }
    }

    fn texture_material(&self, shape: &Shape, mesh_texture: Option<PathBuf>) -> Result<Material> {
        let (src, m) = (self.src, &self.spec.material);
        let field = self.field("material.texture");
        let Shape::Mesh(mesh) = shape else {
            return Err(Error::invalid(src, field, "image textures are for meshes"));
        };
        let texture =
            m.texture.as_ref().ok_or_else(|| Error::invalid(src, &field, "missing (a PNG path or \"mtl\")"))?;
        let path = if texture.as_os_str() == "mtl" {
            mesh_texture.ok_or_else(|| Error::invalid(src, &field, "\"mtl\": the OBJ's material has no map_Kd"))?
        } else {
            self.reach.resolve(self.base, texture).map_err(|why| Error::invalid(src, &field, why))?
        };
        if mesh.uvs.is_none() {
            return Err(Error::invalid(
                src,
                field,
                "the mesh file has no texture coordinates (vt / u v) to look the texture up with",
            ));
        }
        let tex = self
            .textures
            .load(&path, m.filter.unwrap_or_default(), m.wrap.unwrap_or_default())
            .map_err(|e| Error::in_field(src, &field, e))?;
        Ok(Material::Texture(Arc::new(tex)))
    }

    fn chart_material(
        &self,
        shape: &Shape,
        kind: &ChartKind,
        framework_chart: &mut Option<Arc<BarChart>>,
    ) -> Result<Material> {
        let (src, m) = (self.src, &self.spec.material);
        let f = |name: &str| self.field(name);
        let Shape::Rect(rect) = shape else {
            return Err(Error::invalid(src, f("material.chart"), "charts are for rects"));
        };
        let chart = match kind {
            ChartKind::Framework => framework_chart.get_or_insert_with(|| Arc::new(usaf::framework_chart())).clone(),
            ChartKind::Usaf => {
                let [g0, g1] = m.groups.unwrap_or([-2, 1]);
                if g0 > g1 || g0 < -10 || g1 > 10 {
                    return Err(Error::invalid(
                        src,
                        f("material.groups"),
                        format!("expected [first, last] with -10 <= first <= last <= 10, got [{g0}, {g1}]"),
                    ));
                }
                let scale = match m.scale.clone().unwrap_or(ChartScaleSpec::Fit) {
                    ChartScaleSpec::Fit => ChartScale::Fit,
                    ChartScaleSpec::Physical => {
                        ChartScale::Physical { half_size: DVec2::new(rect.half_u.length(), rect.half_v.length()) }
                    }
                };
                Arc::new(usaf::procedural_chart(g0..=g1, scale))
            }
            ChartKind::File => {
                let file = m
                    .file
                    .as_ref()
                    .ok_or_else(|| Error::invalid(src, f("material.file"), "chart = \"file\" needs `file`"))?;
                let path =
                    self.reach.resolve(self.base, file).map_err(|why| Error::invalid(src, f("material.file"), why))?;
                let text = read_text(&path)?;
                Arc::new(BarChart::new(usaf::parse_bar_list(&text, &path.display().to_string())?))
            }
        };
        Ok(Material::Chart {
            chart,
            bar: albedo3(src, &f("material.bar_albedo"), m.bar_albedo.unwrap_or([0.0; 3]))?,
            backing: albedo3(src, &f("material.backing_albedo"), m.backing_albedo.unwrap_or([1.0; 3]))?,
        })
    }
}

impl ObjectSpec {
    fn rect_default() -> Self {
        ObjectSpec {
            name: None,
            kind: ShapeKind::Rect,
            center: None,
            file: None,
            transform: None,
            fit: None,
            count: None,
            spacing: None,
            radius: None,
            segments: None,
            size: None,
            half_u: None,
            half_v: None,
            material: MaterialSpec::default(),
        }
    }
}

/// Loads a scene: `builtin:paper` or a TOML file.
pub fn load_scene(spec: &str, base: &Path) -> Result<Scene> {
    if spec == "builtin:paper" {
        return Ok(Scene::paper());
    }
    let path = base.join(spec);
    let text = read_text(&path)?;
    let s: SceneSpec = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
    s.to_scene(&path.display().to_string(), path.parent().unwrap_or(Path::new(".")))
}
