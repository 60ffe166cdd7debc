//! Bar-chart textures: a white backing square with black rectangular bars, in the square's own
//! coordinates `[-1, 1]^2` (u right, v up). This is how the paper's framework textured its
//! USAF-1951 squares (Sec. 4.1, Fig. 3).
//!
//! Lookups must not scan every bar (the paper's chart has 146): a uniform grid classifies each
//! cell as empty, fully inside one bar, or mixed with a short list of candidate bars.
//! [`BarChart::is_bar_brute_force`] is the slow twin that tests check the grid against.
//! Bars are closed rectangles: a point on a bar's edge is on the bar.

use glam::DVec2;

/// One axis-aligned bar, in chart coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bar {
    /// Lower-left corner.
    pub min: DVec2,
    /// Upper-right corner.
    pub max: DVec2,
}

impl Bar {
    /// True when `p` lies in the bar (edges included).
    #[inline]
    pub fn contains(&self, p: DVec2) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Cell {
    Empty,
    Full,
    /// Candidates are `candidates[start..start + len]`.
    Mixed {
        start: u32,
        len: u32,
    },
}

/// A set of bars over `[-1, 1]^2` with a grid for constant-time lookups.
#[derive(Clone, Debug)]
pub struct BarChart {
    bars: Vec<Bar>,
    cells: Vec<Cell>,
    candidates: Vec<u32>,
}

/// Grid cells per side.
const GRID: usize = 128;

impl BarChart {
    /// A chart from bars in `[-1, 1]^2`; bars are clipped to that square (parts outside it
    /// could never be seen on the chart's rectangle) and empty bars are dropped.
    pub fn new(bars: Vec<Bar>) -> Self {
        let bars: Vec<Bar> = bars
            .into_iter()
            .map(|b| Bar { min: b.min.max(DVec2::splat(-1.0)), max: b.max.min(DVec2::splat(1.0)) })
            .filter(|b| b.min.x <= b.max.x && b.min.y <= b.max.y)
            .collect();
        let step = 2.0 / GRID as f64;
        // Cells are grown by a hair so that rounding in the index computation can never put a
        // point in a cell whose lists do not consider the bar that contains it.
        let eps = 1e-9;
        let mut cells = Vec::with_capacity(GRID * GRID);
        let mut candidates = Vec::new();
        for j in 0..GRID {
            for i in 0..GRID {
                let lo = DVec2::new(-1.0 + i as f64 * step - eps, -1.0 + j as f64 * step - eps);
                let hi = DVec2::new(-1.0 + (i + 1) as f64 * step + eps, -1.0 + (j + 1) as f64 * step + eps);
                let overlapping: Vec<u32> = bars
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| b.min.x <= hi.x && b.max.x >= lo.x && b.min.y <= hi.y && b.max.y >= lo.y)
                    .map(|(k, _)| k as u32)
                    .collect();
                let full = overlapping.iter().any(|&k| {
                    let b = &bars[k as usize];
                    b.min.x <= lo.x && b.max.x >= hi.x && b.min.y <= lo.y && b.max.y >= hi.y
                });
                cells.push(if overlapping.is_empty() {
                    Cell::Empty
                } else if full {
                    Cell::Full
                } else {
                    let start = candidates.len() as u32;
                    candidates.extend_from_slice(&overlapping);
                    Cell::Mixed { start, len: overlapping.len() as u32 }
                });
            }
        }
        Self { bars, cells, candidates }
    }

    /// Every bar of the chart.
    pub fn bars(&self) -> &[Bar] {
        &self.bars
    }

    /// The grid cell [`BarChart::is_bar`] looks `uv` up in; `None` where it answers "no bar"
    /// without a lookup (below, beyond or NaN).
    #[inline(always)]
    fn cell_of(uv: DVec2) -> Option<usize> {
        let fi = (uv.x + 1.0) * (0.5 * GRID as f64);
        let fj = (uv.y + 1.0) * (0.5 * GRID as f64);
        if !(fi >= 0.0 && fj >= 0.0) {
            return None;
        }
        let i = (fi as i32 as usize).min(GRID - 1);
        let j = (fj as i32 as usize).min(GRID - 1);
        if fi > GRID as f64 + 1.0 || fj > GRID as f64 + 1.0 {
            return None;
        }
        Some(j * GRID + i)
    }

