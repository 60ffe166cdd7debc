//! The bench's plots, as PNG and SVG (plotters): speed against error (`speed_psnr`,
//! `speed_ssim`: PSNR or SSIM against wall time per method and backend), the convergence of
//! each series (`la_grid`, `pupil_grid`, `retina_samples`) with its fitted power law, and the cost
//! of precision (`precision`: each Table 1 estimator's error against seconds).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::io::plot::{e2s, legend};
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::markdown::{estimator_name, secs, series_setting};
use super::options::{BenchRow, Estimator, MethodLabel, Series};
use super::precision::{PRECISION_TARGETS_DB, SWEPT};
use super::summary::ConvergenceSummary;
use super::BenchReport;
use crate::error::{Error, Result};

/// Draws `$body` (with the drawing area bound to `$area`) into `$out/$name.png` and `.svg`, each
/// written atomically.
macro_rules! draw_plot {
    ($out:expr, $name:expr, $size:expr, |$area:ident| $body:expr) => {{
        for ext in ["png", "svg"] {
            let path = $out.join(format!("{}.{ext}", $name));
            crate::io::output::write_atomic(&path, |tmp| {
                crate::io::plot::register_font().map_err(|e| Error::draw(path.display(), "plot", e))?;
                let res: PlotResult = if ext == "png" {
                    let $area = BitMapBackend::new(tmp, $size).into_drawing_area();
                    $body
                } else {
                    let $area = SVGBackend::new(tmp, $size).into_drawing_area();
                    $body
                };
                res.map_err(|e| Error::draw(path.display(), "plot", e))
            })?;
        }
    }};
}

/// Every plot of `report` into `out`.
pub fn write_plots(report: &BenchReport, out: &Path) -> Result<()> {
    for (name, metric) in [("speed_psnr", Metric::Psnr), ("speed_ssim", Metric::Ssim)] {
        draw_plot!(out, name, (1400, 1000), |area| plot_speed(area, report, metric));
    }
    for s in &report.convergence {
        draw_plot!(out, s.series, (900, 560), |area| plot_convergence(area, report, s));
    }
    if !report.precision.points.is_empty() {
        draw_plot!(out, "precision", (1200, 800), |area| plot_precision(area, report));
    }
    Ok(())
}

#[derive(Clone, Copy, PartialEq)]
enum Metric {
    Psnr,
    Ssim,
}

type PlotResult = std::result::Result<(), String>;

/// Two significant digits, without trailing zeros: axis labels of log scales.
fn significant(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let decimals = (1 - v.log10().floor() as i32).max(0) as usize;
    let t = format!("{v:.decimals$}");
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    }
}

fn method_color(method: MethodLabel) -> RGBColor {
    match method {
        MethodLabel::Lc => RGBColor(31, 119, 180),
        MethodLabel::Pc => RGBColor(214, 39, 40),
        MethodLabel::La => RGBColor(44, 160, 44),
        MethodLabel::Gt => RGBColor(80, 80, 80),
        MethodLabel::Opt => RGBColor(148, 103, 189),
    }
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
}

