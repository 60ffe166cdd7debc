//! The schematic eyes inside the measurement (docs/EYE.md): invariants that would fail if a
//! real eye's rays entered the estimators wrongly.
//! - A uniform scene seen through any eye model gives a uniform retinal image (ground truth, grid
//!   and converged, single wavelength and the display primaries, with Stiles-Crawford).
//! - A schematic eye made thin and aberration-free on axis (a reduced eye: one ellipsoidal
//!   surface with the iris at its vertex, a flat retina at its focus) reproduces the thin-lens
//!   eye's Table 1 within the intervals, over a small field and pupil.
//! - The thin lens through the generic path (Stiles-Crawford with rho = 0) equals its fast path.

use std::path::Path;

use glam::{DVec2, DVec3};
use inimtrace::experiment::{assess_images, RunOptions};
use inimtrace::measure::estimator::{DisplaySource, Replicates};
use inimtrace::measure::sampler::Sampler;
use inimtrace::optics::eye::{EyeModel, EyeOptics, EyeOpticsSpec, FocusCriterion};
use inimtrace::optics::spectrum::Primaries;
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::overrides::Override;
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::ray::Ray;
use inimtrace::render::retina::{ground_truth, DisplayStack};
use inimtrace::render::RadianceField;
use inimtrace::settings::load_experiment;

/// A scene of one colour in every direction.
struct Uniform(DVec3);

impl RadianceField for Uniform {
    fn radiance(&self, _ray: &Ray) -> DVec3 {
        self.0
    }
}

fn spec(model: EyeModel, primaries: bool, stiles_crawford: Option<(f64, DVec2)>) -> EyeOpticsSpec {
    EyeOpticsSpec {
        model,
        criterion: FocusCriterion::Paraxial,
        reference_nm: 555.0,
        primaries,
        wavelength_samples: 3,
        stiles_crawford,
        diffraction: Default::default(),
    }
}

fn eye_with(spec: &EyeOpticsSpec, focus_diopters: f64) -> Eye {
    let mut eye = Eye::thin_lens(5.0, Focus::Diopters(focus_diopters), 4);
    eye.optics = EyeOptics::build(spec, &eye.aperture, 17.0, &Primaries::default(), 0.5, "test", "focus").unwrap();
    eye
}

#[test]
fn a_uniform_scene_looks_uniform_through_every_eye_model() {
    let colour = DVec3::new(0.8, 0.5, 0.2);
    let field = Uniform(colour);
    let retina = Retina { resolution: 12, half_tangent: 0.3, samples_per_pixel: 2 };
    let models = [EyeModel::Navarro1985, EyeModel::Navarro1999, EyeModel::Arizona];
    let sc = Some((0.05, DVec2::ZERO));
    for model in models {
        for (primaries, sce) in [(false, None), (true, None), (true, sc)] {
            let s = spec(model.clone(), primaries, sce);
            let eye = eye_with(&s, 2.5);
            let gt = ground_truth(&eye, &retina, &field, &Progress::hidden());
            for p in &gt.pixels {
                for c in 0..3 {
                    assert!((f64::from(p[c]) - colour[c]).abs() < 1e-6, "{model:?} {primaries} {sce:?}: {p:?}");
                }
            }
        }
    }
    // Le Grand does not accommodate: at its own focus.
    let s = spec(EyeModel::LeGrand, true, sc);
    let mut eye = Eye::pinhole();
    eye.optics = EyeOptics::build(&s, &eye.aperture, 17.0, &Primaries::default(), 0.5, "test", "focus").unwrap();
    let gt = ground_truth(&eye, &retina, &field, &Progress::hidden());
    for (i, p) in gt.pixels.iter().enumerate() {
        assert!((f64::from(p[1]) - 0.5).abs() < 1e-6, "pixel {i}: {p:?}");
    }
}

