//! Experiments: the paper's assessment (Sec. 4, Table 1, Fig. 3) as data, and the `assess`
//! pipeline that runs one: render the display image of every method, simulate what each eye
//! case perceives, render the ground truth, score with PSNR and SSIM, and write every output.

use std::borrow::Borrow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::accel::analytic::AnalyticRects;
use crate::error::{Error, Result};
use crate::io::config::{self, read_text};
use crate::measure::spec::{EstimatorKind, MeasurementSpec};
use crate::measure::stats::Estimate;
use crate::metrics::{self, SsimConstants};
use crate::optics::{Aperture, Display, Eye, Focus, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::backend::resolve;
use crate::render::retina::{simulate_stack, DisplayStack};
use crate::render::{
    ground_truth, render_display_image_with_depth, with_fields, BackendChoice, DisplayRenderSettings, FacingPlanes,
    Method, RadianceField,
};
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
}

impl Default for DisplayRenderSpec {
    fn default() -> Self {
        Self { la_grid: 5, samples_per_pixel: 1, reference_plane_z: 0.0, eye_position: None }
    }
}

/// `[eye]`: the eye shared by all eye cases.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EyeSpec {
    /// v0, mm.
    pub retina_distance: f64,
    /// Pupil diameter, mm.
    pub pupil_diameter: f64,
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
}

impl Default for EyeSpec {
    fn default() -> Self {
        Self {
            retina_distance: 17.0,
            pupil_diameter: 5.0,
            pupil_grid: 8,
            retina_resolution: 512,
            retina_half_tangent: 0.3,
            retina_samples: 1,
            position: [0.0; 3],
        }
    }
}

/// `[[eye_cases]]`: one row of Table 1.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EyeCaseSpec {
    /// Used in file names (`gt_<name>.exr`) and as the table's row label.
    pub name: String,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub pinhole: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_mm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_diopters: Option<f64>,
}

/// An experiment file.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExperimentSpec {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// `builtin:paper` or a scene TOML path (relative to this file).
    #[serde(default = "builtin")]
    pub scene: String,
    /// `builtin:paper` or a display TOML / OpenCV YAML path (relative to this file).
    #[serde(default = "builtin")]
    pub display: String,
    /// "LC", "PC", "LA" (grid from `display_render.la_grid`), or "LA<k>".
    #[serde(default = "default_methods")]
    pub methods: Vec<String>,
    /// "wang2004" (default) or "framework-8bit".
    #[serde(default)]
    pub ssim: SsimConstants,
    /// `[measurement]`: the estimator, its targets and budget (none: the grid estimator).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurement: Option<MeasurementSpec>,
    #[serde(default)]
    pub display_render: DisplayRenderSpec,
    #[serde(default)]
    pub eye: EyeSpec,
    pub eye_cases: Vec<EyeCaseSpec>,
}

