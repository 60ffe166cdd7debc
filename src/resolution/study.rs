//! The study file of `inimtrace resolution` (the paper's abstract: "perceived spatial
//! resolution at different focused depths", and its conclusion's Fourier-domain analysis): which
//! display and methods, which content depths, eye focuses and spatial frequencies, how the retina
//! samples them and how precisely. `studies/paper.toml` spells out the default study.
//!
//! ```toml
//! name = "paper"
//! display = "builtin:paper"            # or a display file, relative to this file
//! methods = ["LC", "PC", "LA"]         # the ground truth is always measured too
//! pupil_diameter_mm = 5.0
//! content_diopters = { from = 0.5, to = 3.5, step = 0.5 }   # a list or a range
//! content_mm = [300, 400, 600]         # more content depths, in mm (duplicates are merged)
//! focus_diopters = { from = 0.0, to = 4.0, step = 0.25 }
//! frequencies_cpd = [0.5, 1, 1.5, 2, 3, 4, 5, 6, 7, 8]
//! orientations_deg = [0, 45, 90, 135]  # the gratings' orientations (0 always; this is the default)
//! orientations_through_focus = false   # other orientations only with the eye on the content
//! field_deg = [0, 0]                   # the charts' centre off axis: [horizontal, vertical]
//! [target]                             # gratings and the slanted edge: mean and contrast
//! [retina]                             # pixels per degree, measured windows, guard bands
//! [measurement]                        # samples per pixel, replicates, seed
//! [accommodation]                      # the frequency rule's frequency, the area rule's limit
//! [limits]                             # display.md's depth ranges: contrast and frequencies
//! ```
//!
//! Loading applies `--set` overrides to the file's TOML first, then deserializes and validates;
//! every error names the file and the field. The resolved [`Study`] is what `study.json` holds.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::io::display_file::load_display;
use crate::io::text::{base_dir, read_text, toml_error};
use crate::optics::eye::pupil::{AutoPupil, PupilSetting};
use crate::optics::Display;
use crate::overrides::Override;
use crate::render::Method;

/// The default study, `studies/paper.toml`, built in.
pub const PAPER_STUDY: &str = include_str!("../../studies/paper.toml");

pub use super::values::Values;

/// `[target]`: the gratings' and the edge's luminance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetSpec {
    /// Mean luminance (linear, 0..1).
    pub mean: f64,
    /// Michelson contrast of the gratings and the edge (0..1].
    pub contrast: f64,
}

/// `[retina]`: how finely the retina samples and where it looks.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RetinaSpec {
    /// Retina pixels per degree (64: Nyquist 32 cpd, never the limit).
    pub pixels_per_degree: f64,
    /// Each grating's measured window, degrees across and along its bars: the width must hold a
    /// whole number of periods of every frequency.
    pub window_deg: [f64; 2],
    /// Grating (and edge) beyond its window on every side, degrees: blur from around a patch
    /// reaches the window only when wider than this.
    pub guard_deg: f64,
    /// The slanted edge's window, degrees across and along the edge.
    pub edge_window_deg: [f64; 2],
    /// The edge's angle from vertical, degrees (ISO 12233: a few degrees).
    pub edge_angle_deg: f64,
}

/// `[measurement]`: the converged estimator's sampling.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplingSpec {
    /// Samples (eye rays) per retina pixel in each replicate.
    pub samples_per_pixel: u32,
    /// Independent replicates (at least 3): the 95% intervals have one fewer degrees of freedom.
    pub replicates: usize,
    /// Seed of the Sobol scrambles.
    pub seed: u64,
    /// How the colour channels combine into the measured grey: `"luminance"` (the default, the
    /// primaries' V(lambda) shares) or `"mean"` ([`super::window::Channels`]).
    #[serde(default)]
    pub channels: super::window::Channels,
}

/// `[accommodation]`: the two rules' settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AccommodationSpec {
    /// The frequency rule: focus of the highest contrast at this frequency (one of the study's).
    pub frequency_cpd: f64,
    /// The area rule: focus of the largest area under the grating MTF from the lowest frequency
    /// up to this one (one of the study's).
    pub area_limit_cpd: f64,
}

