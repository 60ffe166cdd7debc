//! Displays stated by intent (`[intent]`: the central depth plane, v1, f, the lenslet pitch and
//! lattice, thin or thick lenslets): the derived display against the paper's explicit one, a thick
//! lenslet's against an independent paraxial ray trace through its surfaces, against the explicit
//! file `info --write-display` writes, and hostile intent refused naming the file and the field.

use std::path::{Path, PathBuf};
use std::process::Command;

use inimtrace::io::load_display;
use inimtrace::optics::Display;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

const PAPER_BY_INTENT: &str = r#"
name = "paper by intent"
[intent]
central_depth_plane = 385.7
eye_to_lenslets = 20.0
focal_length = 6.427
lattice = "square"
lenslet_pitch = 1.2
[lcd]
size = [21.6, 21.6]
resolution = [2160, 2160]
"#;

/// The paper's display by intent with plano-convex PMMA lenslets (`displays/paper-pmma.toml`'s).
const PMMA_BY_INTENT: &str = r#"
name = "paper PMMA by intent"
[intent]
central_depth_plane = 385.7
eye_to_lenslets = 20.0
lattice = "square"
lenslet_pitch = 1.2
[lcd]
size = [21.6, 21.6]
resolution = [2160, 2160]
[lenslet]
kind = "thick"
thickness = 1.0
front = { radius = 3.1532, conic = 0.0 }
back = { radius = 0.0 }
material = "pmma"
"#;

/// A biconvex N-BK7 design on a hexagonal lattice: both principal planes inside the lens, away from
/// the vertices.
const BICONVEX_BY_INTENT: &str = r#"
[intent]
central_depth_plane = 600.0
eye_to_lenslets = 18.0
focal_length = 4.774
lattice = "hexagonal"
views_across_pupil = 4.5
[lcd]
size = [20.0, 20.0]
resolution = [1000, 1000]
[lenslet]
kind = "thick"
thickness = 0.8
front = { radius = 6.0, conic = -0.5 }
back = { radius = -4.0 }
material = "n-bk7"
"#;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Every number of two displays differs by at most `tol` mm (names aside).
fn max_difference(a: &Display, b: &Display) -> f64 {
    let mut d = (a.eye_to_lenslets - b.eye_to_lenslets).abs();
    d = d.max((a.lenslets_to_lcd - b.lenslets_to_lcd).abs());
    d = d.max((a.focal_length - b.focal_length).abs());
    for (x, y) in [(&a.lenslets, &b.lenslets), (&a.elemental_images, &b.elemental_images)] {
        for (p, q) in x.row_major().iter().zip(y.row_major()) {
            d = d.max((p - q).abs());
        }
        d = d.max((x.shift - y.shift).abs().max_element());
    }
    d.max((a.lcd.size - b.lcd.size).abs().max_element())
}

#[test]
fn the_papers_display_by_intent_reproduces_its_v2_and_elemental_image_pitch() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "paper-intent.toml", PAPER_BY_INTENT);
    let d = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
    let paper = load_display("displays/paper.toml", &root()).unwrap();
    // v2: 1 / (1/6.427 + 1/365.7) = 6.31599 mm against the file's 6.316.
    assert!((d.lenslets_to_lcd - paper.lenslets_to_lcd).abs() < 0.001, "{}", d.lenslets_to_lcd);
    // The elemental-image pitch: 1.2 x 26.316 / 20 = 1.57896 mm against the file's rounded 1.58.
    let [a, b, c, e] = d.elemental_images.row_major();
    assert!((a - 1.58).abs() < 0.002 && (e - 1.58).abs() < 0.002 && b == 0.0 && c == 0.0, "{a} {b} {c} {e}");
    assert!((a - 1.2 * (20.0 + d.lenslets_to_lcd) / 20.0).abs() < 1e-15);
    assert_eq!(d.lenslets.row_major(), paper.lenslets.row_major());
    assert_eq!((d.eye_to_lenslets, d.focal_length, d.lcd), (20.0, 6.427, paper.lcd));
    // The CDP is where the intent put it.
    assert!((d.central_depth_plane().unwrap() - 385.7).abs() < 1e-9);
    println!("v2 {:.6} (file {}), EI pitch {:.6} (file 1.58)", d.lenslets_to_lcd, paper.lenslets_to_lcd, a);
}

