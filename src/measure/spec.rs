//! The `[measurement]` table of an experiment file: how Table 1 (paper Sec. 4.2) is measured.
//!
//! ```toml
//! [measurement]
//! estimator = "converged"        # or "grid": today's regular grids (pupil_grid, retina_samples)
//! psnr_ci95_db = 0.02            # target: every PSNR's 95% half-width (dB)
//! ssim_ci95 = 0.002              # target: every SSIM's 95% half-width
//! max_samples_per_pixel = 4096   # budget: samples per retina pixel, over all replicates
//! max_seconds = 600.0            # budget: wall seconds of the whole measurement
//! seed = 1
//! replicates = 8                 # independent scrambles, at least 3
//! scores = ["psnr", "ssim", "cvvdp", "flip"]   # also "psnr-luminance"; default PSNR and SSIM
//! cvvdp_ci95 = 0.05              # optional targets of the scores named (JOD; FLIP; dB)
//! optics = "auto"                # the eye's optics counted once: "auto", "retinal", "neural"
//! ```
//!
//! A file without the table uses the grid estimator (the published framework's way, and this
//! tool's outputs before the converged measurement existed). Under `converged`, `eye.pupil_grid`
//! and `eye.retina_samples` mean nothing: they must stay at their defaults (8 and 1) or be left
//! out; other values are refused.

use serde::ser::SerializeStruct;
use serde::{Deserialize, Serialize};

use super::sampler::MAX_SAMPLES_PER_REPLICATE;
use super::scores::{ExtraScores, OpticsCount, ScoreName};
use crate::error::{Error, Result};

fn default_scores() -> Vec<ScoreName> {
    vec![ScoreName::Psnr, ScoreName::Ssim]
}

/// How the retinal images and their scores are computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EstimatorKind {
    /// Randomized quasi-Monte Carlo to a stated precision, with 95% intervals.
    #[default]
    Converged,
    /// Regular grids over each pixel and the pupil (`pupil_grid`, `retina_samples`); no error
    /// estimate.
    Grid,
}

impl EstimatorKind {
    /// The name used in experiment files and reports ("converged", "grid").
    pub fn name(self) -> &'static str {
        match self {
            EstimatorKind::Converged => "converged",
            EstimatorKind::Grid => "grid",
        }
    }
}

/// `[measurement]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MeasurementSpec {
    /// The estimator (default converged).
    pub estimator: EstimatorKind,
    /// Target: half-width of every PSNR's 95% interval, dB (the mean of the channels).
    pub psnr_ci95_db: f64,
    /// Target: half-width of every SSIM's 95% interval (the mean of the channels).
    pub ssim_ci95: f64,
    /// Budget: samples per retina pixel over all replicates, per eye case.
    pub max_samples_per_pixel: u64,
    /// Budget: wall seconds of the measurement (all eye cases). Only this budget can make a
    /// result depend on the machine; the report says when it stopped sampling.
    pub max_seconds: f64,
    /// Seed of the scrambles: the same experiment and seed give the same numbers bit for bit.
    pub seed: u64,
    /// Independent replicates (at least 3): the intervals' degrees of freedom are one fewer.
    pub replicates: usize,
    /// The scores reported: PSNR and SSIM (always measured) and any of `psnr-luminance`,
    /// `cvvdp`, `flip` (`crate::perception`).
    pub scores: Vec<ScoreName>,
    /// How the perceptual scores count the eye's optics (`crate::perception::optics_once`).
    pub optics: OpticsCount,
    /// Target: half-width of the luminance PSNR's 95% interval, dB (when named in `scores`).
    pub psnr_luminance_ci95_db: Option<f64>,
    /// Target: half-width of ColorVideoVDP's 95% interval, and bound on its noise bias, JOD
    /// (when named in `scores`).
    pub cvvdp_ci95: Option<f64>,
    /// Target: half-width of the mean FLIP's 95% interval, and bound on its noise bias (when
    /// named in `scores`).
    pub flip_ci95: Option<f64>,
}

