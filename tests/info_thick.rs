//! `inimtrace info` for real (thick) lenslets: every angular quantity goes through the lenslet's
//! principal planes, so a thick design reports what the optically equivalent thin design does
//! (issue #53's figures: displays/paper-pmma.toml against displays/paper.toml's thin lenses,
//! 11.63 pixels per degree and a 4.96 mm eye box).

use std::path::Path;

use inimtrace::info::{display_design, display_design_text};
use inimtrace::io::display_file::load_display;
use inimtrace::optics::lenslet::{LensletOptics, D_LINE_NM};
use inimtrace::optics::Display;

fn pmma() -> Display {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    load_display("displays/paper-pmma.toml", root).unwrap()
}

/// The thin design with the thick lenslet's EFL, v1 to its front principal plane and v2 from its
/// back one: paraxially the same optics.
fn thin_equivalent(d: &Display) -> Display {
    let p = d.thick_lenslet().unwrap().paraxial(D_LINE_NM);
    let (h1, h2) = p.principal_planes();
    let mut thin = d.clone();
    thin.lenslet = LensletOptics::Paraxial;
    thin.focal_length = p.efl;
    thin.eye_to_lenslets = d.eye_to_lenslets + h1;
    thin.lenslets_to_lcd = d.lenslets_to_lcd - h2;
    thin
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-9 * a.abs().max(1.0), "{what}: thick {a} vs thin equivalent {b}");
}

#[test]
fn thick_lenslets_report_their_thin_equivalents_angular_quantities() {
    let d = pmma();
    let thin = thin_equivalent(&d);
    // The equivalence itself: both image the LCD at the same plane.
    close(d.central_depth_plane().unwrap(), thin.central_depth_plane().unwrap(), "central depth plane");
    let (x, y) = (display_design(&d, 5.0), display_design(&thin, 5.0));
    for k in 0..2 {
        close(x.viewing_zone_mm[k], y.viewing_zone_mm[k], "viewing zone");
        close(x.eye_box_mm.unwrap()[k], y.eye_box_mm.unwrap()[k], "eye box");
        close(x.field_of_view_deg[k], y.field_of_view_deg[k], "field of view");
        close(x.pixels_per_degree.unwrap()[k], y.pixels_per_degree.unwrap()[k], "pixels per degree");
        close(x.angular_pixel_pitch_arcmin.unwrap()[k], y.angular_pixel_pitch_arcmin.unwrap()[k], "angular pitch");
        close(x.views_across_pupil.unwrap()[k], y.views_across_pupil.unwrap()[k], "views across the pupil");
        close(x.pixel_beam_spacing_mm[k], y.pixel_beam_spacing_mm[k], "pixel beam spacing");
    }
    assert_eq!(x.views_in_pupil, y.views_in_pupil);
    assert_eq!(x.lenslet_pixel_beams_in_pupil, y.lenslet_pixel_beams_in_pupil);
    assert_eq!(x.lenslets_on_lcd, y.lenslets_on_lcd);
    // The numbers for the thin design, and the eye relief still the stated v1.
    assert_eq!(format!("{:.2}", x.pixels_per_degree.unwrap()[0]), "11.63");
    assert_eq!(format!("{:.2}", x.eye_box_mm.unwrap()[0]), "4.96");
    assert_eq!(x.eye_relief_mm, d.eye_to_lenslets);
    // The thin design has no principal planes to report; the thick one says it used them.
    assert!(y.principal_planes_mm.is_none());
    let [h1, h2] = x.principal_planes_mm.unwrap();
    assert!(h1.abs() < 1e-12, "a plano-convex lenslet curved toward the eye: H at the front vertex, {h1}");
    // The back principal plane of a plano-convex lenslet lies t / n before the plane back vertex.
    close(h2, -1.0 / d.thick_lenslet().unwrap().material.index(D_LINE_NM), "back principal plane");
    let text = display_design_text(&x, "pmma");
    assert!(text.contains("through its principal planes"), "{text}");
    assert!(!display_design_text(&y, "thin").contains("principal planes"));
}
