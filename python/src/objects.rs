//! The inputs of the paper's pipeline as Python objects (Sec. 2-4): `Display` (the lenslet array
//! and LCD), `Eye` (the thin-lens or schematic eye with its retina and gaze, as the CLI's eye
//! flags and `[eye]` keys), `Scene` and
//! `Experiment`, each loaded by the library's own loaders, with `set=` as `--set`.

use std::path::{Path, PathBuf};

use glam::DVec3;
use pyo3::prelude::*;

use inimtrace::experiment::{Experiment, ExperimentSpec};
use inimtrace::info::DisplayParameters;
use inimtrace::optics::eye::settings::pose_of;
use inimtrace::optics::eye::{CentreOfRotation, EyeModel, Gaze};
use inimtrace::optics::{Aperture, Display, Eye, Retina};
use inimtrace::scene::Scene;
use inimtrace::settings::{load_display_part, load_experiment, load_scene_part};

use crate::convert::{overrides, to_py};
use crate::errors::{value_error, warn_all, IntoPy};
use inimtrace::optics::plausibility::{check, display_warnings, focus_warning, PUPIL_DIAMETER};

/// A near-eye integral-imaging display: lenslet array and LCD (lengths in mm).
#[pyclass(name = "Display", module = "inimtrace", frozen)]
#[derive(Clone)]
pub struct PyDisplay {
    pub inner: Display,
}

#[pymethods]
impl PyDisplay {
    /// Loads a display TOML or the framework's OpenCV YAML; `set` overrides its settings
    /// (keys `display.…`, as `--set`).
    #[staticmethod]
    #[pyo3(signature = (path, set=None))]
    fn load(py: Python<'_>, path: PathBuf, set: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let inner = load_display_part(Some(&path), &overrides(set)?).py_err()?;
        warn_all(py, &display_warnings(&inner, &path.display().to_string()))?;
        Ok(Self { inner })
    }

    /// The paper's display (the framework's `lensletdisplay.yaml`); `set` overrides its settings.
    #[staticmethod]
    #[pyo3(signature = (set=None))]
    fn paper(py: Python<'_>, set: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let inner = load_display_part(None, &overrides(set)?).py_err()?;
        warn_all(py, &display_warnings(&inner, "Display.paper()"))?;
        Ok(Self { inner })
    }

    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// v1: pupil plane to lenslet plane, mm.
    #[getter]
    fn eye_to_lenslets_mm(&self) -> f64 {
        self.inner.eye_to_lenslets
    }
    /// v2: lenslet plane to LCD, mm.
    #[getter]
    fn lenslets_to_lcd_mm(&self) -> f64 {
        self.inner.lenslets_to_lcd
    }
    #[getter]
    fn focal_length_mm(&self) -> f64 {
        self.inner.focal_length
    }
    /// Lenslet pitch matrix, row-major (m00, m01, m10, m11), mm.
    #[getter]
    fn lenslet_pitch_matrix_mm(&self) -> [f64; 4] {
        self.inner.lenslets.row_major()
    }
    #[getter]
    fn lenslet_shift_mm(&self) -> [f64; 2] {
        self.inner.lenslets.shift.to_array()
    }
    /// Elemental-image pitch matrix, row-major, mm.
    #[getter]
    fn elemental_image_pitch_matrix_mm(&self) -> [f64; 4] {
        self.inner.elemental_images.row_major()
    }
    #[getter]
    fn elemental_image_shift_mm(&self) -> [f64; 2] {
        self.inner.elemental_images.shift.to_array()
    }
    /// LCD width and height, mm.
    #[getter]
    fn lcd_size_mm(&self) -> [f64; 2] {
        self.inner.lcd.size.to_array()
    }
    /// LCD columns and rows.
    #[getter]
    fn lcd_resolution(&self) -> [usize; 2] {
        self.inner.lcd.resolution
    }
    /// The shape of a display image of this display: (rows, columns, 3).
    #[getter]
    fn image_shape(&self) -> (usize, usize, usize) {
        (self.inner.lcd.rows(), self.inner.lcd.columns(), 3)
    }
    /// Distance of the central depth plane, mm (None: at infinity or real).
    #[getter]
    fn central_depth_plane_mm(&self) -> Option<f64> {
        self.inner.central_depth_plane()
    }
    /// The display's parameters as a dict (the `display` of `results.json`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &DisplayParameters::from(&self.inner))
    }
    /// The design figures of `inimtrace info --json`: eye box, field of view, pixels per degree,
    /// views through a `pupil` mm pupil (`views_across_pupil`, `views_in_pupil`) and one
    /// lenslet's pixel beams in it (`lenslet_pixel_beams_in_pupil`).
    #[pyo3(signature = (pupil=5.0))]
    fn design<'py>(&self, py: Python<'py>, pupil: f64) -> PyResult<Bound<'py, PyAny>> {
        if !(pupil.is_finite() && pupil > 0.0) {
            return Err(value_error(format!("pupil must be a positive number of mm, got {pupil}")));
        }
        to_py(py, &inimtrace::info::display_design(&self.inner, pupil))
    }
    fn __repr__(&self) -> String {
        format!("<inimtrace.Display {}>", self.inner.summary())
    }
}

