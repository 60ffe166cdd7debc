//! `inimtrace bench`: every rendering method on every backend that can render the scene,
//! reported as speed against error, and the convergence of each sampling parameter (LA's k x k
//! lenslet grid, the eye's n x n pupil grid, samples per retina pixel), so that a user can pick
//! the cheapest setting that is accurate enough.
//!
//! Every score is PSNR and SSIM (Wang 2004) against a high-sample reference of the same
//! quantity (not against the ground truth: that is `assess`'s Table 1):
//!
//! - **speed against error** (`series = "method"`): for every backend and method (LC, PC, LA at
//!   the paper's k = 5), at each of [`Sizes::display_samples`] samples per display pixel (the
//!   paper's one by default), the display image against the same method with 4 x 4 samples per
//!   pixel (LA: also an 8 x 8 lenslet grid), and the perceived image of every focused eye case
//!   of the paper's experiment (pupil grid 8, one sample per retina pixel) against the
//!   reference display image seen by a finer eye (pupil grid 12, 4 x 4 samples per retina
//!   pixel). Perceived rows time the display render plus the simulation, which is the cost of
//!   getting that image from scratch. References are rendered once, on the first (fastest)
//!   backend;
//! - **convergence** (`la_grid`, `pupil_grid`, `retina_samples`), on the fastest backend: the
//!   LA display image for k = 1..8 against k = 16; the LC perceived image at the first focused
//!   eye case for n = 2..16 against n = 32; the ground truth at that eye case for 1, 2 x 2,
//!   3 x 3, 4 x 4 samples per retina pixel against 8 x 8 (until the Table 1 series existed: 1,
//!   2 x 2, 4 x 4, 8 x 8 against 16 x 16, a minute more of the full run for the same rate);
//! - **Table 1 convergence** (`series = "table1"`, the swept parameter in `sweep`), on the
//!   fastest backend: the quantity users report, the paper's Table 1 (PSNR and SSIM of the
//!   perceived image against the ground-truth retinal image, per method and eye case, computed
//!   by the stage functions of [`crate::experiment`] that `assess` runs), with one sampling
//!   parameter swept and the others at the paper's settings: samples per retina pixel, samples
//!   per display pixel, the eye's pupil grid n and LA's k. The value at a sweep's highest setting
//!   is taken as converged; [`Table1Sweep`] reports the cheapest setting within
//!   [`CONVERGED_TOLERANCE_DB`] of it, for every method and eye case at once and per method.
//!
//! Writes `bench.csv` (one row per measured point, with the core count, git revision and every
//! setting), `builds.csv` (acceleration-structure build time and triangle count per mesh
//! backend), `bench.json` (all of it, plus the observed convergence rates and checks),
//! `bench.md` (the report), `summary.md` (its tables, for the README) and plots as PNG and SVG
//! (plotters): `speed_psnr`, `speed_ssim`, `la_grid`, `pupil_grid`, `retina_samples`, `table1`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::Serialize;

use crate::accel::analytic::AnalyticRects;
use crate::accel::bvh::BvhIntersector;
#[cfg(feature = "embree")]
use crate::accel::embree::{BuildQuality, EmbreeIntersector};
use crate::error::{Error, Result};
use crate::experiment::{self, Experiment, ExperimentSpec};
use crate::metrics::{self, SsimConstants};
use crate::optics::{Aperture, Display, Eye, Focus, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::backend::scene_meshes;
use crate::render::retina::simulate;
use crate::render::{
    ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, RadianceField, SceneTracer,
};
use crate::scene::{Mesh, Scene};

/// Draws `$body` (with the drawing area bound to `$area`) into `$out/$name.png` and `.svg`.
macro_rules! draw_plot {
    ($out:expr, $name:expr, $size:expr, |$area:ident| $body:expr) => {{
        for ext in ["png", "svg"] {
            let path = $out.join(format!("{}.{ext}", $name));
            let res: PlotResult = if ext == "png" {
                let $area = BitMapBackend::new(&path, $size).into_drawing_area();
                $body
            } else {
                let $area = SVGBackend::new(&path, $size).into_drawing_area();
                $body
            };
            res.map_err(|e| Error::Unsupported(format!("{}: cannot draw plot: {e}", path.display())))?;
        }
    }};
}

/// PSNR reported for identical images, so that tables, fits and plots stay finite.
pub const IDENTICAL_PSNR_DB: f64 = 200.0;

/// Tolerance of "reaches the converged PSNR" in the report.
pub const CONVERGED_TOLERANCE_DB: f64 = 0.1;

/// Image sizes and sample counts of a run.
#[derive(Clone, Debug, Serialize)]
pub struct Sizes {
    /// LCD pixels per side (the paper's display is 2160).
    pub lcd_resolution: usize,
    /// Retina pixels per side (the paper's experiment: 512).
    pub retina_resolution: usize,
    /// Samples per display pixel (per axis) of the speed-against-error points.
    pub display_samples: Vec<usize>,
    /// Reference of the `method` series: samples per display pixel (per axis)...
    pub reference_display_samples: usize,
    /// ... LA's lenslet grid ...
    pub reference_la_grid: usize,
    /// ... and the eye: pupil grid and samples per retina pixel (per axis).
    pub reference_pupil_grid: usize,
    pub reference_retina_samples: usize,
    /// Sweeps of the convergence series and their references.
    pub la_grids: Vec<usize>,
    pub la_grid_reference: usize,
    pub pupil_grids: Vec<usize>,
    pub pupil_grid_reference: usize,
    pub retina_samples: Vec<usize>,
    pub retina_samples_reference: usize,
    /// Table 1 convergence: the settings of each sweep, lowest first (each includes the
    /// paper's setting; the highest is taken as converged): samples per retina pixel and per
    /// display pixel (per axis), the pupil grid n, LA's k.
    pub table1_retina_samples: Vec<usize>,
    pub table1_display_samples: Vec<usize>,
    pub table1_pupil_grids: Vec<usize>,
    pub table1_la_grids: Vec<usize>,
}

impl Sizes {
    /// The full run: the paper's LCD (2160 x 2160) and retina (512 x 512).
    pub fn full() -> Self {
        Self {
            lcd_resolution: 2160,
            retina_resolution: 512,
            display_samples: vec![1],
            reference_display_samples: 4,
            reference_la_grid: 8,
            reference_pupil_grid: 12,
            reference_retina_samples: 4,
            la_grids: (1..=8).collect(),
            la_grid_reference: 16,
            pupil_grids: vec![2, 3, 4, 5, 6, 8, 10, 12, 16],
            pupil_grid_reference: 32,
            retina_samples: vec![1, 2, 3, 4],
            retina_samples_reference: 8,
            table1_retina_samples: vec![1, 2, 3, 4],
            table1_display_samples: vec![1, 2, 3, 4],
            table1_pupil_grids: vec![2, 3, 4, 5, 6, 8, 10, 12, 16],
            // Every sweep of the Table 1 series recomputes the whole Table 1 (3 display images,
            // 4 ground truths and simulations) at each setting: about 3 minutes of the full run
            // on 2 shared cores. The highest settings are what fits; see `last_step_db`.
            table1_la_grids: vec![1, 2, 3, 4, 5, 6, 8],
        }
    }

    /// `--quick`: the same sweeps at a quarter of the LCD's and retina's resolution (a
    /// sixteenth of the pixels).
    pub fn quick() -> Self {
        Self { lcd_resolution: 540, retina_resolution: 128, ..Self::full() }
    }
}

/// Settings of a bench run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    pub sizes: Sizes,
    /// Written into the report ("quick" or "full").
    pub mode: String,
    pub out: PathBuf,
    pub quiet: bool,
}

impl BenchOptions {
    pub fn new(quick: bool, out: PathBuf, quiet: bool) -> Self {
        let (sizes, mode) = if quick { (Sizes::quick(), "quick") } else { (Sizes::full(), "full") };
        Self { sizes, mode: mode.into(), out, quiet }
    }
}

/// One measured point.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    /// "method", "la_grid", "pupil_grid", "retina_samples", "table1".
    pub series: String,
    /// The parameter `parameter` holds: "display_samples" (`method` series), the series' own
    /// name (`la_grid`, `pupil_grid`, `retina_samples`), or the swept parameter of a `table1`
    /// row: "retina_samples", "display_samples", "pupil_grid" or "la_grid".
    pub sweep: String,
    /// What was rendered and scored: "display", "perceived" or "ground_truth" (`table1` rows:
    /// "perceived", scored against the ground truth).
    pub quantity: String,
    /// Eye case of perceived and ground-truth images ("Near"); empty for display images.
    pub eye_case: String,
    /// Its focus distance (mm); `None` for display images.
    pub focus_mm: Option<f64>,
    pub backend: String,
    pub method: String,
    /// The swept parameter's value: samples per display pixel per axis (`method`), k, n, or
    /// samples per retina pixel per axis.
    pub parameter: usize,
    /// Samples per pixel along the swept dimension: parameter^2, or the pupil samples kept
    /// inside the circle for `pupil_grid`.
    pub samples: usize,
    /// Wall time. Perceived rows of the `method` series: display render plus simulation.
    /// `table1` rows: computing the whole Table 1 at that setting (every display image, ground
    /// truth, simulation and score; no files), the same for each of the point's rows.
    pub seconds: f64,
    /// Rays traced: camera rays of the display render, plus eye rays of the simulation.
    /// `table1` rows: every camera and eye ray (ground truths and simulations) of the point.
    pub rays: u64,
    pub rays_per_second: f64,
    /// Mean of the R, G, B PSNRs against the reference (peak 1, linear values). `table1`
    /// rows: Table 1's PSNR (perceived image against the ground truth).
    pub psnr_db: f64,
    /// Mean SSIM (Wang 2004 constants) of R, G, B against the reference.
    pub ssim: f64,
    // Settings of the point.
    pub scene: String,
    pub lcd_resolution: usize,
    pub retina_resolution: usize,
    /// Samples per display pixel, per axis.
    pub display_samples: usize,
    /// LA's k (1 for LC and PC).
    pub la_grid: usize,
    /// Pupil grid n (0 for display images) and the samples it keeps.
    pub pupil_grid: usize,
    pub pupil_samples: usize,
    /// Samples per retina pixel, per axis (0 for display images).
    pub retina_samples: usize,
    /// The reference this point is scored against.
    pub reference: String,
    /// Rayon worker threads and the machine's logical cores.
    pub threads: usize,
    pub cores: usize,
    pub git_revision: String,
}

