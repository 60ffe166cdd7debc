//! Experiments: the paper's assessment (Sec. 4, Table 1, Fig. 3) as data. This file holds the
//! experiment file's spec types and their resolution into an [`Experiment`]; the eye's settings
//! and the pipeline that runs one live beside it, one concept per file: `optics/eye/settings.rs` (the
//! `[eye]` and `[[eye_cases]]` settings), `stages.rs` (render the display image of every method,
//! simulate what each eye case perceives, render the ground truth, score with PSNR and SSIM),
//! `assess.rs` (the run and its image outputs), `metadata.rs` (the typed EXR header of every
//! image) and `report.rs` (Table 1 and the CSV/JSON reports). Everything public is re-exported
//! here.

mod assess;
pub mod converged;
pub(crate) mod converged_report;
pub mod metadata;
mod perceptual;
mod report;
pub mod simulated;
mod stages;
mod tracking;

use crate::optics::eye::settings::prefix_field;
pub use crate::optics::eye::settings::{BaseEye, EyeCaseSpec, EyeModelSettings, EyeSpec};
pub use assess::{
    assess, assess_images, check, check_text, estimate, prepare_output_dir, Assessment, RunOptions, Z_CHANNEL_NOTE,
};
pub use report::{sampling_cost_warnings, table_markdown, AssessReport, Score, StageTime};
pub use stages::{
    ground_truth_image, pack_display_images, perceived_images, render_display_images, render_display_stack,
    render_optimized, table1, table1_each, table1_scores, CaseResult, DisplayImages, Table1,
};
pub use tracking::tracked_pupil;

use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::io::text::{base_dir, read_text, toml_error};
use crate::io::{load_display, load_scene};
use crate::measure::spec::MeasurementSpec;
use crate::metrics::SsimConstants;
use crate::optics::diffraction::OpticsSpec;
use crate::optics::eye::pupil::{AutoPupil, PupilSetting};
use crate::optics::{Aperture, Display, Eye, Focus, Retina};
use crate::render::{DisplayRenderSettings, Method};
use crate::scene::Scene;

fn builtin() -> String {
    "builtin:paper".into()
}
fn default_methods() -> Vec<String> {
    vec!["LC".into(), "PC".into(), "LA".into()]
}

/// `[display_render]`: how display images are rendered.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DisplayRenderSpec {
    /// LensletAverage grid k (k x k samples over the lenslet's pitch cell).
    pub la_grid: usize,
    /// k x k stratified samples per display pixel.
    pub samples_per_pixel: usize,
    /// z of the plane camera rays start on.
    pub reference_plane_z: f64,
    /// Pupil centre PupilCenter aims at (default: the simulated eye's position).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eye_position: Option<[f64; 3]>,
    /// What PupilCenter knows of a turned eye's pupil: "ideal" (the default) or "none"
    /// (`experiment/tracking.rs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pupil_tracking: Option<String>,
    /// The eye tracker's error, mm, with `pupil_tracking = "ideal"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tracking_error_mm: Option<[f64; 3]>,
}

impl Default for DisplayRenderSpec {
    fn default() -> Self {
        Self {
            la_grid: 5,
            samples_per_pixel: 1,
            reference_plane_z: 0.0,
            eye_position: None,
            pupil_tracking: None,
            tracking_error_mm: None,
        }
    }
}

/// An experiment file.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExperimentSpec {
    /// Names the experiment and its default output folder `out/<name>`.
    pub name: String,
    /// One line for reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// `builtin:paper` or a scene TOML path (relative to this file).
    #[serde(default = "builtin")]
    pub scene: String,
    /// `builtin:paper` or a display TOML / OpenCV YAML path (relative to this file).
    #[serde(default = "builtin")]
    pub display: String,
    /// "LC", "PC", "LA" (grid from `display_render.la_grid`), or `LA<k>`.
    #[serde(default = "default_methods")]
    pub methods: Vec<String>,
    /// "wang2004" (default) or "framework-8bit".
    #[serde(default)]
    pub ssim: SsimConstants,
    /// `[measurement]`: the estimator, its targets and budget (none: the grid estimator).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurement: Option<MeasurementSpec>,
    /// `[display_render]`: how display images are rendered.
    #[serde(default)]
    pub display_render: DisplayRenderSpec,
    /// `[optics]`: diffraction at the apertures (absent: rays only, the paper's model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optics: Option<OpticsSpec>,
    /// `[eye]`: the eye shared by all eye cases.
    #[serde(default)]
    pub eye: EyeSpec,
    /// `[[eye_cases]]`: the rows of Table 1, each a focus of the eye.
    pub eye_cases: Vec<EyeCaseSpec>,
    /// `[optimize]`: how the optimised method OPT is trained (read when `methods` lists OPT).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimize: Option<crate::optimize::OptimizeSpec>,
}

