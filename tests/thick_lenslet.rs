//! The real (thick) lenslet traced exactly (`optics::lenslet`): the paraxial limit is eq. (1),
//! the focal length is the lensmaker's, a plano-convex lens has third-order spherical aberration,
//! the trace is reversible, the root-finding twin agrees, and the hard cases (total internal
//! reflection, a conic without a point in the cell, rays at a cell's edge and corner) are handled.

use glam::{DVec2, DVec3};
use inimtrace::optics::eye::medium::Dispersion;
use inimtrace::optics::lenslet::{cell_radius, Intersection, Material, Surface, ThickLenslet, D_LINE_NM};
use inimtrace::optics::{Display, Lattice, PlaneRay};

/// Deterministic uniform numbers (64-bit LCG, top 53 bits).
struct Lcg(u64);
impl Lcg {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn point(&mut self, half: f64) -> DVec2 {
        DVec2::new(self.uniform(-half, half), self.uniform(-half, half))
    }
}

fn glass(n: f64) -> Material {
    Material { name: "user".into(), dispersion: Dispersion::Constant(n) }
}

fn lens(front: f64, back: f64, thickness: f64, n: f64) -> ThickLenslet {
    ThickLenslet {
        front: Surface { radius: front, conic: 0.0 },
        back: Surface { radius: back, conic: 0.0 },
        thickness,
        material: glass(n),
        design_cdp_mm: None,
    }
}

const FRONT_Z: f64 = 20.0;

#[test]
fn zero_thickness_paraxial_rays_follow_eq_1() {
    let display = Display::paper();
    let f = display.focal_length;
    let v2 = display.lenslets_to_lcd;
    let mut rng = Lcg(1);
    // Plano-convex either way round and an equi-convex lens, each of focal length f at t = 0.
    let n = 1.49;
    for l in [lens((n - 1.0) * f, 0.0, 0.0, n), lens(0.0, -(n - 1.0) * f, 0.0, n), {
        let r = 2.0 * (n - 1.0) * f;
        lens(r, -r, 0.0, n)
    }] {
        assert!((l.paraxial(D_LINE_NM).efl - f).abs() < 1e-12);
        let mut worst: f64 = 0.0;
        for _ in 0..2_000 {
            // A ray near a lenslet's axis with a small slope (paraxial: 1e-4 mm, 1e-4).
            let cell = display.lenslets.center(glam::IVec2::new(rng.uniform(-8.0, 8.0) as i32, 3));
            let x2 = cell + rng.point(1e-4);
            let w = rng.point(1e-4);
            let origin = (x2 - w * FRONT_Z).extend(0.0);
            let exact = l
                .trace_to_lcd(&display.lenslets, FRONT_Z, FRONT_Z + v2, origin, w, D_LINE_NM, Intersection::ClosedForm)
                .expect("a paraxial ray passes");
            let eq1 = PlaneRay { position: x2, slope: w }.refract(cell, 1.0 / f).propagate(v2).position;
            worst = worst.max((exact.lcd - eq1).length());
        }
        assert!(worst < 1e-9, "largest distance from eq. (1): {worst:e} mm");
    }
}