/// The acceleration structure of a mesh backend.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRecord {
    pub backend: String,
    pub triangles: usize,
    /// The backend's own build time (`build_seconds()`).
    pub build_seconds: f64,
    /// Wall time of the whole constructor (copying the meshes in, building, committing).
    pub constructor_seconds: f64,
    pub threads: usize,
    pub cores: usize,
    pub git_revision: String,
}

/// Which setting of a convergence series first comes within [`CONVERGED_TOLERANCE_DB`] of the
/// converged PSNR (the PSNR of its highest setting), and what it costs.
#[derive(Clone, Debug, Serialize)]
pub struct WithinTolerance {
    pub parameter: usize,
    pub samples: usize,
    pub seconds: f64,
    pub psnr_db: f64,
}

/// Observed convergence of one series.
#[derive(Clone, Debug, Serialize)]
pub struct ConvergenceSummary {
    pub series: String,
    pub quantity: String,
    pub backend: String,
    pub reference: String,
    /// p in error ~ samples^p: least-squares slope of ln(error) against ln(samples) over every
    /// point of the series, with error = 10^(-PSNR/20) (the geometric mean of the R, G, B
    /// RMSEs; peak 1). `None` with fewer than two usable points.
    pub rate: Option<f64>,
    /// PSNR of the highest setting.
    pub converged_psnr_db: f64,
    pub highest_parameter: usize,
    pub highest_seconds: f64,
    pub first_within_tolerance: Option<WithinTolerance>,
}

/// Consistency checks the run makes on its own images.
#[derive(Clone, Debug, Serialize)]
pub struct Checks {
    /// LA with k = 1 rendered bit for bit the same display image as LC (same rays).
    pub la_k1_equals_lc: bool,
}

/// The cheapest setting of a Table 1 sweep at which a set of Table-1 PSNRs is within
/// [`CONVERGED_TOLERANCE_DB`] of their converged values (those at the sweep's highest setting).
#[derive(Clone, Debug, Serialize)]
pub struct Table1Within {
    /// "all" (every method and eye case at once) or a method ("LC", "PC", "LA": its eye cases).
    pub methods: String,
    pub parameter: usize,
    pub samples: usize,
    /// Computing the whole Table 1 at that setting.
    pub seconds: f64,
    /// Largest |PSNR - converged PSNR| at that setting over those methods and eye cases.
    pub max_diff_db: f64,
    /// Every higher setting of the sweep is within the tolerance too.
    pub stays_within: bool,
}

/// One Table 1 sweep: its settings, their cost, and which reach the converged Table 1.
#[derive(Clone, Debug, Serialize)]
pub struct Table1Sweep {
    /// "retina_samples", "display_samples", "pupil_grid" or "la_grid".
    pub sweep: String,
    pub backend: String,
    /// The paper's setting of the swept parameter (the others stay at theirs).
    pub paper_parameter: usize,
    /// Settings in sweep order (fewest samples first), and the seconds each cost.
    pub parameters: Vec<usize>,
    pub seconds: Vec<f64>,
    /// The highest setting, whose Table 1 is taken as converged.
    pub converged_parameter: usize,
    /// Largest |PSNR - converged PSNR| over every method and eye case at the paper's setting.
    pub paper_max_diff_db: Option<f64>,
    /// Largest change of any Table-1 PSNR over the sweep's last step (second-highest to highest
    /// setting). Above the tolerance, the sweep has not levelled off: its "converged" Table 1 is
    /// only the best it measured, and the setting within tolerance is its highest.
    pub last_step_db: Option<f64>,
    /// The cheapest setting within tolerance for every method and eye case at once...
    pub all_methods: Option<Table1Within>,
    /// ... and for each method on its own (its eye cases).
    pub per_method: Vec<Table1Within>,
}

/// Wall time of a step that is not a measured point (references, scoring, writing).
#[derive(Clone, Debug, Serialize)]
pub struct StageTime {
    pub stage: String,
    pub seconds: f64,
}

/// Everything a run measured (`bench.json`).
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub mode: String,
    pub scene: String,
    pub triangles_when_tessellated: usize,
    pub git_revision: String,
    pub threads: usize,
    pub cores: usize,
    pub sizes: Sizes,
    /// The paper experiment's settings the `method` series measures at.
    pub la_grid: usize,
    pub pupil_diameter_mm: f64,
    pub pupil_grid: usize,
    pub retina_samples: usize,
    pub eye_cases: Vec<(String, f64)>,
    /// Backends measured, in order; the first renders every reference and the convergence series.
    pub backends: Vec<String>,
    pub builds: Vec<BuildRecord>,
    pub convergence: Vec<ConvergenceSummary>,
    /// Table 1 convergence, one entry per sweep.
    pub table1: Vec<Table1Sweep>,
    pub checks: Checks,
    /// Where the rest of the time went.
    pub stages: Vec<StageTime>,
    /// 1-minute load average (`/proc/loadavg`) at the start and the end of the run: above the
    /// thread count, another job shared the cores and the timings are pessimistic.
    pub load_average: [Option<f64>; 2],
    pub total_seconds: f64,
    pub rows: Vec<BenchRow>,
}

fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg").ok()?.split_whitespace().next()?.parse().ok()
}

/// The revision the binary was built from (fixed at build time, so it is known wherever the
/// bench runs).
fn git_revision() -> String {
    crate::version::GIT_REVISION.to_string()
}

/// PSNR (mean of channels; [`IDENTICAL_PSNR_DB`] for identical images) and SSIM.
fn score(a: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
    let p = metrics::psnr(a, reference)?.mean;
    let s = metrics::ssim(a, reference, SsimConstants::Wang2004)?.mean;
    Ok((if p.is_finite() { p.min(IDENTICAL_PSNR_DB) } else { IDENTICAL_PSNR_DB }, s))
}

fn timed<T>(f: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
    let t = Instant::now();
    let v = f()?;
    Ok((v, t.elapsed().as_secs_f64()))
}

/// p in error ~ samples^p (see [`ConvergenceSummary::rate`]) from (samples, PSNR) points.
/// Points with non-finite or identical-image PSNR are left out.
pub fn convergence_rate(points: &[(f64, f64)]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|(n, p)| *n > 0.0 && p.is_finite() && *p < IDENTICAL_PSNR_DB)
        .map(|(n, p)| (n.ln(), -p / 20.0 * std::f64::consts::LN_10))
        .collect();
    if xy.len() < 2 {
        return None;
    }
    let m = xy.len() as f64;
    let (mx, my) = (xy.iter().map(|v| v.0).sum::<f64>() / m, xy.iter().map(|v| v.1).sum::<f64>() / m);
    let sxx: f64 = xy.iter().map(|v| (v.0 - mx) * (v.0 - mx)).sum();
    let sxy: f64 = xy.iter().map(|v| (v.0 - mx) * (v.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Index of the first point (in sweep order) whose PSNR is within `tolerance` dB of the last
/// point's (the highest setting's).
pub fn first_within(psnr: &[f64], tolerance: f64) -> Option<usize> {
    let last = *psnr.last()?;
    psnr.iter().position(|p| *p >= last - tolerance)
}

/// Largest |a - b| over two equally long lists; infinite when their lengths differ or a
/// difference is NaN.
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, |m, d| if d.is_nan() { f64::INFINITY } else { m.max(d) })
}

/// Index of the cheapest point of a sweep (the first: sweeps go from fewest to most samples)
/// whose every value is within `tolerance` of the same value at the last point (the converged
/// values): `points[i]` holds the values of point i, in the same order at every point.
pub fn cheapest_within(points: &[Vec<f64>], tolerance: f64) -> Option<usize> {
    let last = points.last()?;
    points.iter().position(|p| max_abs_diff(p, last) <= tolerance)
}

/// A backend that can render the scene: its radiance field, and how long it took to set up.
struct Backend<'a> {
    name: &'static str,
    field: &'a dyn RadianceField,
}

/// Sizes-independent context of every row.
struct Ctx {
    scene: String,
    lcd: usize,
    ret: usize,
    threads: usize,
    cores: usize,
    rev: String,
}

impl Ctx {
    fn row(&self, series: &str, quantity: &str, backend: &str, method: &str) -> BenchRow {
        BenchRow {
            series: series.into(),
            sweep: series.into(),
            quantity: quantity.into(),
            eye_case: String::new(),
            focus_mm: None,
            backend: backend.into(),
            method: method.into(),
            parameter: 0,
            samples: 0,
            seconds: 0.0,
            rays: 0,
            rays_per_second: 0.0,
            psnr_db: f64::NAN,
            ssim: f64::NAN,
            scene: self.scene.clone(),
            lcd_resolution: self.lcd,
            retina_resolution: self.ret,
            display_samples: 1,
            la_grid: 1,
            pupil_grid: 0,
            pupil_samples: 0,
            retina_samples: 0,
            reference: String::new(),
            threads: self.threads,
            cores: self.cores,
            git_revision: self.rev.clone(),
        }
    }
}

/// Fills in the measurement of a row.
fn measured(mut r: BenchRow, seconds: f64, rays: u64, q: (f64, f64)) -> BenchRow {
    r.seconds = seconds;
    r.rays = rays;
    r.rays_per_second = rays as f64 / seconds.max(1e-9);
    r.psnr_db = q.0;
    r.ssim = q.1;
    r
}

/// A focused eye case of the paper's experiment.
struct Case {
    name: String,
    focus_mm: f64,
    focus: Focus,
}