impl ExperimentSpec {
    fn paper_cases() -> Vec<EyeCaseSpec> {
        let case = |name: &str, focus: Option<f64>| EyeCaseSpec {
            name: name.into(),
            pinhole: focus.is_none(),
            focus_mm: focus,
            focus_diopters: None,
            position: None,
            pupil_diameter: None,
            weight: None,
            gaze_deg: None,
        };
        vec![case("Pin", None), case("Near", Some(300.0)), case("Cen", Some(400.0)), case("Far", Some(600.0))]
    }

    /// The paper's experiment as its text states it (Sec. 4.1).
    pub fn paper() -> Self {
        Self {
            name: "paper".into(),
            description: Some("The paper's experiment as its text states it (Sec. 4.1): 5 mm pupil, 8 x 8 pupil grid (52 samples), LA 5 x 5, one sample per pixel.".into()),
            scene: builtin(),
            display: builtin(),
            methods: default_methods(),
            ssim: SsimConstants::Wang2004,
            measurement: Some(MeasurementSpec::grid()),
            display_render: DisplayRenderSpec::default(),
            optics: None,
            eye: EyeSpec::default(),
            eye_cases: Self::paper_cases(),
            optimize: None,
        }
    }

    /// What the paper's published code actually ran: `ApertureRadius` kept its 1 mm default (a
    /// 2 mm pupil), a 5 x 5 pupil grid (21 samples in the circle), one sample per pixel, and
    /// SSIM with 8-bit constants on [0, 1] data.
    pub fn framework_2020() -> Self {
        Self {
            name: "framework-2020".into(),
            description: Some("What the published framework (2020) actually ran: 2 mm pupil (ApertureRadius default 1 mm), 5 x 5 pupil grid (21 samples), one sample per pixel, SSIM with 8-bit constants.".into()),
            ssim: SsimConstants::Framework8Bit,
            eye: EyeSpec { pupil_diameter: PupilSetting::Mm(2.0), pupil_grid: 5, ..EyeSpec::default() },
            ..Self::paper()
        }
    }

    /// The paper's experiment measured converged (`experiments/paper-converged.toml`): the
    /// paper's scene, display, methods and eyes; each retina pixel averaged over its square and
    /// the pupil disk, every score to +-0.02 dB and +-0.002 (95%).
    pub fn paper_converged() -> Self {
        Self {
            name: "paper-converged".into(),
            description: Some("The paper's experiment (Sec. 4.1: 5 mm pupil, LA 5 x 5, one sample per display pixel) measured converged: each retina pixel is the average over its square and the continuous pupil disk, every PSNR within +-0.02 dB and SSIM within +-0.002 at 95%.".into()),
            measurement: Some(MeasurementSpec::default()),
            ..Self::paper()
        }
    }

