//! Diffraction at the eye's pupil and at the lenslet apertures as one more sampled dimension of
//! the converged estimator (docs/OPTICS.md).
//!
//! Light through an aperture leaves it spread over directions by the aperture's Fraunhofer
//! pattern: the squared modulus of the Fourier transform of the aperture (Goodman, *Introduction
//! to Fourier Optics*, 3rd ed., Sec. 4.4 and 6.3: the incoherent point-spread function of an
//! aberration-free system is the Fraunhofer pattern of its pupil, and its optical transfer
//! function the normalised autocorrelation of the pupil). Drawing a ray's angular deviation from
//! that pattern and averaging over the draws convolves the geometric image with the pattern, so
//! the image's transfer function is the geometric one times the aperture's incoherent OTF,
//! exactly for the aberration-free case; this is the stochastic ray bending of Freniere, Gregory
//! and Hassler (*Edge diffraction in Monte Carlo ray tracing*, Proc. SPIE 3780, 1999), with the
//! deviation drawn from the aperture's exact Fraunhofer pattern instead of their Gaussian by the
//! distance to the nearest edge.
//!
//! - A disk of diameter D (the eye's entrance pupil): the Airy pattern. With `x = pi D theta /
//!   lambda`, the radial density is `2 J1(x)^2 / x` and its distribution the encircled energy
//!   `1 - J0(x)^2 - J1(x)^2` (Rayleigh; Born & Wolf, *Principles of Optics*, Sec. 8.5.2), inverted
//!   from a table (linear between nodes 0.005 apart; beyond x = 400 by its asymptote
//!   `1 - E = 2 / (pi x)`).
//! - A rectangle of sides a1, a2 (a square or rectangular lenslet cell): `sinc^2 x sinc^2` along
//!   its sides, each factor drawn by inverting `2 int_0^x sinc^2` (Simpson's rule on the same grid;
//!   beyond x = 400 by `1 - G = 1 / (pi^2 x)`), with `x = a theta / lambda`.
//! - Any other convex polygon (the hexagonal Voronoi cell of a hexagonal or oblique lattice): the
//!   pattern `|F(q)|^2` from the polygon's exact Fourier transform (a sum over its edges, by the
//!   divergence theorem), tabulated once on a polar grid in units of `lambda / sqrt(area)` out to
//!   radius 400 and drawn by its radial marginal and each ring's angular distribution (uniform
//!   within a bin). The pattern's mass beyond the grid (its ridges' tails, about 1/(pi^2 400) per
//!   ridge) is left out and the rest renormalised: [`PolygonPattern::captured`] says how much.
//!
//! Every draw maps uniform numbers monotonically (radius by the first, angle or sign by the
//! second), so the estimator's stratification carries over to the deviations.

use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};

use super::lattice::Lattice;

/// `[optics] diffraction`: which apertures diffract.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Diffraction {
    /// Rays only (the paper's model; the default, bit for bit today's numbers).
    #[default]
    None,
    /// The eye's pupil only (the ground truth and every perceived image alike).
    Pupil,
    /// The eye's pupil and the lenslet aperture each perceived ray passes through.
    Apertures,
}

impl Diffraction {
    /// True unless `None`.
    pub fn is_on(self) -> bool {
        self != Diffraction::None
    }
    /// True when the lenslet apertures diffract.
    pub fn lenslets(self) -> bool {
        self == Diffraction::Apertures
    }
    /// The file name.
    pub fn name(self) -> &'static str {
        match self {
            Diffraction::None => "none",
            Diffraction::Pupil => "pupil",
            Diffraction::Apertures => "apertures",
        }
    }
}

/// `[optics]` of an experiment or a resolution study.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OpticsSpec {
    /// "none" (the default), "pupil" or "apertures" (the pupil and the lenslets).
    pub diffraction: Diffraction,
}

/// Nodes of the inverse-CDF tables: x = i * STEP for i in 0..=NODES.
const STEP: f64 = 0.005;
const NODES: usize = 80_000;
/// The tables' last abscissa (400).
const X_MAX: f64 = STEP * NODES as f64;

