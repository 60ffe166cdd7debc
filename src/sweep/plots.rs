//! A sweep's plots (PNG and SVG): each Table 1 score (Sec. 4.2: PSNR, SSIM) and each extra
//! score the experiment names (luminance PSNR, ColorVideoVDP's JOD, HDR-FLIP), or a study's
//! MTF50 ([`super::study`]), against each numeric axis, one series per method (a study's: per
//! source and content depth). Every point and eye case is a dot (with its 95%
//! interval when the measurement gives one); the line joins the mean at each axis value over
//! the other axes and the eye cases. For every pair of numeric axes (a 2-D sweep), the same
//! score against one axis with one line per value of the other (`_by_`), and a heatmap per
//! method over both (`_x_`, each cell's value written in it). Axis labels carry the settings'
//! units ([`super::units`]).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::io::plot::legend;

use super::store::ScoreRow;
use crate::error::{Error, Result};
use crate::perception::ScoreName;

/// One row of `sweep.csv` as the plots see it: the value of every swept key (`None` where it
/// is not a number), the series it belongs to (a method; a study's source at a content depth)
/// and its values with their 95% half-widths.
#[derive(Clone, Debug)]
pub struct PlotRow {
    /// The value of every swept key, in the keys' order (`None`: not a number).
    pub xs: Vec<Option<f64>>,
    /// The series: the method (`LC`), or a study's source at a content depth (`LC 2.5D`,
    /// `LC 1.667D`).
    pub method: String,
    /// Each score of the row: its value (finite) and 95% half-width (finite), if measured.
    values: Vec<(Metric, Option<Measured>)>,
}

/// A value with its 95% half-width, if the measurement gives one.
type Measured = (f64, Option<f64>);

impl PlotRow {
    /// The row of an experiment's point: one method under one eye case.
    pub fn of_score(xs: Vec<Option<f64>>, s: &ScoreRow) -> Self {
        let mut values =
            vec![(Metric::Psnr, finite(s.psnr_db, s.psnr_ci95_db)), (Metric::Ssim, finite(s.ssim, s.ssim_ci95))];
        values.extend(s.perceptual.iter().map(|(n, e)| (Metric::Extra(*n), finite(e.value, e.ci95))));
        Self { xs, method: s.method.clone(), values }
    }

    /// The row of a study's point: one source's MTF50 at one content depth.
    pub fn of_mtf50(xs: Vec<Option<f64>>, r: &super::study::Mtf50Row) -> Self {
        let values = vec![(Metric::Mtf50, finite(r.mtf50_cpd, Some(r.mtf50_ci95)))];
        // The depth to a thousandth of a dioptre (600 mm is `1.667D`).
        let d = format!("{:.3}", r.content_diopters);
        Self { xs, method: format!("{} {}D", r.source, d.trim_end_matches('0').trim_end_matches('.')), values }
    }
}

/// A value and its half-width as a plot takes them: PSNR of identical images (inf), an MTF50
/// beyond the retina's Nyquist frequency (NaN) are left out.
fn finite(v: f64, ci: Option<f64>) -> Option<Measured> {
    v.is_finite().then_some((v, ci.filter(|c| c.is_finite())))
}

/// A score plotted: PSNR, SSIM, one of the extra scores `[measurement] scores` names, or a
/// study's MTF50.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Metric {
    Psnr,
    Ssim,
    Extra(ScoreName),
    Mtf50,
}

impl Metric {
    /// Every score of any row, in report order (PSNR, SSIM, the extra scores; MTF50).
    fn all(rows: &[PlotRow]) -> Vec<Metric> {
        let extra: BTreeSet<ScoreName> = rows
            .iter()
            .flat_map(|r| r.values.iter())
            .filter_map(|(m, _)| match m {
                Metric::Extra(n) => Some(*n),
                _ => None,
            })
            .collect();
        let has = |m: Metric| rows.iter().any(|r| r.values.iter().any(|(n, _)| *n == m));
        [Metric::Psnr, Metric::Ssim]
            .into_iter()
            .filter(|m| has(*m))
            .chain(extra.into_iter().map(Metric::Extra))
            .chain([Metric::Mtf50].into_iter().filter(|m| has(*m)))
            .collect()
    }