/// Runs the benchmark on `scene` (named `scene_label` in the outputs) and the paper's display,
/// and writes every report into `opts.out`.
pub fn run(opts: &BenchOptions, scene: &Scene, scene_label: &str) -> Result<BenchReport> {
    let start = Instant::now();
    let load_at_start = load_average();
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let sz = &opts.sizes;
    let mut stages = Vec::new();
    let stage = |stages: &mut Vec<StageTime>, name: &str, since: Instant| {
        stages.push(StageTime { stage: name.into(), seconds: since.elapsed().as_secs_f64() })
    };
    // Scoring (PSNR + SSIM) is timed apart from the renders it scores.
    let score_seconds = std::cell::Cell::new(0.0);
    let score = |a: &RgbImage, b: &RgbImage| {
        let t = Instant::now();
        let q = score(a, b);
        score_seconds.set(score_seconds.get() + t.elapsed().as_secs_f64());
        q
    };
    let paper = ExperimentSpec::paper();
    let mut display = Display::paper();
    display.lcd.resolution = [sz.lcd_resolution, sz.lcd_resolution];
    let retina = Retina {
        resolution: sz.retina_resolution,
        half_tangent: paper.eye.retina_half_tangent,
        samples_per_pixel: paper.eye.retina_samples,
    };
    let cases: Vec<Case> = paper
        .eye_cases
        .iter()
        .filter_map(|c| {
            let focus = match (c.focus_mm, c.focus_diopters) {
                (Some(mm), _) => Focus::Millimetres(mm),
                (None, Some(d)) => Focus::Diopters(d),
                _ => return None,
            };
            Some(Case { name: c.name.clone(), focus_mm: focus.distance_mm(), focus })
        })
        .collect();
    let eye = |focus: Focus, n: usize| Eye {
        retina_distance: paper.eye.retina_distance,
        ..Eye::thin_lens(paper.eye.pupil_diameter, focus, n)
    };
    let ctx = Ctx {
        scene: scene_label.into(),
        lcd: sz.lcd_resolution,
        ret: sz.retina_resolution,
        threads: rayon::current_num_threads(),
        cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        rev: git_revision(),
    };

    // Every backend that can render the scene: the analytic ones for rectangle-only scenes (the
    // fused planar kernel when the scene allows it), then the mesh backends on the tessellated
    // scene.
    let t = Instant::now();
    let analytic = if scene.is_analytic() { Some(AnalyticRects::new(scene)?) } else { None };
    let fused = analytic.as_ref().and_then(|a| FacingPlanes::new(scene, a));
    let analytic_tracer = analytic.as_ref().map(|a| SceneTracer { scene, backend: a });
    let meshes = scene_meshes(scene);
    let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
    let triangles: usize = refs.iter().map(|(_, m)| m.triangle_count()).sum();
    let mut builds = Vec::new();
    let mut build = |name: &str, build_seconds: f64, constructor_seconds: f64| {
        builds.push(BuildRecord {
            backend: name.into(),
            triangles,
            build_seconds,
            constructor_seconds,
            threads: ctx.threads,
            cores: ctx.cores,
            git_revision: ctx.rev.clone(),
        })
    };
    #[cfg(feature = "embree")]
    let embree = {
        let (e, secs) = timed(|| EmbreeIntersector::new(&refs, BuildQuality::High))?;
        build("embree", e.build_seconds(), secs);
        e
    };
    let (bvh, secs) = timed(|| BvhIntersector::new(&refs))?;
    build("bvh", bvh.build_seconds(), secs);
    drop(refs);
    #[cfg(feature = "embree")]
    let embree_tracer = SceneTracer { scene, backend: &embree };
    let bvh_tracer = SceneTracer { scene, backend: &bvh };

    let mut backends: Vec<Backend<'_>> = Vec::new();
    if let Some(f) = &fused {
        backends.push(Backend { name: "analytic-fused", field: f });
    }
    if let Some(t) = &analytic_tracer {
        backends.push(Backend { name: "analytic", field: t });
    }
    #[cfg(feature = "embree")]
    backends.push(Backend { name: "embree", field: &embree_tracer });
    backends.push(Backend { name: "bvh", field: &bvh_tracer });
    let best = &backends[0];
    stage(&mut stages, "set up backends (including the builds)", t);

    let hidden = Progress::hidden();
    let progress = Progress::new(backends.len() as u64 + 4 + TABLE1_SWEEPS.len() as u64, "bench", opts.quiet);
    let mut rows = Vec::new();
    let la = Method::LensletAverage { grid: paper.display_render.la_grid };
    let methods = [Method::LensletCenter, Method::PupilCenter, la];
    let lcd_px = (sz.lcd_resolution * sz.lcd_resolution) as u64;
    let ret_px = (sz.retina_resolution * sz.retina_resolution) as u64;
    let spp = |k: usize| DisplayRenderSettings { samples_per_pixel: k, ..DisplayRenderSettings::default() };

    // 1. Speed against error. References: each method with many samples per display pixel (LA
    //    also with a finer lenslet grid), and what a finer eye perceives of those.
    let ref_method = |m: Method| match m {
        Method::LensletAverage { .. } => Method::LensletAverage { grid: sz.reference_la_grid },
        m => m,
    };
    let ref_retina = Retina { samples_per_pixel: sz.reference_retina_samples, ..retina };
    let t = Instant::now();
    let ref_displays: Vec<RgbImage> = methods
        .iter()
        .map(|m| {
            render_display_image(&display, ref_method(*m), &spp(sz.reference_display_samples), best.field, &hidden)
        })
        .collect::<Result<_>>()?;
    let ref_display_refs: Vec<&RgbImage> = ref_displays.iter().collect();
    let ref_perceived: Vec<Vec<RgbImage>> = cases
        .iter()
        .map(|c| simulate(&display, &eye(c.focus, sz.reference_pupil_grid), &ref_retina, &ref_display_refs, &hidden))
        .collect::<Result<_>>()?;
    drop(ref_display_refs);
    stage(&mut stages, "references of the method series", t);
    progress.inc(1);
    let measured_eye = |c: &Case| eye(c.focus, paper.eye.pupil_grid);
    let pupil_samples = eye(Focus::Millimetres(300.0), paper.eye.pupil_grid).pupil_samples().len();
    for b in &backends {
        for (mi, &method) in methods.iter().enumerate() {
            let ref_m = ref_method(method);
            let ref_name = format!(
                "{} ({}x{} per display pixel, {} best backend {})",
                ref_m,
                sz.reference_display_samples,
                sz.reference_display_samples,
                if ref_m == method { "same method," } else { "finer lenslet grid," },
                best.name
            );
            for &k in &sz.display_samples {
                let (img, t_display) = timed(|| render_display_image(&display, method, &spp(k), b.field, &hidden))?;
                let display_rays = lcd_px * (k * k * method.lenslet_samples()) as u64;
                let base = BenchRow {
                    parameter: k,
                    samples: k * k,
                    display_samples: k,
                    la_grid: match method {
                        Method::LensletAverage { grid } => grid,
                        _ => 1,
                    },
                    sweep: "display_samples".into(),
                    ..ctx.row("method", "display", b.name, method.short_name())
                };
                rows.push(measured(
                    BenchRow { reference: ref_name.clone(), ..base.clone() },
                    t_display,
                    display_rays,
                    score(&img, &ref_displays[mi])?,
                ));
                for (ci, c) in cases.iter().enumerate() {
                    let e = measured_eye(c);
                    let (sim, t_sim) = timed(|| simulate(&display, &e, &retina, &[&img], &hidden))?;
                    let eye_rays = ret_px * (pupil_samples * retina.samples_per_pixel.pow(2)) as u64;
                    let r = BenchRow {
                        quantity: "perceived".into(),
                        eye_case: c.name.clone(),
                        focus_mm: Some(c.focus_mm),
                        pupil_grid: paper.eye.pupil_grid,
                        pupil_samples,
                        retina_samples: retina.samples_per_pixel,
                        reference: format!(
                            "{ref_name}, seen with pupil grid {} and {}x{} per retina pixel",
                            sz.reference_pupil_grid, sz.reference_retina_samples, sz.reference_retina_samples
                        ),
                        ..base.clone()
                    };
                    rows.push(measured(
                        r,
                        t_display + t_sim,
                        display_rays + eye_rays,
                        score(&sim[0], &ref_perceived[ci][mi])?,
                    ));
                }
            }
        }
        progress.inc(1);
    }
    drop(ref_perceived);
    drop(ref_displays);

    // 2. LA's k x k lenslet grid: the display image against a much finer grid.
    let t = Instant::now();
    let reference = render_display_image(
        &display,
        Method::LensletAverage { grid: sz.la_grid_reference },
        &spp(1),
        best.field,
        &hidden,
    )?;
    let lc = render_display_image(&display, Method::LensletCenter, &spp(1), best.field, &hidden)?;
    stage(&mut stages, "reference of la_grid (and the LC image)", t);
    let mut la_k1_equals_lc = false;
    for &k in &sz.la_grids {
        let m = Method::LensletAverage { grid: k };
        let (img, secs) = timed(|| render_display_image(&display, m, &spp(1), best.field, &hidden))?;
        if k == 1 {
            la_k1_equals_lc = img == lc;
        }
        let r = BenchRow {
            parameter: k,
            samples: k * k,
            la_grid: k,
            reference: format!("LA {0}x{0}", sz.la_grid_reference),
            ..ctx.row("la_grid", "display", best.name, "LA")
        };
        rows.push(measured(r, secs, lcd_px * (k * k) as u64, score(&img, &reference)?));
    }
    progress.inc(1);

    // 3. The eye's n x n pupil grid: the LC perceived image at the first focused eye case.
    let first =
        cases.first().ok_or_else(|| Error::Unsupported("the paper experiment has no focused eye case".into()))?;
    let t = Instant::now();
    let reference = simulate(&display, &eye(first.focus, sz.pupil_grid_reference), &retina, &[&lc], &hidden)?.remove(0);
    stage(&mut stages, "reference of pupil_grid", t);
    for &n in &sz.pupil_grids {
        let e = eye(first.focus, n);
        let (sim, secs) = timed(|| simulate(&display, &e, &retina, &[&lc], &hidden))?;
        let kept = e.pupil_samples().len();
        let r = BenchRow {
            eye_case: first.name.clone(),
            focus_mm: Some(first.focus_mm),
            parameter: n,
            samples: kept,
            pupil_grid: n,
            pupil_samples: kept,
            retina_samples: retina.samples_per_pixel,
            reference: format!("pupil grid {}", sz.pupil_grid_reference),
            ..ctx.row("pupil_grid", "perceived", best.name, "LC")
        };
        rows.push(measured(r, secs, ret_px * kept as u64, score(&sim[0], &reference)?));
    }
    progress.inc(1);

    // 4. Samples per retina pixel: the ground truth at the first focused eye case.
    let e = measured_eye(first);
    let t = Instant::now();
    let reference =
        ground_truth(&e, &Retina { samples_per_pixel: sz.retina_samples_reference, ..retina }, best.field, &hidden);
    stage(&mut stages, "reference of retina_samples", t);
    for &k in &sz.retina_samples {
        let r = Retina { samples_per_pixel: k, ..retina };
        let (gt, secs) = timed(|| Ok(ground_truth(&e, &r, best.field, &hidden)))?;
        let row = BenchRow {
            eye_case: first.name.clone(),
            focus_mm: Some(first.focus_mm),
            parameter: k,
            samples: k * k,
            pupil_grid: paper.eye.pupil_grid,
            pupil_samples,
            retina_samples: k,
            reference: format!("{0}x{0} per retina pixel", sz.retina_samples_reference),
            ..ctx.row("retina_samples", "ground_truth", best.name, "GT")
        };
        rows.push(measured(row, secs, ret_px * (k * k * pupil_samples) as u64, score(&gt, &reference)?));
    }
    progress.inc(1);
    drop(reference);

    // 5. Table 1 convergence, on the fastest backend.
    let t = Instant::now();
    table1_series(sz, scene, &display, best.field, best.name, &ctx, &progress, &mut rows)?;
    stage(&mut stages, "Table 1 convergence (wall time of every sweep, scoring included)", t);
    progress.finish();
    stages.push(StageTime { stage: "scoring (PSNR and SSIM)".into(), seconds: score_seconds.get() });

    let convergence = ["la_grid", "pupil_grid", "retina_samples"].iter().filter_map(|s| summarize(s, &rows)).collect();
    let paper_setting = |sweep: &str| match sweep {
        "retina_samples" => paper.eye.retina_samples,
        "display_samples" => paper.display_render.samples_per_pixel,
        "pupil_grid" => paper.eye.pupil_grid,
        _ => paper.display_render.la_grid,
    };
    let table1 = TABLE1_SWEEPS.iter().filter_map(|s| summarize_table1(s, paper_setting(s), &rows)).collect();
    let report = BenchReport {
        mode: opts.mode.clone(),
        scene: scene_label.into(),
        triangles_when_tessellated: triangles,
        git_revision: ctx.rev.clone(),
        threads: ctx.threads,
        cores: ctx.cores,
        sizes: sz.clone(),
        la_grid: paper.display_render.la_grid,
        pupil_diameter_mm: paper.eye.pupil_diameter,
        pupil_grid: paper.eye.pupil_grid,
        retina_samples: paper.eye.retina_samples,
        eye_cases: cases.iter().map(|c| (c.name.clone(), c.focus_mm)).collect(),
        backends: backends.iter().map(|b| b.name.to_string()).collect(),
        builds,
        convergence,
        table1,
        checks: Checks { la_k1_equals_lc },
        stages,
        load_average: [load_at_start, load_average()],
        total_seconds: start.elapsed().as_secs_f64(),
        rows,
    };
    let mut report = report;
    let t = Instant::now();
    write_reports(&report, &opts.out)?;
    // The JSON is written last and carries the time of writing everything else.
    report.stages.push(StageTime { stage: "writing reports and plots".into(), seconds: t.elapsed().as_secs_f64() });
    report.total_seconds = start.elapsed().as_secs_f64();
    write_json(&report, &opts.out)?;
    Ok(report)
}

