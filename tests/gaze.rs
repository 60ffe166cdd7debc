//! The eye turned to a gaze about its centre of rotation (src/optics/eye/gaze.rs): the pupil centre
//! and any point of the eye against their rotation about the stated centre computed here
//! independently (Fick's line of sight, Rodrigues' rotation formula about Listing's axis), and bad
//! gazes and centres refused naming the field. The turned eye in the optical system: its rays are
//! its rays at rest turned about the centre, a vanishing gaze meets eq. (1)'s LCD pixels, an eye
//! turned with its scene sees the image of the eye at rest (thin lens and schematic); in an
//! experiment: every case turned, PupilCenter's tracked pupil, and without tracking PupilCenter's
//! quality falling with gaze.

use std::path::Path;

use glam::{DVec2, DVec3};
use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::experiment::{Experiment, ExperimentSpec};
use inimtrace::fixtures::Lcg;
use inimtrace::optics::eye::settings::pose_of;
use inimtrace::optics::eye::{
    CentreOfRotation, EyeModel, EyeOptics, EyeOpticsSpec, EyePose, FocusCriterion, Gaze, SchematicEye,
};
use inimtrace::optics::spectrum::Primaries;
use inimtrace::optics::system::{EyeSample, Kernel, OpticalSystem, Traces};
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::ray::Ray;
use inimtrace::render::field::RadianceField;
use inimtrace::render::retina::simulate;
use inimtrace::render::{ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method};
use inimtrace::scene::Scene;

/// Rodrigues' formula: `v` turned by `angle` about the unit `axis`.
fn rodrigues(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    v * angle.cos() + axis.cross(v) * angle.sin() + axis * axis.dot(v) * (1.0 - angle.cos())
}

#[test]
fn the_pupil_centre_at_a_gaze_is_its_rotation_about_the_centre_to_a_nanometre() {
    for pupil_at_rest in [DVec3::ZERO, DVec3::new(1.5, -0.7, 2.0)] {
        for behind in [10.26, 13.0, 8.0] {
            for (h, v) in [(20.0, 0.0), (0.0, -15.0), (30.0, 25.0), (-42.0, 17.0), (5.0, -55.0), (0.001, 0.0)] {
                let pose = EyePose::new(Gaze::new(h, v), pupil_at_rest, behind);
                // Fick: turned h about the vertical, then v up.
                let (h, v) = (f64::to_radians(h), f64::to_radians(v));
                let los = DVec3::new(v.cos() * h.sin(), v.sin(), v.cos() * h.cos());
                // Listing: about the axis across straight ahead and the line of sight.
                let axis = DVec3::Z.cross(los).normalize();
                let angle = los.z.clamp(-1.0, 1.0).acos();
                let centre = pupil_at_rest - DVec3::new(0.0, 0.0, behind);
                let want = centre + rodrigues(pupil_at_rest - centre, axis, angle);
                assert!((pose.pupil_centre - want).length() < 1e-9, "{pose:?} vs {want}");
                assert!((pose.line_of_sight - los).length() < 1e-12);
                // The pupil sits `behind` from the centre along the line of sight.
                assert!((pose.pupil_centre - (centre + behind * los)).length() < 1e-9);
                // Any other point of the eye turns the same way.
                let q = DVec3::new(0.4, -2.0, -17.0) + pupil_at_rest;
                assert!((pose.point(q) - (centre + rodrigues(q - centre, axis, angle))).length() < 1e-9);
            }
        }
    }
    // Straight ahead nothing moves.
    let rest = DVec3::new(0.2, 0.1, 0.0);
    assert_eq!(EyePose::new(Gaze::AHEAD, rest, 10.26).pupil_centre, rest);
}

