//! Mesh loading (OBJ, PLY), transforms, validation errors and `tessellate_rect`.
#![deny(unsafe_code)]

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use inimtrace::accel::brute::BruteForce;
use inimtrace::io::{load_mesh, MeshLoad};
use inimtrace::ray::{Intersector, Ray, Surface};
use inimtrace::scene::mesh::{tessellate_rect, Mesh};
use inimtrace::scene::Transform;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

fn load(rel: &str) -> MeshLoad {
    let path = data(rel);
    load_mesh(&path).unwrap_or_else(|e| panic!("loading {}: {e}", path.display()))
}

/// Per-corner attributes of every triangle, in triangle order: independent of how a format
/// numbers its vertices (tobj's single index renumbers OBJ vertices by first use).
#[derive(Debug, PartialEq)]
struct Corners {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    uvs: Vec<DVec2>,
    colors: Vec<DVec3>,
}

fn corners(mesh: &Mesh) -> Corners {
    let idx: Vec<usize> = mesh.triangles.iter().flatten().map(|&i| i as usize).collect();
    Corners {
        positions: idx.iter().map(|&i| mesh.positions[i]).collect(),
        normals: idx.iter().map(|&i| mesh.normals.as_ref().expect("normals")[i]).collect(),
        uvs: idx.iter().map(|&i| mesh.uvs.as_ref().expect("uvs")[i]).collect(),
        colors: idx.iter().map(|&i| mesh.colors.as_ref().expect("colors")[i]).collect(),
    }
}

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn obj_and_ply_variants_load_identically() {
    let reference = load("meshes/pyramid_ascii.ply");
    assert_eq!(reference.mesh.positions.len(), 5);
    // A quad base (fan-triangulated into 2) and 4 sides.
    assert_eq!(reference.mesh.triangles.len(), 6);
    assert_eq!(reference.dropped_degenerate, 0);
    assert_eq!(reference.texture, None);
    // Fan triangulation (0, i, i + 1) of the base quad 0 3 2 1.
    assert_eq!(reference.mesh.triangles[0], [0, 3, 2]);
    assert_eq!(reference.mesh.triangles[1], [0, 2, 1]);
    let want = corners(&reference.mesh);
    for rel in
        ["meshes/pyramid.obj", "meshes/pyramid_two_objects.obj", "meshes/pyramid_le.ply", "meshes/pyramid_be.ply"]
    {
        let got = load(rel);
        assert_eq!(got.mesh.triangles.len(), 6, "{rel}");
        assert_eq!(got.dropped_degenerate, 0, "{rel}");
        let c = corners(&got.mesh);
        assert_eq!(c.positions, want.positions, "{rel}");
        assert_eq!(c.normals, want.normals, "{rel}");
        assert_eq!(c.uvs, want.uvs, "{rel}");
        for (a, b) in c.colors.iter().zip(&want.colors) {
            assert!((*a - *b).abs().max_element() < 1e-12, "{rel}: colour {a} vs {b}");
        }
    }
    // Multi-object OBJ: objects merged, each keeping its own vertices (4 + 5).
    let two = load("meshes/pyramid_two_objects.obj");
    assert_eq!(two.mesh.positions.len(), 9);
}

#[test]
fn per_vertex_attributes_are_read_and_colours_linearised() {
    let m = load("meshes/pyramid_ascii.ply").mesh;
    // Vertex 3 of the fixture: normal (-0.5, 0.5, 0.25), uv (0, 1), colour (128, 64, 10) / 255.
    assert_eq!(m.positions[3], DVec3::new(-1.0, 1.0, 0.0));
    assert_eq!(m.normals.as_ref().unwrap()[3], DVec3::new(-0.5, 0.5, 0.25));
    assert_eq!(m.uvs.as_ref().unwrap()[3], DVec2::new(0.0, 1.0));
    let c = m.colors.as_ref().unwrap()[3];
    let want = DVec3::new(srgb_to_linear(128.0 / 255.0), srgb_to_linear(64.0 / 255.0), srgb_to_linear(10.0 / 255.0));
    assert!((c - want).abs().max_element() < 1e-15, "{c} vs {want}");
    // Known values of the sRGB curve: 128/255 -> 0.21586, 10/255 (linear segment) -> 0.003035.
    assert!((c.x - 0.215_860_5).abs() < 1e-6);
    assert!((c.z - 10.0 / 255.0 / 12.92).abs() < 1e-15);
    assert_eq!(m.colors.as_ref().unwrap()[4], DVec3::ONE);
    assert_eq!(m.colors.as_ref().unwrap()[0], DVec3::new(1.0, 0.0, 0.0));
}

