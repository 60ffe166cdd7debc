//! USAF-1951 resolution charts (paper Sec. 4.1: "vectorgraphics texture of USAF 1951 resolution
//! test charts").
//!
//! - [`framework_chart`]: the exact chart the paper's framework used, 146 bars shipped in
//!   `data/usaf-1951-rectangles.txt` (MIT License, Copyright (c) 2020 LeksiDor; notice in
//!   `data/LICENSE-LFDisplay-MIT.txt`). As the framework did, the bounding box of all bars is
//!   normalised to `[-1, 1]` independently in x and in y.
//! - [`procedural_chart`]: a MIL-STD-150A chart for new scenes: element (group g, element e)
//!   resolves `2^(g + (e - 1)/6)` line pairs per mm; a bar is `1/(2R)` mm wide and five times as
//!   long, bars are one bar-width apart; each element has three horizontal and three vertical bars.

use glam::DVec2;

use super::texture::{Bar, BarChart};
use crate::error::{Error, Result};

/// The framework's bar list (`minx miny maxx maxy` per line), shipped with the crate.
pub const FRAMEWORK_BARS: &str = include_str!("../../data/usaf-1951-rectangles.txt");

/// Parses a bar list (`minx miny maxx maxy` per line, blank lines ignored) and normalises its
/// bounding box to `[-1, 1]^2` independently per axis, as the framework did.
pub fn parse_bar_list(text: &str, source: &str) -> Result<Vec<Bar>> {
    let mut raw = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let vals: Vec<f64> = line
            .split_whitespace()
            .map(|t| t.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| Error::parse(source, format!("line {}: {e}: `{line}`", n + 1)))?;
        if vals.len() != 4 || vals.iter().any(|v| !v.is_finite()) {
            return Err(Error::parse(
                source,
                format!("line {}: expected four finite numbers `minx miny maxx maxy`, got `{line}`", n + 1),
            ));
        }
        if vals[2] < vals[0] || vals[3] < vals[1] {
            return Err(Error::parse(source, format!("line {}: max is below min in `{line}`", n + 1)));
        }
        raw.push(Bar { min: DVec2::new(vals[0], vals[1]), max: DVec2::new(vals[2], vals[3]) });
    }
    if raw.is_empty() {
        return Err(Error::parse(source, "no bars found"));
    }
    let lo = raw.iter().fold(DVec2::splat(f64::INFINITY), |a, b| a.min(b.min));
    let hi = raw.iter().fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(b.max));
    let extent = hi - lo;
    if extent.x <= 0.0 || extent.y <= 0.0 {
        return Err(Error::parse(source, "the bars' bounding box has zero width or height"));
    }
    let norm = |p: DVec2| (p - lo) / extent * 2.0 - DVec2::ONE;
    Ok(raw.into_iter().map(|b| Bar { min: norm(b.min), max: norm(b.max) }).collect())
}

/// The paper's chart (146 bars), normalised like the framework.
pub fn framework_chart() -> BarChart {
    BarChart::new(parse_bar_list(FRAMEWORK_BARS, "built-in usaf-1951-rectangles.txt").expect("built-in chart parses"))
}

/// MIL-STD-150A element resolution in line pairs per mm.
pub fn element_resolution(group: i32, element: i32) -> f64 {
    2f64.powf(group as f64 + (element as f64 - 1.0) / 6.0)
}

