//! Scenes beyond the paper's: mesh objects from files, the backend choice, lights and the
//! display image's depth (issue "Embree backend ... and complex triangle-mesh scenes").
#![cfg(feature = "embree")]
#![deny(unsafe_code)]

use std::path::{Path, PathBuf};

use glam::DVec3;
use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::accel::brute::BruteForce;
use inimtrace::io;
use inimtrace::metrics;
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::ray::{Intersector, Ray};
use inimtrace::render::backend::scene_meshes;
use inimtrace::render::retina::simulate;
use inimtrace::render::{
    ground_truth, render_display_image_with_depth, with_fields, BackendChoice, DisplayRenderSettings, Method,
    RadianceField, SceneTracer,
};
use inimtrace::scene::{Light, Mesh, Scene};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn small_display(res: usize) -> Display {
    let mut d = Display::paper();
    d.lcd.resolution = [res, res];
    d
}

fn load(text: &str, dir: &Path) -> inimtrace::Result<Scene> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    io::load_scene(&path.to_string_lossy(), Path::new(""))
}

/// Number of pixels whose channels differ by more than 1e-6.
fn differing(a: &RgbImage, b: &RgbImage) -> usize {
    a.pixels.iter().zip(&b.pixels).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-6)).count()
}

struct Rendered {
    displays: Vec<RgbImage>,
    depths: Vec<Option<Vec<f32>>>,
    gts: Vec<RgbImage>,
    sims: Vec<Vec<RgbImage>>,
    backend: &'static str,
}

/// Every image of a reduced assessment (LCD 540 x 540, retina 128, pupil grid 4) of `scene`.
fn render_all(scene: &Scene, choice: BackendChoice) -> Rendered {
    let display = small_display(540);
    let settings = DisplayRenderSettings::default();
    let methods = [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 3 }];
    let eyes = [
        Eye::pinhole(),
        Eye::thin_lens(5.0, Focus::Millimetres(300.0), 4),
        Eye::thin_lens(5.0, Focus::Millimetres(600.0), 4),
    ];
    let retina = Retina { resolution: 128, ..Retina::default() };
    with_fields(scene, choice, |fields| {
        let mut displays = Vec::new();
        let mut depths = Vec::new();
        for m in methods {
            let (img, z) =
                render_display_image_with_depth(&display, m, &settings, fields.with_depth, &Progress::hidden())?;
            displays.push(img);
            depths.push(z);
        }
        let refs: Vec<&RgbImage> = displays.iter().collect();
        let mut gts = Vec::new();
        let mut sims = Vec::new();
        for eye in &eyes {
            gts.push(ground_truth(eye, &retina, fields.shade, &Progress::hidden()));
            sims.push(simulate(&display, eye, &retina, &refs, &Progress::hidden())?);
        }
        Ok(Rendered { displays, depths, gts, sims, backend: fields.name })
    })
    .unwrap()
}

#[test]
fn paper_scene_through_embree_matches_the_analytic_backend() {
    let scene = Scene::paper();
    let exact = render_all(&scene, BackendChoice::Auto);
    let embree = render_all(&scene, BackendChoice::Embree);
    assert_eq!(exact.backend, "analytic (fused planar kernel)");
    assert_eq!(embree.backend, "embree");
    let mut report = Vec::new();
    let pairs = exact
        .displays
        .iter()
        .zip(&embree.displays)
        .map(|p| ("display", p))
        .chain(exact.gts.iter().zip(&embree.gts).map(|p| ("ground truth", p)))
        .chain(exact.sims.iter().flatten().zip(embree.sims.iter().flatten()).map(|p| ("simulated", p)));
    for (kind, (a, b)) in pairs {
        let psnr = metrics::psnr(a, b).unwrap().mean;
        let n = differing(a, b);
        report.push(format!("{kind}: PSNR {psnr:.1} dB, {n} of {} pixels differ", a.pixels.len()));
        assert!(psnr >= 50.0, "{kind}: PSNR {psnr} dB");
        // The differences are rays that graze an edge of a chart square or of a bar: Embree
        // rounds ray and vertices to f32 (relative 6e-8, i.e. ~3e-5 mm at 400 mm), so only rays
        // within that distance of an edge can change sides. That is a small fraction of pixels.
        assert!(n * 100 <= a.pixels.len(), "{kind}: {n} of {} pixels differ", a.pixels.len());
    }
    eprintln!("{}", report.join("\n"));
    // Depths: the same surfaces at the same distances (f32 t has ~1e-7 relative error).
    for (za, zb) in exact.depths.iter().zip(&embree.depths) {
        let (za, zb) = (za.as_ref().unwrap(), zb.as_ref().unwrap());
        let close = za.iter().zip(zb).filter(|(a, b)| (**a - **b).abs() <= 1e-3 * a.abs().max(1.0)).count();
        assert!(close * 100 >= 99 * za.len(), "{close} of {} depths agree", za.len());
        assert!(za.iter().all(|z| *z >= 300.0 && z.is_finite()), "every LCD ray of the paper scene hits");
    }
}

