//! A sweep's plots (PNG and SVG): each Table 1 score (Sec. 4.2: PSNR, SSIM) against each
//! numeric axis, one series per method. Every point and eye case is a dot (with its 95%
//! interval when the measurement gives one); the line joins the mean at each axis value over
//! the other axes and the eye cases.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::io::plot::legend;

use super::store::ScoreRow;
use crate::error::{Error, Result};

/// One row of `sweep.csv` as the plots see it: the value of every swept key (`None` where it
/// is not a number) and the scores.
#[derive(Clone, Debug)]
pub struct PlotRow {
    /// The value of every swept key, in the keys' order (`None`: not a number).
    pub xs: Vec<Option<f64>>,
    /// The point's score of one method and eye case.
    pub score: ScoreRow,
}

#[derive(Clone, Copy)]
enum Metric {
    Psnr,
    Ssim,
}

impl Metric {
    fn name(self) -> &'static str {
        match self {
            Metric::Psnr => "psnr",
            Metric::Ssim => "ssim",
        }
    }

    fn label(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR (dB)",
            Metric::Ssim => "SSIM",
        }
    }

    /// The value and its 95% half-width; PSNR of identical images (inf) is left out.
    fn of(self, s: &ScoreRow) -> Option<(f64, Option<f64>)> {
        let (v, ci) = match self {
            Metric::Psnr => (s.psnr_db, s.psnr_ci95_db),
            Metric::Ssim => (s.ssim, s.ssim_ci95),
        };
        v.is_finite().then_some((v, ci.filter(|c| c.is_finite())))
    }
}

/// Writes `<psnr|ssim>_vs_<key>.png` and `.svg` into `dir` for every numeric key with at least
/// two values; returns the PNG paths. No plot is drawn when no point is complete.
pub fn write_plots(dir: &Path, keys: &[String], rows: &[PlotRow]) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    if rows.is_empty() {
        return Ok(written);
    }
    for (k, key) in keys.iter().enumerate() {
        let mut distinct: Vec<f64> = Vec::new();
        let mut numeric = true;
        for r in rows {
            match r.xs.get(k).copied().flatten() {
                Some(x) if x.is_finite() => {
                    if !distinct.contains(&x) {
                        distinct.push(x);
                    }
                }
                _ => numeric = false,
            }
        }
        if !numeric || distinct.len() < 2 {
            continue;
        }
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let stem: String =
            key.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' }).collect();
        for metric in [Metric::Psnr, Metric::Ssim] {
            let name = format!("{}_vs_{stem}", metric.name());
            for ext in ["png", "svg"] {
                let path = dir.join(format!("{name}.{ext}"));
                let size = (900, 600);
                crate::io::output::write_atomic(&path, |tmp| {
                    let drawn = if ext == "png" {
                        draw(BitMapBackend::new(tmp, size).into_drawing_area(), key, k, rows, metric)
                    } else {
                        draw(SVGBackend::new(tmp, size).into_drawing_area(), key, k, rows, metric)
                    };
                    drawn.map_err(|e| Error::draw(path.display(), "plot", e))
                })?;
                if ext == "png" {
                    written.push(path);
                }
            }
        }
    }
    Ok(written)
}

/// A dot: axis value, score, 95% half-width.
type Dot = (f64, f64, Option<f64>);

fn method_color(method: &str, i: usize) -> RGBColor {
    match method {
        "LC" => RGBColor(31, 119, 180),
        "PC" => RGBColor(214, 39, 40),
        "LA" => RGBColor(44, 160, 44),
        _ => [RGBColor(148, 103, 189), RGBColor(255, 127, 14), RGBColor(140, 86, 75)][i % 3],
    }
}

fn draw<DB: DrawingBackend>(
    area: DrawingArea<DB, plotters::coord::Shift>,
    key: &str,
    k: usize,
    rows: &[PlotRow],
    metric: Metric,
) -> std::result::Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e2s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    area.fill(&WHITE).map_err(e2s)?;
    // (x, value, half-width) per method, methods in order of appearance.
    let mut methods: Vec<(String, Vec<Dot>)> = Vec::new();
    for r in rows {
        let (Some(x), Some((v, ci))) = (r.xs[k], metric.of(&r.score)) else { continue };
        match methods.iter_mut().find(|(m, _)| *m == r.score.method) {
            Some((_, pts)) => pts.push((x, v, ci)),
            None => methods.push((r.score.method.clone(), vec![(x, v, ci)])),
        }
    }
    let all = methods.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, v, ci) in all {
        let h = ci.unwrap_or(0.0);
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(v - h), y1.max(v + h));
    }
    if !(x0.is_finite() && y0.is_finite()) {
        return area.present().map_err(e2s);
    }
    let xpad = (x1 - x0) * 0.05;
    let ypad = ((y1 - y0) * 0.08).max(match metric {
        Metric::Psnr => 0.2,
        Metric::Ssim => 0.002,
    });
    let mut chart = ChartBuilder::on(&area)
        .caption(format!("{} against {key}", metric.label()), ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0 - xpad)..(x1 + xpad), (y0 - ypad)..(y1 + ypad))
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_desc(key)
        .y_desc(format!("{}: dots every point and eye case, line the mean", metric.label()))
        .y_label_formatter(&|v| match metric {
            Metric::Psnr => format!("{v:.1}"),
            Metric::Ssim => format!("{v:.3}"),
        })
        .draw()
        .map_err(e2s)?;
    for (i, (method, pts)) in methods.iter().enumerate() {
        let color = method_color(method, i);
        let mut means: BTreeMap<u64, (f64, f64, usize)> = BTreeMap::new();
        for &(x, v, _) in pts {
            let e = means.entry(x.to_bits() ^ (1 << 63)).or_insert((x, 0.0, 0));
            e.1 += v;
            e.2 += 1;
        }
        let mut line: Vec<(f64, f64)> = means.values().map(|&(x, s, n)| (x, s / n as f64)).collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        let style = color.stroke_width(2);
        chart
            .draw_series(LineSeries::new(line, style))
            .map_err(e2s)?
            .label(method.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        chart.draw_series(pts.iter().map(|&(x, v, _)| Circle::new((x, v), 3, color.mix(0.6).filled()))).map_err(e2s)?;
        chart
            .draw_series(
                pts.iter().filter_map(|&(x, v, ci)| {
                    ci.map(|h| PathElement::new(vec![(x, v - h), (x, v + h)], color.mix(0.6)))
                }),
            )
            .map_err(e2s)?;
    }
    legend(&mut chart, SeriesLabelPosition::LowerRight, Some(14))?;
    area.present().map_err(e2s)
}
