//! Two-dimensional lattices of cells: lenslet centres and elemental-image centres
//! (paper Sec. 2.3, eq. (1): `x_c`, "the center of the lenslet that intercepts the ray").
//!
//! The centre of cell (i, j) is `shift + M (i, j)` with a 2x2 pitch matrix `M` (square,
//! rectangular, hexagonal or tilted layouts). A point belongs to the cell whose centre is
//! nearest (its Voronoi cell). Ties are broken deterministically: the candidate found by
//! rounding the lattice coordinates (`floor(u + 0.5)`) wins, so a point exactly half-way
//! between two centres of an axis-aligned lattice belongs to the cell with the larger index.
//!
//! The nearest-cell search looks at the rounded candidate's neighbours, which is right only
//! for a reduced basis (`2 |b1 . b2| <= min(|b1|^2, |b2|^2)`). A basis that is not reduced (e.g.
//! `[[1.2, 12], [0, 1.2]]`, a shear of the square lattice) is reduced by Lagrange-Gauss when the
//! lattice is made, and the search runs in the reduced basis; cell indices stay the user's (the
//! found cell is mapped back by the unimodular change of basis), since the lenslet and
//! elemental-image lattices share them. A basis that is already reduced is used untouched.

use glam::{DMat2, DVec2, IVec2};

/// A lattice of cell centres `shift + matrix * (i, j)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Centre of cell (0, 0), mm.
    pub shift: DVec2,
    /// Pitch matrix; its columns are the two lattice vectors (mm).
    pub matrix: DMat2,
    inverse: DMat2,
    axis_aligned: bool,
    /// For axis-aligned lattices: the pitch matrix's diagonal and its inverse's, so the hot
    /// paths skip the zero products (same values as the full products for finite input).
    diagonal: DVec2,
    inverse_diagonal: DVec2,
    /// The Lagrange-Gauss reduced basis of the same lattice (equal to `matrix` when that is
    /// reduced already) and its inverse.
    reduced: DMat2,
    reduced_inverse: DMat2,
    /// `matrix` is reduced: the search runs in it directly.
    given_is_reduced: bool,
    /// Columns of the unimodular integer matrix `U` with `reduced = matrix U`: a cell `k` of the
    /// reduced basis is cell `U k` of the user's.
    to_user: [[i64; 2]; 2],
}

impl Lattice {
    /// A lattice from its shift and pitch matrix. Returns `None` when the matrix is singular
    /// or not finite (callers turn that into an error naming the field).
    pub fn new(shift: DVec2, matrix: DMat2) -> Option<Self> {
        let det = matrix.determinant();
        let scale = matrix.x_axis.length() * matrix.y_axis.length();
        if !det.is_finite() || !shift.is_finite() || scale == 0.0 || det.abs() <= 1e-12 * scale {
            return None;
        }
        let axis_aligned = matrix.x_axis.y == 0.0 && matrix.y_axis.x == 0.0;
        let inverse = matrix.inverse();
        let given_is_reduced = is_reduced(matrix.x_axis, matrix.y_axis);
        let (reduced, to_user) = if given_is_reduced { (matrix, [[1, 0], [0, 1]]) } else { reduce(matrix)? };
        Some(Self {
            shift,
            matrix,
            inverse,
            axis_aligned,
            diagonal: DVec2::new(matrix.x_axis.x, matrix.y_axis.y),
            inverse_diagonal: DVec2::new(inverse.x_axis.x, inverse.y_axis.y),
            reduced,
            reduced_inverse: if given_is_reduced { inverse } else { reduced.inverse() },
            given_is_reduced,
            to_user,
        })
    }

    /// The reduced basis of the lattice (Lagrange-Gauss; the pitch matrix itself when that is
    /// reduced): its columns span the same centres with the shortest, most nearly orthogonal
    /// vectors, so its parallelogram is the shape of one cell.
    pub fn reduced_matrix(&self) -> DMat2 {
        self.reduced
    }