#[test]
fn lc_depth_is_the_distance_to_the_hit_plane() {
    // One wall at z = 500 facing the eye: LC's depth for a pixel is the length of its camera
    // ray from the pupil plane to z = 500, i.e. 500 * |dir| with dir = (slope, 1).
    let dir = tempfile::tempdir().unwrap();
    let scene = load(
        "name = \"wall\"\n[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 500]\nsize = [1e5, 1e5]\nmaterial = { albedo = [1, 1, 1] }\n",
        dir.path(),
    )
    .unwrap();
    let display = small_display(108);
    for choice in [BackendChoice::Analytic, BackendChoice::Embree] {
        let z = with_fields(&scene, choice, |f| {
            render_display_image_with_depth(
                &display,
                Method::LensletCenter,
                &DisplayRenderSettings::default(),
                f.with_depth,
                &Progress::hidden(),
            )
        })
        .unwrap()
        .1
        .unwrap();
        let (row, col) = (7, 93);
        let center = display.lcd.pixel_center(row, col);
        let c = display.lenslets.center(display.elemental_image_of(center));
        let ray = inimtrace::optics::transfer::camera_ray(&display, center, c, c, 0.0);
        let expected = 500.0 * ray.dir.length();
        assert!((z[row * 108 + col] as f64 - expected).abs() < 1e-3, "{choice}: {} vs {expected}", z[row * 108 + col]);
        assert!(z.iter().all(|v| *v >= 500.0 && v.is_finite()));
    }
}

#[test]
fn embree_and_brute_force_agree_on_a_small_lit_mesh_scene() {
    let dir = tempfile::tempdir().unwrap();
    let pyramid = root().join("tests/data/meshes/pyramid.obj");
    let text = format!(
        r#"name = "small"
allow_outside_paths = true
background = [0.05, 0.05, 0.05]
[light]
type = "distant"
direction = [0.2, -0.3, 1.0]
radiance = [1.0, 0.9, 0.8]
[[objects]]
type = "mesh"
file = "{}"
transform = {{ scale = [30, 30, 30], rotation_deg = [20, 30, 0], translation = [0, 0, 350] }}
material = {{ albedo = [0.9, 0.5, 0.2] }}
[[objects]]
type = "sphere-grid"
center = [0, 0, 420]
count = [3, 3]
spacing = 40
radius = 12
segments = 12
material = {{ albedo = [0.3, 0.8, 0.3] }}
[[objects]]
type = "rect"
center = [0, 0, 500]
size = [300, 300]
material = {{ chart = "usaf" }}
"#,
        pyramid.display()
    );
    let scene = load(&text, dir.path()).unwrap();
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 3);
    let retina = Retina { resolution: 96, ..Retina::default() };
    let images: Vec<RgbImage> = [BackendChoice::Embree, BackendChoice::Brute]
        .iter()
        .map(|c| with_fields(&scene, *c, |f| Ok(ground_truth(&eye, &retina, f.shade, &Progress::hidden()))).unwrap())
        .collect();
    let psnr = metrics::psnr(&images[0], &images[1]).unwrap().mean;
    let n = differing(&images[0], &images[1]);
    eprintln!("embree vs brute: PSNR {psnr:.1} dB, {n} of {} pixels differ", images[0].pixels.len());
    assert!(psnr >= 50.0, "PSNR {psnr}");
    assert!(n * 50 <= images[0].pixels.len(), "{n} pixels differ");
    // The scene is lit: something is in shadow (black) and something is not.
    assert!(images[0].pixels.iter().any(|p| p[0] > 0.2));
    assert!(images[0].pixels.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
}

