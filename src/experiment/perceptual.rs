//! The perceptual scores of an experiment's eye cases (`[measurement] scores`, see
//! `crate::perception` and docs/PERCEPTION.md): how each case's images are seen (the retina's
//! pixels per degree, the display's luminance, the eye's optics counted once), the scores of the
//! grid estimator's images and of the converged estimator's replicates, and their distortion
//! maps.

use crate::error::Result;
use crate::experiment::{Experiment, Score};
use crate::measure::estimator::Replicates;
use crate::optics::eye::model::EyeModel;
use crate::optics::Aperture;
use crate::perception::{Perception, PerceptualScores, ScoreName, Viewing};

/// Whether eye case `c`'s retinal images hold a real eye's aberrations (a schematic eye focused
/// through a pupil), which the perceptual metrics' sensitivity holds already.
pub fn has_aberrations(exp: &Experiment, c: usize) -> bool {
    let eye = &exp.cases[c].eye;
    matches!(eye.aperture, Aperture::ThinLens { .. })
        && eye.optics.as_ref().is_some_and(|o| !matches!(o.model, EyeModel::ThinLens))
}

/// The entrance pupil's diameter of eye case `c`, mm (0 for a pinhole).
fn pupil_mm(exp: &Experiment, c: usize) -> f64 {
    match exp.cases[c].eye.aperture {
        Aperture::Pinhole => 0.0,
        Aperture::ThinLens { pupil_diameter, .. } => pupil_diameter,
    }
}

/// How eye case `c`'s images are seen: the retina's pixels per degree, the display's luminance.
pub fn viewing(exp: &Experiment) -> Viewing {
    Viewing::of_retina(&exp.retina, exp.luminance)
}

/// The scorer of eye case `c`'s extra scores (`None` when the experiment names none).
pub fn for_case(exp: &Experiment, c: usize) -> Result<Option<Perception>> {
    if exp.extra_scores.is_empty() {
        return Ok(None);
    }
    let n = exp.retina.resolution;
    let compensate = exp.measurement.optics.compensates(has_aberrations(exp, c)).then(|| pupil_mm(exp, c));
    let compensate = compensate.filter(|d| *d > 0.0);
    let weights = exp.display.luminance_weights();
    Perception::new(&exp.extra_scores, &viewing(exp), weights, (n, n), compensate).map(Some)
}

/// The extra scores of every scored image of `reps` against image 0 (one per method, in order).
pub fn replicate_scores(p: &Perception, reps: &Replicates) -> Result<Vec<PerceptualScores>> {
    (1..reps.images()).map(|k| p.score_replicates(reps, k)).collect()
}

/// Every cell's half-width over its `[measurement]` target, of every extra score that has one
/// (empty when none has).
pub fn target_ratios(exp: &Experiment, cells: &[PerceptualScores]) -> Vec<f64> {
    let targets = exp.measurement.score_targets();
    let mut out = Vec::new();
    for cell in cells {
        for (name, target, _) in &targets {
            if let (Some(e), Some(t)) = (cell.get(*name), target) {
                out.push(e.ci95.unwrap_or(f64::INFINITY) / t);
            }
        }
    }
    out
}

/// Sets each cell's extra scores (one per method, in order), and marks a cell whose extra score
/// misses its `[measurement]` target as not met.
pub fn set_scores(exp: &Experiment, cells: Vec<PerceptualScores>, scores: &mut [Score]) {
    for (score, cell) in scores.iter_mut().zip(cells) {
        let met = target_ratios(exp, std::slice::from_ref(&cell)).iter().all(|r| *r <= 1.0);
        score.perceptual = cell;
        if !met {
            score.target_met = Some(false);
        }
    }
}

/// Whether any extra score of `exp` has a `[measurement]` target (which then drives the
/// converged estimator's sampling).
pub fn has_targets(exp: &Experiment) -> bool {
    exp.measurement.score_targets().iter().any(|(n, t, _)| t.is_some() && exp.extra_scores.contains(*n))
}

/// The extra scores of a figure caption (`, JOD 9.12, FLIP 0.031`; empty when none are named).
pub fn caption(score: &Score) -> String {
    score
        .perceptual
        .0
        .iter()
        .map(|(n, e)| match n {
            ScoreName::Cvvdp => format!(", JOD {:.2}", e.value),
            ScoreName::Flip => format!(", FLIP {:.3}", e.value),
            _ => format!(", PSNR-Y {} dB", crate::metrics::format_db(e.value, 2)),
        })
        .collect()
}
