//! Off-axis astigmatism of the schematic eyes (src/optics/eye/oblique.rs, Coddington's equations
//! along the real chief ray) against an independent calculation: finite-difference real-ray fans
//! traced through the models' surfaces as written here from their papers, by a tracer of this
//! file's own (Newton's method on the sag, Snell's law by tangential components).

use glam::DVec3;
use inimtrace::optics::eye::{oblique_foci, EyeModel, SchematicEye};

/// A conic of revolution in the lens-design frame (t from the cornea's vertex toward the retina).
struct Surface {
    vertex: f64,
    c: f64,
    q: f64,
}

impl Surface {
    fn new(vertex: f64, radius: f64, q: f64) -> Self {
        Self { vertex, c: 1.0 / radius, q }
    }

    /// `sqrt(1 - (1 + Q) c² r²)`.
    fn root(&self, r2: f64) -> f64 {
        (1.0 - (1.0 + self.q) * self.c * self.c * r2).sqrt()
    }

    fn sag(&self, r2: f64) -> f64 {
        self.c * r2 / (1.0 + self.root(r2))
    }

    /// Where the ray `p + s d` meets the surface: Newton's method on `t(s) - sag(r(s))` from the
    /// vertex plane (d sag / d r² = c / (2 root)).
    fn hit(&self, p: DVec3, d: DVec3) -> DVec3 {
        let mut s = (self.vertex - p.z) / d.z;
        for _ in 0..100 {
            let x = p + s * d;
            let r2 = x.x * x.x + x.y * x.y;
            let h = x.z - self.vertex - self.sag(r2);
            let dh = d.z - self.c / self.root(r2) * (x.x * d.x + x.y * d.y);
            let step = h / dh;
            s -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        p + s * d
    }

    /// The unit normal: the gradient of `t - sag(r²)`.
    fn normal(&self, x: DVec3) -> DVec3 {
        let k = self.c / self.root(x.x * x.x + x.y * x.y);
        DVec3::new(-k * x.x, -k * x.y, 1.0).normalize()
    }
}

/// Snell's law by the tangential component: `n1 sin = n2 sin'` along the surface.
fn snell(d: DVec3, normal: DVec3, n1: f64, n2: f64) -> DVec3 {
    let n = if d.dot(normal) < 0.0 { -normal } else { normal };
    let tangential = (d - d.dot(n) * n) * (n1 / n2);
    tangential + (1.0 - tangential.length_squared()).sqrt() * n
}

/// An eye as its paper gives it: surfaces, indices (`n[0]` air), the iris plane, the retina.
struct PaperEye {
    surfaces: Vec<Surface>,
    n: Vec<f64>,
    iris_t: f64,
    retina: Surface,
}

impl PaperEye {
    /// Escudero-Sanz & Navarro, JOSA A 16:1881 (1999), Table 1, unaccommodated, 589.3 nm.
    fn navarro_1999() -> Self {
        Self {
            surfaces: vec![
                Surface::new(0.0, 7.72, -0.26),
                Surface::new(0.55, 6.50, 0.0),
                Surface::new(3.60, 10.2, -3.1316),
                Surface::new(7.60, -6.0, -1.0),
            ],
            n: vec![1.0, 1.376, 1.3374, 1.42, 1.336],
            iris_t: 3.60,
            retina: Surface::new(7.60 + 16.3203, -12.0, 0.0),
        }
    }

    /// Le Grand & El Hage (1980), full theoretical eye, 589.3 nm, with a -12 mm retina.
    fn le_grand() -> Self {
        Self {
            surfaces: vec![
                Surface::new(0.0, 7.8, 0.0),
                Surface::new(0.55, 6.5, 0.0),
                Surface::new(3.60, 10.2, 0.0),
                Surface::new(7.60, -6.0, 0.0),
            ],
            n: vec![1.0, 1.3771, 1.3374, 1.42, 1.336],
            iris_t: 3.60,
            retina: Surface::new(7.60 + 16.5966, -12.0, 0.0),
        }
    }

    /// Through every surface, forward (`out = false`, toward the retina) or backward.
    fn trace(&self, mut p: DVec3, mut d: DVec3, out: bool) -> (DVec3, DVec3) {
        let k = self.surfaces.len();
        for j in 0..k {
            let i = if out { k - 1 - j } else { j };
            let (n1, n2) = if out { (self.n[i + 1], self.n[i]) } else { (self.n[i], self.n[i + 1]) };
            p = self.surfaces[i].hit(p, d);
            d = snell(d, self.surfaces[i].normal(p), n1, n2);
        }
        (p, d)
    }

    /// Where the object-space ray through `(x, 0, -5)` along `d` crosses the iris plane (x).
    fn iris_x(&self, x: f64, d: DVec3) -> f64 {
        let (mut p, mut d) = (DVec3::new(x, 0.0, -5.0), d);
        for i in 0..2 {
            p = self.surfaces[i].hit(p, d);
            d = snell(d, self.surfaces[i].normal(p), self.n[i], self.n[i + 1]);
        }
        (p + (self.iris_t - p.z) / d.z * d).x
    }

