//! The eye's settings, one schema for every file that states an eye: the `[eye]` table shared by
//! every eye state of an experiment (the paper's thin-lens eye of Sec. 3, or a schematic eye of
//! docs/EYE.md with its wavelengths and the Stiles-Crawford effect), the eye-model settings a
//! resolution study, the single-stage commands and Python share with it, and the eye-state rows:
//! `[[eye_cases]]` (Table 1, Sec. 4.1: Pin, Near, Cen, Far) and `[[optimize.states]]` (OPT's
//! further training states, docs/OPTIMAL.md), both resolved by [`EyeCaseSpec::resolve`] against
//! the `[eye]` table ([`BaseEye`]).

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::optics::eye::pupil::{AutoPupil, Observer, PupilSetting};
use crate::optics::eye::{
    CentreOfRotation, EyeModel, EyeOptics, EyeOpticsSpec, EyePose, FocusCriterion, Gaze, UserEye,
};
use crate::optics::spectrum::Primaries;
use crate::optics::{Aperture, Eye, Retina};

/// `[eye]`: the eye shared by all eye cases.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EyeSpec {
    /// v0, mm.
    pub retina_distance: f64,
    /// Pupil diameter, mm, or `"auto"`: the light-adapted pupil of Watson & Yellott (2012) for
    /// the display's photometry and the scene ([`crate::optics::eye::pupil`],
    /// `render::adapting`).
    pub pupil_diameter: PupilSetting,
    /// n: n x n grid over the pupil's bounding square, kept inside the circle.
    pub pupil_grid: usize,
    /// Retina pixels per side.
    pub retina_resolution: usize,
    /// T: the retina covers tangents -T..T.
    pub retina_half_tangent: f64,
    /// k: k x k stratified samples per retina pixel.
    pub retina_samples: usize,
    /// Pupil centre, mm.
    pub position: [f64; 3],
    /// The eye model ([`EyeModel::parse`]): "thin-lens" (the paper's, the default), "navarro"
    /// (1985), "navarro-1999", "arizona", "le-grand" or "user" (with `[eye.user]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// `[eye.user]`: a user-defined schematic eye (with `model = "user"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub user: Option<UserEye>,
    /// How a schematic eye's focus is judged when its accommodation is solved: "paraxial" or
    /// "min-rms-spot".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focus_criterion: Option<FocusCriterion>,
    /// The reference wavelength of the focus and the retina's map, and the single-wavelength
    /// mode's wavelength, nm (555).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wavelength_nm: Option<f64>,
    /// "primaries" (each channel at its display primary's wavelengths; a schematic eye's
    /// default) or "single" (every channel at `wavelength_nm`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<String>,
    /// The grid estimator's wavelengths per channel (3); the converged one samples them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wavelength_samples: Option<usize>,
    /// The Stiles-Crawford effect's rho, 1/mm^2 (absent: not applied; 0.05 is typical).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiles_crawford_rho: Option<f64>,
    /// The Stiles-Crawford peak in the entrance pupil, mm from its centre ([0, 0]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiles_crawford_peak: Option<[f64; 2]>,
    /// The observer's age for `pupil_diameter = "auto"`, years (default 30).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub age: Option<f64>,
    /// Eyes adapted to the display for `pupil_diameter = "auto"`: 1 or 2 (default 2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapted_eyes: Option<u8>,
    /// The gaze, `[horizontal, vertical]` degrees in Fick's angles ([`Gaze`]; absent: [0, 0],
    /// straight ahead): the whole eye turned about its centre of rotation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gaze_deg: Option<[f64; 2]>,
    /// The centre of rotation, mm behind the cornea on the optical axis (absent:
    /// [`CentreOfRotation::DEFAULT_MM`], 13.3 mm).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub centre_of_rotation_mm: Option<f64>,
}

impl EyeSpec {
    /// The gaze of `gaze_deg` (straight ahead when absent), checked; errors name `source` and
    /// `eye.gaze_deg`.
    pub fn gaze(&self, source: &str) -> Result<Gaze> {
        let g = self.gaze_deg.map(Gaze::from).unwrap_or_default();
        g.validate(source, "eye.gaze_deg")?;
        Ok(g)
    }

