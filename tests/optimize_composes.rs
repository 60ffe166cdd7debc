//! OPT composes with the simulation's optics (issue #27, docs/OPTIMAL.md): its operator is the
//! perceived-image simulation, sample for sample, through a polychromatic schematic eye, through
//! real (thick) lenslets, and with diffraction at the pupil and the lenslet apertures (whose
//! deviations are part of the operator's fixed sample pattern), and its adjoint is the exact
//! transpose in each case.
#![deny(unsafe_code)]

use std::path::Path;

use glam::DVec3;
use inimtrace::experiment::EyeModelSettings;
use inimtrace::fixtures::Lcg;
use inimtrace::io::load_display;
use inimtrace::measure::estimator::{DisplaySource, PairedSource};
use inimtrace::optics::diffraction::Diffraction;
use inimtrace::optics::eye::EyeOptics;
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::optimize::{EyeOperator, Operator, Rgb};
use inimtrace::progress::Progress;
use inimtrace::raster::RgbImage;
use inimtrace::ray::Ray;
use inimtrace::render::retina::DisplayStack;
use inimtrace::render::{simulate, RadianceField};

const LCD: usize = 160;

fn retina() -> Retina {
    Retina { resolution: 16, half_tangent: 0.2, samples_per_pixel: 2 }
}

/// The paper's display, or with real PMMA lenslets, at a small LCD.
fn display(thick: bool) -> Display {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let name = if thick { "displays/paper-pmma.toml" } else { "displays/paper.toml" };
    let mut d = load_display(name, root).unwrap();
    d.lcd.resolution = [LCD, LCD];
    assert_eq!(d.thick_lenslet().is_some(), thick);
    d
}

/// A thin-lens eye focused at 400 mm with `model`'s optics, each channel at its display
/// primary's wavelengths, and `diffraction`.
fn eye(display: &Display, model: &str, diffraction: Diffraction) -> Eye {
    let mut eye = Eye::thin_lens(4.0, Focus::Millimetres(400.0), 3);
    let settings = EyeModelSettings {
        model: Some(model.into()),
        spectrum: Some("primaries".into()),
        wavelength_samples: Some(2),
        ..EyeModelSettings::default()
    };
    let spec = settings.optics_spec(4.0, "test", "eye.").unwrap().with_diffraction(diffraction, true);
    let primaries = display.primaries.clone().unwrap_or_default();
    eye.optics = EyeOptics::build(&spec, &eye.aperture, eye.retina_distance, &primaries, 0.3, "test", "focus").unwrap();
    eye
}

fn random_image(rng: &mut Lcg) -> (RgbImage, Vec<Rgb>) {
    let mut image = RgbImage::new(LCD, LCD);
    image.pixels.iter_mut().for_each(|p| *p = std::array::from_fn(|_| rng.next() as f32));
    let x = image.pixels.iter().map(|p| p.map(f64::from)).collect();
    (image, x)
}

fn dot(a: &[Rgb], b: &[Rgb]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).sum()
}

fn forward(op: &EyeOperator, x: &[Rgb]) -> Vec<Rgb> {
    let mut ax = vec![[0.0; 3]; op.rows()];
    op.forward(x, &mut ax);
    ax
}

/// `<A x, y> = <x, A^T y>` to 1e-10 relative for random x, y.
fn assert_exact_adjoint(name: &str, op: &EyeOperator, rng: &mut Lcg) {
    for _ in 0..2 {
        let x: Vec<Rgb> = (0..op.cols()).map(|_| std::array::from_fn(|_| rng.range(-1.0, 1.0))).collect();
        let y: Vec<Rgb> = (0..op.rows()).map(|_| std::array::from_fn(|_| rng.range(-1.0, 1.0))).collect();
        let ax = forward(op, &x);
        let mut aty = vec![[0.0; 3]; op.cols()];
        op.adjoint_add(&y, 1.0, &mut aty);
        let (l, r) = (dot(&ax, &y), dot(&x, &aty));
        let scale = l.abs().max(r.abs());
        assert!(scale > 1e-3, "{name}: the operator sees the display ({l})");
        assert!((l - r).abs() <= 1e-10 * scale, "{name}: <Ax,y> = {l} vs <x,A^T y> = {r}");
    }
}

