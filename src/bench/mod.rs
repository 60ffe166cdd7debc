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
//! - **the cost of precision** (`series = "precision"`, the estimator in `estimator`), on the
//!   fastest backend: the paper's Table 1 (PSNR and SSIM of the perceived image against the
//!   ground-truth retinal image, per method and eye case) by the grid estimator, plain random
//!   sampling, and randomized QMC scored naively and de-biased, at increasing sample counts,
//!   against a converged reference run; the error (largest |PSNR error| over Table 1's cells)
//!   against seconds, and the seconds each estimator needs to stay within
//!   [`PRECISION_TARGETS_DB`] (`precision`).
//!
//! Writes `bench.csv` (one row per measured point, with the core count, git revision and every
//! setting), `builds.csv` (acceleration-structure build time and triangle count per mesh
//! backend), `bench.json` (all of it, plus the observed convergence rates and checks),
//! `bench.md` (the report), `summary.md` (its tables, for the README) and plots as PNG and SVG
//! (plotters): `speed_psnr`, `speed_ssim`, `la_grid`, `pupil_grid`, `retina_samples`, `precision`.
//!
//! Every image, references included, is made by the stage functions `assess` runs, on copies of
//! the paper's experiment with one sampling setting changed (`pipeline`). The parts: `options`
//! (sizes and the typed rows), `runs` (backends, builds, the method and convergence series),
//! `precision` (the cost of precision), `summary` (rates and settings within tolerance), `report`
//! (CSV, JSON, the console table), `markdown` and `plots`; `backends` is `bench --backends`, the
//! mesh backends (and Embree builds) side by side.

pub mod backends;
mod markdown;
mod options;
mod pipeline;
mod plots;
mod precision;
mod report;
mod runs;
mod summary;

use std::time::Instant;

use serde::Serialize;

pub use backends::BackendsOptions;
pub use options::{
    Backend, BenchOptions, BenchRow, BuildRecord, Estimator, MethodLabel, Parameter, Quantity, Series, Sizes,
};
pub use precision::{PrecisionPoint, PrecisionReached, PrecisionSummary, PRECISION_TARGETS_DB};
pub use report::{console_table, rows_csv};
pub use summary::{
    cheapest_within, convergence_rate, first_within, max_abs_diff, ConvergenceSummary, WithinTolerance,
    CONVERGED_TOLERANCE_DB, IDENTICAL_PSNR_DB,
};

use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::scene::Scene;

/// Consistency checks the run makes on its own images.
#[derive(Clone, Debug, Serialize)]
pub struct Checks {
    /// LA with k = 1 rendered bit for bit the same display image as LC (same rays).
    pub la_k1_equals_lc: bool,
}

/// Wall time of a step that is not a measured point (references, scoring, writing).
#[derive(Clone, Debug, Serialize)]
pub struct StageTime {
    /// What the step did.
    pub stage: String,
    /// Its wall time, s.
    pub seconds: f64,
}

impl StageTime {
    fn since(stage: &str, t: Instant) -> Self {
        Self { stage: stage.into(), seconds: t.elapsed().as_secs_f64() }
    }
}

/// Everything a run measured (`bench.json`).
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// "quick" or "full".
    pub mode: String,
    /// The scene measured.
    pub scene: String,
    /// Its triangles, rectangles tessellated into two each.
    pub triangles_when_tessellated: usize,
    /// The git revision of the build.
    pub git_revision: String,
    /// Rayon threads used.
    pub threads: usize,
    /// CPU cores of the machine.
    pub cores: usize,
    /// The sizes the run measured at.
    pub sizes: Sizes,
    /// The paper experiment's settings the `method` series measures at.
    pub la_grid: usize,
    /// Pupil diameter of the `method` series' eye, mm.
    pub pupil_diameter_mm: f64,
    /// Its pupil grid n.
    pub pupil_grid: usize,
    /// Its samples per retina pixel, per axis.
    pub retina_samples: usize,
    /// Its eye cases: name and focus distance, mm.
    pub eye_cases: Vec<(String, f64)>,
    /// Backends measured, in order; the first renders every reference and the convergence series.
    pub backends: Vec<Backend>,
    /// Build time of every mesh backend's acceleration structure.
    pub builds: Vec<BuildRecord>,
    /// The convergence series, summarised.
    pub convergence: Vec<ConvergenceSummary>,
    /// The cost of precision: each Table 1 estimator against the converged Table 1.
    pub precision: PrecisionSummary,
    /// What the run checked (the backends agree, the series converge).
    pub checks: Checks,
    /// Where the rest of the time went.
    pub stages: Vec<StageTime>,
    /// 1-minute load average (`/proc/loadavg`) at the start and the end of the run: above the
    /// thread count, another job shared the cores and the timings are pessimistic.
    pub load_average: [Option<f64>; 2],
    /// Wall time of the whole run, s.
    pub total_seconds: f64,
    /// Every measured point.
    pub rows: Vec<BenchRow>,
}