/// `[limits]`: display.md's depth ranges.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LimitsSpec {
    /// Contrast a method must keep (eye focused on the content).
    pub contrast: f64,
    /// At these frequencies (each one of the study's).
    pub frequencies_cpd: Vec<f64>,
}

/// The study file as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    /// Names the output folder `out/resolution-<name>`.
    pub name: String,
    /// One line for reports.
    #[serde(default)]
    pub description: String,
    /// `builtin:paper` or a display file (TOML or OpenCV YAML), relative to the study file.
    pub display: String,
    /// Methods measured: "LC", "PC", "LA", `LA<k>`.
    pub methods: Vec<String>,
    /// Pupil diameter, mm, or `"auto"` (the light-adapted pupil; `[eye] age`, `adapted_eyes`).
    pub pupil_diameter_mm: PupilSetting,
    /// v0: pupil to retina, mm (default 17).
    #[serde(default = "default_retina_distance")]
    pub retina_distance_mm: f64,
    /// Content depths, dioptres (a list or a range).
    #[serde(default = "no_values")]
    pub content_diopters: Values,
    /// More content depths, mm from the pupil.
    #[serde(default)]
    pub content_mm: Vec<f64>,
    /// The eye's focus grid, dioptres (every content depth is added).
    pub focus_diopters: Values,
    /// Grating frequencies, cycles per degree.
    pub frequencies_cpd: Values,
    /// Orientations of the gratings, degrees counter-clockwise from vertical bars (modulation
    /// along x); 0 must be one of them (default 0, 45, 90, 135).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientations_deg: Option<Vec<f64>>,
    /// Measure the other orientations at every focus too (default: with the eye on the content).
    #[serde(default)]
    pub orientations_through_focus: bool,
    /// The direction the charts face, `[horizontal, vertical]` degrees (default on the axis).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field_deg: Option<crate::optics::eye::Gaze>,
    /// `[target]`: the patterns' mean and contrast.
    pub target: TargetSpec,
    /// `[retina]`: pixels per degree, windows and guards.
    pub retina: RetinaSpec,
    /// `[measurement]`: replicates and samples per pixel.
    pub measurement: SamplingSpec,
    /// `[accommodation]`: what predicts the eye's focus.
    pub accommodation: AccommodationSpec,
    /// `[limits]`: the display-limit contrast and frequencies.
    pub limits: LimitsSpec,
    /// `[eye]`: the eye model (default the paper's thin lens), its focus criterion, wavelengths
    /// and Stiles-Crawford effect, as an experiment's `[eye]` names them (docs/EYE.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eye: Option<crate::experiment::EyeModelSettings>,
    /// `[optics]`: diffraction at the apertures, as an experiment's `[optics]` (absent: rays
    /// only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optics: Option<crate::optics::diffraction::OpticsSpec>,
    /// `[display_render]`: the pupil PupilCenter renders for when the eye turns (absent: the
    /// turned pupil, ideal tracking).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub display_render: Option<super::field::StudyRenderSpec>,
}

fn no_values() -> Values {
    Values::List(Vec::new())
}

fn default_retina_distance() -> f64 {
    17.0
}

/// A content depth.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Depth {
    /// Vergence, dioptres.
    pub diopters: f64,
    /// Distance from the pupil, mm.
    pub mm: f64,
}

