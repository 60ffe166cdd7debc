//! The cost of precision: how many seconds each estimator of the paper's Table 1
//! (Sec. 4.2: PSNR and SSIM of the perceived image against the ground-truth retinal image, per
//! method and eye case) needs to come within a given distance of the converged Table 1.
//!
//! The converged value is a reference run of the converged estimator to a very tight target
//! ([`Sizes::precision_reference_db`]) with its own seed. Against it, at increasing sample
//! counts, on the fastest backend and the same display images:
//!
//! - **grid**: the paper's estimator (`assess` with the grid estimator): a pupil grid n x n kept
//!   inside the disk times s x s samples per retina pixel, PSNR of the single perceived image
//!   against the single ground truth;
//! - **random**: plain Monte Carlo, independent uniform points over pixel x pupil disk
//!   ([`Sampler::independent`]), the naive PSNR of the mean image over every sample;
//! - **rqmc_naive**: the randomized-QMC replicates (Owen-scrambled Sobol), the naive PSNR of the
//!   replicates' mean image (biased by the noise left in both images);
//! - **rqmc**: the same replicates scored by the cross-replicate (de-biased) estimator.
//!
//! Rays are the eye rays traced (the grid: ground truth and simulation each; the reference: its
//! eye case). Seconds count the eye rays and the scoring (the display images, common to all, are rendered
//! once and not counted); the sequences are nested, so a sample count's seconds are all the
//! sampling up to it plus its own scoring. The error of a point is the largest |PSNR error| over
//! Table 1's cells; each estimator "reaches" a target from the first point after which every
//! point of the sweep stays within it.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use serde::Serialize;

use super::options::{
    la_grid_of, Backend, BenchRow, Estimator, MethodLabel, Parameter, Quantity, RowContext, Series, Sizes,
};
use super::pipeline::{display_images, focus_mm, ground_truth_image, perceived_images, Sampling};
use super::runs::Field;
use super::summary::capped_psnr;
use crate::error::Result;
use crate::experiment::converged::{case_sampler, independent_case_sampler, measure, naive_scores};
use crate::experiment::{self, Experiment};
use crate::measure::adaptive::{self, Precision};
use crate::measure::estimator::{DisplaySource, Replicates};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::retina::DisplayStack;
use crate::render::RadianceField;

/// The precision targets of the thresholds table, dB (largest |PSNR error| over Table 1).
pub const PRECISION_TARGETS_DB: [f64; 4] = [0.1, 0.05, 0.02, 0.01];

/// The estimators of the sweep, in report order.
pub const SWEPT: [Estimator; 4] = [Estimator::Grid, Estimator::Random, Estimator::RqmcNaive, Estimator::Rqmc];

/// One point of one estimator: Table 1 at one sample count.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionPoint {
    /// The estimator measured.
    pub estimator: Estimator,
    /// Samples per retina pixel (eye rays per pixel; the grid: pupil points kept x s^2).
    pub samples_per_pixel: u64,
    /// The setting in words ("n = 8, s = 2x2"; "8 x 16").
    pub setting: String,
    /// Wall time of the point (see the module comment for what counts), s.
    pub seconds: f64,
    /// Largest |PSNR - converged PSNR| over Table 1's cells, dB.
    pub max_psnr_error_db: f64,
    /// Largest |SSIM - converged SSIM| over Table 1's cells.
    pub max_ssim_error: f64,
}

/// When an estimator reaches a target: the first point from which every point is within it.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionReached {
    /// The estimator.
    pub estimator: Estimator,
    /// The target, dB (largest |PSNR error| over Table 1).
    pub target_db: f64,
    /// `None`: the sweep's top does not reach it.
    pub seconds: Option<f64>,
    /// Samples per pixel at that point; `None` as for `seconds`.
    pub samples_per_pixel: Option<u64>,
}

/// The cost-of-precision section of a run.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionSummary {
    /// Target of the reference run (half-width of every PSNR's 95% interval), dB.
    pub reference_target_db: f64,
    /// What the reference reached: its largest PSNR half-width, dB ...
    pub reference_ci95_db: f64,
    /// ... its samples per pixel (largest over the eye cases) and its seconds.
    pub reference_samples_per_pixel: u64,
    /// Wall time of the reference run, s.
    pub reference_seconds: f64,
    /// Why the reference stopped: "target met" for every eye case, else the first budget that
    /// stopped one ("sample budget", "time budget").
    pub reference_stopped_by: String,
    /// Replicates of the randomized-QMC points.
    pub replicates: usize,
    /// Every point, estimators in `SWEPT` order, sample counts increasing.
    pub points: Vec<PrecisionPoint>,
    /// Per estimator and target of [`PRECISION_TARGETS_DB`].
    pub reached: Vec<PrecisionReached>,
}