#[test]
fn a_display_by_intent_equals_the_explicit_file_info_writes_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let paper = write(dir.path(), "paper-intent.toml", PAPER_BY_INTENT);
    let hex = root().join("displays/hex-1mm.toml");
    let views = write(
        dir.path(),
        "views.toml",
        &PAPER_BY_INTENT
            .replace("lenslet_pitch = 1.2", "views_across_pupil = 4.0\npupil_diameter = 3.0")
            .replace("\"square\"", "\"hexagonal\""),
    );
    let pmma = write(dir.path(), "pmma.toml", PMMA_BY_INTENT);
    let biconvex = write(dir.path(), "biconvex.toml", BICONVEX_BY_INTENT);
    for intent in [paper, hex, views, pmma, biconvex] {
        let out = dir.path().join("explicit.toml");
        let _ = std::fs::remove_file(&out);
        let (ok, stdout, stderr) =
            inimtrace(&["info", "--display", &intent.to_string_lossy(), "--write-display", &out.to_string_lossy()]);
        assert!(ok, "{stderr}");
        assert!(
            stdout.contains("display stated by intent")
                && (stdout.contains("v2 = 1 / (1/f") || stdout.contains("v2 = h2 + 1 / (1/f + 1/(z_cdp - v1 - h1))")),
            "{stdout}"
        );
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(!text.contains("[intent]"), "{text}");
        let by_intent = load_display(&intent.to_string_lossy(), Path::new("")).unwrap();
        let explicit = load_display(&out.to_string_lossy(), Path::new("")).unwrap();
        let diff = max_difference(&by_intent, &explicit);
        assert!(diff <= 1e-12, "{}: {diff} mm", intent.display());
        assert_eq!(by_intent.name, explicit.name);
        assert_eq!(by_intent.lenslet, explicit.lenslet);
        // An existing file is kept unless --force.
        let (ok, _, stderr) =
            inimtrace(&["info", "--display", &intent.to_string_lossy(), "--write-display", &out.to_string_lossy()]);
        assert!(!ok && stderr.contains("--force") && stderr.contains("explicit.toml"), "{stderr}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), text);
        let (ok, _, stderr) = inimtrace(&[
            "info",
            "--display",
            &intent.to_string_lossy(),
            "--write-display",
            &out.to_string_lossy(),
            "--force",
        ]);
        assert!(ok, "{stderr}");
    }
}

#[test]
fn experiments_and_settings_see_the_derived_display() {
    // The settings path (assess, sweeps) inlines the derived explicit display.
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "paper-intent.toml", PAPER_BY_INTENT);
    let direct = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
    let via = inimtrace::settings::display_with(Some(&p), &[]).unwrap();
    assert_eq!(max_difference(&direct, &via), 0.0);
    let o: inimtrace::overrides::Override = "display.lenslets_to_lcd=6.0".parse().unwrap();
    let changed = inimtrace::settings::display_with(Some(&p), &[o]).unwrap();
    assert_eq!(changed.lenslets_to_lcd, 6.0);
}

#[test]
fn hostile_intent_is_refused_naming_the_file_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("central_depth_plane = 385.7", "central_depth_plane = 15.0", "intent.central_depth_plane"),
        ("central_depth_plane = 385.7", "central_depth_plane = -385.7", "intent.central_depth_plane"),
        ("central_depth_plane = 385.7", "central_depth_plane = nan", "intent.central_depth_plane"),
        ("central_depth_plane = 385.7", "central_depth_plane = 20.0", "intent.central_depth_plane"),
        ("focal_length = 6.427", "focal_length = -6.427", "intent.focal_length"),
        ("focal_length = 6.427", "focal_length = nan", "intent.focal_length"),
        ("focal_length = 6.427", "focal_length = 1e9", "intent.focal_length"),
        ("eye_to_lenslets = 20.0", "eye_to_lenslets = -20.0", "intent.eye_to_lenslets"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 0.0", "intent.lenslet_pitch"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = inf", "intent.lenslet_pitch"),
        ("lenslet_pitch = 1.2", "", "intent.lenslet_pitch"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 1.2\nviews_across_pupil = 4", "intent.views_across_pupil"),
        ("lenslet_pitch = 1.2", "views_across_pupil = nan", "intent.views_across_pupil"),
        ("lenslet_pitch = 1.2", "views_across_pupil = 4\npupil_diameter = -5", "intent.pupil_diameter"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 1.2\npupil_diameter = 5", "intent.pupil_diameter"),
        ("\"square\"", "\"triangular\"", "lattice"),
        ("lenslet_pitch = 1.2", "lenslet_pitch = 1.2\nlenslets_to_lcd = 6.3", "lenslets_to_lcd"),
        ("name = \"paper by intent\"", "lenslet = { kind = \"thick\" }", "thickness"),
        ("focal_length = 6.427", "", "intent.focal_length"),
    ];
    // A thick lenslet's own refusals.
    let thick = [
        ("lattice = \"square\"", "lattice = \"square\"\nfocal_length = 6.5", "intent.focal_length"),
        ("radius = 3.1532, conic = 0.0", "radius = -3.1532", "lenslet.front"),
        ("material = \"pmma\"", "material = \"pmma\"\ndesign_cdp_mm = 385.7", "lenslet.design_cdp_mm"),
        ("thickness = 1.0", "thickness = -1.0", "lenslet.thickness"),
        ("radius = 3.1532, conic = 0.0", "radius = 0.5", "lenslet.front"),
        ("material = \"pmma\"", "material = \"glass\"", "lenslet.material"),
    ];
    let cases = cases.iter().map(|&(f, t, x)| (PAPER_BY_INTENT, f, t, x));
    for (i, (base, from, to, field)) in cases.chain(thick.map(|(f, t, x)| (PMMA_BY_INTENT, f, t, x))).enumerate() {
        let text = base.replace(from, to);
        assert_ne!(text, base, "{from}");
        let name = format!("hostile{i}.toml");
        let p = write(dir.path(), &name, &text);
        let e = load_display(&p.to_string_lossy(), Path::new("")).expect_err(to).to_string();
        assert!(e.contains(&name) && e.contains(field), "{to}: {e}");
        assert_eq!(e.lines().count(), 1, "{e}");
        // The settings path (assess, sweeps) refuses it the same way.
        let e = inimtrace::settings::display_with(Some(&p), &[]).expect_err(to).to_string();
        assert!(e.contains(&name) && e.contains(field), "{to}: {e}");
    }
}

