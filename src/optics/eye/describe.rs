//! `inimtrace info --eye MODEL`: a schematic eye's published data as inimtrace builds it (docs/EYE.md):
//! its citation, accommodation range and the foci it reaches, and at one focus the solved
//! accommodation, the paraxial power, pupils and planes at the reference wavelength, and the
//! longitudinal chromatic aberration (the change of the focused vergence from 450 to 650 nm); at
//! each field angle asked for, the sagittal and tangential foci and the astigmatism
//! ([`super::oblique`]).

use serde::Serialize;

use super::{oblique_foci, EyeModel, FocusCriterion, ObliqueFoci, SchematicEye};
use crate::error::{Error, Result};

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
    /// The foci at each field angle asked for (`--field-deg`), at the reference wavelength, the
    /// image side for an object at `focus_d`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fields: Vec<ObliqueFoci>,
}

/// The largest field angle `info --eye --field-deg` accepts, degrees.
pub const MAX_FIELD_DEG: f64 = 80.0;

/// The description of `model` focused at `focus_d` D with an entrance pupil of `pupil` mm, and
/// its foci at `fields_deg` (degrees off the axis; `field` names them in errors).
pub fn describe(
    model: &EyeModel,
    focus_d: f64,
    pupil: f64,
    criterion: FocusCriterion,
    nm: f64,
    (fields_deg, field): (&[f64], &str),
) -> Result<EyeDescription> {
    let range = model.accommodation_range();
    let at = |a: f64| -> Result<f64> {
        Ok(SchematicEye::new(model, a, "info --eye")?.best_focus_vergence(nm, criterion, pupil).unwrap_or(f64::NAN))
    };
    let focus_range_d = (at(range.0)?, at(range.1)?);
    let (eye, a) = SchematicEye::focused(model, focus_d, nm, criterion, pupil, "info --eye", "--focus-diopters")?;
    let p = eye.paraxial(nm);
    let lca = eye.paraxial(450.0).conjugate_vergence_d - eye.paraxial(650.0).conjugate_vergence_d;
    let fields = fields_deg
        .iter()
        .map(|&deg| {
            if !(deg.is_finite() && deg.abs() <= MAX_FIELD_DEG) {
                return Err(Error::invalid(
                    "info --eye",
                    field,
                    format!("{deg} degrees: a field angle must be within +-{MAX_FIELD_DEG} degrees of the axis"),
                ));
            }
            oblique_foci(&eye, deg, focus_d, nm).ok_or_else(|| {
                Error::invalid(
                    "info --eye",
                    field,
                    format!(
                        "the {} eye's chief ray at {deg} degrees is blocked (it misses a surface or passes \
                         beyond its semi-diameter)",
                        model.name()
                    ),
                )
            })
        })
        .collect::<Result<Vec<_>>>()?;
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
        fields,
    })
}

impl EyeDescription {
    /// The description as text.
    pub fn text(&self) -> String {
        self.paraxial_text() + &self.fields_text()
    }

    /// The off-axis foci as a table (empty without field angles).
    fn fields_text(&self) -> String {
        if self.fields.is_empty() {
            return String::new();
        }
        let mut s = format!(
            "off-axis foci at {} nm (Coddington's equations along the real chief ray):\n\
             \x20 refraction: the object vergence (D from the entrance pupil, + in front of the eye) whose sagittal / \
             tangential focal line lies on the retina;\n\
             \x20 image side: for an object at {:.3} D, how far in front of the retina the focal lines lie along the \
             chief ray (mm); height: where the chief ray meets the retina, mm off the axis\n\
             {:>7}  {:>10}  {:>10}  {:>11}  {:>8}  | {:>11}  {:>11}  | {:>9}\n",
            self.wavelength_nm,
            self.focus_d,
            "field",
            "sagittal",
            "tangential",
            "astigmatism",
            "mean",
            "sagittal",
            "tangential",
            "height"
        );
        for f in &self.fields {
            s += &format!(
                "{:>6.2}°  {:>8.3} D  {:>8.3} D  {:>9.3} D  {:>6.3} D  | {:>8.4} mm  {:>8.4} mm  | {:>6.3} mm\n",
                f.field_deg,
                f.sagittal_d,
                f.tangential_d,
                f.astigmatism_d,
                f.mean_d,
                plain(f.sagittal_before_retina_mm),
                plain(f.tangential_before_retina_mm),
                f.retina_height_mm
            );
        }
        s
    }

    /// The on-axis description as text.
    fn paraxial_text(&self) -> String {
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

/// `x` with rounding's leftovers below the printed 0.1 micrometre shown as 0 (no "-0.0000").
fn plain(x: f64) -> f64 {
    if x.abs() < 5e-5 {
        0.0
    } else {
        x
    }
}
