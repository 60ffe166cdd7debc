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
//! take that form; `f` and `g` are polynomials of total degree `DEGREE` in the scaled
//! invariants, so the map is an odd polynomial of degree `2 DEGREE + 1` in the ray coordinates
//! (paraxial optics and the third, fifth, ... eleventh orders of aberration). This is the idea of
//! polynomial optics in rendering (M. B. Hullin, J. Hanika, W. Heidrich, "Polynomial Optics",
//! Computer Graphics Forum 31(4), 2012). The fit is done at wavelength nodes equally spaced in
//! `1 / lambda^2` (in which the media's indices are nearly linear: Cauchy's formula) and
//! interpolated between them by cubic Lagrange interpolation on the four nearest nodes,
//! tabulated eight times finer so that an evaluation blends two table nodes linearly.
//!
//! Measured (Navarro 1985, 5 mm pupil, tangents up to 0.43, 380-780 nm): largest errors
//! 1.8e-7 mm in position and 4.2e-8 in slope; a retina pixel of the paper's experiment is
//! 1.2e-3 in tangent. The fit takes about 0.2 s per eye on two cores.
//!
//! The map covers tangents up to `max_tangent` and the whole pupil. It is built only when every
//! fit ray and a ring of rays a little outside the domain pass the eye (so no semi-diameter or
//! total internal reflection cuts the domain), and used only when its largest error against the
//! exact aim, over an independent check set at wavelengths between the nodes, is within
//! [`POSITION_TOLERANCE`] and [`SLOPE_TOLERANCE`]; otherwise every ray is aimed exactly.

use glam::DVec2;
use nalgebra::DMatrix;
use rayon::prelude::*;

use super::SchematicEye;
use crate::optics::PlaneRay;

/// Degree of `f` and `g` in the invariants.
const DEGREE: usize = 5;
/// Monomials of total degree <= DEGREE in three variables.
const TERMS: usize = (DEGREE + 1) * (DEGREE + 2) * (DEGREE + 3) / 6;
/// Wavelength nodes of the fit over a range (one for a single wavelength).
const NODES: usize = 51;
/// Nodes of the evaluated table per fit node interval: the table holds the fit's cubic
/// interpolant at `FINE` times the density, so that an evaluation blends two nodes linearly.
const FINE: usize = 8;
/// Fit points per axis (tangent, pupil radius, pupil angle).
const FIT_POINTS: usize = 2 * DEGREE + 5;
/// Check points, at wavelengths between the nodes.
const CHECK_POINTS: usize = 4000;
/// Largest accepted difference from the exact aim of the ray's position at z = 0, mm.
pub const POSITION_TOLERANCE: f64 = 1e-6;
/// Largest accepted difference from the exact aim of the ray's slope (tangent).
pub const SLOPE_TOLERANCE: f64 = 1e-7;

/// One wavelength node: `[f_position, g_position, f_slope, g_slope]`.
type Node = [[f64; TERMS]; 4];

/// The fitted map (see the module documentation).
#[derive(Clone, Debug)]
pub struct RayMap {
    tau_max: f64,
    /// Scale of pupil points (the pupil radius, or 1 for a pinhole).
    radius: f64,
    /// `1 / lambda^2` (1/um^2) of node 0 and the nodes' spacing in it.
    x0: f64,
    dx: f64,
    nodes: Vec<Node>,
    /// The largest errors on the check set: position at z = 0 (mm) and slope.
    pub check_error: (f64, f64),
}

/// The monomials `a^i b^j c^k` (i + j + k <= DEGREE) in a fixed order.
#[inline(always)]
fn monomials(a: f64, b: f64, c: f64) -> [f64; TERMS] {
    let mut m = [0.0; TERMS];
    let mut pa = [1.0; DEGREE + 1];
    let mut pb = [1.0; DEGREE + 1];
    let mut pc = [1.0; DEGREE + 1];
    for d in 1..=DEGREE {
        pa[d] = pa[d - 1] * a;
        pb[d] = pb[d - 1] * b;
        pc[d] = pc[d - 1] * c;
    }
    let mut n = 0;
    for (i, a) in pa.iter().enumerate() {
        for (j, b) in pb[..=DEGREE - i].iter().enumerate() {
            for c in &pc[..=DEGREE - i - j] {
                m[n] = a * b * c;
                n += 1;
            }
        }
    }
    m
}