/// The eye: a thin lens (or pinhole) with its retina, as the CLI's eye flags.
#[pyclass(name = "Eye", module = "inimtrace", frozen)]
#[derive(Clone)]
pub struct PyEye {
    pub eye: Eye,
    pub retina: Retina,
    /// The centre of rotation the eye turns about (`[eye] centre_of_rotation_mm`).
    pub centre: CentreOfRotation,
    /// How a schematic eye's optics are rebuilt for a display's own primaries (None: the eye of
    /// an experiment's case, built with its display's primaries already).
    pub rebuild: Option<(inimtrace::experiment::EyeModelSettings, &'static str)>,
}

impl PyEye {
    /// The eye seen with `display`: a polychromatic schematic eye's channels take the display's
    /// `[primaries]` (the eye was built with the default primaries, not knowing the display).
    /// A turned eye's line of sight must meet the display's LCD, as the CLI checks `eye.gaze_deg`.
    pub fn for_display(&self, display: Option<&inimtrace::optics::Display>) -> PyResult<Eye> {
        if let (Some(d), Some(pose)) = (display, &self.eye.pose) {
            d.check_gaze(pose, "Eye()", "gaze").py_err()?;
        }
        let mut eye = self.eye.clone();
        let primaries = display.and_then(|d| d.primaries.as_ref());
        let polychromatic = eye.optics.as_ref().is_some_and(|o| !o.is_single_wavelength());
        if let (Some(primaries), Some((settings, focus)), true) = (primaries, &self.rebuild, polychromatic) {
            eye.optics = settings.optics_for(&eye, self.retina.half_tangent, primaries, "Eye()", focus).py_err()?;
        }
        Ok(eye)
    }
}

#[pymethods]
impl PyEye {
    /// Give exactly one of `pinhole=True`, `focus_mm` or `focus_diopters` (0 D is infinity).
    /// `pupil` (mm), `pupil_grid` (n x n grid kept inside the circle), `retina` (pixels per
    /// side), `half_tangent`, `retina_samples` (k x k per pixel), `retina_distance` (v0, mm) and
    /// `position` (pupil centre, mm) default to the CLI's defaults.
    #[new]
    /// `model` (`[eye] model`: "thin-lens", "navarro", "navarro-1999", "arizona", "le-grand"),
    /// `spectrum` ("primaries" or "single") and `stiles_crawford_rho` choose the eye as an
    /// experiment's `[eye]` does (docs/EYE.md). `gaze` (`[eye] gaze_deg`: horizontal, vertical
    /// degrees) turns the whole eye about its centre of rotation, `centre_of_rotation` mm behind
    /// the cornea (`[eye] centre_of_rotation_mm`, 13.3 by default).
    #[pyo3(signature = (*, pinhole=false, focus_mm=None, focus_diopters=None, pupil=5.0, pupil_grid=8, retina=512,
        half_tangent=0.3, retina_samples=1, retina_distance=17.0, position=(0.0, 0.0, 0.0), model=None,
        spectrum=None, stiles_crawford_rho=None, gaze=(0.0, 0.0), centre_of_rotation=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        pinhole: bool,
        focus_mm: Option<f64>,
        focus_diopters: Option<f64>,
        pupil: f64,
        pupil_grid: usize,
        retina: usize,
        half_tangent: f64,
        retina_samples: usize,
        retina_distance: f64,
        position: (f64, f64, f64),
        model: Option<String>,
        spectrum: Option<String>,
        stiles_crawford_rho: Option<f64>,
        gaze: (f64, f64),
        centre_of_rotation: Option<f64>,
    ) -> PyResult<Self> {
        let aperture = Aperture::stated(pinhole, focus_mm, focus_diopters, pupil)
            .ok_or_else(|| value_error("Eye: give exactly one of pinhole=True, focus_mm or focus_diopters"))?;
        let mut eye = Eye {
            retina_distance,
            aperture,
            pupil_grid,
            position: DVec3::new(position.0, position.1, position.2),
            optics: None,
            pose: None,
        };
        eye.validate("Eye()").py_err()?;
        // Likely unit mistakes, as the CLI warns of them.
        let mut warnings: Vec<String> =
            check("Eye()", "pupil", pupil, PUPIL_DIAMETER).into_iter().filter(|_| !pinhole).collect();
        if let Some(z) = focus_mm {
            warnings.extend(focus_warning("Eye()", "focus_mm", z, false));
        } else if let Some(d) = focus_diopters {
            warnings.extend(focus_warning("Eye()", "focus_diopters", 1000.0 / d, true));
        }
        warn_all(py, &warnings)?;
        let settings =
            inimtrace::experiment::EyeModelSettings { model, spectrum, stiles_crawford_rho, ..Default::default() };
        let focus = if focus_mm.is_some() { "focus_mm" } else { "focus_diopters" };
        let primaries = inimtrace::optics::spectrum::Primaries::default();
        eye.optics = settings.optics_for(&eye, half_tangent, &primaries, "Eye()", focus).py_err()?;
        let retina = Retina { resolution: retina, half_tangent, samples_per_pixel: retina_samples };
        retina.validate("Eye()").py_err()?;
        let gaze = Gaze::new(gaze.0, gaze.1);
        gaze.validate("Eye()", "gaze").py_err()?;
        let centre =
            centre_of_rotation.map_or_else(CentreOfRotation::default, |mm| CentreOfRotation { behind_cornea_mm: mm });
        centre.validate("Eye()", "centre_of_rotation").py_err()?;
        let model = eye.optics.as_ref().map_or(EyeModel::ThinLens, |o| o.model.clone());
        eye.pose = pose_of(&model, gaze, centre, eye.position, "Eye()").py_err()?;
        Ok(Self { eye, retina, centre, rebuild: Some((settings, focus)) })
    }

