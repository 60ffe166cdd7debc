//! Refractive index n(λ) of the ocular media, by the dispersion formula each model's paper uses.
//!
//! - [`Dispersion::Navarro`]: Navarro, Santamaria & Bescos, "Accommodation-dependent model of the
//!   human eye with aspherics", JOSA A 2:1273 (1985), Eq. (4) and Table 3: a Herzberger-type
//!   interpolation `n(λ) = a1(λ) n(365) + a2(λ) n(486.1) + a3(λ) n(656.3) + a4(λ) n(1014)`, with
//!   `ai(λ) = Ai + Bi λ² + Ci/(λ² - λ0²) + Di/(λ² - λ0²)²` (λ in µm, λ0 = 0.1673 µm, the
//!   Herzberger form: M. Herzberger, Opt. Acta 6:197, 1959); the four indices per medium are the
//!   paper's (also listed by Atchison & Smith, "Chromatic dispersions of the ocular media of
//!   human eyes", JOSA A 22:29, 2005).
//! - [`Dispersion::Abbe`]: the Arizona eye's linear form from the d-line index and the Abbe
//!   number, `n(λ) = nd + (λ - 589.3) (nd - 1) / (Vd (486.1 - 656.3))` (λ in nm), Schwiegerling,
//!   "Field Guide to Visual and Ophthalmic Optics", SPIE FG04 (2004), p. 16.
//! - [`Dispersion::Cauchy`]: `n = a + b/λ² + c/λ⁴` (λ in µm), A.-L. Cauchy (1836); see Born &
//!   Wolf, "Principles of Optics", 7th ed., Sec. 2.3.4.
//! - [`Dispersion::Sellmeier`]: `n² = 1 + Σ Bi λ² / (λ² - Ci)` (λ in µm, Ci in µm²), W. Sellmeier,
//!   Ann. Phys. 219:272 (1871); Born & Wolf Sec. 2.3.4.
//! - [`Dispersion::Table`]: measured indices at tabulated wavelengths, linearly interpolated
//!   (clamped to the end values outside the table).
//! - [`Dispersion::Constant`]: one index at every wavelength.
//!
//! A user's formula is checked by analysis, not by sampling ([`Dispersion::validate`]): its
//! poles are found exactly (Sellmeier's at λ² = Ci) and refused inside 350-1100 nm; elsewhere
//! every formula is a sum of terms each monotone in λ over any interval without a pole (Cauchy's
//! quadratic in 1/λ² is bounded exactly through its vertex, a table through its nodes), so the sum
//! of each term's smaller and larger end value bounds the index over the interval. The range is
//! split until those bounds lie within 1-3 or a wavelength outside them is found (interval
//! arithmetic by monotone decomposition: R. E. Moore, R. B. Kearfott & M. J. Cloud, "Introduction
//! to Interval Analysis", SIAM 2009, Ch. 6).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Herzberger's pole of Navarro et al.'s Eq. (4), µm.
const HERZBERGER_L0: f64 = 0.1673;

/// Navarro et al. (1985) Eq. (4) coefficients: rows a1..a4; columns constant, λ²,
/// 1/(λ² - λ0²), 1/(λ² - λ0²)².
const NAVARRO_COEFFS: [[f64; 4]; 4] = [
    [0.661_471_96, -0.403_527_96, -0.280_467_90, 0.033_859_79],
    [-4.201_463_83, 2.735_089_56, 1.505_437_84, -0.115_932_35],
    [6.298_342_37, -4.694_099_35, -1.575_086_50, 0.102_930_38],
    [-1.758_350_59, 2.362_537_94, 0.350_116_57, -0.020_857_82],
];

