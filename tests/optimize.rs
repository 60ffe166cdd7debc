//! The optimised method OPT (docs/OPTIMAL.md): its operator is the simulation and its adjoint the
//! exact transpose; its solver reaches the constrained least-squares optimum that an independent
//! dense solve finds, never increases the objective and stays within [0, 1].
#![deny(unsafe_code)]
// Dense linear algebra reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

use glam::{DMat2, DVec2, DVec3};
use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::experiment::EyeModelSettings;
use inimtrace::fixtures::Lcg;
use inimtrace::metrics::psnr;
use inimtrace::optics::Aperture;
use inimtrace::optics::{Display, Eye, Focus, Lattice, Retina};
use inimtrace::optimize::{
    render_optimal_into, solve, EyeOperator, Operator, Optimization, Rgb, SolverMethod, SolverSettings, Term,
    TrainingState,
};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::simulate;
use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method};
use inimtrace::scene::Scene;

/// The paper's display at a small LCD, with square, hexagonal and tilted lattices.
fn displays(res: usize) -> Vec<(&'static str, Display)> {
    let mut square = Display::paper();
    square.lcd.resolution = [res, res];
    let mut hex = square.clone();
    hex.lenslets = Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(1.2, 0.0), DVec2::new(0.6, 1.039))).unwrap();
    hex.elemental_images =
        Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(1.58, 0.0), DVec2::new(0.79, 1.368))).unwrap();
    let mut tilted = square.clone();
    tilted.lenslets =
        Lattice::new(DVec2::new(0.05, -0.02), DMat2::from_angle(0.3) * DMat2::from_diagonal(DVec2::splat(1.2)))
            .unwrap();
    tilted.elemental_images =
        Lattice::new(DVec2::new(-0.01, 0.03), DMat2::from_angle(0.3) * DMat2::from_diagonal(DVec2::splat(1.58)))
            .unwrap();
    vec![("square", square), ("hexagonal", hex), ("tilted", tilted)]
}

/// Pinhole, thin lenses in and out of focus (one displaced), and a schematic eye.
fn eyes(retina: &Retina, display: &Display) -> Vec<(&'static str, Eye)> {
    let mut moved = Eye::thin_lens(4.0, Focus::Millimetres(300.0), 4);
    moved.position = DVec3::new(0.8, -0.5, 1.0);
    let mut navarro = Eye::thin_lens(4.0, Focus::Millimetres(400.0), 3);
    let settings = EyeModelSettings { model: Some("navarro".into()), ..EyeModelSettings::default() };
    navarro.optics = settings
        .optics_for(&navarro, retina.half_tangent, &display.primaries.clone().unwrap_or_default(), "test", "focus")
        .unwrap();
    assert!(navarro.optics.is_some());
    vec![
        ("pinhole", Eye::pinhole()),
        ("thin lens", Eye::thin_lens(5.0, Focus::Millimetres(400.0), 5)),
        ("displaced thin lens", moved),
        ("navarro", navarro),
    ]
}

fn random(n: usize, rng: &mut Lcg, lo: f64, hi: f64) -> Vec<Rgb> {
    (0..n).map(|_| [rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi)]).collect()
}

fn dot(a: &[Rgb], b: &[Rgb]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).sum()
}

#[test]
fn the_adjoint_is_the_exact_transpose() {
    let mut rng = Lcg(27);
    let retina = Retina { resolution: 20, half_tangent: 0.25, samples_per_pixel: 2 };
    for (dname, display) in displays(240) {
        for (ename, eye) in eyes(&retina, &display) {
            let op = EyeOperator::new(&display, &eye, &retina);
            for _ in 0..2 {
                let x = random(op.cols(), &mut rng, -1.0, 1.0);
                let y = random(op.rows(), &mut rng, -1.0, 1.0);
                let mut ax = vec![[0.0; 3]; op.rows()];
                op.forward(&x, &mut ax);
                let mut aty = vec![[0.0; 3]; op.cols()];
                op.adjoint_add(&y, 1.0, &mut aty);
                let (l, r) = (dot(&ax, &y), dot(&x, &aty));
                let scale = l.abs().max(r.abs());
                assert!(scale > 1e-3, "{dname} {ename}: the operator sees the display ({l})");
                assert!((l - r).abs() <= 1e-10 * scale, "{dname} {ename}: <Ax,y> = {l} vs <x,A^T y> = {r}");
            }
            // adjoint_add adds, scaled.
            let y = random(op.rows(), &mut rng, 0.0, 1.0);
            let (mut once, mut twice) = (vec![[0.0; 3]; op.cols()], vec![[0.0; 3]; op.cols()]);
            op.adjoint_add(&y, 2.0, &mut once);
            op.adjoint_add(&y, 1.0, &mut twice);
            op.adjoint_add(&y, 1.0, &mut twice);
            for (a, b) in once.iter().zip(&twice) {
                for c in 0..3 {
                    assert!((a[c] - b[c]).abs() <= 1e-12 * (1.0 + a[c].abs()));
                }
            }
        }
    }
}

