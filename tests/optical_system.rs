//! The optical system (`optics/system.rs`), decided once: every kernel it picks against its
//! slow twin (one sample at a time), bit for bit, on random samples of every kind of eye and
//! lenslet, straight ahead and turned to a gaze; the grid's order against the per-pixel trace;
//! and the kernel each eye gets.

use std::path::Path;

use glam::DVec2;
use inimtrace::fixtures::Lcg;
use inimtrace::io::display_file::load_display;
use inimtrace::optics::diffraction::Diffraction;
use inimtrace::optics::eye::settings::pose_of;
use inimtrace::optics::eye::{CentreOfRotation, EyeModel, EyeOptics, EyeOpticsSpec, FocusCriterion, Gaze};
use inimtrace::optics::spectrum::Primaries;
use inimtrace::optics::system::{EyeSample, GridBuffers, Kernel, OpticalSystem, Traces};
use inimtrace::optics::{Display, Eye, Focus, Retina};

fn spec(model: EyeModel, primaries: bool, sc: bool, diffraction: Diffraction) -> EyeOpticsSpec {
    EyeOpticsSpec {
        model,
        criterion: FocusCriterion::Paraxial,
        reference_nm: 555.0,
        primaries,
        wavelength_samples: 3,
        stiles_crawford: sc.then_some((0.05, DVec2::new(0.3, -0.2))),
        diffraction: Diffraction::None,
    }
    .with_diffraction(diffraction, primaries)
}

fn eye(spec: Option<EyeOpticsSpec>) -> Eye {
    let mut eye = Eye::thin_lens(4.0, Focus::Diopters(2.5), 4);
    if let Some(s) = spec {
        eye.optics = EyeOptics::build(&s, &eye.aperture, 17.0, &Primaries::default(), 0.3, "test", "eye").unwrap();
    }
    eye
}