/// A resolved study: everything `inimtrace resolution` needs, as `study.json` records it.
#[derive(Clone, Debug, Serialize)]
pub struct Study {
    /// The study's name.
    pub name: String,
    /// One line for reports.
    pub description: String,
    /// Where the study came from (a path, or `builtin:paper`).
    pub source: String,
    /// The display as the file named it.
    pub display_source: String,
    /// The display, resolved.
    #[serde(skip)]
    pub display: Display,
    /// Methods measured.
    #[serde(serialize_with = "method_names")]
    pub methods: Vec<Method>,
    /// Pupil diameter, mm (stated, or chosen by `"auto"`).
    pub pupil_diameter_mm: f64,
    /// How `"auto"` chose it: the chart's grey at the display's photometry over its field.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auto_pupil: Option<AutoPupil>,
    /// v0, mm.
    pub retina_distance_mm: f64,
    /// Content depths, far to near (increasing diopters), duplicates merged.
    pub depths: Vec<Depth>,
    /// Eye focuses measured, diopters: the focus grid and every content depth, increasing.
    pub focus_diopters: Vec<f64>,
    /// The focus grid as the file gave it.
    pub focus_grid_diopters: Vec<f64>,
    /// Grating frequencies, cpd, increasing.
    pub frequencies_cpd: Vec<f64>,
    /// Grating orientations, degrees in [0, 180), increasing: 0 first.
    pub orientations_deg: Vec<f64>,
    /// Orientations other than 0 measured at every focus, not only with the eye on the content.
    pub orientations_through_focus: bool,
    /// The direction the charts face ([`super::field`]; absent from `study.json` on the axis).
    #[serde(skip_serializing_if = "crate::optics::eye::Gaze::is_ahead")]
    pub field_deg: crate::optics::eye::Gaze,
    /// The patterns' mean and contrast.
    pub target: TargetSpec,
    /// The retina's sampling.
    pub retina: RetinaSpec,
    /// Size of one retina pixel, degrees (1 / pixels per degree).
    pub retina_pixel_deg: f64,
    /// The retina's Nyquist frequency, cpd.
    pub retina_nyquist_cpd: f64,
    /// Replicates and samples per pixel.
    pub measurement: SamplingSpec,
    /// The eye-model settings as the file gave them (absent: the thin lens).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eye: Option<crate::experiment::EyeModelSettings>,
    /// The eye beyond the thin lens they ask for.
    #[serde(skip)]
    pub eye_optics: crate::optics::eye::EyeOpticsSpec,
    /// Where the eye is (`[eye] gaze_deg`, `centre_of_rotation_mm`, `position`) and the pupil
    /// PupilCenter renders for; the chart goes with the eye.
    #[serde(skip)]
    pub eye_place: super::field::EyePlacement,
    /// `[display_render]` as the file gave it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub display_render: Option<super::field::StudyRenderSpec>,
    /// What predicts the eye's focus.
    pub accommodation: AccommodationSpec,
    /// The display-limit settings.
    pub limits: LimitsSpec,
}

fn method_names<S: serde::Serializer>(m: &[Method], s: S) -> std::result::Result<S::Ok, S::Error> {
    s.collect_seq(m.iter().map(|m| m.to_string()))
}

impl Study {
    /// The default study (`studies/paper.toml`, built in), with `overrides` applied.
    pub fn paper(overrides: &[Override]) -> Result<Self> {
        Self::from_text(PAPER_STUDY, "builtin:paper (studies/paper.toml)", Path::new("."), overrides)
    }

    /// Reads a study file, applies `overrides`, validates.
    pub fn load(path: &Path, overrides: &[Override]) -> Result<Self> {
        let text = read_text(path)?;
        Self::from_text(&text, &path.display().to_string(), &base_dir(path), overrides)
    }

    /// Parses `text` (named `source` in errors); relative paths resolve against `base`.
    pub fn from_text(text: &str, source: &str, base: &Path, overrides: &[Override]) -> Result<Self> {
        let path = Path::new(source);
        let spec: StudySpec = if overrides.is_empty() {
            toml::from_str(text).map_err(|e| toml_error(path, text, &e))?
        } else {
            let mut doc: toml::Value = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
            for o in overrides {
                o.apply(&mut doc).map_err(|e| Error::invalid(source, &o.key, e))?;
            }
            StudySpec::deserialize(doc).map_err(|e| Error::parse(path, format!("after --set: {}", e.message())))?
        };
        Self::from_spec(&spec, source, base)
    }