#[test]
fn batched_tracing_gives_the_same_image_as_one_ray_at_a_time() {
    /// A field that only knows single rays (so renderers use the per-ray defaults).
    struct OneByOne<'a>(SceneTracer<'a, dyn Intersector>);
    impl RadianceField for OneByOne<'_> {
        fn radiance(&self, ray: &Ray) -> DVec3 {
            self.0.radiance(ray)
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = load(
        "name = \"s\"\n[light]\ntype = \"none\"\n[[objects]]\ntype = \"sphere-grid\"\ncenter = [0, 0, 400]\ncount = [5, 4]\nspacing = 30\nradius = 14\nsegments = 16\nmaterial = { albedo = [1, 0.5, 0.2] }\n",
        dir.path(),
    )
    .unwrap();
    let meshes = scene_meshes(&scene);
    let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
    let embree = inimtrace::accel::embree::EmbreeIntersector::new(&refs, Default::default()).unwrap();
    let tracer: SceneTracer<'_, dyn Intersector> = SceneTracer { scene: &scene, backend: &embree };
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 3);
    let retina = Retina { resolution: 64, ..Retina::default() };
    let batched = ground_truth(&eye, &retina, &tracer, &Progress::hidden());
    let single = ground_truth(&eye, &retina, &OneByOne(tracer), &Progress::hidden());
    assert!(batched == single, "packets and single rays must find the same hits");
    assert!(batched.pixels.iter().any(|p| p[0] == 1.0) && batched.pixels.iter().any(|p| p[0] == 0.0));
}

#[test]
fn lights_shade_lambertian_and_cast_shadows() {
    let mut scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let shade = |scene: &Scene, ray: Ray| {
        inimtrace::render::shade(scene, &ray, backend.intersect(&ray, f64::INFINITY).as_ref(), &backend)
    };
    // A point on the background square (z = 1302, albedo (0.2, 0.7, 0.8)) seen from the eye.
    let bg = Ray { origin: DVec3::ZERO, dir: DVec3::new(150.0, -300.0, 1302.0) / 1302.0 };
    // Unlit: albedo.
    assert_eq!(shade(&scene, bg), DVec3::new(0.2, 0.7, 0.8));
    // Light along +z: head-on, so radiance = albedo ...
    scene.light = Some(Light { direction: DVec3::Z, radiance: DVec3::ONE });
    assert_eq!(shade(&scene, bg), DVec3::new(0.2, 0.7, 0.8));
    // ... except in the shadow of a nearer chart. From the pupil centre every shadow of the
    // paper's scene is hidden behind the chart that casts it, so look from z = 700, between
    // the far chart (z = 600, x and y in 0..180) and the background: straight ahead at
    // (100, 100) is the background in the far chart's shadow; at (200, 200) it is lit.
    let from_behind = |x: f64, y: f64| Ray { origin: DVec3::new(x, y, 700.0), dir: DVec3::Z };
    assert_eq!(backend.intersect(&from_behind(100.0, 100.0), f64::INFINITY).unwrap().object, 3);
    assert_eq!(shade(&scene, from_behind(100.0, 100.0)), DVec3::ZERO);
    assert_eq!(shade(&scene, from_behind(200.0, 200.0)), DVec3::new(0.2, 0.7, 0.8));
    // An oblique light scales by the cosine, and light from behind a surface gives black.
    scene.light = Some(Light { direction: DVec3::new(0.0, 0.6, 0.8), radiance: DVec3::splat(2.0) });
    let lit = shade(&scene, bg);
    assert!((lit - DVec3::new(0.2, 0.7, 0.8) * 2.0 * 0.8).abs().max_element() < 1e-12, "{lit}");
    scene.light = Some(Light { direction: -DVec3::Z, radiance: DVec3::ONE });
    assert_eq!(shade(&scene, bg), DVec3::ZERO);
}