    /// A square lattice of the given pitch, centred on the optical axis.
    pub fn square(pitch: f64) -> Option<Self> {
        Self::new(DVec2::ZERO, DMat2::from_diagonal(DVec2::splat(pitch)))
    }

    /// A lattice from OpenCV's row-major 2x2 layout `[a, b, c, d]` meaning
    /// `centre = shift + [[a, b], [c, d]] (i, j)`.
    pub fn from_row_major(shift: DVec2, m: [f64; 4]) -> Option<Self> {
        Self::new(shift, DMat2::from_cols(DVec2::new(m[0], m[2]), DVec2::new(m[1], m[3])))
    }

    /// The pitch matrix in row-major order `[a, b, c, d]`.
    pub fn row_major(&self) -> [f64; 4] {
        [self.matrix.x_axis.x, self.matrix.y_axis.x, self.matrix.x_axis.y, self.matrix.y_axis.y]
    }

    /// True when the lattice vectors are along x and y (rectangular or square layouts).
    pub fn is_axis_aligned(&self) -> bool {
        self.axis_aligned
    }

    /// Centre of cell `index`.
    #[inline(always)]
    pub fn center(&self, index: IVec2) -> DVec2 {
        if self.axis_aligned {
            self.shift + self.diagonal * index.as_dvec2()
        } else {
            self.shift + self.matrix * index.as_dvec2()
        }
    }

    /// Continuous lattice coordinates of a point: `M^-1 (p - shift)`.
    #[inline(always)]
    pub fn coordinates(&self, p: DVec2) -> DVec2 {
        if self.axis_aligned {
            (p - self.shift) * self.inverse_diagonal
        } else {
            self.inverse * (p - self.shift)
        }
    }

    /// Area of one cell (mm^2).
    pub fn cell_area(&self) -> f64 {
        self.matrix.determinant().abs()
    }

    /// Index of the cell whose centre is nearest to `p`.
    ///
    /// Axis-aligned lattices: rounding the lattice coordinates is exact. Other lattices: the
    /// rounded candidate and its eight neighbours are compared (enough for a reduced basis,
    /// e.g. hexagonal (p, 0), (p/2, p sqrt(3)/2) or any rotation of a rectangular lattice).
    /// Distances are compared in lattice coordinates through the metric `M^T M`, so a point
    /// exactly half-way between two centres is an exact tie, which the rounded candidate wins.
    /// `nearest_brute_force` is the slow twin that tests check this against.
    #[inline(always)]
    pub fn nearest(&self, p: DVec2) -> IVec2 {
        if !self.given_is_reduced {
            return self.nearest_via_reduced(p);
        }
        let u = self.coordinates(p);
        let rounded = IVec2::new(round_half_up(u.x), round_half_up(u.y));
        if self.axis_aligned {
            return rounded;
        }
        self.nearest_around(u, rounded, 1)
    }

    /// [`Lattice::nearest`] then [`Lattice::center`] for many points, in place: each point
    /// becomes the centre of its cell. The layout is tested once per batch, so the axis-aligned
    /// loop has no branch and vectorises; the arithmetic is the single-point one (same bits).
    #[inline(always)]
    pub fn nearest_centers(&self, points: &mut [DVec2]) {
        if self.axis_aligned {
            for p in points {
                let u = (*p - self.shift) * self.inverse_diagonal;
                let index = DVec2::new(f64::from(round_half_up(u.x)), f64::from(round_half_up(u.y)));
                *p = self.shift + self.diagonal * index;
            }
        } else {
            for p in points {
                *p = self.center(self.nearest(*p));
            }
        }
    }