    #[getter]
    fn pinhole(&self) -> bool {
        matches!(self.eye.aperture, Aperture::Pinhole)
    }
    /// Focus distance, mm (None for a pinhole; inf at 0 D).
    #[getter]
    fn focus_mm(&self) -> Option<f64> {
        match self.eye.aperture {
            Aperture::ThinLens { focus, .. } => Some(focus.distance_mm()),
            Aperture::Pinhole => None,
        }
    }
    #[getter]
    fn focus_diopters(&self) -> Option<f64> {
        match self.eye.aperture {
            Aperture::ThinLens { focus, .. } => Some(focus.diopters()),
            Aperture::Pinhole => None,
        }
    }
    /// Pupil diameter, mm (None for a pinhole).
    #[getter]
    fn pupil(&self) -> Option<f64> {
        match self.eye.aperture {
            Aperture::ThinLens { pupil_diameter, .. } => Some(pupil_diameter),
            Aperture::Pinhole => None,
        }
    }
    #[getter]
    fn pupil_grid(&self) -> usize {
        self.eye.pupil_grid
    }
    /// The pupil samples the grid estimator uses (inside the circle).
    #[getter]
    fn pupil_samples(&self) -> usize {
        self.eye.pupil_samples().len()
    }
    #[getter]
    fn retina(&self) -> usize {
        self.retina.resolution
    }
    #[getter]
    fn half_tangent(&self) -> f64 {
        self.retina.half_tangent
    }
    #[getter]
    fn retina_samples(&self) -> usize {
        self.retina.samples_per_pixel
    }
    #[getter]
    fn retina_distance(&self) -> f64 {
        self.eye.retina_distance
    }
    #[getter]
    fn position(&self) -> (f64, f64, f64) {
        self.eye.position.into()
    }
    /// The gaze, (horizontal, vertical) degrees ((0, 0): straight ahead).
    #[getter]
    fn gaze(&self) -> (f64, f64) {
        self.eye.pose.map_or((0.0, 0.0), |p| (p.gaze.horizontal_deg, p.gaze.vertical_deg))
    }
    /// The centre of rotation, mm behind the cornea.
    #[getter]
    fn centre_of_rotation(&self) -> f64 {
        self.centre.behind_cornea_mm
    }
    /// The pupil centre at the gaze, mm (`position` straight ahead): where PupilCenter renders
    /// for with ideal tracking (`render_display(..., eye_position=eye.pupil_centre)`).
    #[getter]
    fn pupil_centre(&self) -> (f64, f64, f64) {
        self.eye.pose.map_or(self.eye.position, |p| p.pupil_centre).into()
    }
    /// The eye model's canonical name (`[eye] model`): "thin-lens", "navarro-1985",
    /// "navarro-1999", "arizona", "le-grand" or "user".
    #[getter]
    fn model(&self) -> &'static str {
        self.eye.optics.as_ref().map_or("thin-lens", |o| o.model.name())
    }
    fn __repr__(&self) -> String {
        let what = match self.eye.aperture {
            Aperture::Pinhole => "pinhole".to_string(),
            Aperture::ThinLens { pupil_diameter, focus } => {
                format!("pupil {pupil_diameter} mm, focus {:.1} mm ({:.3} D)", focus.distance_mm(), focus.diopters())
            }
        };
        format!("<inimtrace.Eye {}, {what}, retina {}>", self.model(), self.retina.resolution)
    }
}

