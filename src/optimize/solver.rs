//! The bound-constrained least-squares problem of the optimised method (docs/OPTIMAL.md) and its
//! solvers:
//!
//! ```text
//! minimise f(x) = sum_s c_s ||A_s x - t_s||^2 + mu ||x - x0||^2   over 0 <= x <= 1,
//! c_s = w_s / (3 N_s),  mu = lambda / (3 M)
//! ```
//!
//! (`N_s` retina pixels of state `s`, `M` LCD pixels, three channels each: the weights are per
//! value, so `f` is a weighted mean squared error.) Three solvers share the problem's pieces here
//! (residuals, objective, gradient, projected-gradient norm); each costs one adjoint and one
//! forward application per state and iteration, keeps `x` in [0, 1] and never increases `f`:
//!
//! - [`SolverMethod::Spg`], here: spectral projected gradient with an exact line search (Birgin,
//!   Martinez & Raydan, SIAM J. Optim. 10, 2000, with the monotone exact step that a quadratic
//!   allows): from `x` with gradient `g`, the direction `d = P(x - alpha g) - x` (`P` clips to
//!   [0, 1]) stays feasible for every step `t` in [0, 1]; `f(x + t d) = f + t g.d + t^2 q` with
//!   `q = sum_s c_s ||A_s d||^2 + mu ||d||^2`, so the best step is `t = min(1, -g.d / (2 q))`.
//!   The next `alpha` is the Barzilai-Borwein step `||d||^2 / (2 q)`.
//! - [`SolverMethod::Fista`] (`accelerated.rs`): FISTA with a diagonal majoriser and monotone restart.
//! - [`SolverMethod::Pcg`] (`conjugate.rs`): projected conjugate gradient with the Jacobi
//!   preconditioner.

use std::time::Instant;

use rayon::prelude::*;

use super::operator::{Operator, Rgb};
use crate::progress::Progress;

/// One training term: the operator of an eye state, its target (ground truth) and its weight.
pub struct Term<O> {
    /// `A_s`.
    pub operator: O,
    /// `t_s`: one value per retina pixel of `A_s`.
    pub target: Vec<Rgb>,
    /// `w_s` (before the normalisation by the number of values).
    pub weight: f64,
}

/// Which algorithm minimises `f` (docs/OPTIMAL.md compares them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverMethod {
    /// Spectral projected gradient with the exact step.
    Spg,
    /// FISTA with the diagonal majoriser `diag(H 1)` and monotone restart.
    Fista,
    /// Projected conjugate gradient, Jacobi-preconditioned, restarted when the step meets a bound.
    Pcg,
}

impl SolverMethod {
    /// The names `[optimize] solver` accepts.
    pub const NAMES: &'static str = "\"spg\", \"fista\" or \"pcg\"";
}

impl std::str::FromStr for SolverMethod {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "spg" => Ok(Self::Spg),
            "fista" => Ok(Self::Fista),
            "pcg" => Ok(Self::Pcg),
            _ => Err(format!("unknown solver `{s}`: name {}", Self::NAMES)),
        }
    }
}

/// How and when the solver stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// The algorithm.
    pub method: SolverMethod,
    /// The most iterations.
    pub max_iterations: usize,
    /// Stop when the projected-gradient norm falls below `tolerance` times its initial value.
    pub tolerance: f64,
    /// lambda: the weight of `||x - x0||^2` (per value), 0 for none.
    pub regularization: f64,
}

/// One iteration's record (iteration 0 is the starting point).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Iteration {
    /// The iteration (0: the start).
    pub iteration: usize,
    /// f(x) after the iteration.
    pub objective: f64,
    /// `||P(x - g) - x||`: zero exactly at the constrained minimum (at x after the iteration).
    pub projected_gradient: f64,
    /// The step taken along the projected direction (0 to 1).
    pub step: f64,
    /// Wall seconds of the iteration.
    pub seconds: f64,
}

/// Why the solver stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// The projected gradient fell below the tolerance.
    Converged,
    /// The iteration budget was spent.
    Iterations,
    /// No further decrease is possible in floating point (the direction is not one of descent).
    Stalled,
}

/// The solution and its convergence history.
#[derive(Clone, Debug)]
pub struct Solution {
    /// x*: one value per LCD pixel, in [0, 1].
    pub x: Vec<Rgb>,
    /// The history, iteration 0 first.
    pub history: Vec<Iteration>,
    /// Why it stopped.
    pub stop: Stop,
    /// Each term's mean squared error `||A_s x - t_s||^2 / (3 N_s)` at the start.
    pub initial_mse: Vec<f64>,
    /// Each term's mean squared error at x* (from a fresh forward application).
    pub final_mse: Vec<f64>,
}

