//! The eye box measured (src/optics/crosstalk.rs): the shares of a uniformly white display's
//! perceived light that come from the crossed lenslet's own elemental image, a neighbour's, or
//! off the panel, against eq. (1) solved by hand for a pinhole eye moved across the box.

use glam::{DVec3, IVec2};
use inimtrace::optics::crosstalk::light_shares;
use inimtrace::optics::eye::settings::pose_of;
use inimtrace::optics::eye::{CentreOfRotation, EyeModel, Gaze};
use inimtrace::optics::{Aperture, Display, Eye, Focus, Retina};

fn eye_at(x: f64, aperture: Aperture) -> Eye {
    Eye { retina_distance: 17.0, aperture, pupil_grid: 16, position: DVec3::new(x, 0.0, 0.0), optics: None, pose: None }
}

/// A pinhole at `x` sees, through the point `l = c + u` of lenslet `c`, the LCD point
/// `l + v2 (l - x) / v1 - v2 u / f` (eq. (1)), `a u - b x` from the centre `c (v1 + v2) / v1` of
/// the lenslet's elemental image, with `a = 1 + v2 / v1 - v2 / f` and `b = v2 / v1`. It sees its
/// own image while `|a u - b x| <= EI pitch / 2`; over a whole number of lenslets the retina's
/// rays cross every `u` of `[-p/2, p/2]` equally often, so the own share is the length of
/// that interval where the bound holds, over `p` (along y the pinhole is centred: always own).
fn own_share_by_hand(d: &Display, x: f64) -> f64 {
    let (v1, v2, f) = (d.eye_to_lenslets, d.lenslets_to_lcd, d.focal_length);
    let (a, b) = (1.0 + v2 / v1 - v2 / f, v2 / v1);
    let p = d.lenslets.center(IVec2::new(1, 0)).x - d.lenslets.center(IVec2::ZERO).x;
    let h = 0.5 * (d.elemental_images.center(IVec2::new(1, 0)).x - d.elemental_images.center(IVec2::ZERO).x);
    let lo = ((b * x - h) / a).max(-0.5 * p);
    let hi = ((b * x + h) / a).min(0.5 * p);
    (hi - lo).max(0.0) / p
}

#[test]
fn a_pinhole_moved_across_the_eye_box_sees_its_own_elemental_images_as_eq_1_says() {
    let d = Display::paper();
    // The retina spans six lenslets exactly (2 x 0.18 x v1 = 7.2 mm = 6 pitches), 100 pixels each.
    let retina = Retina { resolution: 600, half_tangent: 0.18, samples_per_pixel: 1 };
    // The eye box's edge for the chief ray (u = 0): |x| v2 / v1 = EI pitch / 2, 2.50 mm.
    let edge = 0.5 * 1.58 * d.eye_to_lenslets / d.lenslets_to_lcd;
    for x in [0.0, 1.5, 2.0, edge, 3.0, -edge] {
        let s = light_shares(&d, &eye_at(x, Aperture::Pinhole), &retina, "t").unwrap();
        let want = own_share_by_hand(&d, x.abs());
        assert!((s.own - want).abs() < 0.012, "pinhole at {x}: own {} by hand {want}", s.own);
        assert_eq!(s.off_panel, 0.0, "pinhole at {x}: the rays stay on the panel");
        assert!((s.own + s.neighbour + s.off_panel - 1.0).abs() < 1e-12);
    }
    // At the box's edge half the rays see a neighbour's image.
    let s = light_shares(&d, &eye_at(edge, Aperture::Pinhole), &retina, "t").unwrap();
    assert!((s.crosstalk() - 0.5).abs() < 0.012, "{s:?}");
    // Inside the box, none.
    let s = light_shares(&d, &eye_at(0.0, Aperture::Pinhole), &retina, "t").unwrap();
    assert_eq!((s.own, s.crosstalk(), s.illumination()), (1.0, 0.0, 1.0));
}

#[test]
fn a_field_past_the_panel_loses_its_light_and_a_turned_eye_is_refused() {
    let d = Display::paper();
    // A pinhole's field past the display's (+-22.3 degrees). Lenslet k's rays meet the LCD
    // within `a p / 2` of its elemental image's centre `k P` (eq. (1), as above): lenslets up
    // to k = 6 land on the 10.8 mm half panel, the 7th (11.05 mm) lands past it, whole. Lit:
    // the retina tangents whose lens-plane point `v1 t` lies on lenslets -6 to 6, per axis.
    let retina = Retina { resolution: 200, half_tangent: 0.6, samples_per_pixel: 1 };
    let s = light_shares(&d, &eye_at(0.0, Aperture::Pinhole), &retina, "t").unwrap();
    let (v1, v2, f, p, big_p) = (d.eye_to_lenslets, d.lenslets_to_lcd, d.focal_length, 1.2, 1.58);
    let spread = 0.5 * p * (1.0 + v2 / v1 - v2 / f);
    let k = ((10.8 - spread) / big_p).floor();
    assert!(k == 6.0 && (k + 1.0) * big_p - spread > 10.8);
    let on = ((k + 0.5) * p / v1 / 0.6).powi(2);
    assert!((s.illumination() - on).abs() < 0.01, "{s:?} against {on}");
    assert_eq!(s.neighbour, 0.0);
    // A focused 5 mm pupil moved off the axis: more crosstalk the farther it goes.
    let focused = |x| eye_at(x, Aperture::ThinLens { pupil_diameter: 5.0, focus: Focus::Millimetres(400.0) });
    let small = Retina { resolution: 60, half_tangent: 0.18, samples_per_pixel: 1 };
    let shares: Vec<f64> =
        [0.0, 1.0, 2.0].iter().map(|&x| light_shares(&d, &focused(x), &small, "t").unwrap().crosstalk()).collect();
    assert!(shares.windows(2).all(|w| w[1] > w[0]), "{shares:?}");
    let mut turned = eye_at(0.0, Aperture::Pinhole);
    turned.pose =
        pose_of(&EyeModel::ThinLens, Gaze::new(5.0, 0.0), CentreOfRotation::default(), DVec3::ZERO, "t").unwrap();
    let e = light_shares(&d, &turned, &retina, "t.toml").unwrap_err().to_string();
    assert!(e.contains("t.toml") && e.contains("straight ahead"), "{e}");
}