/// A tabulated distribution function on [0, X_MAX] with a 1/x tail beyond (`1 - F = c / x`).
struct Table {
    cdf: Vec<f64>,
    tail: f64,
    /// `guide[j]`: the first node with `F > j / GUIDE` (j = 0..=GUIDE), so the node a `u` in
    /// `[j / GUIDE, (j + 1) / GUIDE)` looks for lies in `guide[j]..=guide[j + 1]`.
    guide: Vec<u32>,
}

/// Buckets of the inverse tables' guide (a power of two: `u * GUIDE` and `j / GUIDE` are exact).
const GUIDE: usize = 4096;

impl Table {
    /// The table of distribution values `cdf` (non-decreasing, from 0) with tail constant `tail`.
    fn new(cdf: Vec<f64>, tail: f64) -> Self {
        let guide = (0..=GUIDE)
            .map(|j| {
                let u = j as f64 / GUIDE as f64;
                cdf.partition_point(|&f| f <= u) as u32
            })
            .collect();
        Self { cdf, tail, guide }
    }

    /// The x with F(x) = u, u in [0, 1).
    #[inline]
    fn invert(&self, u: f64) -> f64 {
        self.invert_with(u, |u| {
            // The guide's bucket narrows the search; the same node as a search of the whole table.
            let j = (u * GUIDE as f64) as usize;
            let (lo, hi) = (self.guide[j] as usize, self.guide[j + 1] as usize);
            lo + self.cdf[lo..hi].partition_point(|&f| f <= u)
        })
    }

    /// Slow twin of [`Table::invert`]: the node found by a binary search of the whole table.
    #[cfg(test)]
    fn invert_searching_all(&self, u: f64) -> f64 {
        self.invert_with(u, |u| self.cdf.partition_point(|&f| f <= u))
    }

    /// The inversion, given how to find the first node with F > u (for u below the last node).
    #[inline(always)]
    fn invert_with(&self, u: f64, first_above: impl Fn(f64) -> usize) -> f64 {
        let last = self.cdf[NODES];
        if u >= last {
            // 1 - u = c / x beyond the table (joined at the last node's own 1 - F).
            let x = self.tail / (1.0 - u).max(f64::MIN_POSITIVE);
            return x.max(X_MAX);
        }
        // The first node with F > u (F is non-decreasing, F[0] = 0).
        let i = first_above(u).clamp(1, NODES);
        let (f0, f1) = (self.cdf[i - 1], self.cdf[i]);
        let t = if f1 > f0 { (u - f0) / (f1 - f0) } else { 0.0 };
        STEP * ((i - 1) as f64 + t)
    }
}

/// The Airy pattern's encircled energy, `1 - J0(x)^2 - J1(x)^2`.
pub fn airy_encircled(x: f64) -> f64 {
    let (j0, j1) = (libm::j0(x), libm::j1(x));
    1.0 - j0 * j0 - j1 * j1
}

fn airy_table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(|| {
        let mut cdf: Vec<f64> = (0..=NODES).map(|i| airy_encircled(STEP * i as f64)).collect();
        cdf[0] = 0.0;
        for i in 1..cdf.len() {
            cdf[i] = cdf[i].max(cdf[i - 1]);
        }
        let tail = (1.0 - cdf[NODES]) * X_MAX;
        Table::new(cdf, tail)
    })
}

/// `sin^2(pi x) / (pi x)^2`.
#[inline]
fn sinc2(x: f64) -> f64 {
    if x == 0.0 {
        return 1.0;
    }
    let s = (PI * x).sin() / (PI * x);
    s * s
}

fn sinc2_table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(|| {
        // G(x) = 2 int_0^x sinc^2 (the distribution of |X|), by Simpson's rule per interval.
        let mut cdf = Vec::with_capacity(NODES + 1);
        let mut g = 0.0;
        cdf.push(0.0);
        for i in 0..NODES {
            let (a, b) = (STEP * i as f64, STEP * (i + 1) as f64);
            g += 2.0 * (b - a) / 6.0 * (sinc2(a) + 4.0 * sinc2(0.5 * (a + b)) + sinc2(b));
            cdf.push(g.min(1.0));
        }
        let tail = (1.0 - cdf[NODES]) * X_MAX;
        Table::new(cdf, tail)
    })
}

