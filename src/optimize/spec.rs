//! The `[optimize]` table of an experiment (docs/OPTIMAL.md) and its resolved form: the eye
//! states the optimised method (OPT) is trained on, with their weights, the training sample
//! pattern (its own retina and pupil grids), the solver's budget and tolerance, the regulariser
//! and the starting image.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::solver::{SolverMethod, SolverSettings};
use crate::error::{Error, Result};
use crate::optics::{Aperture, Eye, Focus, Retina};
use crate::render::Method;

/// `[[optimize.states]]`: a training state beyond the experiment's eye cases, an eye state of the
/// same schema as `[[eye_cases]]` (with its `weight`).
pub type StateSpec = crate::optics::eye::settings::EyeCaseSpec;

/// `[optimize]`: how OPT's display image is optimised.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OptimizeSpec {
    /// The experiment's eye cases trained on, by name (absent: every eye case).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub train_cases: Option<Vec<String>>,
    /// The weight of each of `train_cases` (absent: 1 each).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub case_weights: Option<Vec<f64>>,
    /// Further training states.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub states: Vec<StateSpec>,
    /// The solver: "spg" (the default), "fista" or "pcg" (docs/OPTIMAL.md).
    pub solver: String,
    /// The most solver iterations.
    pub iterations: usize,
    /// Stop when the projected-gradient norm falls below this fraction of its initial value.
    pub tolerance: f64,
    /// lambda: the weight of `||x - x0||^2` per value (0: none).
    pub regularization: f64,
    /// The starting image (and the regulariser's centre): a method's name, LA by default.
    pub initial: String,
    /// The training pupil grid (n x n over the pupil's square; default: `eye.pupil_grid`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pupil_grid: Option<usize>,
    /// The training retina's pixels per side (default: `eye.retina_resolution`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub retina_resolution: Option<usize>,
    /// k x k training samples per retina pixel (1).
    pub retina_samples: usize,
    /// k x k training samples per retina pixel for a pinhole eye (4): it has one pupil point, so
    /// its pixel's square is sampled finely at little cost.
    pub pinhole_retina_samples: usize,
}

impl Default for OptimizeSpec {
    fn default() -> Self {
        Self {
            train_cases: None,
            case_weights: None,
            states: Vec::new(),
            solver: "spg".into(),
            iterations: 40,
            tolerance: 1e-3,
            regularization: 0.0,
            initial: "LA".into(),
            pupil_grid: None,
            retina_resolution: None,
            retina_samples: 1,
            pinhole_retina_samples: 4,
        }
    }
}

/// One training state, resolved.
#[derive(Clone, Debug)]
pub struct TrainingState {
    /// Its label.
    pub name: String,
    /// The eye (with the training pupil grid).
    pub eye: Eye,
    /// Its training retina (the sample pattern of its operator and ground truth).
    pub retina: Retina,
    /// w_s.
    pub weight: f64,
}

/// `[optimize]`, resolved: everything OPT needs besides the display and the scene.
#[derive(Clone, Debug)]
pub struct Optimization {
    /// The training states.
    pub states: Vec<TrainingState>,
    /// The starting image's method.
    pub initial: Method,
    /// Budget, tolerance, regulariser.
    pub solver: SolverSettings,
}

pub use crate::optics::eye::settings::BaseEye;

