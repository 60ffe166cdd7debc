//! The optimised method's convergence record: the objective, the projected-gradient norm and the
//! wall time of every iteration, as `optimize_OPT.csv` and a plot (`optimize_OPT.png`, plotters
//! as the other charts): the objective relative to its start and the projected-gradient norm
//! relative to its start, both on a log scale, against the iteration.

use std::path::Path;

use plotters::prelude::*;
use serde::Serialize;

use super::solver::{Iteration, Stop};
use crate::error::{Error, Result};
use crate::io::csv_table::CsvTable;
use crate::io::plot::{e2s, legend};

/// What one optimisation did: for `results.json`, the CSV and the plot.
#[derive(Clone, Debug, Serialize)]
pub struct OptimizationReport {
    /// The method's name ("OPT").
    pub method: String,
    /// The starting image's method.
    pub initial: String,
    /// The solver ("fista", "spg" or "pcg").
    pub solver: super::solver::SolverMethod,
    /// The training states: name and weight.
    pub states: Vec<(String, f64)>,
    /// Training retina pixels per side.
    pub retina_resolution: usize,
    /// Samples per retina pixel of each state (sub-pixel points x pupil points).
    pub samples_per_pixel: Vec<usize>,
    /// Each state's mean squared error on the training samples at the start (the initial image).
    pub initial_mse: Vec<f64>,
    /// Each state's mean squared error on the training samples at x*.
    pub final_mse: Vec<f64>,
    /// Why the solver stopped.
    pub stop: Stop,
    /// Every iteration, 0 (the start) first.
    pub iterations: Vec<Iteration>,
    /// Wall seconds of the ground truths of the training states.
    pub targets_seconds: f64,
    /// Wall seconds of the solve.
    pub solve_seconds: f64,
}

impl OptimizationReport {
    /// The iterations as CSV: iteration, objective, projected-gradient norm, step, seconds.
    pub fn csv(&self) -> String {
        let mut t = CsvTable::new();
        t.row(["iteration", "objective", "projected_gradient", "step", "seconds"]);
        for i in &self.iterations {
            t.row([
                i.iteration.to_string(),
                format!("{:e}", i.objective),
                format!("{:e}", i.projected_gradient),
                format!("{}", i.step),
                format!("{:.6}", i.seconds),
            ]);
        }
        t.finish()
    }

    /// Writes the convergence plot to `path` (PNG).
    pub fn write_plot(&self, path: &Path) -> Result<()> {
        crate::io::output::write_atomic(path, |tmp| {
            crate::io::plot::register_font().map_err(|e| Error::draw(path.display(), "plot", e))?;
            let area = BitMapBackend::new(tmp, (900, 560)).into_drawing_area();
            self.draw(area).map_err(|e| Error::draw(path.display(), "plot", e))
        })
    }

    fn draw<DB: DrawingBackend>(&self, area: DrawingArea<DB, plotters::coord::Shift>) -> std::result::Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        area.fill(&WHITE).map_err(e2s)?;
        let first = self.iterations.first().copied();
        let (f0, p0) = first.map_or((1.0, 1.0), |i| (i.objective, i.projected_gradient));
        let rel = |v: f64, base: f64| if base > 0.0 && v.is_finite() { v / base } else { f64::NAN };
        let objective: Vec<(f64, f64)> =
            self.iterations.iter().map(|i| (i.iteration as f64, rel(i.objective, f0))).collect();
        let gradient: Vec<(f64, f64)> = self
            .iterations
            .iter()
            .map(|i| (i.iteration as f64, rel(i.projected_gradient, p0)))
            .filter(|p| p.1.is_finite() && p.1 > 0.0)
            .collect();
        let lo = objective.iter().chain(&gradient).map(|p| p.1).filter(|v| *v > 0.0).fold(1.0f64, f64::min);
        let last = self.iterations.last().map_or(1, |i| i.iteration.max(1)) as f64;
        let title = format!(
            "{}: convergence ({} states, from {}; stop: {:?})",
            self.method,
            self.states.len(),
            self.initial,
            self.stop
        );
        let mut chart = ChartBuilder::on(&area)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..last, (lo * 0.5..2.0).log_scale())
            .map_err(e2s)?;
        chart
            .configure_mesh()
            .x_desc("iteration")
            .y_desc("relative to iteration 0 (log)")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(e2s)?;
        let blue = RGBColor(31, 119, 180);
        let red = RGBColor(214, 39, 40);
        chart
            .draw_series(LineSeries::new(objective, blue.stroke_width(2)))
            .map_err(e2s)?
            .label("objective f(x) / f(x0)")
            .legend(move |(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], blue.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(gradient, red.stroke_width(2)))
            .map_err(e2s)?
            .label("projected gradient norm / initial")
            .legend(move |(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], red.stroke_width(2)));
        legend(&mut chart, SeriesLabelPosition::LowerLeft, Some(13))?;
        area.present().map_err(e2s)
    }
}

/// Whether eye case `case` is one of OPT's training states ("trained") or not ("held out"):
/// the label beside its row of `table.md`.
pub fn case_role(opt: &super::Optimization, case: &str) -> &'static str {
    if opt.states.iter().any(|s| s.name == case) {
        "trained"
    } else {
        "held out"
    }
}

/// The paragraph beside `table.md` when the methods list OPT: what it was trained on (the
/// states, the training's pupil grid and retina samples), how the solve ended, and which bound
/// is which.
pub fn table_note(opt: &super::Optimization, report: Option<&OptimizationReport>) -> String {
    let states: Vec<String> = opt
        .states
        .iter()
        .map(|s| {
            let grid = match s.eye.aperture {
                crate::optics::Aperture::Pinhole => "pinhole".to_string(),
                _ => format!(
                    "{n} x {n} pupil grid ({} points inside the pupil)",
                    s.eye.pupil_samples().len(),
                    n = s.eye.pupil_grid
                ),
            };
            format!(
                "{} ({grid}, {} x {} rays per retina pixel)",
                s.name, s.retina.samples_per_pixel, s.retina.samples_per_pixel
            )
        })
        .collect();
    let end = report.map_or(String::new(), |r| {
        let iterations = r.iterations.last().map_or(0, |i| i.iteration);
        let why = match r.stop {
            super::solver::Stop::Converged => "its tolerance was met",
            super::solver::Stop::Iterations => "its iteration budget was spent",
            super::solver::Stop::Stalled => "no further decrease was possible",
        };
        format!(" The solve stopped after {} because {why}.", crate::count::count(iterations, "iteration"))
    });
    format!(
        "\nOPT was optimised from {} by the `{}` solver on the rows marked trained, each state sampled as the training \
         samples it: {}.{end} On the trained states OPT's score bounds what LC, PC and LA, display images it could \
         have chosen, reach there; its gain over them is a lower bound on the headroom, because the solve stops at \
         its budget. Rows marked held out are eye states it never saw: its gain there says whether the \
         optimisation carries over.\n",
        opt.initial.name(),
        format!("{:?}", opt.solver.method).to_lowercase(),
        states.join("; ")
    )
}