#[test]
fn bunny_scene_renders_without_nan_and_shows_the_bunny() {
    let path = root().join("scenes/bunny.toml");
    if !Path::new("/usr/share/glmark2/models/bunny.obj").exists() {
        eprintln!("skipped: install glmark2-data for the bunny");
        return;
    }
    let scene = io::load_scene(&path.to_string_lossy(), Path::new("")).unwrap();
    assert_eq!(scene.objects[0].name, "bunny");
    assert_eq!(scene.triangle_count(), 69_666 + 4);
    let display = small_display(270);
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(386.0), 3);
    let retina = Retina { resolution: 96, ..Retina::default() };
    let (gt, lc, z) = with_fields(&scene, BackendChoice::Auto, |f| {
        assert_eq!(f.name, "embree");
        let (lc, z) = render_display_image_with_depth(
            &display,
            Method::LensletAverage { grid: 2 },
            &DisplayRenderSettings::default(),
            f.with_depth,
            &Progress::hidden(),
        )?;
        Ok((ground_truth(&eye, &retina, f.shade, &Progress::hidden()), lc, z.unwrap()))
    })
    .unwrap();
    for img in [&gt, &lc] {
        assert!(img.pixels.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    }
    assert!(z.iter().all(|v| !v.is_nan()));
    // The centre of the view is the bunny (albedo (0.8, 0.6, 0.45) times the light's cosine):
    // red > green > blue there, unlike the chart (grey) and the background (cyan).
    let c = gt.pixels[48 * 96 + 48];
    assert!(c[0] > c[1] && c[1] > c[2] && c[0] > 0.1, "{c:?}");
    // Random rays, including degenerate ones, never give NaN.
    with_fields(&scene, BackendChoice::Embree, |f| {
        let mut s = 3u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for i in 0..20_000 {
            let dir = match i % 100 {
                0 => DVec3::ZERO,
                1 => DVec3::new(f64::NAN, 0.0, 1.0),
                _ => DVec3::new(next(), next(), next() + 0.7),
            };
            let ray = Ray { origin: DVec3::new(40.0 * next(), 40.0 * next(), 300.0 * next()), dir };
            let v = f.shade.radiance(&ray);
            assert!(v.is_finite(), "{ray:?} -> {v}");
        }
        Ok(())
    })
    .unwrap();
}

