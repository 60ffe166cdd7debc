//! OPT (docs/OPTIMAL.md) beyond the paraxial display and the ray-only eye: through real (thick)
//! lenslets and with diffraction at the apertures. Its display image is solved for, never another
//! method's: it differs from LC's (and from LA's, where it starts), and on every training state its
//! perceived image, as the simulation it was trained on sees it (the eye state's operator `A_s`,
//! docs/OPTIMAL.md), is at least as close to that state's ground truth as LA's. The render layer
//! refuses OPT instead of answering with another method's image.
#![deny(unsafe_code)]

use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::experiment::{Experiment, ExperimentSpec};
use inimtrace::optics::lenslet::{LensletOptics, Material, ThickLenslet};
use inimtrace::optics::Display;
use inimtrace::optimize::{EyeOperator, Operator, OptimizeSpec, Rgb};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::render::{ground_truth, render_display_image, FacingPlanes, Method, RadianceField};
use inimtrace::scene::Scene;

/// The paper's display on an LCD of 108 x 108 pixels of 0.2 mm, with paraxial lenslets or (as
/// displays/paper-pmma.toml) PMMA plano-convex ones.
fn display(thick: bool) -> Display {
    let mut d = Display::paper();
    d.lcd.resolution = [108, 108];
    if thick {
        d.lenslet = LensletOptics::Thick(Box::new(ThickLenslet::plano_convex(Material::pmma(), 6.427, 1.0)));
        d.lenslets_to_lcd = 5.6451;
    }
    d
}

/// A small experiment on `display`: LC, LA 3 x 3 and OPT, a 20 x 20 retina, trained on Pin and Cen
/// with a 3 x 3 pupil grid; `diffraction`: `[optics] diffraction`.
fn experiment(display: Display, diffraction: Option<&str>) -> Experiment {
    let mut spec = ExperimentSpec::paper_converged();
    spec.methods = vec!["LC".into(), "LA3".into(), "OPT".into()];
    spec.eye.retina_resolution = 20;
    spec.optimize = Some(OptimizeSpec {
        train_cases: Some(vec!["Pin".into(), "Cen".into()]),
        iterations: 12,
        tolerance: 0.0,
        pupil_grid: Some(3),
        pinhole_retina_samples: 2,
        ..OptimizeSpec::default()
    });
    let mut text = spec.to_toml();
    if let Some(d) = diffraction {
        text += &format!("\n[optics]\ndiffraction = \"{d}\"\n");
    }
    let spec: ExperimentSpec = toml::from_str(&text).unwrap();
    Experiment::from_parts(spec, Scene::paper(), display, "opt.toml").unwrap()
}

fn to_rgb(image: &RgbImage) -> Vec<Rgb> {
    image.pixels.iter().map(|p| p.map(f64::from)).collect()
}

/// The mean squared error of `A x` against `target`.
fn mse(op: &EyeOperator<'_>, x: &RgbImage, target: &[Rgb]) -> f64 {
    let mut y = vec![[0.0; 3]; op.rows()];
    op.forward(&to_rgb(x), &mut y);
    y.iter().zip(target).map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>()).sum::<f64>()
        / (3 * y.len()) as f64
}

/// Renders every method of `exp` through the router; checks OPT against LC and LA as the module
/// says; returns the OPT and LA MSE per training state.
fn check_opt(exp: &Experiment, case: &str) -> Vec<(f64, f64)> {
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = FacingPlanes::new(&scene, &backend).unwrap();
    let hidden = Progress::hidden();
    let training = exp.optimize.as_ref();
    let images: Vec<RgbImage> = exp
        .methods
        .iter()
        .map(|&m| inimtrace::methods::render(&exp.display, m, &exp.render, training, &field, &hidden).unwrap().0)
        .collect();
    let (lc, la, opt) = (&images[0], &images[1], &images[2]);
    assert!(opt.pixels.iter().flatten().all(|v| (0.0..=1.0).contains(v)), "{case}: OPT lies in [0, 1]");
    let differ = |a: &RgbImage, b: &RgbImage| a.pixels.iter().zip(&b.pixels).filter(|(p, q)| p != q).count();
    assert!(differ(opt, lc) > lc.pixels.len() / 10, "{case}: OPT is LC's image ({} pixels differ)", differ(opt, lc));
    assert!(differ(opt, la) > 0, "{case}: OPT never left LA's image");
    let states = &training.unwrap().states;
    states
        .iter()
        .map(|s| {
            let op = EyeOperator::new(&exp.display, &s.eye, &s.retina);
            let target = op.diffracted_target(&field).unwrap_or_else(|| {
                ground_truth(&s.eye, &s.retina, &field, &hidden).pixels.iter().map(|p| p.map(f64::from)).collect()
            });
            let (o, l) = (mse(&op, opt, &target), mse(&op, la, &target));
            assert!(o <= l, "{case} {}: OPT's MSE {o:e} > LA's {l:e}", s.name);
            (o, l)
        })
        .collect()
}

#[test]
fn opt_through_real_lenslets_is_its_own_image_and_beats_la_on_its_training_states() {
    let exp = experiment(display(true), None);
    assert!(exp.display.thick_lenslet().is_some());
    let per_state = check_opt(&exp, "thick lenslets");
    // The training set as a whole gains strictly.
    assert!(per_state.iter().map(|(o, _)| o).sum::<f64>() < per_state.iter().map(|(_, l)| l).sum::<f64>());
}