    /// The spec as an experiment file (what `info --print paper-experiment` prints).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

/// An eye case, resolved.
#[derive(Clone, Debug)]
pub struct EyeCase {
    /// Table 1's row label and the file-name part (`gt_<name>.exr`).
    pub name: String,
    /// The eye: the shared `[eye]` with this case's focus.
    pub eye: Eye,
}

/// A resolved experiment: everything needed to run it.
#[derive(Clone, Debug)]
pub struct Experiment {
    /// The experiment's name.
    pub name: String,
    /// The file it came from (or "built-in ..."), for errors and reports.
    pub source: String,
    /// The scene the display shows.
    pub scene: Scene,
    /// The display.
    pub display: Display,
    /// The rendering methods compared, in the table's column order.
    pub methods: Vec<Method>,
    /// How display images are rendered.
    pub render: DisplayRenderSettings,
    /// The retina's sampling.
    pub retina: Retina,
    /// The eye cases, in the table's row order.
    pub cases: Vec<EyeCase>,
    /// SSIM constants.
    pub ssim: SsimConstants,
    /// How Table 1 is measured (`[measurement]`; the grid estimator when absent).
    pub measurement: MeasurementSpec,
    /// The scores reported beyond PSNR and SSIM (`[measurement] scores`).
    pub extra_scores: crate::perception::ExtraScores,
    /// The display's luminance as the perceptual scores see it.
    pub luminance: crate::perception::DisplayLuminance,
    /// How OPT is trained (`[optimize]`), when `methods` lists it.
    pub optimize: Option<crate::optimize::Optimization>,
    /// How `eye.pupil_diameter = "auto"` chose the pupil (absent for a stated diameter).
    pub auto_pupil: Option<AutoPupil>,
    /// The spec it was resolved from (what reports echo).
    pub spec: ExperimentSpec,
    /// What the run read and how it was asked to run (filled in by the loaders of
    /// [`crate::settings`]; empty for an experiment built in code).
    pub provenance: crate::provenance::Provenance,
}

impl Experiment {
    /// Resolves a spec; `source` names its file (for errors), `base` resolves relative paths.
    pub fn from_spec(spec: ExperimentSpec, source: &str, base: &Path) -> Result<Self> {
        check_name(&spec, source)?;
        // Name the experiment file and its field as well as the file that failed.
        let display =
            load_display(&spec.display, base).map_err(|e| Error::load(source, "display", &spec.display, e))?;
        let scene = load_scene(&spec.scene, base).map_err(|e| Error::load(source, "scene", &spec.scene, e))?;
        Self::from_parts(spec, scene, display, source)
    }

    /// Resolves a spec whose scene and display are already built (`spec.scene` and
    /// `spec.display` only label them): the same checks as [`Experiment::from_spec`].
    pub fn from_parts(spec: ExperimentSpec, scene: Scene, display: Display, source: &str) -> Result<Self> {
        check_name(&spec, source)?;
        let methods = parse_methods(&spec, source)?;
        let dr = &spec.display_render;
        let e = &spec.eye;
        let (position, mut render) = render_settings(&spec, &display, source)?;
        let retina = Retina {
            resolution: e.retina_resolution,
            half_tangent: e.retina_half_tangent,
            samples_per_pixel: e.retina_samples,
        };
        retina.validate(source).map_err(|err| prefix_field(err, "eye."))?;
        if retina.resolution < crate::metrics::SSIM_WINDOW {
            // Table 1's SSIM needs its window inside the image: refused here, before any image.
            return Err(Error::invalid(
                source,
                "eye.retina_resolution",
                format!(
                    "must be at least {0} pixels for SSIM's {0} x {0} window, got {1}",
                    crate::metrics::SSIM_WINDOW,
                    retina.resolution
                ),
            ));
        }
        if spec.eye_cases.is_empty() {
            return Err(Error::invalid(source, "eye_cases", "list at least one eye case"));
        }
        let diffraction = spec.optics.as_ref().map(|o| o.diffraction).unwrap_or_default();
        let (pupil_diameter, auto_pupil) = resolve_pupil(e, &scene, &display, position, source)?;
        let base = BaseEye {
            retina_distance: e.retina_distance,
            pupil_diameter,
            pupil_grid: e.pupil_grid,
            position,
            retina,
            optics: e.optics_spec(pupil_diameter, source)?.with_diffraction(diffraction, e.spectrum.is_some()),
            primaries: display.primaries.clone().unwrap_or_default(),
            gaze: e.gaze(source)?,
            centre_of_rotation: e.centre_of_rotation(source)?,
        };
        let cases = resolve_cases(&spec, &base, &display, source)?;
        if let Some(pupil) = tracking::pc_pupil(dr, &base, source)? {
            crate::optics::transfer::check_eye_in_front(&display, pupil.z, source, "display_render.pupil_tracking")?;
            render.eye_position = pupil;
        }
        if methods.contains(&Method::PupilCenter) {
            crate::optics::transfer::check_pupil_center(&display, render.eye_position).map_err(|e| {
                let i = methods.iter().position(|m| *m == Method::PupilCenter).unwrap_or(0);
                let eye = if dr.eye_position.is_some() { "display_render.eye_position" } else { "eye.position" };
                let e = match e {
                    Error::Singular(m) => Error::Singular(format!("{m} (display `{}`)", spec.display)),
                    e => e,
                };
                Error::in_field(source, format!("methods[{i}] (PupilCenter) at {eye}"), e)
            })?;
        }
        let optimize = match (methods.contains(&Method::Optimized), &spec.optimize) {
            (false, None) => None,
            (false, Some(_)) => {
                return Err(Error::invalid(source, "optimize", "is only read when `methods` lists OPT"));
            }
            (true, o) => {
                let named: Vec<(String, Eye)> = cases.iter().map(|c| (c.name.clone(), c.eye.clone())).collect();
                // The explicit [[optimize.states]] are eye states of the experiment's eye, as its
                // cases are (a schematic eye, the primaries' wavelengths, diffraction).
                let spec = o.clone().unwrap_or_default();
                let opt = spec.resolve(&named, &base, dr.la_grid, source)?;
                check_state_gazes(&spec, &opt, &display, source)?;
                Some(opt)
            }
        };
        let measurement = spec.measurement.clone().unwrap_or_else(MeasurementSpec::grid);
        measurement.validate(source)?;
        let extra_scores = measurement.extra_scores(source)?;
        let luminance = crate::perception::DisplayLuminance::from(&display.photometry());
        check_measurement(&spec, &base, &measurement, &cases, source)?;
        Ok(Self {
            name: spec.name.clone(),
            source: source.into(),
            scene,
            display,
            methods,
            render,
            retina,
            cases,
            ssim: spec.ssim,
            measurement,
            extra_scores,
            luminance,
            optimize,
            auto_pupil,
            spec,
            provenance: Default::default(),
        })
    }