fn pmma() -> Display {
    load_display("displays/paper-pmma.toml", Path::new(env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// `eye` turned to a gaze of [9, -6] degrees about the default centre.
fn turned(eye: Eye) -> Eye {
    let (gaze, centre) = (Gaze::new(9.0, -6.0), CentreOfRotation::default());
    Eye { pose: pose_of(&EyeModel::ThinLens, gaze, centre, eye.position, "t").unwrap(), ..eye }
}

/// Every kind of system: (name, display, eye, the kernel it must get).
fn systems() -> Vec<(&'static str, Display, Eye, Kernel)> {
    let paper = Display::paper();
    let thin = || eye(None);
    let navarro = |sc| eye(Some(spec(EyeModel::Navarro1985, true, sc, Diffraction::None)));
    let thin_diffracted = || eye(Some(spec(EyeModel::ThinLens, true, false, Diffraction::Apertures)));
    let thin_sc_diffracted = || eye(Some(spec(EyeModel::ThinLens, true, true, Diffraction::Apertures)));
    vec![
        ("thin lens", paper.clone(), thin(), Kernel::Paraxial),
        ("thin lens, thick lenslets", pmma(), thin(), Kernel::ThinThick),
        ("navarro", paper.clone(), navarro(false), Kernel::EyeRays),
        ("navarro, stiles-crawford", paper.clone(), navarro(true), Kernel::EyeRays),
        ("thin lens, diffraction", paper.clone(), thin_diffracted(), Kernel::ThinDiffracted),
        ("thin lens, stiles-crawford, diffraction", paper.clone(), thin_sc_diffracted(), Kernel::General),
        ("navarro, thick lenslets", pmma(), navarro(false), Kernel::General),
        ("thin lens, diffraction, thick lenslets", pmma(), thin_diffracted(), Kernel::General),
        ("thin lens, turned", paper.clone(), turned(thin()), Kernel::Rotated),
        ("thin lens, thick lenslets, turned", pmma(), turned(thin()), Kernel::Rotated),
        ("navarro, stiles-crawford, turned", paper.clone(), turned(navarro(true)), Kernel::Rotated),
        ("thin lens, diffraction, turned", paper.clone(), turned(thin_diffracted()), Kernel::Rotated),
    ]
}

fn random_samples(rng: &mut Lcg, count: usize) -> Vec<EyeSample> {
    (0..count)
        .map(|_| {
            let (r, a) = (2.0 * rng.next().sqrt(), std::f64::consts::TAU * rng.next());
            EyeSample {
                tangent: DVec2::new(rng.range(-0.25, 0.25), rng.range(-0.25, 0.25)),
                pupil: DVec2::new(r * a.cos(), r * a.sin()),
                spectral: rng.next(),
                diffraction: std::array::from_fn(|_| rng.next()),
            }
        })
        .collect()
}

#[test]
fn every_eye_gets_its_kernel_and_every_kernel_traces_the_bits_of_its_slow_twin() {
    let mut rng = Lcg(2024);
    for (name, display, eye, kernel) in systems() {
        let system = OpticalSystem::new(&display, &eye);
        assert_eq!(system.kernel(), kernel, "{name}");
        // Odd and even batch sizes (pairs of samples share a schematic eye's ray map).
        for count in [1, 7, 64] {
            let samples = random_samples(&mut rng, count);
            let (mut fast, mut slow) = (Traces::default(), Traces::default());
            system.trace(&samples, &[], &mut fast);
            system.trace_each(&samples, &mut slow);
            assert_eq!(fast.samples, slow.samples, "{name}: {count} samples");
            assert_eq!(fast.scene, slow.scene, "{name}: {count} samples");
            assert_eq!(fast.samples.len(), count, "{name}");
            // Something is seen: not every sample off the LCD.
            assert!(fast.samples.iter().any(|t| t.lcd.iter().any(|&l| l < u32::MAX - 1)), "{name}");
        }
    }
}

#[test]
fn the_grid_traces_each_pixels_samples_as_tracing_them_one_pixel_at_a_time() {
    let retina = Retina { resolution: 9, half_tangent: 0.2, samples_per_pixel: 2 };
    let draws = |pixel: u64, k: u64| [((pixel * 7 + k) % 10) as f64 / 10.0, 0.35, 0.6, ((k * 3) % 10) as f64 / 10.0];
    for (name, display, eye, _) in systems() {
        for system in [OpticalSystem::new(&display, &eye), OpticalSystem::geometric(&display, &eye)] {
            let n = retina.resolution;
            // Each pixel's samples, in the order the grid gives them.
            let mut per_pixel: Vec<Vec<(inimtrace::optics::system::Traced, Vec<u64>)>> = vec![Vec::new(); n * n];
            let mut buf = GridBuffers::default();
            system.trace_grid(&retina, 0..n, 4, true, &draws, &mut buf, |pixels, t| {
                for (&p, s) in pixels.iter().zip(&t.samples) {
                    let rays = (0..3).filter_map(|c| s.scene_ray(c)).map(|j| t.scene[j].dir.x.to_bits()).collect();
                    per_pixel[p as usize].push((*s, rays));
                }
            });
            let mut samples = Vec::new();
            let mut traces = Traces::default();
            for row in 0..n {
                for col in 0..n {
                    system.grid_samples(&retina, (row, col), &draws, &mut samples);
                    assert_eq!(samples.len(), system.grid_samples_per_pixel(&retina), "{name}");
                    system.trace_each(&samples, &mut traces);
                    let got = &per_pixel[row * n + col];
                    assert_eq!(got.len(), samples.len(), "{name} ({row}, {col})");
                    for (i, t) in traces.samples.iter().enumerate() {
                        let rays: Vec<u64> =
                            (0..3).filter_map(|c| t.scene_ray(c)).map(|j| traces.scene[j].dir.x.to_bits()).collect();
                        // Same LCD pixels and weights; the closed form's LCD pixel is the same
                        // bits through a pupil-grid index as through the pupil point.
                        assert_eq!((got[i].0.lcd, got[i].0.weight, got[i].0.rays), (t.lcd, t.weight, t.rays), "{name}");
                        assert_eq!(got[i].1, rays, "{name} ({row}, {col}) sample {i}");
                    }
                }
            }
        }
    }
}

#[test]
fn a_geometric_system_does_not_diffract() {
    let display = Display::paper();
    let e = eye(Some(spec(EyeModel::ThinLens, true, false, Diffraction::Apertures)));
    assert!(OpticalSystem::new(&display, &e).needs_diffraction());
    let geometric = OpticalSystem::geometric(&display, &e);
    assert!(!geometric.needs_diffraction());
    assert_eq!(geometric.kernel(), Kernel::EyeRays);
}
