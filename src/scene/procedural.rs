//! Procedural triangle meshes for scale tests: a grid of UV spheres (`type = "sphere-grid"` in
//! a scene file). Not in the paper; it gives scenes of millions of triangles without shipping
//! or downloading a mesh file, to exercise the Embree backend (paper Sec. 3.1's ray tracing of
//! the 3-D scene) at scale.

use glam::{DVec2, DVec3};

use crate::scene::mesh::Mesh;

/// `count[0] x count[1]` spheres of radius `radius` on a grid in the plane `z = center.z`,
/// spaced `spacing` mm apart and centred on `center`. Each sphere has `segments` longitudes
/// and `segments / 2` latitudes (so `2 * segments * (segments / 2 - 1)` triangles; poles are
/// single vertices). Vertex normals are the exact sphere normals; uvs are longitude / latitude
/// in `[0, 1]`.
pub fn sphere_grid(center: DVec3, count: [usize; 2], spacing: f64, radius: f64, segments: usize) -> Mesh {
    let lon = segments.max(3);
    let lat = (segments / 2).max(2);
    // One sphere: north pole, (lat - 1) rings of lon vertices, south pole.
    let mut unit = Vec::new();
    let mut uv = Vec::new();
    unit.push(DVec3::Y);
    uv.push(DVec2::new(0.5, 1.0));
    for i in 1..lat {
        let theta = std::f64::consts::PI * i as f64 / lat as f64;
        for j in 0..lon {
            let phi = std::f64::consts::TAU * j as f64 / lon as f64;
            unit.push(DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
            uv.push(DVec2::new(j as f64 / lon as f64, 1.0 - i as f64 / lat as f64));
        }
    }
    unit.push(-DVec3::Y);
    uv.push(DVec2::new(0.5, 0.0));
    let south = (unit.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * lon + j % lon) as u32;
    let mut tris = Vec::new();
    for j in 0..lon {
        tris.push([0, ring(1, j + 1), ring(1, j)]);
        tris.push([south, ring(lat - 1, j), ring(lat - 1, j + 1)]);
    }
    for i in 1..lat - 1 {
        for j in 0..lon {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    // Outward winding: (b - a) x (c - a) along the outward normal for every triangle above.
    let n = count[0] * count[1];
    let mut mesh = Mesh {
        positions: Vec::with_capacity(n * unit.len()),
        triangles: Vec::with_capacity(n * tris.len()),
        normals: Some(Vec::with_capacity(n * unit.len())),
        uvs: Some(Vec::with_capacity(n * unit.len())),
        colors: None,
    };
    let origin = center
        - DVec3::new(0.5 * (count[0].max(1) - 1) as f64 * spacing, 0.5 * (count[1].max(1) - 1) as f64 * spacing, 0.0);
    for gy in 0..count[1] {
        for gx in 0..count[0] {
            let c = origin + DVec3::new(gx as f64 * spacing, gy as f64 * spacing, 0.0);
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(unit.iter().map(|u| c + radius * *u));
            if let Some(ns) = &mut mesh.normals {
                ns.extend_from_slice(&unit);
            }
            if let Some(uvs) = &mut mesh.uvs {
                uvs.extend_from_slice(&uv);
            }
            mesh.triangles.extend(tris.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        }
    }
    mesh
}

/// An icosahedron subdivided `levels` times (each triangle into four), vertices on a sphere of
/// `radius` around `centre`: a closed, watertight mesh whose vertices have irrational
/// coordinates, used by tests and benchmarks of every mesh backend.
pub fn icosphere(levels: usize, centre: DVec3, radius: f64) -> Mesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push(((positions[a as usize] + positions[b as usize]) * 0.5).normalize());
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::new();
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let positions = positions.into_iter().map(|p| centre + radius * p).collect();
    Mesh { positions, triangles, ..Default::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_grid_counts_and_outward_winding() {
        let m = sphere_grid(DVec3::new(0.0, 0.0, 500.0), [3, 2], 10.0, 4.0, 16);
        assert_eq!(m.triangle_count(), 6 * 2 * 16 * 7);
        m.validate("test").unwrap();
        let normals = m.normals.as_ref().unwrap();
        for t in 0..m.triangle_count() {
            let [p0, p1, p2] = m.triangle_positions(t);
            let g = (p1 - p0).cross(p2 - p0);
            let [a, _, _] = m.triangles[t];
            assert!(g.length() > 0.0);
            // Winding agrees with the outward vertex normals.
            let centroid_normal = normals[a as usize] + normals[m.triangles[t][1] as usize];
            assert!(g.dot(centroid_normal) > 0.0, "triangle {t}");
        }
        // Every vertex lies on its sphere.
        let (lo, hi) = m.bounds();
        assert!((lo - DVec3::new(-14.0, -9.0, 496.0)).abs().max_element() < 1e-9);
        assert!((hi - DVec3::new(14.0, 9.0, 504.0)).abs().max_element() < 1e-9);
    }
}