    /// The entrance pupil's diameter, mm: `[eye] pupil_diameter`, or the one `"auto"` chose.
    pub fn pupil_diameter(&self) -> f64 {
        match &self.auto_pupil {
            Some(p) => p.diameter_mm,
            None => self.spec.eye.pupil_diameter.stated().unwrap_or(f64::NAN),
        }
    }

    /// Values that are valid but implausible for a near-eye display and a human eye (a unit
    /// mistake, most likely), each a line naming the file, the field and the likely unit
    /// ([`crate::optics::plausibility`]). Never an error.
    pub fn plausibility_warnings(&self) -> Vec<String> {
        use crate::optics::plausibility::{check, display_warnings, focus_warning, PUPIL_DIAMETER};
        let mut w = display_warnings(&self.display, &self.spec.display);
        let mut pupil_checked = false;
        for (i, case) in self.cases.iter().enumerate() {
            if let Aperture::ThinLens { pupil_diameter, focus } = case.eye.aperture {
                if !pupil_checked {
                    w.extend(check(&self.source, "eye.pupil_diameter", pupil_diameter, PUPIL_DIAMETER));
                    pupil_checked = true;
                }
                w.extend(match focus {
                    Focus::Millimetres(z) => focus_warning(&self.source, &format!("eye_cases[{i}].focus_mm"), z, false),
                    Focus::Diopters(d) => {
                        focus_warning(&self.source, &format!("eye_cases[{i}].focus_diopters"), 1000.0 / d, true)
                    }
                });
            }
        }
        w.extend(self.cases.iter().filter_map(|c| exact_aim_note(c, &self.cases)));
        w
    }

    /// Loads an experiment file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        let spec: ExperimentSpec = toml::from_str(&text).map_err(|e| toml_error(path, &text, &e))?;
        Self::from_spec(spec, &path.display().to_string(), &base_dir(path))
    }

    /// The paper's experiment, built in.
    pub fn paper() -> Self {
        Self::from_spec(ExperimentSpec::paper(), "built-in paper experiment", Path::new("."))
            .expect("built-in experiment is valid")
    }

    /// The paper's experiment measured converged, built in (what `inimtrace assess` runs).
    pub fn paper_converged() -> Self {
        Self::from_spec(ExperimentSpec::paper_converged(), "built-in paper-converged experiment", Path::new("."))
            .expect("built-in experiment is valid")
    }
}

/// The pupil diameter of `[eye]` (mm): stated, or for `"auto"` the light-adapted pupil of the
/// display's field over `scene` seen from `position`, with how it was chosen.
fn resolve_pupil(
    e: &EyeSpec,
    scene: &Scene,
    display: &Display,
    position: DVec3,
    source: &str,
) -> Result<(f64, Option<AutoPupil>)> {
    let Some(observer) = e.observer(source)? else {
        return Ok((e.pupil_diameter.stated().unwrap_or(f64::NAN), None));
    };
    let p = crate::render::adapting::auto_pupil(scene, display, position, observer)?;
    Ok((p.diameter_mm, Some(p)))
}