/// One eye case of the random or RQMC sweep at one sample count.
struct Step {
    case: usize,
    /// Index into [`Sizes::precision_samples`].
    step: usize,
    samples_per_pixel: u64,
    /// Sampling seconds up to this count (nested sequences).
    sampled: f64,
    /// Naive scores of the replicates' mean images, and their seconds ...
    naive: Vec<(crate::metrics::Psnr, crate::metrics::Ssim)>,
    naive_seconds: f64,
    /// ... and the de-biased ones (RQMC only).
    debiased: Option<(Vec<adaptive::CellScores>, f64)>,
}

/// Table 1 as (eye case, method) -> (PSNR, SSIM).
type Cells = HashMap<(String, MethodLabel), (f64, f64)>;

/// Largest |PSNR error| and |SSIM error| of `cells` against `reference` (every reference cell
/// must be present; a missing one is an infinite error).
fn max_errors(cells: &Cells, reference: &Cells) -> (f64, f64) {
    reference.iter().fold((0.0f64, 0.0f64), |(p, s), (k, (rp, rs))| match cells.get(k) {
        Some((cp, cs)) => (p.max((cp - rp).abs()), s.max((cs - rs).abs())),
        None => (f64::INFINITY, f64::INFINITY),
    })
}

/// When each estimator of `points` reaches each target (see [`PrecisionReached`]).
pub fn reached(points: &[PrecisionPoint]) -> Vec<PrecisionReached> {
    let mut out = Vec::new();
    for e in SWEPT {
        let pts: Vec<&PrecisionPoint> = points.iter().filter(|p| p.estimator == e).collect();
        for target in PRECISION_TARGETS_DB {
            // The first index from which every later point is within the target.
            let mut first = None;
            for (i, p) in pts.iter().enumerate().rev() {
                if p.max_psnr_error_db <= target {
                    first = Some(i);
                } else {
                    break;
                }
            }
            out.push(PrecisionReached {
                estimator: e,
                target_db: target,
                seconds: first.map(|i| pts[i].seconds),
                samples_per_pixel: first.map(|i| pts[i].samples_per_pixel),
            });
        }
    }
    out
}

/// Everything the section measures on `best` from the bench's experiment `base`, appending one
/// row per point and Table 1 cell (and the reference's) to `rows`.
pub fn precision_series(
    base: &Experiment,
    sizes: &Sizes,
    best: &Field<'_>,
    ctx: &RowContext,
    progress: &Progress,
    rows: &mut Vec<BenchRow>,
) -> Result<PrecisionSummary> {
    let field = best.field;
    let (displays, _) = display_images(base, field)?;
    let refs: Vec<&RgbImage> = displays.iter().collect();
    let stack = experiment::pack_display_images(base, &refs, &mut Vec::new())?;
    let maker = RowMaker {
        base,
        ctx,
        backend: best.backend,
        labels: base.methods.iter().map(|&x| MethodLabel::from(x)).collect(),
        pixels: (base.retina.resolution * base.retina.resolution) as u64,
    };

    let reference = reference_run(&maker, sizes, field, &stack, rows);
    progress.inc(1);

    let mut points = grid_points(&maker, sizes, field, &refs, &reference.cells, rows)?;
    progress.inc(1);

    let (rqmc, random) = ladder_steps(&maker, sizes, field, &stack)?;
    for (estimator, list) in [(Estimator::Random, &random), (Estimator::RqmcNaive, &rqmc), (Estimator::Rqmc, &rqmc)] {
        ladder_points(&maker, sizes, estimator, list, &reference.cells, rows, &mut points);
    }
    progress.inc(1);

    let reached = reached(&points);
    Ok(PrecisionSummary {
        reference_target_db: sizes.precision_reference_db,
        reference_ci95_db: reference.ci95_db,
        reference_samples_per_pixel: reference.samples_per_pixel,
        reference_seconds: reference.seconds,
        reference_stopped_by: reference.stopped_by.into(),
        replicates: base.measurement.replicates,
        points,
        reached,
    })
}

