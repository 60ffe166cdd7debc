//! `inimtrace info --eye MODEL`: a schematic eye's published data as inimtrace builds it (docs/EYE.md):
//! its citation, accommodation range and the foci it reaches, and at one focus the solved
//! accommodation, the paraxial power, pupils and planes at the reference wavelength, and the
//! longitudinal chromatic aberration (the change of the focused vergence from 450 to 650 nm).

use serde::Serialize;

use super::{EyeModel, FocusCriterion, SchematicEye};
use crate::error::Result;

/// What `info --eye` prints.
#[derive(Clone, Debug, Serialize)]
pub struct EyeDescription {
    /// The model's name.
    pub model: String,
    /// Where its parameters come from.
    pub citation: String,
    /// The model's accommodation parameter range, D.
    pub accommodation_range_d: (f64, f64),
    /// The object vergences in best focus at the ends of that range, D.
    pub focus_range_d: (f64, f64),
    /// The focus asked for, D.
    pub focus_d: f64,
    /// The accommodation solved for it, D.
    pub accommodation_d: f64,
    /// The criterion.
    pub focus_criterion: String,
    /// The reference wavelength, nm.
    pub wavelength_nm: f64,
    /// Total power at the reference wavelength, D.
    pub power_d: f64,
    /// The entrance pupil's diameter (`pupil_diameter`), mm.
    pub entrance_pupil_mm: f64,
    /// The iris diameter that gives it, mm.
    pub iris_mm: f64,
    /// The entrance pupil behind the cornea's front vertex, mm.
    pub entrance_pupil_depth_mm: f64,
    /// The iris behind the cornea's front vertex, mm.
    pub iris_depth_mm: f64,
    /// The retina's vertex behind the cornea's front vertex (axial length), mm.
    pub axial_length_mm: f64,
    /// Object vergence in best focus at 450 nm minus that at 650 nm, at this accommodation
    /// (paraxial), D.
    pub chromatic_difference_450_650_d: f64,
}

/// The description of `model` focused at `focus_d` D with an entrance pupil of `pupil` mm.
pub fn describe(
    model: &EyeModel,
    focus_d: f64,
    pupil: f64,
    criterion: FocusCriterion,
    nm: f64,
) -> Result<EyeDescription> {
    let range = model.accommodation_range();
    let at = |a: f64| -> Result<f64> {
        Ok(SchematicEye::new(model, a, "info --eye")?.best_focus_vergence(nm, criterion, pupil).unwrap_or(f64::NAN))
    };
    let focus_range_d = (at(range.0)?, at(range.1)?);
    let (eye, a) = SchematicEye::focused(model, focus_d, nm, criterion, pupil, "info --eye", "--focus-diopters")?;
    let p = eye.paraxial(nm);
    let lca = eye.paraxial(450.0).conjugate_vergence_d - eye.paraxial(650.0).conjugate_vergence_d;
    Ok(EyeDescription {
        model: model.name().to_string(),
        citation: model.citation().to_string(),
        accommodation_range_d: range,
        focus_range_d,
        focus_d,
        accommodation_d: a,
        focus_criterion: super::rays::criterion_name(criterion).to_string(),
        wavelength_nm: nm,
        power_d: p.power_d,
        entrance_pupil_mm: pupil,
        iris_mm: eye.iris_diameter(pupil),
        entrance_pupil_depth_mm: p.cornea_z - p.entrance_pupil_z,
        iris_depth_mm: p.cornea_z - p.iris_z,
        axial_length_mm: p.cornea_z - p.retina_z,
        chromatic_difference_450_650_d: lca,
    })
}

impl EyeDescription {
    /// The description as text.
    pub fn text(&self) -> String {
        format!(
            "eye: {} ({})\n\
             accommodation {:.2}..{:.2} D focuses objects at {:.3}..{:.3} D ({} focus, {} nm)\n\
             focused at {:.3} D: accommodation {:.4} D, power {:.3} D\n\
             entrance pupil {:.3} mm (pupil_diameter), iris {:.3} mm; entrance pupil {:.3} mm and iris {:.3} mm behind the cornea, axial length {:.3} mm\n\
             longitudinal chromatic aberration 450-650 nm: {:.3} D\n",
            self.model,
            self.citation,
            self.accommodation_range_d.0,
            self.accommodation_range_d.1,
            self.focus_range_d.0,
            self.focus_range_d.1,
            self.focus_criterion,
            self.wavelength_nm,
            self.focus_d,
            self.accommodation_d,
            self.power_d,
            self.entrance_pupil_mm,
            self.iris_mm,
            self.entrance_pupil_depth_mm,
            self.iris_depth_mm,
            self.axial_length_mm,
            self.chromatic_difference_450_650_d,
        )
    }
}
