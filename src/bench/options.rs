//! What a bench run measures and how its points are named: the image sizes and sample counts
//! of a run ([`Sizes`], [`BenchOptions`]), the typed names of every measured point (series,
//! swept parameter, quantity, backend, method), and the rows themselves ([`BenchRow`],
//! [`BuildRecord`]). The names serialise to exactly the text of `bench.csv` and `bench.json`.

use std::fmt;
use std::path::PathBuf;

use serde::Serialize;

use crate::render::Method;

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
    /// Samples per retina pixel (per axis) of the reference eye.
    pub reference_retina_samples: usize,
    /// Sweeps of the convergence series and their references.
    pub la_grids: Vec<usize>,
    /// LA's k of the `la_grid` series' reference.
    pub la_grid_reference: usize,
    /// Pupil grids n of the `pupil_grid` series.
    pub pupil_grids: Vec<usize>,
    /// Pupil grid n of its reference.
    pub pupil_grid_reference: usize,
    /// Samples per retina pixel (per axis) of the `retina_samples` series.
    pub retina_samples: Vec<usize>,
    /// Samples per retina pixel (per axis) of its reference.
    pub retina_samples_reference: usize,
    /// The cost of precision: the reference run's target (half-width of every Table 1 PSNR's
    /// 95% interval, dB), its budget of samples per pixel and its time budget (seconds, over
    /// every eye case) ...
    pub precision_reference_db: f64,
    /// Samples per pixel budget of the reference run.
    pub precision_reference_max_samples: u64,
    /// Time budget of the reference run, s (over every eye case).
    pub precision_reference_seconds: f64,
    /// ... the grid estimator's settings (pupil grid n, samples per retina pixel per axis),
    /// cheapest first ...
    pub precision_grids: Vec<(usize, usize)>,
    /// ... and samples per replicate of the random and randomized-QMC points, increasing.
    pub precision_samples: Vec<u32>,
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
            precision_reference_db: 0.005,
            precision_reference_max_samples: 1 << 16,
            precision_reference_seconds: 900.0,
            precision_grids: vec![(4, 1), (8, 1), (8, 2), (12, 2), (16, 3), (24, 4)],
            precision_samples: vec![1, 2, 4, 8, 16, 32, 64, 128],
        }
    }

    /// `--quick`: the same sweeps at a quarter of the LCD's and retina's resolution (a
    /// sixteenth of the pixels), and a shorter cost-of-precision sweep (a looser reference).
    pub fn quick() -> Self {
        Self {
            lcd_resolution: 540,
            retina_resolution: 128,
            precision_reference_db: 0.01,
            precision_reference_max_samples: 1 << 13,
            precision_reference_seconds: 60.0,
            precision_grids: vec![(4, 1), (8, 1), (8, 2), (16, 3)],
            precision_samples: vec![1, 2, 4, 8, 16, 32],
            ..Self::full()
        }
    }
}

/// Settings of a bench run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// The sizes of the run (quick or full).
    pub sizes: Sizes,
    /// Written into the report ("quick" or "full").
    pub mode: String,
    /// The folder `bench.json`, `bench.csv` and the report go to.
    pub out: PathBuf,
    /// No progress bars.
    pub quiet: bool,
}

impl BenchOptions {
    /// The quick (`--quick`) or full sizes, writing into `out`.
    pub fn new(quick: bool, out: PathBuf, quiet: bool) -> Self {
        let (sizes, mode) = if quick { (Sizes::quick(), "quick") } else { (Sizes::full(), "full") };
        Self { sizes, mode: mode.into(), out, quiet }
    }
}

/// The text of a name (as written into `bench.csv`, and by serde into `bench.json`), printing
/// it, and comparing it with text.
macro_rules! names {
    ($ty:ident { $($variant:ident => $text:literal),+ $(,)? }) => {
        impl $ty {
            /// Every value, in declaration order.
            pub const ALL: &'static [$ty] = &[$($ty::$variant),+];

            /// The name as `bench.csv` and `bench.json` write it.
            pub fn as_str(self) -> &'static str {
                match self {
                    $($ty::$variant => $text),+
                }
            }
        }

        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl PartialEq<&str> for $ty {
            fn eq(&self, other: &&str) -> bool {
                self.as_str() == *other
            }
        }
    };
}