#[test]
fn the_default_centre_lies_about_ten_millimetres_behind_each_models_pupil() {
    let c = CentreOfRotation::default();
    assert_eq!(c.behind_cornea_mm, 13.3);
    for model in [
        inimtrace::optics::eye::EyeModel::Navarro1985,
        inimtrace::optics::eye::EyeModel::Navarro1999,
        inimtrace::optics::eye::EyeModel::Arizona,
        inimtrace::optics::eye::EyeModel::LeGrand,
    ] {
        let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
        let p = eye.paraxial(eye.reference_wavelength());
        let behind = c.behind_pupil_mm(CentreOfRotation::pupil_depth(Some(&p)));
        assert!((10.2..10.4).contains(&behind), "{}: {behind}", model.name());
    }
    assert!((c.behind_pupil_mm(CentreOfRotation::pupil_depth(None)) - 10.26).abs() < 1e-12);
}

#[test]
fn bad_gazes_and_centres_are_refused_naming_the_field() {
    for (h, v) in [(61.0, 0.0), (0.0, -60.5), (50.0, 40.0), (f64::NAN, 0.0), (0.0, f64::INFINITY)] {
        let e = Gaze::new(h, v).validate("e.toml", "eye.gaze_deg").unwrap_err().to_string();
        assert!(e.contains("eye.gaze_deg") && e.contains("e.toml"), "{h} {v}: {e}");
    }
    for (h, v) in [(60.0, 0.0), (45.0, 45.0), (-30.0, 20.0)] {
        Gaze::new(h, v).validate("e.toml", "eye.gaze_deg").unwrap();
    }
    for mm in [-2.0, 0.0, 31.0, f64::NAN] {
        let e = CentreOfRotation { behind_cornea_mm: mm }.validate("e.toml", "eye.centre_of_rotation_mm");
        let e = e.unwrap_err().to_string();
        assert!(e.contains("eye.centre_of_rotation_mm") && e.contains("e.toml"), "{mm}: {e}");
        if mm <= 0.0 {
            assert!(e.contains("in front of the cornea"), "{e}");
        }
    }
    CentreOfRotation::default().validate("e.toml", "eye.centre_of_rotation_mm").unwrap();
}

// ---- The turned eye in the optical system's trace and in an experiment's settings ----

/// A thin-lens eye (`None`) or a schematic eye of `model` (4 mm pupil, 2.5 D, 4 x 4 grid).
fn test_eye(model: Option<EyeModel>) -> Eye {
    let mut eye = Eye::thin_lens(4.0, Focus::Diopters(2.5), 4);
    if let Some(model) = model {
        let spec = EyeOpticsSpec {
            model,
            criterion: FocusCriterion::Paraxial,
            reference_nm: 555.0,
            primaries: false,
            wavelength_samples: 1,
            stiles_crawford: None,
            diffraction: Default::default(),
        };
        eye.optics = EyeOptics::build(&spec, &eye.aperture, 17.0, &Primaries::default(), 0.4, "t", "eye").unwrap();
    }
    eye
}

/// `eye` turned to `gaze` about the default centre.
fn turned(eye: &Eye, model: &EyeModel, gaze: Gaze) -> Eye {
    let pose = pose_of(model, gaze, CentreOfRotation::default(), eye.position, "t").unwrap();
    Eye { pose, ..eye.clone() }
}

fn samples(rng: &mut Lcg, count: usize) -> Vec<EyeSample> {
    (0..count)
        .map(|_| {
            let (r, a) = (2.0 * rng.next().sqrt(), std::f64::consts::TAU * rng.next());
            EyeSample {
                tangent: DVec2::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2)),
                pupil: DVec2::new(r * a.cos(), r * a.sin()),
                spectral: rng.next(),
                diffraction: [0.5; 4],
            }
        })
        .collect()
}