#[test]
fn the_forward_operator_is_the_perceived_image_simulation() {
    let mut rng = Lcg(3);
    let retina = Retina { resolution: 24, half_tangent: 0.25, samples_per_pixel: 1 };
    for (dname, display) in displays(200) {
        let mut image = RgbImage::new(200, 200);
        image.pixels.iter_mut().for_each(|p| *p = std::array::from_fn(|_| rng.next() as f32));
        let x: Vec<Rgb> = image.pixels.iter().map(|p| p.map(f64::from)).collect();
        for (ename, eye) in eyes(&retina, &display) {
            let op = EyeOperator::new(&display, &eye, &retina);
            let mut ax = vec![[0.0; 3]; op.rows()];
            op.forward(&x, &mut ax);
            let seen = simulate(&display, &eye, &retina, &[&image], &Progress::hidden()).unwrap().remove(0);
            for (a, s) in ax.iter().zip(&seen.pixels) {
                for c in 0..3 {
                    assert!((a[c] - f64::from(s[c])).abs() <= 1e-6, "{dname} {ename}: {a:?} vs {s:?}");
                }
            }
        }
    }
}

/// Cholesky solve of the symmetric positive definite `h` (n x n, row-major) with `b`.
fn cholesky_solve(h: &[f64], n: usize, b: &[f64]) -> Vec<f64> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = h[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                assert!(s > 0.0, "positive definite");
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i * n + k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i * n + i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k * n + i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i * n + i];
    }
    x
}

/// Dense projected Newton (Bertsekas 1982) for `min 1/2 x'Hx + b'x + c` over [0, 1]^n: Newton
/// steps on the free variables, an Armijo search along the projection arc.
fn projected_newton(h: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let f = |x: &[f64]| -> f64 {
        (0..n).map(|i| x[i] * (0.5 * (0..n).map(|j| h[i * n + j] * x[j]).sum::<f64>() + b[i])).sum()
    };
    let grad =
        |x: &[f64]| -> Vec<f64> { (0..n).map(|i| (0..n).map(|j| h[i * n + j] * x[j]).sum::<f64>() + b[i]).collect() };
    let mut x = vec![0.5; n];
    for _ in 0..200 {
        let g = grad(&x);
        let pg: f64 = (0..n).map(|i| ((x[i] - g[i]).clamp(0.0, 1.0) - x[i]).powi(2)).sum::<f64>().sqrt();
        if pg < 1e-14 {
            break;
        }
        let eps = pg.min(1e-3);
        let free: Vec<usize> =
            (0..n).filter(|&i| !((x[i] <= eps && g[i] > 0.0) || (x[i] >= 1.0 - eps && g[i] < 0.0))).collect();
        let m = free.len();
        let mut hf = vec![0.0; m * m];
        for (a, &i) in free.iter().enumerate() {
            for (c, &j) in free.iter().enumerate() {
                hf[a * m + c] = h[i * n + j];
            }
        }
        let rhs: Vec<f64> = free.iter().map(|&i| -g[i]).collect();
        let p = if m > 0 { cholesky_solve(&hf, m, &rhs) } else { Vec::new() };
        let mut dir = g.iter().map(|v| -v).collect::<Vec<f64>>();
        for (a, &i) in free.iter().enumerate() {
            dir[i] = p[a];
        }
        let f0 = f(&x);
        let mut t = 1.0;
        loop {
            let xn: Vec<f64> = (0..n).map(|i| (x[i] + t * dir[i]).clamp(0.0, 1.0)).collect();
            let dec: f64 = (0..n).map(|i| g[i] * (x[i] - xn[i])).sum();
            if f(&xn) <= f0 - 1e-4 * dec || t < 1e-20 {
                x = xn;
                break;
            }
            t *= 0.5;
        }
    }
    x
}

