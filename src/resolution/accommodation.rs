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
//! is reported as is and flagged ([`GridEdge`]): the true peak may lie beyond it. The focus's
//! interval is the 95% half-width of the three contrasts carried through the parabola's vertex
//! (first-order error propagation, the three taken as independent). Pure functions of the
//! measured numbers.

/// The peak of a sampled curve: where it is and how high.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    /// Where the peak is (the curve's x, e.g. dioptres).
    pub at: f64,
    /// Its height.
    pub value: f64,
}

/// Where a peak lies on the focus grid: inside it, or on its first or last point (where the
/// curve may still rise beyond the grid: not a normal prediction).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GridEdge {
    /// Between the grid's ends.
    Inside,
    /// On the grid's first (lowest) focus.
    Floor,
    /// On the grid's last (highest) focus.
    Ceiling,
}

impl GridEdge {
    /// Where `at` lies on the grid `xs` (increasing).
    pub fn of(xs: &[f64], at: f64) -> Self {
        match (xs.first(), xs.last()) {
            (Some(&lo), _) if at <= lo => GridEdge::Floor,
            (_, Some(&hi)) if at >= hi => GridEdge::Ceiling,
            _ => GridEdge::Inside,
        }
    }

    /// The CSV's word: empty inside, `floor` or `ceiling`.
    pub fn name(self) -> &'static str {
        match self {
            GridEdge::Inside => "",
            GridEdge::Floor => "floor",
            GridEdge::Ceiling => "ceiling",
        }
    }
}

/// The 95% half-width of [`refined_peak`]'s position when each `ys[j]` has the 95% half-width
/// `hs[j]`: the vertex's derivative with respect to the three contrasts it is placed by (central
/// differences), the three taken as independent. `None` when the peak is not a parabola's vertex
/// strictly inside the grid (an end point, a flat top, a clamped vertex, or NaN).
pub fn peak_half_width(xs: &[f64], ys: &[f64], hs: &[f64]) -> Option<f64> {
    assert_eq!(xs.len(), hs.len(), "one half-width per point");
    let peak = refined_peak(xs, ys)?;
    let (i, _) = best_index(ys)?;
    if i == 0 || i + 1 == xs.len() {
        return None;
    }
    let vertex = |y: [f64; 3]| -> f64 {
        let (x0, x1, x2) = (xs[i - 1], xs[i], xs[i + 1]);
        let a = (y[1] - y[0]) / (x1 - x0);
        let c = ((y[2] - y[1]) / (x2 - x1) - a) / (x2 - x0);
        0.5 * (x0 + x1 - a / c)
    };
    let y = [ys[i - 1], ys[i], ys[i + 1]];
    let at = vertex(y);
    if !(at > xs[i - 1] && at < xs[i + 1]) || (at - peak.at).abs() > 1e-9 * (1.0 + at.abs()) {
        return None;
    }
    let mut sum = 0.0;
    for k in 0..3 {
        let step = 1e-6 * y[k].abs().max(1e-3);
        let (mut up, mut down) = (y, y);
        up[k] += step;
        down[k] -= step;
        let slope = (vertex(up) - vertex(down)) / (2.0 * step);
        sum += (slope * hs[i - 1 + k]).powi(2);
    }
    Some(sum.sqrt()).filter(|w| w.is_finite())
}

/// The maximum of `ys` over `xs` (increasing), refined by the parabola through the best sample
/// and its neighbours; the vertex is kept within the neighbours' span. `None` when no value is
/// finite.
pub fn refined_peak(xs: &[f64], ys: &[f64]) -> Option<Peak> {
    assert_eq!(xs.len(), ys.len(), "one value per point");
    let (i, best) = best_index(ys)?;
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

/// The index and value of the first of the equal maxima of `ys`'s finite values.
fn best_index(ys: &[f64]) -> Option<(usize, f64)> {
    ys.iter().enumerate().filter(|(_, y)| y.is_finite()).fold(None, |acc: Option<(usize, f64)>, (i, &y)| match acc {
        Some((_, b)) if b >= y => acc,
        _ => Some((i, y)),
    })
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
    fn grid_ends_are_flagged_and_carry_no_interval() {
        let xs = [0.25, 0.5, 0.75, 1.0];
        let falling = [0.9, 0.8, 0.7, 0.6];
        let p = refined_peak(&xs, &falling).unwrap();
        assert_eq!(GridEdge::of(&xs, p.at), GridEdge::Floor);
        assert_eq!(GridEdge::of(&xs, refined_peak(&xs, &[0.1, 0.2, 0.3, 0.4]).unwrap().at), GridEdge::Ceiling);
        assert_eq!(GridEdge::of(&xs, 0.6), GridEdge::Inside);
        assert!(peak_half_width(&xs, &falling, &[0.01; 4]).is_none());
    }

    #[test]
    fn the_focus_interval_is_the_vertex_moved_by_the_contrasts_half_widths() {
        // y = 1 - (x - 1.1)^2 on a 0.5 D grid: peak at 1.1 placed by the points 0.5, 1.0, 1.5.
        let xs = [0.0, 0.5, 1.0, 1.5, 2.0];
        let ys: Vec<f64> = xs.iter().map(|x| 1.0 - (x - 1.1) * (x - 1.1)).collect();
        let hs = [0.5, 0.02, 0.01, 0.03, 0.5];
        let w = peak_half_width(&xs, &ys, &hs).unwrap();
        // The same first-order sum from finite moves of each contrast by a small fraction of its
        // half-width (the ends' large half-widths do not enter).
        let mut sum = 0.0;
        for k in 1..4 {
            let mut moved = ys.clone();
            let e = 1e-4;
            moved[k] += e * hs[k];
            let shift = (refined_peak(&xs, &moved).unwrap().at - 1.1) / e;
            sum += shift * shift;
        }
        assert!((w - sum.sqrt()).abs() < 1e-4 * w, "{w} vs {}", sum.sqrt());
        // Analytically on an even grid h: x* = x1 + h (y2 - y0) / (2 q), q = 2 y1 - y0 - y2
        // (here y0, y1, y2 at 0.5, 1, 1.5, q = 2 h^2 = 0.5): dx*/dy1 = -h (y2 - y0) / q^2.
        let (h, q) = (0.5, 0.5);
        let (y0, y2) = (ys[1], ys[3]);
        let d0 = h * (-1.0 / (2.0 * q) + (y2 - y0) / (2.0 * q * q));
        let d1 = -h * (y2 - y0) / (q * q);
        let d2 = h * (1.0 / (2.0 * q) + (y2 - y0) / (2.0 * q * q));
        let exact = ((d0 * hs[1]).powi(2) + (d1 * hs[2]).powi(2) + (d2 * hs[3]).powi(2)).sqrt();
        assert!((w - exact).abs() < 1e-8, "{w} vs {exact}");
        // Exact contrasts: no interval width.
        assert_eq!(peak_half_width(&xs, &ys, &[0.0; 5]), Some(0.0));
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
