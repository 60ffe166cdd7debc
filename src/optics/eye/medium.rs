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
        for w in (350..=1100).step_by(25) {
            let n = self.index(w as f64);
            if !(n.is_finite() && (1.0..=3.0).contains(&n)) {
                return bad(format!("index at {w} nm is {n}; it must be between 1 and 3 over 350-1100 nm"));
            }
        }
        Ok(())
    }
}

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