#[test]
fn opt_with_diffraction_is_its_own_image_and_beats_la_on_its_training_states() {
    for (thick, case) in [(false, "paraxial lenslets, diffraction"), (true, "thick lenslets, diffraction")] {
        let exp = experiment(display(thick), Some("apertures"));
        let opt = exp.optimize.as_ref().unwrap();
        assert!(opt.states.iter().all(|s| s.eye.optics.as_ref().is_some_and(|o| o.diffraction.is_on())));
        let per_state = check_opt(&exp, case);
        assert!(per_state.iter().map(|(o, _)| o).sum::<f64>() < per_state.iter().map(|(_, l)| l).sum::<f64>());
    }
}

#[test]
fn the_render_layer_refuses_opt_rather_than_trace_another_method() {
    struct Grey;
    impl RadianceField for Grey {
        fn radiance(&self, _: &inimtrace::ray::Ray) -> glam::DVec3 {
            glam::DVec3::splat(0.5)
        }
    }
    for thick in [false, true] {
        let d = display(thick);
        let err = render_display_image(&d, Method::Optimized, &Default::default(), &Grey, &Progress::hidden())
            .unwrap_err()
            .to_string();
        assert!(err.contains("OPT") && err.contains("methods"), "thick {thick}: {err}");
        // The router without training states says what OPT needs.
        let err =
            inimtrace::methods::render(&d, Method::Optimized, &Default::default(), None, &Grey, &Progress::hidden())
                .unwrap_err()
                .to_string();
        assert!(err.contains("[optimize]"), "{err}");
    }
}

fn run(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "--threads", "2"])
        .args(args)
        .output()
        .expect("binary runs")
}

/// Writes `display.toml` (the repository's `name` with a 108 x 108 LCD) and `opt.toml` (LC, LA 3 x
/// 3 and OPT trained on Pin and Cen, a 20 x 20 retina, 3 x 3 pupil grid, `extra` appended) into
/// `dir`; returns the experiment's path.
fn cli_experiment(dir: &std::path::Path, display: &str, extra: &str) -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text =
        std::fs::read_to_string(root.join("displays").join(display)).unwrap().replace("[2160, 2160]", "[108, 108]");
    assert!(text.contains("[108, 108]"));
    std::fs::write(dir.join("display.toml"), text).unwrap();
    let exp = format!(
        "name = \"opt\"\nscene = {:?}\ndisplay = \"display.toml\"\nmethods = [\"LC\", \"LA3\", \"OPT\"]\n{extra}\n\
         [eye]\nretina_resolution = 20\n\n\
         [[eye_cases]]\nname = \"Pin\"\npinhole = true\n\n[[eye_cases]]\nname = \"Cen\"\nfocus_mm = 400.0\n\n\
         [[eye_cases]]\nname = \"Far\"\nfocus_mm = 600.0\n\n\
         [optimize]\ntrain_cases = [\"Pin\", \"Cen\"]\niterations = 12\ntolerance = 0.0\npupil_grid = 3\n\
         pinhole_retina_samples = 1\n",
        root.join("scenes/paper.toml").display().to_string()
    );
    let path = dir.join("opt.toml");
    std::fs::write(&path, exp).unwrap();
    path
}

/// `assess` of `exp`: OPT's display image is not LC's, and its record shows every training state's
/// MSE at most LA's (where it started). Returns results.json.
fn assess_cli(exp: &std::path::Path) -> serde_json::Value {
    let out = exp.parent().unwrap().join("out");
    let o = run(&["assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |m: &str| inimtrace::io::exr::read_rgb(&out.join(format!("display_{m}.exr"))).unwrap();
    let (lc, la, opt) = (read("LC"), read("LA3"), read("OPT"));
    let differ = |a: &RgbImage, b: &RgbImage| a.pixels.iter().zip(&b.pixels).filter(|(p, q)| p != q).count();
    assert!(differ(&opt, &lc) > lc.pixels.len() / 10, "OPT is LC's image");
    assert!(differ(&opt, &la) > 0, "OPT never left LA's image");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let rec = &report["optimization"];
    assert_eq!(rec["method"], "OPT");
    assert!(rec["initial"].as_str().unwrap().starts_with("LA"));
    let (before, after) = (rec["initial_mse"].as_array().unwrap(), rec["final_mse"].as_array().unwrap());
    assert_eq!(before.len(), 2);
    for (b, a) in before.iter().zip(after) {
        assert!(a.as_f64().unwrap() <= b.as_f64().unwrap(), "a training state lost: {b} -> {a}");
    }
    report
}

#[test]
fn the_cli_trains_opt_through_real_lenslets_and_it_beats_la_on_its_training_cases() {
    let dir = tempfile::tempdir().unwrap();
    // The grid estimator on OPT's own samples: Table 1's perceived images are A_s x.
    let report = assess_cli(&cli_experiment(dir.path(), "paper-pmma.toml", ""));
    let psnr = |m: &str, case: &str| {
        let s = report["scores"].as_array().unwrap().iter().find(|s| s["method"] == m && s["eye_case"] == case);
        s.unwrap()["psnr"]["mean"].as_f64().unwrap()
    };
    for case in ["Pin", "Cen"] {
        assert!(
            psnr("OPT", case) >= psnr("LA3", case) - 1e-6,
            "{case}: OPT {} < LA {}",
            psnr("OPT", case),
            psnr("LA3", case)
        );
    }
}

#[test]
fn the_cli_trains_opt_with_diffraction_at_the_apertures() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "[optics]\ndiffraction = \"apertures\"\n\n[measurement]\nestimator = \"converged\"\n\
                 psnr_ci95_db = 5.0\nssim_ci95 = 0.5\nmax_samples_per_pixel = 12\nreplicates = 3\nmax_seconds = 60.0\n";
    let report = assess_cli(&cli_experiment(dir.path(), "paper.toml", extra));
    assert_eq!(report["settings"]["optics"]["diffraction"], "apertures");
}
