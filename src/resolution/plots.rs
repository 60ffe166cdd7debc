//! The study's plots, PNG and SVG (plotters):
//! - `mtf`: grating contrast (lines) and slanted-edge MTF (crosses) against frequency per source,
//!   the eye focused on the content, one panel per content depth, the display's Nyquist marked;
//! - `through_focus`: contrast at the accommodation frequency against eye focus per source, one
//!   panel per content depth, the CDP (grey) and the content depth (black) marked;
//! - `accommodation`: the predicted focus against content depth per source (lines: the
//!   frequency rule; hollow circles: the area rule), the identity line and the CDP;
//! - `orientations` (when the study has more than one orientation): grating contrast against
//!   frequency, one line per orientation, one panel per source (columns) for the content depth
//!   nearest the CDP and the farthest one (rows), the eye focused on the content.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::io::plot::{e2s, legend};

use super::report::AccommodationRow;
use super::run::StudyResults;
use crate::error::{Error, Result};
use crate::io::output::OutputDir;

type PlotResult = std::result::Result<(), String>;

/// Ground truth grey, then LC blue, PC red, LA green, further methods in other colours.
fn color(k: usize) -> RGBColor {
    [
        RGBColor(60, 60, 60),
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
    ][k % 6]
}

/// Draws `$body` with `$area` bound to a PNG, then an SVG drawing area, into `$dir`'s
/// `$name.png` and `$name.svg`, each written atomically.
macro_rules! draw_plot {
    ($dir:expr, $name:expr, $size:expr, |$area:ident| $body:expr) => {{
        for ext in ["png", "svg"] {
            let file = format!("{}.{ext}", $name);
            $dir.write_with(&file, |path| {
                crate::io::plot::register_font().map_err(|e| Error::draw(&file, "plot", e))?;
                let res: PlotResult = if ext == "png" {
                    let $area = BitMapBackend::new(path, $size).into_drawing_area();
                    $body
                } else {
                    let $area = SVGBackend::new(path, $size).into_drawing_area();
                    $body
                };
                res.map_err(|e| Error::draw(&file, "plot", e))
            })?;
        }
    }};
}

/// Every plot of the study into `dir`.
pub fn write_plots(r: &StudyResults, accommodation: &[AccommodationRow], dir: &OutputDir) -> Result<()> {
    let nd = r.study.depths.len();
    let cols = 3.min(nd).max(1);
    let rows = nd.div_ceil(cols) as u32;
    let size = (420 * cols as u32, 60 + 320 * rows);
    draw_plot!(dir, "mtf", size, |area| plot_mtf(area, r, cols));
    draw_plot!(dir, "through_focus", size, |area| plot_through_focus(area, r, cols));
    draw_plot!(dir, "accommodation", (900, 700), |area| plot_accommodation(area, r, accommodation));
    if r.study.orientations_deg.len() > 1 {
        let size = (380 * r.sources.len() as u32, 60 + 2 * 320);
        draw_plot!(dir, "orientations", size, |area| plot_orientations(area, r));
    }
    Ok(())
}

fn cdp_diopters(r: &StudyResults) -> Option<f64> {
    r.study.display.central_depth_plane().map(|z| 1000.0 / z)
}

