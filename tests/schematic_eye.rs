//! Physics of the schematic eyes (src/optics/eye/): published powers against an independent
//! y-nu trace, Navarro's accommodation and chromatic aberration against an independent
//! brute-force real-ray calculation, the invariants of tracing and the hard cases.

use glam::{DVec2, DVec3};
use inimtrace::optics::eye::conic::Conic;
use inimtrace::optics::eye::{Dispersion, EyeModel, FocusCriterion, SchematicEye, UserEye};
use inimtrace::optics::PlaneRay;

/// A small deterministic generator.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Independent y-nu trace: power (D) of surfaces `radii` between indices `n` (n[0] = 1) with
/// vertex separations `d`.
fn ynu_power(radii: &[f64], n: &[f64], d: &[f64]) -> f64 {
    let (mut y, mut nu) = (1.0, 0.0);
    for i in 0..radii.len() {
        nu -= y * (n[i + 1] - n[i]) / radii[i];
        if i < d.len() {
            y += d[i] * nu / n[i + 1];
        }
    }
    -1000.0 * nu
}

#[test]
fn published_powers_match_an_independent_ynu_trace() {
    // Navarro et al. 1985 Table 1 (589.3 nm): 60.416 D.
    let nav = ynu_power(&[7.72, 6.5, 10.2, -6.0], &[1.0, 1.376, 1.3374, 1.42, 1.336], &[0.55, 3.05, 4.0]);
    // Le Grand & El Hage 1980 (Atchison & Smith 2000, Appendix 3): 59.94 D.
    let lg = ynu_power(&[7.8, 6.5, 10.2, -6.0], &[1.0, 1.3771, 1.3374, 1.42, 1.336], &[0.55, 3.05, 4.0]);
    // Arizona eye (Schwiegerling 2004, p. 16) at A = 0, nd indices: its parameters give 60.62 D.
    let az = ynu_power(&[7.8, 6.5, 12.0, -5.224557], &[1.0, 1.377, 1.337, 1.42, 1.336], &[0.55, 2.97, 3.767]);
    for (model, independent, published) in [
        (EyeModel::Navarro1985, nav, 60.416),
        (EyeModel::Navarro1999, nav, 60.416),
        (EyeModel::LeGrand, lg, 59.94),
        (EyeModel::Arizona, az, 60.62),
    ] {
        let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
        let p = eye.paraxial(589.3);
        println!("{}: {:.4} D (independent {independent:.4}, published {published})", model.name(), p.power_d);
        assert!((p.power_d - independent).abs() < 1e-9, "{}", model.name());
        assert!((p.power_d - published).abs() < 0.05, "{}", model.name());
        // The frame's origin is the entrance pupil at the reference wavelength.
        assert!(eye.paraxial(555.0).entrance_pupil_z.abs() < 1e-12);
        assert!((p.cornea_z - 3.0).abs() < 0.1 && (p.retina_z + 21.0).abs() < 0.3, "{p:?}");
    }
    // Le Grand's cardinal points from the cornea vertex (Le Grand & El Hage 1980; Atchison &
    // Smith 2000): F -15.089, F' 24.197, H 1.595, H' 1.908, N 7.200, N' 7.513 mm.
    let eye = SchematicEye::new(&EyeModel::LeGrand, 0.0, "t").unwrap();
    let p = eye.paraxial(589.3);
    let t = |z: f64| p.cornea_z - z;
    for (got, want) in [
        (t(p.front_focal_z), -15.089),
        (t(p.back_focal_z), 24.197),
        (t(p.principal_z.0), 1.595),
        (t(p.principal_z.1), 1.908),
        (t(p.nodal_z.0), 7.200),
        (t(p.nodal_z.1), 7.513),
    ] {
        assert!((got - want).abs() < 0.005, "{got} vs {want}");
    }
}