/// The Airy radius `x = pi D theta / lambda` for the uniform number `u`.
#[inline]
pub fn airy_radius(u: f64) -> f64 {
    airy_table().invert(u)
}

/// A signed draw of density `sinc^2(x)` for the uniform number `u` (the sign from `u < 0.5`).
#[inline]
pub fn sinc2_draw(u: f64) -> f64 {
    let v = 2.0 * u - 1.0;
    let x = sinc2_table().invert(v.abs());
    if v < 0.0 {
        -x
    } else {
        x
    }
}

/// The angular deviation (radians, as a slope change) of a ray through a disk of diameter
/// `diameter` mm at `nm` nanometres, for the uniform pair `u`.
#[inline]
pub fn disk_deviation(u: [f64; 2], diameter: f64, nm: f64) -> DVec2 {
    if diameter <= 0.0 {
        return DVec2::ZERO;
    }
    disk_draw(u).disk(diameter, nm)
}

/// The Airy pattern's draw for the uniform pair `u`, before a diameter and a wavelength scale it
/// ([`ApertureDraw::disk`]).
#[inline]
pub fn disk_draw(u: [f64; 2]) -> ApertureDraw {
    let (s, c) = (TAU * u[1]).sin_cos();
    ApertureDraw([airy_radius(u[0]), c, s])
}

/// An aperture's deviation for one uniform pair before the wavelength scales it
/// ([`disk_draw`], [`ApertureShape::draw`]): the table inversions and the angle, computed once
/// per sample and shared by the colour channels, whose deviations are this draw scaled by each
/// channel's wavelength (the same arithmetic as drawing per channel, so the same bits).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ApertureDraw([f64; 3]);

impl ApertureDraw {
    /// The deviation through a disk of diameter `diameter` mm at `nm` (a draw of [`disk_draw`]).
    #[inline(always)]
    pub fn disk(self, diameter: f64, nm: f64) -> DVec2 {
        let [a, c, s] = self.0;
        let r = a * nm * 1e-6 / (PI * diameter);
        DVec2::new(r * c, r * s)
    }
}

/// A lenslet's aperture: the shape of one cell of its lattice.
#[derive(Clone, Debug)]
pub enum ApertureShape {
    /// A rectangle with unit side directions `axes` and side lengths `sides`, mm.
    Rectangle {
        /// The sides' unit directions.
        axes: [DVec2; 2],
        /// The sides' lengths, mm.
        sides: [f64; 2],
    },
    /// A disk of this diameter, mm.
    Disk(f64),
    /// A convex polygon (the hexagonal Voronoi cell), its pattern tabulated.
    Polygon(Box<PolygonPattern>),
}

impl ApertureShape {
    /// The Voronoi cell of `lattice` (its reduced basis): a rectangle when the reduced vectors are
    /// orthogonal, else the hexagon of the six nearest neighbours.
    pub fn of_lattice(lattice: &Lattice) -> Self {
        let m: DMat2 = lattice.reduced_matrix();
        let (b1, b2) = (m.x_axis, m.y_axis);
        if b1.dot(b2).abs() <= 1e-12 * b1.length() * b2.length() {
            return ApertureShape::Rectangle {
                axes: [b1.normalize(), b2.normalize()],
                sides: [b1.length(), b2.length()],
            };
        }
        ApertureShape::Polygon(Box::new(PolygonPattern::new(&voronoi_hexagon(b1, b2))))
    }

    /// The ray's angular deviation (slope change) for the uniform pair `u` at `nm` nanometres.
    #[inline]
    pub fn deviation(&self, u: [f64; 2], nm: f64) -> DVec2 {
        self.scaled(self.draw(u), nm)
    }

    /// The wavelength-free part of [`ApertureShape::deviation`] for the uniform pair `u` (the
    /// tables' inversions), to scale per channel with [`ApertureShape::scaled`].
    #[inline]
    pub fn draw(&self, u: [f64; 2]) -> ApertureDraw {
        match self {
            ApertureShape::Rectangle { .. } => ApertureDraw([sinc2_draw(u[0]), sinc2_draw(u[1]), 0.0]),
            ApertureShape::Disk(_) => disk_draw(u),
            ApertureShape::Polygon(p) => {
                let d = p.draw(u);
                ApertureDraw([d.x, d.y, 0.0])
            }
        }
    }