#[test]
fn focal_length_is_the_lensmakers_and_real_rays_find_it() {
    for (r1, r2, t, n) in
        [(3.2, 0.0, 1.0, 1.49), (5.0, -7.0, 0.8, 1.5168), (-9.0, -3.0, 0.5, 1.6), (4.0, 12.0, 2.0, 1.45)]
    {
        let l = lens(r1, r2, t, n);
        let p = l.paraxial(D_LINE_NM);
        let (c1, c2) = (if r1 == 0.0 { 0.0 } else { 1.0 / r1 }, if r2 == 0.0 { 0.0 } else { 1.0 / r2 });
        // Lensmaker's formula for a thick lens (Hecht, "Optics", eq. 6.2).
        let inv = (n - 1.0) * (c1 - c2 + (n - 1.0) * t * c1 * c2 / n);
        assert!((p.efl * inv - 1.0).abs() < 1e-13, "{r1} {r2} {t} {n}: {} vs {}", p.efl, 1.0 / inv);
        // A real ray 1e-4 mm off the axis, parallel to it, leaves at the slope -h/EFL and crosses
        // the axis at the back focal distance.
        let lattice = Lattice::square(50.0).unwrap();
        let h = 1e-4;
        let tr = l
            .trace_to_lcd(
                &lattice,
                0.0,
                t + 100.0,
                DVec3::new(h, 0.0, -10.0),
                DVec2::ZERO,
                D_LINE_NM,
                Intersection::ClosedForm,
            )
            .unwrap();
        let slope = tr.dir.x / tr.dir.z;
        assert!((-h / slope / p.efl - 1.0).abs() < 1e-6, "EFL by the real ray {} vs {}", -h / slope, p.efl);
        let crossing = tr.back.z - tr.back.x / slope - t;
        assert!((crossing - p.bfd).abs() < 1e-6 * p.efl.abs(), "BFD {crossing} vs {}", p.bfd);
    }
}

/// Third-order longitudinal spherical aberration of a thin lens for an object at infinity (Hecht,
/// "Optics", 5th ed., Sec. 6.3.1): `LA = h^2 / (8 f n (n - 1)) [n^3/(n-1) + (3n+2)(n-1) p^2 +
/// 4(n+1) p q + (n+2)/(n-1) q^2]` with shape factor q = (R2 + R1)/(R2 - R1) and position factor
/// p = -1 (object at infinity); for n = 1.5 it is 1.17 h^2/f convex side first, 4.5 h^2/f flat first.
fn third_order_la(h: f64, f: f64, n: f64, q: f64) -> f64 {
    let p = -1.0;
    h * h / (8.0 * f * n * (n - 1.0))
        * (n.powi(3) / (n - 1.0)
            + (3.0 * n + 2.0) * (n - 1.0) * p * p
            + 4.0 * (n + 1.0) * p * q
            + (n + 2.0) / (n - 1.0) * q * q)
}

#[test]
fn plano_convex_spherical_aberration_is_third_order_in_the_paraxial_limit() {
    let f = 6.427;
    let lattice = Lattice::square(100.0).unwrap();
    for n in [1.5, Material::pmma().index(D_LINE_NM)] {
        // Convex side toward the collimated light (q = +1) and flat side first (q = -1), thin.
        for (l, q) in [(lens((n - 1.0) * f, 0.0, 0.0, n), 1.0), (lens(0.0, -(n - 1.0) * f, 0.0, n), -1.0)] {
            let focus = |h: f64| {
                let tr = l
                    .trace_to_lcd(
                        &lattice,
                        0.0,
                        50.0,
                        DVec3::new(h, 0.0, -10.0),
                        DVec2::ZERO,
                        D_LINE_NM,
                        Intersection::ClosedForm,
                    )
                    .unwrap();
                tr.back.z - tr.back.x * tr.dir.z / tr.dir.x
            };
            let paraxial = l.paraxial(D_LINE_NM).bfd;
            for (h, tol) in [(f / 50.0, 5e-3), (f / 200.0, 5e-4)] {
                let la = paraxial - focus(h);
                let theory = third_order_la(h, f, n, q);
                assert!((la / theory - 1.0).abs() < tol, "n {n} q {q} h {h}: LA {la:e} vs third order {theory:e}");
            }
            if n == 1.5 {
                let k = third_order_la(1.0, 1.0, n, q);
                assert!((k - if q > 0.0 { 7.0 / 6.0 } else { 4.5 }).abs() < 1e-12, "{k}");
            }
        }
    }
}