/// Navarro et al. (1985) Table 3: indices at 365, 486.1, 656.3 and 1014 nm.
pub mod navarro_media {
    /// Cornea.
    pub const CORNEA: [f64; 4] = [1.3975, 1.3807, 1.37405, 1.3668];
    /// Aqueous humour.
    pub const AQUEOUS: [f64; 4] = [1.3593, 1.3422, 1.3354, 1.3278];
    /// Crystalline lens (unaccommodated).
    pub const LENS: [f64; 4] = [1.4492, 1.4263, 1.4175, 1.4097];
    /// Vitreous humour.
    pub const VITREOUS: [f64; 4] = [1.3565, 1.3407, 1.3341, 1.3273];
}

/// A dispersion formula: the refractive index as a function of wavelength.
///
/// In files (the user eye) a medium is written as one of `{ constant = 1.336 }`,
/// `{ cauchy = { a = 1.32, b = 0.0045, c = 0.0 } }`, `{ sellmeier = { b = [..], c = [..] } }`,
/// `{ table = { wavelength_nm = [..], index = [..] } }`, `{ abbe = { nd = 1.377, vd = 57.1 } }` or
/// `{ navarro = { n = [n365, n486, n656, n1014], offset = 0.0 } }`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Dispersion {
    /// The same index at every wavelength.
    Constant(f64),
    /// Cauchy: `n = a + b/λ² + c/λ⁴`, λ in µm.
    Cauchy {
        /// Constant term.
        a: f64,
        /// λ⁻² coefficient, µm².
        b: f64,
        /// λ⁻⁴ coefficient, µm⁴.
        #[serde(default)]
        c: f64,
    },
    /// Sellmeier: `n² = 1 + Σ b[i] λ² / (λ² - c[i])`, λ in µm, c in µm².
    Sellmeier {
        /// Oscillator strengths.
        b: Vec<f64>,
        /// Resonance wavelengths squared, µm².
        c: Vec<f64>,
    },
    /// Tabulated indices, linearly interpolated, clamped outside the table.
    Table {
        /// Wavelengths, nm, strictly increasing.
        wavelength_nm: Vec<f64>,
        /// The index at each wavelength.
        index: Vec<f64>,
    },
    /// Arizona eye (Schwiegerling 2004): linear in λ from the d-line index and the Abbe number.
    Abbe {
        /// Index at 589.3 nm.
        nd: f64,
        /// Abbe number `(nd - 1) / (nF - nC)`.
        vd: f64,
    },
    /// Navarro et al. (1985) Eq. (4) from the medium's indices at 365, 486.1, 656.3, 1014 nm,
    /// plus a constant `offset` (the accommodation term of the lens index, or a shift to
    /// another model's index).
    Navarro {
        /// Indices at 365, 486.1, 656.3 and 1014 nm.
        n: [f64; 4],
        /// Added to the interpolated index.
        #[serde(default)]
        offset: f64,
    },
}

impl Dispersion {
    /// The index at `wavelength_nm`.
    pub fn index(&self, wavelength_nm: f64) -> f64 {
        let um = wavelength_nm * 1e-3;
        match self {
            Dispersion::Constant(n) => *n,
            Dispersion::Cauchy { a, b, c } => {
                let l2 = um * um;
                a + b / l2 + c / (l2 * l2)
            }
            Dispersion::Sellmeier { b, c } => {
                let l2 = um * um;
                let n2 = 1.0 + b.iter().zip(c).map(|(bi, ci)| bi * l2 / (l2 - ci)).sum::<f64>();
                n2.max(0.0).sqrt()
            }
            Dispersion::Table { wavelength_nm: w, index } => table(w, index, wavelength_nm),
            Dispersion::Abbe { nd, vd } => nd + (wavelength_nm - 589.3) * (nd - 1.0) / (vd * (486.1 - 656.3)),
            Dispersion::Navarro { n, offset } => navarro(n, um) + offset,
        }
    }