/// Speed against error: one panel per image (display, then each eye case), x = wall time
/// (log), y = PSNR or SSIM; one series per method (colour) and backend (marker), its points
/// being 1 and 2 x 2 samples per display pixel.
fn plot_speed<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, rep: &BenchReport, metric: Metric) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let title = match metric {
        Metric::Psnr => "Speed against error: PSNR vs high-sample reference",
        Metric::Ssim => "Speed against error: SSIM vs high-sample reference",
    };
    let area = area.titled(title, ("sans-serif", 24)).map_err(e2s)?;
    let mut panels: Vec<(String, String)> = vec![(String::new(), "display image".into())];
    for (c, mm) in &rep.eye_cases {
        panels.push((c.clone(), format!("perceived, {c} ({mm:.0} mm)")));
    }
    let cols = 2;
    let nrows = panels.len().div_ceil(cols);
    let cells = area.split_evenly((nrows, cols));
    let value = |r: &BenchRow| match metric {
        Metric::Psnr => r.psnr_db,
        Metric::Ssim => r.ssim,
    };
    for (i, ((eye, label), cell)) in panels.iter().zip(cells.iter()).enumerate() {
        let pts: Vec<&BenchRow> =
            rep.rows.iter().filter(|r| r.series == Series::Method && &r.eye_case == eye).collect();
        if pts.is_empty() {
            continue;
        }
        let (t0, t1) = range(pts.iter().map(|r| r.seconds));
        let (v0, v1) = range(pts.iter().map(|r| value(r)));
        let pad = ((v1 - v0) * 0.08).max(match metric {
            Metric::Psnr => 0.5,
            Metric::Ssim => 0.002,
        });
        let mut chart = ChartBuilder::on(cell)
            .caption(label, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((t0 * 0.7..t1 * 1.4).log_scale(), (v0 - pad)..(v1 + pad))
            .map_err(e2s)?;
        chart
            .configure_mesh()
            .max_light_lines(2)
            .x_labels(8)
            .x_label_formatter(&|v| significant(*v))
            .x_desc("wall time (s, log)")
            .y_desc(match metric {
                Metric::Psnr => "PSNR (dB)",
                Metric::Ssim => "SSIM",
            })
            .y_label_formatter(&|v| match metric {
                Metric::Psnr => format!("{v:.1}"),
                Metric::Ssim => format!("{v:.3}"),
            })
            .draw()
            .map_err(e2s)?;
        for m in MethodLabel::METHODS {
            for (bi, b) in rep.backends.iter().enumerate() {
                let mut line: Vec<(f64, f64)> =
                    pts.iter().filter(|r| r.method == m && r.backend == *b).map(|r| (r.seconds, value(r))).collect();
                line.sort_by(|a, b| a.0.total_cmp(&b.0));
                if line.is_empty() {
                    continue;
                }
                let color = method_color(m);
                let style = color.stroke_width(2);
                let anno = chart.draw_series(LineSeries::new(line.clone(), style)).map_err(e2s)?;
                if i == 0 {
                    anno.label(format!("{m} {b}")).legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(-8, 0), (8, 0)], style)
                            + marker_element(bi, color)
                    });
                }
                chart
                    .draw_series(line.iter().map(|p| EmptyElement::at(*p) + marker_element(bi, color)))
                    .map_err(e2s)?;
            }
        }
        if i == 0 {
            legend(&mut chart, SeriesLabelPosition::LowerRight, Some(13))?;
        }
    }
    area.present().map_err(e2s)
}

/// A marker per backend: circle, triangle, square, cross.
fn marker_element<DB: DrawingBackend>(backend: usize, color: RGBColor) -> DynElement<'static, DB, (i32, i32)> {
    let filled = color.filled();
    match backend % 4 {
        0 => Circle::new((0, 0), 5, filled).into_dyn(),
        1 => TriangleMarker::new((0, 0), 6, filled).into_dyn(),
        2 => Rectangle::new([(-4, -4), (4, 4)], filled).into_dyn(),
        _ => Cross::new((0, 0), 5, color.stroke_width(2)).into_dyn(),
    }
}