    /// The deviation at `nm` nanometres of the draw `d` ([`ApertureShape::draw`]).
    #[inline]
    pub fn scaled(&self, d: ApertureDraw, nm: f64) -> DVec2 {
        let lambda = nm * 1e-6;
        let [x, y, _] = d.0;
        match self {
            ApertureShape::Rectangle { axes, sides } => {
                axes[0] * (x * lambda / sides[0]) + axes[1] * (y * lambda / sides[1])
            }
            ApertureShape::Disk(diameter) => {
                if *diameter <= 0.0 {
                    DVec2::ZERO
                } else {
                    d.disk(*diameter, nm)
                }
            }
            ApertureShape::Polygon(p) => DVec2::new(x, y) * (lambda / p.scale),
        }
    }

    /// The diffraction angle lambda / w (radians) at `nm` of the aperture's width w: the side
    /// (the shorter of two), the diameter, or the polygon's flat-to-flat width.
    pub fn angle(&self, nm: f64) -> f64 {
        let w = match self {
            ApertureShape::Rectangle { sides, .. } => sides[0].min(sides[1]),
            ApertureShape::Disk(d) => *d,
            ApertureShape::Polygon(p) => p.width,
        };
        nm * 1e-6 / w
    }

    /// A short name: "square", "rectangle", "round" or "hexagonal".
    pub fn name(&self) -> &'static str {
        match self {
            ApertureShape::Rectangle { sides, .. } if (sides[0] - sides[1]).abs() <= 1e-12 * sides[0] => "square",
            ApertureShape::Rectangle { .. } => "rectangle",
            ApertureShape::Disk(_) => "round",
            ApertureShape::Polygon(_) => "hexagonal",
        }
    }
}

/// The Voronoi cell of the lattice with reduced basis (b1, b2), counter-clockwise vertices.
pub fn voronoi_hexagon(b1: DVec2, b2: DVec2) -> Vec<DVec2> {
    let b3 = if b1.dot(b2) > 0.0 { b1 - b2 } else { b1 + b2 };
    let mut n = [b1, b2, b3, -b1, -b2, -b3];
    n.sort_by(|a, b| a.y.atan2(a.x).total_cmp(&b.y.atan2(b.x)));
    // The vertex between neighbours a and b: x . a = |a|^2 / 2, x . b = |b|^2 / 2.
    (0..6)
        .map(|i| {
            let (a, b) = (n[i], n[(i + 1) % 6]);
            let m = DMat2::from_cols(DVec2::new(a.x, b.x), DVec2::new(a.y, b.y));
            m.inverse() * DVec2::new(0.5 * a.length_squared(), 0.5 * b.length_squared())
        })
        .collect()
}

/// The Fourier transform `int_A exp(-i q . x) dA` of the convex polygon `v` (counter-clockwise)
/// at `q != 0`, as (re, im): `(i / |q|^2) sum_e (q . n_e) L_e exp(-i q . m_e) sinc(q . (b - a) / 2)`.
pub fn polygon_transform(v: &[DVec2], q: DVec2) -> (f64, f64) {
    let q2 = q.length_squared();
    let (mut re, mut im) = (0.0, 0.0);
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        let e = b - a;
        // Outward normal times length for a counter-clockwise polygon.
        let nl = DVec2::new(e.y, -e.x);
        let m = 0.5 * (a + b);
        let h = 0.5 * q.dot(e);
        let s = if h == 0.0 { 1.0 } else { h.sin() / h };
        let k = q.dot(nl) * s;
        let (sn, cs) = q.dot(m).sin_cos();
        // k exp(-i phi) = k (cos - i sin)
        re += k * cs;
        im -= k * sn;
    }
    // times i / |q|^2: (re + i im) i = -im + i re
    (-im / q2, re / q2)
}