/// What every row of the section shares: the bench's experiment, the backend measured and the
/// methods' labels.
struct RowMaker<'a> {
    base: &'a Experiment,
    ctx: &'a RowContext,
    backend: Backend,
    labels: Vec<MethodLabel>,
    /// Retina pixels of one image.
    pixels: u64,
}

impl RowMaker<'_> {
    /// The row of eye case `case` and method `k` of `estimator` at `spp` samples per pixel.
    fn row(
        &self,
        estimator: Estimator,
        case: usize,
        k: usize,
        spp: u64,
        (seconds, rays): (f64, u64),
        scores: (f64, f64),
    ) -> BenchRow {
        let c = &self.base.cases[case];
        BenchRow {
            estimator: Some(estimator),
            eye_case: c.name.clone(),
            focus_mm: focus_mm(c),
            parameter: spp as usize,
            samples: spp as usize,
            la_grid: la_grid_of(self.base.methods[k]),
            pupil_samples: c.eye.pupil_samples().len(),
            retina_samples: 0,
            reference: "converged reference (same display images)".into(),
            ..self.ctx.row(
                Series::Precision,
                Parameter::RetinaSamples,
                Quantity::Perceived,
                self.backend,
                self.labels[k],
            )
        }
        .measured(seconds, rays, (capped_psnr(scores.0), scores.1))
    }
}

/// The reference run and what it reached (see [`PrecisionSummary`]'s `reference_*` fields).
struct ReferenceRun {
    cells: Cells,
    ci95_db: f64,
    samples_per_pixel: u64,
    seconds: f64,
    stopped_by: &'static str,
}

/// The reference: every eye case to the tight target, with its own seed.
fn reference_run(
    maker: &RowMaker<'_>,
    sizes: &Sizes,
    field: &dyn RadianceField,
    stack: &DisplayStack,
    rows: &mut Vec<BenchRow>,
) -> ReferenceRun {
    let base = maker.base;
    let m = &base.measurement;
    let mut out = ReferenceRun {
        cells: Cells::new(),
        ci95_db: 0.0,
        samples_per_pixel: 0,
        seconds: 0.0,
        stopped_by: "target met",
    };
    let ref_precision = Precision {
        psnr_ci95_db: sizes.precision_reference_db,
        ssim_ci95: f64::INFINITY,
        max_samples_per_pixel: sizes.precision_reference_max_samples,
        deadline: None,
        initial_samples: 16,
        replicates: m.replicates,
    };
    let ref_seed = m.seed.wrapping_add(0x5eed);
    for (i, case) in base.cases.iter().enumerate() {
        let t = Instant::now();
        let deadline = Some(t + Duration::from_secs_f64(sizes.precision_reference_seconds / base.cases.len() as f64));
        let source = DisplaySource::new(&base.display, &case.eye, field, stack);
        let got =
            measure(&source, ref_seed, i, &case.eye, &base.retina, base.ssim, &Precision { deadline, ..ref_precision });
        let seconds = t.elapsed().as_secs_f64();
        out.seconds += seconds;
        out.samples_per_pixel = out.samples_per_pixel.max(got.samples_per_pixel());
        if out.stopped_by == "target met" {
            out.stopped_by = got.stopped_by;
        }
        for (k, cell) in got.cells.iter().enumerate() {
            out.ci95_db = out.ci95_db.max(cell.psnr.ci95.unwrap_or(f64::INFINITY));
            out.cells.insert((case.name.clone(), maker.labels[k]), (cell.psnr.mean, cell.ssim.mean));
            rows.push(maker.row(
                Estimator::Reference,
                i,
                k,
                got.samples_per_pixel(),
                (seconds, got.samples_per_pixel() * maker.pixels),
                (cell.psnr.mean, cell.ssim.mean),
            ));
        }
    }
    out
}

