//! Scene description (paper Sec. 4.1, Fig. 3): objects with a shape and a material. Without a
//! light, radiance equals albedo (the paper's scene needs nothing more: matte front-facing
//! planes lit from behind the eye). With an optional distant [`Light`] (as the published
//! framework lit the paper's scene) surfaces are Lambertian and the renderer traces shadow rays
//! (`render::tracer::shade`). Rays that hit nothing see `background`.
//!
//! Shapes are analytic rectangles (intersected exactly in `f64` by
//! `accel::analytic::AnalyticRects`) or triangle meshes. Every rectangle can be
//! tessellated ([`Rect::to_mesh`]) so that every scene renders with every mesh backend.

pub mod image_texture;
pub mod mesh;
pub(crate) mod polygon;
pub mod procedural;
pub mod target;
pub mod texture;
pub mod transform;
pub mod usaf;

use std::sync::Arc;

use glam::{DVec2, DVec3};

use crate::ray::{Hit, Ray, Surface};
pub use image_texture::ImageTexture;
pub use mesh::Mesh;
pub use target::{Grating, SlantedEdge};
pub use texture::{Bar, BarChart};
pub use transform::Transform;

/// A planar rectangle `center + s half_u + t half_v`, `s, t` in `[-1, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// Centre, world mm.
    pub center: DVec3,
    /// Half of the first side, as a vector.
    pub half_u: DVec3,
    /// Half of the second side, as a vector.
    pub half_v: DVec3,
}

impl Rect {
    /// A rectangle facing the eye (normal along z), `width` along x and `height` along y.
    pub fn facing_eye(center: DVec3, width: f64, height: f64) -> Self {
        Self { center, half_u: DVec3::new(0.5 * width, 0.0, 0.0), half_v: DVec3::new(0.0, 0.5 * height, 0.0) }
    }

    /// Two triangles with per-vertex `uv` = the rectangle's local coordinates, so that
    /// interpolating them at a triangle hit recovers the analytic backend's `uv`.
    pub fn to_mesh(&self) -> Mesh {
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        Mesh {
            positions: corners.iter().map(|&(s, t)| self.center + s * self.half_u + t * self.half_v).collect(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            normals: None,
            uvs: Some(corners.iter().map(|&(s, t)| DVec2::new(s, t)).collect()),
            colors: None,
        }
    }
}

/// The geometry of an object.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A planar rectangle (exact for the analytic backend).
    Rect(Rect),
    /// A triangle mesh, shared between scenes that hold it.
    Mesh(Arc<Mesh>),
}

/// What an object looks like. Albedos are linear RGB.
#[derive(Clone, Debug)]
pub enum Material {
    /// A constant albedo.
    Albedo(DVec3),
    /// A bar chart: `bar` albedo on the bars, `backing` elsewhere, looked up by surface `uv`.
    Chart {
        /// The bars, in the rectangle's surface coordinates.
        chart: Arc<BarChart>,
        /// Albedo on the bars.
        bar: DVec3,
        /// Albedo elsewhere.
        backing: DVec3,
    },
    /// Per-vertex colours of a mesh, interpolated.
    VertexColor,
    /// An image looked up by the mesh's interpolated texture coordinates (objects without
    /// texture coordinates see the texture's mean colour).
    Texture(Arc<ImageTexture>),
    /// A sinusoidal grating in tangent coordinates (resolution target, [`target`]).
    Grating(Grating),
    /// A slanted edge in tangent coordinates (resolution target, [`target`]).
    Edge(SlantedEdge),
}

/// A distant light: parallel light travelling along `direction` (unit), with `radiance` (linear
/// RGB) scaled so that a surface facing it head-on has radiance `albedo * radiance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit direction the light travels.
    pub direction: DVec3,
    /// Linear RGB radiance.
    pub radiance: DVec3,
}

/// One object of a scene: its geometry and material.
#[derive(Clone, Debug)]
pub struct Object {
    /// Name, for `info --scene` and errors.
    pub name: String,
    /// Its geometry.
    pub shape: Shape,
    /// Its colour: albedo, chart or texture.
    pub material: Material,
}

/// A 3-D scene in world millimetres: objects, background and an optional distant light.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name, for reports.
    pub name: String,
    /// The objects, in file order.
    pub objects: Vec<Object>,
    /// Radiance seen by rays that hit nothing.
    pub background: DVec3,
    /// Optional distant light; `None` = radiance is albedo.
    pub light: Option<Light>,
    /// Notes from loading the scene (e.g. degenerate triangles dropped) for the caller to show.
    pub warnings: Vec<String>,
}

/// Corner uvs of a tessellated [`Rect`] ([`Rect::to_mesh`]), by triangle.
const RECT_TRIANGLE_UVS: [[DVec2; 3]; 2] = [
    [DVec2::new(-1.0, -1.0), DVec2::new(1.0, -1.0), DVec2::new(1.0, 1.0)],
    [DVec2::new(-1.0, -1.0), DVec2::new(1.0, 1.0), DVec2::new(-1.0, 1.0)],
];