impl BenchReport {
    /// The rows of the cost-of-precision section of `estimator`.
    pub fn precision_rows(&self, estimator: Estimator) -> impl Iterator<Item = &BenchRow> + '_ {
        self.rows.iter().filter(move |r| r.series == Series::Precision && r.estimator == Some(estimator))
    }
}

fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg").ok()?.split_whitespace().next()?.parse().ok()
}

/// The revision the binary was built from (fixed at build time, so it is known wherever the
/// bench runs).
fn git_revision() -> String {
    crate::version::GIT_REVISION.to_string()
}

/// Runs the benchmark on `scene` (named `scene_label` in the outputs) and the paper's display,
/// and writes every report into `opts.out`.
pub fn run(opts: &BenchOptions, scene: &Scene, scene_label: &str) -> Result<BenchReport> {
    let start = Instant::now();
    let load_at_start = load_average();
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let sz = &opts.sizes;
    let base = pipeline::base_experiment(sz, scene)?;
    let ctx = options::RowContext {
        scene: scene_label.into(),
        lcd_resolution: sz.lcd_resolution,
        retina_resolution: sz.retina_resolution,
        threads: rayon::current_num_threads(),
        cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        git_revision: git_revision(),
    };

    let t = Instant::now();
    let built = runs::Backends::build(scene, &ctx)?;
    let fields = built.fields(scene);
    let backends = fields.list();
    let best = backends[0];
    let set_up = StageTime::since("set up backends (including the builds)", t);

    let progress = Progress::new(backends.len() as u64 + 4 + 3, "bench", opts.quiet);
    let mut runs = runs::Runs::new(&base, sz, &ctx, &progress);
    runs.method_series(&backends)?;
    let (lc, la_k1_equals_lc) = runs.la_grid_series(&best)?;
    runs.pupil_grid_series(&best, &lc)?;
    drop(lc);
    runs.retina_samples_series(&best)?;
    let t = Instant::now();
    let precision = precision::precision_series(&base, sz, &best, &ctx, &progress, &mut runs.rows)?;
    progress.finish();

    let mut stages = vec![set_up];
    stages.append(&mut runs.stages);
    stages.push(StageTime::since("the cost of precision (wall time: reference, every estimator, display images)", t));
    stages.push(StageTime { stage: "scoring (PSNR and SSIM)".into(), seconds: runs.score_seconds });
    let rows = runs.rows;
    let paper = pipeline::Sampling::of(&base);
    let mut report = BenchReport {
        mode: opts.mode.clone(),
        scene: scene_label.into(),
        triangles_when_tessellated: built.triangles,
        git_revision: ctx.git_revision.clone(),
        threads: ctx.threads,
        cores: ctx.cores,
        sizes: sz.clone(),
        la_grid: paper.la,
        pupil_diameter_mm: base.pupil_diameter(),
        pupil_grid: paper.pupil,
        retina_samples: paper.retina,
        eye_cases: pipeline::focused_cases(&base)?
            .cases
            .iter()
            .filter_map(|c| Some((c.name.clone(), pipeline::focus_mm(c)?)))
            .collect(),
        backends: backends.iter().map(|b| b.backend).collect(),
        builds: built.builds.clone(),
        convergence: Series::CONVERGENCE.iter().filter_map(|s| summary::summarize(*s, &rows)).collect(),
        precision,
        checks: Checks { la_k1_equals_lc },
        stages,
        load_average: [load_at_start, load_average()],
        total_seconds: start.elapsed().as_secs_f64(),
        rows,
    };
    let t = Instant::now();
    report::write_reports(&report, &opts.out)?;
    // The JSON is written last and carries the time of writing everything else.
    report.stages.push(StageTime::since("writing reports and plots", t));
    report.total_seconds = start.elapsed().as_secs_f64();
    report::write_json(&report, &opts.out)?;
    Ok(report)
}