    /// The centre of rotation of `centre_of_rotation_mm` (the default when absent), checked;
    /// errors name `source` and `eye.centre_of_rotation_mm`.
    pub fn centre_of_rotation(&self, source: &str) -> Result<CentreOfRotation> {
        let c = self
            .centre_of_rotation_mm
            .map_or_else(CentreOfRotation::default, |mm| CentreOfRotation { behind_cornea_mm: mm });
        c.validate(source, "eye.centre_of_rotation_mm")?;
        Ok(c)
    }

    /// The observer of `pupil_diameter = "auto"` (`None` for a stated diameter); errors name
    /// `source` and the field.
    pub fn observer(&self, source: &str) -> Result<Option<Observer>> {
        observer_of(self.pupil_diameter, self.age, self.adapted_eyes, source, "eye.", "eye.pupil_diameter")
    }

    /// The eye beyond the thin lens these settings ask for, with the pupil `pupil_diameter` mm
    /// (stated, or chosen by `"auto"`); errors name `source` and the field.
    pub fn optics_spec(&self, pupil_diameter: f64, source: &str) -> Result<EyeOpticsSpec> {
        let m = EyeModelSettings {
            model: self.model.clone(),
            user: self.user.clone(),
            focus_criterion: self.focus_criterion,
            wavelength_nm: self.wavelength_nm,
            spectrum: self.spectrum.clone(),
            wavelength_samples: self.wavelength_samples,
            stiles_crawford_rho: self.stiles_crawford_rho,
            stiles_crawford_peak: self.stiles_crawford_peak,
            age: None,
            adapted_eyes: None,
            gaze_deg: None,
            centre_of_rotation_mm: None,
            position: None,
        };
        m.optics_spec(pupil_diameter, source, "eye.")
    }
}

/// The observer of a pupil setting (the field `pupil_key`) with its `age` and `adapted_eyes`
/// (`None` for a stated diameter, which reads neither); errors name `source` and `prefix` + the
/// field.
pub fn observer_of(
    pupil: PupilSetting,
    age: Option<f64>,
    eyes: Option<u8>,
    source: &str,
    prefix: &str,
    pupil_key: &str,
) -> Result<Option<Observer>> {
    if pupil != PupilSetting::Auto {
        for (given, field) in [(age.is_some(), "age"), (eyes.is_some(), "adapted_eyes")] {
            if given {
                return Err(Error::invalid(
                    source,
                    format!("{prefix}{field}"),
                    format!("is only read with `{pupil_key} = \"auto\"` (the light-adapted pupil)"),
                ));
            }
        }
        return Ok(None);
    }
    let d = Observer::default();
    let o = Observer { age: age.unwrap_or(d.age), eyes: eyes.unwrap_or(d.eyes) };
    o.validate(source, prefix)?;
    Ok(Some(o))
}

/// The eye-model settings of an experiment's `[eye]` (there among the eye's other fields) and of
/// a resolution study's `[eye]` table: the model, its focus criterion, the wavelengths and the
/// Stiles-Crawford effect (docs/EYE.md).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EyeModelSettings {
    /// See [`EyeSpec::model`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// See [`EyeSpec::user`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub user: Option<UserEye>,
    /// See [`EyeSpec::focus_criterion`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focus_criterion: Option<FocusCriterion>,
    /// See [`EyeSpec::wavelength_nm`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wavelength_nm: Option<f64>,
    /// See [`EyeSpec::spectrum`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<String>,
    /// See [`EyeSpec::wavelength_samples`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wavelength_samples: Option<usize>,
    /// See [`EyeSpec::stiles_crawford_rho`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiles_crawford_rho: Option<f64>,
    /// See [`EyeSpec::stiles_crawford_peak`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiles_crawford_peak: Option<[f64; 2]>,
    /// See [`EyeSpec::age`] (a study's `pupil_diameter_mm = "auto"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub age: Option<f64>,
    /// See [`EyeSpec::adapted_eyes`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapted_eyes: Option<u8>,
    /// A study's gaze, see [`EyeSpec::gaze_deg`] (the chart goes with the eye,
    /// `resolution::chart`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gaze_deg: Option<[f64; 2]>,
    /// A study's centre of rotation, see [`EyeSpec::centre_of_rotation_mm`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub centre_of_rotation_mm: Option<f64>,
    /// A study's pupil centre straight ahead, mm, see [`EyeSpec::position`] (absent: the origin).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
}

