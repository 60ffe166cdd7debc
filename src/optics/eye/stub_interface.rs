//! TEMPORARY stand-in for the schematic-eye core (replaced at merge).
#![allow(missing_docs, dead_code)]
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::optics::PlaneRay;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UserEye {}

#[derive(Clone, Debug, PartialEq)]
pub enum EyeModel {
    ThinLens,
    Navarro1985,
    Navarro1999,
    Arizona,
    LeGrand,
    User(Box<UserEye>),
}
impl EyeModel {
    pub fn parse(name: &str, _user: Option<UserEye>, source: &str) -> Result<EyeModel> {
        Ok(match name {
            "thin-lens" => EyeModel::ThinLens,
            "navarro" | "navarro-1985" => EyeModel::Navarro1985,
            "navarro-1999" => EyeModel::Navarro1999,
            "arizona" => EyeModel::Arizona,
            "le-grand" => EyeModel::LeGrand,
            _ => return Err(Error::invalid(source, "eye.model", format!("unknown `{name}`"))),
        })
    }
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
    pub fn citation(&self) -> &'static str {
        "stub"
    }
    pub fn accommodation_range(&self) -> (f64, f64) {
        (0.0, 10.0)
    }
}
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FocusCriterion {
    Paraxial,
    MinRmsSpot,
}
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paraxial {
    pub power_d: f64,
    pub entrance_pupil_z: f64,
    pub pupil_magnification: f64,
    pub iris_z: f64,
    pub cornea_z: f64,
    pub retina_z: f64,
}
#[derive(Clone, Debug, PartialEq)]
pub struct SchematicEye {
    a: f64,
    power: f64,
}
impl SchematicEye {
    pub fn new(_model: &EyeModel, accommodation: f64, _source: &str) -> Result<Self> {
        Ok(Self { a: accommodation, power: 1.0 / 17.0 + accommodation / 1000.0 })
    }
    pub fn focused(
        model: &EyeModel,
        v: f64,
        _nm: f64,
        _c: FocusCriterion,
        _p: f64,
        source: &str,
        _field: &str,
    ) -> Result<(Self, f64)> {
        Ok((Self::new(model, v, source)?, v))
    }
    pub fn accommodation(&self) -> f64 {
        self.a
    }
    pub fn reference_wavelength(&self) -> f64 {
        555.0
    }
    pub fn paraxial(&self, _nm: f64) -> Paraxial {
        Paraxial {
            power_d: 1000.0 * self.power,
            entrance_pupil_z: 0.0,
            pupil_magnification: 1.0,
            iris_z: 0.0,
            cornea_z: 0.0,
            retina_z: -17.0,
        }
    }
    pub fn retina_point(&self, t: DVec2) -> DVec3 {
        (-17.0 * t).extend(-17.0)
    }
    pub fn ray_out(&self, retina: DVec3, iris: DVec2, _nm: f64) -> Option<PlaneRay> {
        let w0 = (iris - retina.truncate()) / 17.0;
        Some(PlaneRay { position: iris, slope: w0 - iris * self.power })
    }
    pub fn iris_diameter(&self, p: f64) -> f64 {
        p
    }
}