/// The grid estimator's points: pupil grid and retina samples together.
fn grid_points(
    maker: &RowMaker<'_>,
    sizes: &Sizes,
    field: &dyn RadianceField,
    refs: &[&RgbImage],
    reference: &Cells,
    rows: &mut Vec<BenchRow>,
) -> Result<Vec<PrecisionPoint>> {
    let (base, pixels) = (maker.base, maker.pixels);
    let mut points = Vec::new();
    let paper = Sampling::of(base);
    for &(pupil, retina) in &sizes.precision_grids {
        let exp = Sampling { pupil, retina, ..paper }.apply(base);
        let mut seconds = 0.0;
        let mut gts = Vec::new();
        for case in &exp.cases {
            let (img, t) = ground_truth_image(&exp, case, field);
            seconds += t;
            gts.push(img);
        }
        let sims = perceived_images(&exp, refs)?;
        seconds += sims.pack_seconds + sims.case_seconds.iter().sum::<f64>();
        let mut stages = Vec::new();
        let scores = experiment::table1_scores(&exp, &gts, &sims.images, &mut stages)?;
        seconds += super::pipeline::stage_seconds(&stages);
        let kept = exp.cases.iter().map(|c| c.eye.pupil_samples().len()).max().unwrap_or(1);
        let spp = (kept * retina * retina) as u64;
        // The ground truth and the simulation each trace every retina sample through every
        // pupil sample.
        let rays: u64 =
            exp.cases.iter().map(|c| 2 * pixels * (retina * retina * c.eye.pupil_samples().len()) as u64).sum();
        let mut cells = Cells::new();
        for sc in &scores {
            let Some(i) = exp.cases.iter().position(|c| c.name == sc.eye_case) else { continue };
            let Some(k) = exp.methods.iter().position(|x| x.name() == sc.method) else { continue };
            cells.insert((sc.eye_case.clone(), maker.labels[k]), (sc.psnr.mean, sc.ssim.mean));
            let mut r = maker.row(Estimator::Grid, i, k, spp, (seconds, rays), (sc.psnr.mean, sc.ssim.mean));
            (r.pupil_grid, r.retina_samples) = (pupil, retina);
            rows.push(r);
        }
        let (pe, se) = max_errors(&cells, reference);
        let setting = format!("n = {pupil}, s = {retina}x{retina}");
        points.push(PrecisionPoint {
            estimator: Estimator::Grid,
            samples_per_pixel: spp,
            setting,
            seconds,
            max_psnr_error_db: pe,
            max_ssim_error: se,
        });
    }
    Ok(points)
}

/// Random and randomized-QMC steps, `(rqmc, random)`: the same replicate count and sample
/// ladder ([`Sizes::precision_samples`]) for every eye case.
fn ladder_steps(
    maker: &RowMaker<'_>,
    sizes: &Sizes,
    field: &dyn RadianceField,
    stack: &DisplayStack,
) -> Result<(Vec<Step>, Vec<Step>)> {
    let base = maker.base;
    let m = &base.measurement;
    let nr = m.replicates;
    let loose = Precision {
        psnr_ci95_db: 0.0,
        ssim_ci95: 0.0,
        max_samples_per_pixel: u64::MAX,
        deadline: None,
        initial_samples: 1,
        replicates: nr,
    };
    let mut rqmc = Vec::new();
    let mut random = Vec::new();
    for (i, case) in base.cases.iter().enumerate() {
        let source = DisplaySource::new(&base.display, &case.eye, field, stack);
        for (independent, store) in [(false, &mut rqmc), (true, &mut random)] {
            let sampler = if independent {
                independent_case_sampler(m.seed, i, &case.eye)
            } else {
                case_sampler(m.seed, i, &case.eye)
            };
            let mut reps = Replicates::new(base.retina.resolution, nr, 1 + base.methods.len());
            let mut sampled = 0.0;
            for (j, &n) in sizes.precision_samples.iter().enumerate() {
                let t = Instant::now();
                reps.extend(&source, &sampler, &base.retina, n, &Progress::hidden());
                sampled += t.elapsed().as_secs_f64();
                let t = Instant::now();
                let naive = naive_scores(&reps, base.ssim)?;
                let naive_seconds = t.elapsed().as_secs_f64();
                let debiased = if independent {
                    None
                } else {
                    let t = Instant::now();
                    let cells = adaptive::score(&reps, base.ssim, &loose);
                    Some((cells, t.elapsed().as_secs_f64()))
                };
                store.push(Step {
                    case: i,
                    step: j,
                    samples_per_pixel: reps.samples_per_pixel(),
                    sampled,
                    naive,
                    naive_seconds,
                    debiased,
                });
            }
        }
    }
    Ok((rqmc, random))
}