impl EyeModelSettings {
    /// The eye beyond the thin lens these settings ask for, with a pupil of `pupil_diameter`
    /// mm; errors name `source` and the field (`prefix` + its name).
    pub fn optics_spec(&self, pupil_diameter: f64, source: &str, prefix: &str) -> Result<EyeOpticsSpec> {
        let f = |name: &str| format!("{prefix}{name}");
        let model = EyeModel::parse(self.model.as_deref().unwrap_or("thin-lens"), self.user.clone(), source)
            .map_err(|e| prefix_model_field(e, prefix))?;
        if self.user.is_some() && !matches!(model, EyeModel::User(_)) {
            return Err(Error::invalid(source, f("user"), "is only read with `model = \"user\"`"));
        }
        let reference_nm = self.wavelength_nm.unwrap_or(555.0);
        if !(reference_nm.is_finite() && (380.0..=780.0).contains(&reference_nm)) {
            return Err(Error::invalid(
                source,
                f("wavelength_nm"),
                format!("must be a visible wavelength in nm (380 to 780), got {reference_nm}"),
            ));
        }
        let primaries = match self.spectrum.as_deref() {
            None => model != EyeModel::ThinLens,
            Some("primaries") => true,
            Some("single") => false,
            Some(other) => {
                return Err(Error::invalid(
                    source,
                    f("spectrum"),
                    format!("`{other}` is not one of \"primaries\" or \"single\""),
                ))
            }
        };
        let stiles_crawford = match (self.stiles_crawford_rho, self.stiles_crawford_peak) {
            (None, None) => None,
            (None, Some(_)) => {
                return Err(Error::invalid(
                    source,
                    f("stiles_crawford_peak"),
                    "needs eye.stiles_crawford_rho (0.05 /mm^2 is typical)",
                ))
            }
            (Some(rho), peak) => {
                if !(rho.is_finite() && (0.0..=1.0).contains(&rho)) {
                    return Err(Error::invalid(
                        source,
                        f("stiles_crawford_rho"),
                        format!("must be between 0 and 1 /mm^2 (0.05 is typical), got {rho}"),
                    ));
                }
                let peak = DVec2::from_array(peak.unwrap_or([0.0; 2]));
                if !peak.is_finite() || peak.length() > 0.5 * pupil_diameter.max(0.0) + 1e-12 {
                    return Err(Error::invalid(
                        source,
                        f("stiles_crawford_peak"),
                        format!("must lie inside the pupil (radius {} mm), got {peak}", 0.5 * pupil_diameter),
                    ));
                }
                Some((rho, peak))
            }
        };
        Ok(EyeOpticsSpec {
            model,
            criterion: self.focus_criterion.unwrap_or(FocusCriterion::Paraxial),
            reference_nm,
            primaries,
            wavelength_samples: self.wavelength_samples.unwrap_or(3),
            stiles_crawford,
            diffraction: Default::default(),
        })
    }
}

impl EyeModelSettings {
    /// The optics these settings give `eye` (its aperture and focus), with the display's
    /// `primaries` (its `[primaries]`, or the default's): what the single-stage commands'
    /// `--eye-model` flags and Python's `Eye(model=...)` build. `None` for the thin lens without
    /// Stiles-Crawford.
    /// `focus_field` names the focus in errors (an unreachable focus); `half_tangent` is the
    /// retina's half field per axis (the fitted ray map covers it).
    pub fn optics_for(
        &self,
        eye: &Eye,
        half_tangent: f64,
        primaries: &crate::optics::spectrum::Primaries,
        source: &str,
        focus_field: &str,
    ) -> Result<Option<std::sync::Arc<EyeOptics>>> {
        let pupil = match eye.aperture {
            Aperture::Pinhole => 0.0,
            Aperture::ThinLens { pupil_diameter, .. } => pupil_diameter,
        };
        let spec = self.optics_spec(pupil, source, "eye.")?;
        EyeOptics::build(
            &spec,
            &eye.aperture,
            eye.retina_distance,
            primaries,
            half_tangent * std::f64::consts::SQRT_2,
            source,
            focus_field,
        )
    }
}