/// Convergence of one series: x = samples per pixel (log), y = PSNR against the reference,
/// the wall time beside each point, and the fitted power law.
fn plot_convergence<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    rep: &BenchReport,
    c: &ConvergenceSummary,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let pts: Vec<&BenchRow> = rep.rows.iter().filter(|r| r.series == c.series).collect();
    let (n0, n1) = range(pts.iter().map(|r| r.samples as f64));
    let (p0, p1) = range(pts.iter().map(|r| r.psnr_db.min(120.0)));
    let title = format!("{} vs {}", c.quantity, c.reference);
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 18))
        .margin(14)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d((n0 * 0.7..n1 * 3.0).log_scale(), (p0 - 2.0)..(p1 + 2.5))
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_label_formatter(&|v| significant(*v))
        .x_desc(match c.series {
            Series::LaGrid => "lenslet samples per display pixel, k x k (log)",
            Series::PupilGrid => "pupil samples: n x n grid, kept inside the circle (log)",
            Series::Method | Series::RetinaSamples | Series::Precision => "samples per retina pixel, k x k (log)",
        })
        .y_desc("PSNR (dB)")
        .draw()
        .map_err(e2s)?;
    let color = RGBColor(31, 119, 180);
    let line: Vec<(f64, f64)> = pts.iter().map(|r| (r.samples as f64, r.psnr_db.min(120.0))).collect();
    chart
        .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
        .map_err(e2s)?
        .label(format!("{} ({} backend)", c.series, c.backend))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
    chart.draw_series(line.iter().map(|p| Circle::new(*p, 4, color.filled()))).map_err(e2s)?;
    // The wall time beside each point, alternately above-left and below-right of it so that
    // neighbours do not overlap.
    for (i, r) in pts.iter().enumerate() {
        let (dx, dy) = if i % 2 == 0 { (0.8, 0.9) } else { (1.08, -0.5) };
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{}: {} s", series_setting(c.series, r.parameter, r.samples), secs(r.seconds)),
                (r.samples as f64 * dx, r.psnr_db.min(120.0) + dy),
                ("sans-serif", 12),
            )))
            .map_err(e2s)?;
    }
    if let Some(p) = c.rate {
        // ln(err) = a + p ln(N), fitted through the mean point; PSNR = -20 log10(err).
        let xy: Vec<(f64, f64)> = line
            .iter()
            .filter(|(_, v)| *v < 120.0)
            .map(|(n, v)| (n.ln(), -v / 20.0 * std::f64::consts::LN_10))
            .collect();
        let m = xy.len() as f64;
        let a = xy.iter().map(|v| v.1).sum::<f64>() / m - p * xy.iter().map(|v| v.0).sum::<f64>() / m;
        let fit = |n: f64| -20.0 * (a + p * n.ln()) / std::f64::consts::LN_10;
        let gray = RGBColor(120, 120, 120);
        chart
            .draw_series(LineSeries::new(
                (0..=40).map(|i| {
                    let n = n0 * (n1 / n0).powf(i as f64 / 40.0);
                    (n, fit(n))
                }),
                gray.stroke_width(1),
            ))
            .map_err(e2s)?
            .label(format!("fit: error ~ N^{p:.2}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], gray.stroke_width(1)));
    }
    legend(&mut chart, SeriesLabelPosition::LowerRight, None)?;
    area.present().map_err(e2s)
}

/// The cost of precision: x = seconds (log), y = largest |PSNR error| over Table 1's cells
/// against the converged Table 1 (log), one line per estimator with its points labelled by
/// samples per pixel; dashed horizontal lines at the targets of the thresholds table.
fn plot_precision<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, rep: &BenchReport) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let p = &rep.precision;
    let floor = 1e-4;
    let err = |v: f64| v.max(floor);
    let (t0, t1) = range(p.points.iter().map(|q| q.seconds.max(1e-4)));
    let (e0, e1) = range(p.points.iter().map(|q| err(q.max_psnr_error_db)));
    let (e0, e1) = (e0.min(PRECISION_TARGETS_DB[3]) * 0.5, e1.max(PRECISION_TARGETS_DB[0]) * 2.0);
    let mut chart = ChartBuilder::on(&area)
        .caption(
            format!(
                "The cost of precision: Table 1's largest |PSNR error| against the converged Table 1 ({} backend)",
                rep.backends.first().map(|b| b.as_str()).unwrap_or("?")
            ),
            ("sans-serif", 20),
        )
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((t0 * 0.7..t1 * 1.4).log_scale(), (e0..e1).log_scale())
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .x_desc("seconds (eye rays and scoring of the whole Table 1; log)")
        .y_desc("largest |PSNR - converged| over Table 1 (dB, log)")
        .x_label_formatter(&|v| significant(*v))
        .y_label_formatter(&|v| significant(*v))
        .draw()
        .map_err(e2s)?;
    let gray = RGBColor(150, 150, 150);
    for t in PRECISION_TARGETS_DB {
        chart
            .draw_series(DashedLineSeries::new([(t0 * 0.7, t), (t1 * 1.4, t)], 6, 4, gray.stroke_width(1)))
            .map_err(e2s)?;
    }
    let small = ("sans-serif", 12).into_font().into_text_style(&area).pos(Pos::new(HPos::Left, VPos::Bottom));
    for (i, e) in SWEPT.into_iter().enumerate() {
        let color = estimator_color(e);
        let pts: Vec<_> = p.points.iter().filter(|q| q.estimator == e).collect();
        let line: Vec<(f64, f64)> = pts.iter().map(|q| (q.seconds.max(1e-4), err(q.max_psnr_error_db))).collect();
        chart
            .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
            .map_err(e2s)?
            .label(estimator_name(e))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2)));
        chart.draw_series(line.iter().map(|q| EmptyElement::at(*q) + marker_element(i, color))).map_err(e2s)?;
        chart
            .draw_series(
                pts.iter().zip(&line).map(|(q, xy)| Text::new(q.samples_per_pixel.to_string(), *xy, small.clone())),
            )
            .map_err(e2s)?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, Some(15))?;
    area.present().map_err(e2s)
}

fn estimator_color(e: Estimator) -> RGBColor {
    match e {
        Estimator::Grid => RGBColor(31, 119, 180),
        Estimator::Random => RGBColor(255, 127, 14),
        Estimator::RqmcNaive => RGBColor(214, 39, 40),
        Estimator::Rqmc => RGBColor(44, 160, 44),
        Estimator::Reference => RGBColor(80, 80, 80),
    }
}
