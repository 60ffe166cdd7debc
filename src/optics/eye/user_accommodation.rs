//! A user eye's accommodation law: which of its surface parameters change with the accommodation
//! `A` (D), as polynomials in `A` or as tables of `(A, value)` points joined by straight lines,
//! the way the published accommodating eyes state theirs (Navarro, Santamaria & Bescos, JOSA A
//! 2:1273, 1985, Table 1: radii, thicknesses and indices as functions of `A`; Schwiegerling,
//! Field Guide to Visual and Ophthalmic Optics, SPIE 2004: polynomials in `A`).
//!
//! ```toml
//! [eye.user.accommodation]
//! range = [0.0, 10.0]               # the accommodation A the eye can take, D
//! [[eye.user.accommodation.laws]]
//! surface = "lens-front"            # a surface's name, or its index as a string
//! parameter = "radius"              # radius, conic, thickness or index
//! polynomial = [12.0, -0.4]         # value(A) = 12.0 - 0.4 A
//! [[eye.user.accommodation.laws]]
//! surface = "lens-front"
//! parameter = "index"               # the medium after the surface: a constant's n or abbe's nd
//! table = { accommodation = [0.0, 5.0, 10.0], value = [1.42, 1.4273, 1.4236] }
//! ```
//!
//! A law's value replaces the surface table's own at every `A` (the table keeps it where no law
//! speaks). Without `[eye.user.accommodation]` the eye has one fixed focus.

use serde::{Deserialize, Serialize};

use super::medium::Dispersion;
use crate::error::{Error, Result};

/// The accommodation law of a user eye.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserAccommodation {
    /// The accommodation range `[lo, hi]`, D (`lo < hi`).
    pub range: [f64; 2],
    /// The parameters that change with `A`.
    pub laws: Vec<AccommodationLaw>,
}

/// The surface parameter a law sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LawParameter {
    /// Signed vertex radius of curvature, mm.
    Radius,
    /// Conic constant.
    Conic,
    /// Axial distance to the next surface's vertex, mm.
    Thickness,
    /// The index of the medium after the surface: a `constant` medium's `n`, an `abbe` medium's
    /// `nd` (its Abbe number kept).
    Index,
}

/// One parameter's law: exactly one of `polynomial` and `table`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AccommodationLaw {
    /// The surface: its `name`, or its index as a string.
    pub surface: String,
    /// The parameter the law sets.
    pub parameter: LawParameter,
    /// `value(A) = c0 + c1 A + c2 A^2 + ...`.
    #[serde(default)]
    pub polynomial: Option<Vec<f64>>,
    /// Points `(accommodation[i], value[i])`, joined by straight lines.
    #[serde(default)]
    pub table: Option<LawTable>,
}

/// A law's table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawTable {
    /// Accommodations, D, strictly increasing and spanning the range.
    pub accommodation: Vec<f64>,
    /// The parameter's value at each.
    pub value: Vec<f64>,
}

impl AccommodationLaw {
    /// The law's value at `a` (validated: one form, finite, a table spanning `a`).
    pub fn value(&self, a: f64) -> f64 {
        match (&self.polynomial, &self.table) {
            (Some(c), _) => c.iter().rev().fold(0.0, |acc, &ci| acc * a + ci),
            (None, Some(t)) => {
                let (x, y) = (&t.accommodation, &t.value);
                let i = x.partition_point(|&v| v <= a).clamp(1, x.len().max(2) - 1);
                if x.len() == 1 {
                    return y[0];
                }
                let s = (a - x[i - 1]) / (x[i] - x[i - 1]);
                y[i - 1] + s * (y[i] - y[i - 1])
            }
            (None, None) => f64::NAN,
        }
    }
}

/// What a law needs of the eye it changes: the surface's index from its reference.
pub(crate) fn surface_index(names: &[Option<String>], reference: &str) -> Option<usize> {
    names
        .iter()
        .position(|n| n.as_deref() == Some(reference))
        .or_else(|| reference.parse::<usize>().ok().filter(|&i| i < names.len()))
}