impl ExperimentSpec {
    fn paper_cases() -> Vec<EyeCaseSpec> {
        let case = |name: &str, focus: Option<f64>| EyeCaseSpec {
            name: name.into(),
            pinhole: focus.is_none(),
            focus_mm: focus,
            focus_diopters: None,
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
            eye: EyeSpec::default(),
            eye_cases: Self::paper_cases(),
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
            eye: EyeSpec { pupil_diameter: 2.0, pupil_grid: 5, ..EyeSpec::default() },
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

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

/// An eye case, resolved.
#[derive(Clone, Debug)]
pub struct EyeCase {
    pub name: String,
    pub eye: Eye,
}

/// A resolved experiment: everything needed to run it.
#[derive(Clone, Debug)]
pub struct Experiment {
    pub name: String,
    pub source: String,
    pub scene: Scene,
    pub display: Display,
    pub methods: Vec<Method>,
    pub render: DisplayRenderSettings,
    pub retina: Retina,
    pub cases: Vec<EyeCase>,
    pub ssim: SsimConstants,
    /// How Table 1 is measured (`[measurement]`; the grid estimator when absent).
    pub measurement: MeasurementSpec,
    pub spec: ExperimentSpec,
}

impl Experiment {
    /// Resolves a spec; `source` names its file (for errors), `base` resolves relative paths.
    pub fn from_spec(spec: ExperimentSpec, source: &str, base: &Path) -> Result<Self> {
        // Name the experiment file and its field as well as the file that failed.
        let display = config::load_display(&spec.display, base)
            .map_err(|e| Error::invalid(source, "display", format!("cannot load `{}`: {e}", spec.display)))?;
        let scene = config::load_scene(&spec.scene, base)
            .map_err(|e| Error::invalid(source, "scene", format!("cannot load `{}`: {e}", spec.scene)))?;
        let dr = &spec.display_render;
        let mut methods = Vec::new();
        for (i, m) in spec.methods.iter().enumerate() {
            let method: Method = m.parse().map_err(|e: String| Error::invalid(source, format!("methods[{i}]"), e))?;
            let method = match (method, m.trim().eq_ignore_ascii_case("LA")) {
                (Method::LensletAverage { .. }, true) => Method::LensletAverage { grid: dr.la_grid },
                (other, _) => other,
            };
            if methods.iter().any(|x: &Method| x.short_name() == method.short_name()) {
                return Err(Error::invalid(
                    source,
                    format!("methods[{i}]"),
                    format!("{} appears twice (output file names would collide)", method.short_name()),
                ));
            }
            methods.push(method);
        }
        if methods.is_empty() {
            return Err(Error::invalid(source, "methods", "list at least one of LC, PC, LA"));
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
        let e = &spec.eye;
        let position = DVec3::from_array(e.position);
        let render = DisplayRenderSettings {
            samples_per_pixel: dr.samples_per_pixel,
            reference_plane_z: dr.reference_plane_z,
            eye_position: dr.eye_position.map(DVec3::from_array).unwrap_or(position),
        };
        if !render.eye_position.is_finite() {
            return Err(Error::invalid(source, "display_render.eye_position", "must be finite"));
        }
        let retina = Retina {
            resolution: e.retina_resolution,
            half_tangent: e.retina_half_tangent,
            samples_per_pixel: e.retina_samples,
        };
        retina.validate(source).map_err(|err| prefix_field(err, "eye."))?;
        if spec.eye_cases.is_empty() {
            return Err(Error::invalid(source, "eye_cases", "list at least one eye case"));
        }
        let mut cases = Vec::new();
        for (i, c) in spec.eye_cases.iter().enumerate() {
            let field = format!("eye_cases[{i}]");
            if c.name.is_empty() || !c.name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_') {
                return Err(Error::invalid(
                    source,
                    format!("{field}.name"),
                    format!("`{}` must be non-empty and use only letters, digits, - and _ (it names files)", c.name),
                ));
            }
            if cases.iter().any(|x: &EyeCase| x.name == c.name) {
                return Err(Error::invalid(source, format!("{field}.name"), format!("`{}` appears twice", c.name)));
            }
            let aperture = match (c.pinhole, c.focus_mm, c.focus_diopters) {
                (true, None, None) => Aperture::Pinhole,
                (false, Some(mm), None) => {
                    Aperture::ThinLens { pupil_diameter: e.pupil_diameter, focus: Focus::Millimetres(mm) }
                }
                (false, None, Some(d)) => {
                    Aperture::ThinLens { pupil_diameter: e.pupil_diameter, focus: Focus::Diopters(d) }
                }
                _ => {
                    return Err(Error::invalid(
                        source,
                        field,
                        "give exactly one of `pinhole = true`, `focus_mm` or `focus_diopters`",
                    ))
                }
            };
            let eye = Eye { retina_distance: e.retina_distance, aperture, pupil_grid: e.pupil_grid, position };
            eye.validate(source).map_err(|err| prefix_field(err, &format!("{field} / eye.")))?;
            cases.push(EyeCase { name: c.name.clone(), eye });
        }
        if methods.contains(&Method::PupilCenter) {
            crate::render::display_image::check_pupil_center(&display, render.eye_position)?;
        }
        let measurement = spec.measurement.clone().unwrap_or_else(MeasurementSpec::grid);
        measurement.validate(source)?;
        measurement.check_grid_only(source, e.pupil_grid, e.retina_samples)?;
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
            spec,
        })
    }

    /// Loads an experiment file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        let spec: ExperimentSpec = toml::from_str(&text).map_err(|e| config::toml_error(path, &text, &e))?;
        Self::from_spec(spec, &path.display().to_string(), &config::base_dir(path))
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

fn prefix_field(err: Error, prefix: &str) -> Error {
    match err {
        Error::Invalid { source_name, field, message } => {
            Error::Invalid { source_name, field: format!("{prefix}{field}"), message }
        }
        other => other,
    }
}

/// One score: a method under an eye case. The converged estimator adds the 95% half-widths
/// (`ci95`, `channels_ci95` in `psnr` and `ssim`), its samples and whether the targets were met.
#[derive(Clone, Debug, Serialize)]
pub struct Score {
    pub method: String,
    pub eye_case: String,
    pub psnr: Estimate,
    pub ssim: Estimate,
    /// Samples per retina pixel, over all replicates (converged estimator).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples_per_pixel: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replicates: Option<usize>,
    /// Both 95% half-widths within the experiment's targets.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_met: Option<bool>,
}

/// Wall time of one stage.
#[derive(Clone, Debug, Serialize)]
pub struct StageTime {
    pub stage: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eye_case: Option<String>,
    pub seconds: f64,
}

/// What `assess` produced.
#[derive(Clone, Debug, Serialize)]
pub struct AssessReport {
    pub experiment: String,
    pub ssim_constants: String,
    pub backend: String,
    pub threads: usize,
    pub display: String,
    pub central_depth_plane_mm: Option<f64>,
    pub scores: Vec<Score>,
    pub stages: Vec<StageTime>,
    pub total_seconds: f64,
    pub settings: ExperimentSpec,
}

/// What the display EXRs' `Z` channel holds (also written into their headers).
pub const Z_CHANNEL_NOTE: &str = "hit distance in mm along each camera ray from its start on the reference plane; \
     mean over the pixel's rays that hit (LA, multi-sample), +inf where none hit";

/// Options of a run.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunOptions {
    pub quiet: bool,
    /// Scene intersection backend (`auto`: analytic for rectangle-only scenes, else Embree).
    pub backend: BackendChoice,
}

/// Runs an experiment and writes every output into `out`.
pub fn assess(exp: &Experiment, out: &Path, opts: RunOptions) -> Result<AssessReport> {
    let start = Instant::now();
    prepare_output_dir(out)?;
    // The paper's kind of scene: the fused planar kernel, called directly (no virtual call per
    // ray) for both images and depths. Everything else: the backend chosen by `with_fields`.
    if resolve(&exp.scene, opts.backend) == BackendChoice::Analytic && exp.scene.is_analytic() {
        let backend = AnalyticRects::new(&exp.scene)?;
        if let Some(fast) = FacingPlanes::new(&exp.scene, &backend) {
            return assess_with(exp, out, opts, &fast, &fast, "analytic (fused planar kernel)", start);
        }
    }
    with_fields(&exp.scene, opts.backend, |fields| {
        assess_with(exp, out, opts, fields.shade, fields.with_depth, fields.name, start)
    })
}

/// Creates the output directory and checks it can be written, before any long computation.
pub fn prepare_output_dir(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let probe = out.join(".inimtrace-write-test");
    std::fs::write(&probe, b"").map_err(|e| Error::io(out, e))?;
    let _ = std::fs::remove_file(&probe);
    // An interrupted earlier run must not look complete: the report is written last.
    let _ = std::fs::remove_file(out.join("results.json"));
    Ok(())
}

struct Job<'a> {
    stem: String,
    image: &'a RgbImage,
    depth: Option<&'a [f32]>,
    attributes: Vec<(&'static str, String)>,
}

#[allow(clippy::too_many_arguments)]
fn assess_with<S: RadianceField + ?Sized, D: RadianceField + ?Sized>(
    exp: &Experiment,
    out: &Path,
    opts: RunOptions,
    shade: &S,
    with_depth: &D,
    backend_name: &str,
    start: Instant,
) -> Result<AssessReport> {
    let mut stages = Vec::new();
    let display = &exp.display;

    // 1-3. Display images, then per eye case the ground truth and the perceived image of every
    // method, then the scores: the same stage functions `inimtrace bench` times.
    let (displays, depths) = render_display_images(exp, with_depth, opts.quiet, &mut stages)?;
    let stack = pack_display_images(exp, &displays.iter().collect::<Vec<_>>(), &mut stages)?;
    // The converged estimator (src/measure/) or the grid one.
    let (gts, sims, scores) = match crate::measure::run::table1(exp, shade, &stack, opts.quiet, &mut stages)? {
        Some(table) => table,
        None => {
            let mut gts = Vec::new();
            let mut sims = Vec::new();
            for case in &exp.cases {
                gts.push(ground_truth_image(exp, case, shade, opts.quiet, &mut stages));
                sims.push(perceived_images(exp, case, &stack, opts.quiet, &mut stages)?);
            }
            let scores = table1_scores(exp, &gts, &sims, &mut stages)?;
            (gts, sims, scores)
        }
    };
    drop(stack);

    // 4. Images: EXR + PNG preview each, written in parallel.
    let t = Instant::now();
    let mut jobs = Vec::new();
    let common = |kind: &str| -> Vec<(&'static str, String)> {
        vec![
            ("inimtrace:kind", kind.to_string()),
            ("inimtrace:experiment", exp.name.clone()),
            ("inimtrace:units", "linear radiance (albedo units); lengths in mm".into()),
            ("inimtrace:version", env!("CARGO_PKG_VERSION").into()),
        ]
    };
    let eye_attrs = |case: &EyeCase| -> Vec<(&'static str, String)> {
        let mut v = vec![("inimtrace:eye_case", case.name.clone())];
        match case.eye.aperture {
            Aperture::Pinhole => v.push(("inimtrace:eye", "pinhole".into())),
            Aperture::ThinLens { pupil_diameter, focus } => {
                v.push(("inimtrace:eye", "thin lens".into()));
                v.push(("inimtrace:focus_mm", format!("{}", focus.distance_mm())));
                v.push(("inimtrace:focus_diopters", format!("{}", focus.diopters())));
                v.push(("inimtrace:pupil_diameter_mm", format!("{pupil_diameter}")));
            }
        }
        match scores.iter().find(|s| s.eye_case == case.name).and_then(|s| s.samples_per_pixel) {
            Some(spp) => v.extend(crate::measure::run::exr_attributes(exp, spp)),
            None => {
                v.push(("inimtrace:pupil_samples", case.eye.pupil_samples().len().to_string()));
                v.push(("inimtrace:retina_samples_per_pixel", (exp.retina.samples_per_pixel.pow(2)).to_string()));
            }
        }
        v.push(("inimtrace:retina_half_tangent", exp.retina.half_tangent.to_string()));
        v
    };
    for ((m, img), depth) in exp.methods.iter().zip(&displays).zip(&depths) {
        let mut attributes = common("display image");
        attributes.push(("inimtrace:method", m.to_string()));
        attributes.push(("inimtrace:display", display.summary()));
        attributes.push(("inimtrace:samples_per_pixel", exp.render.samples_per_pixel.pow(2).to_string()));
        attributes.push(("inimtrace:backend", backend_name.to_string()));
        if depth.is_some() {
            attributes.push(("inimtrace:Z", Z_CHANNEL_NOTE.into()));
        }
        jobs.push(Job { stem: format!("display_{}", m.short_name()), image: img, depth: depth.as_deref(), attributes });
    }
    for (c, case) in exp.cases.iter().enumerate() {
        let mut attributes = common("ground truth retinal image");
        attributes.extend(eye_attrs(case));
        jobs.push(Job { stem: format!("gt_{}", case.name), image: &gts[c], depth: None, attributes });
        for (k, m) in exp.methods.iter().enumerate() {
            let mut attributes = common("simulated retinal image");
            attributes.push(("inimtrace:method", m.to_string()));
            attributes.extend(eye_attrs(case));
            jobs.push(Job {
                stem: format!("sim_{}_{}", m.short_name(), case.name),
                image: &sims[c][k],
                depth: None,
                attributes,
            });
        }
    }
    // Biggest first so the two cores finish together.
    jobs.sort_by_key(|j| std::cmp::Reverse(j.image.pixels.len()));
    let figure_rows: Vec<(&str, Vec<&RgbImage>)> = exp
        .cases
        .iter()
        .enumerate()
        .map(|(c, case)| (case.name.as_str(), std::iter::once(&gts[c]).chain(sims[c].iter()).collect()))
        .collect();
    let mut labels = vec!["GT"];
    labels.extend(exp.methods.iter().map(|m| m.short_name()));
    let (image_result, figure_result) = rayon::join(
        || {
            jobs.par_iter().try_for_each(|j| -> Result<()> {
                let attrs: Vec<(&str, String)> = j.attributes.iter().map(|(k, v)| (*k, v.clone())).collect();
                crate::io::exr::write_rgb(&out.join(format!("{}.exr", j.stem)), j.image, j.depth, &attrs)?;
                crate::io::png::write_preview(&out.join(format!("{}.png", j.stem)), j.image)
            })
        },
        || crate::io::figure::write_montage(&out.join("figure.png"), &figure_rows, &labels),
    );
    image_result?;
    figure_result?;
    stage_time(&mut stages, "write_images", None, None, t);

    let report = AssessReport {
        experiment: exp.name.clone(),
        ssim_constants: exp.ssim.name().into(),
        backend: backend_name.into(),
        threads: rayon::current_num_threads(),
        display: display.summary(),
        central_depth_plane_mm: display.central_depth_plane(),
        scores,
        stages,
        total_seconds: start.elapsed().as_secs_f64(),
        settings: exp.spec.clone(),
    };
    write_reports(&report, exp, out)?;
    Ok(report)
}

fn stage_time(stages: &mut Vec<StageTime>, stage: &str, method: Option<&str>, case: Option<&str>, t: Instant) {
    stages.push(StageTime {
        stage: stage.into(),
        method: method.map(String::from),
        eye_case: case.map(String::from),
        seconds: t.elapsed().as_secs_f64(),
    });
}

/// Display images, one per method, and their depth planes (`None` where the field knows no
/// depths).
pub type DisplayImages = (Vec<RgbImage>, Vec<Option<Vec<f32>>>);

/// Stage 1 of [`assess`]: the display image of every method of `exp` and its depth plane (when
/// `with_depth` knows depths), each timed as a `render_display` stage.
pub fn render_display_images<D: RadianceField + ?Sized>(
    exp: &Experiment,
    with_depth: &D,
    quiet: bool,
    stages: &mut Vec<StageTime>,
) -> Result<DisplayImages> {
    let display = &exp.display;
    let mut displays = Vec::new();
    let mut depths = Vec::new();
    for m in &exp.methods {
        let t = Instant::now();
        let p = Progress::new(display.lcd.rows() as u64, &format!("display image {}", m.short_name()), quiet);
        let (img, depth) = render_display_image_with_depth(display, *m, &exp.render, with_depth, &p)?;
        p.finish();
        stage_time(stages, "render_display", Some(m.short_name()), None, t);
        displays.push(img);
        depths.push(depth);
    }
    Ok((displays, depths))
}

/// The display images interleaved for the simulation (`pack_display_images` stage).
pub fn pack_display_images(
    exp: &Experiment,
    displays: &[&RgbImage],
    stages: &mut Vec<StageTime>,
) -> Result<DisplayStack> {
    let t = Instant::now();
    let stack = DisplayStack::new(&exp.display, displays)?;
    stage_time(stages, "pack_display_images", None, None, t);
    Ok(stack)
}

/// Stage 2a of [`assess`]: the ground-truth retinal image of one eye case (`ground_truth` stage).
pub fn ground_truth_image<S: RadianceField + ?Sized>(
    exp: &Experiment,
    case: &EyeCase,
    shade: &S,
    quiet: bool,
    stages: &mut Vec<StageTime>,
) -> RgbImage {
    let t = Instant::now();
    let p = Progress::new(exp.retina.resolution as u64, &format!("ground truth {}", case.name), quiet);
    let gt = ground_truth(&case.eye, &exp.retina, shade, &p);
    p.finish();
    stage_time(stages, "ground_truth", None, Some(&case.name), t);
    gt
}

/// Stage 2b of [`assess`]: what the eye of one eye case perceives of every display image in
/// `stack`, all traced at once (`simulate_all_methods` stage).
pub fn perceived_images(
    exp: &Experiment,
    case: &EyeCase,
    stack: &DisplayStack,
    quiet: bool,
    stages: &mut Vec<StageTime>,
) -> Result<Vec<RgbImage>> {
    let t = Instant::now();
    let p = Progress::new(exp.retina.resolution as u64, &format!("simulate {}", case.name), quiet);
    let sims = simulate_stack(&exp.display, &case.eye, &exp.retina, stack, &p)?;
    p.finish();
    stage_time(stages, "simulate_all_methods", None, Some(&case.name), t);
    Ok(sims)
}

/// Stage 3 of [`assess`], Table 1: PSNR and SSIM of `sims[case][method]` against `gts[case]`,
/// for every eye case and method of `exp` (`metrics` stage). Scores are ordered by eye case,
/// then method.
pub fn table1_scores<G: Borrow<RgbImage> + Sync>(
    exp: &Experiment,
    gts: &[G],
    sims: &[Vec<RgbImage>],
    stages: &mut Vec<StageTime>,
) -> Result<Vec<Score>> {
    let t = Instant::now();
    if gts.len() != exp.cases.len()
        || sims.len() != exp.cases.len()
        || sims.iter().any(|s| s.len() != exp.methods.len())
    {
        return Err(Error::Unsupported(
            "table1_scores: one ground truth per eye case and one perceived image per method and eye case".into(),
        ));
    }
    let pairs: Vec<(usize, usize)> =
        (0..exp.cases.len()).flat_map(|c| (0..exp.methods.len()).map(move |m| (c, m))).collect();
    let scores: Vec<Score> = pairs
        .par_iter()
        .map(|&(c, m)| -> Result<Score> {
            Ok(Score {
                method: exp.methods[m].short_name().into(),
                eye_case: exp.cases[c].name.clone(),
                psnr: metrics::psnr(&sims[c][m], gts[c].borrow())?.into(),
                ssim: metrics::ssim(&sims[c][m], gts[c].borrow(), exp.ssim)?.into(),
                samples_per_pixel: None,
                replicates: None,
                target_met: None,
            })
        })
        .collect::<Result<_>>()?;
    stage_time(stages, "metrics", None, None, t);
    Ok(scores)
}

/// Table 1 as Markdown: rows are eye cases, columns PSNR per method | SSIM per method.
pub fn table_markdown(report: &AssessReport, exp: &Experiment) -> String {
    let methods: Vec<&str> = exp.methods.iter().map(|m| m.short_name()).collect();
    let mut s = format!(
        "# {}: PSNR (dB) and SSIM ({}) of the perceived retinal image against the ground truth\n\n",
        report.experiment, report.ssim_constants
    );
    s.push_str("| Eye |");
    for m in &methods {
        s.push_str(&format!(" PSNR {m} |"));
    }
    for m in &methods {
        s.push_str(&format!(" SSIM {m} |"));
    }
    s.push_str("\n|---|");
    s.push_str(&"---:|".repeat(2 * methods.len()));
    s.push('\n');
    for case in &exp.cases {
        s.push_str(&format!("| {} |", case.name));
        let find = |m: &str| report.scores.iter().find(|x| x.method == m && x.eye_case == case.name);
        for m in &methods {
            let v = find(m).map(crate::measure::report::psnr_cell).unwrap_or_default();
            s.push_str(&format!(" {v} |"));
        }
        // The framework's 8-bit constants pin SSIM near 1: show enough digits to tell methods apart.
        let digits = if exp.ssim == SsimConstants::Framework8Bit { 5 } else { 3 };
        for m in &methods {
            let v = find(m).map(|x| crate::measure::report::ssim_cell(x, digits)).unwrap_or_default();
            s.push_str(&format!(" {v} |"));
        }
        s.push('\n');
    }
    s.push_str(&format!(
        "\nPSNR: mean of the R, G, B channel PSNRs (linear values, peak 1). SSIM: Wang et al. 2004 window (11 x 11 Gaussian, sigma 1.5), constants `{}`, mean of channels.\n",
        report.ssim_constants
    ));
    if exp.measurement.estimator == EstimatorKind::Converged {
        s.push_str(&crate::measure::report::table_note(report, exp));
    }
    s
}

fn write_reports(report: &AssessReport, exp: &Experiment, out: &Path) -> Result<()> {
    let write = |name: &str, text: String| -> Result<()> {
        let path: PathBuf = out.join(name);
        std::fs::write(&path, text).map_err(|e| Error::io(&path, e))
    };
    write("table.md", table_markdown(report, exp))?;
    // psnr_ci95_db and ssim_ci95 (last, empty for the grid estimator): 95% half-widths.
    let mut csv =
        String::from("record,experiment,method,eye_case,channel,psnr_db,ssim,stage,seconds,psnr_ci95_db,ssim_ci95\n");
    let ci = |h: Option<f64>| h.map(csv_db).unwrap_or_default();
    for s in &report.scores {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            csv.push_str(&format!(
                "score,{},{},{},{},{},{},,,{},{}\n",
                report.experiment,
                s.method,
                s.eye_case,
                name,
                csv_db(s.psnr.channels[c]),
                s.ssim.channels[c],
                ci(s.psnr.channels_ci95.map(|h| h[c])),
                ci(s.ssim.channels_ci95.map(|h| h[c])),
            ));
        }
        csv.push_str(&format!(
            "score,{},{},{},mean,{},{},,,{},{}\n",
            report.experiment,
            s.method,
            s.eye_case,
            csv_db(s.psnr.mean),
            s.ssim.mean,
            ci(s.psnr.ci95),
            ci(s.ssim.ci95),
        ));
    }
    for st in &report.stages {
        csv.push_str(&format!(
            "stage,{},{},{},,,,{},{},,\n",
            report.experiment,
            st.method.as_deref().unwrap_or(""),
            st.eye_case.as_deref().unwrap_or(""),
            st.stage,
            st.seconds
        ));
    }
    csv.push_str(&format!("stage,{},,,,,,total,{},,\n", report.experiment, report.total_seconds));
    write("results.csv", csv)?;
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| Error::Unsupported(format!("cannot serialise the report: {e}")))?;
    // Last: its presence marks a complete run.
    write("results.json", json)
}

/// PSNR for CSV: identical images give "inf".
fn csv_db(db: f64) -> String {
    if db.is_finite() {
        format!("{db}")
    } else {
        "inf".into()
    }
}