#[test]
fn a_uniform_scene_and_a_uniform_display_look_uniform_in_the_converged_measurement() {
    let mut display = Display::paper();
    display.lcd.resolution = [540, 540];
    let white = RgbImage::filled(540, 540, [0.25, 0.5, 1.0]);
    let stack = DisplayStack::new(&display, &[&white]).unwrap();
    let field = Uniform(DVec3::new(0.25, 0.5, 1.0));
    // The central field: every ray there reaches the LCD.
    let retina = Retina { resolution: 8, half_tangent: 0.1, samples_per_pixel: 1 };
    for (primaries, sce) in [(false, None), (true, Some((0.05, DVec2::ZERO)))] {
        let s = spec(EyeModel::Navarro1985, primaries, sce);
        let eye = eye_with(&s, 2.5);
        let source = DisplaySource::new(&display, &eye, &field, &stack);
        let sampler = Sampler::new(1, 0, Some(2.5));
        let mut reps = Replicates::new(8, 3, 2);
        reps.extend(&source, &sampler, &retina, 16, &Progress::hidden());
        for k in 0..2 {
            let img = reps.mean_image(k);
            for p in &img.pixels {
                assert!(
                    (p[0] - 0.25).abs() < 1e-6 && (p[1] - 0.5).abs() < 1e-6 && (p[2] - 1.0).abs() < 1e-6,
                    "{k}: {p:?}"
                );
            }
        }
    }
}

fn overrides(list: &[String]) -> Vec<Override> {
    list.iter().map(|s| s.parse().unwrap()).collect()
}

fn small_paper(extra: &[String]) -> Vec<Override> {
    let mut set: Vec<String> = [
        "display.lcd.resolution=[540, 540]",
        "eye.retina_resolution=48",
        "measurement.max_samples_per_pixel=256",
        "measurement.psnr_ci95_db=0.05",
        "measurement.ssim_ci95=0.005",
        r#"eye_cases=[{ name = "Inf", focus_diopters = 0.0 }]"#,
        "eye.pupil_diameter=2.0",
        "eye.retina_half_tangent=0.08",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    set.extend(extra.iter().cloned());
    overrides(&set)
}

#[test]
fn a_thin_aberration_free_schematic_eye_reproduces_the_thin_lens_within_the_intervals() {
    // A reduced eye (one refracting surface, the iris just in front of it) whose surface is the
    // ellipsoid Q = -1/n^2 that images infinity without aberration onto the axis (Descartes'
    // oval for infinity), a flat retina at its focal distance n R / (n - 1): focused at
    // infinity, free of spherical aberration, thin (the stop at the surface).
    let (n, r) = (1.336f64, 5.55f64);
    // The iris 0.05 mm in front of the surface, behind a plane "window" of air.
    let user = format!(
        "eye.user={{ retina_radius = 0.0, iris = {{ after = \"0\", distance = 0.05 }}, surfaces = [\
         {{ radius = 0.0, thickness = 0.1, semi_diameter = 5.0, medium = {{ constant = 1.0 }} }}, \
         {{ radius = {r}, conic = {}, thickness = {}, semi_diameter = 5.0, medium = {{ constant = {n} }} }}] }}",
        -1.0 / (n * n),
        n * r / (n - 1.0)
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper-converged.toml");
    let thin = load_experiment(Some(&path), None, &small_paper(&[])).unwrap();
    let schematic = load_experiment(
        Some(&path),
        None,
        &small_paper(&["eye.model=\"user\"".into(), user, "eye.spectrum=\"single\"".into()]),
    )
    .unwrap();
    assert!(schematic.cases[0].eye.optics.is_some());
    let opts = || RunOptions { quiet: true, ..Default::default() };
    let a = assess_images(&thin, None, opts()).unwrap();
    let b = assess_images(&schematic, None, opts()).unwrap();
    for (x, y) in a.report.scores.iter().zip(&b.report.scores) {
        let (cx, cy) = (x.psnr.ci95.unwrap(), y.psnr.ci95.unwrap());
        // Independent samples (different eyes, same seeds): agreement within the combined
        // interval, with a floor for the eyes' residual differences (thickness, distortion).
        let bound = 2.0 * (cx * cx + cy * cy).sqrt() + 0.05;
        assert!(
            (x.psnr.mean - y.psnr.mean).abs() < bound,
            "{}: {} vs {} (bound {bound})",
            x.method,
            x.psnr.mean,
            y.psnr.mean
        );
        let (sx, sy) = (x.ssim.ci95.unwrap(), y.ssim.ci95.unwrap());
        let bound = 2.0 * (sx * sx + sy * sy).sqrt() + 0.002;
        assert!((x.ssim.mean - y.ssim.mean).abs() < bound, "{}: {} vs {}", x.method, x.ssim.mean, y.ssim.mean);
    }
}

#[test]
fn the_thin_lens_through_the_generic_path_equals_its_fast_path() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let base = [
        "display.lcd.resolution=[540, 540]".to_string(),
        "eye.retina_resolution=32".into(),
        "eye.pupil_grid=4".into(),
        r#"eye_cases=[{ name = "Near", focus_diopters = 3.0 }, { name = "Pin", pinhole = true }]"#.into(),
    ];
    let fast = load_experiment(Some(&path), None, &overrides(&base)).unwrap();
    let mut with = base.to_vec();
    with.push("eye.stiles_crawford_rho=0.0".into());
    let generic = load_experiment(Some(&path), None, &overrides(&with)).unwrap();
    assert!(fast.cases[0].eye.optics.is_none() && generic.cases[0].eye.optics.is_some());
    let opts = || RunOptions { quiet: true, ..Default::default() };
    let a = assess_images(&fast, None, opts()).unwrap();
    let b = assess_images(&generic, None, opts()).unwrap();
    let images = |x: &inimtrace::experiment::Assessment| -> Vec<RgbImage> {
        x.ground_truths.iter().chain(x.perceived.iter().flatten()).cloned().collect()
    };
    // The same rays in another order of operations: a sample may land on the other side of an
    // LCD pixel or chart edge by rounding, nothing more.
    for (k, (ia, ib)) in images(&a).iter().zip(&images(&b)).enumerate() {
        let differ =
            ia.pixels.iter().zip(&ib.pixels).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-5)).count();
        assert!(differ * 100 <= ia.pixels.len(), "image {k}: {differ} pixels differ");
        for (p, q) in ia.pixels.iter().zip(&ib.pixels) {
            assert!((0..3).all(|c| (p[c] - q[c]).abs() <= 0.25), "image {k}: {p:?} vs {q:?}");
        }
    }
}