/// A scene (rectangles, meshes, sphere grids, an optional distant light), lengths in mm.
#[pyclass(name = "Scene", module = "inimtrace", frozen)]
#[derive(Clone)]
pub struct PyScene {
    pub inner: Scene,
}

#[pymethods]
impl PyScene {
    /// Loads a scene TOML; `set` overrides its settings (keys `scene.…`, as `--set`).
    #[staticmethod]
    #[pyo3(signature = (path, set=None))]
    fn load(py: Python<'_>, path: PathBuf, set: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let inner = load_scene_part(Some(&path), &overrides(set)?).py_err()?;
        // What loading noticed (an unreadable texture or material library), as the CLI says it.
        warn_all(py, &inner.warnings)?;
        Ok(Self { inner })
    }
    /// The paper's scene (USAF-1951 charts); `set` overrides its settings.
    #[staticmethod]
    #[pyo3(signature = (set=None))]
    fn paper(set: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        Ok(Self { inner: load_scene_part(None, &overrides(set)?).py_err()? })
    }
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// Notes from loading (e.g. degenerate triangles dropped).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }
    #[getter]
    fn object_count(&self) -> usize {
        self.inner.objects.len()
    }
    #[getter]
    fn triangle_count(&self) -> usize {
        self.inner.triangle_count()
    }
    /// The summary of `inimtrace info --scene --json`: objects, bounds, depth range.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &inimtrace::info::scene_summary(&self.inner))
    }
    fn __repr__(&self) -> String {
        format!(
            "<inimtrace.Scene `{}`: {}>",
            self.inner.name,
            inimtrace::count::count(self.inner.objects.len(), "object")
        )
    }
}

