//! The schematic eye models by name, and the surface table every model is built from.
//!
//! Each model's parameters and their source are in its own file: [`super::navarro`] (Navarro,
//! Santamaria & Bescos, JOSA A 2:1273, 1985; Escudero-Sanz & Navarro, JOSA A 16:1881, 1999),
//! [`super::arizona`] (Schwiegerling, Field Guide to Visual and Ophthalmic Optics, SPIE 2004),
//! [`super::le_grand`] (Le Grand & El Hage, Physiological Optics, Springer 1980) and
//! [`super::user`].

use serde::{Deserialize, Serialize};

use super::medium::Dispersion;
use super::user::UserEye;
use crate::error::{Error, Result};

/// A schematic eye model (the thin-lens eye is handled by [`super::Eye`]).
#[derive(Clone, Debug, PartialEq)]
pub enum EyeModel {
    /// The paraxial thin-lens eye of [`super::Eye`] (not a schematic eye).
    ThinLens,
    /// Navarro, Santamaria & Bescos (1985), accommodating, aspheric.
    Navarro1985,
    /// Escudero-Sanz & Navarro (1999) wide-angle variant of Navarro (1985).
    Navarro1999,
    /// The Arizona eye (Schwiegerling 2004), accommodating, aspheric.
    Arizona,
    /// Le Grand & El Hage (1980) full theoretical eye, spherical, unaccommodated.
    LeGrand,
    /// A user-defined surface table.
    User(Box<UserEye>),
}

impl EyeModel {
    /// The names used in files: "thin-lens", "navarro" (= 1985), "navarro-1985",
    /// "navarro-1999", "arizona", "le-grand", "user" (which needs `user`). `source` names the
    /// file in errors; the field is `eye.model`.
    pub fn parse(name: &str, user: Option<UserEye>, source: &str) -> Result<EyeModel> {
        let model = match name {
            "thin-lens" => EyeModel::ThinLens,
            "navarro" | "navarro-1985" => EyeModel::Navarro1985,
            "navarro-1999" => EyeModel::Navarro1999,
            "arizona" => EyeModel::Arizona,
            "le-grand" => EyeModel::LeGrand,
            "user" => match user {
                Some(u) => {
                    u.validate(source)?;
                    return Ok(EyeModel::User(Box::new(u)));
                }
                None => return Err(Error::invalid(source, "eye.model", "\"user\" needs an [eye.user] surface table")),
            },
            other => {
                return Err(Error::invalid(
                    source,
                    "eye.model",
                    format!(
                        "unknown eye model `{other}` (expected thin-lens, navarro, navarro-1985, navarro-1999, arizona, le-grand or user)"
                    ),
                ))
            }
        };
        if user.is_some() {
            return Err(Error::invalid(
                source,
                "eye.user",
                format!("a surface table is only for model \"user\", not `{name}`"),
            ));
        }
        Ok(model)
    }

    /// The canonical name.
    pub fn name(&self) -> &'static str {
        match self {
            EyeModel::ThinLens => "thin-lens",
            EyeModel::Navarro1985 => "navarro-1985",
            EyeModel::Navarro1999 => "navarro-1999",
            EyeModel::Arizona => "arizona",
            EyeModel::LeGrand => "le-grand",
            EyeModel::User(_) => "user",
        }
    }

    /// One line citing the model's source.
    pub fn citation(&self) -> &'static str {
        match self {
            EyeModel::ThinLens => "thin lens at the pupil (paper Sec. 2.3)",
            EyeModel::Navarro1985 => "Navarro, Santamaria & Bescos, JOSA A 2:1273 (1985)",
            EyeModel::Navarro1999 => "Escudero-Sanz & Navarro, JOSA A 16:1881 (1999)",
            EyeModel::Arizona => "Schwiegerling, Field Guide to Visual and Ophthalmic Optics, SPIE FG04 (2004)",
            EyeModel::LeGrand => "Le Grand & El Hage, Physiological Optics, Springer (1980)",
            EyeModel::User(_) => "user-defined surface table",
        }
    }

    /// The range of the model's accommodation parameter, dioptres; (0, 0) for Le Grand and
    /// a user eye without an accommodation law (one fixed focus).
    pub fn accommodation_range(&self) -> (f64, f64) {
        match self {
            EyeModel::Navarro1985 | EyeModel::Navarro1999 | EyeModel::Arizona => (0.0, 10.0),
            EyeModel::User(u) => u.accommodation_range(),
            _ => (0.0, 0.0),
        }
    }

    /// The model's surface table at accommodation `a` (not checked against the range here).
    pub(crate) fn definition(&self, a: f64) -> Option<EyeDefinition> {
        match self {
            EyeModel::ThinLens => None,
            EyeModel::Navarro1985 => Some(super::navarro::definition(a, false)),
            EyeModel::Navarro1999 => Some(super::navarro::definition(a, true)),
            EyeModel::Arizona => Some(super::arizona::definition(a)),
            EyeModel::LeGrand => Some(super::le_grand::definition()),
            EyeModel::User(u) => Some(u.definition(a)),
        }
    }
}

/// How "best focus" is judged when an eye is focused on an object.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FocusCriterion {
    /// The paraxial image of the object point lies on the retina vertex.
    Paraxial,
    /// The on-axis real-ray spot on the retina (rays filling the entrance pupil) has the least
    /// RMS radius: the focus of a real eye with spherical aberration. The default: it follows
    /// the pupil, and it costs a few milliseconds per focus (measured, docs/EYE.md).
    #[default]
    MinRmsSpot,
}

/// One refracting surface of a surface table, in order from the cornea toward the retina.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SurfaceDef {
    /// Signed vertex radius of curvature, mm (positive: centre toward the retina; 0 plane).
    pub radius: f64,
    /// Conic constant.
    pub conic: f64,
    /// Axial distance to the next surface (or, for the last one, to the retina vertex), mm.
    pub thickness: f64,
    /// The medium after the surface.
    pub medium: Dispersion,
    /// Semi-diameter, mm.
    pub semi_diameter: f64,
}

/// A model's surface table at one accommodation.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EyeDefinition {
    /// The surfaces, cornea front first.
    pub surfaces: Vec<SurfaceDef>,
    /// The iris plane is `iris_distance` mm behind the vertex of surface `iris_after`.
    pub iris_after: usize,
    /// See `iris_after`.
    pub iris_distance: f64,
    /// Retina radius of curvature, mm (negative: concave toward the lens; 0 flat).
    pub retina_radius: f64,
    /// The wavelength at which the eye's frame and retina map are built, nm.
    pub reference_wavelength: f64,
}

/// The frame's reference wavelength unless a model says otherwise, nm (the photopic peak).
pub const REFERENCE_WAVELENGTH: f64 = 555.0;
