//! Triangulation of a mesh file's polygon faces (OBJ `f` lines, PLY `face` lists) into the
//! triangles that every intersection backend traces (paper Sec. 3.1: "each ray is traversed
//! until it hits an object"; complex scenes arrive as polygon meshes).
//!
//! A convex face keeps the fan `(0, i, i + 1)` that readers have always produced. A concave
//! face (or a non-planar one, which has no unique triangulation) is projected onto the plane
//! of its Newell normal and cut into ears by the `earcut` crate, so a concave ring is not
//! filled in. Every triangle keeps the face's winding (its normal points along the face's).
//!
//! Ear clipping is quadratic in the corners of a face in the worst case (seconds at 10^5
//! corners), so a concave face may have at most [`MAX_CONCAVE_CORNERS`] corners; a larger one
//! is refused (the reader names the file and the face). Convex faces of any size are a fan, in
//! linear time.

use glam::{DVec2, DVec3};

/// The most corners of a concave (or non-planar) face: ear clipping beyond it could take
/// seconds. Real meshes' faces have a handful of corners; a font outline a few hundred.
pub const MAX_CONCAVE_CORNERS: usize = 20_000;

/// Appends the triangles of polygon `face` (indices into `positions`, in winding order) to
/// `out`. Faces with fewer than three corners add nothing. Indices must be in range (callers
/// check them first, to name the file and line). A concave face of more than
/// [`MAX_CONCAVE_CORNERS`] corners adds nothing and is an error message (the caller names the
/// file and the face).
pub fn triangulate(positions: &[DVec3], face: &[u32], out: &mut Vec<[u32; 3]>) -> Result<(), String> {
    let n = face.len();
    if n < 3 {
        return Ok(());
    }
    let fan = |out: &mut Vec<[u32; 3]>| {
        for i in 1..n - 1 {
            out.push([face[0], face[i], face[i + 1]]);
        }
    };
    if n == 3 {
        fan(out);
        return Ok(());
    }
    let Some(projected) = project(positions, face) else {
        // No plane (all corners on a line, or non-finite): every triangle would be degenerate
        // and is dropped later anyway.
        fan(out);
        return Ok(());
    };
    if is_convex(&projected) {
        fan(out);
        return Ok(());
    }
    if n > MAX_CONCAVE_CORNERS {
        return Err(format!(
            "a concave face of {n} corners: at most {MAX_CONCAVE_CORNERS} are triangulated (split the face)"
        ));
    }
    let mut local: Vec<u32> = Vec::with_capacity(3 * (n - 2));
    earcut::Earcut::new().earcut(projected.iter().map(|p| [p.x, p.y]), &[] as &[u32], &mut local);
    if local.is_empty() {
        fan(out);
        return Ok(());
    }
    for t in local.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        // Keep the face's winding: counter-clockwise in the projection, which looks down the
        // face's normal.
        if signed_area(projected[a], projected[b], projected[c]) >= 0.0 {
            out.push([face[a], face[b], face[c]]);
        } else {
            out.push([face[a], face[c], face[b]]);
        }
    }
    Ok(())
}

/// The face's corners in 2-D: the plane perpendicular to the largest component of the Newell
/// normal, oriented so the face winds counter-clockwise. `None` when the normal vanishes.
fn project(positions: &[DVec3], face: &[u32]) -> Option<Vec<DVec2>> {
    let p = |i: usize| positions[face[i] as usize];
    let n = face.len();
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        let (a, b) = (p(i), p((i + 1) % n));
        normal += DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    if !normal.is_finite() || normal == DVec3::ZERO {
        return None;
    }
    let abs = normal.abs();
    // Drop the dominant axis; the remaining two (u, v) form a right-handed pair with it, so
    // a positive normal component means counter-clockwise in (u, v).
    let (axis, (u, v)) = if abs.x >= abs.y && abs.x >= abs.z {
        (normal.x, (1, 2))
    } else if abs.y >= abs.z {
        (normal.y, (2, 0))
    } else {
        (normal.z, (0, 1))
    };
    let flip = axis < 0.0;
    Some(
        (0..n)
            .map(|i| {
                let q = p(i).to_array();
                if flip {
                    DVec2::new(q[v], q[u])
                } else {
                    DVec2::new(q[u], q[v])
                }
            })
            .collect(),
    )
}