/// Bars of a MIL-STD-150A chart in millimetres, centred on the origin.
///
/// Layout: one column per group, largest (lowest group) on the left; elements 1 to 6 top to
/// bottom; each element is a 5w x 5w block of three horizontal bars, a gap of 2w, and a block of
/// three vertical bars (w = bar width of that element).
pub fn procedural_bars_mm(groups: std::ops::RangeInclusive<i32>) -> Vec<Bar> {
    let mut bars = Vec::new();
    let mut x = 0.0;
    for g in groups {
        let w1 = 1.0 / (2.0 * element_resolution(g, 1));
        let column_width = 12.0 * w1;
        let mut y = 0.0;
        for e in 1..=6 {
            let w = 1.0 / (2.0 * element_resolution(g, e));
            let top = y;
            // Three horizontal bars, 5w long, w tall, w apart.
            for k in 0..3 {
                let y0 = top - (2 * k) as f64 * w - w;
                bars.push(Bar { min: DVec2::new(x, y0), max: DVec2::new(x + 5.0 * w, y0 + w) });
            }
            // Three vertical bars, w wide, 5w tall, w apart, after a 2w gap.
            for k in 0..3 {
                let x0 = x + 7.0 * w + (2 * k) as f64 * w;
                bars.push(Bar { min: DVec2::new(x0, top - 5.0 * w), max: DVec2::new(x0 + w, top) });
            }
            y -= 7.0 * w;
        }
        x += column_width + 2.0 * w1;
    }
    // Centre on the origin.
    let lo = bars.iter().fold(DVec2::splat(f64::INFINITY), |a, b| a.min(b.min));
    let hi = bars.iter().fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(b.max));
    let c = (lo + hi) / 2.0;
    bars.into_iter().map(|b| Bar { min: b.min - c, max: b.max - c }).collect()
}

/// How a procedural chart is placed on its rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChartScale {
    /// Scaled uniformly to fill 90% of the rectangle's shorter side (resolutions are then
    /// relative, not in the target's millimetres).
    Fit,
    /// Chart millimetres are the rectangle's millimetres (true MIL-STD-150A scale); bars outside
    /// the rectangle are clipped. `half_size` is the rectangle's half width and height, mm.
    Physical {
        /// The rectangle's half width and height, mm.
        half_size: DVec2,
    },
}

/// A procedural MIL-STD-150A chart for groups `groups`, as a texture over `[-1, 1]^2`.
pub fn procedural_chart(groups: std::ops::RangeInclusive<i32>, scale: ChartScale) -> BarChart {
    let bars = procedural_bars_mm(groups);
    let hi = bars.iter().fold(DVec2::ZERO, |a, b| a.max(b.max.abs()).max(b.min.abs()));
    let factor = match scale {
        ChartScale::Fit => DVec2::splat(0.9 / hi.max_element().max(f64::MIN_POSITIVE)),
        ChartScale::Physical { half_size } => DVec2::ONE / half_size,
    };
    BarChart::new(bars.into_iter().map(|b| Bar { min: b.min * factor, max: b.max * factor }).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framework_chart_is_normalised_to_the_unit_square() {
        let chart = framework_chart();
        let lo = chart.bars().iter().fold(DVec2::splat(9.0), |a, b| a.min(b.min));
        let hi = chart.bars().iter().fold(DVec2::splat(-9.0), |a, b| a.max(b.max));
        assert!((lo - DVec2::splat(-1.0)).length() < 1e-12 && (hi - DVec2::ONE).length() < 1e-12);
    }

    #[test]
    fn procedural_elements_follow_mil_std_150a() {
        assert!((element_resolution(0, 1) - 1.0).abs() < 1e-15);
        assert!((element_resolution(2, 1) - 4.0).abs() < 1e-12);
        assert!((element_resolution(-2, 1) - 0.25).abs() < 1e-15);
        assert!((element_resolution(0, 4) - 2f64.sqrt()).abs() < 1e-12);
        let bars = procedural_bars_mm(0..=1);
        assert_eq!(bars.len(), 2 * 6 * 6);
        // Group 0 element 1: bars 0.5 mm wide and 2.5 mm long.
        let b = bars[0];
        let size = b.max - b.min;
        assert!((size.x - 2.5).abs() < 1e-12 && (size.y - 0.5).abs() < 1e-12, "{size:?}");
        let v = bars[3];
        let size = v.max - v.min;
        assert!((size.x - 0.5).abs() < 1e-12 && (size.y - 2.5).abs() < 1e-12, "{size:?}");
        // Adjacent bars are one bar width apart (line pair period = 1/R).
        assert!(((bars[4].min.x - bars[3].min.x) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_bar_lists_name_the_line() {
        let e = parse_bar_list("0 0 1 1\n0 0 x 1\n", "bars.txt").unwrap_err().to_string();
        assert!(e.contains("bars.txt") && e.contains("line 2"), "{e}");
        assert!(parse_bar_list("", "b").is_err());
        assert!(parse_bar_list("0 0 1 nan", "b").unwrap_err().to_string().contains("line 1"));
    }
}