/// Sweeps of the Table 1 series, in report order.
pub const TABLE1_SWEEPS: [&str; 4] = ["retina_samples", "display_samples", "pupil_grid", "la_grid"];

/// A setting of the Table 1 series.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Table1Setting {
    /// Samples per retina pixel and per display pixel, per axis.
    retina: usize,
    display: usize,
    /// Pupil grid n.
    pupil: usize,
    /// LA's k.
    la: usize,
}

impl Table1Setting {
    fn with(self, sweep: &str, v: usize) -> Self {
        match sweep {
            "retina_samples" => Self { retina: v, ..self },
            "display_samples" => Self { display: v, ..self },
            "pupil_grid" => Self { pupil: v, ..self },
            _ => Self { la: v, ..self },
        }
    }
}

/// Table 1 at one setting.
#[derive(Clone)]
struct Table1Point {
    exp: Experiment,
    scores: Vec<experiment::Score>,
    /// Computing all of it from scratch (cached stages counted at their measured time).
    seconds: f64,
    rays: u64,
}

/// Computes Table 1 at any setting with `assess`'s stage functions. Images that a sweep does
/// not change (the display images at the paper's display settings, the ground truths at the
/// paper's eye settings) are computed once and their measured time counted at every point that
/// uses them; the paper's own setting, shared by every sweep, is computed once.
struct Table1Runner<'a> {
    base: Experiment,
    paper: Table1Setting,
    field: &'a dyn RadianceField,
    displays: HashMap<(Method, usize), (Arc<RgbImage>, f64)>,
    gts: HashMap<(String, usize, usize), (Arc<RgbImage>, f64)>,
    points: HashMap<Table1Setting, Table1Point>,
}

fn stage_seconds(stages: &[experiment::StageTime]) -> f64 {
    stages.iter().map(|s| s.seconds).sum()
}

impl Table1Runner<'_> {
    fn experiment(&self, s: Table1Setting) -> Experiment {
        let mut e = self.base.clone();
        e.retina.samples_per_pixel = s.retina;
        e.spec.eye.retina_samples = s.retina;
        e.render.samples_per_pixel = s.display;
        e.spec.display_render.samples_per_pixel = s.display;
        for c in &mut e.cases {
            c.eye.pupil_grid = s.pupil;
        }
        e.spec.eye.pupil_grid = s.pupil;
        for m in &mut e.methods {
            if let Method::LensletAverage { grid } = m {
                *grid = s.la;
            }
        }
        e.spec.display_render.la_grid = s.la;
        e
    }

    fn point(&mut self, s: Table1Setting) -> Result<Table1Point> {
        if let Some(p) = self.points.get(&s) {
            return Ok(p.clone());
        }
        let exp = self.experiment(s);
        let mut seconds = 0.0;
        let mut displays: Vec<Arc<RgbImage>> = Vec::new();
        for m in &exp.methods {
            let key = (*m, s.display);
            if let Some((img, t)) = self.displays.get(&key) {
                seconds += t;
                displays.push(img.clone());
                continue;
            }
            let one = Experiment { methods: vec![*m], ..exp.clone() };
            let mut stages = Vec::new();
            let (mut img, _depth) = experiment::render_display_images(&one, self.field, true, &mut stages)?;
            let t = stage_seconds(&stages);
            let img = Arc::new(img.remove(0));
            let paper_la = !matches!(m, Method::LensletAverage { .. }) || s.la == self.paper.la;
            if s.display == self.paper.display && paper_la {
                self.displays.insert(key, (img.clone(), t));
            }
            seconds += t;
            displays.push(img);
        }
        let mut stages = Vec::new();
        let refs: Vec<&RgbImage> = displays.iter().map(|d| d.as_ref()).collect();
        let stack = experiment::pack_display_images(&exp, &refs, &mut stages)?;
        let mut gts: Vec<Arc<RgbImage>> = Vec::new();
        let mut sims = Vec::new();
        for case in &exp.cases {
            let key = (case.name.clone(), s.pupil, s.retina);
            match self.gts.get(&key) {
                Some((img, t)) => {
                    seconds += t;
                    gts.push(img.clone());
                }
                None => {
                    let mut st = Vec::new();
                    let img = Arc::new(experiment::ground_truth_image(&exp, case, self.field, true, &mut st));
                    let t = stage_seconds(&st);
                    if s.pupil == self.paper.pupil && s.retina == self.paper.retina {
                        self.gts.insert(key, (img.clone(), t));
                    }
                    seconds += t;
                    gts.push(img);
                }
            }
            sims.push(experiment::perceived_images(&exp, case, &stack, true, &mut stages)?);
        }
        drop(stack);
        let scores = experiment::table1_scores(&exp, &gts, &sims, &mut stages)?;
        seconds += stage_seconds(&stages);
        let lcd_px = (exp.display.lcd.columns() * exp.display.lcd.rows()) as u64;
        let ret_px = (exp.retina.resolution * exp.retina.resolution) as u64;
        let camera_rays: u64 =
            exp.methods.iter().map(|m| lcd_px * (s.display * s.display * m.lenslet_samples()) as u64).sum();
        // Ground truth and simulation each trace every retina sample through every pupil sample.
        let eye_rays: u64 =
            exp.cases.iter().map(|c| 2 * ret_px * (s.retina * s.retina * c.eye.pupil_samples().len()) as u64).sum();
        let p = Table1Point { exp, scores, seconds, rays: camera_rays + eye_rays };
        if s == self.paper {
            self.points.insert(s, p.clone());
        }
        Ok(p)
    }
}

/// Runs every Table 1 sweep of `sz` on `field`, appending one row per setting, method and eye
/// case to `rows`.
#[allow(clippy::too_many_arguments)]
fn table1_series(
    sz: &Sizes,
    scene: &Scene,
    display: &Display,
    field: &dyn RadianceField,
    backend: &str,
    ctx: &Ctx,
    progress: &Progress,
    rows: &mut Vec<BenchRow>,
) -> Result<()> {
    let mut base = Experiment::from_spec(ExperimentSpec::paper(), "built-in paper experiment", Path::new("."))?;
    base.name = "bench-table1".into();
    base.scene = scene.clone();
    base.display = display.clone();
    base.retina.resolution = sz.retina_resolution;
    base.spec.eye.retina_resolution = sz.retina_resolution;
    let la = base
        .methods
        .iter()
        .find_map(|m| match m {
            Method::LensletAverage { grid } => Some(*grid),
            _ => None,
        })
        .unwrap_or(1);
    let paper = Table1Setting {
        retina: base.retina.samples_per_pixel,
        display: base.render.samples_per_pixel,
        pupil: base.spec.eye.pupil_grid,
        la,
    };
    let mut runner =
        Table1Runner { base, paper, field, displays: HashMap::new(), gts: HashMap::new(), points: HashMap::new() };
    for sweep in TABLE1_SWEEPS {
        let settings = match sweep {
            "retina_samples" => &sz.table1_retina_samples,
            "display_samples" => &sz.table1_display_samples,
            "pupil_grid" => &sz.table1_pupil_grids,
            _ => &sz.table1_la_grids,
        };
        for &v in settings {
            let s = paper.with(sweep, v);
            let p = runner.point(s)?;
            // Pupil samples of the setting: those of the thin-lens eye cases (a pinhole has one).
            let kept = p.exp.cases.iter().map(|c| c.eye.pupil_samples().len()).max().unwrap_or(1);
            for sc in &p.scores {
                let Some(case) = p.exp.cases.iter().find(|c| c.name == sc.eye_case) else { continue };
                let pupil_samples = case.eye.pupil_samples().len();
                let la_grid = if sc.method == "LA" { s.la } else { 1 };
                let samples = match sweep {
                    "pupil_grid" => kept,
                    _ => v * v,
                };
                let psnr = sc.psnr.mean;
                let r = BenchRow {
                    sweep: sweep.into(),
                    eye_case: sc.eye_case.clone(),
                    focus_mm: match case.eye.aperture {
                        Aperture::ThinLens { focus, .. } => Some(focus.distance_mm()),
                        Aperture::Pinhole => None,
                    },
                    parameter: v,
                    samples,
                    display_samples: s.display,
                    la_grid,
                    pupil_grid: s.pupil,
                    pupil_samples,
                    retina_samples: s.retina,
                    reference: "ground truth (same eye, same samples per retina pixel)".into(),
                    ..ctx.row("table1", "perceived", backend, &sc.method)
                };
                let q = (if psnr.is_finite() { psnr.min(IDENTICAL_PSNR_DB) } else { IDENTICAL_PSNR_DB }, sc.ssim.mean);
                rows.push(measured(r, p.seconds, p.rays, q));
            }
        }
        progress.inc(1);
    }
    Ok(())
}

