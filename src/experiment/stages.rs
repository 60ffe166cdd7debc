//! The stages of an assessment (Sec. 4, Fig. 2): the display image of every method (Sec. 3),
//! the packed display stack, the ground-truth and perceived retinal images of each eye case, and
//! the Table-1 scores, each timed. `assess` and `inimtrace bench` both run these functions.

use std::borrow::Borrow;
use std::time::Instant;

use rayon::prelude::*;

use super::{Experiment, EyeCase, Score, StageTime};
use crate::error::{Error, Result};
use crate::metrics;
use crate::optimize::OptimizationReport;
use crate::progress::Progress;
use crate::raster::{RgbImage, RgbView};
use crate::render::display_stack::StackBuilder;
use crate::render::retina::{simulate_stack, DisplayStack};
use crate::render::{ground_truth, Method, RadianceField};

pub(super) fn stage_time(
    stages: &mut Vec<StageTime>,
    stage: &str,
    method: Option<&str>,
    case: Option<&str>,
    t: Instant,
) {
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

/// Stage 1 of [`assess`](super::assess()): the display image of every method of `exp` and its depth plane (when
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
        let p = crate::methods::progress(display, *m, exp.optimize.as_ref(), quiet);
        let (img, depth, _) = crate::methods::render(display, *m, &exp.render, exp.optimize.as_ref(), with_depth, &p)?;
        p.finish();
        stage_time(stages, "render_display", Some(m.name().as_str()), None, t);
        displays.push(img);
        depths.push(depth);
    }
    Ok((displays, depths))
}

/// OPT's display image for `exp` (its `[optimize]` training states) into `image`, with its
/// convergence record. Errors when `exp` has no resolved `[optimize]` (OPT not among its methods).
pub fn render_optimized<D: RadianceField + ?Sized>(
    exp: &Experiment,
    field: &D,
    quiet: bool,
    image: &mut RgbImage,
) -> Result<OptimizationReport> {
    let (opt, m) = (exp.optimize.as_ref(), Method::Optimized);
    let p = crate::methods::progress(&exp.display, m, opt, quiet);
    let r = crate::methods::render_into(&exp.display, m, &exp.render, opt, field, &p, image, &mut Vec::new())?;
    p.finish();
    r.optimization.ok_or_else(|| Error::Mismatch("OPT's display image came without its record".into()))
}