#[test]
fn mesh_objects_load_with_transform_and_materials() {
    let dir = tempfile::tempdir().unwrap();
    let ply = root().join("tests/data/meshes/pyramid_le.ply");
    let scene = load(
        &format!(
            "name = \"m\"\nallow_outside_paths = true\n[[objects]]\ntype = \"mesh\"\nfile = \"{}\"\ntransform = {{ scale = [2, 2, 2], translation = [0, 0, 100] }}\nmaterial = {{ albedo = [0.5, 0.5, 0.5] }}\n",
            ply.display()
        ),
        dir.path(),
    )
    .unwrap();
    let raw = io::load_mesh(&ply).unwrap().mesh;
    let inimtrace::scene::Shape::Mesh(m) = &scene.objects[0].shape else { panic!() };
    assert_eq!(m.triangles.len(), raw.triangles.len());
    assert_eq!(m.positions[0], raw.positions[0] * 2.0 + DVec3::new(0.0, 0.0, 100.0));
    // A mesh scene without `[light]` is lit from the eye.
    assert_eq!(scene.light, Some(inimtrace::io::scene_file::DEFAULT_LIGHT));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Relative paths resolve against the scene file's directory.
    std::fs::copy(root().join("tests/data/meshes/pyramid.obj"), dir.path().join("p.obj")).unwrap();
    let s2 = load(
        "name = \"m\"\n[[objects]]\ntype = \"mesh\"\nfile = \"p.obj\"\nmaterial = { albedo = [1, 1, 1] }\n",
        dir.path(),
    )
    .unwrap();
    assert!(!s2.is_analytic());
    assert_eq!(inimtrace::render::backend::resolve(&s2, BackendChoice::Auto), BackendChoice::Embree);
    assert_eq!(inimtrace::render::backend::resolve(&Scene::paper(), BackendChoice::Auto), BackendChoice::Analytic);
    // The analytic backend refuses meshes with a clear message.
    let e = with_fields(&s2, BackendChoice::Analytic, |_| Ok(())).unwrap_err().to_string();
    assert!(e.contains("analytic") && e.contains("embree"), "{e}");
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("d.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n")
        .unwrap();
    let scene = load(
        "name = \"d\"\n[[objects]]\ntype = \"mesh\"\nfile = \"d.obj\"\nmaterial = { albedo = [1, 1, 1] }\n",
        dir.path(),
    )
    .unwrap();
    assert_eq!(scene.triangle_count(), 1);
    assert_eq!(scene.warnings.len(), 1);
    assert!(
        scene.warnings[0].contains("dropped 2 degenerate") && scene.warnings[0].contains("d.obj"),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn textures_are_looked_up_through_uvs() {
    let dir = tempfile::tempdir().unwrap();
    // A quad with uvs (0,0) bottom left .. (1,1) top right, and a 2 x 1 texture: red | blue.
    std::fs::write(
        dir.path().join("q.obj"),
        "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    let img = image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 0, 255]).unwrap();
    img.save(dir.path().join("t.png")).unwrap();
    let scene = load(
        "name = \"t\"\n[[objects]]\ntype = \"mesh\"\nfile = \"q.obj\"\ntransform = { translation = [0, 0, 200] }\nmaterial = { texture = \"t.png\", filter = \"nearest\" }\n",
        dir.path(),
    )
    .unwrap();
    with_fields(&scene, BackendChoice::Embree, |f| {
        let left = f.shade.radiance(&Ray { origin: DVec3::ZERO, dir: DVec3::new(-0.1, 0.05, 1.0) });
        let right = f.shade.radiance(&Ray { origin: DVec3::ZERO, dir: DVec3::new(0.1, -0.05, 1.0) });
        assert_eq!(left, DVec3::X);
        assert_eq!(right, DVec3::Z);
        Ok(())
    })
    .unwrap();
}

#[test]
fn bad_mesh_scenes_name_the_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("scene.toml");
    let obj = |file: &str, material: &str| {
        format!("name = \"b\"\nallow_outside_paths = true\n[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\nmaterial = {material}\n")
    };
    let bad = root().join("tests/data/bad");
    // A mesh with neither vertex colours nor uvs.
    std::fs::write(dir.path().join("plain.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let cases: Vec<(String, Vec<String>)> = vec![
        (obj("missing.obj", "{ albedo = [1, 1, 1] }"), vec!["objects[0].file".into(), "missing.obj".into()]),
        (
            obj(&bad.join("index_out_of_range.ply").to_string_lossy(), "{ albedo = [1, 1, 1] }"),
            vec!["objects[0].file".into(), "index_out_of_range.ply".into()],
        ),
        (
            obj(&bad.join("inf_vertex.ply").to_string_lossy(), "{ albedo = [1, 1, 1] }"),
            vec!["objects[0].file".into(), "inf_vertex.ply".into()],
        ),
        (
            obj("plain.obj", "{ vertex_color = true }"),
            vec!["objects[0].material.vertex_color".into(), "no per-vertex colours".into()],
        ),
        (
            obj("plain.obj", "{ texture = \"t.png\" }"),
            vec!["objects[0].material.texture".into(), "no texture coordinates".into()],
        ),
        (
            "name = \"b\"\n[[objects]]\ntype = \"mesh\"\nmaterial = { albedo = [1, 1, 1] }\n".into(),
            vec!["objects[0].file".into(), "missing".into()],
        ),
        (
            "name = \"b\"\n[[objects]]\ntype = \"mesh\"\nfile = \"x.obj\"\ncenter = [0, 0, 0]\nmaterial = { albedo = [1, 1, 1] }\n"
                .into(),
            vec!["objects[0].center".into()],
        ),
        (
            format!(
                "name = \"b\"\nallow_outside_paths = true\n[[objects]]\ntype = \"mesh\"\nfile = \"{}\"\ntransform = {{ scale = [0, 1, 1] }}\nmaterial = {{ albedo = [1, 1, 1] }}\n",
                root().join("tests/data/meshes/pyramid.obj").display()
            ),
            vec!["objects[0].transform.scale".into()],
        ),
        (
            "name = \"b\"\n[light]\ntype = \"distant\"\ndirection = [0, 0, 0]\nradiance = [1, 1, 1]\n[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 1]\nsize = [1, 1]\nmaterial = { albedo = [1, 1, 1] }\n"
                .into(),
            vec!["light.direction".into()],
        ),
        (
            "name = \"b\"\n[[objects]]\ntype = \"sphere-grid\"\ncenter = [0, 0, 1]\ncount = [0, 3]\nradius = 1\nspacing = 2\nmaterial = { albedo = [1, 1, 1] }\n"
                .into(),
            vec!["objects[0].count".into()],
        ),
    ];
    for (text, needles) in cases {
        let e = load(&text, dir.path()).unwrap_err().to_string();
        assert!(e.contains(&*scene_path.to_string_lossy()), "error does not name the scene file: {e}");
        for n in &needles {
            assert!(e.contains(n.as_str()), "error lacks `{n}`: {e}");
        }
    }
    // A malformed OBJ line is reported with its line number.
    std::fs::write(dir.path().join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n").unwrap();
    let e = load(&obj("bad.obj", "{ albedo = [1, 1, 1] }"), dir.path()).unwrap_err().to_string();
    assert!(e.contains("bad.obj") && e.contains("line 3"), "{e}");
}

#[test]
fn brute_force_backend_refuses_big_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = load(
        "name = \"big\"\n[[objects]]\ntype = \"sphere-grid\"\ncenter = [0, 0, 400]\ncount = [10, 10]\nspacing = 5\nradius = 2\nsegments = 32\nmaterial = { albedo = [1, 1, 1] }\n",
        dir.path(),
    )
    .unwrap();
    let e = with_fields(&scene, BackendChoice::Brute, |_| Ok(())).unwrap_err().to_string();
    assert!(e.contains("brute") && e.contains("96000"), "{e}");
    let _ = BruteForce::new(&[]).unwrap();
}

#[test]
fn display_exr_gets_a_z_channel_with_inf_for_misses() {
    // A small square: most LCD rays miss it (Z = +inf), the ones that hit see z = 300.
    let dir = tempfile::tempdir().unwrap();
    let scene = load(
        "name = \"sq\"\n[[objects]]\ntype = \"rect\"\ncenter = [0, 0, 300]\nsize = [40, 40]\nmaterial = { albedo = [1, 1, 1] }\n",
        dir.path(),
    )
    .unwrap();
    let display = small_display(216);
    for choice in [BackendChoice::Analytic, BackendChoice::Embree] {
        let (img, z) = with_fields(&scene, choice, |f| {
            render_display_image_with_depth(
                &display,
                Method::LensletAverage { grid: 2 },
                &DisplayRenderSettings::default(),
                f.with_depth,
                &Progress::hidden(),
            )
        })
        .unwrap();
        let z = z.unwrap();
        let path = dir.path().join(format!("{choice}.exr"));
        inimtrace::io::exr::write_rgb(&path, &img, Some(&z), &[]).unwrap();
        let (back, zb) = inimtrace::io::exr::read_rgb_depth(&path).unwrap();
        assert!(back == img);
        let zb = zb.unwrap();
        assert_eq!(zb, z);
        let (mut hit, mut miss) = (0, 0);
        for (p, d) in img.pixels.iter().zip(&zb) {
            if p[0] == 0.0 {
                assert_eq!(*d, f32::INFINITY, "{choice}: a pixel whose rays all miss has Z = +inf");
                miss += 1;
            } else {
                assert!(*d >= 300.0 && *d < 330.0, "{choice}: {d}");
                hit += 1;
            }
        }
        assert!(hit > 100 && miss > 100, "{hit} {miss}");
    }
}

#[test]
fn cli_reports_backend_and_degenerate_triangles() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("d.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n").unwrap();
    std::fs::write(
        dir.path().join("d.toml"),
        "name = \"d\"\n[[objects]]\ntype = \"mesh\"\nfile = \"d.obj\"\ntransform = { scale = [100, 100, 100], translation = [0, 0, 300] }\nmaterial = { albedo = [1, 1, 1] }\n",
    )
    .unwrap();
    let run = |backend: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace"))
            .args(["ground-truth", "--pinhole", "--retina", "16", "--backend", backend, "--scene"])
            .arg(dir.path().join("d.toml"))
            .arg("-o")
            .arg(dir.path().join(format!("gt_{backend}.exr")))
            .output()
            .unwrap()
    };
    let ok = run("auto");
    let err = String::from_utf8_lossy(&ok.stderr);
    assert!(ok.status.success(), "{err}");
    assert!(err.contains("warning:") && err.contains("dropped 1 degenerate"), "{err}");
    assert!(err.contains("backend: embree (picked by auto"), "{err}");
    let attrs = inimtrace::io::exr::read_attributes(&dir.path().join("gt_auto.exr")).unwrap();
    assert!(attrs.iter().any(|(k, v)| k == "inimtrace:backend" && v == "embree"), "{attrs:?}");
    let bad = run("analytic");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("analytic backend cannot intersect"));
    assert!(!run("warp").status.success());
}