    /// For many points, in place: each point becomes the centre in `other` of the cell of this
    /// lattice nearest to it, `other.center(self.nearest(p))` (an LCD point's lenslet, found
    /// through its elemental image). Both layouts are tested once per batch, so the
    /// axis-aligned loop has no branch and vectorises; the arithmetic is the single-point one
    /// (same bits).
    #[inline(always)]
    pub fn nearest_centers_in(&self, other: &Lattice, points: &mut [DVec2]) {
        if self.axis_aligned && other.axis_aligned {
            for p in points {
                let u = (*p - self.shift) * self.inverse_diagonal;
                let index = DVec2::new(f64::from(round_half_up(u.x)), f64::from(round_half_up(u.y)));
                *p = other.shift + other.diagonal * index;
            }
        } else {
            for p in points {
                *p = other.center(self.nearest(*p));
            }
        }
    }

    /// Slow, obviously correct twin of [`Lattice::nearest`]: compares every cell within `radius`
    /// indices of the rounded coordinates, also for axis-aligned lattices.
    pub fn nearest_brute_force(&self, p: DVec2, radius: i32) -> IVec2 {
        let u = self.coordinates(p);
        let rounded = IVec2::new(round_half_up(u.x), round_half_up(u.y));
        self.nearest_around(u, rounded, radius)
    }

    /// [`Lattice::nearest`] for a pitch matrix that is not reduced: the search in the reduced
    /// basis, the cell mapped back to the user's indices (saturating, never overflowing).
    #[inline(never)]
    fn nearest_via_reduced(&self, p: DVec2) -> IVec2 {
        let u = self.reduced_inverse * (p - self.shift);
        let rounded = IVec2::new(round_half_up(u.x), round_half_up(u.y));
        let k = nearest_around(self.reduced, u, rounded, 1);
        let [c0, c1] = self.to_user;
        let (kx, ky) = (i64::from(k.x), i64::from(k.y));
        let to_i32 = |v: i64| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
        IVec2::new(to_i32(c0[0] * kx + c1[0] * ky), to_i32(c0[1] * kx + c1[1] * ky))
    }

    #[inline(always)]
    fn nearest_around(&self, u: DVec2, rounded: IVec2, radius: i32) -> IVec2 {
        nearest_around(self.matrix, u, rounded, radius)
    }
}

/// The candidate within `radius` of `rounded` with the smallest squared distance
/// `d^T (M^T M) d`, `d = u - candidate`; ties keep `rounded`, then the first found.
#[inline(always)]
fn nearest_around(matrix: DMat2, u: DVec2, rounded: IVec2, radius: i32) -> IVec2 {
    let dist2 = |cand: IVec2| (matrix * (u - cand.as_dvec2())).length_squared();
    let mut best = rounded;
    let mut best_d2 = dist2(rounded);
    for dj in -radius..=radius {
        for di in -radius..=radius {
            let cand = rounded + IVec2::new(di, dj);
            let d2 = dist2(cand);
            if d2 < best_d2 {
                best = cand;
                best_d2 = d2;
            }
        }
    }
    best
}

/// A basis is reduced when `2 |b1 . b2| <= min(|b1|^2, |b2|^2)` (within a relative 1e-9, so that
/// a hexagonal basis whose product rounds a hair above the half stays as given).
fn is_reduced(b1: DVec2, b2: DVec2) -> bool {
    2.0 * b1.dot(b2).abs() <= b1.length_squared().min(b2.length_squared()) * (1.0 + 1e-9)
}