impl Default for MeasurementSpec {
    fn default() -> Self {
        Self {
            estimator: EstimatorKind::Converged,
            psnr_ci95_db: 0.02,
            ssim_ci95: 0.002,
            max_samples_per_pixel: 4096,
            max_seconds: 600.0,
            seed: 1,
            replicates: 8,
            scores: default_scores(),
            optics: OpticsCount::Auto,
            psnr_luminance_ci95_db: None,
            cvvdp_ci95: None,
            flip_ci95: None,
        }
    }
}

impl MeasurementSpec {
    /// The grid estimator (what a file without `[measurement]` gets).
    pub fn grid() -> Self {
        Self { estimator: EstimatorKind::Grid, ..Self::default() }
    }

    /// Checks the values; `source` names the file, fields are named `measurement.<field>`.
    pub fn validate(&self, source: &str) -> Result<()> {
        let field = |f: &str| format!("measurement.{f}");
        let extra = self.extra_scores(source)?;
        for (name, target, key) in self.score_targets() {
            let Some(t) = target else { continue };
            if !extra.contains(name) {
                return Err(Error::invalid(
                    source,
                    field(key),
                    format!("is a target of `{name}`, which `measurement.scores` does not name"),
                ));
            }
            if !(t.is_finite() && t > 0.0) {
                return Err(Error::invalid(source, field(key), format!("must be positive, got {t}")));
            }
            if self.estimator == EstimatorKind::Grid {
                return Err(Error::invalid(
                    source,
                    field(key),
                    "is a target of the converged estimator; the grid estimator has no intervals",
                ));
            }
        }
        if self.estimator == EstimatorKind::Grid {
            return self.check_converged_only(source);
        }
        if !(self.psnr_ci95_db.is_finite() && self.psnr_ci95_db > 0.0) {
            return Err(Error::invalid(
                source,
                field("psnr_ci95_db"),
                format!("must be a positive number of dB, got {}", self.psnr_ci95_db),
            ));
        }
        if !(self.ssim_ci95.is_finite() && self.ssim_ci95 > 0.0) {
            return Err(Error::invalid(
                source,
                field("ssim_ci95"),
                format!("must be positive, got {}", self.ssim_ci95),
            ));
        }
        if !(3..=64).contains(&self.replicates) {
            return Err(Error::invalid(
                source,
                field("replicates"),
                format!("must be between 3 and 64 (the intervals need at least 3), got {}", self.replicates),
            ));
        }
        let max = MAX_SAMPLES_PER_REPLICATE * self.replicates as u64;
        if self.max_samples_per_pixel < self.replicates as u64 || self.max_samples_per_pixel > max {
            return Err(Error::invalid(
                source,
                field("max_samples_per_pixel"),
                format!(
                    "must be between `replicates` ({}) and {max} (2^16 per replicate), got {}",
                    self.replicates, self.max_samples_per_pixel
                ),
            ));
        }
        if self.max_seconds.is_nan() || self.max_seconds <= 0.0 {
            return Err(Error::invalid(
                source,
                field("max_seconds"),
                format!("must be positive (inf for no limit), got {}", self.max_seconds),
            ));
        }
        Ok(())
    }
}

impl MeasurementSpec {
    /// The scores beyond PSNR and SSIM (a name given twice is an error naming the field).
    pub fn extra_scores(&self, source: &str) -> Result<ExtraScores> {
        ExtraScores::from_names(&self.scores, source, "measurement.scores")
    }