#[test]
fn opt_reaches_the_dense_bound_constrained_optimum() {
    // A few lenslets over a 24 x 24 LCD, seen by a small retina.
    let mut display = Display::paper();
    display.lcd.size = DVec2::splat(3.6);
    display.lcd.resolution = [24, 24];
    let retina = Retina { resolution: 10, half_tangent: 0.1, samples_per_pixel: 1 };
    let mut moved = Eye::thin_lens(3.0, Focus::Millimetres(300.0), 3);
    moved.position = DVec3::new(0.4, 0.0, 0.0);
    let eyes = [Eye::pinhole(), moved, Eye::thin_lens(4.0, Focus::Millimetres(600.0), 4)];
    let weights = [1.0, 2.0, 0.5];
    let mut rng = Lcg(99);
    let m = display.lcd.pixel_count();
    // Targets partly out of reach (below 0, above 1): the bounds bind.
    let terms: Vec<Term<EyeOperator>> = eyes
        .iter()
        .zip(weights)
        .map(|(eye, weight)| {
            let operator = EyeOperator::new(&display, eye, &retina);
            let target = random(operator.rows(), &mut rng, -0.3, 1.3);
            Term { operator, target, weight }
        })
        .collect();
    let x0 = random(m, &mut rng, 0.0, 1.0);
    let lambda = 1e-3;
    let solutions: Vec<_> = [SolverMethod::Spg, SolverMethod::Fista, SolverMethod::Pcg]
        .into_iter()
        .map(|method| {
            let settings = SolverSettings { method, max_iterations: 20_000, tolerance: 1e-13, regularization: lambda };
            let sol = solve(&terms, &x0, &settings, &Progress::hidden());
            assert!(sol.x.iter().all(|v| v.iter().all(|c| (0.0..=1.0).contains(c))), "{method:?}: x* in [0, 1]");
            for w in sol.history.windows(2) {
                assert!(
                    w[1].objective <= w[0].objective,
                    "{method:?}: the objective increased: {:?} -> {:?}",
                    w[0],
                    w[1]
                );
            }
            (method, sol)
        })
        .collect();

    // The same problem as dense matrices, channel by channel: H = 2 (sum c_s A'A + mu I),
    // b = -2 (sum c_s A't + mu x0); f = 1/2 x'Hx + b'x + const.
    let rows = retina.resolution * retina.resolution;
    let mu = lambda / (3.0 * m as f64);
    let dense: Vec<Vec<f64>> = terms
        .iter()
        .map(|t| {
            let mut a = vec![0.0; rows * m];
            let mut e = vec![[0.0; 3]; m];
            let mut col = vec![[0.0; 3]; rows];
            for j in 0..m {
                e[j] = [1.0, 0.0, 0.0];
                t.operator.forward(&e, &mut col);
                e[j] = [0.0; 3];
                for i in 0..rows {
                    a[i * m + j] = col[i][0];
                }
            }
            a
        })
        .collect();
    let cs: Vec<f64> = terms.iter().map(|t| t.weight / (3.0 * rows as f64)).collect();
    let mut h = vec![0.0; m * m];
    for (a, c) in dense.iter().zip(&cs) {
        for i in 0..m {
            for j in 0..m {
                let s: f64 = (0..rows).map(|r| a[r * m + i] * a[r * m + j]).sum();
                h[i * m + j] += 2.0 * c * s;
            }
        }
    }
    for i in 0..m {
        h[i * m + i] += 2.0 * mu;
    }
    let objective = |x: &dyn Fn(usize, usize) -> f64| -> f64 {
        let mut f = 0.0;
        for ch in 0..3 {
            for ((a, c), t) in dense.iter().zip(&cs).zip(&terms) {
                for r in 0..rows {
                    let ax: f64 = (0..m).map(|j| a[r * m + j] * x(j, ch)).sum();
                    f += c * (ax - t.target[r][ch]).powi(2);
                }
            }
            f += mu * (0..m).map(|j| (x(j, ch) - x0[j][ch]).powi(2)).sum::<f64>();
        }
        f
    };
    let mut best = vec![[0.0; 3]; m];
    for ch in 0..3 {
        let mut b = vec![0.0; m];
        for ((a, c), t) in dense.iter().zip(&cs).zip(&terms) {
            for j in 0..m {
                b[j] -= 2.0 * c * (0..rows).map(|r| a[r * m + j] * t.target[r][ch]).sum::<f64>();
            }
        }
        for j in 0..m {
            b[j] -= 2.0 * mu * x0[j][ch];
        }
        for (j, v) in projected_newton(&h, &b, m).into_iter().enumerate() {
            best[j][ch] = v;
        }
    }
    let f_dense = objective(&|j, c| best[j][c]);
    assert!(f_dense > 1e-3, "the bounds bind: {f_dense}");
    for (method, sol) in &solutions {
        let f_opt = objective(&|j, c| sol.x[j][c]);
        let reported = sol.history.last().unwrap().objective;
        assert!((f_opt - f_dense).abs() <= 1e-6 * f_dense, "{method:?}: OPT {f_opt} vs dense {f_dense}");
        assert!((reported - f_opt).abs() <= 1e-9 * f_opt, "{method:?}: reported {reported} vs recomputed {f_opt}");
        println!(
            "{method:?}: {} iterations, {:?}, relative gap {:e}",
            sol.history.len() - 1,
            sol.stop,
            (f_opt - f_dense) / f_dense
        );
    }
    // The Jacobi diagonal is diag(A^T A) of the dense matrices.
    for (t, a) in terms.iter().zip(&dense) {
        let mut diag = vec![[0.5; 3]; m];
        t.operator.diagonal_add(2.0, &mut diag);
        for j in 0..m {
            let exact: f64 = (0..rows).map(|r| a[r * m + j] * a[r * m + j]).sum();
            for c in 0..3 {
                assert!((diag[j][c] - 0.5 - 2.0 * exact).abs() <= 1e-12, "diagonal {j}: {:?} vs {exact}", diag[j]);
            }
        }
        assert!(diag.iter().any(|d| d[0] > 0.5), "the diagonal sees the display");
    }
    // Many values sit on a bound.
    let bound = best.iter().flatten().filter(|v| **v == 0.0 || **v == 1.0).count();
    assert!(bound > 10, "{bound} values on a bound");
}