fn signed_area(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// True when no corner of the counter-clockwise polygon turns clockwise (collinear corners
/// allowed) and the corners go around once (a convex polygon: the fan covers it exactly).
fn is_convex(p: &[DVec2]) -> bool {
    let n = p.len();
    let mut winding = 0.0;
    for i in 0..n {
        let (a, b, c) = (p[i], p[(i + 1) % n], p[(i + 2) % n]);
        if signed_area(a, b, c) < 0.0 {
            return false;
        }
        let (e1, e2) = (b - a, c - b);
        winding += e1.perp_dot(e2).atan2(e1.dot(e2));
    }
    // Turning angles of a simple convex polygon add up to exactly one turn; a star or a
    // polygon that winds twice turns more.
    (winding - std::f64::consts::TAU).abs() < 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twice the signed area of a 2-D polygon (shoelace).
    fn shoelace(p: &[DVec2]) -> f64 {
        (0..p.len()).map(|i| p[i].perp_dot(p[(i + 1) % p.len()])).sum::<f64>() / 2.0
    }

    /// Even-odd point-in-polygon test: the obviously correct twin of "inside".
    fn inside(p: &[DVec2], q: DVec2) -> bool {
        let mut odd = false;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                odd = !odd;
            }
        }
        odd
    }

    fn lcg(state: &mut u64) -> f64 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Checks a triangulation of a planar polygon in the z = 0 plane against brute force:
    /// n - 2 triangles, all counter-clockwise, each centroid inside the polygon, areas adding
    /// up to the polygon's (so no triangle overlaps another or leaves the polygon).
    fn check_planar(poly: &[DVec2]) {
        let positions: Vec<DVec3> = poly.iter().map(|p| p.extend(0.0)).collect();
        let face: Vec<u32> = (0..poly.len() as u32).collect();
        let mut tris = Vec::new();
        triangulate(&positions, &face, &mut tris).unwrap();
        assert_eq!(tris.len(), poly.len() - 2, "{poly:?}");
        let mut area = 0.0;
        for t in &tris {
            let (a, b, c) = (poly[t[0] as usize], poly[t[1] as usize], poly[t[2] as usize]);
            let s = signed_area(a, b, c) / 2.0;
            assert!(s >= 0.0, "clockwise triangle {t:?}");
            if s > 1e-12 {
                assert!(inside(poly, (a + b + c) / 3.0), "triangle {t:?} outside {poly:?}");
            }
            area += s;
        }
        let exact = shoelace(poly);
        assert!((area - exact).abs() < 1e-9 * exact.abs().max(1.0), "area {area} vs {exact}");
    }

    #[test]
    fn convex_faces_keep_the_fan() {
        let positions =
            [DVec3::new(0.0, 0.0, 0.0), DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::new(-0.5, 0.5, 0.0)];
        let mut tris = Vec::new();
        triangulate(&positions, &[0, 1, 2, 3, 4], &mut tris).unwrap();
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn concave_star_polygons_match_brute_force() {
        let mut s = 7u64;
        for trial in 0..300 {
            let n = 4 + trial % 40;
            // Star-shaped around the origin (so simple), radii random: mostly concave.
            let poly: Vec<DVec2> = (0..n)
                .map(|i| {
                    let phi = std::f64::consts::TAU * (i as f64 + 0.4 * lcg(&mut s)) / n as f64;
                    let r = 0.2 + lcg(&mut s);
                    DVec2::new(r * phi.cos(), r * phi.sin())
                })
                .collect();
            check_planar(&poly);
            // The same polygon wound clockwise.
            let rev: Vec<DVec2> = poly.iter().rev().copied().collect();
            let positions: Vec<DVec3> = rev.iter().map(|p| p.extend(0.0)).collect();
            let mut tris = Vec::new();
            triangulate(&positions, &(0..n as u32).collect::<Vec<_>>(), &mut tris).unwrap();
            let area: f64 = tris
                .iter()
                .map(|t| signed_area(rev[t[0] as usize], rev[t[1] as usize], rev[t[2] as usize]) / 2.0)
                .sum();
            assert!((area - shoelace(&rev)).abs() < 1e-9, "clockwise face lost its winding");
        }
    }

    #[test]
    fn a_concave_ring_is_not_filled() {
        // An annulus-like "C": outer arc out, inner arc back (assimp's ring is this shape).
        let mut poly = Vec::new();
        for i in 0..=16 {
            let phi = 0.3 + (std::f64::consts::TAU - 0.6) * i as f64 / 16.0;
            poly.push(DVec2::new(phi.cos(), phi.sin()));
        }
        for i in (0..=16).rev() {
            let phi = 0.3 + (std::f64::consts::TAU - 0.6) * i as f64 / 16.0;
            poly.push(0.5 * DVec2::new(phi.cos(), phi.sin()));
        }
        check_planar(&poly);
        let positions: Vec<DVec3> = poly.iter().map(|p| p.extend(0.0)).collect();
        let mut tris = Vec::new();
        triangulate(&positions, &(0..poly.len() as u32).collect::<Vec<_>>(), &mut tris).unwrap();
        // The centre of the ring is in no triangle.
        for t in &tris {
            let (a, b, c) = (poly[t[0] as usize], poly[t[1] as usize], poly[t[2] as usize]);
            let q = DVec2::ZERO;
            let inside_tri = signed_area(a, b, q) > 0.0 && signed_area(b, c, q) > 0.0 && signed_area(c, a, q) > 0.0;
            assert!(!inside_tri, "triangle {t:?} covers the hole");
        }
    }

    #[test]
    fn tilted_faces_keep_their_normal() {
        // A concave "L" in a tilted plane, both windings.
        let l = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)];
        let (eu, ev) = (DVec3::new(1.0, 0.2, 0.5).normalize(), DVec3::new(-0.3, 1.0, 0.4));
        let ev = (ev - eu * eu.dot(ev)).normalize();
        let normal = eu.cross(ev);
        for reverse in [false, true] {
            let mut positions: Vec<DVec3> =
                l.iter().map(|&(u, v)| DVec3::new(3.0, -1.0, 5.0) + u * eu + v * ev).collect();
            if reverse {
                positions.reverse();
            }
            let mut tris = Vec::new();
            triangulate(&positions, &[0, 1, 2, 3, 4, 5], &mut tris).unwrap();
            assert_eq!(tris.len(), 4);
            let mut area = 0.0;
            for t in &tris {
                let (a, b, c) = (positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
                let n = (b - a).cross(c - a);
                let along = if reverse { -normal } else { normal };
                assert!(n.dot(along) > 0.0, "triangle {t:?} flipped");
                area += n.length() / 2.0;
            }
            assert!((area - 3.0).abs() < 1e-12, "area {area}");
        }
    }

    #[test]
    fn degenerate_faces_do_not_panic() {
        let positions = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0), DVec3::new(3.0, 0.0, 0.0), DVec3::NAN];
        let mut tris = Vec::new();
        triangulate(&positions, &[0, 1, 2, 3], &mut tris).unwrap();
        triangulate(&positions, &[0, 1, 4, 2], &mut tris).unwrap();
        triangulate(&positions, &[0, 1], &mut tris).unwrap();
        assert!(tris.iter().flatten().all(|&i| i < 5));
    }

    /// A comb: a concave polygon of `n` corners (`n` even) along the x axis, teeth up.
    fn comb(n: usize) -> Vec<DVec3> {
        let teeth = n / 2;
        let mut p: Vec<DVec3> =
            (0..teeth).map(|i| DVec3::new(i as f64, if i % 2 == 0 { 0.0 } else { 0.5 }, 0.0)).collect();
        p.extend((0..teeth).rev().map(|i| DVec3::new(i as f64, 2.0 + (i % 3) as f64, 0.0)));
        p
    }

    #[test]
    fn concave_faces_beyond_the_limit_are_refused_and_convex_ones_of_any_size_are_a_fan() {
        let ok = comb(1000);
        let mut tris = Vec::new();
        triangulate(&ok, &(0..ok.len() as u32).collect::<Vec<_>>(), &mut tris).unwrap();
        assert_eq!(tris.len(), ok.len() - 2);
        let big = comb(MAX_CONCAVE_CORNERS + 2);
        let mut tris = Vec::new();
        let e = triangulate(&big, &(0..big.len() as u32).collect::<Vec<_>>(), &mut tris).unwrap_err();
        assert!(e.contains(&format!("{} corners", MAX_CONCAVE_CORNERS + 2)) && e.contains("20000"), "{e}");
        assert!(tris.is_empty());
        // 200,000 corners on a circle: convex, a fan, linear.
        let n = 200_000;
        let circle: Vec<DVec3> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                DVec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let mut tris = Vec::new();
        triangulate(&circle, &(0..n as u32).collect::<Vec<_>>(), &mut tris).unwrap();
        assert_eq!(tris.len(), n - 2);
        assert!(tris.iter().all(|t| t[0] == 0));
    }
}