#[test]
fn obj_texture_resolved_relative_to_file() {
    let l = load("meshes/pyramid.obj");
    assert_eq!(l.texture, Some(data("meshes/textures/stone.png")));
}

#[test]
fn degenerate_triangles_dropped_and_counted() {
    let l = load("meshes/degenerate.obj");
    assert_eq!(l.dropped_degenerate, 2);
    assert_eq!(l.mesh.triangles.len(), 1);
    let [a, b, c] = l.mesh.triangles[0];
    let p = |i: u32| l.mesh.positions[i as usize];
    assert_eq!([p(a), p(b), p(c)], [DVec3::ZERO, DVec3::X, DVec3::Y]);
}

#[test]
fn stanford_bunny_loads() {
    let path = Path::new("/usr/share/glmark2/models/bunny.obj");
    if !path.exists() {
        assert!(
            std::env::var_os("INIMTRACE_REQUIRE_BUNNY").is_none(),
            "INIMTRACE_REQUIRE_BUNNY is set but {} is missing (Debian package glmark2-data)",
            path.display()
        );
        eprintln!("SKIPPED stanford_bunny_loads: {} not present", path.display());
        return;
    }
    let l = load_mesh(path).unwrap();
    assert_eq!(l.mesh.triangles.len() + l.dropped_degenerate, 69_666);
    assert_eq!(l.mesh.triangles.len(), 69_666);
    assert_eq!(l.mesh.positions.len(), 34_835);
    let (lo, hi) = l.mesh.bounds();
    assert!(lo.cmplt(hi).all());
    assert!(l.mesh.validate("bunny").is_ok());
}

/// Each broken fixture gives an error naming the file and where the problem is.
#[test]
fn bad_files_give_located_errors() {
    let cases: &[(&str, &[&str])] = &[
        ("bad/does_not_exist.obj", &["does_not_exist.obj"]),
        ("bad/a_directory.obj", &["a_directory.obj", "directory"]),
        ("bad/empty.obj", &["empty.obj", "no triangles"]),
        ("bad/bad_number.obj", &["bad_number.obj", "line 3", "1.x"]),
        ("bad/index_out_of_range.obj", &["index_out_of_range.obj", "line 5", "index 7"]),
        ("bad/nan_vertex.obj", &["nan_vertex.obj", "line 3", "vertex 3", "non-finite"]),
        ("bad/bad_header.ply", &["bad_header.ply", "line 4", "flaot"]),
        ("bad/bad_number.ply", &["bad_number.ply", "line 11", "vertex 1", "zero"]),
        ("bad/index_out_of_range.ply", &["index_out_of_range.ply", "face 1", "index 5"]),
        ("bad/inf_vertex.ply", &["inf_vertex.ply", "vertex 2", "non-finite"]),
        ("bad/truncated.ply", &["truncated.ply", "truncated", "face 3 of 5"]),
    ];
    for (rel, needles) in cases {
        let err = match load_mesh(&data(rel)) {
            Ok(_) => panic!("{rel}: loaded without error"),
            Err(e) => e.to_string(),
        };
        for needle in *needles {
            assert!(err.contains(needle), "{rel}: error '{err}' lacks '{needle}'");
        }
    }
}

