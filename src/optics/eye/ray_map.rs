//! The fitted ray map of a schematic eye: the object-space ray of (retina tangent, entrance-pupil
//! point, wavelength) as a polynomial, fitted by least squares to exact aimed rays
//! ([`super::EyeAtWavelength::ray_out`], its slow twin) and used by the measurement where it
//! agrees with them.
//!
//! The form is fixed by the eye's rotational symmetry. A map that commutes with rotations and
//! reflections about the axis, from two plane vectors (the tangent `t` and the pupil point `p`)
//! to a plane vector, is `f t + g p` with `f` and `g` functions of the three invariants
//! `|t|^2`, `t . p` and `|p|^2` (G. W. Schwarz, "Smooth functions invariant under the action of
//! a compact Lie group", Topology 14:63, 1975; for optics, the aberration expansion of H. H.
//! Hopkins, "Wave Theory of Aberrations", 1950, and W. T. Welford, "Aberrations of Optical
//! Systems", 1986, Ch. 7, is the same statement). Both the ray's position at z = 0 and its slope
//! take that form; `f` and `g` are polynomials of total degree 4 (or 5, `DEGREES`) in the scaled
//! invariants, so the map is an odd polynomial of degree 9 (or 11) in the ray coordinates
//! (paraxial optics and the third, fifth, ... ninth or eleventh orders of aberration). This is the idea of
//! polynomial optics in rendering (M. B. Hullin, J. Hanika, W. Heidrich, "Polynomial Optics",
//! Computer Graphics Forum 31(4), 2012). The fit is done at wavelength nodes at the Chebyshev
//! points of `1 / lambda^2` (in which the media's indices are nearly linear: Cauchy's formula),
//! and the coefficients are the nodes' interpolating Chebyshev series (L. N. Trefethen,
//! "Approximation Theory and Approximation Practice", SIAM 2013, Ch. 3-4), cut at the lowest
//! degree that meets the tolerances. An evaluation then forms each output's Chebyshev
//! coefficients at the ray's point once (one pass over the monomials) and each wavelength only
//! sums a short series: three channels cost little more than one.
//!
//! Measured (Navarro 1985, 5 mm pupil, tangents up to 0.43, 408-693 nm): degree 4, 6
//! Chebyshev terms (fewer for the higher degrees, 556 coefficients), largest errors 3.2e-6 mm in
//! position and 9.0e-7 in slope; a retina pixel of the paper's experiment is 1.2e-3 in tangent.
//!
//! The map covers tangents up to `max_tangent` and the whole pupil. It is built only when every
//! fit ray and a ring of rays a little outside the domain pass the eye (so no semi-diameter or
//! total internal reflection cuts the domain), and used only when its largest error against the
//! exact aim, over an independent check set at wavelengths between the nodes, is within
//! [`POSITION_TOLERANCE`] and [`SLOPE_TOLERANCE`]; otherwise every ray is aimed exactly.

use glam::DVec2;
use nalgebra::DMatrix;
use rayon::prelude::*;

use super::monomials::{monomials, monomials_into};
use super::SchematicEye;
use crate::optics::PlaneRay;

/// The highest degree of `f` and `g` in the invariants; a map takes the lowest of
/// `DEGREES` that meets the tolerances.
pub(super) const DEGREE: usize = 5;
/// The degrees a fit tries, lowest first.
const DEGREES: [usize; 2] = [4, DEGREE];
/// Monomials of total degree <= DEGREE in three variables.
pub(super) const TERMS: usize = terms(DEGREE);