/// Lagrange-Gauss reduction of the columns of `m`: the reduced basis `m U` and the columns of the
/// unimodular `U`. `None` for a basis so skewed that `U` would be absurd (entries beyond 2^20).
fn reduce(m: DMat2) -> Option<(DMat2, [[i64; 2]; 2])> {
    let at = |u: [i64; 2]| m * DVec2::new(u[0] as f64, u[1] as f64);
    let (mut u1, mut u2) = ([1i64, 0], [0i64, 1]);
    if at(u1).length_squared() > at(u2).length_squared() {
        std::mem::swap(&mut u1, &mut u2);
    }
    for _ in 0..200 {
        let (b1, b2) = (at(u1), at(u2));
        let mu = (b1.dot(b2) / b1.length_squared()).round();
        if !mu.is_finite() || mu.abs() > f64::from(1 << 20) {
            return None;
        }
        let mu = mu as i64;
        u2 = [u2[0] - mu * u1[0], u2[1] - mu * u1[1]];
        if u2.iter().chain(&u1).any(|v| v.abs() > 1 << 20) {
            return None;
        }
        if at(u2).length_squared() < at(u1).length_squared() {
            std::mem::swap(&mut u1, &mut u2);
        } else {
            break;
        }
    }
    Some((DMat2::from_cols(at(u1), at(u2)), [u1, u2]))
}

/// Nearest integer to `x`, halves rounding up, as an index; saturates for absurd inputs and
/// maps NaN to 0 (never panics). Written as `floor(x)` plus a test of the fractional part
/// (computed exactly) rather than `floor(x + 0.5)`, whose addition rounds 0.49999999999999994
/// up to 1.
#[inline(always)]
fn round_half_up(x: f64) -> i32 {
    let f = x.floor();
    floor_to_i32(f).saturating_add((x - f >= 0.5) as i32)
}