    /// The chief ray at `field` degrees: its start at t = -5 and direction (the object on +x).
    fn chief_ray(&self, field: f64) -> (DVec3, DVec3) {
        let d = DVec3::new(-field.to_radians().sin(), 0.0, field.to_radians().cos());
        let (mut x0, mut x1) = (0.0, 1.0);
        let (mut f0, mut f1) = (self.iris_x(x0, d), self.iris_x(x1, d));
        while f1.abs() > 1e-13 {
            let x2 = x1 - f1 * (x1 - x0) / (f1 - f0);
            (x0, f0, x1) = (x1, f1, x2);
            f1 = self.iris_x(x1, d);
        }
        (DVec3::new(x1, 0.0, -5.0), d)
    }

    /// The entrance pupil's t: where a chief ray 0.001 degree off the axis crosses the axis.
    fn entrance_pupil_t(&self) -> f64 {
        let (p, d) = self.chief_ray(1e-3);
        p.z - p.x / d.x * d.z
    }

    /// The object vergences (D, from the entrance-pupil plane along the chief ray) conjugate to
    /// the chief ray's retina point in the tangential and sagittal sections: fans of rays
    /// `delta` radians either side of the reversed chief ray, from the retina point out of the
    /// eye; the vergence of each pair is minus its change of angle over its change of height,
    /// at the plane through the entrance pupil across the chief ray.
    fn retina_conjugates(&self, field: f64, delta: f64) -> (f64, f64) {
        let (p, d) = self.chief_ray(field);
        let (q, d) = self.trace(p, d, false);
        let retina = self.retina.hit(q, d);
        let u0 = -d;
        let (q0, w0) = self.trace(retina, u0, true);
        let ep = self.entrance_pupil_t();
        let e = q0 + (ep - q0.z) / w0.z * w0;
        // Height and angle of an outgoing ray along `across`, at the plane through e across w0.
        let at = |u: DVec3, across: DVec3| {
            let (q, w) = self.trace(retina, u.normalize(), true);
            let s = (e - q).dot(w0) / w.dot(w0);
            ((q + s * w - e).dot(across), w.dot(across) / w.dot(w0))
        };
        let tangential_dir = DVec3::new(u0.z, 0.0, -u0.x).normalize();
        let tangential_out = DVec3::new(w0.z, 0.0, -w0.x).normalize();
        let (h1, a1) = at(u0 + delta * tangential_dir, tangential_out);
        let (h2, a2) = at(u0 - delta * tangential_dir, tangential_out);
        let tangential = -1000.0 * (a1 - a2) / (h1 - h2);
        let (h, a) = at(u0 + delta * DVec3::Y, DVec3::Y);
        let sagittal = -1000.0 * a / h;
        (sagittal, tangential)
    }

