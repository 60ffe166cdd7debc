//! Projected conjugate gradient with the Jacobi preconditioner for the optimised method's problem
//! (`solver.rs`; preconditioned CG restricted to the free variables, restarted when a step meets
//! a bound, as in the active-set CG of O'Leary, Math. Program. 1980, and Polyak 1969). The
//! preconditioner is the diagonal of the Hessian `H = 2 (sum_s c_s A_s^T A_s + mu I)`, exact and
//! matrix-free ([`Operator::diagonal_add`]: each band's samples summed per matrix entry), computed
//! once.
//!
//! A value is bound when it sits on 0 with `g > 0` or on 1 with `g < 0`; the others are free.
//! From `x` with gradient `g`, `z = -M^-1 g` on the free values (0 on the bound ones), and the
//! direction `p = z + beta p_prev` (Fletcher-Reeves in the preconditioned metric,
//! `beta = g.z / g_prev.z_prev`; `beta = 0` after a restart, or when `p` is not one of descent).
//! The exact step along `p` costs one forward application per state:
//! - it stays in [0, 1]: taken, a conjugate-gradient step;
//! - it leaves [0, 1]: the projected direction `d = P(x + t p) - x` (`P` clips to [0, 1]) is taken
//!   with its own exact step in [0, 1] (one more forward application), and the next direction
//!   restarts.
//!
//! Either way `f` never increases. Then one adjoint for the new gradient.
//! Memory: x, g, p, the diagonal, and d (five LCD-sized vectors).

use std::time::Instant;

use rayon::prelude::*;

use super::operator::{Operator, Rgb};
use super::solver::{
    clipped, coefficient, dot, gradient, mse, objective, projected_gradient, residuals, sum_sq, Iteration, Solution,
    SolverSettings, Stop, Term,
};
use crate::progress::Progress;

/// The Hessian's diagonal `2 (sum_s c_s diag(A_s^T A_s) + mu)`.
fn jacobi<O: Operator>(terms: &[Term<O>], m: usize, mu: f64) -> Vec<Rgb> {
    let mut d = vec![[2.0 * mu; 3]; m];
    for t in terms {
        t.operator.diagonal_add(2.0 * coefficient(t), &mut d);
    }
    d
}

/// Whether value `x` with gradient `g` is held by its bound.
#[inline(always)]
fn bound(x: f64, g: f64) -> bool {
    (x <= 0.0 && g > 0.0) || (x >= 1.0 && g < 0.0)
}

/// `A_s v` for every term, into `out`.
fn forward_all<O: Operator>(terms: &[Term<O>], v: &[Rgb], out: &mut [Vec<Rgb>]) {
    for (t, a) in terms.iter().zip(out.iter_mut()) {
        t.operator.forward(v, a);
    }
}

/// `sum_s c_s ||A_s v||^2 + mu ||v||^2` from the `A_s v`: half the curvature along `v`.
fn curvature<O: Operator>(terms: &[Term<O>], av: &[Vec<Rgb>], v: &[Rgb], mu: f64) -> f64 {
    terms.iter().zip(av).map(|(t, a)| coefficient(t) * sum_sq(a, None)).sum::<f64>() + mu * sum_sq(v, None)
}

/// `z = -M^-1 g` of channel `c` of one value: `-g / l` on a free value with a positive diagonal
/// `l`, 0 on a bound one.
#[inline(always)]
fn z_of(x: &[f64; 3], g: &[f64; 3], l: &[f64; 3], c: usize) -> f64 {
    if l[c] > 0.0 && !bound(x[c], g[c]) {
        -g[c] / l[c]
    } else {
        0.0
    }
}

