//! The display file's `lenslet` table: the lenslets' optics, `{ kind = "paraxial" }` (the
//! default: the paper's thin lens, eq. (1b)) or a real thick lenslet
//! ([`crate::optics::lenslet::ThickLenslet`]):
//!
//! ```toml
//! [lenslet]
//! kind = "thick"
//! thickness = 1.0                        # centre thickness, mm
//! front = { radius = 3.1527, conic = 0.0 } # faces the eye; radius > 0: centre toward the LCD
//! back = { radius = 0.0 }                # radius 0 (or inf): a plane
//! material = "pmma"                      # "pmma", "n-bk7", or a formula: { sellmeier = { b = [..], c = [..] } },
//!                                        # { cauchy = { a = .., b = .., c = .. } }, { table = { .. } }, { constant = 1.5 }
//! design_cdp_mm = 385.7                  # optional: the central depth plane the design intends
//! ```

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::optics::eye::medium::Dispersion;
use crate::optics::lenslet::{LensletOptics, Material, Surface, ThickLenslet};

/// One surface: `{ radius, conic }` (radius 0 or infinite: a plane; conic default 0).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSpec {
    /// Signed radius of curvature, mm (positive: centre of curvature toward the LCD).
    pub radius: f64,
    /// Conic constant.
    #[serde(default)]
    pub conic: f64,
}

/// A material: a built-in name or a dispersion formula.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum MaterialSpec {
    /// "pmma" or "n-bk7" (any case).
    Named(String),
    /// A dispersion formula, as the user eye's media are written.
    Formula(Dispersion),
}

/// The `lenslet` table.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum LensletOpticsSpec {
    /// The paper's thin lens (eq. (1b)); it takes no other field (a struct variant, so that a
    /// thick lenslet's field beside `kind = "paraxial"` is refused as unknown, not ignored).
    Paraxial {},
    /// A real lenslet.
    Thick {
        /// Centre thickness, mm.
        thickness: f64,
        /// The surface facing the eye.
        front: SurfaceSpec,
        /// The surface facing the LCD.
        back: SurfaceSpec,
        /// The material.
        material: MaterialSpec,
        /// The central depth plane the design intends, mm from the pupil.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        design_cdp_mm: Option<f64>,
    },
}

impl LensletOpticsSpec {
    /// The optics, or an error naming `source` and the field.
    pub fn to_optics(&self, source: &str) -> Result<LensletOptics> {
        let LensletOpticsSpec::Thick { thickness, front, back, material, design_cdp_mm } = self else {
            return Ok(LensletOptics::Paraxial);
        };
        let material = match material {
            MaterialSpec::Named(name) => match name.to_ascii_lowercase().as_str() {
                "pmma" => Material::pmma(),
                "n-bk7" | "nbk7" | "bk7" => Material::n_bk7(),
                _ => {
                    return Err(Error::invalid(
                        source,
                        "lenslet.material",
                        format!("unknown material {name:?}: \"pmma\", \"n-bk7\" or a dispersion formula"),
                    ))
                }
            },
            MaterialSpec::Formula(d) => Material { name: "user".into(), dispersion: d.clone() },
        };
        if let Some(z) = design_cdp_mm {
            if !(z.is_finite() && *z > 0.0) {
                return Err(Error::invalid(source, "lenslet.design_cdp_mm", format!("must be positive, got {z}")));
            }
        }
        Ok(LensletOptics::Thick(Box::new(ThickLenslet {
            front: Surface { radius: front.radius, conic: front.conic },
            back: Surface { radius: back.radius, conic: back.conic },
            thickness: *thickness,
            material,
            design_cdp_mm: *design_cdp_mm,
        })))
    }

    /// The table of `optics` (`None` for the default thin lens, so files without it stay so).
    pub fn from_optics(optics: &LensletOptics) -> Option<Self> {
        let t = optics.thick()?;
        let material = match t.material.name.as_str() {
            "PMMA" if t.material == Material::pmma() => MaterialSpec::Named("pmma".into()),
            "N-BK7" if t.material == Material::n_bk7() => MaterialSpec::Named("n-bk7".into()),
            _ => MaterialSpec::Formula(t.material.dispersion.clone()),
        };
        let surface = |s: &Surface| SurfaceSpec { radius: s.radius, conic: s.conic };
        Some(LensletOpticsSpec::Thick {
            thickness: t.thickness,
            front: surface(&t.front),
            back: surface(&t.back),
            material,
            design_cdp_mm: t.design_cdp_mm,
        })
    }
}