/// The area of the polygon `v` (counter-clockwise), mm^2.
pub fn polygon_area(v: &[DVec2]) -> f64 {
    0.5 * (0..v.len()).map(|i| v[i].perp_dot(v[(i + 1) % v.len()])).sum::<f64>()
}

/// The Fraunhofer pattern of a convex polygon on a polar grid, in units of `lambda / scale`
/// (`scale = sqrt(area)`).
#[derive(Clone, Debug)]
pub struct PolygonPattern {
    /// sqrt(area), mm.
    pub scale: f64,
    /// The flat-to-flat width (twice the smallest distance from the centre to an edge), mm.
    pub width: f64,
    /// Radial bin edges.
    radii: Vec<f64>,
    /// The radial marginal's distribution at each edge (0 first, 1 last).
    radial: Vec<f64>,
    /// Per radial bin, the angular distribution at the ANGLES + 1 bin edges.
    angular: Vec<f32>,
    /// The pattern's mass on the grid (the rest, beyond its radius, is left out).
    captured: f64,
}

const ANGLES: usize = 360;

impl PolygonPattern {
    /// The pattern of the polygon `v` (counter-clockwise, centred on the origin).
    pub fn new(v: &[DVec2]) -> Self {
        let area = polygon_area(v).abs();
        let scale = area.sqrt();
        let unit: Vec<DVec2> = v.iter().map(|p| *p / scale).collect();
        let width = 2.0
            * (0..v.len())
                .map(|i| {
                    let (a, b) = (v[i], v[(i + 1) % v.len()]);
                    (a.perp_dot(b) / (b - a).length()).abs()
                })
                .fold(f64::INFINITY, f64::min);
        // Radial edges: 0.02 apart to 12, then growing by 2% to 400.
        let mut radii = vec![0.0];
        let mut r: f64 = 0.0;
        while r < X_MAX {
            r = if r < 12.0 { r + 0.02 } else { r * 1.02 };
            radii.push(r.min(X_MAX));
        }
        let dphi = TAU / ANGLES as f64;
        let mut radial = vec![0.0];
        let mut angular = Vec::with_capacity((radii.len() - 1) * (ANGLES + 1));
        let mut total = 0.0;
        for w in radii.windows(2) {
            let (r0, r1) = (w[0], w[1]);
            let rm = 0.5 * (r0 + r1);
            // The area of the annulus' bin over dphi.
            let da = 0.5 * (r1 * r1 - r0 * r0) * dphi;
            let mut ring = 0.0;
            angular.push(0.0f32);
            let mut acc = Vec::with_capacity(ANGLES);
            for j in 0..ANGLES {
                let phi = (j as f64 + 0.5) * dphi;
                // theta in units of lambda / scale; q = 2 pi theta / lambda in the unit polygon.
                let q = DVec2::new(phi.cos(), phi.sin()) * (TAU * rm);
                let (re, im) = polygon_transform(&unit, q);
                ring += (re * re + im * im) * da;
                acc.push(ring);
            }
            for a in acc {
                angular.push(if ring > 0.0 { (a / ring) as f32 } else { 0.0 });
            }
            total += ring;
            radial.push(total);
        }
        // |F|^2 of the unit-area polygon integrates to 1 over theta (Parseval).
        let captured = total;
        for r in radial.iter_mut() {
            *r /= total;
        }
        Self { scale, width, radii, radial, angular, captured }
    }

    /// The pattern's mass the grid holds (the draws are renormalised to it).
    pub fn captured(&self) -> f64 {
        self.captured
    }

