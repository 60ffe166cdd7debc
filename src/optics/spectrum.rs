//! The emission spectra of the display's red, green and blue primaries (issue "colour as
//! light"): each channel of the LCD (and of the scene's RGB, which the ground truth reads) is
//! light of its primary's spectrum, so a schematic eye traces each channel at wavelengths drawn
//! from that spectrum and the eye's longitudinal and transverse chromatic aberration follow from
//! the media's dispersion (docs/EYE.md).
//!
//! A primary is a Gaussian (peak and full width at half maximum, truncated to 380-780 nm) or a
//! table of (wavelength nm, relative power) pairs, linear between the pairs. The default is a
//! typical white-LED-backlit LCD: blue 450 nm (FWHM 20 nm, the LED's InGaN peak), green 535 nm
//! (FWHM 40 nm) and red 610 nm (FWHM 40 nm), the colour filters' pass bands over the phosphor;
//! these are representative values, not a measured panel: give a panel's own spectra in the
//! display file (`[primaries]`) for its numbers. Wavelengths are drawn by the inverse of each
//! spectrum's cumulative distribution: a Gaussian's tabulated on a 0.25 nm grid, a table's
//! exactly (its pieces are linear, so its distribution is piecewise quadratic and inverted in
//! closed form), so a line narrower than any grid keeps its power and its wavelength. A table's
//! powers are scaled by their maximum before anything is summed (no overflow near 1e308);
//! powers that are all zero or sub-normal are refused.
//!
//! Each primary's share of the display's luminance is its spectrum weighted by the photopic
//! luminous efficiency function V(lambda) of the CIE 1924 standard observer (equal to the
//! y-bar colour-matching function of the CIE 1931 2-degree observer; CIE 015:2018 *Colorimetry*,
//! Sec. 3), read from the 1 nm table of the `colorimetry` crate and linear between its entries:
//! `w_c = int S_c V dl / sum_k int S_k V dl` (a Gaussian's on a 0.25 nm grid, a table's exactly,
//! piece by piece). The spectra are in one relative power scale common to
//! the three primaries (a Gaussian's peak is 1, a table's powers as written): the emission of
//! each channel at full drive.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The visible range every spectrum is confined to, nm.
pub const VISIBLE_NM: (f64, f64) = (380.0, 780.0);

/// One primary's emission spectrum.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
pub enum PrimarySpec {
    /// A Gaussian line: `{ peak_nm = 535, fwhm_nm = 40 }`.
    Gaussian {
        /// Peak wavelength, nm.
        peak_nm: f64,
        /// Full width at half maximum, nm.
        fwhm_nm: f64,
    },
    /// `{ table = [[400, 0.0], [450, 1.0], ...] }`: (wavelength nm, relative power), wavelengths
    /// increasing, powers >= 0 and not all zero; linear between the pairs, zero outside.
    Table {
        /// The (wavelength, power) pairs.
        table: Vec<[f64; 2]>,
    },
}

/// `[primaries]` of a display file: the red, green and blue spectra.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Primaries {
    /// Channel 0.
    pub red: PrimarySpec,
    /// Channel 1.
    pub green: PrimarySpec,
    /// Channel 2.
    pub blue: PrimarySpec,
}

impl Default for Primaries {
    fn default() -> Self {
        Self::typical_lcd()
    }
}

impl Primaries {
    /// The documented default: a typical white-LED LCD (module comment).
    pub fn typical_lcd() -> Self {
        let g = |peak_nm, fwhm_nm| PrimarySpec::Gaussian { peak_nm, fwhm_nm };
        Self { red: g(610.0, 40.0), green: g(535.0, 40.0), blue: g(450.0, 20.0) }
    }

    /// Checks every spectrum; errors name `source` and `primaries.<channel>`.
    pub fn validate(&self, source: &str) -> Result<()> {
        for (name, p) in self.channels() {
            p.validate(source, &format!("primaries.{name}"))?;
        }
        Ok(())
    }