/// The series a row belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Series {
    /// Speed against error: every method on every backend.
    Method,
    /// Convergence of LA's k x k lenslet grid (display image).
    LaGrid,
    /// Convergence of the eye's n x n pupil grid (LC perceived image).
    PupilGrid,
    /// Convergence of samples per retina pixel (ground truth).
    RetinaSamples,
    /// The cost of precision: Table 1 by each estimator at increasing sample counts.
    Precision,
}
names!(Series { Method => "method", LaGrid => "la_grid", PupilGrid => "pupil_grid", RetinaSamples => "retina_samples", Precision => "precision" });

/// An estimator of Table 1 (the `estimator` column of `precision` rows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// The paper's grids: pupil grid n x n, s x s samples per retina pixel.
    Grid,
    /// Independent uniform points, PSNR of the mean image.
    Random,
    /// Randomized QMC replicates, PSNR of their mean image (noise-biased).
    RqmcNaive,
    /// Randomized QMC replicates, cross-replicate (de-biased) PSNR.
    Rqmc,
    /// The converged reference the others are scored against.
    Reference,
}
names!(Estimator { Grid => "grid", Random => "random", RqmcNaive => "rqmc_naive", Rqmc => "rqmc", Reference => "reference" });

impl Series {
    /// The convergence series, in report order.
    pub const CONVERGENCE: [Series; 3] = [Series::LaGrid, Series::PupilGrid, Series::RetinaSamples];
}

/// A sampling parameter: what a row's `parameter` holds (the `sweep` column).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    /// Samples per display pixel, per axis.
    DisplaySamples,
    /// LA's k (k x k lenslet grid).
    LaGrid,
    /// The eye's pupil grid n (n x n, kept inside the circle).
    PupilGrid,
    /// Samples per retina pixel, per axis.
    RetinaSamples,
}
names!(Parameter { DisplaySamples => "display_samples", LaGrid => "la_grid", PupilGrid => "pupil_grid", RetinaSamples => "retina_samples" });

/// What was rendered and scored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// A display image, against its reference.
    Display,
    /// A perceived retinal image.
    Perceived,
    /// A ground-truth retinal image.
    GroundTruth,
}
names!(Quantity { Display => "display", Perceived => "perceived", GroundTruth => "ground_truth" });

/// A backend the bench measures. `AnalyticFused` is the fused planar kernel over the analytic
/// backend (rectangle-only scenes it can handle); the mesh backends see the tessellated scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Backend {
    /// The fused planar kernel over the analytic backend.
    AnalyticFused,
    /// The generic analytic tracer (exact f64 rectangles).
    Analytic,
    /// Intel Embree over the tessellated scene.
    Embree,
    /// inimtrace's own 4-wide BVH over the tessellated scene.
    Bvh,
}
names!(Backend { AnalyticFused => "analytic-fused", Analytic => "analytic", Embree => "embree", Bvh => "bvh" });

/// The rendering method of a row: the paper's abbreviation (LA's grid is in the row's
/// `la_grid`), or GT for ground-truth images.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum MethodLabel {
    /// LensletCenter.
    Lc,
    /// PupilCenter.
    Pc,
    /// LensletAverage.
    La,
    /// The ground truth (no display).
    Gt,
    /// The optimised method.
    Opt,
}
names!(MethodLabel { Lc => "LC", Pc => "PC", La => "LA", Gt => "GT", Opt => "OPT" });

impl MethodLabel {
    /// The display-image methods, in report order.
    pub const METHODS: [MethodLabel; 3] = [MethodLabel::Lc, MethodLabel::Pc, MethodLabel::La];
}

impl From<Method> for MethodLabel {
    fn from(m: Method) -> Self {
        match m {
            Method::LensletCenter => MethodLabel::Lc,
            Method::PupilCenter => MethodLabel::Pc,
            Method::LensletAverage { .. } => MethodLabel::La,
            Method::Optimized => MethodLabel::Opt,
        }
    }
}