/// Stage 1 as `assess` runs it: every method's display image rendered into one reused image
/// buffer and depth plane (`render_display` stages), handed to `finished` (method index, the image, its depth
/// plane; timed as `write_display_image`), then added to the stack the simulation reads
/// (`pack_display_images`: palette indices while the images allow, see
/// [`crate::render::display_stack`]), before the next is rendered. The stack reads as
/// [`pack_display_images`] of [`render_display_images`] bit for bit (tested). OPT's convergence
/// record, when OPT is among the methods, comes back beside the stack.
pub fn render_display_stack<D: RadianceField + ?Sized>(
    exp: &Experiment,
    with_depth: &D,
    quiet: bool,
    stages: &mut Vec<StageTime>,
    mut finished: impl FnMut(usize, RgbView<'_>, Option<&[f32]>) -> Result<()>,
) -> Result<(DisplayStack, Option<OptimizationReport>)> {
    let mut optimized = None;
    let display = &exp.display;
    // One image buffer for every method; the stack keeps palette indices when it can.
    let (mut image, mut depth) =
        (RgbImage::try_new(display.lcd.columns(), display.lcd.rows(), "the display image")?, Vec::new());
    let mut stack = StackBuilder::new(display, exp.methods.len());
    for (k, m) in exp.methods.iter().enumerate() {
        let t = Instant::now();
        let p = crate::methods::progress(display, *m, exp.optimize.as_ref(), quiet);
        let r = crate::methods::render_into(
            display,
            *m,
            &exp.render,
            exp.optimize.as_ref(),
            with_depth,
            &p,
            &mut image,
            &mut depth,
        )?;
        p.finish();
        let known = r.depth_known;
        if r.optimization.is_some() {
            optimized = r.optimization;
        }
        stage_time(stages, "render_display", Some(m.name().as_str()), None, t);
        let t = Instant::now();
        finished(k, RgbView::from(&image), known.then_some(depth.as_slice()))?;
        stage_time(stages, "write_display_image", Some(m.name().as_str()), None, t);
        crate::progress::check_cancelled()?;
        let t = Instant::now();
        stack.push(RgbView::from(&image))?;
        stage_time(stages, "pack_display_images", Some(m.name().as_str()), None, t);
    }
    Ok((stack.finish()?, optimized))
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

/// Stage 2a of [`assess`](super::assess()): the ground-truth retinal image of one eye case (`ground_truth` stage).
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

/// Stage 2b of [`assess`](super::assess()): what the eye of one eye case perceives of every display image in
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

/// The ground truth and perceived images of every eye case and every display image in `stack`,
/// with their Table 1 scores: stages 2-3 of [`assess`](super::assess()), which `inimtrace sweep`
/// runs for each point on display images shared between points.
pub type Table1 = (Vec<RgbImage>, Vec<Vec<RgbImage>>, Vec<Score>);

/// Stages 2-3 of [`assess`](super::assess()): per eye case the ground truth and the perceived
/// images, then the scores ([`Table1`]), measured by the experiment's estimator: the converged
/// one (`src/measure/`) or the grid one. Collects [`table1_each`].
pub fn table1<S: RadianceField + ?Sized>(
    exp: &Experiment,
    shade: &S,
    stack: &DisplayStack,
    quiet: bool,
    stages: &mut Vec<StageTime>,
) -> Result<Table1> {
    let (mut gts, mut sims, mut scores) = (Vec::new(), Vec::new(), Vec::new());
    table1_each(exp, shade, stack, quiet, false, stages, |_, case| {
        gts.push(case.ground_truth);
        sims.push(case.perceived);
        scores.extend(case.scores);
        Ok(())
    })?;
    Ok((gts, sims, scores))
}

/// One eye case of Table 1: its ground truth, the perceived image of every method (in the
/// experiment's order) and their scores.
pub struct CaseResult {
    /// What the eye looking straight at the scene sees.
    pub ground_truth: RgbImage,
    /// What the eye perceives of each method's display image.
    pub perceived: Vec<RgbImage>,
    /// PSNR and SSIM of each perceived image against the ground truth.
    pub scores: Vec<Score>,
    /// The converged estimator's replicates (image 0 the ground truth, then one per method),
    /// when asked for (`keep_replicates`); `None` for the grid estimator.
    pub replicates: Option<crate::measure::estimator::Replicates>,
}

/// [`table1`] one eye case at a time: `each(case index, its results)` is called as soon as a
/// case is measured, so a caller can write and drop its images before the next case (`assess`
/// does; its peak memory then holds one case's images, not all of them). Grid estimator stages:
/// `ground_truth`, `simulate_all_methods` and `metrics` per case.
pub fn table1_each<S: RadianceField + ?Sized>(
    exp: &Experiment,
    shade: &S,
    stack: &DisplayStack,
    quiet: bool,
    keep_replicates: bool,
    stages: &mut Vec<StageTime>,
    mut each: impl FnMut(usize, CaseResult) -> Result<()>,
) -> Result<()> {
    if crate::experiment::converged::table1_each(exp, shade, stack, quiet, keep_replicates, stages, &mut each)? {
        return Ok(());
    }
    for (c, case) in exp.cases.iter().enumerate() {
        let gt = ground_truth_image(exp, case, shade, quiet, stages);
        // A cancelled ground truth skipped rows (`crate::progress`): stop before it is used.
        crate::progress::check_cancelled()?;
        let sims = perceived_images(exp, case, stack, quiet, stages)?;
        let t = Instant::now();
        let scores = case_scores(exp, c, &gt, &sims)?;
        stage_time(stages, "metrics", None, Some(&case.name), t);
        each(c, CaseResult { ground_truth: gt, perceived: sims, scores, replicates: None })?;
    }
    Ok(())
}

/// The Table 1 scores of eye case `c`: PSNR and SSIM of every perceived image against `gt`.
fn case_scores(exp: &Experiment, c: usize, gt: &RgbImage, sims: &[RgbImage]) -> Result<Vec<Score>> {
    let perception = super::perceptual::for_case(exp, c)?;
    sims.par_iter()
        .zip(&exp.methods)
        .map(|(sim, m)| -> Result<Score> {
            let perceptual = match &perception {
                Some(p) => p.score_images(sim, gt)?,
                None => Default::default(),
            };
            Ok(Score {
                method: m.name(),
                eye_case: exp.cases[c].name.clone(),
                psnr: metrics::psnr(sim, gt)?.into(),
                ssim: metrics::ssim(sim, gt, exp.ssim)?.into(),
                samples_per_pixel: None,
                replicates: None,
                target_met: None,
                perceptual,
            })
        })
        .collect()
}

/// Stage 3 of [`assess`](super::assess()), Table 1: PSNR and SSIM of `sims[case][method]` against `gts[case]`,
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
        return Err(Error::Mismatch(
            "table1_scores: one ground truth per eye case and one perceived image per method and eye case".into(),
        ));
    }
    let per_case: Vec<Vec<Score>> = (0..exp.cases.len())
        .into_par_iter()
        .map(|c| case_scores(exp, c, gts[c].borrow(), &sims[c]))
        .collect::<Result<_>>()?;
    let scores: Vec<Score> = per_case.into_iter().flatten().collect();
    stage_time(stages, "metrics", None, None, t);
    Ok(scores)
}