#[inline(always)]
fn dot(a: &[f64; TERMS], b: &[f64; TERMS]) -> f64 {
    let mut s = [0.0; 4];
    for (x, y) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// The fit nodes' cubic Lagrange interpolant (on the four nodes nearest each cell; the end
/// cells use the four nodes nearest them) at `FINE` points per cell: a map is linear in its
/// coefficients, so this is the interpolant of the rays themselves.
fn refine(coarse: &[Node]) -> Vec<Node> {
    let last = coarse.len() - 1;
    let lagrange = |x: f64| -> (usize, [f64; 4]) {
        let j = (x as usize).clamp(1, last - 2) - 1;
        let w = x - j as f64; // nodes j..j+3 at 0, 1, 2, 3
        let l = [
            -(w - 1.0) * (w - 2.0) * (w - 3.0) / 6.0,
            w * (w - 2.0) * (w - 3.0) / 2.0,
            -w * (w - 1.0) * (w - 3.0) / 2.0,
            w * (w - 1.0) * (w - 2.0) / 6.0,
        ];
        (j, l)
    };
    (0..=last * FINE)
        .map(|i| {
            let (j, l) = lagrange(i as f64 / FINE as f64);
            let mut node = [[0.0; TERMS]; 4];
            for (d, ld) in l.iter().enumerate() {
                for (out, c) in node.iter_mut().zip(&coarse[j + d]) {
                    for (o, ck) in out.iter_mut().zip(c) {
                        *o += ld * ck;
                    }
                }
            }
            node
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

impl RayMap {
    /// The map of `eye` for tangents up to `max_tangent`, entrance-pupil points within `radius`
    /// mm (iris points `scale` times them) and wavelengths in `nm_range`, checked against the
    /// exact aim; None when the optics cut the domain or the fit misses the tolerances.
    pub fn fit(eye: &SchematicEye, max_tangent: f64, radius: f64, scale: f64, nm_range: (f64, f64)) -> Option<Self> {
        let (lo, hi) = nm_range;
        if !(max_tangent > 0.0 && max_tangent.is_finite() && radius >= 0.0 && lo > 0.0 && hi >= lo) {
            return None;
        }
        let count = if hi - lo < 1e-9 { 1 } else { NODES };
        let (x0, x1) = (inv2(hi), inv2(lo));
        let dx = if count > 1 { (x1 - x0) / (count - 1) as f64 } else { 1.0 };
        let unit = if radius > 0.0 { radius } else { 1.0 };
        let exact = |t: DVec2, p: DVec2, nm: f64| eye.ray_out(eye.retina_point(t), p * scale, nm);
        // Fit points: t = (tau, 0) and p over the half disk (the map's mirror symmetry); the
        // pinhole has p = 0 only.
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
        // One design matrix for every node (the same points): its pseudo-inverse once (SVD,
        // which also takes the pinhole's rank deficiency).
        let rows = 2 * points.len();
        let mut a = DMatrix::<f64>::zeros(rows, 2 * TERMS);
        for (i, &(tau, q)) in points.iter().enumerate() {
            let m = monomials(tau * tau, tau * q.x, q.length_squared());
            for (k, mk) in m.iter().enumerate() {
                a[(2 * i, k)] = mk * tau;
                a[(2 * i, TERMS + k)] = mk * q.x;
                a[(2 * i + 1, TERMS + k)] = mk * q.y;
            }
        }
        let pinv = a.svd(true, true).pseudo_inverse(1e-13).ok()?;
        let nodes: Option<Vec<Node>> = (0..count)
            .into_par_iter()
            .map(|j| {
                let nm = if count == 1 { lo } else { 1e3 / (x0 + j as f64 * dx).sqrt() };
                let at = eye.at(nm);
                let mut b = DMatrix::<f64>::zeros(rows, 2);
                for (i, &(tau, q)) in points.iter().enumerate() {
                    let t = DVec2::new(tau * max_tangent, 0.0);
                    let ray = at.ray_out(eye.retina_point(t), q * unit * scale)?;
                    b[(2 * i, 0)] = ray.position.x;
                    b[(2 * i + 1, 0)] = ray.position.y;
                    b[(2 * i, 1)] = ray.slope.x;
                    b[(2 * i + 1, 1)] = ray.slope.y;
                }
                let x = &pinv * b;
                let col = |c: usize, off: usize| -> [f64; TERMS] { std::array::from_fn(|k| x[(off + k, c)]) };
                Some([col(0, 0), col(0, TERMS), col(1, 0), col(1, TERMS)])
            })
            .collect();
        let coarse = nodes?;
        let (nodes, dx) = if count == 1 { (coarse, dx) } else { (refine(&coarse), dx / FINE as f64) };
        let mut map = RayMap { tau_max: max_tangent, radius: unit, x0, dx, nodes, check_error: (0.0, 0.0) };
        // A ring just outside the domain must pass at both ends of the range: nothing cuts it.
        for k in 0..64 {
            let e = DVec2::from_angle(std::f64::consts::TAU * k as f64 / 64.0);
            for nm in [lo, hi] {
                exact(e * max_tangent * 1.02, e * radius * 1.02, nm)?;
                exact(e * max_tangent * 1.02, -e * radius * 1.02, nm)?;
            }
        }
        // The check set: quasi-random points of the domain at wavelengths between the nodes.
        let worst = (0..CHECK_POINTS)
            .into_par_iter()
            .map(|i| {
                let u = r_sequence::<5>(i);
                let t = max_tangent * u[0].sqrt() * DVec2::from_angle(std::f64::consts::TAU * u[1]);
                let p = radius * u[2].sqrt() * DVec2::from_angle(std::f64::consts::TAU * u[3]);
                let nm = lo + (hi - lo) * u[4];
                let e = exact(t, p, nm)?;
                let [f] = map.eval(t, p, [nm]);
                Some(((e.position - f.position).length(), (e.slope - f.slope).length()))
            })
            .try_fold(|| (0.0f64, 0.0f64), |w, e| e.map(|e| (w.0.max(e.0), w.1.max(e.1))))
            .try_reduce(|| (0.0, 0.0), |a, b| Some((a.0.max(b.0), a.1.max(b.1))))?;
        map.check_error = worst;
        (worst.0 <= POSITION_TOLERANCE && worst.1 <= SLOPE_TOLERANCE).then_some(map)
    }

    /// The rays of tangent `t` and entrance-pupil point `p` at wavelengths `nm`, or None
    /// outside the map's field.
    #[inline]
    pub fn ray<const N: usize>(&self, t: DVec2, p: DVec2, nm: [f64; N]) -> Option<[PlaneRay; N]> {
        if t.length_squared() > self.tau_max * self.tau_max {
            return None;
        }
        Some(self.eval(t, p, nm))
    }

    #[inline]
    fn eval<const N: usize>(&self, t: DVec2, p: DVec2, nm: [f64; N]) -> [PlaneRay; N] {
        let ts = t / self.tau_max;
        let ps = p / self.radius;
        let m = monomials(ts.length_squared(), ts.dot(ps), ps.length_squared());
        let last = self.nodes.len() - 1;
        nm.map(|nm| {
            let mut v = [0.0; 4];
            if last == 0 {
                for (k, vk) in v.iter_mut().enumerate() {
                    *vk = dot(&self.nodes[0][k], &m);
                }
            } else {
                let x = ((inv2(nm) - self.x0) / self.dx).clamp(0.0, last as f64);
                let j = (x as usize).min(last - 1);
                let w = x - j as f64;
                let (a, b) = (&self.nodes[j], &self.nodes[j + 1]);
                for (k, vk) in v.iter_mut().enumerate() {
                    let va = dot(&a[k], &m);
                    *vk = va + w * (dot(&b[k], &m) - va);
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