impl EyeModelSettings {
    /// A resolution study's pupil (`pupil_diameter_mm`), mm, and how `"auto"` chose it: the light-
    /// adapted pupil of the chart's grey `grey` (`target.mean`) at `display`'s photometry over its
    /// field (the grey's luminance at the display's photometry over its field of view,
    /// [`crate::optics::Display::field_area_deg2`]), for the observer of these settings' `age`
    /// and `adapted_eyes`. Errors name `source` and the field.
    pub fn study_pupil(
        &self,
        setting: PupilSetting,
        grey: f64,
        display: &crate::optics::Display,
        source: &str,
    ) -> Result<(f64, Option<AutoPupil>)> {
        let key = "pupil_diameter_mm";
        let observer = observer_of(setting, self.age, self.adapted_eyes, source, "eye.", key)?;
        let (l, a) = (display.photometry().absolute(grey), display.field_area_deg2());
        let auto = observer.map(|o| AutoPupil::new(o, l, a));
        let pupil = auto.map_or(setting.stated().unwrap_or(f64::NAN), |p| p.diameter_mm);
        crate::optics::limits::PUPIL_DIAMETER.check(source, key, pupil)?;
        Ok((pupil, auto))
    }
}

/// Refuses `[eye]` settings the run would not use, as an unknown field is refused: a focus
/// criterion for the thin lens (it focuses exactly), a wavelength or the primaries' spectrum for
/// a thin lens without diffraction (it is achromatic), wavelength samples where no wavelengths
/// are sampled on a grid (the converged estimator samples them; one wavelength has none).
/// `optics` is the resolved optics (`with_diffraction` applied); `converged`, the estimator.
pub fn check_applicable(e: &EyeSpec, optics: &EyeOpticsSpec, converged: bool, source: &str) -> Result<()> {
    let bad = |f: &str, why: String| Err(Error::invalid(source, format!("eye.{f}"), why));
    let thin = optics.model == EyeModel::ThinLens;
    let diffraction = optics.diffraction.is_on();
    if thin && e.focus_criterion.is_some() {
        return bad(
            "focus_criterion",
            "applies to a schematic eye's accommodation (eye.model); the thin-lens eye focuses exactly".into(),
        );
    }
    if thin && !diffraction {
        let achromatic = "the thin-lens eye is achromatic: it changes nothing unless eye.model is a schematic eye or \
                          optics.diffraction is on";
        if let Some(w) = e.wavelength_nm {
            return bad("wavelength_nm", format!("{w} nm: {achromatic}"));
        }
        if e.spectrum.as_deref() == Some("primaries") {
            return bad("spectrum", format!("\"primaries\": {achromatic}"));
        }
    }
    if let Some(k) = e.wavelength_samples {
        let sampled = optics.primaries && (!thin || diffraction);
        if converged {
            return bad(
                "wavelength_samples",
                format!("{k} is a setting of the grid estimator; the converged estimator samples the wavelengths"),
            );
        }
        if !sampled {
            return bad(
                "wavelength_samples",
                format!("{k}: every channel is traced at one wavelength here (eye.spectrum, eye.model)"),
            );
        }
    }
    Ok(())
}