impl UserAccommodation {
    /// Checks the range and every law's form; the surface table at each `A` is checked by the
    /// user eye itself. `names` are the surfaces' names; errors name `eye.accommodation...`.
    pub fn validate(&self, names: &[Option<String>], media: &[Dispersion], source: &str) -> Result<()> {
        let err = |f: String, m: String| Err(Error::invalid(source, f, m));
        let [lo, hi] = self.range;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi && hi <= 30.0) {
            return err(
                "eye.accommodation.range".into(),
                format!("must be [lo, hi] D with 0 <= lo < hi <= 30, got [{lo}, {hi}]"),
            );
        }
        if self.laws.is_empty() || self.laws.len() > 256 {
            return err("eye.accommodation.laws".into(), format!("needs 1 to 256 laws, got {}", self.laws.len()));
        }
        for (i, law) in self.laws.iter().enumerate() {
            let f = |name: &str| format!("eye.accommodation.laws[{i}].{name}");
            let Some(k) = surface_index(names, &law.surface) else {
                return err(f("surface"), format!("names no surface: `{}`", law.surface));
            };
            if law.parameter == LawParameter::Index
                && !matches!(media[k], Dispersion::Constant(_) | Dispersion::Abbe { .. })
            {
                return err(
                    f("parameter"),
                    format!("an index law needs a `constant` or `abbe` medium after surface `{}`", law.surface),
                );
            }
            let others = self.laws[..i]
                .iter()
                .any(|o| o.parameter == law.parameter && surface_index(names, &o.surface) == Some(k));
            if others {
                return err(
                    f("parameter"),
                    format!("a second law for {:?} of surface `{}`", law.parameter, law.surface),
                );
            }
            match (&law.polynomial, &law.table) {
                (Some(c), None) => {
                    if c.is_empty() || c.len() > 8 || c.iter().any(|v| !v.is_finite()) {
                        return err(f("polynomial"), format!("needs 1 to 8 finite coefficients, got {c:?}"));
                    }
                }
                (None, Some(t)) => {
                    let (x, y) = (&t.accommodation, &t.value);
                    if x.len() != y.len() || x.len() < 2 || x.len() > 1024 {
                        return err(
                            f("table"),
                            format!(
                                "needs as many accommodations as values (2 to 1024), got {} and {}",
                                x.len(),
                                y.len()
                            ),
                        );
                    }
                    if x.iter().chain(y).any(|v| !v.is_finite()) || x.windows(2).any(|w| w[1] <= w[0]) {
                        return err(f("table"), "needs finite values and strictly increasing accommodations".into());
                    }
                    if x[0] > lo || x[x.len() - 1] < hi {
                        return err(
                            f("table.accommodation"),
                            format!("must span the range {lo}..{hi} D, got {}..{} D", x[0], x[x.len() - 1]),
                        );
                    }
                }
                _ => return err(f("polynomial"), "give exactly one of `polynomial` and `table`".into()),
            }
        }
        Ok(())
    }

    /// The accommodations at which the surface table is checked: the range in steps of at most
    /// 0.25 D, and every table point inside it.
    pub fn checkpoints(&self) -> Vec<f64> {
        let [lo, hi] = self.range;
        let n = ((hi - lo) / 0.25).ceil().max(1.0) as usize;
        let mut a: Vec<f64> = (0..=n).map(|i| lo + (hi - lo) * i as f64 / n as f64).collect();
        for law in &self.laws {
            if let Some(t) = &law.table {
                a.extend(t.accommodation.iter().copied().filter(|&x| x > lo && x < hi));
            }
        }
        a.sort_by(f64::total_cmp);
        a.dedup();
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomials_and_tables_give_their_values() {
        let poly = AccommodationLaw {
            surface: "0".into(),
            parameter: LawParameter::Radius,
            polynomial: Some(vec![12.0, -0.4, 0.01]),
            table: None,
        };
        assert_eq!(poly.value(0.0), 12.0);
        assert!((poly.value(2.0) - (12.0 - 0.8 + 0.04)).abs() < 1e-14);
        let table = AccommodationLaw {
            surface: "0".into(),
            parameter: LawParameter::Thickness,
            polynomial: None,
            table: Some(LawTable { accommodation: vec![0.0, 4.0, 8.0], value: vec![3.0, 3.4, 3.6] }),
        };
        assert_eq!(table.value(0.0), 3.0);
        assert_eq!(table.value(8.0), 3.6);
        assert!((table.value(2.0) - 3.2).abs() < 1e-15);
        assert!((table.value(6.0) - 3.5).abs() < 1e-15);
    }
}