    /// Validates `spec` and resolves it.
    pub fn from_spec(spec: &StudySpec, source: &str, base: &Path) -> Result<Self> {
        let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
        if !crate::io::output::is_plain_name(&spec.name) || spec.name.contains("..") {
            return Err(bad(
                "name",
                format!("`{}` must use only letters, digits, -, _ and . (it names the output folder)", spec.name),
            ));
        }
        let display = load_display(&spec.display, base)?;
        display.validate(&spec.display)?;
        let methods = study_methods(spec, source)?;
        crate::optics::limits::RETINA_DISTANCE.check(source, "retina_distance_mm", spec.retina_distance_mm)?;
        let depths = content_depths(spec, source, &display)?;

        let grid = spec.focus_diopters.expand(source, "focus_diopters")?;
        for (i, f) in grid.iter().enumerate() {
            crate::optics::limits::FOCUS_DIOPTERS.check(source, &format!("focus_diopters[{i}]"), *f)?;
        }
        let mut focus: Vec<f64> = grid.iter().copied().chain(depths.iter().map(|d| d.diopters)).collect();
        focus.sort_by(f64::total_cmp);
        focus.dedup_by(|a, b| (*a - *b).abs() < 1e-9);

        let r = spec.retina;
        check_retina(&r, source)?;
        let frequencies = study_frequencies(spec, source)?;
        let nyquist = 0.5 * r.pixels_per_degree;
        check_target_and_measurement(spec, source)?;
        let eye = spec.eye.clone().unwrap_or_default();
        let (pupil, auto_pupil) = eye.study_pupil(spec.pupil_diameter_mm, spec.target.mean, &display, source)?;
        check_listed_frequencies(spec, source, &frequencies)?;
        let orientations = study_orientations(spec, source)?;
        let eye_optics = eye.optics_spec(pupil, source, "eye.")?.with_diffraction(
            spec.optics.as_ref().map(|o| o.diffraction).unwrap_or_default(),
            spec.eye.as_ref().is_some_and(|e| e.spectrum.is_some()),
        );
        let eye_place = super::field::EyePlacement::resolve(
            &eye,
            spec.display_render.as_ref(),
            &eye_optics.model,
            (&display, &methods),
            source,
        )?;
        let study = Study {
            name: spec.name.clone(),
            description: spec.description.clone(),
            source: source.to_string(),
            display_source: spec.display.clone(),
            display,
            methods,
            pupil_diameter_mm: pupil,
            auto_pupil,
            retina_distance_mm: spec.retina_distance_mm,
            depths,
            focus_diopters: focus,
            focus_grid_diopters: grid,
            frequencies_cpd: frequencies,
            orientations_deg: orientations,
            orientations_through_focus: spec.orientations_through_focus,
            field_deg: spec.field_deg.unwrap_or_default(),
            target: spec.target,
            retina: r,
            retina_pixel_deg: 1.0 / r.pixels_per_degree,
            retina_nyquist_cpd: nyquist,
            measurement: spec.measurement,
            eye: spec.eye.clone(),
            eye_optics,
            eye_place,
            display_render: spec.display_render.clone(),
            accommodation: spec.accommodation,
            limits: spec.limits.clone(),
        };
        super::field::check_field(&study, source)?;
        Ok(study)
    }

    /// The index of frequency `f` (one of the study's).
    pub fn frequency_index(&self, f: f64) -> Option<usize> {
        self.frequencies_cpd.iter().position(|g| (g - f).abs() < 1e-9)
    }

    /// The index of orientation `o` degrees (one of the study's; 0 is index 0).
    pub fn orientation_index(&self, o: f64) -> Option<usize> {
        self.orientations_deg.iter().position(|g| (g - o).abs() < 1e-9)
    }

    /// The index of focus `d` diopters (one of the measured focuses).
    pub fn focus_index(&self, d: f64) -> Option<usize> {
        self.focus_diopters.iter().position(|g| (g - d).abs() < 1e-9)
    }
}

/// The grating orientations measured when the study names none.
pub const DEFAULT_ORIENTATIONS_DEG: [f64; 4] = [0.0, 45.0, 90.0, 135.0];

/// The study's grating orientations: each in [0, 180) degrees, listed once, 0 among them (the
/// accommodation rules and the display limits read the 0-degree gratings); increasing.
fn study_orientations(spec: &StudySpec, source: &str) -> Result<Vec<f64>> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let mut v = spec.orientations_deg.clone().unwrap_or_else(|| DEFAULT_ORIENTATIONS_DEG.to_vec());
    for (i, o) in v.iter().enumerate() {
        let field = format!("orientations_deg[{i}]");
        if !(o.is_finite() && (0.0..180.0).contains(o)) {
            return Err(bad(
                &field,
                format!("must be in [0, 180) degrees (a grating at 180 + a is the one at a), got {o}"),
            ));
        }
        // Orientations are angles modulo 180 degrees: 179.9999999999 is the grating at 0.
        let same = |p: &f64| {
            let d = (p - o).rem_euclid(180.0);
            d.min(180.0 - d) < 1e-9
        };
        if let Some(p) = v[..i].iter().find(|p| same(p)) {
            return Err(bad(
                &field,
                format!("{o} degrees is the grating at {p} degrees (orientations are equal modulo 180); list it once"),
            ));
        }
    }
    if !v.contains(&0.0) {
        return Err(bad(
            "orientations_deg",
            format!("must include 0 (vertical bars: the accommodation rules and display limits use them), got {v:?}"),
        ));
    }
    if v.len() > 12 {
        return Err(bad("orientations_deg", format!("at most 12 orientations, got {}", v.len())));
    }
    v.sort_by(f64::total_cmp);
    Ok(v)
}