/// The Navarro 1985 eye at accommodation `a`, written here from the paper's Tables 1-2.
fn independent_navarro(a: f64) -> (Vec<Conic>, Conic, [Dispersion; 4]) {
    let l = (a + 1.0).ln();
    let aq = 3.05 - 0.05 * l;
    let lens = 4.0 + 0.1 * l;
    let t = [0.0, 0.55, 0.55 + aq, 0.55 + aq + lens];
    let s = vec![
        Conic::from_radius(t[0], 7.72, -0.26, 5.5),
        Conic::from_radius(t[1], 6.5, 0.0, 5.5),
        Conic::from_radius(t[2], 10.2 - 1.75 * l, -3.1316 - 0.34 * l, 4.5),
        Conic::from_radius(t[3], -6.0 + 0.2294 * l, -1.0 - 0.125 * l, 4.5),
    ];
    let retina = Conic::from_radius(24.0, -12.0, 0.0, 12.0);
    // Table 3 indices through Table 1's 589.3 nm values.
    let nav = |n: [f64; 4], n589: f64| {
        let off = n589 - Dispersion::Navarro { n, offset: 0.0 }.index(589.3);
        Dispersion::Navarro { n, offset: off }
    };
    let m = [
        nav([1.3975, 1.3807, 1.37405, 1.3668], 1.376),
        nav([1.3593, 1.3422, 1.3354, 1.3278], 1.3374),
        nav([1.4492, 1.4263, 1.4175, 1.4097], 1.42 + 9e-5 * (10.0 * a + a * a)),
        nav([1.3565, 1.3407, 1.3341, 1.3273], 1.336),
    ];
    (s, retina, m)
}

fn snell(d: DVec3, nrm: DVec3, n1: f64, n2: f64) -> Option<DVec3> {
    let nrm = if nrm.dot(d) > 0.0 { -nrm } else { nrm };
    let c = -nrm.dot(d);
    let e = n1 / n2;
    let k = 1.0 - e * e * (1.0 - c * c);
    (k >= 0.0).then(|| e * d + (e * c - k.sqrt()) * nrm)
}

