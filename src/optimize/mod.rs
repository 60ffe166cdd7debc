//! The optimised method OPT (docs/OPTIMAL.md): the display image that is best, in the least-squares
//! sense, over a set of eye states. The perceived image is linear in the display image x, `A_s x`
//! for eye state s (the simulation's trace, `operator.rs`), so
//!
//! ```text
//! x* = argmin over 0 <= x <= 1 of  sum_s w_s / (3 N_s) ||A_s x - t_s||^2 + lambda / (3 M) ||x - x0||^2
//! ```
//!
//! with `t_s` the ground truth of state s, found matrix-free by a projected-gradient solver
//! (`solver.rs`) from a starting image x0 (LA by default). This file runs it for a display and a
//! scene: `spec.rs` is the `[optimize]` table, `report.rs` the convergence record and plot.
//! OPT needs the scene only for the training states' ground truths; it works with any radiance
//! field and any eye the simulation knows, because it uses only the simulation's forward operator
//! and its adjoint.

pub mod accelerated;
pub mod conjugate;
pub mod operator;
pub mod report;
pub mod solver;
pub mod spec;

use std::time::Instant;

use rayon::prelude::*;

pub use operator::{EyeOperator, Operator, Rgb};
pub use report::OptimizationReport;
pub use solver::{solve, Iteration, Solution, SolverMethod, SolverSettings, Stop, Term};
pub use spec::{Optimization, OptimizeSpec, TrainingState};

use crate::error::{Error, Result};
use crate::optics::Display;
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::{ground_truth, render_display_image_into, DisplayRenderSettings, Method, RadianceField};

/// OPT's display image into `image` (the LCD's size): the starting image rendered by its method,
/// the training states' ground truths traced through `field`, then the solve. `progress` counts
/// iterations (and may cancel the run). Returns the convergence record.
pub fn render_optimal_into<R: RadianceField + ?Sized>(
    display: &Display,
    settings: &DisplayRenderSettings,
    opt: &Optimization,
    field: &R,
    progress: &Progress,
    image: &mut RgbImage,
) -> Result<OptimizationReport> {
    let hidden = Progress::hidden();
    let mut depth = Vec::new();
    render_display_image_into(display, opt.initial, settings, field, &hidden, image, &mut depth)?;
    drop(depth);
    for s in &opt.states {
        crate::optics::transfer::check_eye_in_front(display, s.eye.position.z, "optimize", &s.name)?;
    }
    let t = Instant::now();
    let mut terms = Vec::with_capacity(opt.states.len());
    for s in &opt.states {
        let operator = EyeOperator::new(display, &s.eye, &s.retina);
        // With diffraction the target sees the operator's diffracted rays; else the grid's.
        let target = match operator.diffracted_target(field) {
            Some(t) => t,
            None => {
                ground_truth(&s.eye, &s.retina, field, &hidden).pixels.par_iter().map(|p| p.map(f64::from)).collect()
            }
        };
        crate::progress::check_cancelled()?;
        terms.push(Term { operator, target, weight: s.weight });
    }
    let targets_seconds = t.elapsed().as_secs_f64();
    let x0: Vec<Rgb> = image.pixels.par_iter().map(|p| p.map(f64::from)).collect();
    let t = Instant::now();
    let solution = solve(&terms, &x0, &opt.solver, progress);
    let solve_seconds = t.elapsed().as_secs_f64();
    progress.check()?;
    drop(x0);
    image.pixels.par_iter_mut().zip(&solution.x).for_each(|(p, x)| *p = x.map(|v| v as f32));
    if !image.all_finite() {
        return Err(Error::Mismatch("OPT's display image is not finite".into()));
    }
    let samples_per_pixel = opt
        .states
        .iter()
        .map(|s| {
            let per = s.eye.optics.as_ref().map_or(1, |o| o.grid_spectral().len());
            s.retina.subpixel_offsets().len() * s.eye.pupil_samples().len() * per
        })
        .collect();
    Ok(OptimizationReport {
        method: Method::Optimized.name(),
        initial: opt.initial.name(),
        solver: opt.solver.method,
        states: opt.states.iter().map(|s| (s.name.clone(), s.weight)).collect(),
        retina_resolution: opt.states.first().map_or(0, |s| s.retina.resolution),
        samples_per_pixel,
        initial_mse: solution.initial_mse,
        final_mse: solution.final_mse,
        stop: solution.stop,
        iterations: solution.history,
        targets_seconds,
        solve_seconds,
    })
}