/// A paraxial ray `(y, u)` (height from the lenslet's axis and slope, in air before the front
/// vertex plane) traced surface by surface through `d`'s thick lenslet at `n`: refraction
/// `n' u' = n u - y (n' - n) c`, transfer `y + t u`; its height and slope at the back vertex plane.
fn paraxial_trace(d: &Display, n: f64, y: f64, u: f64) -> (f64, f64) {
    let t = d.thick_lenslet().unwrap();
    let u1 = (u - y * (n - 1.0) * t.front.curvature()) / n;
    let y2 = y + t.thickness * u1;
    let u2 = n * u1 - y2 * (1.0 - n) * t.back.curvature();
    (y2, u2)
}

#[test]
fn a_thick_lenslet_by_intent_images_the_cdp_onto_the_lcd_and_centres_the_elemental_images_on_its_nodal_rays() {
    use inimtrace::optics::lenslet::{Intersection, D_LINE_NM};
    let dir = tempfile::tempdir().unwrap();
    for (file, text) in [("pmma.toml", PMMA_BY_INTENT), ("biconvex.toml", BICONVEX_BY_INTENT)] {
        let p = write(dir.path(), file, text);
        let d = load_display(&p.to_string_lossy(), Path::new("")).unwrap();
        let t = d.thick_lenslet().unwrap().clone();
        let n = t.material.index(D_LINE_NM);
        let z: f64 = if file == "pmma.toml" { 385.7 } else { 600.0 };
        let (v1, v2) = (d.eye_to_lenslets, d.lenslets_to_lcd);
        // A ray from the eye aimed at the CDP's axial point comes to focus on the LCD (the reverse of
        // the LCD's light leaving toward the eye from its virtual image at the CDP).
        for y in [1e-3, 0.1, 0.4] {
            let (y2, u2) = paraxial_trace(&d, n, y, -y / (z - v1));
            let focus = -y2 / u2;
            assert!((focus - v2).abs() < 1e-9, "{file}: focus {focus} mm behind the back vertex, v2 {v2}");
        }
        // A real ray near the axis does too (spherical aberration ~ y^2 aside).
        let lcd_z = d.lcd_z();
        for y in [1e-4, -2e-4] {
            let origin = glam::DVec3::new(y, 0.0, v1);
            let slope = glam::DVec2::new(-y / (z - v1), 0.0);
            let hit = t.trace_to_lcd(&d.lenslets, v1, lcd_z, origin, slope, D_LINE_NM, Intersection::ClosedForm);
            let hit = hit.expect("a paraxial ray passes");
            assert!(hit.lcd.length() < 1e-9, "{file}: {} mm off the axis", hit.lcd.length());
        }
        assert!((d.central_depth_plane().unwrap() - z).abs() < 1e-9 * z, "{file}");
        assert_eq!(t.design_cdp_mm, Some(z));
        // The ray from the pupil centre that leaves the lenslet at (i, j) = (1, 0) parallel to its
        // incoming direction (its nodal ray; linear in the slope, found from two slopes) meets the LCD
        // at the elemental image's centre.
        let xc = d.lenslets.center(glam::IVec2::new(1, 0));
        let out = |u: f64| paraxial_trace(&d, n, u * v1 - xc.x, u);
        let ((_, ua), (_, ub)) = (out(0.0), out(1.0));
        // u2(u) - u = ua + (ub - ua - 1) u = 0.
        let u = -ua / (ub - ua - 1.0);
        let (y2, u2) = out(u);
        let lcd = xc.x + y2 + u2 * v2;
        let ei = d.elemental_images.center(glam::IVec2::new(1, 0));
        assert!((lcd - ei.x).abs() < 1e-12 && ei.y.abs() < 1e-12, "{file}: nodal ray at {lcd}, EI centre {ei}");
    }
}
