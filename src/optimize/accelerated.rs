//! FISTA for the optimised method's problem (`solver.rs`; Beck & Teboulle, SIAM J. Imaging Sci.
//! 2, 2009), in a diagonal metric and with monotone restart. `f` is quadratic with Hessian
//! `H = 2 (sum_s c_s A_s^T A_s + mu I)`, whose entries are all >= 0 (the simulation's weights are),
//! so `D = diag(H 1)` majorises it (`D - H` is diagonally dominant): from any `y`,
//! `z = P(y - D^-1 g(y))` (`P` clips to [0, 1]) never has a larger `f` than `y`. `D` costs one
//! forward and one adjoint per state (of the all-ones image), once. Each iteration extrapolates
//! `y = x_k + beta (x_k - x_(k-1))`, whose gradient is the same combination of the last two
//! gradients (`g` is affine in `x`: no operator call), steps to `z`, and applies the forward
//! operator once to evaluate `f(z)`:
//! - `f(z) <= f(x_k)`: accepted, one adjoint for `g(z)`.
//! - otherwise: rejected, the momentum restarts (O'Donoghue & Candes, Found. Comput. Math. 15,
//!   2015), and the next step is the plain majorised step from `x_k`, which cannot increase `f`.
//!
//! Memory: x, the previous x, their gradients and `D` (five LCD-sized vectors).

use std::time::Instant;

use rayon::prelude::*;

use super::operator::{Operator, Rgb};
use super::solver::{
    clipped, coefficient, gradient, mse, objective, projected_gradient, residuals, Iteration, Solution, SolverSettings,
    Stop, Term,
};
use crate::progress::Progress;

/// `D = diag(H 1) = 2 (sum_s c_s A_s^T (A_s 1) + mu)`, per value.
pub(super) fn majoriser<O: Operator>(terms: &[Term<O>], m: usize, mu: f64) -> Vec<Rgb> {
    let ones = vec![[1.0; 3]; m];
    let mut d = vec![[2.0 * mu; 3]; m];
    for t in terms {
        let mut a = vec![[0.0; 3]; t.operator.rows()];
        t.operator.forward(&ones, &mut a);
        t.operator.adjoint_add(&a, 2.0 * coefficient(t), &mut d);
    }
    d
}

/// Minimises `f` from `x0` by FISTA with the majoriser `D` and monotone restart.
pub(super) fn fista<O: Operator>(
    terms: &[Term<O>],
    x0: &[Rgb],
    settings: &SolverSettings,
    progress: &Progress,
) -> Solution {
    let m = x0.len();
    let mu = settings.regularization / (3.0 * m as f64);
    let lip = majoriser(terms, m, mu);
    let mut x = clipped(x0);
    let mut res = residuals(terms, &x);
    let initial_mse = mse(&res);
    let mut f = objective(terms, &res, &x, x0, mu);
    let mut g = vec![[0.0; 3]; m];
    gradient(terms, &res, &x, x0, mu, &mut g);
    let mut pg = projected_gradient(&g, &x);
    let pg0 = pg;
    let mut history = vec![Iteration { iteration: 0, objective: f, projected_gradient: pg, step: 0.0, seconds: 0.0 }];
    // The previous point and its gradient (overwritten by the trial point z and its gradient).
    let mut xp = x.clone();
    let mut gp = g.clone();
    let mut t = 1.0f64;
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
        let tn = 0.5 * (1.0 + (1.0 + 4.0 * t * t).sqrt());
        let beta = (t - 1.0) / tn;
        // z = P(y - D^-1 g(y)), y = x + beta (x - xp), g(y) = g + beta (g - gp); into xp.
        xp.par_iter_mut().zip(&x).zip(&g).zip(&gp).zip(&lip).for_each(|((((z, x), g), gp), l)| {
            *z = std::array::from_fn(|c| {
                if l[c] > 0.0 {
                    let y = x[c] + beta * (x[c] - z[c]);
                    let gy = g[c] + beta * (g[c] - gp[c]);
                    (y - gy / l[c]).clamp(0.0, 1.0)
                } else {
                    // No sample reaches it and no regulariser: f does not depend on it.
                    x[c]
                }
            })
        });
        let res_z = residuals(terms, &xp);
        let f_z = objective(terms, &res_z, &xp, x0, mu);
        let step;
        if f_z <= f {
            if beta == 0.0 && f - f_z <= 1e-15 * f {
                // The plain majorised step gains nothing above the objective's rounding.
                stop = Stop::Stalled;
                break;
            }
            gradient(terms, &res_z, &xp, x0, mu, &mut gp);
            std::mem::swap(&mut x, &mut xp);
            std::mem::swap(&mut g, &mut gp);
            res = res_z;
            f = f_z;
            t = tn;
            step = 1.0;
        } else {
            if beta == 0.0 {
                // The majorised step cannot increase f: only rounding can have made it.
                stop = Stop::Stalled;
                break;
            }
            t = 1.0;
            step = 0.0;
        }
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
    drop((res, g, gp, xp, lip));
    let final_mse = mse(&residuals(terms, &x));
    Solution { x, history, stop, initial_mse, final_mse }
}