/// Deterministic `sum |a - b|^2` (fixed chunks summed in order).
pub(super) fn sum_sq(a: &[Rgb], b: Option<&[Rgb]>) -> f64 {
    const CHUNK: usize = 8192;
    let parts: Vec<f64> = a
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(i, c)| {
            let mut s = 0.0;
            for (j, v) in c.iter().enumerate() {
                let o = b.map_or([0.0; 3], |b| b[i * CHUNK + j]);
                for k in 0..3 {
                    s += (v[k] - o[k]) * (v[k] - o[k]);
                }
            }
            s
        })
        .collect();
    parts.iter().sum()
}

/// The objective's pieces for the terms' residuals `r_s = A_s x - t_s` and `x`.
pub(super) fn objective<O: Operator>(terms: &[Term<O>], residuals: &[Vec<Rgb>], x: &[Rgb], x0: &[Rgb], mu: f64) -> f64 {
    let data: f64 = terms.iter().zip(residuals).map(|(t, r)| coefficient(t) * sum_sq(r, None)).sum();
    data + if mu > 0.0 { mu * sum_sq(x, Some(x0)) } else { 0.0 }
}

/// c_s = w_s / (3 N_s).
pub(super) fn coefficient<O: Operator>(t: &Term<O>) -> f64 {
    t.weight / (3.0 * t.operator.rows() as f64)
}

/// `A_s x - t_s` for every term.
pub(super) fn residuals<O: Operator>(terms: &[Term<O>], x: &[Rgb]) -> Vec<Vec<Rgb>> {
    terms
        .iter()
        .map(|t| {
            let mut r = vec![[0.0; 3]; t.operator.rows()];
            t.operator.forward(x, &mut r);
            r.par_iter_mut().zip(&t.target).for_each(|(r, t)| *r = [r[0] - t[0], r[1] - t[1], r[2] - t[2]]);
            r
        })
        .collect()
}

/// The gradient `2 sum_s c_s A_s^T r_s + 2 mu (x - x0)` into `g` (one adjoint per term).
pub(super) fn gradient<O: Operator>(
    terms: &[Term<O>],
    res: &[Vec<Rgb>],
    x: &[Rgb],
    x0: &[Rgb],
    mu: f64,
    g: &mut [Rgb],
) {
    g.par_iter_mut().zip(x).zip(x0).for_each(|((g, x), x0)| {
        *g = if mu > 0.0 { std::array::from_fn(|c| 2.0 * mu * (x[c] - x0[c])) } else { [0.0; 3] };
    });
    for (t, r) in terms.iter().zip(res) {
        t.operator.adjoint_add(r, 2.0 * coefficient(t), g);
    }
}