    fn name(self) -> &'static str {
        match self {
            Metric::Psnr => "psnr",
            Metric::Ssim => "ssim",
            Metric::Extra(n) => n.name(),
            Metric::Mtf50 => "mtf50",
        }
    }

    fn label(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR (dB)",
            Metric::Ssim => "SSIM",
            Metric::Extra(ScoreName::Cvvdp) => "ColorVideoVDP (JOD)",
            Metric::Extra(ScoreName::Flip) => "HDR-FLIP",
            Metric::Extra(_) => "luminance PSNR (dB)",
            Metric::Mtf50 => "MTF50 (cpd)",
        }
    }

    /// The least half-height of a plot's range.
    fn least_pad(self) -> f64 {
        match self {
            Metric::Psnr | Metric::Extra(ScoreName::PsnrLuminance) => 0.2,
            Metric::Extra(ScoreName::Cvvdp) | Metric::Mtf50 => 0.02,
            _ => 0.002,
        }
    }

    /// A value as a tick (`cell` false) or a heatmap's cell (`cell` true) prints it.
    fn text(self, v: f64, cell: bool) -> String {
        let digits = match self {
            Metric::Psnr | Metric::Extra(ScoreName::PsnrLuminance) => 1,
            Metric::Extra(ScoreName::Cvvdp) | Metric::Mtf50 => 2,
            _ => 3,
        };
        format!("{v:.*}", digits + cell as usize)
    }

    /// The value and its 95% half-width in `row`, if it has this score.
    fn of(self, row: &PlotRow) -> Option<Measured> {
        row.values.iter().find(|(m, _)| *m == self).and_then(|(_, v)| *v)
    }
}

/// The sorted distinct values of key `k` over `rows`, if every row has a finite number there
/// and there are at least two.
fn numeric_values(rows: &[PlotRow], k: usize) -> Option<Vec<f64>> {
    let mut distinct: Vec<f64> = Vec::new();
    for r in rows {
        let x = r.xs.get(k).copied().flatten().filter(|x| x.is_finite())?;
        if !distinct.contains(&x) {
            distinct.push(x);
        }
    }
    distinct.sort_by(f64::total_cmp);
    (distinct.len() >= 2).then_some(distinct)
}

/// A key as a file-name part.
fn stem(key: &str) -> String {
    key.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' }).collect()
}

/// Draws one plot into `<dir>/<name>.png` and `.svg`, each by `$body` with `$area` its drawing
/// area; evaluates to the PNG's path (an error returns from the calling function).
macro_rules! plot_file {
    ($dir:expr, $name:expr, $size:expr, |$area:ident| $body:expr) => {{
        for ext in ["png", "svg"] {
            let path = $dir.join(format!("{}.{ext}", $name));
            crate::io::output::write_atomic(&path, |tmp| {
                crate::io::plot::register_font().map_err(|e| Error::draw(path.display(), "plot", e))?;
                let drawn = if ext == "png" {
                    let $area = BitMapBackend::new(tmp, $size).into_drawing_area();
                    $body
                } else {
                    let $area = SVGBackend::new(tmp, $size).into_drawing_area();
                    $body
                };
                drawn.map_err(|e| Error::draw(path.display(), "plot", e))
            })?;
        }
        $dir.join(format!("{}.png", $name))
    }};
}