#[test]
fn the_trace_is_reversible_and_the_root_finding_twin_agrees() {
    let display = Display::paper();
    let lattice = &display.lenslets;
    let l = ThickLenslet::plano_convex(Material::pmma(), 6.427, 1.0);
    let mut biconvex = ThickLenslet { back: Surface { radius: -12.0, conic: -0.5 }, ..l.clone() };
    biconvex.front.conic = 0.8;
    let lcd_z = FRONT_Z + 1.0 + 5.8;
    let mut rng = Lcg(7);
    let (mut compared, mut edges) = (0, 0);
    for lens in [&l, &biconvex] {
        for i in 0..1_000 {
            // Rays from the pupil over the whole array; every third aimed at a cell boundary or corner.
            let eye = rng.point(2.0).extend(0.0);
            let mut target = rng.point(9.0);
            if i % 3 == 0 {
                let c = lattice.center(lattice.nearest(target));
                target = c + DVec2::new(0.6, if i % 2 == 0 { 0.6 } else { rng.uniform(-0.6, 0.6) }) + rng.point(1e-9);
                edges += 1;
            }
            let slope = (target - eye.truncate()) / FRONT_Z;
            for nm in [450.0, 550.0, 620.0] {
                let fast = lens.trace_to_lcd(lattice, FRONT_Z, lcd_z, eye, slope, nm, Intersection::ClosedForm);
                let slow = lens.trace_to_lcd(lattice, FRONT_Z, lcd_z, eye, slope, nm, Intersection::RootFinding);
                let (Some(fast), Some(slow)) = (fast, slow) else {
                    assert_eq!(fast.is_some(), slow.is_some(), "{eye} {slope}: {fast:?} vs {slow:?}");
                    continue;
                };
                assert_eq!(fast.cell, slow.cell);
                assert!((fast.lcd - slow.lcd).length() < 1e-9, "{:?} vs {:?}", fast.lcd, slow.lcd);
                assert!((fast.front - slow.front).length() < 1e-10);
                compared += 1;
                // Back from the LCD through the same lenslet: the same ray toward the eye.
                let cell = lattice.nearest(fast.back.truncate());
                if cell != fast.cell {
                    continue; // crosstalk into a neighbour: the camera ray's extended lenslet is another
                }
                let back_plane = FRONT_Z + lens.thickness;
                let p = fast.back.truncate() + fast.dir.truncate() * ((back_plane - fast.back.z) / fast.dir.z);
                let center = lattice.center(cell);
                let rev = lens
                    .trace_from_lcd(center, FRONT_Z, lcd_z, fast.lcd, p, nm, Intersection::ClosedForm)
                    .expect("the reverse of a passing ray passes");
                let d = slope.extend(1.0).normalize();
                assert!((rev.point - fast.front).length() < 1e-9, "{:?} vs {:?}", rev.point, fast.front);
                assert!((rev.dir + d).length() < 1e-9, "{:?} vs {:?}", rev.dir, -d);
                // And its camera ray reaches the pupil where the eye's ray left it.
                let ray = lens.camera_ray(center, FRONT_Z, lcd_z, fast.lcd, p, 0.0, nm).unwrap();
                assert!((ray.origin - eye).length() < 1e-9);
            }
        }
    }
    assert!(compared == 6_000 && edges > 600, "{compared} {edges}");
}

#[test]
fn rays_at_a_cells_edge_meet_one_continuous_surface() {
    // The caps of neighbouring cells have equal sag on their common boundary: a ray through the
    // boundary meets the front surface at the same point whichever side it is assigned to, and a
    // ray at a corner settles in one of the four cells without NaN.
    let display = Display::paper();
    let lattice = &display.lenslets;
    let l = ThickLenslet::plano_convex(Material::pmma(), 6.427, 1.0);
    let lcd_z = FRONT_Z + 1.0 + 5.8;
    for (dx, dy) in [(0.6, 0.1), (0.6, 0.6), (-0.6, -0.6), (0.1, -0.6)] {
        let mut fronts = Vec::new();
        for eps in [-1e-12, 0.0, 1e-12] {
            let target = DVec2::new(dx + eps, dy + eps);
            let eye = DVec3::new(0.3, -0.2, 0.0);
            let slope = (target - eye.truncate()) / FRONT_Z;
            let t = l
                .trace_to_lcd(lattice, FRONT_Z, lcd_z, eye, slope, 550.0, Intersection::ClosedForm)
                .expect("a ray at a cell boundary passes");
            assert!(t.lcd.is_finite());
            fronts.push(t.front);
        }
        assert!((fronts[0] - fronts[2]).length() < 1e-9, "{fronts:?}");
    }
}