/// The name becomes the default output folder `out/<name>`: letters, digits, -, _ and . only,
/// so it can never point outside `out/`.
fn check_name(spec: &ExperimentSpec, source: &str) -> Result<()> {
    if !crate::io::output::is_plain_name(&spec.name) || spec.name.contains("..") {
        return Err(Error::invalid(
            source,
            "name",
            format!(
                "`{}` must be non-empty, start with a letter or digit and use only letters, digits, -, _ and . \
                 (it names the output folder)",
                spec.name
            ),
        ));
    }
    Ok(())
}

/// Why eye case `case` will cost several times the others to sample: its schematic eye's fitted
/// ray map fails its checks at the case's accommodation (the optics cut the map's domain, or it
/// misses its tolerances), so every ray is aimed exactly, while another case's eye has the map.
pub fn exact_aim_note(case: &EyeCase, cases: &[EyeCase]) -> Option<String> {
    let optics = case.eye.optics.as_ref()?;
    optics.schematic()?;
    let mapped = |c: &EyeCase| c.eye.optics.as_ref().is_some_and(|o| o.has_ray_map());
    if mapped(case) || !cases.iter().any(mapped) {
        return None;
    }
    Some(format!(
        "eye case `{}`: the {} eye's fitted ray map fails its checks at this accommodation (A = {:.3} D: its optics \
         cut the map's domain or it misses its tolerances), so each of its rays is aimed exactly, an iterative solve: \
         expect its sampling to cost about ten times the other cases'",
        case.name,
        optics.model.name(),
        optics.accommodation.unwrap_or(f64::NAN)
    ))
}

/// The experiment's methods (`methods`, LA at `display_render.la_grid`), each named once, and the
/// display-render settings' bounds.
fn parse_methods(spec: &ExperimentSpec, source: &str) -> Result<Vec<Method>> {
    let dr = &spec.display_render;
    let mut methods = Vec::new();
    let mut method_names = std::collections::HashSet::new();
    for (i, m) in spec.methods.iter().enumerate() {
        let method: Method = m.parse().map_err(|e: String| Error::invalid(source, format!("methods[{i}]"), e))?;
        let method = match (method, m.trim().eq_ignore_ascii_case("LA")) {
            (Method::LensletAverage { .. }, true) => Method::LensletAverage { grid: dr.la_grid },
            (other, _) => other,
        };
        if !method_names.insert(method.name()) {
            return Err(Error::invalid(
                source,
                format!("methods[{i}]"),
                format!("{} appears twice (output file names would collide)", method.name()),
            ));
        }
        methods.push(method);
    }
    if methods.is_empty() {
        return Err(Error::invalid(source, "methods", "list at least one of LC, PC, LA, OPT"));
    }
    if dr.la_grid == 0 || dr.la_grid > 64 {
        return Err(Error::invalid(
            source,
            "display_render.la_grid",
            format!("must be between 1 and 64, got {}", dr.la_grid),
        ));
    }
    if dr.samples_per_pixel == 0 || dr.samples_per_pixel > 64 {
        return Err(Error::invalid(
            source,
            "display_render.samples_per_pixel",
            format!("must be between 1 and 64, got {}", dr.samples_per_pixel),
        ));
    }
    if !dr.reference_plane_z.is_finite() {
        return Err(Error::invalid(source, "display_render.reference_plane_z", "must be finite"));
    }
    crate::optics::limits::REFERENCE_PLANE_Z.check(source, "display_render.reference_plane_z", dr.reference_plane_z)?;
    Ok(methods)
}

/// The eye's position and the display-render settings (the eye position the methods render for),
/// each checked in front of the lenslets.
fn render_settings(spec: &ExperimentSpec, display: &Display, source: &str) -> Result<(DVec3, DisplayRenderSettings)> {
    let (dr, e) = (&spec.display_render, &spec.eye);
    let position = DVec3::from_array(e.position);
    let render = DisplayRenderSettings {
        samples_per_pixel: dr.samples_per_pixel,
        reference_plane_z: dr.reference_plane_z,
        eye_position: dr.eye_position.map(DVec3::from_array).unwrap_or(position),
    };
    if !render.eye_position.is_finite() {
        return Err(Error::invalid(source, "display_render.eye_position", "must be finite"));
    }
    // An eye at or beyond the lenslets sees nothing of the display, for every method.
    crate::optics::transfer::check_eye_in_front(display, position.z, source, "eye.position")?;
    if dr.eye_position.is_some() {
        crate::optics::transfer::check_eye_in_front(
            display,
            render.eye_position.z,
            source,
            "display_render.eye_position",
        )?;
    }
    Ok((position, render))
}

