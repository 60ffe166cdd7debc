//! The resolution targets of a scene file (the paper's Sec. 4 "perceived spatial
//! resolution"): `material = { grating = { ... } }` and `material = { edge = { ... } }`, read
//! into [`crate::scene::Grating`] and [`crate::scene::SlantedEdge`] (tangent coordinates seen
//! from the pupil centre, see [`crate::scene::target`]). Every error names the scene file and
//! the field (`objects[0].material.grating.contrast`).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::scene::{Grating, Material, SlantedEdge};

/// `grating = { frequency_cpd, orientation_deg = 0, mean = 0.5, contrast = 1, phase_deg = 0 }`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GratingSpec {
    /// Cycles per degree seen from the pupil centre (the same at every depth).
    pub frequency_cpd: f64,
    /// Direction of modulation, degrees counter-clockwise from +x (0 = vertical bars).
    #[serde(default)]
    pub orientation_deg: f64,
    /// Mean luminance (linear; default 0.5).
    #[serde(default = "half")]
    pub mean: f64,
    /// Michelson contrast.
    #[serde(default = "one")]
    pub contrast: f64,
    /// Phase at the pattern's origin, degrees.
    #[serde(default)]
    pub phase_deg: f64,
}

/// `edge = { angle_deg = 5, low = 0, high = 1, through = [0, 0] }`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EdgeSpec {
    /// Direction of the edge's normal (toward `high`), degrees counter-clockwise from +x: 5 is
    /// a vertical edge turned 5 degrees, 95 a nearly horizontal one with `high` above.
    #[serde(default = "five")]
    pub angle_deg: f64,
    /// Value on the dark side (default 0).
    #[serde(default)]
    pub low: f64,
    /// Value on the light side (default 1).
    #[serde(default = "one")]
    pub high: f64,
    /// A point of the edge in tangent coordinates `(x / z, y / z)`.
    #[serde(default)]
    pub through: [f64; 2],
}

fn half() -> f64 {
    0.5
}
fn one() -> f64 {
    1.0
}
fn five() -> f64 {
    5.0
}

impl GratingSpec {
    /// The material; `src` names the file, `field` the `material` table.
    pub fn to_material(&self, src: &str, field: &str) -> Result<Material> {
        let g = Grating {
            frequency_cpd: self.frequency_cpd,
            orientation_deg: self.orientation_deg,
            mean: self.mean,
            contrast: self.contrast,
            phase_deg: self.phase_deg,
        };
        g.check().map_err(|(name, why)| Error::invalid(src, format!("{field}.grating.{name}"), why))?;
        Ok(Material::Grating(g))
    }
}

impl EdgeSpec {
    /// The material; `src` names the file, `field` the `material` table.
    pub fn to_material(&self, src: &str, field: &str) -> Result<Material> {
        let e = SlantedEdge {
            through: DVec2::from_array(self.through),
            angle_deg: self.angle_deg,
            low: self.low,
            high: self.high,
        };
        e.check().map_err(|(name, why)| Error::invalid(src, format!("{field}.edge.{name}"), why))?;
        Ok(Material::Edge(e))
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::io::scene_file::SceneSpec;
    use crate::scene::Scene;

    fn load(text: &str) -> Result<Scene> {
        let spec: SceneSpec = toml::from_str(text).map_err(|e| Error::invalid("t.toml", "toml", e.to_string()))?;
        spec.to_scene("t.toml", Path::new("."))
    }

    #[test]
    fn targets_load_with_defaults_on_rects_and_meshes() {
        let s = load(
            r#"
            [[objects]]
            type = "rect"
            center = [0, 0, 400]
            size = [100, 100]
            material = { grating = { frequency_cpd = 4, orientation_deg = 90 } }
            [[objects]]
            type = "rect"
            center = [0, 0, 500]
            size = [100, 100]
            material = { edge = { through = [0.01, 0] } }
            [[objects]]
            type = "sphere-grid"
            center = [0, 0, 600]
            count = [1, 1]
            spacing = 10
            radius = 5
            material = { grating = { frequency_cpd = 1, mean = 0.2, contrast = 0.5, phase_deg = 90 } }
            "#,
        )
        .unwrap();
        let g = Grating { frequency_cpd: 4.0, orientation_deg: 90.0, mean: 0.5, contrast: 1.0, phase_deg: 0.0 };
        assert!(matches!(s.objects[0].material, Material::Grating(x) if x == g));
        let e = SlantedEdge { through: DVec2::new(0.01, 0.0), angle_deg: 5.0, low: 0.0, high: 1.0 };
        assert!(matches!(s.objects[1].material, Material::Edge(x) if x == e));
        assert!(matches!(s.objects[2].material, Material::Grating(x) if x.mean == 0.2 && x.phase_deg == 90.0));
    }

    #[test]
    fn bad_targets_are_refused_naming_the_field() {
        let case = |material: &str, field: &str| {
            let text =
                format!("[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 400]\nsize = [1, 1]\nmaterial = {material}\n");
            let e = load(&text).unwrap_err().to_string();
            assert!(e.contains("t.toml") && e.contains(field), "{material}: {e}");
        };
        case("{ grating = { frequency_cpd = 0 } }", "objects[0].material.grating.frequency_cpd");
        case("{ grating = { frequency_cpd = 2, contrast = 1.5 } }", "objects[0].material.grating.contrast");
        case("{ grating = { frequency_cpd = 2, mean = -1 } }", "objects[0].material.grating.mean");
        case("{ edge = { high = inf } }", "objects[0].material.edge.high");
        case("{ edge = { angle_deg = nan } }", "objects[0].material.edge.angle_deg");
        case("{ edge = {}, albedo = [1, 1, 1] }", "objects[0].material");
        case("{ edge = {}, grating = { frequency_cpd = 1 } }", "objects[0].material");
        assert!(load("[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 400]\nsize = [1, 1]\nmaterial = { grating = { frequency_cpd = 1, colour = 2 } }\n").is_err());
    }

    #[test]
    fn the_example_of_docs_scenes_loads() {
        let doc = include_str!("../../docs/SCENES.md");
        let section = &doc[doc.find("## Resolution targets").unwrap()..];
        let start = section.find("```toml\n").unwrap() + 8;
        let block = &section[start..start + section[start..].find("```").unwrap()];
        let s = load(block).unwrap();
        assert!(matches!(s.objects[0].material, Material::Grating(g) if g.frequency_cpd == 4.0));
        assert!(matches!(s.objects[1].material, Material::Edge(e) if e.angle_deg == 5.0));
    }
}