/// The study's methods, parsed, each listed once.
fn study_methods(spec: &StudySpec, source: &str) -> Result<Vec<Method>> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let mut methods = Vec::new();
    for (i, m) in spec.methods.iter().enumerate() {
        let method: Method = m.parse().map_err(|e| bad(&format!("methods[{i}]"), e))?;
        if methods.contains(&method) {
            return Err(bad(&format!("methods[{i}]"), format!("{method} is listed twice")));
        }
        methods.push(method);
    }
    Ok(methods)
}

/// Content depths: dioptres and millimetres, merged, far to near, each beyond the LCD.
fn content_depths(spec: &StudySpec, source: &str, display: &Display) -> Result<Vec<Depth>> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let mut depths = Vec::new();
    for (i, d) in spec.content_diopters.expand_any(source, "content_diopters")?.into_iter().enumerate() {
        if !(d > 0.0 && d <= 100.0) {
            return Err(bad(&format!("content_diopters[{i}]"), format!("must be in (0, 100] D, got {d}")));
        }
        depths.push(Depth { diopters: d, mm: 1000.0 / d });
    }
    for (i, &mm) in spec.content_mm.iter().enumerate() {
        if !(mm.is_finite() && mm >= 10.0) {
            return Err(bad(&format!("content_mm[{i}]"), format!("must be finite and at least 10 mm, got {mm}")));
        }
        depths.push(Depth { diopters: 1000.0 / mm, mm });
    }
    if depths.is_empty() {
        return Err(bad("content_diopters", "no content depth: give content_diopters or content_mm".into()));
    }
    depths.sort_by(|a, b| a.diopters.total_cmp(&b.diopters));
    depths.dedup_by(|a, b| (a.diopters - b.diopters).abs() < 1e-9);
    for d in &depths {
        if d.mm <= display.lcd_z() {
            return Err(bad(
                "content_diopters",
                format!("content at {:.1} mm is not beyond the LCD ({:.1} mm from the pupil)", d.mm, display.lcd_z()),
            ));
        }
    }
    Ok(depths)
}

/// Checks the retina's sampling: positive sizes, whole pixel counts of 4 to 4096 per window,
/// an edge angle of 1 to 20 degrees and at most 60 degrees of field.
fn check_retina(r: &RetinaSpec, source: &str) -> Result<()> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let positive = |field: &str, v: f64| -> Result<()> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(bad(field, format!("must be a positive finite number, got {v}")))
        }
    };
    positive("retina.pixels_per_degree", r.pixels_per_degree)?;
    if r.pixels_per_degree > 1000.0 {
        return Err(bad("retina.pixels_per_degree", format!("at most 1000, got {}", r.pixels_per_degree)));
    }
    for (i, w) in r.window_deg.iter().enumerate() {
        positive(&format!("retina.window_deg[{i}]"), *w)?;
    }
    for (i, w) in r.edge_window_deg.iter().enumerate() {
        positive(&format!("retina.edge_window_deg[{i}]"), *w)?;
    }
    if !(r.guard_deg.is_finite() && r.guard_deg >= 0.0) {
        return Err(bad("retina.guard_deg", format!("must be finite and >= 0, got {}", r.guard_deg)));
    }
    if !(r.edge_angle_deg.is_finite() && (1.0..=20.0).contains(&r.edge_angle_deg)) {
        return Err(bad(
            "retina.edge_angle_deg",
            format!("must be between 1 and 20 degrees, got {}", r.edge_angle_deg),
        ));
    }
    let pixels = |deg: f64| deg * r.pixels_per_degree;
    for (field, deg) in [
        ("retina.window_deg[0]", r.window_deg[0]),
        ("retina.window_deg[1]", r.window_deg[1]),
        ("retina.edge_window_deg[0]", r.edge_window_deg[0]),
        ("retina.edge_window_deg[1]", r.edge_window_deg[1]),
    ] {
        let n = pixels(deg);
        if (n - n.round()).abs() > 1e-6 || n.round() < 4.0 || n.round() > 4096.0 {
            return Err(bad(
                field,
                format!("{deg} degrees is {n} retina pixels: it must be a whole number of pixels, 4 to 4096"),
            ));
        }
    }
    let half_field = 0.5 * (r.window_deg[0].max(r.edge_window_deg[0]) + 2.0 * r.guard_deg);
    if half_field > 30.0 {
        return Err(bad("retina.guard_deg", "windows and guards span more than 60 degrees".into()));
    }
    Ok(())
}

