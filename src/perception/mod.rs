//! What a person would notice: perceptual scores of a perceived retinal image against its ground
//! truth at the display's real luminance, beside the paper's PSNR and SSIM (Sec. 4.2, Table 1).
//! See `docs/PERCEPTION.md`.
//!
//! - the score names of `[measurement] scores` and how they count the eye's optics are the
//!   measurement's settings ([`crate::measure::scores`]);
//! - [`viewing`]: the display's absolute luminance and the retina image's pixels per degree;
//! - [`luminance`]: the luminance PSNR, plain and from the converged estimator's replicates;
//! - [`cvvdp`]: ColorVideoVDP (Mantiuk et al. 2024) in JOD, with its distortion map;
//! - [`flip`]: HDR-FLIP (Andersson et al. 2020, 2021), its mean and its map;
//! - [`optics_once`]: the eye's optics counted once (Barten's typical optics divided out);
//! - [`replicated`]: the nonlinear scores of the replicates, corrected for the noise's bias, with
//!   intervals that hold the correction's uncertainty.

pub mod cvvdp;
pub mod flip;
pub mod luminance;
pub mod optics_once;
pub mod replicated;
pub mod viewing;

use serde::ser::SerializeMap;
use serde::Serialize;

use crate::error::Result;
use crate::measure::estimator::Replicates;
pub use crate::measure::scores::{ExtraScores, ScoreName};
use crate::raster::RgbImage;
pub use optics_once::{Compensation, OpticsCount};
pub use replicated::{BiasExponent, ScalarEstimate};
pub use viewing::{DisplayLuminance, Viewing, BT709_LUMINANCE};

/// The extra scores of one perceived image, in report order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PerceptualScores(pub Vec<(ScoreName, ScalarEstimate)>);

impl PerceptualScores {
    /// The score named `name`, if measured.
    pub fn get(&self, name: ScoreName) -> Option<&ScalarEstimate> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, e)| e)
    }

    /// True when no extra score was asked for.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// In JSON: `{"cvvdp": {"value": ..., "ci95": ..., "noise_bias": ...}, ...}`.
impl Serialize for PerceptualScores {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (n, e) in &self.0 {
            m.serialize_entry(n.name(), e)?;
        }
        m.end()
    }
}

/// A distortion map of one score: one value per pixel, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct DistortionMap {
    /// The score it belongs to (ColorVideoVDP: `1 - JOD_pixel / 10`; FLIP: the per-pixel error).
    pub score: ScoreName,
    /// Width and height.
    pub size: (usize, usize),
    /// The values.
    pub values: Vec<f32>,
}

/// The extra scores of an experiment and how its images are seen: build once per eye case.
pub struct Perception {
    scores: ExtraScores,
    viewing: Viewing,
    weights: [f64; 3],
    compensation: Option<Compensation>,
    cvvdp: Option<cvvdp::Cvvdp>,
}

impl Perception {
    /// The extra `scores` of `size` (width, height) images seen as `viewing` says, with
    /// luminance `weights` (the luminance PSNR's), the typical eye's optics divided out when
    /// `compensate` gives that eye's pupil diameter (mm).
    pub fn new(
        scores: &ExtraScores,
        viewing: &Viewing,
        weights: [f64; 3],
        size: (usize, usize),
        compensate: Option<f64>,
    ) -> Result<Self> {
        let cvvdp = match scores.contains(ScoreName::Cvvdp) {
            true => Some(cvvdp::Cvvdp::new(viewing, size.0, size.1, false)?),
            false => None,
        };
        if scores.contains(ScoreName::Flip) {
            viewing.validate("FLIP", "luminance")?;
        }
        let compensation = compensate.map(|pupil| Compensation::new(pupil, viewing.pixels_per_degree));
        Ok(Self { scores: scores.clone(), viewing: *viewing, weights, compensation, cvvdp })
    }

    /// The extra scores asked for.
    pub fn scores(&self) -> &ExtraScores {
        &self.scores
    }

    /// Whether the typical eye's optics are divided out before the perceptual metrics.
    pub fn compensates(&self) -> bool {
        self.compensation.is_some()
    }

    /// One perceptual score of a pair as the metric sees it (after the compensation).
    fn perceptual(&self, name: ScoreName, test: &RgbImage, reference: &RgbImage) -> Result<f64> {
        let (t, r);
        let (test, reference) = match &self.compensation {
            Some(c) => {
                (t, r) = (c.apply(test), c.apply(reference));
                (&t, &r)
            }
            None => (test, reference),
        };
        match name {
            ScoreName::Cvvdp => match &self.cvvdp {
                Some(m) => Ok(m.score(test, reference)?.jod),
                None => cvvdp::Cvvdp::new(&self.viewing, test.width, test.height, false)?
                    .score(test, reference)
                    .map(|j| j.jod),
            },
            ScoreName::Flip => Ok(flip::flip(test, reference, &self.viewing)?.mean),
            other => unreachable!("{other} is not a perceptual score"),
        }
    }

    /// The extra scores of `test` against `reference` (two plain images: no interval).
    pub fn score_images(&self, test: &RgbImage, reference: &RgbImage) -> Result<PerceptualScores> {
        let mut out = Vec::new();
        for &name in self.scores.names() {
            let value = match name {
                ScoreName::PsnrLuminance => luminance::psnr_luminance(test, reference, self.weights)?,
                _ => self.perceptual(name, test, reference)?,
            };
            out.push((name, ScalarEstimate::exact(value)));
        }
        Ok(PerceptualScores(out))
    }

    /// The extra scores of image `k` of `reps` against image 0, with 95% intervals; the
    /// perceptual scores corrected for the noise's bias ([`replicated`]).
    pub fn score_replicates(&self, reps: &Replicates, k: usize) -> Result<PerceptualScores> {
        let mut out = Vec::new();
        for &name in self.scores.names() {
            let e = match name {
                ScoreName::PsnrLuminance => {
                    let e = luminance::psnr_luminance_estimate(reps, k, self.weights);
                    ScalarEstimate { value: e.mean, ci95: e.ci95, noise_bias: None }
                }
                _ => {
                    let a = match name {
                        ScoreName::Flip => BiasExponent::KINKED,
                        _ => BiasExponent::SMOOTH,
                    };
                    replicated::replicated_estimate(reps, k, a, &|t, r| self.perceptual(name, t, r))?
                }
            };
            out.push((name, e));
        }
        Ok(PerceptualScores(out))
    }

    /// The distortion maps of the perceptual scores asked for, of `test` against `reference`.
    pub fn maps(&self, test: &RgbImage, reference: &RgbImage) -> Result<Vec<DistortionMap>> {
        let (t, r);
        let (test, reference) = match &self.compensation {
            Some(c) => {
                (t, r) = (c.apply(test), c.apply(reference));
                (&t, &r)
            }
            None => (test, reference),
        };
        let size = (test.width, test.height);
        let mut out = Vec::new();
        for &name in self.scores.names() {
            let values = match name {
                ScoreName::Cvvdp => {
                    let m = cvvdp::Cvvdp::new(&self.viewing, size.0, size.1, true)?;
                    m.score(test, reference)?.map.unwrap_or_default()
                }
                ScoreName::Flip => flip::flip(test, reference, &self.viewing)?.map,
                _ => continue,
            };
            out.push(DistortionMap { score: name, size, values });
        }
        Ok(out)
    }
}