    /// A draw (units of lambda / scale) for the uniform pair `u`.
    #[inline]
    pub fn draw(&self, u: [f64; 2]) -> DVec2 {
        let bins = self.radii.len() - 1;
        let i = self.radial.partition_point(|&f| f <= u[0]).clamp(1, bins) - 1;
        let (f0, f1) = (self.radial[i], self.radial[i + 1]);
        let t = if f1 > f0 { ((u[0] - f0) / (f1 - f0)).clamp(0.0, 1.0) } else { 0.5 };
        let (r0, r1) = (self.radii[i], self.radii[i + 1]);
        // Uniform in area within the bin.
        let r = (r0 * r0 + t * (r1 * r1 - r0 * r0)).sqrt();
        let ring = &self.angular[i * (ANGLES + 1)..(i + 1) * (ANGLES + 1)];
        let v = u[1] as f32;
        let j = ring.partition_point(|&f| f <= v).clamp(1, ANGLES) - 1;
        let (a0, a1) = (f64::from(ring[j]), f64::from(ring[j + 1]));
        let s = if a1 > a0 { ((u[1] - a0) / (a1 - a0)).clamp(0.0, 1.0) } else { 0.5 };
        let phi = (j as f64 + s) * TAU / ANGLES as f64;
        let (sn, cs) = phi.sin_cos();
        DVec2::new(r * cs, r * sn)
    }
}