/// The Jacobi diagonal for schematic eyes (per-channel samples) and tilted lattices: each
/// column's `||A e_l||^2`, against forward applications of unit images.
#[test]
fn the_jacobi_diagonal_is_each_columns_squared_norm() {
    let retina = Retina { resolution: 6, half_tangent: 0.05, samples_per_pixel: 2 };
    for (dname, display) in displays(60) {
        for (ename, eye) in eyes(&retina, &display) {
            let op = EyeOperator::new(&display, &eye, &retina);
            let mut diag = vec![[0.0; 3]; op.cols()];
            op.diagonal_add(1.0, &mut diag);
            let mut e = vec![[0.0; 3]; op.cols()];
            let mut col = vec![[0.0; 3]; op.rows()];
            let mut seen = 0;
            for j in (0..op.cols()).filter(|j| diag[*j] != [0.0; 3] || j % 97 == 0) {
                e[j] = [1.0; 3];
                op.forward(&e, &mut col);
                e[j] = [0.0; 3];
                for c in 0..3 {
                    let exact: f64 = col.iter().map(|v| v[c] * v[c]).sum();
                    assert!(
                        (diag[j][c] - exact).abs() <= 1e-12 * (1.0 + exact),
                        "{dname} {ename} {j}: {:?} vs {exact}",
                        diag[j]
                    );
                }
                seen += 1;
            }
            assert!(diag.iter().any(|d| d[0] > 0.0), "{dname} {ename}: {seen} columns");
        }
    }
}

