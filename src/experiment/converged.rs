//! The converged Table 1 of an experiment (paper Sec. 4.2, Table 1 and Fig. 3): every eye case
//! measured by the paired estimator to the experiment's `[measurement]` precision, giving the
//! images `assess` writes (the replicates' means) and the scores with their 95% intervals.

use crate::io::exr::{AttrValue, Attributes};
use std::time::{Duration, Instant};

use super::perceptual;
use crate::error::Result;
use crate::experiment::{CaseResult, Experiment, EyeCase, Score, StageTime};
use crate::measure::adaptive::{measure_case, measure_case_with, CaseMeasurement, Precision};
use crate::measure::estimator::{DisplaySource, PairedSource, Replicates};
use crate::measure::sampler::Sampler;
use crate::measure::spec::EstimatorKind;
use crate::metrics::{self, Psnr, Ssim, SsimConstants};
use crate::optics::{Aperture, Eye, Retina};
use crate::perception::PerceptualScores;
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::retina::DisplayStack;
use crate::render::RadianceField;

/// Samples per replicate of the first round.
pub const INITIAL_SAMPLES: u32 = 4;

/// Ground truths (one per eye case), perceived images (`[case][method]`) and scores.
pub type Table1 = (Vec<RgbImage>, Vec<Vec<RgbImage>>, Vec<Score>);

/// The sampler of eye case `index` of an experiment measured with `seed`.
pub fn case_sampler(seed: u64, index: usize, eye: &Eye) -> Sampler {
    let radius = match eye.aperture {
        Aperture::Pinhole => None,
        Aperture::ThinLens { pupil_diameter, .. } => Some(0.5 * pupil_diameter),
    };
    Sampler::new(seed, index as u64, radius)
}

/// The plain random sampler ([`Sampler::independent`]) of eye case `index` of an experiment
/// measured with `seed`: the bench's Monte Carlo baseline.
pub fn independent_case_sampler(seed: u64, index: usize, eye: &Eye) -> Sampler {
    let radius = match eye.aperture {
        Aperture::Pinhole => None,
        Aperture::ThinLens { pupil_diameter, .. } => Some(0.5 * pupil_diameter),
    };
    Sampler::independent(seed, index as u64, radius)
}

/// Measures one eye case of any paired source to `precision` (see [`measure_case`]), quietly:
/// the building block of [`table1`] for tests and tools.
pub fn measure<S: PairedSource + ?Sized>(
    source: &S,
    seed: u64,
    case_index: usize,
    eye: &Eye,
    retina: &Retina,
    constants: SsimConstants,
    precision: &Precision,
) -> CaseMeasurement {
    measure_case(source, &case_sampler(seed, case_index, eye), retina, constants, precision, &Progress::hidden(), None)
}

/// The converged Table 1 of `exp` (`None` when it uses the grid estimator): per eye case, the
/// stages `converged_sampling` (tracing) and `converged_statistics` (scores and intervals).
pub fn table1<F: RadianceField + ?Sized>(
    exp: &Experiment,
    field: &F,
    stack: &DisplayStack,
    quiet: bool,
    stages: &mut Vec<StageTime>,
) -> Result<Option<Table1>> {
    let (mut gts, mut sims, mut scores) = (Vec::new(), Vec::new(), Vec::new());
    let converged = table1_each(exp, field, stack, quiet, false, stages, &mut |_, case: CaseResult| {
        gts.push(case.ground_truth);
        sims.push(case.perceived);
        scores.extend(case.scores);
        Ok(())
    })?;
    Ok(converged.then_some((gts, sims, scores)))
}

