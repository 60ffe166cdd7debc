//! Table 1 convergence: the paper's Table 1 (PSNR and SSIM of the perceived image against the
//! ground-truth retinal image, per method and eye case) computed by `assess`'s stage functions
//! with one sampling parameter swept and the others at the paper's settings, one row per
//! setting, method and eye case.

use std::collections::HashMap;
use std::sync::Arc;

use super::options::{la_grid_of, BenchRow, MethodLabel, Parameter, Quantity, RowContext, Series, Sizes};
use super::pipeline::{display_images, focus_mm, ground_truth_image, perceived_images, with_methods, Sampling};
use super::runs::Field;
use super::summary::capped_psnr;
use crate::error::Result;
use crate::experiment::{self, Experiment};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::{Method, RadianceField};

/// Sweeps of the Table 1 series, in report order.
pub const TABLE1_SWEEPS: [Parameter; 4] =
    [Parameter::RetinaSamples, Parameter::DisplaySamples, Parameter::PupilGrid, Parameter::LaGrid];

/// Table 1 at one setting.
#[derive(Clone)]
struct Point {
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
struct Runner<'a> {
    base: &'a Experiment,
    paper: Sampling,
    field: &'a dyn RadianceField,
    displays: HashMap<(Method, usize), (Arc<RgbImage>, f64)>,
    gts: HashMap<(String, usize, usize), (Arc<RgbImage>, f64)>,
    points: HashMap<Sampling, Point>,
}

impl Runner<'_> {
    /// The display image of method `m` of `exp` (at setting `s`), from the cache when it holds it.
    fn display_image(&mut self, exp: &Experiment, m: Method, s: Sampling) -> Result<(Arc<RgbImage>, f64)> {
        let key = (m, s.display);
        if let Some((img, t)) = self.displays.get(&key) {
            return Ok((img.clone(), *t));
        }
        let (mut img, t) = display_images(&with_methods(exp, &[m]), self.field)?;
        let img = Arc::new(img.remove(0));
        let paper_la = !matches!(m, Method::LensletAverage { .. }) || s.la == self.paper.la;
        if s.display == self.paper.display && paper_la {
            self.displays.insert(key, (img.clone(), t));
        }
        Ok((img, t))
    }

    /// The ground truth of eye case `c` of `exp` (at setting `s`), from the cache when it holds it.
    fn ground_truth(&mut self, exp: &Experiment, c: usize, s: Sampling) -> (Arc<RgbImage>, f64) {
        let case = &exp.cases[c];
        let key = (case.name.clone(), s.pupil, s.retina);
        if let Some((img, t)) = self.gts.get(&key) {
            return (img.clone(), *t);
        }
        let (img, t) = ground_truth_image(exp, case, self.field);
        let img = Arc::new(img);
        if s.pupil == self.paper.pupil && s.retina == self.paper.retina {
            self.gts.insert(key, (img.clone(), t));
        }
        (img, t)
    }

    fn point(&mut self, s: Sampling) -> Result<Point> {
        if let Some(p) = self.points.get(&s) {
            return Ok(p.clone());
        }
        let exp = s.apply(self.base);
        let mut seconds = 0.0;
        let mut displays = Vec::new();
        for &m in &exp.methods {
            let (img, t) = self.display_image(&exp, m, s)?;
            seconds += t;
            displays.push(img);
        }
        let mut gts = Vec::new();
        for c in 0..exp.cases.len() {
            let (img, t) = self.ground_truth(&exp, c, s);
            seconds += t;
            gts.push(img);
        }
        let sims = perceived_images(&exp, &displays.iter().map(|d| d.as_ref()).collect::<Vec<_>>())?;
        drop(displays);
        seconds += sims.pack_seconds + sims.case_seconds.iter().sum::<f64>();
        let mut stages = Vec::new();
        let scores = experiment::table1_scores(&exp, &gts, &sims.images, &mut stages)?;
        seconds += super::pipeline::stage_seconds(&stages);
        let lcd_px = (exp.display.lcd.columns() * exp.display.lcd.rows()) as u64;
        let ret_px = (exp.retina.resolution * exp.retina.resolution) as u64;
        let camera_rays: u64 =
            exp.methods.iter().map(|m| lcd_px * (s.display * s.display * m.lenslet_samples()) as u64).sum();
        // Ground truth and simulation each trace every retina sample through every pupil sample.
        let eye_rays: u64 =
            exp.cases.iter().map(|c| 2 * ret_px * (s.retina * s.retina * c.eye.pupil_samples().len()) as u64).sum();
        let p = Point { exp, scores, seconds, rays: camera_rays + eye_rays };
        if s == self.paper {
            self.points.insert(s, p.clone());
        }
        Ok(p)
    }
}

/// Runs every Table 1 sweep of `sizes` on `best` from the paper's experiment `base`, appending
/// one row per setting, method and eye case to `rows`.
pub fn table1_series(
    base: &Experiment,
    sizes: &Sizes,
    best: &Field<'_>,
    ctx: &RowContext,
    progress: &Progress,
    rows: &mut Vec<BenchRow>,
) -> Result<()> {
    let paper = Sampling::of(base);
    let mut runner = Runner {
        base,
        paper,
        field: best.field,
        displays: HashMap::new(),
        gts: HashMap::new(),
        points: HashMap::new(),
    };
    for sweep in TABLE1_SWEEPS {
        for &v in sizes.table1_settings(sweep) {
            let s = paper.with(sweep, v);
            let p = runner.point(s)?;
            rows.extend(point_rows(&p, sweep, v, s, best, ctx));
        }
        progress.inc(1);
    }
    Ok(())
}

/// The rows of Table 1 at setting `s` (`sweep` = `v`): one per score, in the scores' order.
fn point_rows(p: &Point, sweep: Parameter, v: usize, s: Sampling, best: &Field<'_>, ctx: &RowContext) -> Vec<BenchRow> {
    // Pupil samples of the setting: those of the thin-lens eye cases (a pinhole has one).
    let kept = p.exp.cases.iter().map(|c| c.eye.pupil_samples().len()).max().unwrap_or(1);
    let samples = match sweep {
        Parameter::PupilGrid => kept,
        Parameter::RetinaSamples | Parameter::DisplaySamples | Parameter::LaGrid => v * v,
    };
    let mut rows = Vec::new();
    for sc in &p.scores {
        let Some(case) = p.exp.cases.iter().find(|c| c.name == sc.eye_case) else { continue };
        let Some(&method) = p.exp.methods.iter().find(|m| m.short_name() == sc.method) else { continue };
        let r = BenchRow {
            eye_case: sc.eye_case.clone(),
            focus_mm: focus_mm(case),
            parameter: v,
            samples,
            display_samples: s.display,
            la_grid: la_grid_of(method),
            pupil_grid: s.pupil,
            pupil_samples: case.eye.pupil_samples().len(),
            retina_samples: s.retina,
            reference: "ground truth (same eye, same samples per retina pixel)".into(),
            ..ctx.row(Series::Table1, sweep, Quantity::Perceived, best.backend, MethodLabel::from(method))
        };
        rows.push(r.measured(p.seconds, p.rays, (capped_psnr(sc.psnr.mean), sc.ssim.mean)));
    }
    rows
}
