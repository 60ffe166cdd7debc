//! The geometric rules a stack of refracting surfaces must keep, shared by the user-defined
//! schematic eye ([`crate::optics::eye::UserEye`]) and the thick lenslet
//! ([`crate::optics::lenslet::ThickLenslet`]): two consecutive surfaces may not cross inside
//! their common semi-diameter, and a stop plane (the eye's iris) must lie between its two
//! neighbours there.
//!
//! A surface is a conic of revolution given by its sag `z(r)` from its vertex (Welford,
//! "Aberrations of Optical Systems", 1986, Sec. 2.4; [`crate::optics::eye::conic`]). Two
//! surfaces whose vertices are `thickness` apart are separated along the z axis, at a distance r
//! from it, by the gap `thickness + z_back(r) - z_front(r)` (the edge thickness of a lens at
//! r); they cross where the gap is negative. The gap is the difference of two smooth functions of
//! r (no more than a few extrema over a semi-diameter), so its minimum is found by a fine scan
//! (512 points) refined by golden-section search (Kiefer 1953; Press et al., "Numerical Recipes",
//! 3rd ed., Sec. 10.2) around the smallest sample.

use super::eye::conic::Conic;

/// Points of the scan over `[0, r_max]`.
const SCAN: usize = 512;

/// Where two surfaces are closest along z within a radius, and how far apart they are there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gap {
    /// Distance from the axis, mm.
    pub r: f64,
    /// `thickness + z_back(r) - z_front(r)`, mm (negative: the surfaces cross).
    pub gap: f64,
}

/// The gap between `front` and `back` (their sags from their own vertices) whose vertices are
/// `thickness` apart, at distance `r` from the axis; `None` where a surface has no point there.
pub fn gap_at(front: &Conic, back: &Conic, thickness: f64, r: f64) -> Option<f64> {
    let r2 = r * r;
    Some(thickness + back.sag(r2)? - front.sag(r2)?)
}

/// The narrowest gap between `front` and `back` over `0 <= r <= r_max` (see the module comment),
/// or `Err(r)`: the first scanned distance where one of them has no point.
pub fn narrowest_gap(front: &Conic, back: &Conic, thickness: f64, r_max: f64) -> Result<Gap, f64> {
    let r_max = r_max.max(0.0);
    let at = |i: usize| r_max * i as f64 / SCAN as f64;
    let mut best = Gap { r: 0.0, gap: f64::INFINITY };
    let mut best_i = 0;
    for i in 0..=SCAN {
        let r = at(i);
        let gap = gap_at(front, back, thickness, r).ok_or(r)?;
        if gap < best.gap {
            best = Gap { r, gap };
            best_i = i;
        }
    }
    // Golden-section search over the two scan steps around the smallest sample.
    let (mut a, mut b) = (at(best_i.saturating_sub(1)), at((best_i + 1).min(SCAN)));
    let g = |r: f64| gap_at(front, back, thickness, r).unwrap_or(f64::INFINITY);
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
    let (mut gc, mut gd) = (g(c), g(d));
    for _ in 0..80 {
        if gc < gd {
            b = d;
            (d, gd) = (c, gc);
            c = b - ratio * (b - a);
            gc = g(c);
        } else {
            a = c;
            (c, gc) = (d, gd);
            d = a + ratio * (b - a);
            gd = g(d);
        }
    }
    for (r, gap) in [(c, gc), (d, gd)] {
        if gap < best.gap {
            best = Gap { r, gap };
        }
    }
    Ok(best)
}

/// Where a plane `distance` behind the vertex of `front` (and `thickness - distance` before the
/// vertex of `back`, when there is one) meets either surface within `r_max` of the axis: the
/// surface it meets (`false`: `front`, `true`: `back`) and the gap there (negative).
pub fn plane_between(
    front: &Conic,
    back: Option<&Conic>,
    thickness: f64,
    distance: f64,
    r_max: f64,
) -> Option<(bool, Gap)> {
    let plane = Conic::from_radius(0.0, 0.0, 0.0, f64::INFINITY);
    // The plane behind `front`: the gap from `front` to the plane `distance` behind its vertex.
    if let Ok(g) = narrowest_gap(front, &plane, distance, r_max) {
        if g.gap < 0.0 {
            return Some((false, g));
        }
    }
    let back = back?;
    match narrowest_gap(&plane, back, thickness - distance, r_max) {
        Ok(g) if g.gap < 0.0 => Some((true, g)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_narrowest_gap_of_two_spheres_is_found_analytically() {
        // A biconvex lens, R = 10 both sides (front convex toward -z, back toward +z), 2 mm at the
        // centre: the gap 2 - 2 (10 - sqrt(100 - r^2)) falls with r, to 0 at r = sqrt(19).
        let front = Conic::from_radius(0.0, 10.0, 0.0, 10.0);
        let back = Conic::from_radius(0.0, -10.0, 0.0, 10.0);
        let g = narrowest_gap(&front, &back, 2.0, 6.0).unwrap();
        assert!((g.r - 6.0).abs() < 1e-12, "{g:?}");
        assert!((g.gap - (2.0 - 2.0 * (10.0 - 64f64.sqrt()))).abs() < 1e-12, "{g:?}");
        let zero = 19f64.sqrt();
        assert!(gap_at(&front, &back, 2.0, zero).unwrap().abs() < 1e-12);
        // A meniscus whose gap has an interior minimum: front R = 10, back R = 12 (both convex
        // toward -z), 1 mm apart: the gap 1 + sag12(r) - sag10(r) falls monotonically; with a
        // conic back surface it turns. The golden-section minimum matches a 1e6-point scan.
        let back = Conic::from_radius(0.0, 12.0, -3.0, 10.0);
        let g = narrowest_gap(&front, &back, 1.0, 5.0).unwrap();
        let fine = (0..=1_000_000)
            .map(|i| gap_at(&front, &back, 1.0, 5.0 * i as f64 / 1e6).unwrap())
            .fold(f64::INFINITY, f64::min);
        assert!(g.gap <= fine + 1e-12, "{g:?} vs {fine}");
        // A surface without a point inside the radius.
        let narrow = Conic::from_radius(0.0, 2.0, 0.0, 2.0);
        assert!(narrowest_gap(&narrow, &front, 1.0, 3.0).is_err());
    }

    #[test]
    fn a_plane_between_two_surfaces_is_checked_against_both() {
        // Behind a surface of radius 6.5 (sag 1.81 mm at r = 4.5): a plane 1 mm behind its
        // vertex crosses it, one 3 mm behind does not; the next surface (convex, R = 10) 3.05 mm
        // behind the first leaves room.
        let front = Conic::from_radius(0.0, 6.5, 0.0, 5.5);
        let back = Conic::from_radius(0.0, 10.0, 0.0, 4.5);
        let (which, g) = plane_between(&front, Some(&back), 3.05, 1.0, 4.5).unwrap();
        assert!(!which && g.gap < 0.0, "{g:?}");
        assert_eq!(plane_between(&front, Some(&back), 3.05, 3.0, 4.5), None);
        // A plane at the back surface's vertex of a concave back surface crosses it.
        let concave = Conic::from_radius(0.0, -10.0, 0.0, 4.5);
        let (which, _) = plane_between(&front, Some(&concave), 3.05, 3.05, 4.5).unwrap();
        assert!(which);
    }
}