/// Monomials of total degree <= `degree` in three variables (the first ones of `monomials::EXPONENTS`).
const fn terms(degree: usize) -> usize {
    (degree + 1) * (degree + 2) * (degree + 3) / 6
}
/// Wavelength nodes of the fit over a range (Chebyshev points in `1 / lambda^2`): the highest
/// degree in it the map may take is one less.
const NODES: usize = 17;
/// Fit points per axis (tangent, pupil radius, pupil angle).
const FIT_POINTS: usize = 2 * DEGREE + 5;
/// Check points, at wavelengths between the nodes.
const CHECK_POINTS: usize = 4000;
/// Largest accepted difference from the exact aim of the ray's position at z = 0, mm (the
/// pupil is millimetres wide; an LCD pixel of the paper's display 0.01 mm).
pub const POSITION_TOLERANCE: f64 = 1e-5;
/// Largest accepted difference from the exact aim of the ray's slope (tangent): a thousandth
/// of a retina pixel of the paper's experiment (1.2e-3); over the 26 mm to the paper's LCD,
/// with the position's, under 0.4% of an LCD pixel.
pub const SLOPE_TOLERANCE: f64 = 1e-6;

/// The four outputs of a fit: `[f_position, g_position, f_slope, g_slope]`.
type Node = [[f64; TERMS]; 4];

/// The fitted map (see the module documentation).
#[derive(Clone, Debug)]
pub struct RayMap {
    /// The degree of `f` and `g` (`DEGREES`): monomials of higher degree keep no terms.
    degree: usize,
    tau_max: f64,
    /// The wavelengths the map covers, nm (a wavelength outside is aimed exactly).
    nm_lo: f64,
    nm_hi: f64,
    /// Scale of pupil points (the pupil radius, or 1 for a pinhole).
    radius: f64,
    /// `1 / lambda^2` (1/um^2) at the range's middle and half its width (1 for one wavelength).
    x_mid: f64,
    x_half: f64,
    /// Chebyshev terms in the scaled `1 / lambda^2` (1 for one wavelength).
    degree1: usize,
    /// For each total degree g of the monomials, how many Chebyshev terms (from degree 0) it
    /// keeps: the chromatic change of the higher aberrations is small, so their series are
    /// cut sooner (non-increasing in g).
    kept: [usize; DEGREE + 1],
    /// Monomials in order of total degree; monomial `term` of total degree g has a row of
    /// `4 kept[g]` coefficients, `[d][k]` for Chebyshev degree d and output k, so a point's
    /// Chebyshev coefficients `y[4 d + k]` are one pass over the rows, shared by every
    /// wavelength.
    coef: Vec<f64>,
    /// The largest errors on the check set: position at z = 0 (mm) and slope.
    pub check_error: (f64, f64),
}

/// The Chebyshev polynomials `T_0 .. T_{n-1}` at `s` (in [-1, 1]).
#[inline(always)]
fn chebyshev<const MAX: usize>(s: f64, n: usize) -> [f64; MAX] {
    let mut t = [0.0; MAX];
    t[0] = 1.0;
    if n > 1 {
        t[1] = s;
    }
    for d in 2..n {
        t[d] = 2.0 * s * t[d - 1] - t[d - 2];
    }
    t
}

/// The fits at the Chebyshev nodes `cos(pi (j + 1/2) / n)` turned into the coefficients of
/// their interpolating Chebyshev series (the discrete cosine transform): a map is linear in its
/// coefficients, so this is the interpolant of the rays themselves.
fn chebyshev_series(nodes: &[Node]) -> Vec<Node> {
    let n = nodes.len();
    (0..n)
        .map(|d| {
            let mut c = [[0.0; TERMS]; 4];
            let scale = if d == 0 { 1.0 } else { 2.0 } / n as f64;
            for (j, node) in nodes.iter().enumerate() {
                let w = scale * (std::f64::consts::PI * d as f64 * (j as f64 + 0.5) / n as f64).cos();
                for (out, v) in c.iter_mut().zip(node) {
                    for (o, vk) in out.iter_mut().zip(v) {
                        *o += w * vk;
                    }
                }
            }
            c
        })
        .collect()
}

/// `1 / lambda^2`, 1/um^2.
#[inline(always)]
fn inv2(nm: f64) -> f64 {
    1e6 / (nm * nm)
}