/// LA's k of a method (1 for LC and PC).
pub fn la_grid_of(m: Method) -> usize {
    match m {
        Method::LensletAverage { grid } => grid,
        Method::LensletCenter | Method::PupilCenter | Method::Optimized => 1,
    }
}

/// One measured point.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    /// The series the row belongs to.
    pub series: Series,
    /// The parameter `parameter` holds: `display_samples` (`method` series), the series' own
    /// parameter (`la_grid`, `pupil_grid`, `retina_samples`); `retina_samples` for `precision`
    /// rows (samples per retina pixel).
    pub sweep: Parameter,
    /// The estimator of a `precision` row; `None` (empty) for the other series.
    pub estimator: Option<Estimator>,
    /// What was rendered and scored (`precision` rows: perceived, scored against the ground
    /// truth).
    pub quantity: Quantity,
    /// Eye case of perceived and ground-truth images ("Near"); empty for display images.
    pub eye_case: String,
    /// Its focus distance (mm); `None` for display images.
    pub focus_mm: Option<f64>,
    /// The backend that rendered the point.
    pub backend: Backend,
    /// The method (LC, PC, LA k).
    pub method: MethodLabel,
    /// The swept parameter's value: samples per display pixel per axis (`method`), k, n, or
    /// samples per retina pixel per axis (`precision`: samples per retina pixel).
    pub parameter: usize,
    /// Samples per pixel along the swept dimension: parameter^2, or the pupil samples kept
    /// inside the circle for `pupil_grid` (`precision`: samples per retina pixel).
    pub samples: usize,
    /// Wall time. Perceived rows of the `method` series: display render plus simulation.
    /// `precision` rows: the estimator's eye rays and scoring for the whole Table 1 at that
    /// sample count (display images not counted; the reference: its eye case), the same for each
    /// of the point's rows.
    pub seconds: f64,
    /// Rays traced: camera rays of the display render, plus eye rays of the simulation.
    /// `precision` rows: the eye rays of the point (the reference's: of its eye case).
    pub rays: u64,
    /// `rays / seconds`.
    pub rays_per_second: f64,
    /// Mean of the R, G, B PSNRs against the reference (peak 1, linear values). `precision`
    /// rows: Table 1's PSNR (perceived image against the ground truth).
    pub psnr_db: f64,
    /// Mean SSIM (Wang 2004 constants) of R, G, B against the reference.
    pub ssim: f64,
    // Settings of the point.
    /// The scene measured.
    pub scene: String,
    /// LCD pixels per side.
    pub lcd_resolution: usize,
    /// Retina pixels per side.
    pub retina_resolution: usize,
    /// Samples per display pixel, per axis.
    pub display_samples: usize,
    /// LA's k (1 for LC and PC).
    pub la_grid: usize,
    /// Pupil grid n (0 for display images) and the samples it keeps.
    pub pupil_grid: usize,
    /// Pupil samples kept inside the circle.
    pub pupil_samples: usize,
    /// Samples per retina pixel, per axis (0 for display images).
    pub retina_samples: usize,
    /// The reference this point is scored against.
    pub reference: String,
    /// Rayon worker threads and the machine's logical cores.
    pub threads: usize,
    /// Logical cores of the machine.
    pub cores: usize,
    /// The git revision of the build.
    pub git_revision: String,
}

impl BenchRow {
    /// The row with its measurement filled in: wall time, rays traced, (PSNR, SSIM).
    pub fn measured(mut self, seconds: f64, rays: u64, (psnr_db, ssim): (f64, f64)) -> Self {
        self.seconds = seconds;
        self.rays = rays;
        self.rays_per_second = rays as f64 / seconds.max(1e-9);
        self.psnr_db = psnr_db;
        self.ssim = ssim;
        self
    }
}

/// What every row of a run shares: the scene, the sizes and the machine.
#[derive(Clone, Debug)]
pub struct RowContext {
    /// The scene measured.
    pub scene: String,
    /// LCD pixels per side.
    pub lcd_resolution: usize,
    /// Retina pixels per side.
    pub retina_resolution: usize,
    /// Rayon threads used.
    pub threads: usize,
    /// CPU cores of the machine.
    pub cores: usize,
    /// The git revision of the build.
    pub git_revision: String,
}