/// The paper's four eye states at a tiny scale: LA's image, then OPT from it with each solver.
/// On the training states (their own samples, where `A_s x` is the perceived image) OPT's PSNR
/// is at least LA's: LA's image is feasible and the optimisation starts from it; the objective
/// never increases and the image lies in [0, 1].
#[test]
fn on_its_training_states_opt_is_at_least_as_good_as_la() {
    let mut display = Display::paper();
    display.lcd.resolution = [216, 216];
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = FacingPlanes::new(&scene, &backend).unwrap();
    let render = DisplayRenderSettings::default();
    let la = Method::LensletAverage { grid: 3 };
    let retina = Retina { resolution: 40, half_tangent: 0.3, samples_per_pixel: 1 };
    let state = |name: &str, eye: Eye, weight| TrainingState {
        name: name.into(),
        retina: Retina { samples_per_pixel: if matches!(eye.aperture, Aperture::Pinhole) { 2 } else { 1 }, ..retina },
        eye,
        weight,
    };
    let four = vec![
        state("Pin", Eye::pinhole(), 1.0),
        state("Near", Eye::thin_lens(5.0, Focus::Millimetres(300.0), 4), 1.0),
        state("Cen", Eye::thin_lens(5.0, Focus::Millimetres(400.0), 4), 1.0),
        state("Far", Eye::thin_lens(5.0, Focus::Millimetres(600.0), 4), 1.0),
    ];
    let one = vec![state("Cen", Eye::thin_lens(5.0, Focus::Millimetres(400.0), 4), 1.0)];
    let la_image = render_display_image(&display, la, &render, &field, &Progress::hidden()).unwrap();
    for states in [one, four] {
        let truths: Vec<RgbImage> =
            states.iter().map(|s| ground_truth(&s.eye, &s.retina, &field, &Progress::hidden())).collect();
        let seen = |image: &RgbImage| -> Vec<(f64, f64)> {
            states
                .iter()
                .zip(&truths)
                .map(|(s, gt)| {
                    let p = simulate(&display, &s.eye, &s.retina, &[image], &Progress::hidden()).unwrap().remove(0);
                    let mse = p
                        .pixels
                        .iter()
                        .zip(&gt.pixels)
                        .map(|(a, b)| (0..3).map(|c| (f64::from(a[c]) - f64::from(b[c])).powi(2)).sum::<f64>())
                        .sum::<f64>()
                        / (3 * p.pixels.len()) as f64;
                    (psnr(&p, gt).unwrap().mean, mse)
                })
                .collect()
        };
        let before = seen(&la_image);
        for method in [SolverMethod::Spg, SolverMethod::Fista, SolverMethod::Pcg] {
            let opt = Optimization {
                states: states.clone(),
                initial: la,
                solver: SolverSettings { method, max_iterations: 25, tolerance: 0.0, regularization: 0.0 },
            };
            let mut image = RgbImage::new(216, 216);
            let report = render_optimal_into(&display, &render, &opt, &field, &Progress::hidden(), &mut image).unwrap();
            assert!(image.pixels.iter().flatten().all(|v| (0.0..=1.0).contains(v)), "{method:?}: image in [0, 1]");
            for w in report.iterations.windows(2) {
                assert!(w[1].objective <= w[0].objective, "{method:?}: {:?} -> {:?}", w[0], w[1]);
            }
            let (first, last) = (report.iterations[0].objective, report.iterations.last().unwrap().objective);
            assert!(last < 0.9 * first, "{method:?}: the objective falls ({first} -> {last})");
            let after = seen(&image);
            let sum = |v: &[(f64, f64)]| v.iter().map(|(_, m)| m).sum::<f64>();
            assert!(sum(&after) < sum(&before), "{method:?}: {after:?} vs LA {before:?}");
            for (s, (b, a)) in states.iter().zip(before.iter().zip(&after)) {
                assert!(a.0 >= b.0, "{method:?} {}: OPT {:.3} dB < LA {:.3} dB", s.name, a.0, b.0);
                println!("{} states, {method:?} {}: LA {:.3} dB, OPT {:.3} dB", states.len(), s.name, b.0, a.0);
            }
        }
    }
}