/// [`table1`] one eye case at a time (see [`crate::experiment::table1_each`]); `false` (and
/// nothing done) when `exp` uses the grid estimator. Each case's replicates are reused by the
/// next case once its mean images and scores are taken, unless `keep_replicates` hands them to
/// `each` ([`CaseResult::replicates`]).
#[allow(clippy::too_many_arguments)]
pub fn table1_each<F: RadianceField + ?Sized>(
    exp: &Experiment,
    field: &F,
    stack: &DisplayStack,
    quiet: bool,
    keep_replicates: bool,
    stages: &mut Vec<StageTime>,
    each: &mut dyn FnMut(usize, CaseResult) -> Result<()>,
) -> Result<bool> {
    let m = &exp.measurement;
    if m.estimator != EstimatorKind::Converged {
        return Ok(false);
    }
    let start = Instant::now();
    let budget = (m.max_seconds.is_finite()).then(|| Duration::from_secs_f64(m.max_seconds));
    // One replicate buffer for every eye case: its pages are faulted in once.
    let mut storage = None;
    for (index, case) in exp.cases.iter().enumerate() {
        let t = Instant::now();
        // What is left of the time budget, shared equally by the eye cases still to measure.
        let deadline = budget.map(|b| {
            let left = b.saturating_sub(start.elapsed());
            t + left / (exp.cases.len() - index) as u32
        });
        let precision = Precision {
            psnr_ci95_db: m.psnr_ci95_db,
            ssim_ci95: m.ssim_ci95,
            max_samples_per_pixel: m.max_samples_per_pixel,
            deadline,
            initial_samples: INITIAL_SAMPLES,
            replicates: m.replicates,
        };
        let source = DisplaySource::new(&exp.display, &case.eye, field, stack);
        let sampler = case_sampler(m.seed, index, &case.eye);
        let label = format!("measure {}", case.name);
        let progress = Progress::new(exp.retina.resolution as u64, &label, quiet);
        let perception = perceptual::for_case(exp, index)?;
        // The perceptual scores of the last replicates asked, by samples per pixel.
        let mut asked: Option<(u64, Result<Vec<PerceptualScores>>)> = None;
        let mut further = |reps: &Replicates| {
            let p = perception.as_ref().filter(|_| perceptual::has_targets(exp))?;
            let cells = perceptual::replicate_scores(p, reps);
            let ratios = cells.as_ref().ok().map(|c| perceptual::target_ratios(exp, c));
            asked = Some((reps.samples_per_pixel(), cells));
            ratios
        };
        let old = storage.take();
        let measured =
            measure_case_with(&source, &sampler, &exp.retina, exp.ssim, &precision, &progress, old, &mut further);
        progress.finish();
        progress.check()?;
        let (gt, case_sims, mut case_scores) = case_outputs(exp, case, &measured);
        if let Some(p) = &perception {
            let t = Instant::now();
            let cells = match asked {
                Some((spp, cells)) if spp == measured.samples_per_pixel() => cells?,
                _ => perceptual::replicate_scores(p, &measured.replicates)?,
            };
            perceptual::set_scores(exp, cells, &mut case_scores);
            let seconds = t.elapsed().as_secs_f64();
            stages.push(StageTime {
                stage: "perceptual_scores".into(),
                method: None,
                eye_case: Some(case.name.clone()),
                seconds,
            });
        }
        for (stage, seconds) in [
            ("converged_sampling", measured.rounds.iter().map(|r| r.sample_seconds).sum::<f64>()),
            ("converged_statistics", measured.rounds.iter().map(|r| r.stats_seconds).sum::<f64>()),
        ] {
            stages.push(StageTime { stage: stage.into(), method: None, eye_case: Some(case.name.clone()), seconds });
        }
        let replicates = match keep_replicates {
            true => Some(measured.replicates),
            false => {
                storage = Some(measured.replicates);
                None
            }
        };
        each(index, CaseResult { ground_truth: gt, perceived: case_sims, scores: case_scores, replicates })?;
    }
    Ok(true)
}

fn case_outputs(exp: &Experiment, case: &EyeCase, measured: &CaseMeasurement) -> (RgbImage, Vec<RgbImage>, Vec<Score>) {
    let reps = &measured.replicates;
    let gt = reps.mean_image(0);
    let sims = (1..reps.images()).map(|k| reps.mean_image(k)).collect();
    let scores = exp
        .methods
        .iter()
        .zip(&measured.cells)
        .map(|(m, cell)| Score {
            method: m.name(),
            eye_case: case.name.clone(),
            psnr: cell.psnr,
            ssim: cell.ssim,
            samples_per_pixel: Some(reps.samples_per_pixel()),
            replicates: Some(reps.replicates()),
            target_met: Some(cell.target_met),
            perceptual: Default::default(),
        })
        .collect();
    (gt, sims, scores)
}

/// The naive scores of a measurement: today's PSNR and SSIM of the replicates' mean images
/// (biased by the noise left in them). For the negative control and the bench.
pub fn naive_scores(
    reps: &crate::measure::estimator::Replicates,
    constants: SsimConstants,
) -> Result<Vec<(Psnr, Ssim)>> {
    let reference = reps.mean_image(0);
    (1..reps.images())
        .map(|k| {
            let img = reps.mean_image(k);
            Ok((metrics::psnr(&img, &reference)?, metrics::ssim(&img, &reference, constants)?))
        })
        .collect()
}

/// The EXR attributes of a retinal image measured converged with `samples_per_pixel` samples
/// per retina pixel (all replicates). They replace the grid estimator's pupil-grid attributes of
/// `attributes` (the pupil is sampled as a continuous disk).
pub fn set_exr_attributes(attributes: &mut Attributes, exp: &Experiment, samples_per_pixel: u64) {
    let m = &exp.measurement;
    attributes.0.retain(|(name, _)| name != "inimtrace:pupil_samples" && name != "inimtrace:pupil_grid");
    attributes
        .set("inimtrace:estimator", "converged (randomized QMC: Owen-scrambled Sobol over pixel x pupil disk)")
        .set("inimtrace:pupil_sampling", "continuous disk")
        .set("inimtrace:retina_samples_per_pixel", AttrValue::count(samples_per_pixel as usize))
        .set("inimtrace:replicates", AttrValue::count(m.replicates))
        .set("inimtrace:seed", crate::experiment::metadata::seed_value(m.seed))
        .set("inimtrace:value", "mean over the replicates");
}