#[test]
fn total_internal_reflection_and_missing_conics_block_the_ray() {
    // A strongly curved front (R = 1 mm, n = 1.5) over a plane back, 0.6 mm thick: light from the
    // LCD crossing the back at x = 0.6 mm with slope -2 (toward the axis) meets the front at about
    // 66 degrees from its normal, beyond the 41.8 degree critical angle: blocked. Tilted the other
    // way (incidence about 7 degrees) it passes.
    let l = lens(1.0, 0.0, 0.6, 1.5);
    let (front_z, v2) = (20.0, 3.0);
    let lcd_z = front_z + 0.6 + v2;
    let p = DVec2::new(0.6, 0.0);
    let tir = l.trace_from_lcd(
        DVec2::ZERO,
        front_z,
        lcd_z,
        p + DVec2::new(2.0 * v2, 0.0),
        p,
        550.0,
        Intersection::ClosedForm,
    );
    assert!(tir.is_none(), "{tir:?}");
    let slow = l.trace_from_lcd(
        DVec2::ZERO,
        front_z,
        lcd_z,
        p + DVec2::new(2.0 * v2, 0.0),
        p,
        550.0,
        Intersection::RootFinding,
    );
    assert!(slow.is_none());
    let ok = l.trace_from_lcd(
        DVec2::ZERO,
        front_z,
        lcd_z,
        p - DVec2::new(2.0 * v2, 0.0),
        p,
        550.0,
        Intersection::ClosedForm,
    );
    assert!(ok.is_some_and(|o| o.dir.is_finite() && o.dir.z < 0.0));

    // A sphere narrower than the cell (R = 0.5 mm, cell corners 0.85 mm out): refused by
    // validation naming the surface, and a ray beyond its rim is blocked, never NaN.
    let lattice = Lattice::square(1.2).unwrap();
    assert!((cell_radius(&lattice) - 0.6 * 2f64.sqrt()).abs() < 1e-9);
    let narrow = lens(0.5, 0.0, 1.0, 1.5);
    let e = narrow.validate(&lattice, "d.toml", "lenslet").unwrap_err().to_string();
    assert!(e.contains("d.toml") && e.contains("lenslet.front") && e.contains("no point"), "{e}");
    let blocked = narrow.trace_to_lcd(
        &lattice,
        front_z,
        lcd_z,
        DVec3::new(0.55, 0.55, 0.0),
        DVec2::ZERO,
        550.0,
        Intersection::ClosedForm,
    );
    assert!(blocked.is_none(), "{blocked:?}");
    // A hyperbolic front (conic -3) has a point at every radius: accepted.
    let hyper = ThickLenslet { front: Surface { radius: 0.5, conic: -3.0 }, ..narrow.clone() };
    let e = hyper.validate(&lattice, "d.toml", "lenslet");
    assert!(e.as_ref().is_err_and(|e| e.to_string().contains("thickness")) || e.is_ok(), "{e:?}");
    // Surfaces that cross inside the cell: a thickness error with the thickness needed.
    let thin = lens(3.0, 0.0, 0.05, 1.5);
    let e = thin.validate(&lattice, "d.toml", "lenslet").unwrap_err().to_string();
    assert!(e.contains("lenslet.thickness") && e.contains("at least"), "{e}");
    // The hexagonal lattice's cell radius is pitch / sqrt(3).
    let hex = Lattice::from_row_major(DVec2::ZERO, [1.0, 0.5, 0.0, 3f64.sqrt() / 2.0]).unwrap();
    assert!((cell_radius(&hex) - 1.0 / 3f64.sqrt()).abs() < 1e-6, "{}", cell_radius(&hex));
}

