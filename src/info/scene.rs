//! `inimtrace info --scene`: what a scene holds (paper Sec. 4.1): its objects, their shapes and
//! materials, triangles, depth range, light and background, as data ([`SceneSummary`],
//! serialisable to JSON) and as text.

use serde::Serialize;

use crate::count::count;
use crate::scene::{Material, Scene, Shape};

/// One scene object as `info --scene` reports it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectSummary {
    /// Object name.
    pub name: String,
    /// "rect" or "mesh".
    pub shape: &'static str,
    /// Tessellated rectangles count 2.
    pub triangles: usize,
    /// Axis-aligned lower bounds after the object's transform, mm.
    pub bounds_min_mm: [f64; 3],
    /// Axis-aligned upper bounds after the object's transform, mm.
    pub bounds_max_mm: [f64; 3],
    /// "albedo [r, g, b]", "chart", "vertex colours", "texture W x H".
    pub material: String,
}

/// A scene as `info --scene` reports it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneSummary {
    /// Scene name.
    pub name: String,
    /// Every object.
    pub objects: Vec<ObjectSummary>,
    /// Triangles of the whole scene (rectangles count 2).
    pub triangles: usize,
    /// Nearest and farthest z of the scene's geometry (along the optical axis), mm.
    pub depth_range_mm: [f64; 2],
    /// The same in diopters (1000 / z; nearest first, so the larger value first).
    pub depth_range_diopters: [f64; 2],
    /// `None`: radiance = albedo.
    pub light_direction: Option<[f64; 3]>,
    /// Linear RGB radiance of the light.
    pub light_radiance: Option<[f64; 3]>,
    /// Radiance of rays that hit nothing.
    pub background: [f64; 3],
    /// What loading the scene noticed.
    pub warnings: Vec<String>,
}

/// Summarises a loaded scene.
pub fn scene_summary(scene: &Scene) -> SceneSummary {
    let objects: Vec<ObjectSummary> = scene
        .objects
        .iter()
        .map(|o| {
            let (shape, triangles, (lo, hi)) = match &o.shape {
                Shape::Rect(r) => ("rect", 2, r.to_mesh().bounds()),
                Shape::Mesh(m) => ("mesh", m.triangle_count(), m.bounds()),
            };
            let material = match &o.material {
                Material::Albedo(a) => format!("albedo [{}, {}, {}]", a.x, a.y, a.z),
                Material::Chart { .. } => "chart".into(),
                Material::VertexColor => "vertex colours".into(),
                Material::Texture(t) => format!("texture {} x {}", t.width, t.height),
                Material::Grating(g) => format!(
                    "grating {} cpd at {} deg, mean {}, contrast {}",
                    g.frequency_cpd, g.orientation_deg, g.mean, g.contrast
                ),
                Material::Edge(e) => format!("slanted edge at {} deg, {} / {}", e.angle_deg, e.low, e.high),
            };
            ObjectSummary {
                name: o.name.clone(),
                shape,
                triangles,
                bounds_min_mm: lo.to_array(),
                bounds_max_mm: hi.to_array(),
                material,
            }
        })
        .collect();
    let near = objects.iter().map(|o| o.bounds_min_mm[2]).fold(f64::INFINITY, f64::min);
    let far = objects.iter().map(|o| o.bounds_max_mm[2]).fold(f64::NEG_INFINITY, f64::max);
    let mut warnings = scene.warnings.clone();
    if near <= 0.0 {
        warnings.push(format!("geometry reaches z = {near} mm, at or behind the pupil plane"));
    }
    SceneSummary {
        name: scene.name.clone(),
        triangles: scene.triangle_count(),
        objects,
        depth_range_mm: [near, far],
        depth_range_diopters: [1000.0 / near, 1000.0 / far],
        light_direction: scene.light.map(|l| l.direction.to_array()),
        light_radiance: scene.light.map(|l| l.radiance.to_array()),
        background: scene.background.to_array(),
        warnings,
    }
}

/// [`SceneSummary`] as the text `inimtrace info --scene` prints.
pub fn scene_summary_text(s: &SceneSummary) -> String {
    let v3 = |v: [f64; 3]| format!("({:.3}, {:.3}, {:.3})", v[0], v[1], v[2]);
    let mut t = format!("scene {}: {}, {}\n", s.name, count(s.objects.len(), "object"), count(s.triangles, "triangle"));
    for o in &s.objects {
        t += &format!(
            "  {} ({}, {}, {}): bounds {} to {} mm, size {}\n",
            o.name,
            o.shape,
            count(o.triangles, "triangle"),
            o.material,
            v3(o.bounds_min_mm),
            v3(o.bounds_max_mm),
            v3([0, 1, 2].map(|k| o.bounds_max_mm[k] - o.bounds_min_mm[k]))
        );
    }
    t += &format!(
        "depth range: z = {:.1} to {:.1} mm ({:.3} to {:.3} D)\n",
        s.depth_range_mm[0], s.depth_range_mm[1], s.depth_range_diopters[0], s.depth_range_diopters[1]
    );
    t += &match (s.light_direction, s.light_radiance) {
        (Some(d), Some(r)) => format!("light: distant, travelling along {}, radiance {}\n", v3(d), v3(r)),
        _ => "light: none (radiance = albedo)\n".into(),
    };
    t += &format!("background: {}\n", v3(s.background));
    for w in &s.warnings {
        t += &format!("warning: {w}\n");
    }
    t
}