/// Writes the plots into `dir` (see the module's comment); `axes[k]` is the sweep axis key `k`
/// belongs to (keys zipped in one axis move together and are never paired). Returns the PNG
/// paths; no plot is drawn when no point is complete.
pub fn write_plots(dir: &Path, keys: &[String], axes: &[usize], rows: &[PlotRow]) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    if rows.is_empty() {
        return Ok(written);
    }
    let values: Vec<Option<Vec<f64>>> = (0..keys.len()).map(|k| numeric_values(rows, k)).collect();
    let numeric: Vec<usize> = (0..keys.len()).filter(|&k| values[k].is_some()).collect();
    if numeric.is_empty() {
        return Ok(written);
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut methods: Vec<String> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method) {
            methods.push(r.method.clone());
        }
    }
    let metrics = Metric::all(rows);
    for &k in &numeric {
        for &metric in &metrics {
            let name = format!("{}_vs_{}", metric.name(), stem(&keys[k]));
            written.push(plot_file!(dir, &name, (900, 600), |area| draw(area, &keys[k], k, rows, metric)));
        }
    }
    for &k in &numeric {
        for &j in numeric.iter().filter(|&&j| j != k && axes.get(j) != axes.get(k)) {
            let by = values[j].as_deref().unwrap_or_default();
            for &metric in &metrics {
                let name = format!("{}_vs_{}_by_{}", metric.name(), stem(&keys[k]), stem(&keys[j]));
                written.push(plot_file!(dir, &name, (900, 600), |area| draw_by(
                    area,
                    (&keys[k], k),
                    (&keys[j], j, by),
                    rows,
                    metric
                )));
            }
        }
    }
    for (a, &k) in numeric.iter().enumerate() {
        for &j in numeric[a + 1..].iter().filter(|&&j| axes.get(j) != axes.get(k)) {
            let (xs, ys) = (values[k].as_deref().unwrap_or_default(), values[j].as_deref().unwrap_or_default());
            for &metric in &metrics {
                for method in &methods {
                    let name = format!("{}_{}_{}_x_{}", metric.name(), stem(method), stem(&keys[k]), stem(&keys[j]));
                    let size = (260 + 90 * xs.len() as u32, 160 + 50 * ys.len() as u32);
                    let size = (size.0.clamp(640, 1800), size.1.clamp(480, 1400));
                    written.push(plot_file!(dir, &name, size, |area| heatmap(
                        area,
                        (&keys[k], k, xs),
                        (&keys[j], j, ys),
                        rows,
                        method,
                        metric
                    )));
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

/// A line plot's chart: numbers across and up.
type LineChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>;

/// The axes every line plot of a sweep shares: `key` (with its unit) across, `metric` up, over
/// the data's box `(x0, x1, y0, y1)` padded by 5% across and 8% up (at least the metric's
/// [`Metric::least_pad`]: 0.2 dB, 0.02 JOD, 0.002 SSIM or FLIP), under `caption` at its font size.
fn metric_axes<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    metric: Metric,
    key: &str,
    (caption, caption_size): (String, u32),
    y_desc: String,
    (x0, x1, y0, y1): (f64, f64, f64, f64),
) -> std::result::Result<LineChart<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    let xpad = ((x1 - x0) * 0.05).max(1e-9);
    let ypad = ((y1 - y0) * 0.08).max(metric.least_pad());
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", caption_size))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0 - xpad)..(x1 + xpad), (y0 - ypad)..(y1 + ypad))?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_desc(super::units::label(key))
        .y_desc(y_desc)
        .y_label_formatter(&|v| metric.text(*v, false))
        .draw()?;
    Ok(chart)
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
        let (Some(x), Some((v, ci))) = (r.xs[k], metric.of(r)) else { continue };
        match methods.iter_mut().find(|(m, _)| *m == r.method) {
            Some((_, pts)) => pts.push((x, v, ci)),
            None => methods.push((r.method.clone(), vec![(x, v, ci)])),
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
    let caption = (format!("{} against {}", metric.label(), super::units::label(key)), 20);
    let y_desc = format!("{}: dots every point and eye case, line the mean", metric.label());
    let mut chart = metric_axes(&area, metric, key, caption, y_desc, (x0, x1, y0, y1)).map_err(e2s)?;
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

/// The mean of `metric` over the rows of `method` (all methods when `None`) whose keys `k`
/// and `j` have the values `x` and `y` (any `y` when `j` is `None`): over the eye cases and any
/// further axes. `None` when no such row has a finite value.
fn mean_at(
    rows: &[PlotRow],
    metric: Metric,
    method: &str,
    (k, x): (usize, f64),
    by: Option<(usize, f64)>,
) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for r in rows {
        let at = |key: usize, v: f64| r.xs.get(key).copied().flatten() == Some(v);
        if r.method != method || !at(k, x) || by.is_some_and(|(j, y)| !at(j, y)) {
            continue;
        }
        if let Some((v, _)) = metric.of(r) {
            sum += v;
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// A value of an axis for a legend or a tick: its shortest decimal form.
fn value_text(v: f64) -> String {
    format!("{v}")
}

/// `metric` against key `k`, one line per method and value of key `j` (the mean over the eye
/// cases and any further axes), the method's colour darker for larger values of `j`.
fn draw_by<DB: DrawingBackend>(
    area: DrawingArea<DB, plotters::coord::Shift>,
    (key, k): (&str, usize),
    (by_key, j, by): (&str, usize, &[f64]),
    rows: &[PlotRow],
    metric: Metric,
) -> std::result::Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e2s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    area.fill(&WHITE).map_err(e2s)?;
    let mut xs: Vec<f64> = rows.iter().filter_map(|r| r.xs.get(k).copied().flatten()).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let mut methods: Vec<String> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method) {
            methods.push(r.method.clone());
        }
    }
    // (method index, index of the value of j, line)
    type Line = (usize, usize, Vec<(f64, f64)>);
    let mut lines: Vec<Line> = Vec::new();
    for (mi, m) in methods.iter().enumerate() {
        for (yi, &y) in by.iter().enumerate() {
            let line: Vec<(f64, f64)> =
                xs.iter().filter_map(|&x| mean_at(rows, metric, m, (k, x), Some((j, y))).map(|v| (x, v))).collect();
            if !line.is_empty() {
                lines.push((mi, yi, line));
            }
        }
    }
    let pts = lines.iter().flat_map(|(_, _, l)| l.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, v) in pts {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(v), y1.max(v));
    }
    if !(x0.is_finite() && y0.is_finite()) {
        return area.present().map_err(e2s);
    }
    let caption = (format!("{} against {}, one line per {}", metric.label(), super::units::label(key), by_key), 18);
    let y_desc = format!("{}: mean over eye cases and other axes", metric.label());
    let mut chart = metric_axes(&area, metric, key, caption, y_desc, (x0, x1, y0, y1)).map_err(e2s)?;
    let unit = super::units::unit_of(by_key).map(|u| format!(" {u}")).unwrap_or_default();
    for (mi, yi, line) in lines {
        let base = method_color(&methods[mi], mi);
        // Lighter for the first value of j, darker for the last.
        let t = if by.len() > 1 { yi as f64 / (by.len() - 1) as f64 } else { 0.0 };
        let shade = |c: u8| ((c as f64) * (1.25 - 0.75 * t)).clamp(0.0, 255.0) as u8;
        let color = RGBColor(shade(base.0), shade(base.1), shade(base.2));
        let style = color.stroke_width(2);
        let label = format!("{} at {}{unit}", methods[mi], value_text(by[yi]));
        chart
            .draw_series(LineSeries::new(line.clone(), style))
            .map_err(e2s)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        chart.draw_series(line.iter().map(|&(x, v)| Circle::new((x, v), 3, color.filled()))).map_err(e2s)?;
    }
    legend(&mut chart, SeriesLabelPosition::LowerRight, Some(12))?;
    area.present().map_err(e2s)
}

/// A colour of a perceptually ordered ramp (dark blue through green to yellow, as viridis) at
/// `t` in [0, 1].
fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let s = t * (STOPS.len() - 1) as f64;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - i as f64;
    let mix = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A heatmap of `metric` for `method` over keys `k` (columns) and `j` (rows): one cell per pair
/// of values (the mean over the eye cases and any further axes), coloured on a ramp from the
/// lowest to the highest value and labelled with its value; cells without a value stay grey.
fn heatmap<DB: DrawingBackend>(
    area: DrawingArea<DB, plotters::coord::Shift>,
    (key, k, xs): (&str, usize, &[f64]),
    (by_key, j, ys): (&str, usize, &[f64]),
    rows: &[PlotRow],
    method: &str,
    metric: Metric,
) -> std::result::Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e2s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    area.fill(&WHITE).map_err(e2s)?;
    let cells: Vec<Vec<Option<f64>>> =
        ys.iter().map(|&y| xs.iter().map(|&x| mean_at(rows, metric, method, (k, x), Some((j, y)))).collect()).collect();
    let (lo, hi) = cells
        .iter()
        .flatten()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mut chart = ChartBuilder::on(&area)
        .caption(
            format!("{} of {method}: {} x {}", metric.label(), super::units::label(key), super::units::label(by_key)),
            ("sans-serif", 18),
        )
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..xs.len() as f64, 0.0..ys.len() as f64)
        .map_err(e2s)?;
    let tick = |values: &[f64], v: f64| {
        let i = v - 0.5;
        if (i - i.round()).abs() < 1e-6 && i >= 0.0 && (i.round() as usize) < values.len() {
            value_text(values[i.round() as usize])
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(2 * xs.len() + 1)
        .y_labels(2 * ys.len() + 1)
        .x_label_formatter(&|v| tick(xs, *v))
        .y_label_formatter(&|v| tick(ys, *v))
        .x_desc(super::units::label(key))
        .y_desc(super::units::label(by_key))
        .draw()
        .map_err(e2s)?;
    for (yi, row) in cells.iter().enumerate() {
        for (xi, cell) in row.iter().enumerate() {
            let (x, y) = (xi as f64, yi as f64);
            let fill = match cell {
                Some(v) if hi > lo => ramp((v - lo) / (hi - lo)),
                Some(_) => ramp(0.5),
                None => RGBColor(200, 200, 200),
            };
            chart.draw_series([Rectangle::new([(x, y), (x + 1.0, y + 1.0)], fill.filled())]).map_err(e2s)?;
            if let Some(v) = cell {
                let text = metric.text(*v, true);
                // Dark text on the light end of the ramp, light text on the dark end.
                let light = hi > lo && (v - lo) / (hi - lo) > 0.6;
                let color = if light { BLACK } else { WHITE };
                let style = TextStyle::from(("sans-serif", 14).into_font()).color(&color).pos(
                    plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Center,
                        plotters::style::text_anchor::VPos::Center,
                    ),
                );
                chart.draw_series([Text::new(text, (x + 0.5, y + 0.5), style)]).map_err(e2s)?;
            }
        }
    }
    area.present().map_err(e2s)
}