impl OptimizeSpec {
    /// Resolves the table against the experiment's eye cases `(name, eye)` and `[eye]`; errors
    /// name `source` and the field (`optimize.*`). `la_grid` is what "LA" means.
    pub fn resolve(
        &self,
        cases: &[(String, Eye)],
        base: &BaseEye,
        la_grid: usize,
        source: &str,
    ) -> Result<Optimization> {
        let f = |name: &str| format!("optimize.{name}");
        if self.iterations == 0 || self.iterations > 100_000 {
            return Err(Error::invalid(
                source,
                f("iterations"),
                format!("must be 1 to 100000, got {}", self.iterations),
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0 && self.tolerance < 1.0) {
            return Err(Error::invalid(source, f("tolerance"), format!("must be in [0, 1), got {}", self.tolerance)));
        }
        if !(self.regularization.is_finite() && self.regularization >= 0.0) {
            return Err(Error::invalid(
                source,
                f("regularization"),
                format!("must be finite and >= 0, got {}", self.regularization),
            ));
        }
        let method: SolverMethod = self.solver.parse().map_err(|e: String| Error::invalid(source, f("solver"), e))?;
        let initial: Method = self.initial.parse().map_err(|e: String| Error::invalid(source, f("initial"), e))?;
        let initial = match (initial, self.initial.trim().eq_ignore_ascii_case("LA")) {
            (Method::LensletAverage { .. }, true) => Method::LensletAverage { grid: la_grid },
            (Method::Optimized, _) => {
                return Err(Error::invalid(source, f("initial"), "OPT cannot start from itself: name LC, PC or LA"))
            }
            (m, _) => m,
        };
        let pupil_grid = self.pupil_grid.unwrap_or(base.pupil_grid);
        if pupil_grid == 0 || pupil_grid > 64 {
            return Err(Error::invalid(source, f("pupil_grid"), format!("must be 1 to 64, got {pupil_grid}")));
        }
        let retina = Retina {
            resolution: self.retina_resolution.unwrap_or(base.retina.resolution),
            samples_per_pixel: self.retina_samples,
            ..base.retina
        };
        let pinhole_retina = Retina { samples_per_pixel: self.pinhole_retina_samples, ..retina };
        for (r, name) in [(&retina, "retina_samples"), (&pinhole_retina, "pinhole_retina_samples")] {
            r.validate(source).map_err(|e| match e {
                Error::Invalid { source_name, field, message } => {
                    let field = if field.contains("resolution") { f("retina_resolution") } else { f(name) };
                    Error::Invalid { source_name, field, message }
                }
                e => e,
            })?;
        }
        let retina_of = |eye: &Eye| if matches!(eye.aperture, Aperture::Pinhole) { pinhole_retina } else { retina };
        let mut states = Vec::new();
        let names: Vec<String> = match &self.train_cases {
            Some(n) => n.clone(),
            None if self.states.is_empty() => cases.iter().map(|(n, _)| n.clone()).collect(),
            None => Vec::new(),
        };
        if let Some(w) = &self.case_weights {
            if w.len() != names.len() {
                return Err(Error::invalid(
                    source,
                    f("case_weights"),
                    format!("gives {} weights for {} training cases", w.len(), names.len()),
                ));
            }
        }
        for (i, name) in names.iter().enumerate() {
            let Some((_, eye)) = cases.iter().find(|(n, _)| n == name) else {
                return Err(Error::invalid(
                    source,
                    format!("optimize.train_cases[{i}]"),
                    format!("no eye case is named `{name}`"),
                ));
            };
            let weight = self.case_weights.as_ref().map_or(1.0, |w| w[i]);
            let mut eye = eye.clone();
            eye.pupil_grid = pupil_grid;
            states.push(TrainingState { name: name.clone(), retina: retina_of(&eye), eye, weight });
        }
        for (i, s) in self.states.iter().enumerate() {
            let mut eye = s.resolve(base, source, &format!("optimize.states[{i}]"))?;
            eye.pupil_grid = pupil_grid;
            states.push(TrainingState {
                name: s.name.clone(),
                retina: retina_of(&eye),
                eye,
                weight: s.weight.unwrap_or(1.0),
            });
        }
        if states.is_empty() {
            return Err(Error::invalid(source, f("train_cases"), "train on at least one eye state"));
        }
        refuse_duplicate_states(&states, names.len(), source)?;
        for (i, s) in states.iter().enumerate() {
            if !(s.weight.is_finite() && s.weight > 0.0) {
                return Err(Error::invalid(
                    source,
                    format!("optimize weight of `{}` (state {i})", s.name),
                    format!("must be finite and > 0, got {}", s.weight),
                ));
            }
        }
        Ok(Optimization {
            states,
            initial,
            solver: SolverSettings {
                method,
                max_iterations: self.iterations,
                tolerance: self.tolerance,
                regularization: self.regularization,
            },
        })
    }
}

/// The field of training state `i`: `optimize.train_cases[i]` for the first `cases` states,
/// then `optimize.states[i - cases]`.
fn state_field(i: usize, cases: usize) -> String {
    if i < cases {
        format!("optimize.train_cases[{i}]")
    } else {
        format!("optimize.states[{}]", i - cases)
    }
}

/// Whether two training states are the same eye state (so that training on both would only
/// double its weight): the same aperture (focus compared as vergence), pupil centre, gaze,
/// retina distance, optics and training retina.
fn same_state(a: &TrainingState, b: &TrainingState) -> bool {
    let aperture = |s: &TrainingState| match s.eye.aperture {
        Aperture::Pinhole => None,
        Aperture::ThinLens { pupil_diameter, focus } => Some((pupil_diameter, focus.vergence())),
    };
    aperture(a) == aperture(b)
        && a.eye.position == b.eye.position
        && a.eye.pose == b.eye.pose
        && a.eye.retina_distance == b.eye.retina_distance
        && a.eye.optics == b.eye.optics
        && a.retina == b.retina
}

/// Refuses a training state listed twice, by name or as the same eye state: it would silently
/// count twice in the objective. A weight says how much a state counts.
fn refuse_duplicate_states(states: &[TrainingState], cases: usize, source: &str) -> Result<()> {
    for (i, s) in states.iter().enumerate() {
        if let Some(j) = states[..i].iter().position(|t| t.name == s.name) {
            return Err(Error::invalid(
                source,
                state_field(i, cases),
                format!(
                    "`{}` is already a training state ({}); each state is trained on once: give it a weight \
                     (optimize.case_weights or the state's `weight`) to count it more",
                    s.name,
                    state_field(j, cases)
                ),
            ));
        }
        if let Some(j) = states[..i].iter().position(|t| same_state(t, s)) {
            return Err(Error::invalid(
                source,
                state_field(i, cases),
                format!(
                    "`{}` is the same eye state as `{}` ({}): training on both would only double its weight; give \
                     one of them a weight instead",
                    s.name,
                    states[j].name,
                    state_field(j, cases)
                ),
            ));
        }
    }
    Ok(())
}

impl Optimization {
    /// Adds OPT's memory to `e`, for a display of `lcd_pixels` LCD pixels: per training state
    /// its target, residual and forward image (f64 RGB) and its ground truth (f32 RGB) on the
    /// training retina; the operator's sample lists of one wave of bands (2 per thread, 8 rows
    /// each, 24 bytes per sample); the solver's display-sized images (f64 RGB, at most 6).
    pub fn add_to_estimate(&self, e: &mut crate::budget::Estimate, lcd_pixels: u64) {
        let setting = |s: &TrainingState| format!("optimize.retina_resolution = {}", s.retina.resolution);
        let pixels: u64 = self.states.iter().map(|s| (s.retina.resolution as u64).pow(2)).sum();
        if let Some(big) = self.states.iter().max_by_key(|s| s.retina.resolution) {
            e.add("OPT's training targets, residuals and ground truths", setting(big), pixels, 3 * 24 + 12);
        }
        let threads = rayon::current_num_threads().max(1) as u64;
        let samples = |s: &TrainingState| {
            let spectral = s.eye.optics.as_ref().map_or(1, |o| o.grid_spectral().len()) as u64;
            (s.retina.subpixel_offsets().len() * s.eye.pupil_samples().len()) as u64 * spectral
        };
        if let Some(s) = self.states.iter().max_by_key(|s| s.retina.resolution as u64 * samples(s)) {
            let rows = (2 * threads).max(4) * 8 * s.retina.resolution as u64;
            e.add(
                "OPT's operator sample lists",
                format!("{} with optimize.pupil_grid and optimize.retina_samples", setting(s)),
                rows.saturating_mul(samples(s)),
                24,
            );
        }
        e.add("OPT's solver images", "the display's lcd.resolution", lcd_pixels.saturating_mul(6), 24);
    }

    /// OPT where no `[optimize]` table is given (`render-display`, Python's `render_display`):
    /// the paper's four eye states (pinhole; thin lens with a 5 mm pupil focused at 300, 400 and
    /// 600 mm; 8 x 8 pupil grid) around `eye_position`, the paper's 512 x 512 retina over
    /// tangents -0.3 to 0.3 (one ray per pixel, 4 x 4 for the pinhole), starting from LA 5 x 5,
    /// 40 iterations of SPG.
    pub fn paper_default(eye_position: DVec3) -> Self {
        let spec = OptimizeSpec::default();
        let state = |name: &str, aperture| {
            let k =
                if matches!(aperture, Aperture::Pinhole) { spec.pinhole_retina_samples } else { spec.retina_samples };
            TrainingState {
                name: name.into(),
                eye: Eye {
                    retina_distance: 17.0,
                    aperture,
                    pupil_grid: 8,
                    position: eye_position,
                    optics: None,
                    pose: None,
                },
                retina: Retina { resolution: 512, half_tangent: 0.3, samples_per_pixel: k },
                weight: 1.0,
            }
        };
        let lens = |mm| Aperture::ThinLens { pupil_diameter: 5.0, focus: Focus::Millimetres(mm) };
        Self {
            states: vec![
                state("Pin", Aperture::Pinhole),
                state("Near", lens(300.0)),
                state("Cen", lens(400.0)),
                state("Far", lens(600.0)),
            ],
            initial: Method::LensletAverage { grid: crate::render::display_image::PAPER_LA_GRID },
            solver: SolverSettings {
                method: spec.solver.parse().unwrap_or(SolverMethod::Spg),
                max_iterations: spec.iterations,
                tolerance: spec.tolerance,
                regularization: spec.regularization,
            },
        }
    }
}