#[test]
fn a_turned_eyes_rays_are_its_rays_at_rest_turned_about_the_centre_and_straight_ahead_keeps_its_kernel() {
    let display = Display::paper();
    let mut rng = Lcg(50);
    for model in [EyeModel::ThinLens, EyeModel::Navarro1985] {
        let rest = test_eye((model != EyeModel::ThinLens).then(|| model.clone()));
        let at_rest = OpticalSystem::new(&display, &rest);
        assert_ne!(at_rest.kernel(), Kernel::Rotated, "{}", model.name());
        // Gaze [0, 0] is the eye at rest: no pose.
        assert_eq!(turned(&rest, &model, Gaze::AHEAD).pose, None);
        let g = Gaze::new(12.0, -7.0);
        let eye = turned(&rest, &model, g);
        let system = OpticalSystem::new(&display, &eye);
        assert_eq!(system.kernel(), Kernel::Rotated);
        let s = samples(&mut rng, 65);
        let (mut a, mut b, mut fast) = (Traces::default(), Traces::default(), Traces::default());
        at_rest.trace_each(&s, &mut a);
        system.trace_each(&s, &mut b);
        system.trace(&s, &[], &mut fast);
        assert_eq!((&fast.samples, &fast.scene), (&b.samples, &b.scene), "the kernel against its slow twin");
        // Independently: Rodrigues about Listing's axis, about the centre 10.26 mm behind the pupil.
        let los = g.line_of_sight();
        let (axis, angle) = (DVec3::Z.cross(los).normalize(), los.z.acos());
        let centre = DVec3::new(0.0, 0.0, -(13.3 - 3.04));
        let centre = if model == EyeModel::ThinLens { centre } else { eye.pose.unwrap().centre };
        assert_eq!(a.scene.len(), b.scene.len());
        for (r0, r1) in a.scene.iter().zip(&b.scene) {
            let o = centre + rodrigues(r0.origin - centre, axis, angle);
            assert!((r1.origin - o).length() < 1e-9 && (r1.dir - rodrigues(r0.dir, axis, angle)).length() < 1e-12);
        }
        // The turned pupil sits on the display's side of the centre: most rays still reach the LCD.
        let seen = b.samples.iter().filter(|t| t.lcd[0] < u32::MAX - 1).count();
        assert!(seen > s.len() / 2, "{}: {seen} of {}", model.name(), s.len());
    }
}

#[test]
fn a_vanishing_gaze_meets_the_lcd_pixels_of_the_closed_form() {
    // The rotated kernel's LCD line (the turned ray re-expressed on the pupil's plane) against
    // eq. (1)'s closed form of the eye at rest, for a gaze of a micro-degree.
    let display = Display::paper();
    let rest = test_eye(None);
    let eye = turned(&rest, &EyeModel::ThinLens, Gaze::new(1e-6, -1e-6));
    let s = samples(&mut Lcg(7), 2000);
    let (mut a, mut b) = (Traces::default(), Traces::default());
    OpticalSystem::new(&display, &rest).trace(&s, &[], &mut a);
    OpticalSystem::new(&display, &eye).trace(&s, &[], &mut b);
    let same = a.samples.iter().zip(&b.samples).filter(|(x, y)| x.lcd[0] == y.lcd[0]).count();
    assert!(same >= 1990, "{same} of 2000 samples on the same LCD pixel");
    for (x, y) in a.scene.iter().zip(&b.scene) {
        assert!((x.origin - y.origin).length() < 1e-6 && (x.dir - y.dir).length() < 1e-6);
    }
}

/// A smooth pattern on the plane z = 400 mm (black elsewhere).
struct Plane;

impl RadianceField for Plane {
    fn radiance(&self, ray: &Ray) -> DVec3 {
        if ray.dir.z <= 0.0 {
            return DVec3::ZERO;
        }
        let p = ray.origin + ray.dir * ((400.0 - ray.origin.z) / ray.dir.z);
        DVec3::new(
            0.5 + 0.5 * (p.x / 9.0).sin(),
            0.5 + 0.5 * (p.y / 6.0 + 1.0).cos(),
            0.5 + 0.4 * (p.x * p.y / 900.0).sin(),
        )
    }
}

/// A field turned by `pose` about its centre: the field at rest seen along the ray turned back.
struct Turned<'a>(&'a dyn RadianceField, EyePose);