    /// Checks a user-given formula: finite coefficients, consistent lengths, an increasing
    /// table, and an index between 1 and 3 over 350-1100 nm. `field` names it in errors.
    pub fn validate(&self, source: &str, field: &str) -> Result<()> {
        let bad = |m: String| Err(Error::invalid(source, field, m));
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match self {
            Dispersion::Constant(n) if !n.is_finite() => return bad(format!("index must be finite, got {n}")),
            Dispersion::Cauchy { a, b, c } if !finite(&[*a, *b, *c]) => {
                return bad("cauchy coefficients must be finite".into())
            }
            Dispersion::Sellmeier { b, c } => {
                if b.len() != c.len() || b.is_empty() {
                    return bad(format!(
                        "sellmeier needs as many b as c terms (>= 1), got {} and {}",
                        b.len(),
                        c.len()
                    ));
                }
                if !finite(b) || !finite(c) {
                    return bad("sellmeier coefficients must be finite".into());
                }
            }
            Dispersion::Table { wavelength_nm, index } => {
                if wavelength_nm.len() != index.len() || wavelength_nm.is_empty() {
                    return bad(format!(
                        "table needs as many wavelengths as indices (>= 1), got {} and {}",
                        wavelength_nm.len(),
                        index.len()
                    ));
                }
                if !finite(wavelength_nm) || !finite(index) {
                    return bad("table entries must be finite".into());
                }
                if wavelength_nm.windows(2).any(|w| w[1] <= w[0]) {
                    return bad("table wavelengths must be strictly increasing".into());
                }
            }
            Dispersion::Abbe { nd, vd } if !(nd.is_finite() && vd.is_finite() && *vd > 0.0) => {
                return bad(format!("abbe needs a finite nd and a positive vd, got {nd}, {vd}"));
            }
            Dispersion::Navarro { n, offset } if !finite(n) || !offset.is_finite() => {
                return bad("navarro indices must be finite".into())
            }
            _ => {}
        }
        if let Some((pole, term)) = self.pole_in(CHECKED_NM) {
            return bad(format!(
                "has a pole at {pole:.3} nm (sellmeier term {term}: c = {} um^2), where the index is infinite; \
                 it must be between 1 and 3 over 350-1100 nm",
                match self {
                    Dispersion::Sellmeier { c, .. } => c[term],
                    _ => f64::NAN,
                }
            ));
        }
        let mut budget = MAX_INTERVALS;
        match self.outside_range(CHECKED_NM.0, CHECKED_NM.1, 0, &mut budget) {
            Some((w, n)) => bad(format!("index at {w:.3} nm is {n}; it must be between 1 and 3 over 350-1100 nm")),
            None if budget == 0 => bad(format!(
                "its index could not be shown to stay between 1 and 3 over 350-1100 nm in {MAX_INTERVALS} \
                 intervals (its terms cancel too finely); simplify the formula"
            )),
            None => Ok(()),
        }
    }

    /// A pole of the formula inside `range` (nm): its wavelength and the Sellmeier term's index.
    /// Only Sellmeier's terms have poles at positive wavelengths (`λ² = Ci`, `Bi ≠ 0`);
    /// Cauchy's and Navarro's lie at 0 and at Herzberger's 167.3 nm, outside every range checked.
    fn pole_in(&self, range: (f64, f64)) -> Option<(f64, usize)> {
        let Dispersion::Sellmeier { b, c } = self else { return None };
        b.iter().zip(c).enumerate().find_map(|(i, (bi, ci))| {
            let nm = 1e3 * ci.sqrt();
            (*bi != 0.0 && *ci > 0.0 && nm >= range.0 && nm <= range.1).then_some((nm, i))
        })
    }

    /// A wavelength in `[lo, hi]` (nm, no pole inside) where the index is not between 1 and 3,
    /// with the index there; `None` when there is none. Bounds by monotone terms; halves the
    /// interval while they straddle the limits.
    /// `budget` counts the intervals left to look at; at 0 the search stops (the caller refuses).
    fn outside_range(&self, lo: f64, hi: f64, depth: u32, budget: &mut usize) -> Option<(f64, f64)> {
        if *budget == 0 {
            return None;
        }
        *budget -= 1;
        let ok = |n: f64| n.is_finite() && (1.0..=3.0).contains(&n);
        for w in [lo, hi] {
            if !ok(self.index(w)) {
                return Some((w, self.index(w)));
            }
        }
        let (min, max) = self.bounds(lo, hi);
        if (min >= 1.0 && max <= 3.0) || depth >= MAX_SPLITS {
            return None;
        }
        let mid = 0.5 * (lo + hi);
        self.outside_range(lo, mid, depth + 1, budget).or_else(|| self.outside_range(mid, hi, depth + 1, budget))
    }

