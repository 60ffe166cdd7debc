//! PupilCenter through real lenslets (issue #53: in studies/paper-pmma.toml PC's predicted focus
//! followed the content, as LC's does, while through thin lenslets it stays at the central depth
//! plane). The cause, isolated: from the pupil centre a lenslet shows only the middle of its
//! elemental image, so for most pixels the real lens sends no light to the pupil centre and the
//! exact solve has no answer; PC then took LC's ray there and showed LC's light field. It now
//! takes the ray of the lens's paraxial equivalent, which passes through the pupil centre as
//! every PC ray must (docs/OPTICS.md).

use glam::{DVec2, DVec3, IVec2};
use inimtrace::io::display_file::load_display;
use inimtrace::optics::Display;
use inimtrace::ray::Ray;
use inimtrace::render::display_thick::{render_with, Sharing};
use inimtrace::render::{DisplayRenderSettings, Method, RadianceField, Sample};

fn pmma() -> Display {
    load_display("displays/paper-pmma.toml", std::path::Path::new(env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// A field whose radiance is how far the camera ray passes from the pupil centre (the origin) at
/// the pupil plane, mm.
struct MissAtPupil;

impl RadianceField for MissAtPupil {
    fn radiance(&self, ray: &Ray) -> DVec3 {
        let at = ray.origin.truncate() + ray.dir.truncate() * (0.0 - ray.origin.z) / ray.dir.z;
        DVec3::splat(at.length())
    }
    fn sample(&self, ray: &Ray) -> Sample {
        Sample { radiance: self.radiance(ray), depth: 100.0 }
    }
}

#[test]
fn from_the_pupil_centre_a_real_lenslet_reaches_only_the_middle_of_its_elemental_image() {
    // The cause: the exact solve has no answer for most pixels of an elemental image.
    let d = pmma();
    let lens = d.thick_lenslet().unwrap();
    let n = lens.material.index(d.channel_wavelengths()[1]);
    let (c, e) = (d.lenslets.center(IVec2::ZERO), d.elemental_images.center(IVec2::ZERO));
    let (mut solved, mut total) = (0, 0);
    for (i, j) in (-78..=78).step_by(6).flat_map(|i| (-78..=78).step_by(6).map(move |j| (i, j))) {
        let x3 = e + DVec2::new(i as f64 * 0.01, j as f64 * 0.01);
        let guess = inimtrace::optics::transfer::pupil_center_point(&d, x3, c, DVec3::ZERO);
        total += 1;
        solved += lens.pupil_center_ray(c, d.eye_to_lenslets, d.lcd_z(), x3, DVec3::ZERO, guess, n).is_some() as usize;
    }
    assert!(solved > 0 && solved * 2 < total, "{solved} of {total} pixels reach the pupil centre");
}

#[test]
fn every_pupil_center_ray_through_real_lenslets_passes_through_the_pupil_centre() {
    let mut d = pmma();
    d.lcd = inimtrace::optics::display::Lcd { size: DVec2::splat(3.2), resolution: [160, 160] };
    let lens = d.thick_lenslet().unwrap().clone();
    let settings = DisplayRenderSettings::default();
    for sharing in [Sharing::Shared, Sharing::PerPixel] {
        let pc = render_with(&d, &lens, Method::PupilCenter, &settings, &MissAtPupil, sharing).unwrap();
        let worst = pc.pixels.iter().flatten().fold(0.0f32, |a, &v| a.max(v));
        assert!(worst < 1e-6, "{sharing:?}: a PC ray misses the pupil centre by {worst} mm");
        // LC's rays go through the lenslet centres instead: the field tells them apart.
        let lc = render_with(&d, &lens, Method::LensletCenter, &settings, &MissAtPupil, sharing).unwrap();
        let far = lc.pixels.iter().flatten().fold(0.0f32, |a, &v| a.max(v));
        assert!(far > 1.0, "{sharing:?}: LC's rays reach {far} mm from the pupil centre");
    }
}

#[test]
fn the_paraxial_pupil_center_ray_is_the_thin_equivalents() {
    // Through the principal planes the ray is the thin lens's PC ray of the equivalent design:
    // the line from the pupil centre through the point eq. (1b)'s closed form gives.
    let d = pmma();
    let lens = d.thick_lenslet().unwrap();
    let nm = inimtrace::optics::lenslet::D_LINE_NM;
    let p = lens.paraxial(nm);
    let (h1, h2) = p.principal_planes();
    let mut thin = d.clone();
    thin.lenslet = inimtrace::optics::lenslet::LensletOptics::Paraxial;
    thin.focal_length = p.efl;
    thin.eye_to_lenslets = d.eye_to_lenslets + h1;
    thin.lenslets_to_lcd = d.lenslets_to_lcd - h2;
    let eye = DVec3::new(0.3, -0.2, 0.0);
    let c = d.lenslets.center(IVec2::new(2, 1));
    for dx in [-0.7, -0.2, 0.0, 0.4, 0.75] {
        let x3 = d.elemental_images.center(IVec2::new(2, 1)) + DVec2::new(dx, 0.5 * dx);
        let ray = lens.paraxial_pupil_center_ray(c, d.eye_to_lenslets, d.lcd_z(), x3, eye, 0.0, p.index).unwrap();
        let q = inimtrace::optics::transfer::pupil_center_point(&thin, x3, c, eye);
        let expect = (q - eye.truncate()) / thin.eye_to_lenslets;
        assert!((ray.origin.truncate() - eye.truncate()).length() < 1e-12, "{ray:?}");
        assert!((ray.dir.truncate() - expect).length() < 1e-12, "{ray:?} vs {expect}");
    }
}