impl RadianceField for Turned<'_> {
    fn radiance(&self, ray: &Ray) -> DVec3 {
        let back = self.1.rotation.inverse();
        let origin = self.1.centre + back * (ray.origin - self.1.centre);
        self.0.radiance(&Ray { origin, dir: back * ray.dir })
    }
}

#[test]
fn an_eye_turned_with_its_scene_sees_the_image_of_the_eye_at_rest_thin_lens_and_schematic() {
    let retina = Retina { resolution: 24, half_tangent: 0.2, samples_per_pixel: 1 };
    let hidden = Progress::hidden();
    for model in [EyeModel::ThinLens, EyeModel::Navarro1999] {
        let rest = test_eye((model != EyeModel::ThinLens).then(|| model.clone()));
        let want = ground_truth(&rest, &retina, &Plane, &hidden);
        let eye = turned(&rest, &model, Gaze::new(-14.0, 9.0));
        let got = ground_truth(&eye, &retina, &Turned(&Plane, eye.pose.unwrap()), &hidden);
        let worst = got.pixels.iter().zip(&want.pixels).flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()));
        let worst = worst.fold(0.0f32, f32::max);
        assert!(worst < 1e-5, "{}: {worst}", model.name());
        // The turned eye on the scene at rest sees another part of it.
        let other = ground_truth(&eye, &retina, &Plane, &hidden);
        let moved = other.pixels.iter().zip(&want.pixels).map(|(a, b)| (a[0] - b[0]).abs()).fold(0.0f32, f32::max);
        assert!(moved > 0.1, "{}: {moved}", model.name());
    }
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn experiment(edit: impl FnOnce(&mut ExperimentSpec)) -> inimtrace::error::Result<Experiment> {
    let mut spec = ExperimentSpec::paper_converged();
    edit(&mut spec);
    Experiment::from_spec(spec, "g.toml", root())
}

#[test]
fn an_experiments_gaze_turns_every_case_and_pupil_center_renders_for_the_tracked_pupil() {
    let e = experiment(|s| s.eye.gaze_deg = Some([10.0, 5.0])).unwrap();
    let pose = e.cases[0].eye.pose.expect("a turned eye");
    assert!(e.cases.iter().all(|c| c.eye.pose == Some(pose)), "every state turns about one point");
    assert_eq!(e.render.eye_position, pose.pupil_centre, "ideal tracking by default");
    let none = experiment(|s| {
        s.eye.gaze_deg = Some([10.0, 5.0]);
        s.display_render.pupil_tracking = Some("none".into());
    })
    .unwrap();
    assert_eq!(none.render.eye_position, DVec3::ZERO);
    let off = experiment(|s| {
        s.eye.gaze_deg = Some([10.0, 5.0]);
        s.display_render.tracking_error_mm = Some([0.5, 0.0, 0.0]);
    })
    .unwrap();
    assert!((off.render.eye_position - pose.pupil_centre - DVec3::X * 0.5).length() < 1e-12);
    // One case's own gaze.
    let row = experiment(|s| s.eye_cases[2].gaze_deg = Some([0.0, -8.0])).unwrap();
    assert_eq!(row.cases[0].eye.pose, None);
    assert_eq!(row.cases[2].eye.pose.unwrap().gaze, Gaze::new(0.0, -8.0));
    // Straight ahead: the eye at rest, PC where it always rendered.
    let ahead = experiment(|s| s.eye.gaze_deg = Some([0.0, 0.0])).unwrap();
    assert!(ahead.cases.iter().all(|c| c.eye.pose.is_none()) && ahead.render.eye_position == DVec3::ZERO);
}