#[test]
fn built_in_materials_have_their_catalogue_indices() {
    // N-BK7: n_d = 1.5168, n_F = 1.52238, n_C = 1.51432 (Schott data sheet).
    let bk7 = Material::n_bk7();
    assert!((bk7.index(587.56) - 1.5168).abs() < 1e-4);
    assert!((bk7.index(486.13) - 1.52238).abs() < 1e-4);
    assert!((bk7.index(656.27) - 1.51432).abs() < 1e-4);
    // PMMA: n_d = 1.4906, Abbe number about 57 (Sultanova et al. 2009).
    let pmma = Material::pmma();
    let nd = pmma.index(587.56);
    assert!((nd - 1.4906).abs() < 5e-4, "{nd}");
    let vd = (nd - 1.0) / (pmma.index(486.13) - pmma.index(656.27));
    assert!((50.0..62.0).contains(&vd), "{vd}");
    // The paper's focal length as a plano-convex PMMA lenslet.
    let l = ThickLenslet::plano_convex(pmma, 6.427, 1.0);
    assert!((l.paraxial(D_LINE_NM).efl - 6.427).abs() < 1e-12);
    // Its v2 for an image 365.7 mm behind the front vertex puts the image there.
    let v2 = l.v2_for_image_distance(365.7, D_LINE_NM);
    assert!((l.lcd_image_distance(v2, D_LINE_NM).unwrap() - 365.7).abs() < 1e-9, "{v2}");
}

#[test]
fn one_front_hit_for_three_channels_traces_what_three_traces_do() {
    // `trace_to_lcd_each` finds the front surface's hit once and refracts it at each channel's
    // index: bit for bit the three traces `trace_to_lcd_in`, blocked rays included (a strongly
    // curved lens blocks many), with either intersection; and `pixel_indices_in` the three pixels
    // of `pixel_index_in`, at the median wavelengths and at a sampled one.
    let display = Display::paper();
    let lattice = &display.lenslets;
    let pmma = ThickLenslet::plano_convex(Material::pmma(), 6.427, 1.0);
    let mut biconic = ThickLenslet { back: Surface { radius: -12.0, conic: -0.5 }, ..pmma.clone() };
    biconic.front.conic = 0.8;
    let strong = lens(1.0, 0.0, 0.6, 1.5);
    let lcd_z = FRONT_Z + 1.0 + 5.8;
    let mut rng = Lcg(29);
    let (mut passed, mut blocked) = (0, 0);
    for l in [&pmma, &biconic, &strong] {
        let ns = [450.0, 550.0, 620.0].map(|nm| l.material.index(nm));
        for i in 0..2_000 {
            let eye = rng.point(2.5).extend(0.0);
            let mut target = rng.point(9.0);
            if i % 3 == 0 {
                let c = lattice.center(lattice.nearest(target));
                target = c + DVec2::new(0.6, rng.uniform(-0.6, 0.6)) + rng.point(1e-9);
            }
            let slope = (target - eye.truncate()) / FRONT_Z;
            for how in [Intersection::ClosedForm, Intersection::RootFinding] {
                if how == Intersection::RootFinding && i % 10 != 0 {
                    continue;
                }
                let each = l.trace_to_lcd_each(lattice, FRONT_Z, lcd_z, eye, slope, ns, how);
                for (c, &n) in ns.iter().enumerate() {
                    let one = l.trace_to_lcd_in(lattice, FRONT_Z, lcd_z, eye, slope, n, how);
                    assert_eq!(format!("{:?}", each[c]), format!("{one:?}"), "{eye} {slope} channel {c}");
                    if one.is_some() {
                        passed += 1;
                    } else {
                        blocked += 1;
                    }
                }
            }
        }
    }
    assert!(passed > 10_000 && blocked > 200, "{passed} passed, {blocked} blocked");

    let mut d = Display::paper();
    d.lenslet = inimtrace::optics::lenslet::LensletOptics::Thick(Box::new(pmma.clone()));
    d.lenslets_to_lcd = 5.6451;
    let eye = inimtrace::optics::Eye::pinhole();
    let transfer = inimtrace::optics::transfer::FastTransfer::for_eye(&d, &eye);
    let mut hits = 0;
    for _ in 0..3_000 {
        let ray = PlaneRay { position: rng.point(2.5), slope: rng.point(0.4) };
        for u in [0.5, rng.uniform(0.0, 1.0)] {
            let each = transfer.pixel_indices_in(ray, u);
            for (c, pixel) in each.iter().enumerate() {
                assert_eq!(*pixel, transfer.pixel_index_in(ray, c, u), "{ray:?} channel {c} at {u}");
                hits += usize::from(pixel.is_some());
            }
        }
    }
    assert!(hits > 5_000, "{hits}");
}