    /// `Some(answer)` when [`BarChart::is_bar`] gives the same answer at every point of the box
    /// `[lo, hi]`: the grid cells of its corners, and so (the cell index grows with u and v) of
    /// every point between them, span at most 4 x 4 cells, all wholly bar or all wholly backing.
    /// `None` when that is not known (more cells, a mixed cell, both kinds, or not finite).
    #[inline(always)]
    pub fn uniform_in(&self, lo: DVec2, hi: DVec2) -> Option<bool> {
        let (a, b) = (Self::cell_of(lo)?, Self::cell_of(hi)?);
        let (i0, j0, i1, j1) = (a % GRID, a / GRID, b % GRID, b / GRID);
        if i1 < i0 || j1 < j0 || i1 - i0 >= 4 || j1 - j0 >= 4 {
            return None;
        }
        let answer = match self.cells[a] {
            Cell::Empty => false,
            Cell::Full => true,
            Cell::Mixed { .. } => return None,
        };
        for j in j0..=j1 {
            for cell in &self.cells[j * GRID + i0..=j * GRID + i1] {
                if !matches!((cell, answer), (Cell::Empty, false) | (Cell::Full, true)) {
                    return None;
                }
            }
        }
        Some(answer)
    }

    /// True when `uv` lies on a bar (grid lookup).
    #[inline(always)]
    pub fn is_bar(&self, uv: DVec2) -> bool {
        let Some(cell) = Self::cell_of(uv) else { return false };
        match self.cells[cell] {
            Cell::Empty => false,
            Cell::Full => true,
            Cell::Mixed { start, len } => self.candidates[start as usize..(start + len) as usize]
                .iter()
                .any(|&k| self.bars[k as usize].contains(uv)),
        }
    }

    /// Slow, obviously correct twin of [`BarChart::is_bar`]: scans every bar.
    pub fn is_bar_brute_force(&self, uv: DVec2) -> bool {
        self.bars.iter().any(|b| b.contains(uv))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::usaf;

    #[test]
    fn grid_lookup_agrees_with_scanning_every_bar() {
        let chart = usaf::framework_chart();
        assert_eq!(chart.bars().len(), 146);
        let mut s = 12345u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..400_000 {
            let p = DVec2::new(next() * 2.2 - 1.1, next() * 2.2 - 1.1);
            assert_eq!(chart.is_bar(p), chart.is_bar_brute_force(p), "{p:?}");
        }
        // Exactly on bar edges and corners, and on grid-cell boundaries.
        for b in chart.bars() {
            for p in [b.min, b.max, DVec2::new(b.min.x, b.max.y), DVec2::new(b.max.x, b.min.y), (b.min + b.max) / 2.0] {
                assert!(chart.is_bar(p));
                assert!(chart.is_bar_brute_force(p));
                for d in
                    [DVec2::new(1e-12, 0.0), DVec2::new(-1e-12, 0.0), DVec2::new(0.0, 1e-12), DVec2::new(0.0, -1e-12)]
                {
                    assert_eq!(chart.is_bar(p + d), chart.is_bar_brute_force(p + d));
                }
            }
        }
        for k in 0..=GRID {
            let x = -1.0 + 2.0 * k as f64 / GRID as f64;
            for j in 0..50 {
                let p = DVec2::new(x, -1.0 + j as f64 / 25.0);
                assert_eq!(chart.is_bar(p), chart.is_bar_brute_force(p));
                let q = DVec2::new(p.y, p.x);
                assert_eq!(chart.is_bar(q), chart.is_bar_brute_force(q));
            }
        }
        assert!(!chart.is_bar(DVec2::new(f64::NAN, 0.0)));
    }

    #[test]
    fn a_box_called_uniform_has_that_answer_at_every_point() {
        let chart = usaf::framework_chart();
        let mut s = 777u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut bar, mut backing, mut unknown) = (0, 0, 0);
        for _ in 0..200_000 {
            let lo = DVec2::new(next() * 2.2 - 1.1, next() * 2.2 - 1.1);
            // Boxes from a tenth of a cell to five cells wide; some on a cell's edge exactly.
            let size = DVec2::new(next(), next()) * (10.0 / GRID as f64);
            let lo = if next() < 0.1 { (lo * 64.0).floor() / 64.0 } else { lo };
            let hi = lo + size;
            match chart.uniform_in(lo, hi) {
                Some(answer) => {
                    for p in [lo, hi, DVec2::new(lo.x, hi.y), DVec2::new(hi.x, lo.y)]
                        .into_iter()
                        .chain((0..8).map(|_| lo + DVec2::new(next(), next()) * size))
                    {
                        assert_eq!(chart.is_bar_brute_force(p), answer, "{lo} {hi} {p}");
                        assert_eq!(chart.is_bar(p), answer, "{lo} {hi} {p}");
                    }
                    if answer {
                        bar += 1
                    } else {
                        backing += 1
                    }
                }
                None => unknown += 1,
            }
        }
        assert!(bar > 1000 && backing > 1000 && unknown > 1000, "{bar} {backing} {unknown}");
        assert_eq!(chart.uniform_in(DVec2::new(f64::NAN, 0.0), DVec2::ZERO), None);
        assert_eq!(chart.uniform_in(DVec2::splat(-0.5), DVec2::splat(f64::NAN)), None);
    }
}