/// The grating frequencies, cycles per degree, sorted: each below the retina's Nyquist, listed
/// once, with a whole number of periods over the window.
fn study_frequencies(spec: &StudySpec, source: &str) -> Result<Vec<f64>> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let r = spec.retina;
    let frequencies = spec.frequencies_cpd.expand(source, "frequencies_cpd")?;
    let nyquist = 0.5 * r.pixels_per_degree;
    for (i, f) in frequencies.iter().enumerate() {
        let field = format!("frequencies_cpd[{i}]");
        if !(*f > 0.0 && *f < nyquist) {
            return Err(bad(&field, format!("must be in (0, {nyquist}) cpd (below the retina's Nyquist), got {f}")));
        }
        let periods = f * r.window_deg[0];
        if (periods - periods.round()).abs() > 1e-6 {
            return Err(bad(
                &field,
                format!(
                    "{f} cpd is {periods} periods over the {} degree window (retina.window_deg[0]): the window \
                     must hold a whole number of periods of every frequency, so that frequencies do not leak \
                     into each other's coefficients",
                    r.window_deg[0]
                ),
            ));
        }
        if frequencies[..i].iter().any(|g| (g - f).abs() < 1e-9) {
            return Err(bad(&field, format!("{f} cpd is listed twice")));
        }
    }
    let mut frequencies = frequencies;
    frequencies.sort_by(f64::total_cmp);
    Ok(frequencies)
}

/// Checks the target's mean and contrast (in (0, 1]) and the measurement's replicates (3 to 64)
/// and samples per pixel (1 to 65536).
fn check_target_and_measurement(spec: &StudySpec, source: &str) -> Result<()> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let t = spec.target;
    if !(t.mean.is_finite() && t.mean > 0.0 && t.mean <= 1.0) {
        return Err(bad("target.mean", format!("must be in (0, 1], got {}", t.mean)));
    }
    if !(t.contrast.is_finite() && t.contrast > 0.0 && t.contrast <= 1.0) {
        return Err(bad("target.contrast", format!("must be in (0, 1], got {}", t.contrast)));
    }
    let m = spec.measurement;
    if !(3..=64).contains(&m.replicates) {
        return Err(bad("measurement.replicates", format!("must be between 3 and 64, got {}", m.replicates)));
    }
    if !(1..=65_536).contains(&m.samples_per_pixel) {
        return Err(bad(
            "measurement.samples_per_pixel",
            format!("must be between 1 and 65536, got {}", m.samples_per_pixel),
        ));
    }
    Ok(())
}