/// `g.z` with `z = -M^-1 g` on the free values (summed in chunks of 8192 values, in order).
fn preconditioned_gz(g: &[Rgb], x: &[Rgb], diag: &[Rgb]) -> f64 {
    g.par_chunks(8192)
        .zip(x.par_chunks(8192))
        .zip(diag.par_chunks(8192))
        .map(|((g, x), l)| {
            let mut s = 0.0;
            for ((g, x), l) in g.iter().zip(x).zip(l) {
                for c in 0..3 {
                    s += g[c] * z_of(x, g, l, c);
                }
            }
            s
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// The search direction `p = z + beta p_prev` in place, 0 on the bound values.
fn set_direction(p: &mut [Rgb], x: &[Rgb], g: &[Rgb], diag: &[Rgb], beta: f64) {
    p.par_iter_mut().zip(x).zip(g).zip(diag).for_each(|(((p, x), g), l)| {
        *p = std::array::from_fn(|c| {
            let z = z_of(x, g, l, c);
            if z == 0.0 && (l[c] <= 0.0 || bound(x[c], g[c])) {
                0.0
            } else {
                z + beta * p[c]
            }
        })
    });
}

/// Whether `x + t p` stays in [0, 1].
fn stays_inside(p: &[Rgb], x: &[Rgb], t: f64) -> bool {
    p.par_iter().zip(x).all(|(p, x)| (0..3).all(|c| (0.0..=1.0).contains(&(x[c] + t * p[c]))))
}

/// The conjugate-gradient step: `x += t p` and each term's residual `r_s += t A_s p`.
fn step_along(x: &mut [Rgb], res: &mut [Vec<Rgb>], p: &[Rgb], ap: &[Vec<Rgb>], t: f64) {
    x.par_iter_mut().zip(p).for_each(|(x, p)| *x = std::array::from_fn(|c| x[c] + t * p[c]));
    for (r, a) in res.iter_mut().zip(ap) {
        r.par_iter_mut().zip(a).for_each(|(r, a)| *r = std::array::from_fn(|c| r[c] + t * a[c]));
    }
}

/// The projected arc `d = P(x + t p) - x` (feasible for steps in [0, 1]) into `d`, and `g.d`;
/// when it bends away from descent, the preconditioned gradient's arc `P(x + t z) - x` instead.
fn projected_arc(d: &mut [Rgb], x: &[Rgb], p: &[Rgb], g: &[Rgb], diag: &[Rgb], t: f64) -> f64 {
    d.par_iter_mut().zip(x).zip(p).for_each(|((d, x), p)| {
        *d = std::array::from_fn(|c| (x[c] + t * p[c]).clamp(0.0, 1.0) - x[c]);
    });
    let mut gd = dot(g, d);
    if gd >= 0.0 {
        // Bent away from descent: the preconditioned gradient's arc is one.
        d.par_iter_mut().zip(x).zip(g).zip(diag).for_each(|(((d, x), g), l)| {
            *d = std::array::from_fn(|c| (x[c] + t * z_of(x, g, l, c)).clamp(0.0, 1.0) - x[c]);
        });
        gd = dot(g, d);
    }
    gd
}

/// The step `s` along the projected arc: `x = P(x + s d)` and `r_s += s A_s d`.
fn step_along_arc(x: &mut [Rgb], res: &mut [Vec<Rgb>], d: &[Rgb], ad: &[Vec<Rgb>], s: f64) {
    x.par_iter_mut().zip(d).for_each(|(x, d)| *x = std::array::from_fn(|c| (x[c] + s * d[c]).clamp(0.0, 1.0)));
    for (r, a) in res.iter_mut().zip(ad) {
        r.par_iter_mut().zip(a).for_each(|(r, a)| *r = std::array::from_fn(|c| r[c] + s * a[c]));
    }
}

/// Minimises `f` from `x0` by projected, Jacobi-preconditioned conjugate gradient.
pub(super) fn pcg<O: Operator>(
    terms: &[Term<O>],
    x0: &[Rgb],
    settings: &SolverSettings,
    progress: &Progress,
) -> Solution {
    let m = x0.len();
    let mu = settings.regularization / (3.0 * m as f64);
    let diag = jacobi(terms, m, mu);
    let mut x = clipped(x0);
    let mut res = residuals(terms, &x);
    let initial_mse = mse(&res);
    let mut f = objective(terms, &res, &x, x0, mu);
    let mut g = vec![[0.0; 3]; m];
    gradient(terms, &res, &x, x0, mu, &mut g);
    let mut pg = projected_gradient(&g, &x);
    let pg0 = pg;
    let mut history = vec![Iteration { iteration: 0, objective: f, projected_gradient: pg, step: 0.0, seconds: 0.0 }];
    let mut p = vec![[0.0; 3]; m];
    let mut d = vec![[0.0; 3]; m];
    let mut ap: Vec<Vec<Rgb>> = terms.iter().map(|t| vec![[0.0; 3]; t.operator.rows()]).collect();
    let mut ad = ap.clone();
    // g_prev.z_prev of the last conjugate step (NaN: restart).
    let mut gz_prev = f64::NAN;
    let mut stop = Stop::Iterations;
    for it in 1..=settings.max_iterations {
        if pg <= settings.tolerance * pg0 || pg == 0.0 {
            stop = Stop::Converged;
            break;
        }
        if progress.cancelled() {
            break;
        }
        let start = Instant::now();
        // z = -M^-1 g on the free values; gz = g.z.
        let gz = preconditioned_gz(&g, &x, &diag);
        if gz >= 0.0 {
            // No free value has a gradient: the projected gradient is zero up to rounding.
            stop = Stop::Stalled;
            break;
        }
        let mut beta = if gz_prev.is_finite() { gz / gz_prev } else { 0.0 };
        set_direction(&mut p, &x, &g, &diag, beta);
        let mut gp = dot(&g, &p);
        if beta != 0.0 && gp >= 0.0 {
            beta = 0.0;
            set_direction(&mut p, &x, &g, &diag, beta);
            gp = gz;
        }
        forward_all(terms, &p, &mut ap);
        let q = curvature(terms, &ap, &p, mu);
        if q <= 0.0 {
            stop = Stop::Stalled;
            break;
        }
        let t = -gp / (2.0 * q);
        let (predicted, step);
        if stays_inside(&p, &x, t) {
            predicted = t * gp + t * t * q;
            step = t;
            if -predicted <= 1e-15 * f {
                stop = Stop::Stalled;
                break;
            }
            step_along(&mut x, &mut res, &p, &ap, t);
            gz_prev = gz;
        } else {
            let gd = projected_arc(&mut d, &x, &p, &g, &diag, t);
            forward_all(terms, &d, &mut ad);
            let qd = curvature(terms, &ad, &d, mu);
            let s = if qd > 0.0 { (-gd / (2.0 * qd)).min(1.0) } else { 1.0 };
            predicted = s * gd + s * s * qd;
            step = s;
            if gd >= 0.0 || -predicted <= 1e-15 * f {
                stop = Stop::Stalled;
                break;
            }
            step_along_arc(&mut x, &mut res, &d, &ad, s);
            gz_prev = f64::NAN;
        }
        f = objective(terms, &res, &x, x0, mu);
        gradient(terms, &res, &x, x0, mu, &mut g);
        pg = projected_gradient(&g, &x);
        history.push(Iteration {
            iteration: it,
            objective: f,
            projected_gradient: pg,
            step,
            seconds: start.elapsed().as_secs_f64(),
        });
    }
    if matches!(stop, Stop::Iterations) && pg <= settings.tolerance * pg0 {
        stop = Stop::Converged;
    }
    drop((res, g, p, d, ap, ad, diag));
    let final_mse = mse(&residuals(terms, &x));
    Solution { x, history, stop, initial_mse, final_mse }
}