/// Chebyshev points of [0, 1] (with both ends).
fn cheb01(n: usize) -> Vec<f64> {
    (0..n).map(|i| 0.5 - 0.5 * (std::f64::consts::PI * i as f64 / (n - 1) as f64).cos()).collect()
}

/// The i-th point of the additive recurrence with the generalised golden ratio of dimension
/// `D` (M. Roberts, "The unreasonable effectiveness of quasirandom sequences", 2018): a
/// low-discrepancy check set independent of the fit's grid.
fn r_sequence<const D: usize>(i: usize) -> [f64; D] {
    let mut g = 2.0f64;
    for _ in 0..30 {
        g = (1.0 + g).powf(1.0 / (D as f64 + 1.0));
    }
    let mut a = 1.0;
    std::array::from_fn(|_| {
        a /= g;
        (0.5 + a * i as f64).fract()
    })
}

/// A point of the check set: retina tangent, entrance-pupil point, wavelength (nm) and its exact ray.
type CheckRay = (DVec2, DVec2, f64, PlaneRay);

/// Whether errors (position, slope) are within [`POSITION_TOLERANCE`] and [`SLOPE_TOLERANCE`].
fn within(e: (f64, f64)) -> bool {
    e.0 <= POSITION_TOLERANCE && e.1 <= SLOPE_TOLERANCE
}

/// Chebyshev terms `n1` for every monomial up to `degree`, none above it (a map's `kept`).
fn up_to(degree: usize, n1: usize) -> [usize; DEGREE + 1] {
    std::array::from_fn(|g| if g <= degree { n1 } else { 0 })
}

/// The fit points `(tau, q)` in units of the domain (tangent `tau max_tangent` along x, pupil
/// point `q radius`): tau and the pupil radius at Chebyshev points, q over the half disk (the
/// map's mirror symmetry); the pinhole (`radius` 0) has q = 0 only.
fn fit_points(radius: f64) -> Vec<(f64, DVec2)> {
    let n = FIT_POINTS;
    let mut points = Vec::new();
    for tau in cheb01(n) {
        for (ri, s) in cheb01(n).into_iter().enumerate() {
            let angles = if ri == 0 || radius == 0.0 { 1 } else { n };
            for ai in 0..angles {
                let phi = std::f64::consts::PI * ai as f64 / (n - 1) as f64;
                points.push((tau, if radius > 0.0 { s * DVec2::from_angle(phi) } else { DVec2::ZERO }));
            }
            if radius == 0.0 {
                break;
            }
        }
    }
    points
}

/// The pseudo-inverse of the design matrix of `f t + g p` with `nt` monomials each, at the fit
/// points (two rows a point, x and y). One matrix serves every wavelength node (the same
/// points); the SVD also takes the pinhole's rank deficiency. None if the SVD fails.
fn design_pseudo_inverse(points: &[(f64, DVec2)], nt: usize) -> Option<DMatrix<f64>> {
    let rows = 2 * points.len();
    let mut a = DMatrix::<f64>::zeros(rows, 2 * nt);
    for (i, &(tau, q)) in points.iter().enumerate() {
        let m = monomials(tau * tau, tau * q.x, q.length_squared());
        for (k, mk) in m[..nt].iter().enumerate() {
            a[(2 * i, k)] = mk * tau;
            a[(2 * i, nt + k)] = mk * q.x;
            a[(2 * i + 1, nt + k)] = mk * q.y;
        }
    }
    a.svd(true, true).pseudo_inverse(1e-13).ok()
}