    /// Bounds on the index over `[lo, hi]` nm, an interval without a pole: each term of the
    /// formula is monotone in λ there, so its values at the ends bound it (Cauchy's quadratic in
    /// 1/λ² and a table are bounded exactly). A squared index that may be negative gives a lower
    /// bound of -1 (no real index).
    fn bounds(&self, lo: f64, hi: f64) -> (f64, f64) {
        let ends = |f: &dyn Fn(f64) -> f64| {
            let (a, b) = (f(lo), f(hi));
            (a.min(b), a.max(b))
        };
        match self {
            Dispersion::Constant(n) => (*n, *n),
            Dispersion::Abbe { .. } => ends(&|w| self.index(w)),
            Dispersion::Cauchy { a, b, c } => {
                // n = a + b y + c y^2 with y = 1/λ^2 (λ in µm): its extremes are at the ends of
                // y's interval and at the vertex y = -b / 2c when inside.
                let (y0, y1) = (1.0 / (hi * 1e-3).powi(2), 1.0 / (lo * 1e-3).powi(2));
                let n = |y: f64| a + b * y + c * y * y;
                let mut v = vec![n(y0), n(y1)];
                if *c != 0.0 {
                    let vertex = -b / (2.0 * c);
                    if vertex > y0 && vertex < y1 {
                        v.push(n(vertex));
                    }
                }
                (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
            }
            Dispersion::Sellmeier { b, c } => {
                let (x0, x1) = ((lo * 1e-3).powi(2), (hi * 1e-3).powi(2));
                let (mut min, mut max) = (1.0, 1.0);
                for (bi, ci) in b.iter().zip(c) {
                    let term = |x: f64| bi * x / (x - ci);
                    let (t0, t1) = (term(x0), term(x1));
                    min += t0.min(t1);
                    max += t0.max(t1);
                }
                let root = |v: f64| if v >= 0.0 { v.sqrt() } else { -1.0 };
                (root(min), root(max))
            }
            Dispersion::Table { wavelength_nm, .. } => {
                let mut v = vec![self.index(lo), self.index(hi)];
                v.extend(wavelength_nm.iter().filter(|w| **w > lo && **w < hi).map(|w| self.index(*w)));
                (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
            }
            Dispersion::Navarro { n, offset } => {
                // Σ rows (A + B x + C u + D u²) n_i with x = λ², u = 1 / (x - λ0²) > 0: four
                // terms, each monotone in λ above λ0.
                let (x0, x1) = ((lo * 1e-3).powi(2), (hi * 1e-3).powi(2));
                let u = |x: f64| 1.0 / (x - HERZBERGER_L0 * HERZBERGER_L0);
                let coef = |k: usize| NAVARRO_COEFFS.iter().zip(n).map(|(row, ni)| row[k] * ni).sum::<f64>();
                let terms: [&dyn Fn(f64) -> f64; 3] =
                    [&|x| coef(1) * x, &|x| coef(2) * u(x), &|x| coef(3) * u(x) * u(x)];
                let (mut min, mut max) = (coef(0) + offset, coef(0) + offset);
                for t in terms {
                    let (a, b) = (t(x0), t(x1));
                    min += a.min(b);
                    max += a.max(b);
                }
                (min, max)
            }
        }
    }
}

/// The wavelengths over which a user's formula must give an index between 1 and 3, nm.
pub const CHECKED_NM: (f64, f64) = (350.0, 1100.0);

/// The most intervals [`Dispersion::validate`] bounds (a few hundred for real media).
const MAX_INTERVALS: usize = 20_000;

/// How many times [`Dispersion::validate`] halves the range at most (750 nm / 2^48 is below
/// a femtometre): where the bounds still straddle a limit, the index touches it.
const MAX_SPLITS: u32 = 48;

fn navarro(n: &[f64; 4], um: f64) -> f64 {
    let l2 = um * um;
    let li2 = 1.0 / (l2 - HERZBERGER_L0 * HERZBERGER_L0);
    let li4 = li2 * li2;
    let mut out = 0.0;
    for (row, ni) in NAVARRO_COEFFS.iter().zip(n) {
        out += (row[0] + row[1] * l2 + row[2] * li2 + row[3] * li4) * ni;
    }
    out
}

fn table(w: &[f64], n: &[f64], x: f64) -> f64 {
    if x <= w[0] || w.len() == 1 {
        return n[0];
    }
    let last = w.len() - 1;
    if x >= w[last] {
        return n[last];
    }
    let i = w.partition_point(|&wi| wi <= x).clamp(1, last);
    let t = (x - w[i - 1]) / (w[i] - w[i - 1]);
    n[i - 1] + t * (n[i] - n[i - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn navarro_reproduces_its_tabulated_indices_and_the_d_line_values() {
        // Eq. (4) is an interpolation through its four nodes.
        let d = Dispersion::Navarro { n: navarro_media::LENS, offset: 0.0 };
        for (w, n) in [365.0, 486.1, 656.3, 1014.0].iter().zip(navarro_media::LENS) {
            assert!((d.index(*w) - n).abs() < 2e-4, "{w}: {} vs {n}", d.index(*w));
        }
        // Table 1 of the paper gives the 589.3 nm indices 1.376, 1.3374, 1.42, 1.336.
        for (m, n) in [
            (navarro_media::CORNEA, 1.376),
            (navarro_media::AQUEOUS, 1.3374),
            (navarro_media::LENS, 1.42),
            (navarro_media::VITREOUS, 1.336),
        ] {
            let got = Dispersion::Navarro { n: m, offset: 0.0 }.index(589.3);
            assert!((got - n).abs() < 1e-3, "{got} vs {n}");
        }
    }

    #[test]
    fn abbe_cauchy_sellmeier_table_behave() {
        let a = Dispersion::Abbe { nd: 1.377, vd: 57.1 };
        assert!((a.index(589.3) - 1.377).abs() < 1e-15);
        assert!(((a.index(486.1) - a.index(656.3)) - 0.377 / 57.1).abs() < 1e-12);
        let c = Dispersion::Cauchy { a: 1.3, b: 0.004, c: 0.0 };
        assert!((c.index(500.0) - (1.3 + 0.004 / 0.25)).abs() < 1e-15);
        // Sellmeier with a single term: n² - 1 = B λ²/(λ² - C).
        let s = Dispersion::Sellmeier { b: vec![0.8], c: vec![0.01] };
        let l2: f64 = 0.25;
        assert!((s.index(500.0) - (1.0 + 0.8 * l2 / (l2 - 0.01)).sqrt()).abs() < 1e-15);
        let t = Dispersion::Table { wavelength_nm: vec![400.0, 600.0], index: vec![1.4, 1.3] };
        assert!((t.index(500.0) - 1.35).abs() < 1e-15);
        assert_eq!(t.index(300.0), 1.4);
        assert_eq!(t.index(900.0), 1.3);
    }

    #[test]
    fn bad_formulas_name_the_field() {
        let t = Dispersion::Table { wavelength_nm: vec![600.0, 400.0], index: vec![1.4, 1.3] };
        let e = t.validate("e.toml", "eye.surfaces[1].medium").unwrap_err().to_string();
        assert!(e.contains("eye.surfaces[1].medium") && e.contains("increasing"), "{e}");
        assert!(Dispersion::Constant(0.5).validate("e", "m").is_err());
        assert!(Dispersion::Sellmeier { b: vec![1.0], c: vec![] }.validate("e", "m").is_err());
    }
}