/// The grid simulation's perceived image of `image` equals `A x` (to the image's f32 rounding).
fn assert_is_the_simulation(name: &str, display: &Display, eye: &Eye, rng: &mut Lcg) {
    let op = EyeOperator::new(display, eye, &retina());
    assert_exact_adjoint(name, &op, rng);
    let (image, x) = random_image(rng);
    let ax = forward(&op, &x);
    let seen = simulate(display, eye, &retina(), &[&image], &Progress::hidden()).unwrap().remove(0);
    let mut lit = 0;
    for (a, s) in ax.iter().zip(&seen.pixels) {
        for c in 0..3 {
            assert!((a[c] - f64::from(s[c])).abs() <= 1e-6, "{name}: {a:?} vs {s:?}");
        }
        lit += usize::from(a.iter().any(|&v| v > 0.0));
    }
    assert!(lit > ax.len() / 2, "{name}: the eye sees the display ({lit} of {} pixels)", ax.len());
}

#[test]
fn through_a_polychromatic_schematic_eye_the_operator_is_the_simulation() {
    let mut rng = Lcg(11);
    let d = display(false);
    let e = eye(&d, "navarro", Diffraction::None);
    let optics = e.optics.as_ref().unwrap();
    assert!(optics.schematic().is_some() && !optics.is_single_wavelength(), "{}", optics.describe());
    assert_is_the_simulation("navarro, primaries", &d, &e, &mut rng);
}

#[test]
fn through_real_lenslets_the_operator_is_the_simulation() {
    let mut rng = Lcg(12);
    let d = display(true);
    // The paper's thin-lens eye (no optics of its own) and a polychromatic schematic eye.
    assert_is_the_simulation("PMMA, thin lens", &d, &Eye::thin_lens(4.0, Focus::Millimetres(400.0), 3), &mut rng);
    assert_is_the_simulation("PMMA, pinhole", &d, &Eye::pinhole(), &mut rng);
    assert_is_the_simulation("PMMA, navarro", &d, &eye(&d, "navarro", Diffraction::None), &mut rng);
    // Each channel finds its own pixel through the real lenslet: a one-channel image is seen in
    // that channel only, and not as the thin lenslet's eq. (1) would see it.
    let op = EyeOperator::new(&d, &Eye::thin_lens(4.0, Focus::Millimetres(400.0), 3), &retina());
    let mut thin = d.clone();
    thin.lenslet = Default::default();
    assert!(thin.thick_lenslet().is_none());
    let thin_op = EyeOperator::new(&thin, &Eye::thin_lens(4.0, Focus::Millimetres(400.0), 3), &retina());
    let (_, x) = random_image(&mut rng);
    let (a, b) = (forward(&op, &x), forward(&thin_op, &x));
    assert!(a.iter().zip(&b).any(|(a, b)| (a[0] - b[0]).abs() > 1e-3), "the real lenslet changes the image");
}

/// A scene of smooth colour: any radiance field serves, the perceived images do not read it.
struct Smooth;

impl RadianceField for Smooth {
    fn radiance(&self, ray: &Ray) -> DVec3 {
        let d = ray.dir / ray.dir.z;
        DVec3::new(0.5 + 0.4 * (7.0 * d.x).sin(), 0.5 + 0.4 * (5.0 * d.y).cos(), 0.3)
    }
}

/// With diffraction the measuring simulation is the converged estimator's paired source: on
/// the operator's own samples (diffraction numbers included) its perceived image, averaged
/// per pixel, is `A x`, and its reference the operator's target.
/// `plain` is the same eye without diffraction.
fn assert_is_the_diffracting_simulation(name: &str, display: &Display, (eye, plain): (&Eye, &Eye), rng: &mut Lcg) {
    let retina = retina();
    let op = EyeOperator::new(display, eye, &retina);
    assert_exact_adjoint(name, &op, rng);
    let (image, x) = random_image(rng);
    let ax = forward(&op, &x);
    let target = op.diffracted_target(&Smooth).expect("diffraction is on");
    let stack = DisplayStack::new(display, &[&image]).unwrap();
    let source = DisplaySource::new(display, eye, &Smooth, &stack);
    let n = retina.resolution;
    for row in 0..n {
        for col in 0..n {
            let samples = op.pixel_samples(row, col);
            assert!(samples.iter().any(|s| s.diffraction != [0.0; 4]), "{name}: diffraction numbers are drawn");
            let mut out = vec![[0.0; 3]; 2 * samples.len()];
            source.eval(&samples, &mut out);
            let inv = 1.0 / samples.len() as f64;
            let (mut gt, mut seen) = ([0.0; 3], [0.0; 3]);
            for o in out.chunks_exact(2) {
                for c in 0..3 {
                    gt[c] += o[0][c] * inv;
                    seen[c] += o[1][c] * inv;
                }
            }
            let (a, t) = (ax[row * n + col], target[row * n + col]);
            for c in 0..3 {
                assert!((a[c] - seen[c]).abs() <= 1e-9, "{name} ({row}, {col}): A x {a:?} vs simulation {seen:?}");
                assert!((t[c] - gt[c]).abs() <= 1e-9, "{name} ({row}, {col}): target {t:?} vs reference {gt:?}");
            }
        }
    }
    // The deviations matter: without them the operator is another matrix.
    let still = EyeOperator::new(display, plain, &retina);
    let b = forward(&still, &x);
    assert!(ax.iter().zip(&b).any(|(a, b)| (a[1] - b[1]).abs() > 1e-3), "{name}: diffraction changes A");
    // The pattern is fixed: a second application is the same bit for bit.
    assert!(forward(&op, &x) == ax, "{name}: the sample pattern is fixed");
}