/// Checks that the accommodation and limits frequencies are among `frequencies` (sorted), the
/// area limit above the lowest one, and the limits' contrast in (0, 1).
fn check_listed_frequencies(spec: &StudySpec, source: &str, frequencies: &[f64]) -> Result<()> {
    let bad = |field: &str, msg: String| Error::invalid(source, field, msg);
    let listed = |field: &str, f: f64| -> Result<()> {
        if frequencies.iter().any(|g| (g - f).abs() < 1e-9) {
            Ok(())
        } else {
            Err(bad(field, format!("{f} cpd is not one of frequencies_cpd {frequencies:?}")))
        }
    };
    listed("accommodation.frequency_cpd", spec.accommodation.frequency_cpd)?;
    listed("accommodation.area_limit_cpd", spec.accommodation.area_limit_cpd)?;
    if spec.accommodation.area_limit_cpd <= frequencies[0] {
        return Err(bad(
            "accommodation.area_limit_cpd",
            format!("must be above the lowest frequency {} cpd (an area needs two)", frequencies[0]),
        ));
    }
    if !(spec.limits.contrast > 0.0 && spec.limits.contrast < 1.0) {
        return Err(bad("limits.contrast", format!("must be in (0, 1), got {}", spec.limits.contrast)));
    }
    for (i, f) in spec.limits.frequencies_cpd.iter().enumerate() {
        listed(&format!("limits.frequencies_cpd[{i}]"), *f)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(key: &str, value: &str) -> Result<Study> {
        Study::paper(&[Override::new(key, crate::overrides::parse_value(value).unwrap()).unwrap()])
    }

    #[test]
    fn the_paper_study_resolves_as_the_issue_states() {
        let s = Study::paper(&[]).unwrap();
        assert_eq!(s.name, "paper");
        assert_eq!(s.pupil_diameter_mm, 5.0);
        assert_eq!(s.methods.iter().map(|m| m.name()).collect::<Vec<_>>(), ["LC", "PC", "LA"]);
        // 0.5..3.5 D and 300, 400, 600 mm; 400 mm is 2.5 D, merged.
        let d: Vec<f64> = s.depths.iter().map(|d| (d.diopters * 1e6).round() / 1e6).collect();
        assert_eq!(d, [0.5, 1.0, 1.5, 1.666667, 2.0, 2.5, 3.0, 3.333333, 3.5]);
        assert_eq!(s.focus_grid_diopters.len(), 17);
        assert_eq!(s.focus_grid_diopters[16], 4.0);
        // The grid plus 600 mm and 300 mm.
        assert_eq!(s.focus_diopters.len(), 19);
        assert!(s.focus_index(1000.0 / 300.0).is_some());
        assert_eq!(s.retina_pixel_deg, 1.0 / 64.0);
        assert_eq!(s.frequencies_cpd[0], 0.5);
        // Beyond the paper display's Nyquist (about 5.8 cpd at the CDP).
        assert!(*s.frequencies_cpd.last().unwrap() > 6.0);
        assert_eq!(s.orientations_deg, [0.0, 45.0, 90.0, 135.0]);
        assert_eq!(with("orientations_deg", "[90, 0]").unwrap().orientations_deg, [0.0, 90.0]);
    }

    #[test]
    fn bad_values_name_the_file_and_field() {
        for (key, value, field) in [
            ("pupil_diameter_mm", "-1", "pupil_diameter_mm"),
            ("methods", "[\"LC\", \"XX\"]", "methods[1]"),
            ("methods", "[\"LC\", \"LC\"]", "methods[1]"),
            ("frequencies_cpd", "[0.5, 0.75]", "frequencies_cpd[1]"),
            ("frequencies_cpd", "[0.5, 40]", "frequencies_cpd[1]"),
            ("content_diopters", "[1, -2]", "content_diopters[1]"),
            ("content_mm", "[5]", "content_mm[0]"),
            ("focus_diopters", "{ from = 1, to = 0, step = 0.5 }", "focus_diopters"),
            ("retina.window_deg", "[2.01, 0.25]", "retina.window_deg[0]"),
            ("measurement.replicates", "2", "measurement.replicates"),
            ("orientations_deg", "[0, 180]", "orientations_deg[1]"),
            ("orientations_deg", "[0, -45]", "orientations_deg[1]"),
            ("orientations_deg", "[0, nan]", "orientations_deg[1]"),
            ("orientations_deg", "[0, 45, 45]", "orientations_deg[2]"),
            ("orientations_deg", "[45, 90]", "orientations_deg"),
            ("accommodation.frequency_cpd", "2.5", "accommodation.frequency_cpd"),
            ("limits.frequencies_cpd", "[1, 9]", "limits.frequencies_cpd[1]"),
            ("target.contrast", "0", "target.contrast"),
            ("name", "\"../x\"", "name"),
        ] {
            let e = with(key, value).unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("studies/paper.toml"), "{key}={value}: {e}");
        }
        let e = with("nonsense", "1").unwrap_err().to_string();
        assert!(e.contains("nonsense"), "{e}");
    }
}