    /// `(score, its target, the target's key)` of every score that may have one.
    pub fn score_targets(&self) -> [(ScoreName, Option<f64>, &'static str); 3] {
        [
            (ScoreName::PsnrLuminance, self.psnr_luminance_ci95_db, "psnr_luminance_ci95_db"),
            (ScoreName::Cvvdp, self.cvvdp_ci95, "cvvdp_ci95"),
            (ScoreName::Flip, self.flip_ci95, "flip_ci95"),
        ]
    }

    /// The settings of the scores beyond the defaults, as `(key, value)` for [`Serialize`]:
    /// none for a file that does not name them (its echo stays as it was).
    fn score_settings(&self) -> Vec<(&'static str, toml::Value)> {
        let mut out = Vec::new();
        if self.scores != default_scores() {
            let names = self.scores.iter().map(|n| toml::Value::String(n.name().into())).collect();
            out.push(("scores", toml::Value::Array(names)));
        }
        if self.optics != OpticsCount::Auto {
            out.push(("optics", toml::Value::String(self.optics.name().into())));
        }
        for (_, target, key) in self.score_targets() {
            if let Some(t) = target {
                out.push((key, toml::Value::Float(t)));
            }
        }
        out
    }
}

/// Written back as a file would give it: the grid estimator has nothing but its name (and the
/// scores, when the file names any beyond PSNR and SSIM).
impl Serialize for MeasurementSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let extra = self.score_settings();
        if self.estimator == EstimatorKind::Grid {
            let mut st = s.serialize_struct("MeasurementSpec", 1 + extra.len())?;
            st.serialize_field("estimator", &self.estimator)?;
            for (key, value) in &extra {
                st.serialize_field(key, value)?;
            }
            return st.end();
        }
        let mut st = s.serialize_struct("MeasurementSpec", 7 + extra.len())?;
        st.serialize_field("estimator", &self.estimator)?;
        st.serialize_field("psnr_ci95_db", &self.psnr_ci95_db)?;
        st.serialize_field("ssim_ci95", &self.ssim_ci95)?;
        st.serialize_field("max_samples_per_pixel", &self.max_samples_per_pixel)?;
        st.serialize_field("max_seconds", &self.max_seconds)?;
        st.serialize_field("seed", &self.seed)?;
        st.serialize_field("replicates", &self.replicates)?;
        for (key, value) in &extra {
            st.serialize_field(key, value)?;
        }
        st.end()
    }
}

impl MeasurementSpec {
    /// Refuses the converged estimator's settings under the grid estimator, other than their
    /// defaults (which it ignores): an inapplicable field is an error, as an unknown one is.
    fn check_converged_only(&self, source: &str) -> Result<()> {
        let d = Self::default();
        let given = [
            ("psnr_ci95_db", self.psnr_ci95_db.to_bits() != d.psnr_ci95_db.to_bits(), self.psnr_ci95_db.to_string()),
            ("ssim_ci95", self.ssim_ci95.to_bits() != d.ssim_ci95.to_bits(), self.ssim_ci95.to_string()),
            (
                "max_samples_per_pixel",
                self.max_samples_per_pixel != d.max_samples_per_pixel,
                self.max_samples_per_pixel.to_string(),
            ),
            ("max_seconds", self.max_seconds.to_bits() != d.max_seconds.to_bits(), self.max_seconds.to_string()),
            ("seed", self.seed != d.seed, self.seed.to_string()),
            ("replicates", self.replicates != d.replicates, self.replicates.to_string()),
        ];
        match given.iter().find(|(_, differs, _)| *differs) {
            Some((key, _, value)) => Err(Error::invalid(
                source,
                format!("measurement.{key}"),
                format!(
                    "{value} is a setting of the converged estimator; the grid estimator has no samples, seed or \
                     targets to set (remove it, or set measurement.estimator = \"converged\")"
                ),
            )),
            None => Ok(()),
        }
    }