/// The incoherent MTF of a disk at normalised frequency `s = nu / (D / lambda)`:
/// `(2 / pi) (acos s - s sqrt(1 - s^2))` (Goodman, eq. 6-31).
pub fn disk_mtf(s: f64) -> f64 {
    if s >= 1.0 {
        return 0.0;
    }
    2.0 / PI * (s.acos() - s * (1.0 - s * s).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_invert_their_distributions() {
        for u in [0.01, 0.2, 0.5, 0.838, 0.9, 0.99, 0.998] {
            let x = airy_radius(u);
            assert!((airy_encircled(x) - u).abs() < 1e-6, "{u}: {x}");
        }
        // 83.8% of the Airy energy inside the first dark ring (x = 3.8317).
        assert!((airy_encircled(3.831_705_970_207_512) - 0.838).abs() < 1e-3);
        // Symmetric sinc^2 draws: u and 1 - u give opposite signs.
        assert!((sinc2_draw(0.2) + sinc2_draw(0.8)).abs() < 1e-9);
        assert_eq!(sinc2_draw(0.5), 0.0);
    }

    #[test]
    fn the_guided_inversion_finds_the_node_a_search_of_the_whole_table_finds() {
        // Every guide bucket's ends and their neighbours, the tables' own nodes (ties: the first
        // node with F > u), the tail's start, and many 24- and 53-bit uniforms.
        let mut us: Vec<f64> = Vec::new();
        for j in 0..=GUIDE {
            let u = j as f64 / GUIDE as f64;
            us.extend([u, u.next_up(), u.next_down()]);
        }
        for t in [airy_table(), sinc2_table()] {
            us.extend(t.cdf.iter().step_by(7).flat_map(|&f| [f, f.next_up(), f.next_down()]));
            us.extend([t.cdf[NODES], t.cdf[NODES].next_down()]);
        }
        let mut h = 5u64;
        for _ in 0..200_000 {
            h = crate::measure::sampler::mix64(h);
            us.push((h >> 11) as f64 / (1u64 << 53) as f64);
            us.push((h & 0xff_ffff) as f64 / 16_777_216.0);
        }
        for t in [airy_table(), sinc2_table()] {
            for &u in us.iter().filter(|u| (0.0..1.0).contains(*u)) {
                assert_eq!(t.invert(u).to_bits(), t.invert_searching_all(u).to_bits(), "{u}");
            }
        }
    }

    #[test]
    fn one_draw_scaled_per_channel_is_the_per_channel_deviation_bit_for_bit() {
        let hex = ApertureShape::of_lattice(
            &Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(0.5, 0.75f64.sqrt())))
                .unwrap(),
        );
        let shapes = [
            ApertureShape::of_lattice(&Lattice::square(1.2).unwrap()),
            ApertureShape::Rectangle { axes: [DVec2::new(0.6, 0.8), DVec2::new(-0.8, 0.6)], sides: [1.1, 0.7] },
            ApertureShape::Disk(5.0),
            ApertureShape::Disk(0.0),
            hex,
        ];
        let mut h = 9u64;
        for _ in 0..2000 {
            h = crate::measure::sampler::mix64(h);
            let u = [(h >> 11) as f64 / (1u64 << 53) as f64, (h & 0xff_ffff) as f64 / 16_777_216.0];
            for shape in &shapes {
                let draw = shape.draw(u);
                for nm in [450.3, 535.0, 611.7] {
                    // Drawn for this channel alone, written out.
                    let lambda = nm * 1e-6;
                    let a = match shape {
                        ApertureShape::Rectangle { axes, sides } => {
                            axes[0] * (sinc2_draw(u[0]) * lambda / sides[0])
                                + axes[1] * (sinc2_draw(u[1]) * lambda / sides[1])
                        }
                        ApertureShape::Disk(d) if *d <= 0.0 => DVec2::ZERO,
                        ApertureShape::Disk(d) => {
                            let r = airy_radius(u[0]) * nm * 1e-6 / (PI * d);
                            let (s, c) = (TAU * u[1]).sin_cos();
                            DVec2::new(r * c, r * s)
                        }
                        ApertureShape::Polygon(p) => p.draw(u) * (lambda / p.scale),
                    };
                    let b = shape.scaled(draw, nm);
                    assert_eq!(a, shape.deviation(u, nm));
                    assert_eq!([a.x.to_bits(), a.y.to_bits()], [b.x.to_bits(), b.y.to_bits()], "{}", shape.name());
                }
            }
            for (d, nm) in [(5.0, 450.3), (2.0, 611.7)] {
                let (a, b) = (disk_deviation(u, d, nm), disk_draw(u).disk(d, nm));
                assert_eq!([a.x.to_bits(), a.y.to_bits()], [b.x.to_bits(), b.y.to_bits()]);
            }
        }
    }

    #[test]
    fn the_square_lattice_cell_is_a_square_and_the_hexagonal_one_a_regular_hexagon() {
        let sq = ApertureShape::of_lattice(&Lattice::square(1.2).unwrap());
        assert_eq!(sq.name(), "square");
        let p = 1.0;
        let hex =
            Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(p, 0.0), DVec2::new(0.5 * p, 0.75f64.sqrt() * p)))
                .unwrap();
        let v = voronoi_hexagon(hex.reduced_matrix().x_axis, hex.reduced_matrix().y_axis);
        // Area of the cell = the lattice's cell area; every vertex 1/sqrt(3) from the centre.
        assert!((polygon_area(&v) - hex.cell_area()).abs() < 1e-12, "{v:?}");
        for x in &v {
            assert!((x.length() - p / 3f64.sqrt()).abs() < 1e-12);
        }
    }

    #[test]
    fn the_polygon_transform_is_the_squares_sinc_product() {
        let v = [DVec2::new(-0.5, -0.5), DVec2::new(0.5, -0.5), DVec2::new(0.5, 0.5), DVec2::new(-0.5, 0.5)];
        for q in [DVec2::new(1.3, 0.0), DVec2::new(0.7, -2.1), DVec2::new(5.0, 3.0)] {
            let (re, im) = polygon_transform(&v, q);
            let s = |x: f64| if x == 0.0 { 1.0 } else { (x / 2.0).sin() / (x / 2.0) };
            assert!((re - s(q.x) * s(q.y)).abs() < 1e-12 && im.abs() < 1e-12, "{q}: {re} {im}");
        }
    }

    #[test]
    fn extreme_uniform_numbers_give_finite_deviations() {
        let hex = ApertureShape::of_lattice(
            &Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(0.5, 0.75f64.sqrt())))
                .unwrap(),
        );
        let shapes = [ApertureShape::of_lattice(&Lattice::square(1.2).unwrap()), ApertureShape::Disk(1.0), hex];
        let top = 1.0 - f64::EPSILON / 2.0;
        for shape in &shapes {
            for u in [[0.0, 0.0], [top, top], [0.0, top], [top, 0.5], [0.5, 0.5]] {
                let d = shape.deviation(u, 555.0);
                assert!(d.is_finite(), "{} {u:?}: {d}", shape.name());
            }
        }
        // The far tail: the table's asymptote, not a division by zero.
        assert!(airy_radius(top).is_finite() && airy_radius(top) > 1e10);
        assert!(sinc2_draw(top).is_finite() && sinc2_draw(0.0).is_finite());
        assert_eq!(disk_deviation([0.3, 0.3], 0.0, 555.0), DVec2::ZERO);
    }
}
