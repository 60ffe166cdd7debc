//! The eye turned to a gaze about its centre of rotation (src/optics/eye/gaze.rs): the pupil centre
//! and any point of the eye against their rotation about the stated centre computed here
//! independently (Fick's line of sight, Rodrigues' rotation formula about Listing's axis), and bad
//! gazes and centres refused naming the field.

use glam::DVec3;
use inimtrace::optics::eye::{CentreOfRotation, EyePose, Gaze, SchematicEye};

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