fn summarize(series: &str, rows: &[BenchRow]) -> Option<ConvergenceSummary> {
    let pts: Vec<&BenchRow> = rows.iter().filter(|r| r.series == series).collect();
    let last = pts.last()?;
    let psnr: Vec<f64> = pts.iter().map(|r| r.psnr_db).collect();
    let within = first_within(&psnr, CONVERGED_TOLERANCE_DB).map(|i| WithinTolerance {
        parameter: pts[i].parameter,
        samples: pts[i].samples,
        seconds: pts[i].seconds,
        psnr_db: pts[i].psnr_db,
    });
    Some(ConvergenceSummary {
        series: series.into(),
        quantity: describe_series(series, last),
        backend: last.backend.clone(),
        reference: last.reference.clone(),
        rate: convergence_rate(&pts.iter().map(|r| (r.samples as f64, r.psnr_db)).collect::<Vec<_>>()),
        converged_psnr_db: last.psnr_db,
        highest_parameter: last.parameter,
        highest_seconds: last.seconds,
        first_within_tolerance: within,
    })
}

/// The methods of the Table 1 rows, in first-seen order.
fn table1_methods(rows: &[&BenchRow]) -> Vec<String> {
    let mut methods: Vec<String> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method) {
            methods.push(r.method.clone());
        }
    }
    methods
}

fn summarize_table1(sweep: &str, paper_parameter: usize, rows: &[BenchRow]) -> Option<Table1Sweep> {
    let pts: Vec<&BenchRow> = rows.iter().filter(|r| r.series == "table1" && r.sweep == sweep).collect();
    let mut parameters: Vec<usize> = Vec::new();
    for r in &pts {
        if !parameters.contains(&r.parameter) {
            parameters.push(r.parameter);
        }
    }
    let last = *parameters.last()?;
    let at = |p: usize| pts.iter().filter(move |r| r.parameter == p);
    let seconds: Vec<f64> = parameters.iter().map(|&p| at(p).next().map(|r| r.seconds).unwrap_or(f64::NAN)).collect();
    let within = |methods: &str| -> Option<Table1Within> {
        let keep = |r: &&&BenchRow| methods == "all" || r.method == methods;
        let values: Vec<Vec<f64>> =
            parameters.iter().map(|&p| at(p).filter(keep).map(|r| r.psnr_db).collect()).collect();
        let i = cheapest_within(&values, CONVERGED_TOLERANCE_DB)?;
        let converged = values.last()?;
        let first = at(parameters[i]).next()?;
        Some(Table1Within {
            methods: methods.into(),
            parameter: parameters[i],
            samples: first.samples,
            seconds: first.seconds,
            max_diff_db: max_abs_diff(&values[i], converged),
            stays_within: values[i..].iter().all(|v| max_abs_diff(v, converged) <= CONVERGED_TOLERANCE_DB),
        })
    };
    let paper_max_diff_db = parameters.contains(&paper_parameter).then(|| {
        let v = |p: usize| at(p).map(|r| r.psnr_db).collect::<Vec<_>>();
        max_abs_diff(&v(paper_parameter), &v(last))
    });
    let last_step_db = (parameters.len() >= 2).then(|| {
        let v = |p: usize| at(p).map(|r| r.psnr_db).collect::<Vec<_>>();
        max_abs_diff(&v(parameters[parameters.len() - 2]), &v(last))
    });
    Some(Table1Sweep {
        sweep: sweep.into(),
        backend: pts.first()?.backend.clone(),
        paper_parameter,
        last_step_db,
        parameters: parameters.clone(),
        seconds,
        converged_parameter: last,
        paper_max_diff_db,
        all_methods: within("all"),
        per_method: table1_methods(&pts).iter().filter_map(|m| within(m)).collect(),
    })
}

fn describe_series(series: &str, r: &BenchRow) -> String {
    match series {
        "la_grid" => "LA display image, k x k lenslet grid".into(),
        "pupil_grid" => format!("LC perceived image ({}), n x n pupil grid", r.eye_case),
        "retina_samples" => format!("ground truth ({}), k x k samples per retina pixel", r.eye_case),
        _ => series.into(),
    }
}

// ---------------------------------------------------------------------------------------------
// Reports

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `bench.csv`: one line per row, the columns of [`BenchRow`] in order.
pub fn rows_csv(rows: &[BenchRow]) -> String {
    let mut csv = String::from(
        "series,sweep,quantity,eye_case,focus_mm,backend,method,parameter,samples,seconds,rays,rays_per_second,psnr_db,ssim,\
         scene,lcd_resolution,retina_resolution,display_samples,la_grid,pupil_grid,pupil_samples,retina_samples,\
         reference,threads,cores,git_revision\n",
    );
    for r in rows {
        let fields = [
            csv_field(&r.series),
            csv_field(&r.sweep),
            csv_field(&r.quantity),
            csv_field(&r.eye_case),
            r.focus_mm.map(|f| f.to_string()).unwrap_or_default(),
            csv_field(&r.backend),
            csv_field(&r.method),
            r.parameter.to_string(),
            r.samples.to_string(),
            r.seconds.to_string(),
            r.rays.to_string(),
            r.rays_per_second.to_string(),
            r.psnr_db.to_string(),
            r.ssim.to_string(),
            csv_field(&r.scene),
            r.lcd_resolution.to_string(),
            r.retina_resolution.to_string(),
            r.display_samples.to_string(),
            r.la_grid.to_string(),
            r.pupil_grid.to_string(),
            r.pupil_samples.to_string(),
            r.retina_samples.to_string(),
            csv_field(&r.reference),
            r.threads.to_string(),
            r.cores.to_string(),
            csv_field(&r.git_revision),
        ];
        csv.push_str(&fields.join(","));
        csv.push('\n');
    }
    csv
}

fn builds_csv(builds: &[BuildRecord]) -> String {
    let mut csv = String::from("backend,triangles,build_seconds,constructor_seconds,threads,cores,git_revision\n");
    for b in builds {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{}",
            csv_field(&b.backend),
            b.triangles,
            b.build_seconds,
            b.constructor_seconds,
            b.threads,
            b.cores,
            csv_field(&b.git_revision)
        );
    }
    csv
}

fn write_reports(report: &BenchReport, out: &Path) -> Result<()> {
    let write = |name: &str, text: String| -> Result<()> {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| Error::io(&p, e))
    };
    write("bench.csv", rows_csv(&report.rows))?;
    write("builds.csv", builds_csv(&report.builds))?;
    let (summary, full) = markdown(report);
    write("summary.md", summary)?;
    write("bench.md", full)?;
    for (name, metric) in [("speed_psnr", Metric::Psnr), ("speed_ssim", Metric::Ssim)] {
        draw_plot!(out, name, (1400, 1000), |area| plot_speed(area, report, metric));
    }
    for s in &report.convergence {
        draw_plot!(out, s.series, (900, 560), |area| plot_convergence(area, report, s));
    }
    if !report.table1.is_empty() {
        draw_plot!(out, "table1", (1400, 1100), |area| plot_table1(area, report));
    }
    Ok(())
}

/// `bench.json`, written last: its presence marks a complete run.
fn write_json(report: &BenchReport, out: &Path) -> Result<()> {
    let p = out.join("bench.json");
    let text = serde_json::to_string_pretty(report).map_err(|e| Error::Unsupported(e.to_string()))?;
    std::fs::write(&p, text).map_err(|e| Error::io(&p, e))
}

fn f2(v: f64) -> String {
    format!("{v:.2}")
}

fn secs(v: f64) -> String {
    if v < 0.1 {
        format!("{v:.3}")
    } else {
        format!("{v:.2}")
    }
}

fn mrays(r: &BenchRow) -> String {
    format!("{:.1}", r.rays_per_second / 1e6)
}