    /// For an object at infinity: how far in front of the retina (mm along the chief ray) the
    /// sagittal and tangential focal lines lie, from parallel rays `h` mm either side of the chief
    /// ray.
    fn foci_before_retina(&self, field: f64, h: f64) -> (f64, f64) {
        let (p, d) = self.chief_ray(field);
        let (q, dq) = self.trace(p, d, false);
        let retina = self.retina.hit(q, dq);
        let tangential_dir = DVec3::new(d.z, 0.0, -d.x);
        let (t1, dt1) = self.trace(p + h * tangential_dir, d, false);
        let (t2, dt2) = self.trace(p - h * tangential_dir, d, false);
        // The two tangential rays' crossing in the x-t plane.
        let s = ((t2 - t1).x * dt2.z - (t2 - t1).z * dt2.x) / (dt1.x * dt2.z - dt1.z * dt2.x);
        let tangential = t1 + s * dt1;
        // The sagittal ray's crossing of the meridional plane y = 0.
        let (s1, ds1) = self.trace(p + h * DVec3::Y, d, false);
        let sagittal = s1 - s1.y / ds1.y * ds1;
        ((retina - sagittal).dot(dq), (retina - tangential).dot(dq))
    }
}

#[test]
fn navarro_1999_foci_agree_with_independent_real_ray_fans_at_10_20_30_degrees() {
    let paper = PaperEye::navarro_1999();
    let eye = SchematicEye::new(&EyeModel::Navarro1999, 0.0, "t").unwrap();
    for field in [10.0, 20.0, 30.0] {
        let f = oblique_foci(&eye, field, 0.0, 589.3).unwrap();
        let (sagittal, tangential) = paper.retina_conjugates(field, 1e-4);
        for (what, got, want) in [
            ("sagittal", f.sagittal_d, sagittal),
            ("tangential", f.tangential_d, tangential),
            ("astigmatism", f.astigmatism_d, tangential - sagittal),
        ] {
            assert!((got - want).abs() < 0.05, "{field} degrees, {what}: {got} D vs fans {want} D");
        }
        let (s_mm, t_mm) = paper.foci_before_retina(field, 1e-3);
        assert!((f.sagittal_before_retina_mm - s_mm).abs() < 0.005, "{field}: {f:?} vs {s_mm}");
        assert!((f.tangential_before_retina_mm - t_mm).abs() < 0.005, "{field}: {f:?} vs {t_mm}");
    }
}

#[test]
fn le_grand_foci_agree_with_independent_real_ray_fans() {
    let paper = PaperEye::le_grand();
    let eye = SchematicEye::new(&EyeModel::LeGrand, 0.0, "t").unwrap();
    for field in [15.0, 35.0] {
        let f = oblique_foci(&eye, field, 0.0, 589.3).unwrap();
        let (sagittal, tangential) = paper.retina_conjugates(field, 1e-4);
        assert!((f.sagittal_d - sagittal).abs() < 0.05, "{field}: {f:?} vs {sagittal}");
        assert!((f.tangential_d - tangential).abs() < 0.05, "{field}: {f:?} vs {tangential}");
    }
}

/// Navarro 1999 as a user eye (Table 1's indices at 589.3 nm, constant), in an experiment's
/// `[eye.user]` table.
const USER_NAVARRO_1999: &str = r#"
[eye]
model = "user"
[eye.user]
retina_radius = -12.0
iris = { after = "cornea-back", distance = 3.05 }
[[eye.user.surfaces]]
name = "cornea-front"
radius = 7.72
conic = -0.26
thickness = 0.55
semi_diameter = 5.5
medium = { constant = 1.376 }
[[eye.user.surfaces]]
name = "cornea-back"
radius = 6.5
thickness = 3.05
semi_diameter = 5.5
medium = { constant = 1.3374 }
[[eye.user.surfaces]]
radius = 10.2
conic = -3.1316
thickness = 4.0
semi_diameter = 4.5
medium = { constant = 1.42 }
[[eye.user.surfaces]]
radius = -6.0
conic = -1.0
thickness = 16.3203
semi_diameter = 4.5
medium = { constant = 1.336 }
"#;

#[test]
fn info_prints_the_foci_of_a_built_in_and_of_a_user_eye_read_from_a_file() {
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let fields = |json: &str| -> Vec<serde_json::Value> {
        let v: serde_json::Value = serde_json::from_str(json).unwrap();
        v["fields"].as_array().unwrap().clone()
    };
    // The built-in model: the library's numbers at the relaxed eye's focus.
    let (ok, json, err) = run(&["info", "--eye", "navarro-1999", "--field-deg", "10,30", "--json"]);
    assert!(ok, "{err}");
    let eye = SchematicEye::new(&EyeModel::Navarro1999, 0.0, "t").unwrap();
    for (f, deg) in fields(&json).iter().zip([10.0, 30.0]) {
        let want = oblique_foci(&eye, deg, eye.paraxial(555.0).conjugate_vergence_d, 555.0).unwrap();
        assert!((f["astigmatism_d"].as_f64().unwrap() - want.astigmatism_d).abs() < 1e-6, "{f} vs {want:?}");
    }
    // The same optics as a user eye from a file, against this file's independent fans.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("eye.toml");
    std::fs::write(&path, USER_NAVARRO_1999).unwrap();
    let (ok, json, err) =
        run(&["info", "--eye", "user", "--eye-file", path.to_str().unwrap(), "--field-deg", "20", "--json"]);
    assert!(ok, "{err}");
    let (sagittal, tangential) = PaperEye::navarro_1999().retina_conjugates(20.0, 1e-4);
    let f = &fields(&json)[0];
    assert!((f["sagittal_d"].as_f64().unwrap() - sagittal).abs() < 0.05, "{f} vs {sagittal}");
    assert!((f["tangential_d"].as_f64().unwrap() - tangential).abs() < 0.05, "{f} vs {tangential}");
    // Bad input: one clear error each.
    for (args, needle) in [
        (vec!["info", "--eye", "user"], "--eye-file"),
        (vec!["info", "--eye", "navarro-1999", "--field-deg", "85"], "--field-deg"),
        (vec!["info", "--eye", "le-grand", "--field-deg", "75"], "blocked"),
        (vec!["info", "--eye", "navarro-1999", "--field-deg", "nan"], "--field-deg"),
        (vec!["info", "--eye", "user", "--eye-file", "/nonexistent/eye.toml"], "/nonexistent/eye.toml"),
    ] {
        let (ok, _, err) = run(&args);
        assert!(!ok && err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
    }
    std::fs::write(&path, "[eye]\nmodel = \"user\"\n").unwrap();
    let (ok, _, err) = run(&["info", "--eye", "user", "--eye-file", path.to_str().unwrap()]);
    assert!(!ok && err.contains("eye.user") && err.contains("eye.toml"), "{err}");
}