/// The least-squares fit at one wavelength `nm`: the exact rays of the fit points (tangent
/// `tau max_tangent`, iris point `q unit scale`) times the pseudo-inverse, as the node's four
/// outputs; None when a fit ray does not pass the eye.
fn fit_node(
    eye: &SchematicEye,
    points: &[(f64, DVec2)],
    pinv: &DMatrix<f64>,
    nt: usize,
    nm: f64,
    max_tangent: f64,
    (unit, scale): (f64, f64),
) -> Option<Node> {
    let at = eye.at(nm);
    let mut b = DMatrix::<f64>::zeros(2 * points.len(), 2);
    for (i, &(tau, q)) in points.iter().enumerate() {
        let t = DVec2::new(tau * max_tangent, 0.0);
        let ray = at.ray_out(eye.retina_point(t), q * unit * scale)?;
        b[(2 * i, 0)] = ray.position.x;
        b[(2 * i + 1, 0)] = ray.position.y;
        b[(2 * i, 1)] = ray.slope.x;
        b[(2 * i + 1, 1)] = ray.slope.y;
    }
    let x = pinv * b;
    // The monomials above the degree keep zero coefficients.
    let col =
        |c: usize, off: usize| -> [f64; TERMS] { std::array::from_fn(|k| if k < nt { x[(off + k, c)] } else { 0.0 }) };
    Some([col(0, 0), col(0, nt), col(1, 0), col(1, nt)])
}

/// Some when a ring just outside the domain (tangents and pupil points 2% beyond it) passes the
/// eye at both ends of the wavelength range: no semi-diameter or total internal reflection cuts
/// the domain.
fn domain_is_uncut(
    exact: &impl Fn(DVec2, DVec2, f64) -> Option<PlaneRay>,
    max_tangent: f64,
    radius: f64,
    (lo, hi): (f64, f64),
) -> Option<()> {
    for k in 0..64 {
        let e = DVec2::from_angle(std::f64::consts::TAU * k as f64 / 64.0);
        for nm in [lo, hi] {
            exact(e * max_tangent * 1.02, e * radius * 1.02, nm)?;
            exact(e * max_tangent * 1.02, -e * radius * 1.02, nm)?;
        }
    }
    Some(())
}

/// The check set: quasi-random points of the domain at wavelengths between the nodes, traced
/// exactly once (None if one does not pass the eye); the series is cut at the lowest degree
/// that meets the tolerances on it.
fn check_set(
    exact: &(impl Fn(DVec2, DVec2, f64) -> Option<PlaneRay> + Sync),
    max_tangent: f64,
    radius: f64,
    (lo, hi): (f64, f64),
) -> Option<Vec<CheckRay>> {
    (0..CHECK_POINTS)
        .into_par_iter()
        .map(|i| {
            let u = r_sequence::<5>(i);
            let t = max_tangent * u[0].sqrt() * DVec2::from_angle(std::f64::consts::TAU * u[1]);
            let p = radius * u[2].sqrt() * DVec2::from_angle(std::f64::consts::TAU * u[3]);
            let nm = lo + (hi - lo) * u[4];
            exact(t, p, nm).map(|e| (t, p, nm, e))
        })
        .collect()
}

impl RayMap {
    /// The map of `eye` for tangents up to `max_tangent`, entrance-pupil points within `radius`
    /// mm (iris points `scale` times them) and wavelengths in `nm_range`, checked against the
    /// exact aim; None when the optics cut the domain or the fit misses the tolerances. The
    /// lowest degree of `DEGREES` that meets them is taken (fewer coefficients per ray).
    pub fn fit(eye: &SchematicEye, max_tangent: f64, radius: f64, scale: f64, nm_range: (f64, f64)) -> Option<Self> {
        DEGREES.iter().find_map(|&degree| Self::fit_degree(eye, max_tangent, radius, scale, nm_range, degree))
    }