/// `floor(x)` as an `i32`; `as` saturates and maps NaN to 0. (With x86-64-v3, set in
/// `.cargo/config.toml`, `floor` is one `roundsd` instruction.)
#[inline(always)]
pub fn floor_to_i32(x: f64) -> i32 {
    x.floor() as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hexagonal(p: f64) -> Lattice {
        Lattice::new(
            DVec2::new(0.1, -0.2),
            DMat2::from_cols(DVec2::new(p, 0.0), DVec2::new(p / 2.0, p * 3f64.sqrt() / 2.0)),
        )
        .unwrap()
    }

    fn tilted(p: f64, angle: f64) -> Lattice {
        let r = DMat2::from_angle(angle);
        Lattice::new(DVec2::new(-0.3, 0.05), r * DMat2::from_diagonal(DVec2::new(p, 1.3 * p))).unwrap()
    }

    /// Deterministic pseudo-random points (no external RNG needed for a unit test).
    fn points(n: usize, half: f64) -> Vec<DVec2> {
        let mut s = 0x9E3779B97F4A7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| DVec2::new((next() * 2.0 - 1.0) * half, (next() * 2.0 - 1.0) * half)).collect()
    }

    #[test]
    fn fast_nearest_agrees_with_brute_force_on_square_hex_and_tilted() {
        for lat in [Lattice::square(1.2).unwrap(), hexagonal(1.2), tilted(1.0, 0.37), tilted(0.8, -1.1)] {
            for p in points(20_000, 12.0) {
                assert_eq!(lat.nearest(p), lat.nearest_brute_force(p, 4), "lattice {lat:?} point {p:?}");
            }
        }
    }

    #[test]
    fn batched_centres_are_nearest_then_center_bit_for_bit() {
        for lat in [Lattice::square(1.2).unwrap(), hexagonal(1.2), tilted(1.0, 0.37)] {
            let mut pts = points(20_000, 12.0);
            // Exact ties between cells and NaN.
            pts.extend([DVec2::new(0.6, 0.6), DVec2::new(-0.6, 1.8), DVec2::new(f64::NAN, 1.0)]);
            let mut batch = pts.clone();
            lat.nearest_centers(&mut batch);
            for (p, c) in pts.iter().zip(&batch) {
                let want = lat.center(lat.nearest(*p));
                assert_eq!((want.x.to_bits(), want.y.to_bits()), (c.x.to_bits(), c.y.to_bits()), "{p}");
            }
        }
    }

    #[test]
    fn batched_centres_in_another_lattice_are_nearest_then_its_center_bit_for_bit() {
        let square = |p: f64, shift: DVec2| Lattice::new(shift, DMat2::from_diagonal(DVec2::new(p, 0.9 * p))).unwrap();
        let (elemental, lenslets) = (square(1.58, DVec2::new(0.03, -0.01)), square(1.2, DVec2::new(-0.02, 0.05)));
        for (from, to) in [(elemental, lenslets), (hexagonal(1.3), lenslets), (elemental, tilted(1.0, 0.37))] {
            let mut pts = points(20_000, 12.0);
            // Exact ties between cells of `from` and NaN.
            pts.extend([DVec2::new(0.82, 0.701), DVec2::new(-0.76, 0.701), DVec2::new(f64::NAN, 1.0)]);
            let mut batch = pts.clone();
            from.nearest_centers_in(&to, &mut batch);
            for (p, c) in pts.iter().zip(&batch) {
                let want = to.center(from.nearest(*p));
                assert_eq!((want.x.to_bits(), want.y.to_bits()), (c.x.to_bits(), c.y.to_bits()), "{p}");
            }
        }
    }

    #[test]
    fn rounding_is_exact_near_halves() {
        assert_eq!(round_half_up(0.49999999999999994), 0);
        assert_eq!(round_half_up(0.5), 1);
        assert_eq!(round_half_up(-0.5), 0);
        assert_eq!(round_half_up(-1.5), -1);
        assert_eq!(round_half_up(-1.5000000000000002), -2);
        assert_eq!(round_half_up(2.4999999999999996), 2);
        assert_eq!(round_half_up(f64::NAN), 0);
        assert_eq!(round_half_up(1e300), i32::MAX);
    }

    #[test]
    fn square_lattice_boundary_goes_to_upper_cell() {
        // Pitch 2: the boundaries x = +-1, 3, ... are exact in binary, so these are exact ties.
        let lat = Lattice::square(2.0).unwrap();
        assert_eq!(lat.nearest(DVec2::new(1.0, -1.0)), IVec2::new(1, 0));
        assert_eq!(lat.nearest(DVec2::new(-1.0, 3.0)), IVec2::new(0, 2));
        assert_eq!(lat.nearest_brute_force(DVec2::new(1.0, -1.0), 3), IVec2::new(1, 0));
        assert_eq!(lat.nearest(DVec2::new(0.999_999, 0.0)), IVec2::new(0, 0));
        // 0.6 in binary is a hair below the true boundary of a 1.2 mm lattice: cell 0.
        assert_eq!(Lattice::square(1.2).unwrap().nearest(DVec2::new(0.6, 0.0)), IVec2::new(0, 0));
    }

    #[test]
    fn singular_or_nan_matrix_is_rejected() {
        assert!(Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(1.0, 2.0), DVec2::new(2.0, 4.0))).is_none());
        assert!(Lattice::square(0.0).is_none());
        assert!(Lattice::square(f64::NAN).is_none());
        assert!(Lattice::new(DVec2::new(f64::NAN, 0.0), DMat2::IDENTITY).is_none());
    }

    #[test]
    fn fast_floor_matches_floor() {
        for x in [-2.5f64, -2.0, -1.0000001, -0.5, -0.0, 0.0, 0.3, 0.5, 1.0, 1.9999999, 1e9, -1e9, 3.0e9, -3.0e9] {
            let expect = x.floor().clamp(i32::MIN as f64, i32::MAX as f64) as i32;
            assert_eq!(floor_to_i32(x), expect, "{x}");
        }
        assert_eq!(floor_to_i32(f64::NAN), 0);
    }

    #[test]
    fn row_major_round_trip() {
        let lat = Lattice::from_row_major(DVec2::ZERO, [1.0, 0.5, 0.0, 0.866]).unwrap();
        assert_eq!(lat.row_major(), [1.0, 0.5, 0.0, 0.866]);
        assert_eq!(lat.center(IVec2::new(1, 1)), DVec2::new(1.5, 0.866));
    }
}