fn plot_mtf<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, r: &StudyResults, cols: usize) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let s = &r.study;
    let area = area
        .titled(
            &format!(
                "MTF with the eye focused on the content ({} mm pupil): gratings (lines), slanted edge (x)",
                s.pupil_diameter_mm
            ),
            ("sans-serif", 20),
        )
        .map_err(e2s)?;
    let nyquist = crate::info::display_design(&s.display, s.pupil_diameter_mm).pixels_per_degree.map(|p| 0.5 * p[0]);
    let fmax = s.frequencies_cpd.last().copied().unwrap_or(1.0) * 1.05;
    let cells = area.split_evenly((s.depths.len().div_ceil(cols), cols));
    for (di, (d, cell)) in s.depths.iter().zip(cells.iter()).enumerate() {
        let fi = s.focus_index(d.diopters).expect("content depths are measured focuses");
        let mut chart = ChartBuilder::on(cell)
            .caption(format!("content {:.2} D ({:.0} mm)", d.diopters, d.mm), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(40)
            .build_cartesian_2d(0.0..fmax, 0.0..1.1)
            .map_err(e2s)?;
        chart.configure_mesh().max_light_lines(1).x_desc("cycles per degree").y_desc("contrast").draw().map_err(e2s)?;
        if let Some(n) = nyquist {
            chart
                .draw_series(LineSeries::new([(n, 0.0), (n, 1.1)], RGBColor(150, 150, 150).stroke_width(1)))
                .map_err(e2s)?;
        }
        for (k, name) in r.sources.iter().enumerate() {
            let c = color(k);
            let pts: Vec<(f64, f64)> =
                s.frequencies_cpd.iter().zip(&r.grating[k][di][fi]).map(|(f, v)| (*f, v.value)).collect();
            let a = chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2))).map_err(e2s)?;
            if di == 0 {
                a.label(name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
            }
            chart.draw_series(pts.iter().map(|p| Circle::new(*p, 2, c.filled()))).map_err(e2s)?;
            let edge: Vec<(f64, f64)> = s
                .frequencies_cpd
                .iter()
                .zip(&r.edge[k][di][fi])
                .filter(|(_, v)| v.value.is_finite())
                .map(|(f, v)| (*f, v.value.min(1.1)))
                .collect();
            chart.draw_series(edge.iter().map(|p| Cross::new(*p, 4, c.stroke_width(1)))).map_err(e2s)?;
        }
        if di == 0 {
            legend(&mut chart, SeriesLabelPosition::UpperRight, Some(12))?;
        }
    }
    area.present().map_err(e2s)
}

fn plot_through_focus<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, r: &StudyResults, cols: usize) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let s = &r.study;
    let f = s.accommodation.frequency_cpd;
    let qi = s.frequency_index(f).expect("validated");
    let area = area
        .titled(
            &format!("Contrast at {f} cpd against eye focus: content depth (black), CDP (grey)"),
            ("sans-serif", 20),
        )
        .map_err(e2s)?;
    let (x0, x1) = (s.focus_diopters[0], *s.focus_diopters.last().unwrap_or(&4.0));
    let cdp = cdp_diopters(r);
    let cells = area.split_evenly((s.depths.len().div_ceil(cols), cols));
    for (di, (d, cell)) in s.depths.iter().zip(cells.iter()).enumerate() {
        let mut chart = ChartBuilder::on(cell)
            .caption(format!("content {:.2} D ({:.0} mm)", d.diopters, d.mm), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(40)
            .build_cartesian_2d(x0..x1.max(x0 + 0.1), 0.0..1.1)
            .map_err(e2s)?;
        chart.configure_mesh().max_light_lines(1).x_desc("eye focus (D)").y_desc("contrast").draw().map_err(e2s)?;
        if let Some(c) = cdp {
            chart
                .draw_series(LineSeries::new([(c, 0.0), (c, 1.1)], RGBColor(150, 150, 150).stroke_width(2)))
                .map_err(e2s)?;
        }
        chart
            .draw_series(LineSeries::new([(d.diopters, 0.0), (d.diopters, 1.1)], BLACK.stroke_width(1)))
            .map_err(e2s)?;
        for (k, name) in r.sources.iter().enumerate() {
            let c = color(k);
            let pts: Vec<(f64, f64)> =
                s.focus_diopters.iter().zip(&r.grating[k][di]).map(|(x, q)| (*x, q[qi].value)).collect();
            let a = chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2))).map_err(e2s)?;
            if di == 0 {
                a.label(name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
            }
            chart.draw_series(pts.iter().map(|p| Circle::new(*p, 2, c.filled()))).map_err(e2s)?;
        }
        if di == 0 {
            legend(&mut chart, SeriesLabelPosition::UpperRight, Some(12))?;
        }
    }
    area.present().map_err(e2s)
}