    /// [`Self::fit`] with `f` and `g` of total degree `degree` (at most [`DEGREE`]).
    fn fit_degree(
        eye: &SchematicEye,
        max_tangent: f64,
        radius: f64,
        scale: f64,
        nm_range: (f64, f64),
        degree: usize,
    ) -> Option<Self> {
        let (lo, hi) = nm_range;
        let nt = terms(degree);
        if !(max_tangent > 0.0 && max_tangent.is_finite() && radius >= 0.0 && lo > 0.0 && hi >= lo) {
            return None;
        }
        let count = if hi - lo < 1e-9 { 1 } else { NODES };
        let (x0, x1) = (inv2(hi), inv2(lo));
        let (x_mid, x_half) = if count > 1 { (0.5 * (x0 + x1), 0.5 * (x1 - x0)) } else { (x0, 1.0) };
        let unit = if radius > 0.0 { radius } else { 1.0 };
        let exact = |t: DVec2, p: DVec2, nm: f64| eye.ray_out(eye.retina_point(t), p * scale, nm);
        let points = fit_points(radius);
        let pinv = design_pseudo_inverse(&points, nt)?;
        // A fit at each wavelength node (Chebyshev points of `1 / lambda^2`), then their series.
        let nodes: Option<Vec<Node>> = (0..count)
            .into_par_iter()
            .map(|j| {
                let s = (std::f64::consts::PI * (j as f64 + 0.5) / count as f64).cos();
                let nm = if count == 1 { lo } else { 1e3 / (x_mid + x_half * s).sqrt() };
                fit_node(eye, &points, &pinv, nt, nm, max_tangent, (unit, scale))
            })
            .collect();
        let series = chebyshev_series(&nodes?);
        domain_is_uncut(&exact, max_tangent, radius, nm_range)?;
        let checks = check_set(&exact, max_tangent, radius, nm_range)?;
        let mut map = RayMap {
            degree,
            tau_max: max_tangent,
            nm_lo: lo,
            nm_hi: hi,
            radius: unit,
            x_mid,
            x_half,
            degree1: count,
            kept: up_to(degree, count),
            coef: Vec::new(),
            check_error: (0.0, 0.0),
        };
        map.pack(&series);
        if !within(map.check_errors(&checks)) {
            return None;
        }
        map.cut_series(&series, &checks);
        map.pack(&series);
        map.check_error = map.check_errors(&checks);
        within(map.check_error).then_some(map)
    }