/// The `[[eye_cases]]` rows, each named once and resolved against the base eye.
fn resolve_cases(spec: &ExperimentSpec, base: &BaseEye, display: &Display, source: &str) -> Result<Vec<EyeCase>> {
    let mut cases = Vec::new();
    let mut names = std::collections::HashSet::new();
    for (i, c) in spec.eye_cases.iter().enumerate() {
        let field = format!("eye_cases[{i}]");
        if c.name.is_empty() || !c.name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_') {
            return Err(Error::invalid(
                source,
                format!("{field}.name"),
                format!("`{}` must be non-empty and use only letters, digits, - and _ (it names files)", c.name),
            ));
        }
        if !names.insert(c.name.as_str()) {
            return Err(Error::invalid(source, format!("{field}.name"), format!("`{}` appears twice", c.name)));
        }
        if c.weight.is_some() {
            return Err(Error::invalid(
                source,
                format!("{field}.weight"),
                "is read only in [[optimize.states]] (OPT's training weights of the eye cases are \
                 optimize.case_weights)",
            ));
        }
        if let Some(p) = c.position.filter(|p| DVec3::from_array(*p).is_finite()) {
            crate::optics::transfer::check_eye_in_front(display, p[2], source, &format!("{field}.position"))?;
        }
        let eye = c.resolve(base, source, &field)?;
        if let Some(pose) = &eye.pose {
            let gaze = if c.gaze_deg.is_some() { format!("{field}.gaze_deg") } else { "eye.gaze_deg".into() };
            display.check_gaze(pose, source, &gaze)?;
        }
        cases.push(EyeCase { name: c.name.clone(), eye });
    }
    Ok(cases)
}

/// OPT's explicit training states look at the display, as the eye cases do: a turned state's
/// line of sight meets the LCD. Errors name `optimize.states[i].gaze_deg` (or `eye.gaze_deg`,
/// which the state inherits).
fn check_state_gazes(
    spec: &crate::optimize::OptimizeSpec,
    opt: &crate::optimize::Optimization,
    display: &Display,
    source: &str,
) -> Result<()> {
    for (i, s) in spec.states.iter().enumerate() {
        let pose = opt.states.iter().find(|t| t.name == s.name).and_then(|t| t.eye.pose.as_ref());
        if let Some(pose) = pose {
            let field =
                if s.gaze_deg.is_some() { format!("optimize.states[{i}].gaze_deg") } else { "eye.gaze_deg".into() };
            display.check_gaze(pose, source, &field)?;
        }
    }
    Ok(())
}

/// The measurement's consistency with the optics and the eye: diffraction needs the converged
/// estimator, grid-only eye fields and inapplicable `[eye]` settings are refused.
fn check_measurement(
    spec: &ExperimentSpec,
    base: &BaseEye,
    measurement: &MeasurementSpec,
    cases: &[EyeCase],
    source: &str,
) -> Result<()> {
    let e = &spec.eye;
    let diffraction = spec.optics.as_ref().map(|o| o.diffraction).unwrap_or_default();
    if diffraction.is_on() && measurement.estimator != crate::measure::spec::EstimatorKind::Converged {
        return Err(Error::invalid(
            source,
            "optics.diffraction",
            format!(
                "\"{}\" needs the converged estimator: a diffraction angle is a sampled dimension of its \
                 integral, which the grid estimator's fixed pupil and retina grids do not have (add a \
                 [measurement] table with estimator = \"converged\", or set optics.diffraction = \"none\")",
                diffraction.name()
            ),
        ));
    }
    let d = EyeSpec::default();
    measurement.check_grid_only(
        source,
        [("pupil_grid", e.pupil_grid, d.pupil_grid), ("retina_samples", e.retina_samples, d.retina_samples)],
    )?;
    let converged = measurement.estimator == crate::measure::spec::EstimatorKind::Converged;
    crate::optics::eye::settings::check_applicable(e, &base.optics, converged, source)?;
    if !converged {
        for c in cases {
            crate::optics::eye::settings::check_grid_stiles_crawford(&c.eye, &c.name, source)?;
        }
    }
    Ok(())
}