impl RowContext {
    /// A row of a display image (one sample per pixel, LA's k = 1, no eye), not yet measured.
    pub fn row(
        &self,
        series: Series,
        sweep: Parameter,
        quantity: Quantity,
        backend: Backend,
        method: MethodLabel,
    ) -> BenchRow {
        BenchRow {
            series,
            sweep,
            estimator: None,
            quantity,
            eye_case: String::new(),
            focus_mm: None,
            backend,
            method,
            parameter: 0,
            samples: 0,
            seconds: 0.0,
            rays: 0,
            rays_per_second: 0.0,
            psnr_db: f64::NAN,
            ssim: f64::NAN,
            scene: self.scene.clone(),
            lcd_resolution: self.lcd_resolution,
            retina_resolution: self.retina_resolution,
            display_samples: 1,
            la_grid: 1,
            pupil_grid: 0,
            pupil_samples: 0,
            retina_samples: 0,
            reference: String::new(),
            threads: self.threads,
            cores: self.cores,
            git_revision: self.git_revision.clone(),
        }
    }

    /// A build record of `backend`.
    pub fn build(
        &self,
        backend: Backend,
        triangles: usize,
        build_seconds: f64,
        constructor_seconds: f64,
    ) -> BuildRecord {
        BuildRecord {
            backend,
            triangles,
            build_seconds,
            constructor_seconds,
            threads: self.threads,
            cores: self.cores,
            git_revision: self.git_revision.clone(),
        }
    }
}

/// The acceleration structure of a mesh backend.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRecord {
    /// The mesh backend.
    pub backend: Backend,
    /// Triangles it was built over.
    pub triangles: usize,
    /// The backend's own build time (`build_seconds()`).
    pub build_seconds: f64,
    /// Wall time of the whole constructor (copying the meshes in, building, committing).
    pub constructor_seconds: f64,
    /// Rayon worker threads.
    pub threads: usize,
    /// Logical cores of the machine.
    pub cores: usize,
    /// The git revision of the build.
    pub git_revision: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// serde's `rename_all` and the CSV text agree on every name.
    fn same_text<T: Serialize + fmt::Display>(all: &[T]) {
        for v in all {
            assert_eq!(serde_json::to_string(v).unwrap(), format!("\"{v}\""));
        }
    }

    #[test]
    fn serde_names_are_the_csv_names() {
        same_text(Series::ALL);
        same_text(Parameter::ALL);
        same_text(Quantity::ALL);
        same_text(Backend::ALL);
        same_text(MethodLabel::ALL);
        let text: Vec<&str> = Series::ALL.iter().map(|s| s.as_str()).collect();
        assert_eq!(text, ["method", "la_grid", "pupil_grid", "retina_samples", "precision"]);
        same_text(Estimator::ALL);
        let text: Vec<&str> = Backend::ALL.iter().map(|s| s.as_str()).collect();
        assert_eq!(text, ["analytic-fused", "analytic", "embree", "bvh"]);
        let text: Vec<&str> = MethodLabel::ALL.iter().map(|s| s.as_str()).collect();
        assert_eq!(text, ["LC", "PC", "LA", "GT", "OPT"]);
        assert_eq!(Quantity::GroundTruth.as_str(), "ground_truth");
        assert_eq!(Parameter::DisplaySamples.as_str(), "display_samples");
    }

    #[test]
    fn method_labels_of_render_methods() {
        assert_eq!(MethodLabel::from(Method::LensletCenter), MethodLabel::Lc);
        assert_eq!(MethodLabel::from(Method::PupilCenter), MethodLabel::Pc);
        assert_eq!(MethodLabel::from(Method::LensletAverage { grid: 7 }), MethodLabel::La);
        assert_eq!(la_grid_of(Method::LensletAverage { grid: 7 }), 7);
        assert_eq!(la_grid_of(Method::PupilCenter), 1);
        assert!(MethodLabel::La == "LA" && MethodLabel::Gt != "LA");
    }
}