fn plot_accommodation<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    r: &StudyResults,
    rows: &[AccommodationRow],
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let s = &r.study;
    let (x0, x1) = (s.focus_diopters[0], *s.focus_diopters.last().unwrap_or(&4.0));
    let title = format!(
        "Predicted accommodation: lines contrast at {} cpd, circles MTF area to {} cpd",
        s.accommodation.frequency_cpd, s.accommodation.area_limit_cpd
    );
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 18))
        .margin(14)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, x0..x1)
        .map_err(e2s)?;
    chart.configure_mesh().x_desc("content depth (D)").y_desc("predicted eye focus (D)").draw().map_err(e2s)?;
    chart
        .draw_series(LineSeries::new([(x0, x0), (x1, x1)], BLACK.stroke_width(1)))
        .map_err(e2s)?
        .label("identity (correct focus cue)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(1)));
    if let Some(c) = cdp_diopters(r) {
        chart
            .draw_series(LineSeries::new([(x0, c), (x1, c)], RGBColor(150, 150, 150).stroke_width(2)))
            .map_err(e2s)?
            .label(format!("CDP ({c:.2} D)"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RGBColor(150, 150, 150).stroke_width(2)));
    }
    for (k, name) in r.sources.iter().enumerate() {
        let c = color(k);
        let pick = |rule: &str| -> Vec<(f64, f64)> {
            rows.iter()
                .filter(|a| &a.source == name && a.rule == rule && a.predicted_focus_diopters.is_finite())
                .map(|a| (a.target_diopters, a.predicted_focus_diopters))
                .collect()
        };
        let f = pick("contrast_at_frequency");
        chart
            .draw_series(LineSeries::new(f.clone(), c.stroke_width(2)))
            .map_err(e2s)?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        chart.draw_series(f.iter().map(|p| Circle::new(*p, 3, c.filled()))).map_err(e2s)?;
        chart.draw_series(pick("mtf_area").iter().map(|p| Circle::new(*p, 6, c.stroke_width(2)))).map_err(e2s)?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft, Some(13))?;
    area.present().map_err(e2s)
}

fn plot_orientations<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, r: &StudyResults) -> PlotResult
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(e2s)?;
    let s = &r.study;
    let area = area
        .titled(
            &format!("Grating contrast by orientation, eye focused on the content ({} mm pupil)", s.pupil_diameter_mm),
            ("sans-serif", 20),
        )
        .map_err(e2s)?;
    let cdp = cdp_diopters(r).unwrap_or(0.0);
    let near = (0..s.depths.len())
        .min_by(|&a, &b| (s.depths[a].diopters - cdp).abs().total_cmp(&(s.depths[b].diopters - cdp).abs()))
        .unwrap_or(0);
    let fmax = s.frequencies_cpd.last().copied().unwrap_or(1.0) * 1.05;
    let ns = r.sources.len();
    let cells = area.split_evenly((2, ns));
    for (row, di) in [near, 0].into_iter().enumerate() {
        let d = s.depths[di];
        let fi = s.focus_index(d.diopters).expect("content depths are measured focuses");
        for (k, name) in r.sources.iter().enumerate() {
            let mut chart = ChartBuilder::on(&cells[row * ns + k])
                .caption(format!("{name}, content {:.2} D", d.diopters), ("sans-serif", 16))
                .margin(8)
                .x_label_area_size(34)
                .y_label_area_size(40)
                .build_cartesian_2d(0.0..fmax, 0.0..1.1)
                .map_err(e2s)?;
            chart
                .configure_mesh()
                .max_light_lines(1)
                .x_desc("cycles per degree")
                .y_desc("contrast")
                .draw()
                .map_err(e2s)?;
            for (oi, o) in s.orientations_deg.iter().enumerate() {
                let c = color(oi + 1);
                let pts: Vec<(f64, f64)> =
                    s.frequencies_cpd.iter().zip(&r.grating_at(oi)[k][di][fi]).map(|(f, v)| (*f, v.value)).collect();
                let a = chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2))).map_err(e2s)?;
                if row == 0 && k == 0 {
                    a.label(format!("{o} deg"))
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
                }
                chart.draw_series(pts.iter().map(|p| Circle::new(*p, 2, c.filled()))).map_err(e2s)?;
            }
            if row == 0 && k == 0 {
                legend(&mut chart, SeriesLabelPosition::UpperRight, Some(12))?;
            }
        }
    }
    area.present().map_err(e2s)
}