impl Scene {
    /// The paper's scene, as its framework built it (see `data/README` notes in the README):
    /// three USAF-1951 chart squares, near 90 mm wide centred at (-45, -45, 300), centre 120 mm
    /// at (0, 0, 400), far 180 mm at (90, 90, 600); behind them a background square of albedo
    /// (0.2, 0.7, 0.8) at z = 1302 spanning x -800..1200, y -1000..1000.
    pub fn paper() -> Self {
        let chart = Arc::new(usaf::framework_chart());
        let square = |name: &str, c: DVec3, w: f64| Object {
            name: name.into(),
            shape: Shape::Rect(Rect::facing_eye(c, w, w)),
            material: Material::Chart { chart: chart.clone(), bar: DVec3::ZERO, backing: DVec3::ONE },
        };
        Scene {
            name: "paper".into(),
            objects: vec![
                square("near chart", DVec3::new(-45.0, -45.0, 300.0), 90.0),
                square("centre chart", DVec3::new(0.0, 0.0, 400.0), 120.0),
                square("far chart", DVec3::new(90.0, 90.0, 600.0), 180.0),
                Object {
                    name: "background".into(),
                    shape: Shape::Rect(Rect::facing_eye(DVec3::new(200.0, 0.0, 1302.0), 2000.0, 2000.0)),
                    material: Material::Albedo(DVec3::new(0.2, 0.7, 0.8)),
                },
            ],
            background: DVec3::ZERO,
            light: None,
            warnings: Vec::new(),
        }
    }

    /// Total triangles of the scene's meshes (tessellated rectangles count 2).
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Rect(_) => 2,
                Shape::Mesh(m) => m.triangle_count(),
            })
            .sum()
    }

    /// True when every object is an analytic primitive.
    pub fn is_analytic(&self) -> bool {
        self.objects.iter().all(|o| matches!(o.shape, Shape::Rect(_)))
    }

    /// Surface coordinates of a hit: the analytic `uv`, or the mesh's interpolated `uv`
    /// (a tessellated rectangle's `uv` are its local coordinates).
    pub fn surface_uv(&self, hit: &Hit) -> Option<DVec2> {
        match hit.surface {
            Surface::Analytic { uv } => Some(uv),
            Surface::Triangle { index, bary } => match &self.objects.get(hit.object as usize)?.shape {
                Shape::Rect(_) => {
                    // Same as interpolating `Rect::to_mesh()`'s uvs, without building the mesh.
                    let [a, b, c] = RECT_TRIANGLE_UVS.get(index as usize)?;
                    Some(*a * (1.0 - bary.x - bary.y) + *b * bary.x + *c * bary.y)
                }
                Shape::Mesh(m) => m.uvs.as_ref().map(|uvs| m.interpolate(uvs, index, bary)),
            },
        }
    }

    /// The unit surface normal at a hit, facing the ray (`dot(normal, ray.dir) <= 0`):
    /// the geometric normal for rectangles, the interpolated vertex normal for meshes that have
    /// normals (the geometric one for those that do not, or where interpolation gives zero).
    pub fn normal(&self, ray: &Ray, hit: &Hit) -> DVec3 {
        let Some(object) = self.objects.get(hit.object as usize) else { return -ray.dir.normalize_or_zero() };
        let n = match (&object.shape, hit.surface) {
            (Shape::Rect(r), _) => r.half_u.cross(r.half_v),
            (Shape::Mesh(m), Surface::Triangle { index, bary }) if (index as usize) < m.triangles.len() => {
                let interpolated = m.normals.as_ref().map(|ns| m.interpolate(ns, index, bary)).unwrap_or(DVec3::ZERO);
                if interpolated.length_squared() > 0.0 && interpolated.is_finite() {
                    interpolated
                } else {
                    let [p0, p1, p2] = m.triangle_positions(index as usize);
                    (p1 - p0).cross(p2 - p0)
                }
            }
            _ => -ray.dir,
        };
        let n = n.normalize_or_zero();
        if n.dot(ray.dir) > 0.0 {
            -n
        } else {
            n
        }
    }

    /// Albedo at the hit of `ray`: the radiance leaving it toward the ray's origin when the
    /// scene has no light; the background for a miss. The ray locates the hit point for the
    /// targets defined in tangent coordinates ([`target::hit_tangent`]).
    #[inline]
    pub fn radiance(&self, ray: &Ray, hit: Option<&Hit>) -> DVec3 {
        let Some(hit) = hit else { return self.background };
        let Some(object) = self.objects.get(hit.object as usize) else { return self.background };
        match &object.material {
            Material::Albedo(a) => *a,
            Material::Chart { chart, bar, backing } => match self.surface_uv(hit) {
                Some(uv) if chart.is_bar(uv) => *bar,
                _ => *backing,
            },
            Material::VertexColor => match (&object.shape, hit.surface) {
                (Shape::Mesh(m), Surface::Triangle { index, bary }) => match &m.colors {
                    Some(c) => m.interpolate(c, index, bary),
                    None => DVec3::ONE,
                },
                _ => DVec3::ONE,
            },
            Material::Texture(tex) => match self.surface_uv(hit) {
                Some(uv) => tex.sample(uv),
                None => tex.mean(),
            },
            Material::Grating(g) => g.at(target::hit_tangent(ray, hit.t)),
            Material::Edge(e) => e.at(target::hit_tangent(ray, hit.t)),
        }
    }
}