    /// Refuses grid-only settings under the converged estimator: `eye.pupil_grid` and
    /// `eye.retina_samples` other than their defaults (which the converged estimator ignores).
    /// `settings` are `(key, value, default)` of the eye's grid-only settings.
    pub fn check_grid_only(&self, source: &str, settings: [(&str, usize, usize); 2]) -> Result<()> {
        if self.estimator != EstimatorKind::Converged {
            return Ok(());
        }
        for (key, value, default) in settings {
            if value != default {
                return Err(Error::invalid(
                    source,
                    format!("eye.{key}"),
                    format!(
                        "{value} is a setting of the grid estimator; the converged estimator integrates each retina \
                         pixel and the pupil disk (remove it, or set measurement.estimator = \"grid\")"
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_defaults_to_converged_and_round_trips() {
        let m: MeasurementSpec = toml::from_str("seed = 5").unwrap();
        assert_eq!(m, MeasurementSpec { seed: 5, ..MeasurementSpec::default() });
        let back: MeasurementSpec = toml::from_str(&toml::to_string(&m).unwrap()).unwrap();
        assert_eq!(back, m);
        let g: MeasurementSpec = toml::from_str("estimator = \"grid\"").unwrap();
        assert_eq!(g, MeasurementSpec::grid());
        assert_eq!(toml::to_string(&g).unwrap().trim(), "estimator = \"grid\"");
        assert!(toml::from_str::<MeasurementSpec>("estimator = \"exact\"").is_err());
        assert!(toml::from_str::<MeasurementSpec>("replicate = 3").is_err());
    }

    #[test]
    fn scores_default_to_psnr_and_ssim_and_round_trip() {
        let m: MeasurementSpec =
            toml::from_str("scores = [\"psnr\", \"ssim\", \"cvvdp\", \"flip\"]\ncvvdp_ci95 = 0.05").unwrap();
        assert_eq!(m.extra_scores("x").unwrap().names(), &[ScoreName::Cvvdp, ScoreName::Flip]);
        let back: MeasurementSpec = toml::from_str(&toml::to_string(&m).unwrap()).unwrap();
        assert_eq!(back, m);
        // The default writes nothing new (results.json's settings stay as they were).
        assert!(!toml::to_string(&MeasurementSpec::default()).unwrap().contains("scores"));
        let e = toml::from_str::<MeasurementSpec>("scores = [\"psnr\", \"jod\"]").unwrap_err().to_string();
        assert!(e.contains("unknown score `jod`") && e.contains("scores"), "{e}");
        for (text, field) in [
            ("cvvdp_ci95 = 0.1", "measurement.cvvdp_ci95"),
            ("scores = [\"flip\"]\nflip_ci95 = -1.0", "measurement.flip_ci95"),
            ("scores = [\"flip\", \"flip\"]", "measurement.scores"),
            ("estimator = \"grid\"\nscores = [\"flip\"]\nflip_ci95 = 0.01", "measurement.flip_ci95"),
        ] {
            let m: MeasurementSpec = toml::from_str(text).unwrap();
            let e = m.validate("x.toml").unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("x.toml"), "{text}: {e}");
        }
    }

    #[test]
    fn bad_values_name_the_field() {
        for (m, field) in [
            (MeasurementSpec { replicates: 2, ..Default::default() }, "measurement.replicates"),
            (MeasurementSpec { psnr_ci95_db: 0.0, ..Default::default() }, "measurement.psnr_ci95_db"),
            (MeasurementSpec { ssim_ci95: f64::NAN, ..Default::default() }, "measurement.ssim_ci95"),
            (MeasurementSpec { max_samples_per_pixel: 4, ..Default::default() }, "measurement.max_samples_per_pixel"),
            (
                MeasurementSpec { max_samples_per_pixel: 1 << 20, ..Default::default() },
                "measurement.max_samples_per_pixel",
            ),
            (MeasurementSpec { max_seconds: 0.0, ..Default::default() }, "measurement.max_seconds"),
        ] {
            let e = m.validate("x.toml").unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("x.toml"), "{e}");
        }
        MeasurementSpec { max_seconds: f64::INFINITY, ..Default::default() }.validate("x").unwrap();
    }

    #[test]
    fn grid_only_settings_are_refused_under_converged() {
        let c = MeasurementSpec::default();
        let e = c.check_grid_only("e.toml", [("pupil_grid", 16, 8), ("retina_samples", 1, 1)]).unwrap_err().to_string();
        assert!(e.contains("e.toml") && e.contains("eye.pupil_grid"), "{e}");
        let e = c.check_grid_only("e.toml", [("pupil_grid", 8, 8), ("retina_samples", 2, 1)]).unwrap_err().to_string();
        assert!(e.contains("eye.retina_samples"), "{e}");
        c.check_grid_only("e", [("pupil_grid", 8, 8), ("retina_samples", 1, 1)]).unwrap();
        MeasurementSpec::grid().check_grid_only("e", [("pupil_grid", 16, 8), ("retina_samples", 4, 1)]).unwrap();
    }
}
