//! Hostile inputs, round three: the physics inputs (schematic eyes, media, lenslet materials,
//! primary spectra, the Stiles-Crawford effect, OPT's training states, the resolution study's
//! orientations) refuse what is impossible with one error naming the field, and never turn into a
//! silent wrong number.

use std::path::{Path, PathBuf};

use glam::DVec2;
use inimtrace::optics::eye::medium::Dispersion;
use inimtrace::optics::eye::rays::StilesCrawford;
use inimtrace::optics::eye::{EyeModel, SchematicEye, UserEye};
use inimtrace::optics::lenslet::{Material, Surface, ThickLenslet};
use inimtrace::optics::spectrum::{Primaries, PrimarySpec, SpectrumSampler};
use inimtrace::optics::Lattice;
use inimtrace::overrides::Override;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The user-eye fixture (tests/data/eyes/navarro-like.toml).
fn navarro_like() -> UserEye {
    toml::from_str(&std::fs::read_to_string(root().join("tests/data/eyes/navarro-like.toml")).unwrap()).unwrap()
}

fn user_error(u: UserEye) -> String {
    match EyeModel::parse("user", Some(u), "e.toml") {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

fn sets(list: &[&str]) -> Vec<Override> {
    list.iter().map(|s| s.parse().unwrap()).collect()
}

/// `experiments/paper.toml` at tiny sizes with `extra` overrides, loaded (not run).
fn load_tiny(extra: &[&str]) -> Result<inimtrace::experiment::Experiment, String> {
    let mut all = vec![
        "display.lcd.resolution=[108, 108]",
        "eye.retina_resolution=16",
        "eye.pupil_grid=4",
        "eye_cases=[{ name = \"E\", focus_diopters = 2.5 }]",
    ];
    all.extend_from_slice(extra);
    let path = root().join("experiments/paper.toml");
    inimtrace::settings::load_experiment(Some(Path::new(&path)), None, &sets(&all)).map_err(|e| e.to_string())
}

#[test]
fn a_spectral_line_narrower_than_the_sampling_grid_is_sampled_exactly() {
    // A triangle 0.2 nm wide, between the sampler's 0.25 nm grid points: its power is all there.
    let line = PrimarySpec::Table { table: vec![[500.0, 0.0], [500.1, 1.0], [500.2, 0.0]] };
    let p = Primaries { red: line.clone(), ..Primaries::typical_lcd() };
    p.validate("d.toml").unwrap();
    let s = SpectrumSampler::new(&line);
    assert!((s.mean_nm() - 500.1).abs() < 1e-9, "mean {}", s.mean_nm());
    for k in 0..=1000 {
        let w = s.wavelength(k as f64 / 1000.0);
        assert!((500.0..=500.2).contains(&w), "u = {}: {w} nm", k as f64 / 1000.0);
    }
    assert!((s.wavelength(0.5) - 500.1).abs() < 1e-9, "{}", s.wavelength(0.5));
    // The triangle's distribution below its peak: F(w) = (w - 500)^2 / 0.02.
    let w = s.wavelength(0.125);
    assert!((w - 500.05).abs() < 1e-9, "{w}");
}

#[test]
fn huge_and_subnormal_spectral_powers_are_handled_safely() {
    // Powers near the largest double: normalised by their maximum, not summed into infinity.
    let huge = PrimarySpec::Table { table: vec![[500.0, 1e308], [510.0, 1.7e308], [520.0, 1e308]] };
    let p = Primaries { green: huge.clone(), ..Primaries::typical_lcd() };
    p.validate("d.toml").unwrap();
    let s = SpectrumSampler::new(&huge);
    assert!(s.mean_nm().is_finite() && (s.mean_nm() - 510.0).abs() < 1e-9, "{}", s.mean_nm());
    assert!((500.0..=520.0).contains(&s.wavelength(0.3)));
    // The luminance shares (CIE 1924 V(lambda)) of such tables: finite, and a narrow line at
    // 555 nm beside the same line at 450 nm in the ratio of V there (0.038).
    let w = Primaries { red: huge.clone(), green: huge.clone(), blue: huge }.luminance_weights();
    assert!(w.iter().all(|x| x.is_finite()) && (w[0] - 1.0 / 3.0).abs() < 1e-12, "{w:?}");
    let narrow = |c: f64| PrimarySpec::Table { table: vec![[c - 0.05, 0.0], [c, 1.0], [c + 0.05, 0.0]] };
    let w = Primaries { red: narrow(555.1), green: narrow(555.1), blue: narrow(450.1) }.luminance_weights();
    assert!(w.iter().all(|x| x.is_finite()), "{w:?}");
    assert!((w[2] / w[0] - 0.038).abs() < 2e-3, "{w:?}");
    // Powers that are all sub-normal carry no usable spectrum: refused, naming the table.
    let tiny = PrimarySpec::Table { table: vec![[500.0, 1e-310], [510.0, 2e-310]] };
    let e = Primaries { blue: tiny, ..Primaries::typical_lcd() }.validate("d.toml").unwrap_err().to_string();
    assert!(e.contains("primaries.blue.table") && e.contains("sub-normal"), "{e}");
}

/// A medium of index about 1.42 with a weak resonance at `pole_nm` (Sellmeier).
fn with_pole(pole_nm: f64) -> Dispersion {
    let c = (pole_nm * 1e-3).powi(2);
    Dispersion::Sellmeier { b: vec![1.0, 1e-6], c: vec![0.01, c] }
}

#[test]
fn a_sellmeier_pole_between_the_old_samples_is_found() {
    // 610 nm lies between the 600 and 625 nm samples a sampling validator would look at.
    let d = with_pole(610.0);
    assert!(d.index(600.0).is_finite() && d.index(625.0).is_finite());
    let e = d.validate("e.toml", "eye.surfaces[2].medium").unwrap_err().to_string();
    assert!(e.contains("eye.surfaces[2].medium") && e.contains("pole") && e.contains("610"), "{e}");
    // The same rule for lenslet materials.
    let lenslet = ThickLenslet {
        front: Surface { radius: 3.15, conic: 0.0 },
        back: Surface::PLANE,
        thickness: 1.0,
        material: Material { name: "user".into(), dispersion: with_pole(610.0) },
        design_cdp_mm: None,
    };
    let e = lenslet.validate(&Lattice::square(1.2).unwrap(), "d.toml", "lenslet").unwrap_err().to_string();
    assert!(e.contains("lenslet.material") && e.contains("pole"), "{e}");
    // Real glasses pass.
    Material::pmma().dispersion.validate("d", "m").unwrap();
    Material::n_bk7().dispersion.validate("d", "m").unwrap();
}

#[test]
fn a_cauchy_medium_dipping_below_one_between_samples_is_found() {
    // n = 0.9999 + 0.02 (1/lambda^2 - 1/0.6125^2)^2 (lambda in um): below 1 only within a few
    // nm of 612.5 nm, above 1 at 600 and 625 nm; the vertex of the quadratic in 1/lambda^2.
    let y = 1.0 / 0.6125f64.powi(2);
    let (c, b, a) = (0.02, -0.04 * y, 0.9999 + 0.02 * y * y);
    let d = Dispersion::Cauchy { a, b, c };
    assert!(d.index(600.0) > 1.0 && d.index(625.0) > 1.0 && d.index(612.5) < 1.0);
    let e = d.validate("e.toml", "m").unwrap_err().to_string();
    assert!(e.contains("nm is 0.9999"), "{e}");
}

#[test]
fn a_medium_infinite_at_the_reference_wavelength_is_named_not_the_iris() {
    let mut u = navarro_like();
    u.surfaces[1].medium = with_pole(555.0);
    let e = match EyeModel::parse("user", Some(u), "e.toml") {
        Ok(m) => SchematicEye::new(&m, 0.0, "e.toml").err().map(|e| e.to_string()).unwrap_or_default(),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("eye.surfaces[1].medium") && !e.contains("iris"), "{e}");
}

#[test]
fn user_eye_surfaces_that_cross_inside_their_semi_diameters_are_refused() {
    // The lens 1 mm thick at the centre: its convex faces meet 2.6 mm inside its semi-diameter.
    let mut u = navarro_like();
    u.surfaces[2].thickness = 1.0;
    let e = user_error(u);
    assert!(e.contains("eye.surfaces[2]") && e.contains("cross"), "{e}");
    // The last surface and the retina are checked alike.
    let mut u = navarro_like();
    u.surfaces[3].thickness = 0.5;
    u.retina_radius = -2.0;
    let e = user_error(u);
    assert!(e.contains("eye.surfaces[3]") && e.contains("retina"), "{e}");
    assert_eq!(user_error(navarro_like()), "");
}

#[test]
fn a_user_eye_iris_inside_a_surface_is_refused() {
    // 0.5 mm behind the cornea's back vertex: the cornea's back surface curves past it 2.9 mm
    // from the axis, inside its semi-diameter.
    let mut u = navarro_like();
    u.iris.distance = 0.5;
    let e = user_error(u);
    assert!(e.contains("eye.iris") && e.contains("cornea-back"), "{e}");
}

#[test]
fn user_eye_surface_names_are_unique() {
    let mut u = navarro_like();
    u.surfaces[2].name = Some("cornea-back".into());
    let e = user_error(u);
    assert!(e.contains("eye.surfaces[2].name") && e.contains("cornea-back"), "{e}");
}

#[test]
fn reference_wavelengths_lie_in_one_range_everywhere() {
    let mut u = navarro_like();
    u.reference_wavelength = Some(1100.0);
    let e = user_error(u);
    assert!(e.contains("eye.reference_wavelength") && e.contains("380") && e.contains("780"), "{e}");
    let e = load_tiny(&["eye.wavelength_nm=1100.0"]).err().unwrap_or_default();
    assert!(e.contains("380") && e.contains("780"), "{e}");
}

#[test]
fn a_retina_too_small_for_the_field_is_refused() {
    let eye = std::fs::read_to_string(root().join("tests/data/eyes/navarro-like.toml")).unwrap();
    let table: toml::Table = toml::from_str(&eye.replace("retina_radius = -12.0", "retina_radius = -1.0")).unwrap();
    let value = toml::Value::Table(table);
    let set = format!("eye.user={}", inline(&value));
    // A pinhole eye: the user eye has no accommodation to reach the tiny experiment's focus.
    let pinhole = "eye_cases=[{ name = \"E\", pinhole = true }]";
    let e = load_tiny(&["eye.model=\"user\"", &set, pinhole]).err().unwrap_or_default();
    assert!(e.contains("eye.retina_radius") || e.contains("eye.user.retina_radius"), "{e}");
    assert!(e.contains("field"), "{e}");
}

/// A TOML value as one inline expression (for `--set`).
fn inline(v: &toml::Value) -> String {
    match v {
        toml::Value::Table(t) => {
            let items: Vec<String> = t.iter().map(|(k, v)| format!("{k} = {}", inline(v))).collect();
            format!("{{ {} }}", items.join(", "))
        }
        toml::Value::Array(a) => format!("[{}]", a.iter().map(inline).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

#[test]
fn a_paraxial_lenslet_with_thick_lenslet_fields_is_refused() {
    let text = std::fs::read_to_string(root().join("displays/paper.toml")).unwrap()
        + "\n[lenslet]\nkind = \"paraxial\"\nthickness = 1.0\n";
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.toml");
    std::fs::write(&path, text).unwrap();
    let e = inimtrace::io::display_file::load_display(&path.display().to_string(), Path::new(""))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("thickness") && e.contains("d.toml"), "{e}");
}

#[test]
fn stiles_crawford_weights_stay_finite_and_average_one_with_the_peak_at_the_edge() {
    // Uniform points of the disk (a stratified polar grid), drawn as the estimators draw them:
    // the warp, then the weight. Their mean weight is the estimate of a uniform scene's value.
    for (rho, radius, peak) in [(0.05, 2.5, 0.5), (1.0, 2.5, 2.5), (1.0, 5.0, 5.0), (1.0, 50.0, 50.0)] {
        let sc = StilesCrawford::new(rho, DVec2::new(peak, 0.0), radius);
        let n = 600;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (s, a) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let p = DVec2::from_angle(std::f64::consts::TAU * a) * radius * s.sqrt();
                let w = sc.weight(sc.warp(p, radius));
                assert!(w.is_finite() && w >= 0.0, "rho {rho}, radius {radius}: weight {w} at {p}");
                sum += w;
            }
        }
        let mean = sum / (n * n) as f64;
        assert!((mean - 1.0).abs() < 0.02, "rho {rho}, pupil radius {radius}, peak {peak}: mean weight {mean}");
    }
}

#[test]
fn a_stiles_crawford_peak_at_the_pupils_edge_gives_no_silent_black_image() {
    // Before: the weights of the grid's pupil points underflowed to nothing, every image was
    // black and every PSNR above 180 dB (or NaN with a 100 mm pupil).
    for pupil in ["10.0", "100.0"] {
        let peak = format!("eye.stiles_crawford_peak=[{}, 0.0]", pupil.parse::<f64>().unwrap() / 2.0);
        let pd = format!("eye.pupil_diameter={pupil}");
        match load_tiny(&["eye.stiles_crawford_rho=1.0", &peak, &pd]) {
            Err(e) => assert!(e.contains("eye.pupil_grid") || e.contains("stiles_crawford"), "{e}"),
            Ok(exp) => {
                let a = inimtrace::experiment::assess_images(&exp, None, Default::default());
                match a {
                    Err(e) => panic!("pupil {pupil}: {e}"),
                    Ok(a) => {
                        for s in &a.report.scores {
                            assert!(s.psnr.mean < 100.0, "pupil {pupil}: {} {}", s.method, s.psnr.mean);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn a_duplicated_opt_training_state_is_refused() {
    let path = root().join("experiments/paper-optimal.toml");
    let load = |extra: &[&str]| {
        inimtrace::settings::load_experiment(Some(&path), None, &sets(extra)).err().map(|e| e.to_string())
    };
    let e = load(&["optimize.train_cases=[\"Near\", \"Near\"]"]).unwrap_or_default();
    assert!(e.contains("optimize.train_cases[1]") && e.contains("Near"), "{e}");
    let e = load(&["optimize.train_cases=[\"Near\"]", "optimize.states=[{ name = \"Near\", focus_mm = 250.0 }]"])
        .unwrap_or_default();
    assert!(e.contains("optimize.states[0]") && e.contains("Near"), "{e}");
    let e = load(&["optimize.train_cases=[\"Near\"]", "optimize.states=[{ name = \"again\", focus_mm = 300.0 }]"])
        .unwrap_or_default();
    assert!(e.contains("optimize.states[0]") && e.contains("Near"), "same eye as Near: {e}");
}

#[test]
fn grating_orientations_a_half_turn_apart_are_one_grating() {
    let load = |o: &str| {
        inimtrace::resolution::study::Study::load(
            &root().join("studies/tiny.toml"),
            &sets(&[&format!("orientations_deg={o}")]),
        )
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default()
    };
    let e = load("[0.0, 179.9999999999]");
    assert!(e.contains("orientations_deg[1]") && e.contains("0"), "{e}");
    let e = load("[0.0, 45.0, 44.99999999999]");
    assert!(e.contains("orientations_deg[2]"), "{e}");
}

#[test]
fn inapplicable_settings_are_errors_as_unknown_ones_are() {
    // The grid estimator (experiments/paper.toml) has no replicates, seed or targets.
    for (set, field) in [
        ("measurement.replicates=5", "measurement.replicates"),
        ("measurement.seed=3", "measurement.seed"),
        ("measurement.psnr_ci95_db=0.1", "measurement.psnr_ci95_db"),
        ("eye.focus_criterion=\"min-rms-spot\"", "eye.focus_criterion"),
        ("eye.wavelength_nm=500.0", "eye.wavelength_nm"),
        ("eye.spectrum=\"primaries\"", "eye.spectrum"),
        ("eye.wavelength_samples=5", "eye.wavelength_samples"),
    ] {
        let e = load_tiny(&[set]).err().unwrap_or_default();
        assert!(e.contains(field), "{set}: {e}");
    }
    // The converged estimator samples the wavelengths: no grid of them to set.
    let path = root().join("experiments/navarro.toml");
    let e = inimtrace::settings::load_experiment(Some(&path), None, &sets(&["eye.wavelength_samples=5"]))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("eye.wavelength_samples"), "{e}");
    // What applies is still accepted.
    load_tiny(&["eye.model=\"navarro\"", "eye.wavelength_samples=5", "eye.focus_criterion=\"paraxial\""]).unwrap();
}