#[test]
fn an_experiments_bad_gaze_centre_or_tracking_is_refused_naming_the_field() {
    type Edit = Box<dyn FnOnce(&mut ExperimentSpec)>;
    let cases: Vec<(Edit, &str)> = vec![
        (Box::new(|s| s.eye.gaze_deg = Some([61.0, 0.0])), "eye.gaze_deg"),
        // The paper's 21.6 mm LCD, 26 mm away: at 25 degrees the line of sight passes it.
        (Box::new(|s| s.eye.gaze_deg = Some([25.0, 0.0])), "eye.gaze_deg"),
        (Box::new(|s| s.eye_cases[1].gaze_deg = Some([0.0, -30.0])), "eye_cases[1].gaze_deg"),
        (Box::new(|s| s.eye_cases[1].gaze_deg = Some([f64::NAN, 0.0])), "eye_cases[1].gaze_deg"),
        (Box::new(|s| s.eye.centre_of_rotation_mm = Some(-1.0)), "eye.centre_of_rotation_mm"),
        (Box::new(|s| s.display_render.pupil_tracking = Some("perfect".into())), "display_render.pupil_tracking"),
        (
            Box::new(|s| {
                s.display_render.pupil_tracking = Some("none".into());
                s.display_render.tracking_error_mm = Some([0.1, 0.0, 0.0]);
            }),
            "display_render.tracking_error_mm",
        ),
    ];
    for (edit, field) in cases {
        let e = experiment(edit).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains("g.toml"), "{field}: {e}");
    }
    let e = experiment(|s| s.eye.gaze_deg = Some([25.0, 0.0])).unwrap_err().to_string();
    assert!(e.contains("look past the display"), "{e}");
}

/// OPT's training states are eye states like the cases: a state's gaze that looks past the
/// display, or beyond 60 degrees, is refused naming `optimize.states[i].gaze_deg`; a state
/// looking at the display loads, turned.
#[test]
fn an_opt_training_states_gaze_is_checked_against_the_display_naming_the_field() {
    let path = root().join("experiments/paper-optimal.toml");
    let load = |state: &str| {
        let sets: Vec<inimtrace::overrides::Override> =
            [format!("optimize.states=[{{ name = \"glance\", focus_mm = 350.0 }}, {state}]")]
                .iter()
                .map(|s| s.parse().unwrap())
                .collect();
        inimtrace::settings::load_experiment(Some(&path), None, &sets)
    };
    for gaze in ["[25.0, 0.0]", "[0.0, -30.0]", "[61.0, 0.0]"] {
        let e = load(&format!("{{ name = \"turned\", focus_mm = 400.0, gaze_deg = {gaze} }}"))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("optimize.states[1].gaze_deg") && e.contains("paper-optimal.toml"), "{gaze}: {e}");
    }
    let e = load("{ name = \"turned\", focus_mm = 400.0, gaze_deg = [25.0, 0.0] }").err().unwrap().to_string();
    assert!(e.contains("look past the display"), "{e}");
    let ok = load("{ name = \"turned\", focus_mm = 400.0, gaze_deg = [10.0, 5.0] }").unwrap();
    let opt = ok.optimize.expect("OPT's training");
    let turned = opt.states.iter().find(|s| s.name == "turned").unwrap();
    assert_eq!(turned.eye.pose.unwrap().gaze, Gaze::new(10.0, 5.0));
}

/// PSNR of PupilCenter rendered for `pc_pupil`, seen by `eye`, against its ground truth.
fn pc_psnr(display: &Display, field: &dyn RadianceField, eye: &Eye, pc_pupil: DVec3, retina: &Retina) -> f64 {
    let hidden = Progress::hidden();
    let settings = DisplayRenderSettings { eye_position: pc_pupil, ..Default::default() };
    let image = render_display_image(display, Method::PupilCenter, &settings, field, &hidden).unwrap();
    let seen = simulate(display, eye, retina, &[&image], &hidden).unwrap();
    let gt = ground_truth(eye, retina, field, &hidden);
    inimtrace::metrics::psnr(&seen[0], &gt).unwrap().mean
}