/// (summary.md, bench.md).
fn markdown(rep: &BenchReport) -> (String, String) {
    let sz = &rep.sizes;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Scene `{}`, paper display at {} x {} LCD pixels, retina {} x {}; paper settings: LA {}x{}, {} mm pupil with \
         an {}x{} grid, {} sample(s) per retina pixel. {} worker thread(s) on {} logical core(s), git revision `{}`, \
         `inimtrace bench` ({} run, {:.0} s of measuring; 1-minute load average {} at the start, {} at the end).\n",
        rep.scene,
        sz.lcd_resolution,
        sz.lcd_resolution,
        sz.retina_resolution,
        sz.retina_resolution,
        rep.la_grid,
        rep.la_grid,
        rep.pupil_diameter_mm,
        rep.pupil_grid,
        rep.pupil_grid,
        rep.retina_samples,
        rep.threads,
        rep.cores,
        rep.git_revision,
        rep.mode,
        rep.total_seconds,
        load_text(rep.load_average[0]),
        load_text(rep.load_average[1])
    );

    // Methods x backends at one sample per display pixel.
    let _ = writeln!(
        s,
        "**Methods x backends** (one sample per display pixel). Display image: render time, camera rays per second, \
         PSNR (dB) / SSIM against the same method with {r}x{r} samples per pixel (LA: {la}x{la} lenslet grid). \
         Perceived images: display render plus simulation (pupil grid {pg}, one sample per retina pixel), against \
         the reference display image seen with pupil grid {rp} and {rr}x{rr} samples per retina pixel.\n",
        r = sz.reference_display_samples,
        la = sz.reference_la_grid,
        pg = rep.pupil_grid,
        rp = sz.reference_pupil_grid,
        rr = sz.reference_retina_samples
    );
    let mut head = "| method | backend | display s | Mrays/s | PSNR / SSIM |".to_string();
    let mut rule = "|---|---|---:|---:|---:|".to_string();
    for (c, mm) in &rep.eye_cases {
        let _ = write!(head, " {c} ({mm:.0} mm) s | PSNR / SSIM |");
        rule.push_str("---:|---:|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
    let method_rows = |quantity: &str, eye: &str, k: usize| -> Vec<&BenchRow> {
        rep.rows
            .iter()
            .filter(|r| r.series == "method" && r.quantity == quantity && r.eye_case == eye && r.parameter == k)
            .collect()
    };
    for m in ["LC", "PC", "LA"] {
        for b in &rep.backends {
            let find = |quantity: &str, eye: &str| {
                method_rows(quantity, eye, 1).into_iter().find(|r| r.method == m && &r.backend == b)
            };
            let Some(d) = find("display", "") else { continue };
            let _ = write!(s, "| {m} | {b} | {} | {} | {} / {:.4} |", secs(d.seconds), mrays(d), f2(d.psnr_db), d.ssim);
            for (c, _) in &rep.eye_cases {
                match find("perceived", c) {
                    Some(p) => {
                        let _ = write!(s, " {} | {} / {:.4} |", secs(p.seconds), f2(p.psnr_db), p.ssim);
                    }
                    None => s.push_str(" | |"),
                }
            }
            s.push('\n');
        }
    }

    // Builds.
    let _ = writeln!(
        s,
        "\n**Acceleration structures** of the mesh backends on the tessellated scene (Embree at its high build \
         quality):\n\n| backend | triangles | build (ms) | whole constructor (ms) |\n|---|---:|---:|---:|"
    );
    for b in &rep.builds {
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {:.3} |",
            b.backend,
            b.triangles,
            1e3 * b.build_seconds,
            1e3 * b.constructor_seconds
        );
    }

    // Convergence summary.
    let _ = writeln!(
        s,
        "\n**Convergence** on the {} backend, each quantity against its own high-sample reference. Rate p: \
         least-squares slope of ln(error) against ln(samples per pixel) over the whole sweep, error = 10^(-PSNR/20) \
         (the geometric mean of the R, G, B RMSEs). At these rates every series still gains several dB at its \
         highest setting; which settings are enough for the numbers users report is the Table 1 convergence \
         below.\n\n| series | against | rate p (error ~ N^p) | highest setting: PSNR, s |\n|---|---|---:|---:|",
        rep.backends.first().map(String::as_str).unwrap_or("?"),
    );
    for c in &rep.convergence {
        let highest = rep.rows.iter().rfind(|r| r.series == c.series).map(|r| r.samples).unwrap_or(0);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {}: {} dB, {} s |",
            c.quantity,
            c.reference,
            c.rate.map(|p| format!("{p:.2}")).unwrap_or_else(|| "-".into()),
            setting(&c.series, c.highest_parameter, highest),
            f2(c.converged_psnr_db),
            secs(c.highest_seconds),
        );
    }
    table1_summary_markdown(rep, &mut s);
    let _ = writeln!(
        s,
        "\nCheck: LA with k = 1 renders {} display image as LC.",
        if rep.checks.la_k1_equals_lc { "bit for bit the same" } else { "**NOT** the same" }
    );

    // The full report: the summary, then every row.
    let mut full = format!("# inimtrace bench ({})\n\n{s}", rep.mode);
    let _ = writeln!(
        full,
        "\n## Plots\n\n![PSNR against wall time](speed_psnr.png)\n\n![SSIM against wall time](speed_ssim.png)\n\n\
         ![LA lenslet grid](la_grid.png)\n\n![pupil grid](pupil_grid.png)\n\n![samples per retina pixel](retina_samples.png)\n\n\
         ![Table 1 convergence](table1.png)\n"
    );
    let _ = writeln!(
        full,
        "## Every speed-against-error point\n\nSamples per display pixel: {}; perceived seconds include the display \
         render, perceived rays the eye rays of the simulation.\n\n| method | backend | samples/px | image | s | Mrays/s | PSNR | SSIM |\n|---|---|---:|---|---:|---:|---:|---:|",
        sz.display_samples.iter().map(|k| format!("{k}x{k}")).collect::<Vec<_>>().join(", ")
    );
    for r in rep.rows.iter().filter(|r| r.series == "method") {
        let what = if r.eye_case.is_empty() { r.quantity.clone() } else { format!("{} {}", r.quantity, r.eye_case) };
        let _ = writeln!(
            full,
            "| {} | {} | {}x{} | {} | {} | {} | {} | {:.4} |",
            r.method,
            r.backend,
            r.parameter,
            r.parameter,
            what,
            secs(r.seconds),
            mrays(r),
            f2(r.psnr_db),
            r.ssim
        );
    }
    let _ = writeln!(full, "\n## Other stages\n\n| stage | s |\n|---|---:|");
    for st in &rep.stages {
        let _ = writeln!(full, "| {} | {} |", st.stage, secs(st.seconds));
    }
    for c in &rep.convergence {
        let _ = writeln!(
            full,
            "\n## Convergence: {}\n\nAgainst {} ({} backend). Observed rate p = {}.\n\n| setting | samples | s | Mrays/s | PSNR | SSIM |\n|---|---:|---:|---:|---:|---:|",
            c.quantity,
            c.reference,
            c.backend,
            c.rate.map(|p| format!("{p:.2}")).unwrap_or_else(|| "-".into())
        );
        for r in rep.rows.iter().filter(|r| r.series == c.series) {
            let _ = writeln!(
                full,
                "| {} | {} | {} | {} | {} | {:.4} |",
                setting(&c.series, r.parameter, r.samples),
                r.samples,
                secs(r.seconds),
                mrays(r),
                f2(r.psnr_db),
                r.ssim
            );
        }
    }
    table1_detail_markdown(rep, &mut full);
    (s, full)
}

/// What a Table 1 sweep varies, for tables and plots.
fn table1_sweep_name(sweep: &str) -> &'static str {
    match sweep {
        "retina_samples" => "samples per retina pixel, k x k",
        "display_samples" => "samples per display pixel, k x k",
        "pupil_grid" => "pupil grid n x n",
        _ => "LA lenslet grid k x k",
    }
}

fn table1_setting(sweep: &str, parameter: usize, samples: usize) -> String {
    match sweep {
        "retina_samples" => format!("{parameter}x{parameter} per retina pixel"),
        "display_samples" => format!("{parameter}x{parameter} per display pixel"),
        "pupil_grid" => format!("pupil n = {parameter} ({samples})"),
        _ => format!("LA k = {parameter}"),
    }
}

fn table1_rows<'a>(rep: &'a BenchReport, sweep: &'a str) -> impl Iterator<Item = &'a BenchRow> + 'a {
    rep.rows.iter().filter(move |r| r.series == "table1" && r.sweep == sweep)
}

fn table1_samples(rep: &BenchReport, sweep: &str, parameter: usize) -> usize {
    table1_rows(rep, sweep).find(|r| r.parameter == parameter).map(|r| r.samples).unwrap_or(0)
}

fn table1_within_text(t: &Table1Sweep, w: &Option<Table1Within>, diff: bool) -> String {
    match w {
        Some(w) => format!(
            "{}, {} s{}{}",
            table1_setting(&t.sweep, w.parameter, w.samples),
            secs(w.seconds),
            if diff { format!(" ({:.2})", w.max_diff_db) } else { String::new() },
            if w.stays_within { "" } else { " *" }
        ),
        None => "-".into(),
    }
}

