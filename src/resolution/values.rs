//! A study setting's values: a list, or a range `{ from, to, step }` expanded with both ends and
//! rounded to 12 significant digits (the content depths, focuses and frequencies of
//! `studies/*.toml`, docs/RESOLUTION.md).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A list of values, or a range `{ from, to, step }` (both ends included when on the grid).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Values {
    /// An explicit list.
    List(Vec<f64>),
    /// `{ from, to, step }`: every `from + i step` up to `to`.
    Range {
        /// First value.
        from: f64,
        /// Last value (included when on the grid).
        to: f64,
        /// Step between values.
        step: f64,
    },
}

impl Values {
    /// The values; `field` names the setting in errors.
    pub(crate) fn expand(&self, source: &str, field: &str) -> Result<Vec<f64>> {
        let v = self.expand_any(source, field)?;
        if v.is_empty() {
            return Err(Error::invalid(source, field, "needs at least one value"));
        }
        Ok(v)
    }

    /// [`Values::expand`], an empty list allowed.
    pub(crate) fn expand_any(&self, source: &str, field: &str) -> Result<Vec<f64>> {
        let v = match *self {
            Values::List(ref v) => v.clone(),
            Values::Range { from, to, step } => {
                if !(from.is_finite() && to.is_finite() && step.is_finite() && step > 0.0 && to >= from) {
                    return Err(Error::invalid(
                        source,
                        field,
                        format!("a range needs finite from <= to and step > 0, got from {from}, to {to}, step {step}"),
                    ));
                }
                let n = ((to - from) / step + 1e-9).floor() as usize + 1;
                if n > 10_000 {
                    return Err(Error::invalid(source, field, format!("{n} values is more than 10000")));
                }
                (0..n).map(|i| round12(from + i as f64 * step)).collect()
            }
        };
        for (i, x) in v.iter().enumerate() {
            if !x.is_finite() {
                return Err(Error::invalid(source, format!("{field}[{i}]"), format!("must be finite, got {x}")));
            }
        }
        Ok(v)
    }
}

/// Rounds to 12 significant digits (ranges: 0.1 + 2 x 0.1 is 0.3).
fn round12(x: f64) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    let scale = 10f64.powi(11 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_expand_with_both_ends_and_round() {
        let v = Values::Range { from: 0.0, to: 0.3, step: 0.1 }.expand("x", "f").unwrap();
        assert_eq!(v, [0.0, 0.1, 0.2, 0.3]);
        let v = Values::Range { from: 0.5, to: 3.5, step: 0.5 }.expand("x", "f").unwrap();
        assert_eq!(v.len(), 7);
        assert!(Values::List(vec![]).expand("x", "f").is_err());
    }
}