/// `||P(x - g) - x||`: zero exactly at the constrained minimum (deterministic chunked sum).
pub(super) fn projected_gradient(g: &[Rgb], x: &[Rgb]) -> f64 {
    g.par_chunks(8192)
        .zip(x.par_chunks(8192))
        .map(|(g, x)| {
            let mut s = 0.0;
            for (g, x) in g.iter().zip(x) {
                for c in 0..3 {
                    let p = (x[c] - g[c]).clamp(0.0, 1.0) - x[c];
                    s += p * p;
                }
            }
            s
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum::<f64>()
        .sqrt()
}

/// Deterministic `sum a.b` (fixed chunks summed in order).
pub(super) fn dot(a: &[Rgb], b: &[Rgb]) -> f64 {
    a.par_chunks(8192)
        .zip(b.par_chunks(8192))
        .map(|(a, b)| {
            let mut s = 0.0;
            for (a, b) in a.iter().zip(b) {
                for c in 0..3 {
                    s += a[c] * b[c];
                }
            }
            s
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// Each residual's mean squared error `||r||^2 / (3 N)`.
pub(super) fn mse(res: &[Vec<Rgb>]) -> Vec<f64> {
    res.iter().map(|r| sum_sq(r, None) / (3.0 * r.len().max(1) as f64)).collect()
}

/// `x0` clipped to [0, 1]: every solver's start.
pub(super) fn clipped(x0: &[Rgb]) -> Vec<Rgb> {
    x0.iter().map(|v| v.map(|c| c.clamp(0.0, 1.0))).collect()
}

/// Minimises `f` from `x0` (which must lie in [0, 1]; it is also the regulariser's centre) with
/// `settings.method`. Deterministic bit for bit at any thread count. A cancelled run
/// (`progress`) stops after the current iteration with the best point so far.
pub fn solve<O: Operator>(terms: &[Term<O>], x0: &[Rgb], settings: &SolverSettings, progress: &Progress) -> Solution {
    match settings.method {
        SolverMethod::Spg => spg(terms, x0, settings, progress),
        SolverMethod::Fista => super::accelerated::fista(terms, x0, settings, progress),
        SolverMethod::Pcg => super::conjugate::pcg(terms, x0, settings, progress),
    }
}

/// Spectral projected gradient with the exact step (this file's header).
fn spg<O: Operator>(terms: &[Term<O>], x0: &[Rgb], settings: &SolverSettings, progress: &Progress) -> Solution {
    let m = x0.len();
    let mu = settings.regularization / (3.0 * m as f64);
    let mut x = clipped(x0);
    let mut res = residuals(terms, &x);
    let initial_mse = mse(&res);
    let mut f = objective(terms, &res, &x, x0, mu);
    let mut g = vec![[0.0; 3]; m];
    let mut history = Vec::new();
    let mut alpha = f64::NAN;
    let mut pg0 = f64::NAN;
    let mut ad: Vec<Vec<Rgb>> = terms.iter().map(|t| vec![[0.0; 3]; t.operator.rows()]).collect();
    let mut stop = Stop::Iterations;
    for it in 0..=settings.max_iterations {
        let start = Instant::now();
        // The gradient: 2 sum_s c_s A_s^T r_s + 2 mu (x - x0).
        gradient(terms, &res, &x, x0, mu, &mut g);
        let pg = projected_gradient(&g, &x);
        if it == 0 {
            pg0 = pg;
            history.push(Iteration { iteration: 0, objective: f, projected_gradient: pg, step: 0.0, seconds: 0.0 });
        } else if let Some(last) = history.last_mut() {
            last.projected_gradient = pg;
        }
        if pg <= settings.tolerance * pg0 || pg == 0.0 {
            stop = Stop::Converged;
            break;
        }
        if it == settings.max_iterations || progress.cancelled() {
            break;
        }
        if !alpha.is_finite() {
            let gmax = g.par_iter().map(|v| v[0].abs().max(v[1].abs()).max(v[2].abs())).reduce(|| 0.0, f64::max);
            alpha = 1.0 / gmax;
        }
        // d = P(x - alpha g) - x, written over g once g.d is known.
        let gd: f64 = g
            .par_chunks(8192)
            .zip(x.par_chunks(8192))
            .map(|(g, x)| {
                let mut s = 0.0;
                for (g, x) in g.iter().zip(x) {
                    for c in 0..3 {
                        s += g[c] * ((x[c] - alpha * g[c]).clamp(0.0, 1.0) - x[c]);
                    }
                }
                s
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        g.par_iter_mut()
            .zip(&x)
            .for_each(|(g, x)| *g = std::array::from_fn(|c| (x[c] - alpha * g[c]).clamp(0.0, 1.0) - x[c]));
        let d = &g;
        let dd = sum_sq(d, None);
        if gd >= 0.0 || dd == 0.0 {
            stop = Stop::Stalled;
            break;
        }
        for (t, a) in terms.iter().zip(ad.iter_mut()) {
            t.operator.forward(d, a);
        }
        let q: f64 = terms.iter().zip(&ad).map(|(t, a)| coefficient(t) * sum_sq(a, None)).sum::<f64>() + mu * dd;
        let step = if q > 0.0 { (-gd / (2.0 * q)).min(1.0) } else { 1.0 };
        let predicted = step * gd + step * step * q;
        // A decrease below the objective's rounding is no decrease: stop rather than step.
        if -predicted <= 1e-15 * f {
            stop = Stop::Stalled;
            break;
        }
        x.par_iter_mut().zip(d).for_each(|(x, d)| *x = std::array::from_fn(|c| (x[c] + step * d[c]).clamp(0.0, 1.0)));
        for (r, a) in res.iter_mut().zip(&ad) {
            r.par_iter_mut().zip(a).for_each(|(r, a)| *r = std::array::from_fn(|c| r[c] + step * a[c]));
        }
        f = objective(terms, &res, &x, x0, mu);
        alpha = if q > 0.0 { (dd / (2.0 * q)).clamp(1e-12, 1e12) } else { 1e12 };
        history.push(Iteration {
            iteration: it + 1,
            objective: f,
            projected_gradient: f64::NAN,
            step,
            seconds: start.elapsed().as_secs_f64(),
        });
    }
    drop((res, ad, g));
    let final_mse = mse(&residuals(terms, &x));
    Solution { x, history, stop, initial_mse, final_mse }
}