/// The Table 1 convergence section of summary.md.
fn table1_summary_markdown(rep: &BenchReport, s: &mut String) {
    let Some(first) = rep.table1.first() else { return };
    let methods: Vec<String> = first.per_method.iter().map(|w| w.methods.clone()).collect();
    let cases: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for r in table1_rows(rep, &first.sweep) {
            if !v.contains(&r.eye_case) {
                v.push(r.eye_case.clone());
            }
        }
        v
    };
    let _ = writeln!(
        s,
        "\n**Table 1 convergence** on the {} backend: the paper's Table 1 as `inimtrace assess` computes it (PSNR of \
         the perceived image against the ground-truth retinal image, mean of R, G, B; {} x {}), with one sampling \
         parameter swept and the others at the paper's settings ({}x{} per retina pixel, {}x{} per display pixel, \
         pupil n = {}, LA k = {}). Converged: the Table 1 of the sweep's highest setting. Seconds: computing the \
         whole Table 1 at that setting ({} display images, {} ground truths and simulations, the scores; no files); \
         images a sweep does not change are computed once and their time counted at each setting. \"Within {} \
         dB\": the cheapest setting (fewest samples) whose Table-1 PSNRs are all within {} dB of their converged \
         values, for every method and eye case at once (\"all\") and for each method's {} eye cases{}.\n",
        first.backend,
        methods.join(", "),
        cases.join(", "),
        rep.retina_samples,
        rep.retina_samples,
        rep.table1.iter().find(|t| t.sweep == "display_samples").map(|t| t.paper_parameter).unwrap_or(1),
        rep.table1.iter().find(|t| t.sweep == "display_samples").map(|t| t.paper_parameter).unwrap_or(1),
        rep.pupil_grid,
        rep.la_grid,
        methods.len(),
        cases.len(),
        CONVERGED_TOLERANCE_DB,
        CONVERGED_TOLERANCE_DB,
        cases.len(),
        if rep.table1.iter().flat_map(|t| t.all_methods.iter().chain(&t.per_method)).any(|w| !w.stays_within) {
            format!("; `*`: a higher setting of the sweep is again more than {CONVERGED_TOLERANCE_DB} dB away")
        } else {
            String::new()
        }
    );
    let mut head = format!(
        "| parameter swept | settings | paper's setting: largest diff. to converged (dB) | converged: highest \
         setting, s | last step (dB) | within {CONVERGED_TOLERANCE_DB} dB, all: setting, s (largest diff., dB) |"
    );
    let mut rule = "|---|---|---:|---:|---:|---:|".to_string();
    for m in &methods {
        let _ = write!(head, " {m} |");
        rule.push_str("---:|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
    for t in &rep.table1 {
        let paper = match t.paper_max_diff_db {
            Some(d) => format!(
                "{}: {:.2}",
                table1_setting(&t.sweep, t.paper_parameter, table1_samples(rep, &t.sweep, t.paper_parameter)),
                d
            ),
            None => "-".into(),
        };
        let _ = write!(
            s,
            "| {} | {} | {} | {}, {} s | {} | {} |",
            table1_sweep_name(&t.sweep),
            t.parameters.iter().map(|p| p.to_string()).collect::<Vec<_>>().join(", "),
            paper,
            table1_setting(&t.sweep, t.converged_parameter, table1_samples(rep, &t.sweep, t.converged_parameter)),
            t.seconds.last().map(|v| secs(*v)).unwrap_or_default(),
            t.last_step_db.map(|d| format!("{d:.2}")).unwrap_or_else(|| "-".into()),
            table1_within_text(t, &t.all_methods, true)
        );
        for m in &methods {
            let w = t.per_method.iter().find(|w| &w.methods == m).cloned();
            let _ = write!(s, " {} |", table1_within_text(t, &w, false));
        }
        s.push('\n');
    }
    // The answer in words.
    let answers: Vec<String> = rep
        .table1
        .iter()
        .filter_map(|t| {
            t.all_methods.as_ref().map(|w| {
                let open = t.last_step_db.is_some_and(|d| d > CONVERGED_TOLERANCE_DB);
                format!(
                    "{} ({} s{})",
                    table1_setting(&t.sweep, w.parameter, w.samples),
                    secs(w.seconds),
                    if open {
                        format!(
                            "; the sweep's highest setting, not levelled off: its last step still moves Table 1 by \
                             {:.2} dB",
                            t.last_step_db.unwrap_or(f64::NAN)
                        )
                    } else {
                        String::new()
                    }
                )
            })
        })
        .collect();
    let paper_off: Vec<String> = rep
        .table1
        .iter()
        .filter_map(|t| t.paper_max_diff_db.map(|d| format!("{d:.2} dB ({})", table1_sweep_name(&t.sweep))))
        .collect();
    let _ = writeln!(
        s,
        "\nOne parameter at a time, every method and eye case of Table 1 is within {} dB of its converged value \
         from: {}. At the paper's settings Table 1 is off its converged value by up to {}.",
        CONVERGED_TOLERANCE_DB,
        answers.join("; "),
        paper_off.join(", ")
    );
}

/// Every point of every Table 1 sweep, for bench.md.
fn table1_detail_markdown(rep: &BenchReport, full: &mut String) {
    for t in &rep.table1 {
        let rows: Vec<&BenchRow> = table1_rows(rep, &t.sweep).collect();
        let mut cases: Vec<String> = Vec::new();
        let mut methods: Vec<String> = Vec::new();
        for r in &rows {
            if !cases.contains(&r.eye_case) {
                cases.push(r.eye_case.clone());
            }
            if !methods.contains(&r.method) {
                methods.push(r.method.clone());
            }
        }
        let value = |p: usize, c: &str, m: &str, ssim: bool| {
            rows.iter()
                .find(|r| r.parameter == p && r.eye_case == c && r.method == m)
                .map(|r| if ssim { format!("{:.4}", r.ssim) } else { f2(r.psnr_db) })
                .unwrap_or_else(|| "-".into())
        };
        let converged: Vec<f64> =
            rows.iter().filter(|r| r.parameter == t.converged_parameter).map(|r| r.psnr_db).collect();
        for ssim in [false, true] {
            let _ = writeln!(
                full,
                "\n## Table 1 convergence: {}{}\n\n{} of the perceived image against the ground truth ({} backend), \
                 the other parameters at the paper's settings; s: computing the whole Table 1 at that setting{}.\n",
                table1_sweep_name(&t.sweep),
                if ssim { " (SSIM)" } else { "" },
                if ssim { "SSIM (Wang 2004)" } else { "PSNR (dB)" },
                t.backend,
                if ssim {
                    ""
                } else {
                    "; largest diff.: largest |PSNR - converged PSNR| over every method and eye case"
                }
            );
            let mut head = "| setting | s | Mrays/s |".to_string();
            let mut rule = "|---|---:|---:|".to_string();
            for c in &cases {
                let _ = write!(head, " {c} {} |", methods.join(" / "));
                rule.push_str("---:|");
            }
            if !ssim {
                head.push_str(" largest diff. (dB) |");
                rule.push_str("---:|");
            }
            let _ = writeln!(full, "{head}\n{rule}");
            for (i, &p) in t.parameters.iter().enumerate() {
                let Some(first) = rows.iter().find(|r| r.parameter == p) else { continue };
                let _ = write!(
                    full,
                    "| {}{} | {} | {} |",
                    table1_setting(&t.sweep, p, first.samples),
                    if p == t.paper_parameter { " (paper)" } else { "" },
                    secs(t.seconds[i]),
                    mrays(first)
                );
                for c in &cases {
                    let v: Vec<String> = methods.iter().map(|m| value(p, c, m, ssim)).collect();
                    let _ = write!(full, " {} |", v.join(" / "));
                }
                if !ssim {
                    let here: Vec<f64> = rows.iter().filter(|r| r.parameter == p).map(|r| r.psnr_db).collect();
                    let _ = write!(full, " {:.3} |", max_abs_diff(&here, &converged));
                }
                full.push('\n');
            }
        }
    }
}

fn load_text(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.2}")).unwrap_or_else(|| "unknown".into())
}

fn setting(series: &str, parameter: usize, samples: usize) -> String {
    match series {
        "la_grid" => format!("k = {parameter}"),
        "pupil_grid" => format!("n = {parameter} ({samples})"),
        _ => format!("{parameter}x{parameter}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Plots

#[derive(Clone, Copy, PartialEq)]
enum Metric {
    Psnr,
    Ssim,
}

type PlotResult = std::result::Result<(), String>;

/// Two significant digits, without trailing zeros: axis labels of log scales.
fn significant(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let decimals = (1 - v.log10().floor() as i32).max(0) as usize;
    let t = format!("{v:.decimals$}");
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    }
}

fn e2s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn method_color(method: &str) -> RGBColor {
    match method {
        "LC" => RGBColor(31, 119, 180),
        "PC" => RGBColor(214, 39, 40),
        "LA" => RGBColor(44, 160, 44),
        _ => RGBColor(80, 80, 80),
    }
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
}

/// Speed against error: one panel per image (display, then each eye case), x = wall time
/// (log), y = PSNR or SSIM; one series per method (colour) and backend (marker), its points
/// being 1 and 2 x 2 samples per display pixel.
fn plot_speed<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, rep: &BenchReport, metric: Metric) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let title = match metric {
        Metric::Psnr => "Speed against error: PSNR vs high-sample reference",
        Metric::Ssim => "Speed against error: SSIM vs high-sample reference",
    };
    let area = area.titled(title, ("sans-serif", 24)).map_err(e2s)?;
    let mut panels: Vec<(String, String)> = vec![(String::new(), "display image".into())];
    for (c, mm) in &rep.eye_cases {
        panels.push((c.clone(), format!("perceived, {c} ({mm:.0} mm)")));
    }
    let cols = 2;
    let nrows = panels.len().div_ceil(cols);
    let cells = area.split_evenly((nrows, cols));
    let value = |r: &BenchRow| match metric {
        Metric::Psnr => r.psnr_db,
        Metric::Ssim => r.ssim,
    };
    for (i, ((eye, label), cell)) in panels.iter().zip(cells.iter()).enumerate() {
        let pts: Vec<&BenchRow> = rep.rows.iter().filter(|r| r.series == "method" && &r.eye_case == eye).collect();
        if pts.is_empty() {
            continue;
        }
        let (t0, t1) = range(pts.iter().map(|r| r.seconds));
        let (v0, v1) = range(pts.iter().map(|r| value(r)));
        let pad = ((v1 - v0) * 0.08).max(match metric {
            Metric::Psnr => 0.5,
            Metric::Ssim => 0.002,
        });
        let mut chart = ChartBuilder::on(cell)
            .caption(label, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((t0 * 0.7..t1 * 1.4).log_scale(), (v0 - pad)..(v1 + pad))
            .map_err(e2s)?;
        chart
            .configure_mesh()
            .max_light_lines(2)
            .x_labels(8)
            .x_label_formatter(&|v| significant(*v))
            .x_desc("wall time (s, log)")
            .y_desc(match metric {
                Metric::Psnr => "PSNR (dB)",
                Metric::Ssim => "SSIM",
            })
            .y_label_formatter(&|v| match metric {
                Metric::Psnr => format!("{v:.1}"),
                Metric::Ssim => format!("{v:.3}"),
            })
            .draw()
            .map_err(e2s)?;
        for m in ["LC", "PC", "LA"] {
            for (bi, b) in rep.backends.iter().enumerate() {
                let mut line: Vec<(f64, f64)> =
                    pts.iter().filter(|r| r.method == m && &r.backend == b).map(|r| (r.seconds, value(r))).collect();
                line.sort_by(|a, b| a.0.total_cmp(&b.0));
                if line.is_empty() {
                    continue;
                }
                let color = method_color(m);
                let style = color.stroke_width(2);
                let anno = chart.draw_series(LineSeries::new(line.clone(), style)).map_err(e2s)?;
                if i == 0 {
                    anno.label(format!("{m} {b}")).legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(-8, 0), (8, 0)], style)
                            + marker_element(bi, color)
                    });
                }
                chart
                    .draw_series(line.iter().map(|p| EmptyElement::at(*p) + marker_element(bi, color)))
                    .map_err(e2s)?;
            }
        }
        if i == 0 {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 13))
                .draw()
                .map_err(e2s)?;
        }
    }
    area.present().map_err(e2s)
}

/// A marker per backend: circle, triangle, square, cross.
fn marker_element<DB: DrawingBackend>(backend: usize, color: RGBColor) -> DynElement<'static, DB, (i32, i32)> {
    let filled = color.filled();
    match backend % 4 {
        0 => Circle::new((0, 0), 5, filled).into_dyn(),
        1 => TriangleMarker::new((0, 0), 6, filled).into_dyn(),
        2 => Rectangle::new([(-4, -4), (4, 4)], filled).into_dyn(),
        _ => Cross::new((0, 0), 5, color.stroke_width(2)).into_dyn(),
    }
}