    /// The largest errors of the map against the exact rays of the check set: position at z = 0
    /// (mm) and slope.
    fn check_errors(&self, checks: &[CheckRay]) -> (f64, f64) {
        checks
            .par_iter()
            .map(|&(t, p, nm, e)| {
                let [f] = self.eval(t, p, [nm]);
                ((e.position - f.position).length(), (e.slope - f.slope).length())
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)))
    }

    /// Cuts the full series (`degree1` terms, within the tolerances): the fewest Chebyshev
    /// terms for all monomials that stays within the tolerances on the check set, then, from
    /// the highest total degree down, the fewest for each degree (never more than the degree
    /// below keeps). Sets `degree1` and `kept`; `coef` is left packed for a trial.
    fn cut_series(&mut self, series: &[Node], checks: &[CheckRay]) {
        let (degree, count) = (self.degree, self.degree1);
        let mut best = count;
        for n1 in (1..count).rev() {
            self.kept = up_to(degree, n1);
            self.pack(series);
            if !within(self.check_errors(checks)) {
                break;
            }
            best = n1;
        }
        self.degree1 = best;
        self.kept = up_to(degree, best);
        for g in (1..=degree).rev() {
            let upper = if g < degree { self.kept[g + 1] } else { 0 };
            let full = self.kept[g];
            for keep in upper..full {
                let mut trial = self.kept;
                trial[g] = keep;
                self.kept = trial;
                self.pack(series);
                if within(self.check_errors(checks)) {
                    break;
                }
                self.kept[g] = full;
            }
        }
    }

    /// Lays out the series' coefficients for `kept` (see `coef`).
    fn pack(&mut self, series: &[Node]) {
        self.coef.clear();
        let mut term = 0;
        for g in 0..=DEGREE {
            for _ in 0..(g + 1) * (g + 2) / 2 {
                for series_d in &series[..self.kept[g]] {
                    for out in series_d {
                        self.coef.push(out[term]);
                    }
                }
                term += 1;
            }
        }
    }

    /// Adds `m[term] row[term]` over `m`'s monomials into `y` (`W` long), accumulated in
    /// registers (one fused multiply-add per coefficient).
    #[inline(always)]
    fn accumulate<const W: usize>(y: &mut [f64], m: &[f64], rows: &[f64]) {
        let mut acc: [f64; W] = std::array::from_fn(|i| y[i]);
        for (mk, row) in m.iter().zip(rows.chunks_exact(W)) {
            for (a, c) in acc.iter_mut().zip(row) {
                *a = mk.mul_add(*c, *a);
            }
        }
        y[..W].copy_from_slice(&acc);
    }

    /// [`Self::accumulate`] for `L` points in lockstep: each coefficient is loaded once for
    /// every point, and the points' sums are independent chains, so the fused multiply-adds
    /// overlap instead of waiting on one another. The columns go in passes of at most 16 (the
    /// accumulators of two points then fit in the registers); each output still sums its
    /// monomials in the same order from the same start, so every point's result is bit for
    /// bit [`Self::accumulate`]'s.
    #[inline(always)]
    fn accumulate_lanes<const W: usize, const L: usize>(y: &mut [[f64; 4 * NODES]; L], m: [&[f64]; L], rows: &[f64]) {
        let mut col = 0;
        while col + 16 <= W {
            Self::pass::<16, L>(y, m, rows, W, col);
            col += 16;
        }
        match W - col {
            0 => {}
            4 => Self::pass::<4, L>(y, m, rows, W, col),
            8 => Self::pass::<8, L>(y, m, rows, W, col),
            12 => Self::pass::<12, L>(y, m, rows, W, col),
            _ => unreachable!("rows are whole Chebyshev terms of four outputs"),
        }
    }

    /// Columns `col .. col + C` of rows `w` wide, for `L` points (see `Self::accumulate_lanes`).
    #[inline(always)]
    fn pass<const C: usize, const L: usize>(
        y: &mut [[f64; 4 * NODES]; L],
        m: [&[f64]; L],
        rows: &[f64],
        w: usize,
        col: usize,
    ) {
        let mut acc: [[f64; C]; L] = std::array::from_fn(|l| std::array::from_fn(|i| y[l][col + i]));
        for (j, row) in rows.chunks_exact(w).enumerate() {
            let c: &[f64; C] = row[col..col + C].try_into().expect("C columns");
            for (a, ml) in acc.iter_mut().zip(&m) {
                let mk = ml[j];
                for (ai, ci) in a.iter_mut().zip(c) {
                    *ai = mk.mul_add(*ci, *ai);
                }
            }
        }
        for (yl, a) in y.iter_mut().zip(&acc) {
            yl[col..col + C].copy_from_slice(a);
        }
    }

    /// True when tangent `t` and every wavelength of `nm` are in the map's domain.
    #[inline(always)]
    fn covers(&self, t: DVec2, nm: &[f64]) -> bool {
        t.length_squared() <= self.tau_max * self.tau_max && nm.iter().all(|&w| w >= self.nm_lo && w <= self.nm_hi)
    }

    /// The degree of the map's `f` and `g` in the invariants (4 or 5).
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The map's coefficients: what one evaluation multiplies and adds.
    pub fn coefficients(&self) -> usize {
        self.coef.len()
    }

    /// Chebyshev terms in wavelength the map uses (1 for a single wavelength).
    pub fn wavelength_terms(&self) -> usize {
        self.degree1
    }

    /// The rays of tangent `t` and entrance-pupil point `p` at wavelengths `nm`, or None
    /// outside the map's field.
    #[inline]
    pub fn ray<const N: usize>(&self, t: DVec2, p: DVec2, nm: [f64; N]) -> Option<[PlaneRay; N]> {
        if !self.covers(t, &nm) {
            return None;
        }
        Some(self.eval(t, p, nm))
    }

    /// [`Self::ray`] for `L` samples at once, bit for bit the same rays (the coefficients are
    /// shared in lockstep, `Self::accumulate_lanes`); None for a sample outside the map's
    /// field.
    #[inline]
    pub fn rays<const L: usize, const N: usize>(
        &self,
        t: [DVec2; L],
        p: [DVec2; L],
        nm: [[f64; N]; L],
    ) -> [Option<[PlaneRay; N]>; L] {
        let inside: [bool; L] = std::array::from_fn(|l| self.covers(t[l], &nm[l]));
        if inside.iter().all(|&i| i) {
            return self.eval_lanes(t, p, nm).map(Some);
        }
        std::array::from_fn(|l| inside[l].then(|| self.eval(t[l], p[l], nm[l])))
    }

    /// The slow twin of the lockstep evaluation is [`Self::eval`], one sample at a time.
    #[inline]
    fn eval_lanes<const L: usize, const N: usize>(
        &self,
        t: [DVec2; L],
        p: [DVec2; L],
        nm: [[f64; N]; L],
    ) -> [[PlaneRay; N]; L] {
        const MAX: usize = NODES;
        let ts = t.map(|t| t / self.tau_max);
        let ps = p.map(|p| p / self.radius);
        let mut m = [[0.0; TERMS]; L];
        for ((ml, t), p) in m.iter_mut().zip(&ts).zip(&ps) {
            monomials_into(ml, t.length_squared(), t.dot(*p), p.length_squared());
        }
        let mut y = [[0.0; 4 * MAX]; L];
        let (mut term, mut offset) = (0, 0);
        for (g, &keep) in self.kept.iter().enumerate() {
            let count = (g + 1) * (g + 2) / 2;
            let ms: [&[f64]; L] = std::array::from_fn(|l| &m[l][term..term + count]);
            let rows = &self.coef[offset..offset + 4 * keep * count];
            macro_rules! widths {
                ($($n:literal)*) => {
                    match keep {
                        0 => {}
                        $($n => Self::accumulate_lanes::<{ 4 * $n }, L>(&mut y, ms, rows),)*
                        _ => unreachable!("at most NODES Chebyshev terms"),
                    }
                };
            }
            widths!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
            term += count;
            offset += 4 * keep * count;
        }
        self.sum_series(&y, ts, ps, nm)
    }

    /// Each sample's and wavelength's ray from the samples' Chebyshev coefficients
    /// `y[l][4 d + k]`: the operations of [`Self::eval`]'s series, for every (sample,
    /// wavelength) in one loop over the degree, so the recurrences and sums of all of them are
    /// independent chains that overlap (bit for bit the same numbers).
    #[inline(always)]
    fn sum_series<const L: usize, const N: usize>(
        &self,
        y: &[[f64; 4 * NODES]; L],
        ts: [DVec2; L],
        ps: [DVec2; L],
        nm: [[f64; N]; L],
    ) -> [[PlaneRay; N]; L] {
        let n1 = self.degree1;
        let mut s = [[0.0; N]; L];
        for (sl, nl) in s.iter_mut().zip(&nm) {
            for (sw, &w) in sl.iter_mut().zip(nl) {
                *sw = ((inv2(w) - self.x_mid) / self.x_half).clamp(-1.0, 1.0);
            }
        }
        // T_{d-2}, T_{d-1} and the sums, as `chebyshev` and `eval` form them.
        let (mut t0, mut t1) = ([[1.0; N]; L], s);
        let mut v = [[[0.0; 4]; N]; L];
        for d in 0..n1 {
            let lanes = v.iter_mut().zip(y).zip(&s).zip(t0.iter_mut()).zip(t1.iter_mut());
            for ((((vl, yl), sl), t0l), t1l) in lanes {
                let yd: &[f64; 4] = yl[4 * d..4 * d + 4].try_into().expect("four outputs");
                for (((vw, &sw), t0w), t1w) in vl.iter_mut().zip(sl).zip(t0l.iter_mut()).zip(t1l.iter_mut()) {
                    let td = match d {
                        0 => 1.0,
                        1 => sw,
                        _ => {
                            let t = 2.0 * sw * *t1w - *t0w;
                            *t0w = *t1w;
                            *t1w = t;
                            t
                        }
                    };
                    for (vk, yk) in vw.iter_mut().zip(yd) {
                        *vk = yk.mul_add(td, *vk);
                    }
                }
            }
        }
        let mut out = [[PlaneRay { position: DVec2::ZERO, slope: DVec2::ZERO }; N]; L];
        for (((ol, vl), t), p) in out.iter_mut().zip(&v).zip(ts).zip(ps) {
            for (o, v) in ol.iter_mut().zip(vl) {
                *o = PlaneRay { position: t * v[0] + p * v[1], slope: t * v[2] + p * v[3] };
            }
        }
        out
    }

    #[inline]
    fn eval<const N: usize>(&self, t: DVec2, p: DVec2, nm: [f64; N]) -> [PlaneRay; N] {
        const MAX: usize = NODES;
        let ts = t / self.tau_max;
        let ps = p / self.radius;
        let mut m = [0.0; TERMS];
        monomials_into(&mut m, ts.length_squared(), ts.dot(ps), ps.length_squared());
        // The four outputs' Chebyshev coefficients at this point, once for every wavelength:
        // `y[4 d + k]`, each total degree of monomials adding into its kept terms.
        let n1 = self.degree1;
        let mut y = [0.0; 4 * MAX];
        let (mut term, mut offset) = (0, 0);
        for (g, &keep) in self.kept.iter().enumerate() {
            let count = (g + 1) * (g + 2) / 2;
            let (ms, rows) = (&m[term..term + count], &self.coef[offset..offset + 4 * keep * count]);
            macro_rules! widths {
                ($($n:literal)*) => {
                    match keep {
                        0 => {}
                        $($n => Self::accumulate::<{ 4 * $n }>(&mut y, ms, rows),)*
                        _ => unreachable!("at most NODES Chebyshev terms"),
                    }
                };
            }
            widths!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
            term += count;
            offset += 4 * keep * count;
        }
        nm.map(|nm| {
            let s = ((inv2(nm) - self.x_mid) / self.x_half).clamp(-1.0, 1.0);
            let tc = chebyshev::<MAX>(s, n1);
            let mut v = [0.0; 4];
            for (d, td) in tc[..n1].iter().enumerate() {
                for (k, vk) in v.iter_mut().enumerate() {
                    *vk = y[4 * d + k].mul_add(*td, *vk);
                }
            }
            PlaneRay { position: ts * v[0] + ps * v[1], slope: ts * v[2] + ps * v[3] }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::eye::{EyeModel, FocusCriterion};

    #[test]
    fn the_fitted_map_agrees_with_the_exact_aim_off_its_fit_points() {
        // The slow twin: ray aiming, at points and wavelengths the fit never saw.
        let pupil = 5.0;
        let (eye, _) =
            SchematicEye::focused(&EyeModel::Navarro1985, 2.5, 555.0, FocusCriterion::Paraxial, pupil, "t", "f")
                .unwrap();
        let scale = eye.iris_diameter(pupil) / pupil;
        let map = RayMap::fit(&eye, 0.43, 0.5 * pupil, scale, (380.0, 780.0)).expect("the map is within tolerance");
        for i in 0..300 {
            let u = r_sequence::<3>(7919 + i);
            let t = DVec2::new(0.3 * (2.0 * u[0] - 1.0), 0.3 * (2.0 * u[1] - 1.0));
            let p = 2.5 * (u[2]).sqrt() * DVec2::from_angle(0.7 + i as f64);
            let nm = 400.0 + 0.9137 * i as f64;
            let exact = eye.ray_out(eye.retina_point(t), p * scale, nm).unwrap();
            let [fit] = map.ray(t, p, [nm]).unwrap();
            assert!((exact.position - fit.position).length() < POSITION_TOLERANCE, "{t} {p} {nm}");
            assert!((exact.slope - fit.slope).length() < SLOPE_TOLERANCE, "{t} {p} {nm}");
        }
        // Outside its field it declines, and the caller aims exactly.
        assert!(map.ray(DVec2::new(0.5, 0.0), DVec2::ZERO, [555.0]).is_none());
    }
}
