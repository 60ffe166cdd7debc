//! The predicted accommodation response (the focus cues of the paper's Sec. 2.2, which
//! an integral-imaging display exists to deliver): where the eye would focus on content at depth
//! `z`, taken as the focus that makes the retinal image sharpest, by two rules:
//!
//! - **frequency rule**: the focus of the highest contrast at one spatial frequency. Accommodation
//!   is driven by the mid spatial frequencies, about 1 to 4 cpd (Owens, Vision Res. 20:159, 1980;
//!   Mathews and Kruger, Vision Res. 34:1965, 1994); the default is 2 cpd, inside that band;
//! - **area rule**: the focus of the largest area under the MTF from the lowest measured
//!   frequency up to a stated limit (trapezoids over the measured frequencies).
//!
//! Both search the measured focus grid for its best point and refine it by the parabola through
//! that point and its two neighbours (on an uneven grid too); a best point at the end of the grid
//! is reported as is. Pure functions of the measured numbers.

/// The peak of a sampled curve: where it is and how high.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    /// Where the peak is (the curve's x, e.g. dioptres).
    pub at: f64,
    /// Its height.
    pub value: f64,
}

/// The maximum of `ys` over `xs` (increasing), refined by the parabola through the best sample
/// and its neighbours; the vertex is kept within the neighbours' span. `None` when no value is
/// finite.
pub fn refined_peak(xs: &[f64], ys: &[f64]) -> Option<Peak> {
    assert_eq!(xs.len(), ys.len(), "one value per point");
    // The first of equal maxima.
    let (i, best) = ys.iter().enumerate().filter(|(_, y)| y.is_finite()).fold(
        None,
        |acc: Option<(usize, f64)>, (i, &y)| match acc {
            Some((_, b)) if b >= y => acc,
            _ => Some((i, y)),
        },
    )?;
    if i == 0 || i + 1 == xs.len() || !ys[i - 1].is_finite() || !ys[i + 1].is_finite() {
        return Some(Peak { at: xs[i], value: best });
    }
    let (x0, x1, x2) = (xs[i - 1], xs[i], xs[i + 1]);
    let (y0, y1, y2) = (ys[i - 1], ys[i], ys[i + 1]);
    // Newton's divided differences: y = y0 + a (x - x0) + c (x - x0)(x - x1).
    let a = (y1 - y0) / (x1 - x0);
    let c = ((y2 - y1) / (x2 - x1) - a) / (x2 - x0);
    if c.is_nan() || c >= 0.0 {
        return Some(Peak { at: x1, value: y1 });
    }
    // dy/dx = a + c (2x - x0 - x1) = 0.
    let at = (0.5 * (x0 + x1 - a / c)).clamp(x0, x2);
    let value = y0 + a * (at - x0) + c * (at - x0) * (at - x1);
    Some(Peak { at, value })
}

/// The area under `mtf` (over increasing `frequencies`) from the first frequency up to `limit`
/// (trapezoids; `limit` one of the frequencies).
pub fn area_under(frequencies: &[f64], mtf: &[f64], limit: f64) -> f64 {
    let mut area = 0.0;
    for i in 1..frequencies.len() {
        if frequencies[i] > limit + 1e-9 {
            break;
        }
        area += 0.5 * (mtf[i] + mtf[i - 1]) * (frequencies[i] - frequencies[i - 1]);
    }
    area
}

/// The frequency rule: the focus (diopters) of the highest contrast; `contrast[j]` is measured at
/// `focus[j]`.
pub fn frequency_rule(focus: &[f64], contrast: &[f64]) -> Option<Peak> {
    refined_peak(focus, contrast)
}

/// The area rule: `mtf[j][i]` is the contrast at `focus[j]` and `frequencies[i]`. The peak's value
/// is the mean contrast over the band (the area over its width).
pub fn area_rule(focus: &[f64], frequencies: &[f64], mtf: &[Vec<f64>], limit: f64) -> Option<Peak> {
    let width = limit - frequencies[0];
    let areas: Vec<f64> = mtf.iter().map(|m| area_under(frequencies, m, limit) / width).collect();
    refined_peak(focus, &areas)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parabola_peak_is_recovered_exactly_between_grid_points() {
        let xs: Vec<f64> = (0..=16).map(|i| 0.25 * i as f64).collect();
        let ys: Vec<f64> = xs.iter().map(|x| 0.8 - 0.3 * (x - 2.37) * (x - 2.37)).collect();
        let p = refined_peak(&xs, &ys).unwrap();
        assert!((p.at - 2.37).abs() < 1e-12 && (p.value - 0.8).abs() < 1e-12, "{p:?}");
        // An uneven grid (the focus grid with content depths added).
        let xs = [0.0, 0.5, 1.0, 1.6667, 2.0, 3.0];
        let ys: Vec<f64> = xs.iter().map(|x| 1.0 - (x - 1.8) * (x - 1.8)).collect();
        let p = refined_peak(&xs, &ys).unwrap();
        assert!((p.at - 1.8).abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn a_gaussian_peak_is_recovered_to_a_fraction_of_the_step() {
        let xs: Vec<f64> = (0..=16).map(|i| 0.25 * i as f64).collect();
        for centre in [0.8, 1.13, 2.5, 3.41] {
            let ys: Vec<f64> = xs.iter().map(|x| (-(x - centre) * (x - centre) / (2.0 * 0.4 * 0.4)).exp()).collect();
            let p = frequency_rule(&xs, &ys).unwrap();
            assert!((p.at - centre).abs() < 0.02, "{centre}: {p:?}");
            assert!((p.value - 1.0).abs() < 0.03);
        }
    }

    #[test]
    fn peaks_at_the_ends_stay_there_and_nan_is_skipped() {
        let xs = [0.0, 1.0, 2.0];
        assert_eq!(refined_peak(&xs, &[3.0, 2.0, 1.0]).unwrap(), Peak { at: 0.0, value: 3.0 });
        assert_eq!(refined_peak(&xs, &[1.0, 2.0, 3.0]).unwrap().at, 2.0);
        assert_eq!(refined_peak(&xs, &[f64::NAN, 2.0, 1.0]).unwrap().at, 1.0);
        assert!(refined_peak(&xs, &[f64::NAN; 3]).is_none());
        // A flat top: no curvature, the sample itself.
        assert_eq!(refined_peak(&xs, &[1.0, 1.0, 1.0]).unwrap().at, 0.0);
    }

    #[test]
    fn the_area_rule_takes_trapezoids_up_to_the_limit() {
        let f = [0.5, 1.0, 2.0, 4.0, 8.0];
        assert!((area_under(&f, &[1.0; 5], 4.0) - 3.5).abs() < 1e-12);
        assert!((area_under(&f, &[1.0, 1.0, 0.0, 0.0, 0.0], 8.0) - 1.0).abs() < 1e-12);
        // A focus sweep whose MTF is best at the middle focus.
        let focus = [1.0, 2.0, 3.0];
        let mtf = vec![vec![0.5; 5], vec![0.9; 5], vec![0.6; 5]];
        let p = area_rule(&focus, &f, &mtf, 4.0).unwrap();
        assert!(p.at > 1.9 && p.at < 2.2 && (p.value - 0.9).abs() < 0.02, "{p:?}");
    }
}