/// Brute force: best-focus object vergence (D from the entrance pupil at 555 nm) by the least
/// RMS radius of a square grid of rays over a 4 mm entrance pupil, traced with the slow
/// root-finding intersection.
fn brute_force_best_focus(a: f64, wavelength: f64) -> f64 {
    let (surfaces, retina, media) = independent_navarro(a);
    // Entrance pupil at 555 nm: the image of the iris (at the lens front vertex) through the
    // cornea, by a paraxial y-nu trace backward from the iris centre.
    let n555: Vec<f64> = std::iter::once(1.0).chain(media.iter().map(|m| m.index(555.0))).collect();
    let iris_t = surfaces[2].vertex;
    // A ray from the iris centre with n u = 1 traced back out to air.
    let (mut y, mut nu) = (0.0, 1.0);
    y -= (iris_t - surfaces[1].vertex) * nu / n555[2];
    nu += y * (n555[2] - n555[1]) * surfaces[1].curvature; // reversed refraction
    y -= (surfaces[1].vertex - surfaces[0].vertex) * nu / n555[1];
    nu += y * (n555[1] - n555[0]) * surfaces[0].curvature;
    let ep_t = -y / nu; // where the outgoing air ray crosses the axis, from the cornea vertex
    let n: Vec<f64> = std::iter::once(1.0).chain(media.iter().map(|m| m.index(wavelength))).collect();
    let rms = |v: f64| {
        let (mut sum, mut count) = (0.0, 0.0);
        let k = 24;
        for i in 0..k {
            for j in 0..k {
                let px = -2.0 + 4.0 * (i as f64 + 0.5) / k as f64;
                let py = -2.0 + 4.0 * (j as f64 + 0.5) / k as f64;
                if px * px + py * py > 4.0 {
                    continue;
                }
                // Object point on the axis at distance 1000/v in front of the pupil.
                let pupil = DVec3::new(px, py, ep_t);
                let d = if v == 0.0 {
                    DVec3::Z
                } else {
                    (pupil - DVec3::new(0.0, 0.0, ep_t - 1000.0 / v)).normalize() * v.signum()
                };
                let mut p = pupil + (-5.0 - ep_t) / d.z * d;
                let mut d = d;
                let mut ok = true;
                for (s, i) in surfaces.iter().zip(0..) {
                    match s.intersect_by_root_finding(p, d, 40.0, 800) {
                        Some(h) => {
                            p = h.point;
                            match snell(d, s.normal(p), n[i], n[i + 1]) {
                                Some(dd) => d = dd,
                                None => ok = false,
                            }
                        }
                        None => ok = false,
                    }
                    if !ok {
                        break;
                    }
                }
                if !ok {
                    continue;
                }
                let h = retina.intersect_by_root_finding(p, d, 40.0, 800).unwrap();
                sum += h.point.x * h.point.x + h.point.y * h.point.y;
                count += 1.0;
            }
        }
        sum / count
    };
    // Golden-section search over a generous bracket.
    let (mut lo, mut hi) = (a - 2.0, a + 3.0);
    let mut best = (f64::INFINITY, a);
    for i in 0..=25 {
        let v = lo + (hi - lo) * i as f64 / 25.0;
        let r = rms(v);
        if r < best.0 {
            best = (r, v);
        }
    }
    let h = (hi - lo) / 25.0;
    (lo, hi) = (best.1 - h, best.1 + h);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    while hi - lo > 1e-4 {
        let (c, d) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if rms(c) < rms(d) {
            hi = d;
        } else {
            lo = c;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn navarro_accommodation_and_chromatic_aberration_match_brute_force() {
    let model = EyeModel::Navarro1985;
    for a in [0.0, 1.0, 2.0, 3.0, 5.0, 10.0] {
        let eye = SchematicEye::new(&model, a, "t").unwrap();
        let ours = eye.best_focus_vergence(550.0, FocusCriterion::MinRmsSpot, 4.0).unwrap();
        let brute = brute_force_best_focus(a, 550.0);
        println!("A = {a} D: best focus {ours:.4} D, brute force {brute:.4} D");
        assert!((ours - brute).abs() < 0.05, "A = {a}: {ours} vs {brute}");
    }
    // Longitudinal chromatic aberration 450-650 nm. Published: Thibos et al., "The chromatic
    // eye", Appl. Opt. 31:3594 (1992), Rx(λ) = 1.68524 - 0.63346/(λ - 0.2141) (µm) gives 1.23 D;
    // Atchison & Smith, JOSA A 22:29 (2005), report Navarro's dispersion within that range.
    let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
    let lca = eye.best_focus_vergence(450.0, FocusCriterion::MinRmsSpot, 4.0).unwrap()
        - eye.best_focus_vergence(650.0, FocusCriterion::MinRmsSpot, 4.0).unwrap();
    let brute = brute_force_best_focus(0.0, 450.0) - brute_force_best_focus(0.0, 650.0);
    println!("LCA 450-650 nm: {lca:.4} D, brute force {brute:.4} D");
    assert!((lca - brute).abs() < 0.05, "{lca} vs {brute}");
    assert!((1.0..=1.5).contains(&lca), "{lca}");
}

fn user_eye() -> UserEye {
    toml::from_str(include_str!("data/eyes/navarro-like.toml")).unwrap()
}

fn all_models() -> Vec<EyeModel> {
    let user = EyeModel::parse("user", Some(user_eye()), "t").unwrap();
    vec![EyeModel::Navarro1985, EyeModel::Navarro1999, EyeModel::Arizona, EyeModel::LeGrand, user]
}

#[test]
fn out_then_in_returns_to_the_retina_point_and_the_retina_table_is_exact() {
    let mut rng = Lcg(11);
    for model in all_models() {
        let (_, hi) = model.accommodation_range();
        for a in [0.0, hi] {
            let eye = SchematicEye::new(&model, a, "t").unwrap().with_pupil(6.0);
            let r_iris = eye.iris_radius().unwrap();
            let mut worst: f64 = 0.0;
            for _ in 0..300 {
                let t = DVec2::new(rng.next() - 0.5, rng.next() - 0.5) * 0.8;
                let retina = eye.retina_point(t);
                let (rad, ang) = (r_iris * rng.next().sqrt(), rng.next() * std::f64::consts::TAU);
                let iris = DVec2::new(rad * ang.cos(), rad * ang.sin());
                for w in [450.0, 555.0, 650.0] {
                    let Some(out) = eye.ray_out(retina, iris, w) else {
                        panic!("{} A {a}: blocked {retina} {iris} {w}", model.name())
                    };
                    assert!(out.position.is_finite() && out.slope.is_finite());
                    let (back, crossing) = eye.ray_in(out, w).unwrap();
                    assert!((back - retina).length() < 1e-9, "{} {}", model.name(), (back - retina).length());
                    assert!((crossing - iris).length() < 1e-9);
                    worst = worst.max((back - retina).length());
                }
            }
            println!("{} A {a}: worst round trip {worst:.2e} mm", model.name());
            // The retina table against the exact chief ray over tangents up to 0.6.
            for i in 0..400 {
                let t = DVec2::new(rng.next() - 0.5, rng.next() - 0.5) * 1.2 * (i as f64 / 400.0);
                let exact = eye.retina_point_exact(t).unwrap();
                assert!((eye.retina_point(t) - exact).length() < 1e-9, "{} {t}", model.name());
            }
        }
    }
}

#[test]
fn rays_that_miss_are_lost_without_nan() {
    let eye = SchematicEye::new(&EyeModel::Navarro1985, 0.0, "t").unwrap();
    // Far off axis: misses the cornea's semi-diameter.
    assert!(eye.ray_in(PlaneRay { position: DVec2::new(20.0, 0.0), slope: DVec2::ZERO }, 555.0).is_none());
    // Steeply inclined: meets the cornea beyond its edge.
    assert!(eye.ray_in(PlaneRay { position: DVec2::ZERO, slope: DVec2::new(50.0, 0.0) }, 555.0).is_none());
    // Aiming at an iris point beyond the lens's reach from a far retina point.
    let r = eye.retina_point(DVec2::new(0.9, 0.0));
    assert!(eye.ray_out(r, DVec2::new(-4.4, 0.0), 555.0).is_none());
    // Non-finite input.
    assert!(eye.ray_out(DVec3::NAN, DVec2::ZERO, 555.0).is_none());
    assert!(eye.ray_in(PlaneRay { position: DVec2::NAN, slope: DVec2::ZERO }, 555.0).is_none());
    assert!(eye.retina_point(DVec2::new(5.0, 0.0)).is_finite());
}

#[test]
fn total_internal_reflection_loses_the_ray() {
    // Glass (1.7) then an air bubble behind a steep concave surface: a ray 1.8 mm off axis meets
    // it at 64 degrees, beyond the 36 degree critical angle.
    let mut u = user_eye();
    u.surfaces[0].radius = 0.0;
    u.surfaces[0].medium = Dispersion::Constant(1.7);
    u.surfaces[0].thickness = 3.0;
    u.surfaces[1].radius = -2.0;
    u.surfaces[1].semi_diameter = 1.95;
    u.surfaces[1].medium = Dispersion::Constant(1.0);
    u.iris.distance = 1.0;
    let model = EyeModel::parse("user", Some(u), "t").unwrap();
    let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
    let lost = eye.ray_in(PlaneRay { position: DVec2::new(1.8, 0.0), slope: DVec2::ZERO }, 555.0);
    assert!(lost.is_none(), "{lost:?}");
    assert!(eye.ray_in(PlaneRay { position: DVec2::new(0.3, 0.0), slope: DVec2::ZERO }, 555.0).is_some());
}

#[test]
fn iris_edge_passes_and_just_beyond_is_blocked() {
    for model in all_models() {
        let eye = SchematicEye::new(&model, 0.0, "t").unwrap().with_pupil(6.0);
        let r = eye.iris_radius().unwrap();
        assert!((2.0 * r - eye.iris_diameter(6.0)).abs() < 1e-15);
        let retina = eye.retina_point(DVec2::new(0.3, -0.2));
        for dir in [DVec2::X, DVec2::Y, DVec2::new(-0.6, 0.8)] {
            let out = eye.ray_out(retina, dir * r, 555.0).expect("the edge passes");
            let (back, crossing) = eye.ray_in(out, 555.0).expect("and comes back in");
            assert!((back - retina).length() < 1e-9 && (crossing.length() - r).abs() < 1e-9);
            assert!(eye.ray_out(retina, dir * r * (1.0 + 1e-9), 555.0).is_none(), "just beyond is blocked");
            assert!(eye.ray_out(retina, dir * (r + 1e-6), 555.0).is_none());
        }
    }
}

#[test]
fn accommodation_at_the_ends_of_the_range_and_beyond() {
    for model in [EyeModel::Navarro1985, EyeModel::Navarro1999, EyeModel::Arizona] {
        let (lo, hi) = model.accommodation_range();
        for a in [lo, hi] {
            let eye = SchematicEye::new(&model, a, "t").unwrap();
            assert!(eye.paraxial(555.0).power_d.is_finite());
            assert!(eye.ray_out(eye.retina_point(DVec2::new(0.4, 0.0)), DVec2::new(2.0, 1.0), 555.0).is_some());
        }
        for a in [hi + 1e-9, lo - 0.5, f64::NAN, f64::INFINITY] {
            let e = SchematicEye::new(&model, a, "exp.toml").unwrap_err().to_string();
            assert!(e.contains("exp.toml") && e.contains("accommodation") && e.contains("0..10"), "{e}");
        }
    }
    let e = SchematicEye::new(&EyeModel::LeGrand, 1.0, "t").unwrap_err().to_string();
    assert!(e.contains("0..0"), "{e}");
    assert!(SchematicEye::new(&EyeModel::ThinLens, 0.0, "t").is_err());
}

#[test]
fn hyperboloid_and_paraboloid_surfaces_trace() {
    // The Arizona lens front is a hyperboloid (Q = -7.5), Navarro's lens back a paraboloid at A = 0.
    for model in [EyeModel::Arizona, EyeModel::Navarro1985] {
        let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
        for h in [0.0, 1.0, 2.5, 3.5] {
            let (p, _) = eye.ray_in(PlaneRay { position: DVec2::new(h, 0.0), slope: DVec2::ZERO }, 555.0).unwrap();
            assert!(p.is_finite() && p.x.abs() < 0.2, "{p}");
        }
    }
}

#[test]
fn unreachable_focus_is_an_error_naming_the_field_and_the_range() {
    for v in [25.0, -8.0] {
        let e = SchematicEye::focused(
            &EyeModel::Navarro1985,
            v,
            555.0,
            FocusCriterion::Paraxial,
            4.0,
            "exp.toml",
            "eye.focus",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("eye.focus") && e.contains("focuses") && e.contains("0..10"), "{e}");
    }
    let e = SchematicEye::focused(&EyeModel::LeGrand, 2.0, 555.0, FocusCriterion::MinRmsSpot, 4.0, "x", "eye.focus")
        .unwrap_err()
        .to_string();
    assert!(e.contains("eye.focus"), "{e}");
    assert!(
        SchematicEye::focused(&EyeModel::Arizona, f64::NAN, 555.0, FocusCriterion::Paraxial, 4.0, "x", "f").is_err()
    );
}

#[test]
fn focused_paraxially_puts_the_conjugate_on_the_requested_vergence() {
    for model in [EyeModel::Navarro1985, EyeModel::Navarro1999, EyeModel::Arizona] {
        for v in [0.5, 1.0, 2.5, 5.0] {
            for w in [555.0, 600.0] {
                let (eye, a) = SchematicEye::focused(&model, v, w, FocusCriterion::Paraxial, 4.0, "t", "f").unwrap();
                let got = eye.paraxial(w).conjugate_vergence_d;
                assert!((got - v).abs() < 1e-6, "{} {v} {w}: {got} at A = {a}", model.name());
                assert_eq!(eye.accommodation(), a);
            }
        }
        // And by the minimum RMS spot: the focus is where the criterion says.
        let (eye, _) = SchematicEye::focused(&model, 2.0, 555.0, FocusCriterion::MinRmsSpot, 4.0, "t", "f").unwrap();
        let best = eye.best_focus_vergence(555.0, FocusCriterion::MinRmsSpot, 4.0).unwrap();
        assert!((best - 2.0).abs() < 1e-6, "{best}");
    }
}

#[test]
#[ignore = "timing; run with --ignored --nocapture in release"]
fn ray_out_speed() {
    for model in all_models() {
        let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
        let at = eye.at(555.0);
        let retina: Vec<DVec3> = (0..64).map(|i| eye.retina_point(DVec2::new(0.01 * i as f64 - 0.3, 0.2))).collect();
        let n = 200_000;
        let t0 = std::time::Instant::now();
        let mut ok = 0;
        for i in 0..n {
            let a = i as f64 * 0.618;
            let iris = DVec2::new(a.cos(), a.sin()) * 2.5 * ((i % 97) as f64 / 97.0).sqrt();
            ok += at.ray_out(retina[i % 64], iris).is_some() as usize;
        }
        let ns = t0.elapsed().as_nanos() as f64 / n as f64;
        let t0 = std::time::Instant::now();
        let mut acc = 0.0;
        for i in 0..n {
            acc += eye.retina_point(DVec2::new(0.3 * (i as f64 * 0.001).sin(), 0.1)).x;
        }
        let ns_retina = t0.elapsed().as_nanos() as f64 / n as f64;
        let t0 = std::time::Instant::now();
        let _ = SchematicEye::focused(&model, 0.0, 555.0, FocusCriterion::MinRmsSpot, 4.0, "t", "f");
        println!(
            "{}: ray_out {ns:.0} ns ({ok}/{n}), retina_point {ns_retina:.1} ns ({acc:.1}), focused(min-rms) {:?}",
            model.name(),
            t0.elapsed()
        );
    }
}

/// A scene whose three channels differ along every direction.
struct Colours;

impl inimtrace::render::RadianceField for Colours {
    fn radiance(&self, ray: &inimtrace::ray::Ray) -> DVec3 {
        let t = (400.0 - ray.origin.z) / ray.dir.z;
        let p = ray.origin + ray.dir * t;
        DVec3::new(0.5 + 0.5 * (p.x * 3.1).cos(), 0.5 + 0.5 * (p.y * 2.3).sin(), 0.5 + 0.5 * ((p.x + p.y) * 4.7).cos())
    }
}

#[test]
fn the_batched_schematic_eye_equals_the_per_sample_path_bit_for_bit() {
    use inimtrace::measure::estimator::{DisplaySource, EyeSample, PairedSource};
    use inimtrace::optics::diffraction::Diffraction;
    use inimtrace::optics::eye::{EyeOptics, EyeOpticsSpec};
    use inimtrace::optics::spectrum::Primaries;
    use inimtrace::optics::{Display, Eye, Focus};
    use inimtrace::raster::RgbImage;
    use inimtrace::render::retina::DisplayStack;
    // The paper's display showing two images of distinct pixels; the Navarro eye (ray map and
    // exact aim: samples beyond the map's field) with one wavelength or the primaries', with and
    // without an off-centre Stiles-Crawford peak, pinhole or 5 mm pupil; odd batch lengths.
    let display = Display::paper();
    let (cols, rows) = (display.lcd.columns(), display.lcd.rows());
    let image = |seed: u32| {
        let mut img = RgbImage::new(cols, rows);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            let h = (i as u32).wrapping_mul(2_654_435_761).wrapping_add(seed.wrapping_mul(40_503));
            *p = [(h % 251) as f32 / 250.0, (h / 251 % 241) as f32 / 240.0, (h / 60_491 % 239) as f32 / 238.0];
        }
        img
    };
    let (a, b) = (image(1), image(2));
    let stack = DisplayStack::new(&display, &[&a, &b]).unwrap();
    let mut rng = Lcg(17);
    let samples: Vec<EyeSample> = (0..2001)
        .map(|i| {
            // Every 50th sample outside the map's field (tangents up to 0.3 sqrt 2).
            let reach = if i % 50 == 0 { 0.45 } else { 0.3 };
            let tangent = DVec2::new(reach * (2.0 * rng.next() - 1.0), reach * (2.0 * rng.next() - 1.0));
            let (r, phi) = (2.5 * rng.next().sqrt(), std::f64::consts::TAU * rng.next());
            let pupil = DVec2::new(r * phi.cos(), r * phi.sin());
            EyeSample { tangent, pupil, spectral: rng.next(), diffraction: [0.0; 4] }
        })
        .collect();
    for pinhole in [false, true] {
        for primaries in [false, true] {
            for stiles_crawford in [None, Some((0.05, DVec2::new(0.4, -0.2)))] {
                let mut eye = if pinhole { Eye::pinhole() } else { Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8) };
                let spec = EyeOpticsSpec {
                    model: EyeModel::Navarro1985,
                    criterion: FocusCriterion::Paraxial,
                    reference_nm: 555.0,
                    primaries,
                    wavelength_samples: 3,
                    stiles_crawford,
                    diffraction: Diffraction::None,
                };
                let optics =
                    EyeOptics::build(&spec, &eye.aperture, eye.retina_distance, &Primaries::default(), 0.43, "t", "f")
                        .unwrap()
                        .unwrap();
                eye.optics = Some(optics);
                let source = DisplaySource::new(&display, &eye, &Colours, &stack);
                let k = source.images();
                for n in [samples.len(), 7, 1] {
                    let s = &samples[..n];
                    let (mut fast, mut slow) = (vec![[f64::NAN; 3]; n * k], vec![[f64::NAN; 3]; n * k]);
                    source.eval(s, &mut fast);
                    source.eval_each_ray(s, &mut slow);
                    let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
                    let case = format!("pinhole {pinhole}, primaries {primaries}, {stiles_crawford:?}, {n} samples");
                    assert_eq!(bits(&fast), bits(&slow), "{case}");
                    if n > 100 {
                        // Not trivially equal: the images and the channels differ.
                        assert!(fast.iter().any(|v| v[0] != v[1] && v[1] != v[2]), "{case}");
                        assert!(fast.chunks_exact(k).any(|o| o[1] != o[2]), "{case}");
                    }
                }
            }
        }
    }
}