    fn channels(&self) -> [(&'static str, &PrimarySpec); 3] {
        [("red", &self.red), ("green", &self.green), ("blue", &self.blue)]
    }

    /// Each channel's share of the display's luminance (module comment): `[red, green, blue]`,
    /// summing to 1. The spectra must be valid (they are, once the display is loaded).
    /// The three spectra share one power scale, so each is scaled by the largest power of the
    /// three (a Gaussian's peak is 1) before it is integrated: tables of powers near 1e308 give
    /// finite shares.
    pub fn luminance_weights(&self) -> [f64; 3] {
        let max = self.channels().iter().fold(0.0f64, |m, (_, p)| m.max(p.max_power()));
        let max = if max.is_finite() && max > 0.0 { max } else { 1.0 };
        let y = self.channels().map(|(_, p)| p.luminous_power_over(max));
        let total: f64 = y.iter().sum();
        y.map(|v| v / total)
    }

    /// The wavelength samplers of the three channels (validated first).
    pub fn samplers(&self, source: &str) -> Result<[SpectrumSampler; 3]> {
        self.validate(source)?;
        Ok(self.channels().map(|(_, p)| SpectrumSampler::new(p)))
    }
}

impl PrimarySpec {
    fn validate(&self, source: &str, field: &str) -> Result<()> {
        match self {
            PrimarySpec::Gaussian { peak_nm, fwhm_nm } => {
                if !(peak_nm.is_finite() && (VISIBLE_NM.0..=VISIBLE_NM.1).contains(peak_nm)) {
                    return Err(Error::invalid(
                        source,
                        format!("{field}.peak_nm"),
                        format!("must be a wavelength in nm between 380 and 780, got {peak_nm}"),
                    ));
                }
                if !(fwhm_nm.is_finite() && *fwhm_nm >= 1.0 && *fwhm_nm <= 200.0) {
                    return Err(Error::invalid(
                        source,
                        format!("{field}.fwhm_nm"),
                        format!("must be between 1 and 200 nm, got {fwhm_nm}"),
                    ));
                }
            }
            PrimarySpec::Table { table } => {
                if table.len() < 2 || table.len() > 10_000 {
                    return Err(Error::invalid(
                        source,
                        format!("{field}.table"),
                        format!("needs 2 to 10000 [wavelength, power] pairs, got {}", table.len()),
                    ));
                }
                for (i, [l, p]) in table.iter().enumerate() {
                    if !(l.is_finite() && (VISIBLE_NM.0..=VISIBLE_NM.1).contains(l)) {
                        return Err(Error::invalid(
                            source,
                            format!("{field}.table[{i}][0]"),
                            format!("must be a wavelength in nm between 380 and 780, got {l}"),
                        ));
                    }
                    if !(p.is_finite() && *p >= 0.0) {
                        return Err(Error::invalid(
                            source,
                            format!("{field}.table[{i}][1]"),
                            format!("must be a finite power >= 0, got {p}"),
                        ));
                    }
                    if i > 0 && *l <= table[i - 1][0] {
                        return Err(Error::invalid(
                            source,
                            format!("{field}.table[{i}][0]"),
                            "wavelengths must increase",
                        ));
                    }
                }
                let max = table.iter().fold(0.0f64, |m, [_, p]| m.max(*p));
                if max == 0.0 {
                    return Err(Error::invalid(source, format!("{field}.table"), "all powers are zero"));
                }
                if max < f64::MIN_POSITIVE {
                    return Err(Error::invalid(
                        source,
                        format!("{field}.table"),
                        format!(
                            "every power is sub-normal (the largest is {max:e}, below {:e}): too small to carry a \
                             spectrum; scale the table (only the powers' ratios matter)",
                            f64::MIN_POSITIVE
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The largest power of the spectrum (a Gaussian's peak: 1).
    fn max_power(&self) -> f64 {
        match self {
            PrimarySpec::Gaussian { .. } => 1.0,
            PrimarySpec::Table { table } => table.iter().fold(0.0f64, |m, [_, p]| m.max(*p)),
        }
    }

    /// [`PrimarySpec::luminous_power`] of the spectrum's powers over `max`: a Gaussian's on the
    /// 0.25 nm grid (over `max`), a table's exactly. A table is linear between its
    /// entries and V(lambda) between whole nanometres, so on each piece between consecutive
    /// breakpoints of the two the product is a quadratic, integrated in closed form: a line
    /// narrower than any grid keeps its luminous power.
    fn luminous_power_over(&self, max: f64) -> f64 {
        let PrimarySpec::Table { table } = self else {
            return self.luminous_power() / max;
        };
        let mut sum = 0.0;
        for w in table.windows(2) {
            let ([l0, p0], [l1, p1]) = (w[0], w[1]);
            let (a, b) = (l0.max(VISIBLE_NM.0), l1.min(VISIBLE_NM.1));
            if b <= a {
                continue;
            }
            let (p0, p1) = (p0 / max, p1 / max);
            let power = |nm: f64| p0 + (p1 - p0) * (nm - l0) / (l1 - l0);
            let mut x0 = a;
            while x0 < b {
                let x1 = (x0.floor() + 1.0).min(b);
                let (q0, q1) = (power(x0), power(x1));
                let (v0, v1) = (photopic_efficiency(x0), photopic_efficiency(x1));
                sum += (x1 - x0) * (q0 * v0 / 3.0 + (q0 * v1 + q1 * v0) / 6.0 + q1 * v1 / 3.0);
                x0 = x1;
            }
        }
        sum
    }

    /// The spectrum's power weighted by V(lambda), `int S V dl` on the sampler's 0.25 nm grid
    /// (trapezoids), in the spectrum's own relative power times nm.
    pub fn luminous_power(&self) -> f64 {
        let n = ((VISIBLE_NM.1 - VISIBLE_NM.0) / STEP).round() as usize;
        let f = |i: usize| {
            let nm = VISIBLE_NM.0 + i as f64 * STEP;
            self.power(nm) * photopic_efficiency(nm)
        };
        (0..n).map(|i| 0.5 * (f(i) + f(i + 1)) * STEP).sum()
    }

    /// Relative power at `nm` (zero outside the visible range and the table).
    pub fn power(&self, nm: f64) -> f64 {
        if !(VISIBLE_NM.0..=VISIBLE_NM.1).contains(&nm) {
            return 0.0;
        }
        match self {
            PrimarySpec::Gaussian { peak_nm, fwhm_nm } => {
                let sigma = fwhm_nm / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt());
                (-0.5 * ((nm - peak_nm) / sigma).powi(2)).exp()
            }
            PrimarySpec::Table { table } => {
                let i = table.partition_point(|[l, _]| *l <= nm);
                if i == 0 || i == table.len() {
                    return if i == table.len() && nm == table[i - 1][0] { table[i - 1][1] } else { 0.0 };
                }
                let ([l0, p0], [l1, p1]) = (table[i - 1], table[i]);
                p0 + (p1 - p0) * (nm - l0) / (l1 - l0)
            }
        }
    }
}

/// The photopic luminous efficiency V(lambda) of the CIE 1924 standard observer at `nm`
/// (module comment): the 1 nm table, linear between its entries, zero outside 380-780 nm.
pub fn photopic_efficiency(nm: f64) -> f64 {
    if !(VISIBLE_NM.0..=VISIBLE_NM.1).contains(&nm) {
        return 0.0;
    }
    let v =
        |l: usize| colorimetry::observer::Observer::Cie1931.xyz_at_wavelength(l).map_or(0.0, |xyz| xyz.to_array()[1]);
    let lo = nm.floor();
    let f = nm - lo;
    let a = v(lo as usize);
    if f == 0.0 {
        a
    } else {
        a + (v(lo as usize + 1) - a) * f
    }
}

/// Draws wavelengths from one spectrum: the inverse of its cumulative distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectrumSampler {
    /// A table's exact distribution (`None`: a Gaussian's, tabulated on the grid below).
    exact: Option<ExactTable>,
    /// Cumulative distribution at `VISIBLE_NM.0 + i * STEP`, normalised to end at 1.
    cdf: Vec<f64>,
    /// `guide[j]`: the number of `cdf` entries below `j / GUIDE` (a guide table, L. Devroye,
    /// "Non-Uniform Random Variate Generation", 1986, Sec. III.2.4): the entry of `u` lies
    /// between `guide[j]` and `guide[j + 1]` for `j = floor(u GUIDE)`, so the search is short
    /// and finds the same entry as a search of the whole table.
    guide: Vec<u32>,
    /// `step[j]`: the `cdf` entry every `u` of the cell `[j / CELLS, (j + 1) / CELLS)` finds
    /// (the first one not below `u`), when one entry serves the whole cell; `u32::MAX` when the
    /// cell holds a step's end (then the guide's search finds it). Same entries, so the same
    /// wavelengths bit for bit, without a search for most `u`.
    step: Vec<u32>,
    /// The spectrum's power-weighted mean wavelength, nm.
    mean_nm: f64,
}

/// Cells of the step table (a power of two, so `j / CELLS` and `u CELLS` are exact).
const CELLS: usize = 4096;

/// Cells of the guide table (a power of two, so `j / GUIDE` and `u GUIDE` are exact).
const GUIDE: usize = 1024;

const STEP: f64 = 0.25;

/// A table spectrum's exact distribution: its powers scaled by their maximum, and the
/// cumulative power at each of its wavelengths (the trapezoids of its linear pieces).
#[derive(Clone, Debug, PartialEq)]
struct ExactTable {
    /// Wavelengths, nm, increasing.
    nm: Vec<f64>,
    /// Powers over their maximum.
    power: Vec<f64>,
    /// `cumulative[i]`: the power from the first wavelength to `nm[i]`.
    cumulative: Vec<f64>,
}

impl ExactTable {
    fn new(table: &[[f64; 2]]) -> Self {
        let max = table.iter().fold(0.0f64, |m, [_, p]| m.max(*p));
        let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
        let nm: Vec<f64> = table.iter().map(|[l, _]| *l).collect();
        // p / max, computed as a division when 1 / max overflows (max sub-normal is refused).
        let power: Vec<f64> = table.iter().map(|[_, p]| if scale.is_finite() { p * scale } else { p / max }).collect();
        let mut cumulative = Vec::with_capacity(nm.len());
        let mut acc = 0.0;
        cumulative.push(0.0);
        for i in 1..nm.len() {
            acc += 0.5 * (power[i - 1] + power[i]) * (nm[i] - nm[i - 1]);
            cumulative.push(acc);
        }
        Self { nm, power, cumulative }
    }

    fn total(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// The power-weighted mean wavelength: each linear piece's first moment, exactly.
    fn mean_nm(&self) -> f64 {
        let mut moment = 0.0;
        for i in 1..self.nm.len() {
            let (l0, len) = (self.nm[i - 1], self.nm[i] - self.nm[i - 1]);
            let (p0, d) = (self.power[i - 1], self.power[i] - self.power[i - 1]);
            // The integral of (l0 + len t) (p0 + d t) len dt over t in [0, 1].
            moment += len * (l0 * (p0 + 0.5 * d) + len * (0.5 * p0 + d / 3.0));
        }
        moment / self.total()
    }

    /// The wavelength below which a fraction `u` of the power lies: the piece holding it, then
    /// the root of its quadratic distribution, in the form without cancellation.
    fn wavelength(&self, u: f64) -> f64 {
        let target = u.clamp(0.0, 1.0) * self.total();
        let last = self.nm.len() - 1;
        // The first piece whose end reaches the target, skipping pieces without power.
        let i = self.cumulative.partition_point(|&c| c < target).clamp(1, last);
        let (l0, len) = (self.nm[i - 1], self.nm[i] - self.nm[i - 1]);
        let (p0, p1) = (self.power[i - 1], self.power[i]);
        let area = (target - self.cumulative[i - 1]).max(0.0) / len;
        // (p1 - p0) / 2 t^2 + p0 t = area, for t in [0, 1].
        let (a, b) = (0.5 * (p1 - p0), p0);
        let disc = (b * b + 4.0 * a * area).max(0.0);
        let denom = b + disc.sqrt();
        let t = if denom > 0.0 { 2.0 * area / denom } else { 0.0 };
        l0 + len * t.clamp(0.0, 1.0)
    }
}

impl SpectrumSampler {
    /// The sampler of `spectrum` (validated by the caller).
    pub fn new(spectrum: &PrimarySpec) -> Self {
        if let PrimarySpec::Table { table } = spectrum {
            let exact = ExactTable::new(table);
            let mean_nm = exact.mean_nm();
            return Self { exact: Some(exact), cdf: Vec::new(), guide: Vec::new(), step: Vec::new(), mean_nm };
        }
        let n = ((VISIBLE_NM.1 - VISIBLE_NM.0) / STEP).round() as usize;
        let mut cdf = Vec::with_capacity(n + 1);
        let (mut acc, mut moment) = (0.0, 0.0);
        cdf.push(0.0);
        for i in 0..n {
            let (a, b) = (VISIBLE_NM.0 + i as f64 * STEP, VISIBLE_NM.0 + (i + 1) as f64 * STEP);
            // Trapezoid over the step: exact for the tables' linear pieces on the grid.
            let w = 0.5 * (spectrum.power(a) + spectrum.power(b)) * STEP;
            acc += w;
            moment += w * 0.5 * (a + b);
            cdf.push(acc);
        }
        let total = acc.max(f64::MIN_POSITIVE);
        cdf.iter_mut().for_each(|c| *c /= total);
        let guide = (0..=GUIDE).map(|j| cdf.partition_point(|&c| c < j as f64 / GUIDE as f64) as u32).collect();
        let last = cdf.len() - 1;
        let step = (0..CELLS)
            .map(|j| {
                // Every u of the cell (u = 1 too, in the last) finds entry i of the cell's lower
                // end when none lies inside it: cdf[i - 1] < j / CELLS and cdf[i] >= (j + 1) / CELLS.
                let (lo, hi) = (j as f64 / CELLS as f64, (j + 1) as f64 / CELLS as f64);
                let i = cdf.partition_point(|&c| c < lo);
                let whole = i >= 1 && i <= last && cdf[i] >= hi;
                if whole {
                    i as u32
                } else {
                    u32::MAX
                }
            })
            .collect();
        Self { exact: None, cdf, guide, step, mean_nm: moment / total }
    }

    /// The wavelength (nm) of the uniform number `u` in [0, 1): the inverse distribution,
    /// linear within each step.
    #[inline(always)]
    pub fn wavelength(&self, u: f64) -> f64 {
        if let Some(table) = &self.exact {
            return table.wavelength(u);
        }
        let u = u.clamp(0.0, 1.0);
        let cell = self.step[((u * CELLS as f64) as usize).min(CELLS - 1)];
        let i = if cell != u32::MAX {
            cell as usize
        } else {
            let j = ((u * GUIDE as f64) as usize).min(GUIDE - 1);
            let (a, b) = (self.guide[j] as usize, self.guide[j + 1] as usize);
            (a + self.cdf[a..b].partition_point(|&c| c < u)).clamp(1, self.cdf.len() - 1)
        };
        let (c0, c1) = (self.cdf[i - 1], self.cdf[i]);
        let f = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
        VISIBLE_NM.0 + (i as f64 - 1.0 + f) * STEP
    }

    /// `k` wavelengths at the midpoints of `k` equal-probability bands (the grid estimator's
    /// stratified wavelength samples).
    pub fn quantiles(&self, k: usize) -> Vec<f64> {
        (0..k).map(|j| self.wavelength((j as f64 + 0.5) / k as f64)).collect()
    }

    /// The power-weighted mean wavelength, nm.
    pub fn mean_nm(&self) -> f64 {
        self.mean_nm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_guide_table_finds_the_entry_a_whole_search_finds() {
        // Slow twin: the search of the whole table, for every kind of u (cell edges, ends,
        // points inside the long flat tails).
        for spec in [
            PrimarySpec::Gaussian { peak_nm: 535.0, fwhm_nm: 40.0 },
            PrimarySpec::Gaussian { peak_nm: 455.0, fwhm_nm: 3.0 },
        ] {
            let s = SpectrumSampler::new(&spec);
            let whole = |u: f64| {
                let u = u.clamp(0.0, 1.0);
                let i = s.cdf.partition_point(|&c| c < u).clamp(1, s.cdf.len() - 1);
                let (c0, c1) = (s.cdf[i - 1], s.cdf[i]);
                let f = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
                VISIBLE_NM.0 + (i as f64 - 1.0 + f) * STEP
            };
            let mut us: Vec<f64> = (0..=4096).map(|k| k as f64 / 4096.0).collect();
            us.extend((0..20_000).map(|k| (k as f64 * 0.618_033_988_749_894_9).fract()));
            us.extend([1e-300, 1.0 - 1e-16, 0.5 + 1e-17]);
            for u in us {
                assert_eq!(s.wavelength(u).to_bits(), whole(u).to_bits(), "u = {u}");
            }
        }
    }

    #[test]
    fn a_gaussian_primary_is_sampled_with_its_mean_and_width() {
        let s = SpectrumSampler::new(&PrimarySpec::Gaussian { peak_nm: 535.0, fwhm_nm: 40.0 });
        assert!((s.mean_nm() - 535.0).abs() < 1e-6, "{}", s.mean_nm());
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|i| s.wavelength((i as f64 + 0.5) / n as f64)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        let sigma = 40.0 / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt());
        assert!((mean - 535.0).abs() < 0.01, "{mean}");
        assert!((sd - sigma).abs() / sigma < 2e-3, "{sd} vs {sigma}");
        // The median of a symmetric line is its peak.
        assert!((s.wavelength(0.5) - 535.0).abs() < 1e-3);
    }

    #[test]
    fn a_table_is_linear_between_its_pairs_and_a_box_samples_uniformly() {
        let t = PrimarySpec::Table { table: vec![[500.0, 1.0], [520.0, 1.0]] };
        assert_eq!(t.power(510.0), 1.0);
        assert_eq!(t.power(499.0), 0.0);
        assert_eq!(t.power(520.0), 1.0);
        let s = SpectrumSampler::new(&t);
        // Uniform over the box, exactly (a table's distribution is inverted in closed form).
        for u in [0.0, 0.1, 0.25, 0.5, 0.9, 1.0] {
            assert!((s.wavelength(u) - (500.0 + 20.0 * u)).abs() < 1e-9, "{u}: {}", s.wavelength(u));
        }
        assert!((s.mean_nm() - 510.0).abs() < 1e-12);
        // A ramp: power rising linearly from 0 at 400 nm to 1 at 500 nm, F(w) = ((w - 400) / 100)^2.
        let ramp = SpectrumSampler::new(&PrimarySpec::Table { table: vec![[400.0, 0.0], [500.0, 1.0]] });
        for u in [0.01, 0.25, 0.64, 1.0] {
            assert!((ramp.wavelength(u) - (400.0 + 100.0 * f64::sqrt(u))).abs() < 1e-9, "{u}");
        }
        assert!((ramp.mean_nm() - (400.0 + 200.0 / 3.0)).abs() < 1e-9);
        assert!((s.wavelength(0.5) - 510.0).abs() < 1e-9);
        assert_eq!(s.quantiles(2).len(), 2);
    }

    #[test]
    fn v_lambda_is_the_cie_1924_table_and_weights_follow_it() {
        // CIE 1924 V(lambda) at tabulated wavelengths (CIE 015:2018, Table T.4's y-bar).
        for (nm, v) in [(450.0, 0.038), (500.0, 0.323), (555.0, 1.0), (610.0, 0.503), (650.0, 0.107)] {
            assert!((photopic_efficiency(nm) - v).abs() < 1e-9, "{nm}: {}", photopic_efficiency(nm));
        }
        // Linear between entries, zero outside the visible range.
        let mid = 0.5 * (photopic_efficiency(555.0) + photopic_efficiency(556.0));
        assert!((photopic_efficiency(555.5) - mid).abs() < 1e-15);
        assert_eq!(photopic_efficiency(379.0), 0.0);
        // Narrow lines weigh as V at their wavelength times their power: two 2 nm boxes of
        // equal power at 555 and 450 nm have weights in the ratio V(555) : V(450).
        let b = |c: f64| PrimarySpec::Table {
            table: vec![[c - 1.0, 0.0], [c - 0.75, 1.0], [c + 0.75, 1.0], [c + 1.0, 0.0]],
        };
        let p = Primaries { red: b(555.0), green: b(555.0), blue: b(450.0) };
        let w = p.luminance_weights();
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(w[0], w[1]);
        assert!((w[2] / w[0] - 0.038).abs() < 2e-3, "{w:?}");
    }

    #[test]
    fn bad_spectra_name_the_field() {
        let mut p = Primaries::typical_lcd();
        p.green = PrimarySpec::Gaussian { peak_nm: f64::NAN, fwhm_nm: 40.0 };
        let e = p.validate("d.toml").unwrap_err().to_string();
        assert!(e.contains("primaries.green.peak_nm") && e.contains("d.toml"), "{e}");
        p.green = PrimarySpec::Table { table: vec![[500.0, 1.0], [490.0, 1.0]] };
        let e = p.validate("d.toml").unwrap_err().to_string();
        assert!(e.contains("primaries.green.table[1][0]"), "{e}");
        p.green = PrimarySpec::Table { table: vec![[500.0, 0.0], [510.0, 0.0]] };
        assert!(p.validate("d").is_err());
        Primaries::typical_lcd().validate("d").unwrap();
    }
}