/// An experiment: scene, display, methods, eye cases and how Table 1 is measured.
#[pyclass(name = "Experiment", module = "inimtrace", frozen)]
pub struct PyExperiment {
    pub inner: Experiment,
}

#[pymethods]
impl PyExperiment {
    /// Loads an experiment TOML; `set` holds the CLI's `--set` overrides, as a dict
    /// (`{"eye.pupil_diameter": 3, "eye_cases[1].focus_diopters": 2.5}`) or a list of
    /// `"KEY=VALUE"` strings; `scene` replaces its scene (as `assess --scene`).
    #[staticmethod]
    #[pyo3(signature = (path, set=None, scene=None))]
    fn load(py: Python<'_>, path: PathBuf, set: Option<&Bound<'_, PyAny>>, scene: Option<PathBuf>) -> PyResult<Self> {
        let inner = load_experiment(Some(&path), scene.as_deref(), &overrides(set)?).py_err()?;
        warn_all(py, &inner.plausibility_warnings())?;
        Ok(Self { inner })
    }
    /// The paper's experiment measured converged (what `inimtrace assess` runs with no file).
    #[staticmethod]
    #[pyo3(signature = (set=None, scene=None))]
    fn paper(py: Python<'_>, set: Option<&Bound<'_, PyAny>>, scene: Option<PathBuf>) -> PyResult<Self> {
        let inner = load_experiment(None, scene.as_deref(), &overrides(set)?).py_err()?;
        warn_all(py, &inner.plausibility_warnings())?;
        Ok(Self { inner })
    }
    /// The paper's experiment as its text states it, with the grid estimator
    /// (`experiments/paper.toml`).
    #[staticmethod]
    #[pyo3(signature = (set=None))]
    fn paper_grid(py: Python<'_>, set: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let set = overrides(set)?;
        let s = inimtrace::settings::Settings::builtin(
            &ExperimentSpec::paper(),
            "built-in paper experiment",
            Path::new("."),
        )
        .py_err()?;
        let mut inner = s.with_overrides(&set).resolve().and_then(|r| r.experiment()).py_err()?;
        // Built in: no file read; its provenance names the scene and display, `set=` and the budgets.
        inner.provenance = inimtrace::settings::provenance_of(&inner, None, Vec::new(), &set);
        warn_all(py, &inner.plausibility_warnings())?;
        Ok(Self { inner })
    }
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene { inner: self.inner.scene.clone() }
    }
    #[getter]
    fn display(&self) -> PyDisplay {
        PyDisplay { inner: self.inner.display.clone() }
    }
    /// The methods' names ("LC", "PC", "LA"; "LA3" for a 3 x 3 LensletAverage).
    #[getter]
    fn methods(&self) -> Vec<String> {
        self.inner.methods.iter().map(|m| m.name()).collect()
    }
    /// The eye cases as (name, Eye) pairs.
    #[getter]
    fn eye_cases(&self) -> Vec<(String, PyEye)> {
        let centre = self
            .inner
            .spec
            .eye
            .centre_of_rotation_mm
            .map_or_else(CentreOfRotation::default, |mm| CentreOfRotation { behind_cornea_mm: mm });
        self.inner
            .cases
            .iter()
            .map(|c| (c.name.clone(), PyEye { eye: c.eye.clone(), retina: self.inner.retina, centre, rebuild: None }))
            .collect()
    }
    /// "converged" or "grid".
    #[getter]
    fn estimator(&self) -> String {
        format!("{:?}", self.inner.measurement.estimator).to_ascii_lowercase()
    }
    /// The experiment's settings as a dict (the `settings` of `results.json`).
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.inner.spec)
    }
    /// The experiment as a TOML file.
    fn to_toml(&self) -> String {
        self.inner.spec.to_toml()
    }
    fn __repr__(&self) -> String {
        format!(
            "<inimtrace.Experiment `{}`: methods {}, eye cases {}>",
            self.inner.name,
            self.methods().join(" "),
            self.inner.cases.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(" ")
        )
    }
}