#[test]
fn camera_rays_side_by_side_are_the_one_ray_traces_bit_for_bit() {
    // `camera_rays_into` (lanes of 8, 4, 2, 1) against `camera_ray_in` ray by ray, passing and
    // blocked alike, for a plano-convex, a biconic and a strongly curved lens; and the lockstep
    // Newton solves of `pupil_center_rays` against three `pupil_center_ray`, over LCD points
    // across an elemental image (most solves near its edge fail).
    let display = Display::paper();
    let lattice = &display.lenslets;
    let pmma = ThickLenslet::plano_convex(Material::pmma(), 6.427, 1.0);
    let mut biconic = ThickLenslet { back: Surface { radius: -12.0, conic: -0.5 }, ..pmma.clone() };
    biconic.front.conic = 0.8;
    let strong = lens(1.0, 0.0, 0.6, 1.5);
    let lcd_z = FRONT_Z + 1.0 + 5.6451;
    let mut rng = Lcg(31);
    let (mut passed, mut blocked) = (0, 0);
    for l in [&pmma, &biconic, &strong] {
        let ns = [450.0, 550.0, 620.0].map(|nm| l.material.index(nm));
        for _ in 0..300 {
            let center = lattice.center(lattice.nearest(rng.point(8.0)));
            let lcd = center * 1.3 + rng.point(0.9);
            let k = 1 + (rng.uniform(0.0, 23.0) as usize);
            let p: Vec<DVec2> = (0..k).map(|_| center + rng.point(1.5)).collect();
            let n: Vec<f64> = (0..k).map(|i| ns[i % 3]).collect();
            let z = if k.is_multiple_of(2) { 0.0 } else { -3.0 };
            let mut out = vec![None; k];
            l.camera_rays_into(center, FRONT_Z, lcd_z, lcd, &p, &n, z, &mut out);
            for i in 0..k {
                let one = l.camera_ray_in(center, FRONT_Z, lcd_z, lcd, p[i], z, n[i]);
                assert_eq!(format!("{:?}", out[i]), format!("{one:?}"), "lane {i} of {k}");
                if one.is_some() {
                    passed += 1;
                } else {
                    blocked += 1;
                }
            }
        }
    }
    assert!(passed > 3_000 && blocked > 300, "{passed} passed, {blocked} blocked");

    let (mut solved, mut failed) = (0, 0);
    for l in [&pmma, &biconic] {
        let ns = [610.0, 535.0, 450.0].map(|nm| l.material.index(nm));
        for i in 0..600 {
            let center = lattice.center(lattice.nearest(rng.point(3.0)));
            let lcd = center * (1.58 / 1.2) + rng.point(0.79);
            let eye = DVec3::ZERO;
            let guess = if i == 0 { DVec2::NAN } else { center + (lcd - center * (1.58 / 1.2)) * 3.0 };
            let each = l.pupil_center_rays(center, FRONT_Z, lcd_z, lcd, eye, guess, ns);
            for c in 0..3 {
                let one = l.pupil_center_ray(center, FRONT_Z, lcd_z, lcd, eye, guess, ns[c]);
                assert_eq!(format!("{:?}", each[c]), format!("{one:?}"), "{lcd} channel {c}");
                if one.is_some() {
                    solved += 1;
                } else {
                    failed += 1;
                }
            }
        }
    }
    assert!(solved > 200 && failed > 200, "{solved} solved, {failed} failed");
}