#[test]
fn ray_aiming_finds_every_ray_inside_the_iris_over_the_field_and_the_visible() {
    // Every retina point of the field (tangents to 0.42, many tiny ones near the axis) through
    // every iris point of a 6 mm entrance pupil, at wavelengths across the primaries: ray aiming
    // must find the ray (nothing in these eyes blocks it), so no sample turns black by a failed
    // aim. Then it traces back in to the same retina point.
    use inimtrace::optics::eye::SchematicEye;
    for model in [EyeModel::Navarro1985, EyeModel::Navarro1999, EyeModel::Arizona, EyeModel::LeGrand] {
        let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
        let iris_r = 0.5 * eye.iris_diameter(6.0);
        let mut failed = 0;
        let mut total = 0;
        for nm in [440.0, 480.0, 535.0, 555.0, 610.0, 650.0] {
            let at = eye.at(nm);
            for it in 0..40 {
                let tau = if it < 10 { 1e-4 * it as f64 } else { 0.42 * (it - 9) as f64 / 30.0 };
                for ia in 0..7 {
                    let angle = 0.9 * ia as f64;
                    let tangent = tau * DVec2::new(angle.cos(), angle.sin());
                    let retina = eye.retina_point(tangent);
                    for ip in 0..25 {
                        let (px, py) = ((ip % 5) as f64 / 2.0 - 1.0, (ip / 5) as f64 / 2.0 - 1.0);
                        let iris = DVec2::new(px, py) * iris_r * 0.7;
                        total += 1;
                        match at.ray_out(retina, iris) {
                            None => {
                                if failed < 6 {
                                    eprintln!("FAIL {model:?} {nm} {tangent} {iris}");
                                }
                                failed += 1
                            }
                            Some(ray) => {
                                let (back, _) = at.ray_in(ray).expect("the found ray comes back in");
                                assert!((back - retina).length() < 1e-9, "{model:?} {nm} {tangent} {iris}");
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(failed, 0, "{model:?}: {failed} of {total} aims failed");
    }
}

#[test]
fn an_eye_whose_iris_lies_inside_a_surface_is_refused_naming_the_iris() {
    // The iris in the vertex plane of the surface it follows, a surface convex toward the air:
    // off the axis the surface lies behind that plane, so the iris would be inside the cornea
    // and no ray reaches the air through it. Refused by the geometric rules (optics/clearance.rs)
    // before any ray is traced.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let user = "eye.user={ retina_radius = 0.0, iris = { after = \"0\", distance = 0.0 }, surfaces = [\
                { radius = 5.55, conic = -0.56, thickness = 22.07, semi_diameter = 5.0, medium = { constant = 1.336 } }] }";
    let set =
        overrides(&["eye.model=\"user\"".into(), user.into(), r#"eye_cases=[{ name = "P", pinhole = true }]"#.into()]);
    let err = load_experiment(Some(&path), None, &set).unwrap_err().to_string();
    assert!(err.contains("eye.iris.distance") && err.contains("inside a surface"), "{err}");
}

#[test]
fn the_single_stage_commands_take_the_eye_model_and_name_an_unreachable_focus() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace")).arg("--quiet").args(args).output().unwrap()
    };
    let (navarro, thin) = (dir.path().join("n.exr"), dir.path().join("t.exr"));
    let base = ["ground-truth", "--focus-diopters", "2.5", "--retina", "24", "--pupil-grid", "3"];
    let n = run(&[&base[..], &["--eye-model", "navarro", "--out", navarro.to_str().unwrap()]].concat());
    assert!(n.status.success(), "{}", String::from_utf8_lossy(&n.stderr));
    assert!(run(&[&base[..], &["--out", thin.to_str().unwrap()]].concat()).status.success());
    // The real eye's chromatic and spherical aberration blur the chart: not the thin lens's image.
    assert_ne!(std::fs::read(&navarro).unwrap(), std::fs::read(&thin).unwrap());
    let far =
        run(&["ground-truth", "--focus-diopters", "0", "--retina", "24", "--eye-model", "navarro", "--out", "x.exr"]);
    let err = String::from_utf8_lossy(&far.stderr);
    assert_eq!(far.status.code(), Some(1));
    assert!(err.contains("--focus-diopters") && err.contains("out of reach"), "{err}");
}

#[test]
fn the_single_stage_commands_take_the_display_files_primaries() {
    // A display whose three primaries are all one narrow line at 555 nm: a polychromatic
    // schematic eye then sees every channel at 555 nm, so its ground truth is the
    // single-wavelength one at 555 nm (to the line's 1 nm width), while the default primaries
    // (610 / 535 / 450 nm) give the eye's chromatic aberration.
    let dir = tempfile::tempdir().unwrap();
    let display = dir.path().join("narrow.toml");
    let base = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/displays/paper.toml")).unwrap();
    let line = "{ peak_nm = 555.0, fwhm_nm = 1.0 }";
    std::fs::write(&display, format!("{base}\n[primaries]\nred = {line}\ngreen = {line}\nblue = {line}\n")).unwrap();
    let run = |args: &[&str]| {
        let out =
            std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace")).arg("--quiet").args(args).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    };
    let image = |name: &str| inimtrace::io::exr::read_rgb(&dir.path().join(name)).unwrap();
    let common =
        ["ground-truth", "--focus-diopters", "2.5", "--retina", "24", "--pupil-grid", "3", "--eye-model", "navarro"];
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let d = display.to_str().unwrap();
    run(&[&common[..], &["--display", d, "--spectrum", "primaries", "--out", &path("p.exr")]].concat());
    run(&[&common[..], &["--display", d, "--spectrum", "single", "--out", &path("s.exr")]].concat());
    run(&[&common[..], &["--spectrum", "primaries", "--out", &path("d.exr")]].concat());
    let (p, s, default) = (image("p.exr"), image("s.exr"), image("d.exr"));
    // Mean absolute differences (a sample of the grid estimator's 3 x 3 x 3 crossing a bar's
    // edge moves a pixel by 1/27).
    let mean = |a: &inimtrace::raster::RgbImage, b: &inimtrace::raster::RgbImage| {
        let d: f32 = a.pixels.iter().flatten().zip(b.pixels.iter().flatten()).map(|(x, y)| (x - y).abs()).sum();
        d / (3 * a.pixels.len()) as f32
    };
    let (narrow, wide) = (mean(&p, &s), mean(&default, &s));
    assert!(wide > 1e-2 && narrow < 0.05 * wide, "{narrow} {wide}");
}

#[test]
fn two_samples_at_once_give_the_rays_of_one_at_a_time_bit_for_bit() {
    // The slow twin is `EyeOptics::rays`. Every kind of eye that reaches it: schematic with the
    // fitted map (one wavelength, primaries, Stiles-Crawford with an off-centre peak), samples
    // beyond the map's field (aimed exactly), and the thin lens with Stiles-Crawford.
    let sc = Some((0.05, DVec2::new(0.4, -0.2)));
    let specs = [
        spec(EyeModel::Navarro1985, false, None),
        spec(EyeModel::Navarro1985, true, None),
        spec(EyeModel::Navarro1985, true, sc),
        spec(EyeModel::ThinLens, false, sc),
    ];
    let bits = |r: &Option<inimtrace::optics::PlaneRay>| {
        r.map(|r| [r.position.x, r.position.y, r.slope.x, r.slope.y].map(f64::to_bits))
    };
    for s in &specs {
        let eye = eye_with(s, 2.5);
        let optics = eye.optics.as_ref().expect("not the thin lens's fast path");
        let mut h = 5u64;
        let mut next = || {
            h = h.wrapping_add(0x9e37_79b9_7f4a_7c15); // splitmix64
            let mut z = h;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..300 {
            let mut sample = || {
                let reach = if i % 5 == 0 { 0.7 } else { 0.45 }; // beyond the map's 0.5 at times
                let t = DVec2::new(reach * (2.0 * next() - 1.0), reach * (2.0 * next() - 1.0));
                let p = 2.5 * next().sqrt() * DVec2::from_angle(std::f64::consts::TAU * next());
                (t, p, next())
            };
            let (a, b) = (sample(), sample());
            let pair = optics.rays2(a, b);
            for (got, (t, p, u)) in pair.iter().zip([a, b]) {
                let want = optics.rays(t, p, u);
                assert_eq!(got.single, want.single);
                assert_eq!(got.weight.to_bits(), want.weight.to_bits());
                for (g, w) in got.rays.iter().zip(&want.rays) {
                    assert_eq!(bits(g), bits(w), "{:?} {t} {p} {u}", s.model);
                }
            }
        }
    }
}

#[test]
fn the_ray_maps_lockstep_evaluation_equals_one_sample_at_a_time_bit_for_bit() {
    // The slow twin: `RayMap::ray`, one sample at a time. Lanes of 2 and 3, one and three
    // wavelengths, and a lane outside the field (that lane declines, the others agree).
    use inimtrace::optics::eye::ray_map::RayMap;
    use inimtrace::optics::eye::SchematicEye;
    let pupil = 5.0;
    let (eye, _) =
        SchematicEye::focused(&EyeModel::Navarro1985, 3.0, 555.0, FocusCriterion::Paraxial, pupil, "t", "f").unwrap();
    let scale = eye.iris_diameter(pupil) / pupil;
    let map = RayMap::fit(&eye, 0.43, 0.5 * pupil, scale, (420.0, 680.0)).expect("the map is within tolerance");
    let bits = |r: &inimtrace::optics::PlaneRay| [r.position.x, r.position.y, r.slope.x, r.slope.y].map(f64::to_bits);
    // Weyl sequences (golden ratio and its square's fraction): points spread over the domain.
    let frac = |i: usize, a: f64| (0.5 + a * i as f64).fract();
    let point = |i: usize| {
        let t = DVec2::new(0.6 * frac(i, 0.754_877_666) - 0.3, 0.6 * frac(i, 0.569_840_290) - 0.3);
        let p = 2.5 * frac(i, 0.618_033_989).sqrt() * DVec2::from_angle(std::f64::consts::TAU * frac(i, 0.414_213_562));
        // Inside the fitted range, 420-680 nm (a wavelength beyond is declined, below).
        let nm = [430.0 + 0.37 * i as f64, 540.0 + 0.11 * i as f64, 610.0 + 0.11 * i as f64];
        (t, p, nm)
    };
    // The map declines a wavelength outside its range (the caller aims that ray exactly).
    assert!(map.ray(DVec2::new(0.1, 0.0), DVec2::new(1.0, 0.0), [700.0]).is_none());
    assert!(map.ray(DVec2::new(0.1, 0.0), DVec2::new(1.0, 0.0), [600.0]).is_some());
    for i in 0..200 {
        let [a, b, mut c] = [point(3 * i), point(3 * i + 1), point(3 * i + 2)];
        if i % 7 == 0 {
            c.0 = DVec2::new(0.44, 0.0); // outside the field
        }
        let three = map.rays([a.0, b.0, c.0], [a.1, b.1, c.1], [a.2, b.2, c.2]);
        let two = map.rays([a.0, b.0], [a.1, b.1], [[a.2[1]], [b.2[1]]]);
        for (lane, (t, p, nm)) in [a, b, c].into_iter().enumerate() {
            match (map.ray(t, p, nm), three[lane]) {
                (Some(one), Some(lock)) => {
                    for (x, y) in one.iter().zip(&lock) {
                        assert_eq!(bits(x), bits(y), "lane {lane} of point {i}");
                    }
                }
                (None, None) => assert_eq!(lane, 2),
                _ => panic!("lane {lane} of point {i}: one inside, the other outside"),
            }
            if lane < 2 {
                let [one] = map.ray(t, p, [nm[1]]).unwrap();
                let [lock] = two[lane].unwrap();
                assert_eq!(bits(&one), bits(&lock), "lane {lane} of point {i}, one wavelength");
            }
        }
    }
}
