//! The scores a measurement can report (`[measurement] scores`): the paper's Table 1 pair, PSNR
//! and SSIM (Sec. 4.2), the luminance PSNR, and the perceptual scores ColorVideoVDP (Mantiuk et
//! al., SIGGRAPH 2024, ACM TOG 43(4):129) and FLIP (Andersson et al., HPG 2020; its HDR variant,
//! Andersson et al., Eurographics 2021 short papers). PSNR and SSIM are always measured (the
//! table's columns and the converged estimator's stopping rule); the others only when named.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Error, Result};

/// One score name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ScoreName {
    /// PSNR, the mean of the R, G and B channel PSNRs (linear values, peak 1), dB.
    Psnr,
    /// SSIM (Wang et al. 2004), the mean of the channels.
    Ssim,
    /// PSNR of the luminance (the display primaries' luminance weights; peak: the white's), dB.
    PsnrLuminance,
    /// ColorVideoVDP, in just-objectionable differences (JOD; 10: no visible difference).
    Cvvdp,
    /// HDR-FLIP, the mean of its per-pixel map (0: no visible difference, 1: the largest).
    Flip,
}

impl ScoreName {
    /// Every score, in report order.
    pub const ALL: [ScoreName; 5] =
        [ScoreName::Psnr, ScoreName::Ssim, ScoreName::PsnrLuminance, ScoreName::Cvvdp, ScoreName::Flip];

    /// The name in experiment files, sweeps, reports and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ScoreName::Psnr => "psnr",
            ScoreName::Ssim => "ssim",
            ScoreName::PsnrLuminance => "psnr-luminance",
            ScoreName::Cvvdp => "cvvdp",
            ScoreName::Flip => "flip",
        }
    }

    /// The unit as a report prints it.
    pub fn unit(self) -> &'static str {
        match self {
            ScoreName::Psnr | ScoreName::PsnrLuminance => "dB",
            ScoreName::Cvvdp => "JOD",
            ScoreName::Ssim | ScoreName::Flip => "",
        }
    }

    /// Whether a larger value means a better (less visibly different) image.
    pub fn higher_is_better(self) -> bool {
        !matches!(self, ScoreName::Flip)
    }

    /// Whether the score needs the display's luminance and the retina's pixels per degree.
    pub fn is_perceptual(self) -> bool {
        matches!(self, ScoreName::Cvvdp | ScoreName::Flip)
    }
}

impl fmt::Display for ScoreName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ScoreName {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        ScoreName::ALL.into_iter().find(|n| n.name() == s).ok_or_else(|| {
            let names: Vec<&str> = ScoreName::ALL.iter().map(|n| n.name()).collect();
            Error::invalid("scores", "name", format!("unknown score `{s}` (expected one of {})", names.join(", ")))
        })
    }
}

impl Serialize for ScoreName {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for ScoreName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(|_| {
            let names: Vec<&str> = ScoreName::ALL.iter().map(|n| n.name()).collect();
            serde::de::Error::custom(format!("unknown score `{s}` (expected one of {})", names.join(", ")))
        })
    }
}

/// The scores beyond PSNR and SSIM that a measurement reports, in [`ScoreName::ALL`]'s order
/// whatever order they were named in. Empty: the paper's Table 1 alone (the default).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ExtraScores(Vec<ScoreName>);

impl ExtraScores {
    /// The extra scores among `names` (PSNR and SSIM, always measured, are dropped); a name
    /// given twice is an error naming `field` of `source`.
    pub fn from_names(names: &[ScoreName], source: &str, field: &str) -> Result<Self> {
        let mut seen = std::collections::BTreeSet::new();
        for n in names {
            if !seen.insert(*n) {
                return Err(Error::invalid(source, field, format!("`{n}` appears twice")));
            }
        }
        Ok(Self(seen.into_iter().filter(|n| !matches!(n, ScoreName::Psnr | ScoreName::Ssim)).collect()))
    }

    /// The scores, in report order.
    pub fn names(&self) -> &[ScoreName] {
        &self.0
    }

    /// Whether `name` is among them.
    pub fn contains(&self, name: ScoreName) -> bool {
        self.0.contains(&name)
    }

    /// True for the paper's table alone.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether any needs the display's luminance and the retina's geometry.
    pub fn any_perceptual(&self) -> bool {
        self.0.iter().any(|n| n.is_perceptual())
    }
}

/// How the metric's sensitivity meets the images' optics (`[measurement] optics`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OpticsCount {
    /// `retinal` for an eye without aberrations (the thin lens: its images hold defocus and
    /// pixels, not a real eye's in-focus blur, which the metric's CSF supplies), `neural` for a
    /// schematic eye (its images hold its aberrations; the CSF's are divided out).
    #[default]
    Auto,
    /// The metric's sensitivity as published (it includes a typical eye's optics).
    Retinal,
    /// The sensitivity less Barten's typical optics: both images filtered by `1 / M_opt`.
    Neural,
}

impl OpticsCount {
    /// The name in experiment files.
    pub fn name(self) -> &'static str {
        match self {
            OpticsCount::Auto => "auto",
            OpticsCount::Retinal => "retinal",
            OpticsCount::Neural => "neural",
        }
    }

    /// Whether the compensation applies to an eye case (`schematic`: its eye has aberrations).
    pub fn compensates(self, schematic: bool) -> bool {
        match self {
            OpticsCount::Auto => schematic,
            OpticsCount::Retinal => false,
            OpticsCount::Neural => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_are_refused() {
        for n in ScoreName::ALL {
            assert_eq!(n.name().parse::<ScoreName>().unwrap(), n);
        }
        let e = "vmaf".parse::<ScoreName>().unwrap_err().to_string();
        assert!(e.contains("vmaf") && e.contains("cvvdp"), "{e}");
    }

    #[test]
    fn extra_scores_keep_report_order_and_refuse_repeats() {
        let x = ExtraScores::from_names(&[ScoreName::Flip, ScoreName::Psnr, ScoreName::Cvvdp], "e.toml", "f").unwrap();
        assert_eq!(x.names(), &[ScoreName::Cvvdp, ScoreName::Flip]);
        let e = ExtraScores::from_names(&[ScoreName::Flip, ScoreName::Flip], "e.toml", "measurement.scores")
            .unwrap_err()
            .to_string();
        assert!(e.contains("e.toml") && e.contains("measurement.scores") && e.contains("twice"), "{e}");
    }
}