#[test]
fn unknown_extension_is_an_error() {
    let err = load_mesh(&data("meshes/make_fixtures.py")).unwrap_err().to_string();
    assert!(err.contains("make_fixtures.py") && err.contains(".obj"), "{err}");
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).abs().max_element() < 1e-12
}

fn single_vertex_mesh(p: DVec3, n: DVec3) -> Mesh {
    Mesh { positions: vec![p], normals: Some(vec![n]), ..Default::default() }
}

#[test]
fn transform_rotation_about_z() {
    let t = Transform { rotation_deg: DVec3::new(0.0, 0.0, 90.0), ..Default::default() };
    let mut m = single_vertex_mesh(DVec3::X, DVec3::X);
    t.apply(&mut m);
    assert!(close(m.positions[0], DVec3::Y), "{}", m.positions[0]);
    assert!(close(m.normals.as_ref().unwrap()[0], DVec3::Y));
}

#[test]
fn transform_euler_order_is_x_then_y_then_z() {
    // X by 90: +y -> +z; then Y by 90: +z -> +x. (Y first would give +y -> +y -> +z.)
    let t = Transform { rotation_deg: DVec3::new(90.0, 90.0, 0.0), ..Default::default() };
    assert!(close(t.apply_point(DVec3::Y), DVec3::X), "{}", t.apply_point(DVec3::Y));
    // Full chain with scale and translation: p' = T + R (S p).
    let t = Transform {
        scale: DVec3::new(2.0, 3.0, 4.0),
        rotation_deg: DVec3::new(0.0, 0.0, 90.0),
        translation: DVec3::new(10.0, 20.0, 30.0),
    };
    // S (1,1,1) = (2,3,4); Rz90 (x,y,z) = (-y,x,z) -> (-3,2,4); + T.
    assert!(close(t.apply_point(DVec3::ONE), DVec3::new(7.0, 22.0, 34.0)));
}

#[test]
fn transform_normals_follow_surfaces() {
    // A tilted triangle with shading normals set to its geometric normal; after any transform
    // (non-uniform and mirroring scales included) they must still equal the geometric normal.
    let p = [DVec3::new(0.3, -0.2, 1.0), DVec3::new(1.7, 0.4, 0.2), DVec3::new(-0.5, 1.1, 0.6)];
    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    let transforms = [
        Transform { scale: DVec3::new(3.0, 0.5, 1.5), ..Default::default() },
        Transform {
            scale: DVec3::new(2.0, 1.0, 0.25),
            rotation_deg: DVec3::new(30.0, -45.0, 100.0),
            translation: DVec3::new(1.0, -2.0, 50.0),
        },
        Transform {
            scale: DVec3::new(-1.0, 2.0, 1.0),
            rotation_deg: DVec3::new(10.0, 20.0, 30.0),
            translation: DVec3::ZERO,
        },
    ];
    for t in transforms {
        let mut m =
            Mesh { positions: p.to_vec(), triangles: vec![[0, 1, 2]], normals: Some(vec![n; 3]), ..Default::default() };
        t.apply(&mut m);
        let [a, b, c] = m.triangle_positions(0);
        let geometric = (b - a).cross(c - a).normalize();
        for shading in m.normals.as_ref().unwrap() {
            assert!(close(*shading, geometric), "{t:?}: {shading} vs {geometric}");
        }
    }
    // Non-uniform scale: the plane x + y = 0 (normal (1,1,0)) scaled by 2 in x becomes
    // x/2 + y = 0, normal (1/2, 1, 0) normalised.
    let t = Transform { scale: DVec3::new(2.0, 1.0, 1.0), ..Default::default() };
    let mut m = single_vertex_mesh(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0).normalize());
    t.apply(&mut m);
    assert!(close(m.normals.unwrap()[0], DVec3::new(0.5, 1.0, 0.0).normalize()));
}