/// The grid estimator's pupil grid against an off-centre Stiles-Crawford peak: its fixed
/// points must average the effect's weights to 1 (within 2%, its quadrature of the weighted
/// mean), else a peak narrower than the grid's spacing would brighten or darken every image.
/// Refused naming `eye.pupil_grid`; `case` names the eye case.
pub fn check_grid_stiles_crawford(eye: &Eye, case: &str, source: &str) -> Result<()> {
    let Some(sc) = eye.optics.as_ref().and_then(|o| o.stiles_crawford) else { return Ok(()) };
    let Aperture::ThinLens { pupil_diameter, .. } = eye.aperture else { return Ok(()) };
    let points = eye.pupil_samples();
    let radius = 0.5 * pupil_diameter;
    let mean = points.iter().map(|p| sc.weight(sc.warp(*p, radius))).sum::<f64>() / points.len().max(1) as f64;
    if (mean - 1.0).abs() <= 0.02 {
        return Ok(());
    }
    Err(Error::invalid(
        source,
        "eye.pupil_grid",
        format!(
            "the {n} x {n} pupil grid ({} points, {:.3} mm apart) averages the Stiles-Crawford weights of eye case \
             `{case}` (rho {} /mm^2, peak at ({}, {}) mm) to {mean:.4} instead of 1: the peak is too narrow for it; \
             raise eye.pupil_grid or use the converged estimator",
            points.len(),
            pupil_diameter / eye.pupil_grid.max(1) as f64,
            sc.rho,
            sc.peak.x,
            sc.peak.y,
            n = eye.pupil_grid
        ),
    ))
}

/// An error of the model's own fields (`eye.model`, `eye.user...`) renamed under `prefix`.
fn prefix_model_field(e: Error, prefix: &str) -> Error {
    match e {
        Error::Invalid { source_name, field, message } if prefix != "eye." => Error::Invalid {
            source_name,
            field: format!("{prefix}{}", field.strip_prefix("eye.").unwrap_or(&field)),
            message,
        },
        other => other,
    }
}

impl Default for EyeSpec {
    fn default() -> Self {
        Self {
            retina_distance: 17.0,
            pupil_diameter: PupilSetting::Mm(5.0),
            pupil_grid: 8,
            retina_resolution: 512,
            retina_half_tangent: 0.3,
            retina_samples: 1,
            position: [0.0; 3],
            model: None,
            user: None,
            focus_criterion: None,
            wavelength_nm: None,
            spectrum: None,
            wavelength_samples: None,
            stiles_crawford_rho: None,
            stiles_crawford_peak: None,
            age: None,
            adapted_eyes: None,
            gaze_deg: None,
            centre_of_rotation_mm: None,
        }
    }
}

/// One eye state: a row of `[[eye_cases]]` (Table 1) or of `[[optimize.states]]` (a training state
/// of OPT beyond the eye cases). Both tables take the same fields, resolved by one function
/// ([`EyeCaseSpec::resolve`]); `weight` is read only in `[[optimize.states]]`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EyeCaseSpec {
    /// Used in file names (`gt_<name>.exr`) and as the table's row label.
    pub name: String,
    /// A pinhole eye (the paper's "Pin"): one chief ray per retina sample, no focus.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub pinhole: bool,
    /// Focus distance from the pupil, mm (give this or `focus_diopters` unless `pinhole`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_mm: Option<f64>,
    /// Focus as vergence, dioptres (0 = infinity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_diopters: Option<f64>,
    /// This state's pupil centre, mm (default: `eye.position`): an eye displaced in the eye box.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    /// This state's pupil diameter, mm (default: `eye.pupil_diameter`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pupil_diameter: Option<f64>,
    /// OPT's weight w_s of this state (1); only in `[[optimize.states]]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<f64>,
    /// This state's gaze, `[horizontal, vertical]` degrees (default: `eye.gaze_deg`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gaze_deg: Option<[f64; 2]>,
}

/// The eye the `[eye]` table gives, before a state's own focus, pupil and position: what
/// [`EyeCaseSpec::resolve`] builds every eye state from.
#[derive(Clone, Debug)]
pub struct BaseEye {
    /// v0, mm.
    pub retina_distance: f64,
    /// Pupil diameter, mm.
    pub pupil_diameter: f64,
    /// Pupil grid n.
    pub pupil_grid: usize,
    /// Pupil centre.
    pub position: DVec3,
    /// The retina of Table 1 (its half field is what a schematic eye's ray map covers).
    pub retina: Retina,
    /// The eye beyond the thin lens (model, wavelengths, Stiles-Crawford, diffraction).
    pub optics: EyeOpticsSpec,
    /// The display's primaries (each channel's wavelengths).
    pub primaries: Primaries,
    /// The gaze of `eye.gaze_deg`.
    pub gaze: Gaze,
    /// The centre of rotation.
    pub centre_of_rotation: CentreOfRotation,
}