/// The paper's display and scene, a 5 mm thin-lens eye focused on the centre chart, a small
/// retina around the line of sight (grid estimator). PupilCenter renders for one pupil centre;
/// untracked, it renders for the pupil straight ahead while the turned pupil has moved about
/// `10.26 mm x sin(gaze)`, so each elemental image is seen from farther from the point it was
/// rendered for. Tracked, it renders for the turned pupil. The eye moved to the same pupil without
/// turning is not the same comparison: it looks through the central lenslets from off the axis,
/// where the turned eye looks through off-axis lenslets along its line of sight, and each sees
/// another part of the scene (docs/FIELD.md gives the figures).
#[test]
fn pupil_center_with_tracking_beats_it_without_and_without_tracking_falls_with_gaze() {
    let display = Display::paper();
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let field = FacingPlanes::new(&scene, &backend).unwrap();
    let retina = Retina { resolution: 48, half_tangent: 0.08, samples_per_pixel: 1 };
    let rest = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 6);
    let mut untracked = vec![pc_psnr(&display, &field, &rest, DVec3::ZERO, &retina)];
    for h in [8.0, 12.0, 15.0] {
        let eye = turned(&rest, &EyeModel::ThinLens, Gaze::new(h, 0.0));
        let pupil = eye.pose.unwrap().pupil_centre;
        let tracked = pc_psnr(&display, &field, &eye, pupil, &retina);
        let none = pc_psnr(&display, &field, &eye, DVec3::ZERO, &retina);
        if h >= 12.0 {
            assert!(tracked > none + 0.5, "gaze {h}: tracked {tracked:.2} dB vs untracked {none:.2} dB");
        }
        untracked.push(none);
    }
    assert!(untracked.windows(2).all(|w| w[1] < w[0]), "PC without tracking falls with gaze: {untracked:?}");
}

#[test]
fn the_gaze_and_eye_box_sweeps_build_every_point_on_two_axes() {
    for (file, gaze) in [("sweeps/gaze.toml", true), ("sweeps/eyebox.toml", false)] {
        let sweep = inimtrace::sweep::Sweep::load(&root().join(file), &[], None).unwrap();
        let points = sweep.resolve().unwrap();
        assert_eq!(points.len(), 25, "{file}");
        let mut seen = Vec::new();
        for p in &points {
            let e = p.experiment().unwrap_or_else(|err| panic!("{file}: {err}"));
            let eye = &e.cases[0].eye;
            seen.push(if gaze {
                eye.pose.map_or([0.0; 2], |p| <[f64; 2]>::from(p.gaze))
            } else {
                [eye.position.x, eye.position.y]
            });
            // PupilCenter renders for the eye's pupil: turned (ideal tracking) or moved.
            let pupil = eye.pose.map_or(eye.position, |p| p.pupil_centre);
            assert!((e.render.eye_position - pupil).length() < 1e-12, "{file}");
        }
        seen.sort_by(|a, b| a.partial_cmp(b).unwrap());
        seen.dedup();
        assert_eq!(seen.len(), 25, "{file}: every point its own gaze or position");
    }
}

#[test]
fn a_turned_eye_is_named_in_the_caption_and_the_image_attributes_and_straight_ahead_is_not() {
    use inimtrace::experiment::{metadata, simulated::Simulated};
    let turned = experiment(|s| s.eye.gaze_deg = Some([10.0, 5.0])).unwrap();
    assert!(Simulated::of(&turned).eye.contains("gaze [10, 5] degrees"), "{}", Simulated::of(&turned).eye);
    let case = &turned.cases[0];
    let a = metadata::ground_truth(None, Some(&case.name), &case.eye, &turned.retina, "analytic");
    assert!(a.get("inimtrace:gaze_horizontal_deg").is_some() && a.get("inimtrace:gaze_vertical_deg").is_some());
    let ahead = experiment(|_| {}).unwrap();
    assert!(!Simulated::of(&ahead).eye.contains("gaze"));
    let case = &ahead.cases[0];
    let a = metadata::ground_truth(None, Some(&case.name), &case.eye, &ahead.retina, "analytic");
    assert!(a.get("inimtrace:gaze_horizontal_deg").is_none());
}