/// The points of `estimator` from its ladder steps `list`, per ladder step: seconds summed over
/// the eye cases, errors over every cell.
fn ladder_points(
    maker: &RowMaker<'_>,
    sizes: &Sizes,
    estimator: Estimator,
    list: &[Step],
    reference: &Cells,
    rows: &mut Vec<BenchRow>,
    points: &mut Vec<PrecisionPoint>,
) {
    let (base, labels, pixels) = (maker.base, &maker.labels, maker.pixels);
    let nr = base.measurement.replicates;
    for (j, &n) in sizes.precision_samples.iter().enumerate() {
        let mut cells = Cells::new();
        let mut seconds = 0.0;
        let mut spp = 0;
        for x in list.iter().filter(|x| x.step == j) {
            let (i, sampled) = (&x.case, x.sampled);
            spp = x.samples_per_pixel;
            let scores: Vec<(f64, f64)> = match (estimator, &x.debiased) {
                (Estimator::Rqmc, Some((c, t))) => {
                    seconds += sampled + t;
                    c.iter().map(|c| (c.psnr.mean, c.ssim.mean)).collect()
                }
                _ => {
                    seconds += sampled + x.naive_seconds;
                    x.naive.iter().map(|(p, s)| (p.mean, s.mean)).collect()
                }
            };
            for (k, sc) in scores.iter().enumerate() {
                cells.insert((base.cases[*i].name.clone(), labels[k]), *sc);
            }
        }
        for (i, case) in base.cases.iter().enumerate() {
            for (k, label) in labels.iter().enumerate() {
                if let Some(&sc) = cells.get(&(case.name.clone(), *label)) {
                    rows.push(maker.row(estimator, i, k, spp, (seconds, spp * pixels * base.cases.len() as u64), sc));
                }
            }
        }
        let (pe, se) = max_errors(&cells, reference);
        let setting = format!("{nr} x {n}");
        points.push(PrecisionPoint {
            estimator,
            samples_per_pixel: spp,
            setting,
            seconds,
            max_psnr_error_db: pe,
            max_ssim_error: se,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(estimator: Estimator, spp: u64, seconds: f64, err: f64) -> PrecisionPoint {
        PrecisionPoint {
            estimator,
            samples_per_pixel: spp,
            setting: String::new(),
            seconds,
            max_psnr_error_db: err,
            max_ssim_error: 0.0,
        }
    }

    #[test]
    fn a_target_is_reached_where_the_error_stays_within_it() {
        let pts = vec![
            point(Estimator::Rqmc, 8, 1.0, 0.2),
            point(Estimator::Rqmc, 16, 2.0, 0.04),
            point(Estimator::Rqmc, 32, 4.0, 0.06),
            point(Estimator::Rqmc, 64, 8.0, 0.015),
        ];
        let r = reached(&pts);
        let of = |t: f64| r.iter().find(|x| x.estimator == Estimator::Rqmc && x.target_db == t).unwrap();
        // 0.1 dB: from 16 samples on (0.06 after it is still within 0.1).
        assert_eq!((of(0.1).seconds, of(0.1).samples_per_pixel), (Some(2.0), Some(16)));
        // 0.05 dB: 16 samples dipped below it, but 32 left it again.
        assert_eq!(of(0.05).seconds, Some(8.0));
        assert_eq!(of(0.02).seconds, Some(8.0));
        assert_eq!(of(0.01).seconds, None);
        // Estimators without points reach nothing.
        assert!(r.iter().filter(|x| x.estimator == Estimator::Grid).all(|x| x.seconds.is_none()));
        assert_eq!(r.len(), SWEPT.len() * PRECISION_TARGETS_DB.len());
    }

    #[test]
    fn errors_are_the_largest_over_the_reference_cells() {
        let key = |c: &str, m| (c.to_string(), m);
        let reference: Cells =
            [(key("Near", MethodLabel::Lc), (20.0, 0.9)), (key("Far", MethodLabel::La), (30.0, 0.8))].into();
        let mut cells: Cells =
            [(key("Near", MethodLabel::Lc), (20.3, 0.95)), (key("Far", MethodLabel::La), (29.5, 0.79))].into();
        let (p, s) = max_errors(&cells, &reference);
        assert!((p - 0.5).abs() < 1e-12 && (s - 0.05).abs() < 1e-12);
        cells.remove(&key("Far", MethodLabel::La));
        assert_eq!(max_errors(&cells, &reference).0, f64::INFINITY);
    }
}