/// Convergence of one series: x = samples per pixel (log), y = PSNR against the reference,
/// the wall time beside each point, and the fitted power law.
fn plot_convergence<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    rep: &BenchReport,
    c: &ConvergenceSummary,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let pts: Vec<&BenchRow> = rep.rows.iter().filter(|r| r.series == c.series).collect();
    let (n0, n1) = range(pts.iter().map(|r| r.samples as f64));
    let (p0, p1) = range(pts.iter().map(|r| r.psnr_db.min(120.0)));
    let title = format!("{} vs {}", c.quantity, c.reference);
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 18))
        .margin(14)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d((n0 * 0.7..n1 * 3.0).log_scale(), (p0 - 2.0)..(p1 + 2.5))
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_label_formatter(&|v| significant(*v))
        .x_desc(match c.series.as_str() {
            "la_grid" => "lenslet samples per display pixel, k x k (log)",
            "pupil_grid" => "pupil samples: n x n grid, kept inside the circle (log)",
            _ => "samples per retina pixel, k x k (log)",
        })
        .y_desc("PSNR (dB)")
        .draw()
        .map_err(e2s)?;
    let color = RGBColor(31, 119, 180);
    let line: Vec<(f64, f64)> = pts.iter().map(|r| (r.samples as f64, r.psnr_db.min(120.0))).collect();
    chart
        .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
        .map_err(e2s)?
        .label(format!("{} ({} backend)", c.series, c.backend))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
    chart.draw_series(line.iter().map(|p| Circle::new(*p, 4, color.filled()))).map_err(e2s)?;
    // The wall time beside each point, alternately above-left and below-right of it so that
    // neighbours do not overlap.
    for (i, r) in pts.iter().enumerate() {
        let (dx, dy) = if i % 2 == 0 { (0.8, 0.9) } else { (1.08, -0.5) };
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{}: {} s", setting(&c.series, r.parameter, r.samples), secs(r.seconds)),
                (r.samples as f64 * dx, r.psnr_db.min(120.0) + dy),
                ("sans-serif", 12),
            )))
            .map_err(e2s)?;
    }
    if let Some(p) = c.rate {
        // ln(err) = a + p ln(N), fitted through the mean point; PSNR = -20 log10(err).
        let xy: Vec<(f64, f64)> = line
            .iter()
            .filter(|(_, v)| *v < 120.0)
            .map(|(n, v)| (n.ln(), -v / 20.0 * std::f64::consts::LN_10))
            .collect();
        let m = xy.len() as f64;
        let a = xy.iter().map(|v| v.1).sum::<f64>() / m - p * xy.iter().map(|v| v.0).sum::<f64>() / m;
        let fit = |n: f64| -20.0 * (a + p * n.ln()) / std::f64::consts::LN_10;
        let gray = RGBColor(120, 120, 120);
        chart
            .draw_series(LineSeries::new(
                (0..=40).map(|i| {
                    let n = n0 * (n1 / n0).powf(i as f64 / 40.0);
                    (n, fit(n))
                }),
                gray.stroke_width(1),
            ))
            .map_err(e2s)?
            .label(format!("fit: error ~ N^{p:.2}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], gray.stroke_width(1)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e2s)?;
    area.present().map_err(e2s)
}

/// Table 1 convergence: one panel per sweep, x = the swept setting, y = Table 1's PSNR, one line
/// per method (colour) and eye case (marker); the seconds of each setting along the top, the
/// paper's setting and the cheapest setting within the tolerance for every method and eye case
/// as vertical lines; the legend in a strip along the bottom.
fn plot_table1<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, rep: &BenchReport) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let area = area
        .titled(
            "Table 1 PSNR (perceived image vs ground truth) against each sampling setting; labels: seconds for the \
             whole Table 1",
            ("sans-serif", 22),
        )
        .map_err(e2s)?;
    let (_, h) = area.dim_in_pixel();
    let (panels, strip) = area.split_vertically(h.saturating_sub(44));
    let gray = RGBColor(150, 150, 150);
    let gold = RGBColor(230, 150, 0);
    let centred =
        |size: u32| ("sans-serif", size).into_font().into_text_style(&panels).pos(Pos::new(HPos::Center, VPos::Center));
    let mut cases: Vec<String> = Vec::new();
    for r in rep.rows.iter().filter(|r| r.series == "table1") {
        if !cases.contains(&r.eye_case) {
            cases.push(r.eye_case.clone());
        }
    }
    let cells = panels.split_evenly((rep.table1.len().div_ceil(2).max(1), 2));
    for (t, cell) in rep.table1.iter().zip(cells.iter()) {
        let rows: Vec<&BenchRow> = table1_rows(rep, &t.sweep).collect();
        if rows.is_empty() {
            continue;
        }
        let (x0, x1) = range(t.parameters.iter().map(|p| *p as f64));
        let (v0, v1) = range(rows.iter().map(|r| r.psnr_db.min(120.0)));
        let pad = ((v1 - v0) * 0.08).max(0.3);
        let top = v1 + 3.0 * pad;
        let xpad = ((x1 - x0) * 0.06).max(0.3);
        let mut chart = ChartBuilder::on(cell)
            .caption(
                format!("{} (others at the paper's; {} backend)", table1_sweep_name(&t.sweep), t.backend),
                ("sans-serif", 17),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d((x0 - xpad)..(x1 + xpad), (v0 - pad)..top)
            .map_err(e2s)?;
        chart
            .configure_mesh()
            .max_light_lines(1)
            .x_labels(t.parameters.len().max(2))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .x_desc(match t.sweep.as_str() {
                "pupil_grid" => "n (pupil grid n x n)",
                "la_grid" => "k (LA lenslet grid k x k)",
                _ => "k (k x k samples per pixel)",
            })
            .y_desc("Table 1 PSNR (dB)")
            .y_label_formatter(&|v| format!("{v:.1}"))
            .draw()
            .map_err(e2s)?;
        // Vertical lines: the paper's setting, and the cheapest setting within the tolerance.
        let paper = t.paper_parameter as f64;
        chart.draw_series(LineSeries::new([(paper, v0 - pad), (paper, top)], gray.stroke_width(2))).map_err(e2s)?;
        if let Some(w) = &t.all_methods {
            let x = w.parameter as f64;
            chart.draw_series(LineSeries::new([(x, v0 - pad), (x, top)], gold.stroke_width(3))).map_err(e2s)?;
        }
        for m in ["LC", "PC", "LA"] {
            let color = method_color(m);
            for (ci, c) in cases.iter().enumerate() {
                let line: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.method == m && &r.eye_case == c)
                    .map(|r| (r.parameter as f64, r.psnr_db.min(120.0)))
                    .collect();
                if line.is_empty() {
                    continue;
                }
                chart.draw_series(LineSeries::new(line.clone(), color.stroke_width(2))).map_err(e2s)?;
                chart
                    .draw_series(line.iter().map(|p| EmptyElement::at(*p) + marker_element(ci, color)))
                    .map_err(e2s)?;
            }
        }
        // Seconds of each setting along the top, on two alternating rows.
        for (k, (p, sec)) in t.parameters.iter().zip(&t.seconds).enumerate() {
            let y = if k % 2 == 0 { top - 0.8 * pad } else { top - 1.9 * pad };
            chart
                .draw_series(std::iter::once(Text::new(format!("{} s", secs(*sec)), (*p as f64, y), centred(12))))
                .map_err(e2s)?;
        }
    }
    // The legend strip.
    let label = ("sans-serif", 14).into_font().into_text_style(&strip).pos(Pos::new(HPos::Left, VPos::Center));
    let y = 22;
    let mut x = 30;
    for m in ["LC", "PC", "LA"] {
        strip.draw(&PathElement::new(vec![(x, y), (x + 24, y)], method_color(m).stroke_width(2))).map_err(e2s)?;
        strip.draw(&Text::new(m.to_string(), (x + 30, y), label.clone())).map_err(e2s)?;
        x += 80;
    }
    for (ci, c) in cases.iter().enumerate() {
        strip.draw(&(EmptyElement::at((x + 8, y)) + marker_element(ci, RGBColor(60, 60, 60)))).map_err(e2s)?;
        strip.draw(&Text::new(c.clone(), (x + 20, y), label.clone())).map_err(e2s)?;
        x += 90;
    }
    for (color, width, text) in [
        (gray, 2, "paper's setting".to_string()),
        (
            gold,
            3,
            format!("cheapest setting within {CONVERGED_TOLERANCE_DB} dB of converged, every method and eye case"),
        ),
    ] {
        strip.draw(&PathElement::new(vec![(x, y - 10), (x, y + 10)], color.stroke_width(width))).map_err(e2s)?;
        strip.draw(&Text::new(text.clone(), (x + 10, y), label.clone())).map_err(e2s)?;
        x += 40 + 7 * text.len() as i32;
    }
    area.present().map_err(e2s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_of_an_exact_power_law() {
        // error = 0.3 N^-0.75  ->  PSNR = -20 log10(0.3 N^-0.75).
        let pts: Vec<(f64, f64)> =
            [1.0, 4.0, 9.0, 16.0, 64.0].iter().map(|&n: &f64| (n, -20.0 * (0.3 * n.powf(-0.75)).log10())).collect();
        assert!((convergence_rate(&pts).unwrap() + 0.75).abs() < 1e-12);
        // Identical-image points are left out; one point is not a fit.
        let mut with_cap = pts.clone();
        with_cap.push((256.0, IDENTICAL_PSNR_DB));
        assert!((convergence_rate(&with_cap).unwrap() + 0.75).abs() < 1e-12);
        assert_eq!(convergence_rate(&pts[..1]), None);
        assert_eq!(convergence_rate(&[(4.0, 20.0), (4.0, 30.0)]), None);
    }

    #[test]
    fn first_setting_within_tolerance_of_the_highest() {
        assert_eq!(first_within(&[20.0, 30.0, 33.95, 34.0], 0.1), Some(2));
        assert_eq!(first_within(&[20.0, 30.0, 34.2, 34.0], 0.1), Some(2));
        assert_eq!(first_within(&[20.0, 30.0, 33.8, 34.0], 0.1), Some(3));
        assert_eq!(first_within(&[], 0.1), None);
    }

    #[test]
    fn cheapest_setting_within_tolerance_of_the_converged_values() {
        // Two values per point; the last point is converged.
        let pts = vec![vec![20.0, 30.0], vec![21.95, 30.5], vec![21.93, 30.05], vec![22.0, 30.0]];
        assert_eq!(cheapest_within(&pts, 0.1), Some(2));
        // Overshooting counts as away from converged too.
        let pts = vec![vec![22.2, 30.0], vec![22.05, 30.0], vec![22.0, 30.0]];
        assert_eq!(cheapest_within(&pts, 0.1), Some(1));
        // The highest setting always qualifies; nothing to compare without points.
        assert_eq!(cheapest_within(&[vec![1.0], vec![5.0]], 0.1), Some(1));
        assert_eq!(cheapest_within(&[], 0.1), None);
        // NaN and length mismatches never qualify.
        assert_eq!(cheapest_within(&[vec![f64::NAN, 30.0], vec![22.0], vec![22.0, 30.0]], 0.1), Some(2));
        assert_eq!(max_abs_diff(&[1.0, 2.0], &[1.5, 1.0]), 1.0);
    }

    #[test]
    fn csv_fields_with_commas_are_quoted() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\", y"), "\"say \"\"x\"\", y\"");
        assert_eq!(csv_field("plain"), "plain");
    }
}