#[test]
fn transform_deserialises_with_defaults_and_rejects_unknown_fields() {
    let t: Transform = serde_json::from_str(r#"{"scale": [2, 2, 2]}"#).unwrap();
    assert_eq!(t.scale, DVec3::splat(2.0));
    assert_eq!(t.rotation_deg, DVec3::ZERO);
    assert_eq!(t.translation, DVec3::ZERO);
    let t: Transform = serde_json::from_str("{}").unwrap();
    assert_eq!(t, Transform::default());
    assert_eq!(t.scale, DVec3::ONE);
    let err = serde_json::from_str::<Transform>(r#"{"rotation": [0, 0, 90]}"#).unwrap_err();
    assert!(err.to_string().contains("rotation"), "{err}");
    let bad = Transform { scale: DVec3::new(1.0, 0.0, 1.0), ..Default::default() };
    let err = bad.validate("scene.yaml").unwrap_err().to_string();
    assert!(err.contains("scene.yaml") && err.contains("scale"), "{err}");
    let bad = Transform { translation: DVec3::new(f64::NAN, 0.0, 0.0), ..Default::default() };
    assert!(bad.validate("scene.yaml").unwrap_err().to_string().contains("translation"));
}

#[test]
fn mesh_validate_and_bounds() {
    let mut m = load("meshes/pyramid_ascii.ply").mesh;
    assert_eq!(m.bounds(), (DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 2.0)));
    m.triangles.push([0, 1, 9]);
    let err = m.validate("pyr").unwrap_err().to_string();
    assert!(err.contains("pyr") && err.contains("triangle 6") && err.contains("9"), "{err}");
    m.triangles.pop();
    m.positions[2].y = f64::INFINITY;
    let err = m.validate("pyr").unwrap_err().to_string();
    assert!(err.contains("vertex 2"), "{err}");
    assert!(Mesh::default().validate("empty").is_err());
}

#[test]
fn tessellated_rectangle_recovers_local_coordinates() {
    let center = DVec3::new(1.0, -2.0, 100.0);
    let half_u = DVec3::new(30.0, 0.0, 5.0);
    let half_v = DVec3::new(0.0, 20.0, 0.0);
    let n = 3;
    let m = tessellate_rect(center, half_u, half_v, n);
    assert_eq!(m.positions.len(), 16);
    assert_eq!(m.triangles.len(), 18);
    m.validate("rect").unwrap();
    // Area of the tessellation = area of the rectangle, 4 |half_u x half_v|; all triangles
    // face along half_u x half_v.
    let normal = half_u.cross(half_v);
    let mut area = 0.0;
    for t in 0..m.triangles.len() {
        let [a, b, c] = m.triangle_positions(t);
        let cr = (b - a).cross(c - a);
        assert!(cr.dot(normal) > 0.0);
        area += 0.5 * cr.length();
    }
    assert!((area - 4.0 * normal.length()).abs() < 1e-9 * area);
    // A ray hitting the point with local coordinates (s, t) hits a triangle whose interpolated
    // uv is (s, t).
    let brute = BruteForce::new(&[(0, &m)]).unwrap();
    let uvs = m.uvs.as_ref().unwrap();
    for (s, t) in [(0.1, 0.2), (-0.77, 0.5), (0.95, -0.95), (-0.3, -0.6), (0.5, 0.123)] {
        let target = center + s * half_u + t * half_v;
        let origin = DVec3::new(0.5, 0.25, 0.0);
        let hit = brute.intersect(&Ray { origin, dir: target - origin }, f64::INFINITY).expect("hit");
        assert!((hit.t - 1.0).abs() < 1e-12, "t = {}", hit.t);
        let Surface::Triangle { index, bary } = hit.surface else { panic!("not a triangle") };
        let uv = m.interpolate(uvs, index, bary);
        assert!((uv - DVec2::new(s, t)).abs().max_element() < 1e-12, "({s}, {t}) -> {uv}");
    }
    // n = 0 is taken as 1.
    assert_eq!(tessellate_rect(center, half_u, half_v, 0).triangles.len(), 2);
}