impl EyeCaseSpec {
    /// The eye of this state on `base`: its aperture (exactly one of `pinhole`, `focus_mm`,
    /// `focus_diopters`, with its own pupil or the base's), its position (or the base's), checked,
    /// and its optics beyond the thin lens solved for its focus. Errors name `source` and `field`
    /// (the row: `eye_cases[2]`, `optimize.states[0]`).
    pub fn resolve(&self, base: &BaseEye, source: &str, field: &str) -> Result<Eye> {
        let pupil = self.pupil_diameter.unwrap_or(base.pupil_diameter);
        let aperture = Aperture::stated(self.pinhole, self.focus_mm, self.focus_diopters, pupil).ok_or_else(|| {
            Error::invalid(source, field, "give exactly one of `pinhole = true`, `focus_mm` or `focus_diopters`")
        })?;
        let position = match self.position {
            Some(p) if !DVec3::from_array(p).is_finite() => {
                return Err(Error::invalid(source, format!("{field}.position"), "must be finite"))
            }
            Some(p) => DVec3::from_array(p),
            None => base.position,
        };
        let mut eye = Eye {
            retina_distance: base.retina_distance,
            aperture,
            pupil_grid: base.pupil_grid,
            position,
            optics: None,
            pose: None,
        };
        eye.validate(source).map_err(|err| prefix_field(err, &format!("{field} / eye.")))?;
        let focus_field =
            if self.focus_mm.is_some() { format!("{field}.focus_mm") } else { format!("{field}.focus_diopters") };
        eye.optics = EyeOptics::build(
            &base.optics,
            &aperture,
            base.retina_distance,
            &base.primaries,
            base.retina.half_tangent * std::f64::consts::SQRT_2,
            source,
            &focus_field,
        )?;
        let gaze = match self.gaze_deg {
            Some(g) => {
                let g = Gaze::from(g);
                g.validate(source, &format!("{field}.gaze_deg"))?;
                g
            }
            None => base.gaze,
        };
        eye.pose = pose_of(&base.optics.model, gaze, base.centre_of_rotation, position, source)?;
        Ok(eye)
    }
}

/// The pose of an eye of `model` whose pupil centre is at `position` straight ahead, turned to
/// `gaze` about `centre` (`None` straight ahead). The centre lies `centre` behind the cornea of
/// the model relaxed (its entrance pupil's depth at 0 D and its reference wavelength; the thin
/// lens takes Navarro's, [`CentreOfRotation::pupil_depth`]), whatever a state's accommodation,
/// so the states of one eye turn about one point. Errors name `source`.
pub fn pose_of(
    model: &EyeModel,
    gaze: Gaze,
    centre: CentreOfRotation,
    position: DVec3,
    source: &str,
) -> Result<Option<EyePose>> {
    if gaze.is_ahead() {
        return Ok(None);
    }
    let paraxial = match model {
        EyeModel::ThinLens => None,
        m => {
            let relaxed = super::SchematicEye::new(m, 0.0, source)?;
            Some(relaxed.paraxial(relaxed.reference_wavelength()))
        }
    };
    let behind = centre.behind_pupil_mm(CentreOfRotation::pupil_depth(paraxial.as_ref()));
    Ok(Some(EyePose::new(gaze, position, behind)))
}

/// `err` with its field under `prefix`.
pub(crate) fn prefix_field(err: Error, prefix: &str) -> Error {
    match err {
        Error::Invalid { source_name, field, message } => {
            Error::Invalid { source_name, field: format!("{prefix}{field}"), message }
        }
        Error::Lattice { source_name, field, message } => {
            Error::Lattice { source_name, field: format!("{prefix}{field}"), message }
        }
        other => other,
    }
}