#[test]
fn with_diffraction_the_operator_is_the_converged_simulation_on_its_fixed_samples() {
    let mut rng = Lcg(13);
    let thin = display(false);
    let thick = display(true);
    for (name, d, model, diffraction) in [
        ("thin lens, pupil", &thin, "thin-lens", Diffraction::Pupil),
        ("thin lens, apertures", &thin, "thin-lens", Diffraction::Apertures),
        ("navarro, apertures", &thin, "navarro", Diffraction::Apertures),
        ("PMMA, apertures", &thick, "thin-lens", Diffraction::Apertures),
    ] {
        let e = eye(d, model, diffraction);
        assert!(e.optics.as_ref().is_some_and(|o| o.diffraction == diffraction), "{name}");
        assert_is_the_diffracting_simulation(name, d, (&e, &eye(d, model, Diffraction::None)), &mut rng);
    }
}

/// One schema for the eye's states: a row of `[[optimize.states]]` takes the fields of an
/// `[[eye_cases]]` row (its own pupil included) and resolves to the same eye through the
/// experiment's eye model and diffraction; `weight` is refused in `[[eye_cases]]`.
#[test]
fn an_optimize_state_is_an_eye_case_row_and_resolves_to_the_same_eye() {
    use inimtrace::experiment::{Experiment, ExperimentSpec, EyeCaseSpec};
    use inimtrace::optimize::OptimizeSpec;
    let row = EyeCaseSpec {
        name: "Mid".into(),
        pinhole: false,
        focus_mm: Some(350.0),
        focus_diopters: None,
        position: Some([0.5, 0.0, 0.0]),
        pupil_diameter: Some(3.0),
        weight: None,
        gaze_deg: None,
    };
    let mut spec = ExperimentSpec::paper_converged();
    spec.methods = vec!["LA".into(), "OPT".into()];
    spec.eye.model = Some("navarro".into());
    spec.optics = Some(toml::from_str("diffraction = \"pupil\"").unwrap());
    spec.eye_cases.push(row.clone());
    spec.optimize = Some(OptimizeSpec {
        train_cases: Some(vec!["Cen".into()]),
        states: vec![EyeCaseSpec { weight: Some(2.0), ..row }],
        ..OptimizeSpec::default()
    });
    let resolve = |spec: ExperimentSpec| {
        Experiment::from_parts(spec, inimtrace::fixtures::white_wall(), display(false), "e.toml")
    };
    let exp = resolve(spec.clone()).unwrap();
    let case = &exp.cases.iter().find(|c| c.name == "Mid").unwrap().eye;
    let state = exp.optimize.as_ref().unwrap().states.iter().find(|s| s.name == "Mid").unwrap();
    assert_eq!(state.weight, 2.0);
    assert!(
        matches!(case.aperture, inimtrace::optics::Aperture::ThinLens { pupil_diameter, .. } if pupil_diameter == 3.0)
    );
    assert_eq!(case.position, DVec3::new(0.5, 0.0, 0.0));
    let (c, s) = (case.optics.as_ref().unwrap(), state.eye.optics.as_ref().unwrap());
    assert!(c.schematic().is_some() && c.diffraction == Diffraction::Pupil);
    assert!(**c == **s, "the state's optics are the case's");
    assert_eq!(
        (case.aperture, case.position, case.retina_distance),
        (state.eye.aperture, state.eye.position, state.eye.retina_distance)
    );
    // A weight belongs to a training state.
    spec.eye_cases[4].weight = Some(2.0);
    let e = resolve(spec).unwrap_err().to_string();
    assert!(e.contains("e.toml") && e.contains("eye_cases[4].weight") && e.contains("optimize.states"), "{e}");
}
