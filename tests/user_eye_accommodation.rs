//! User eyes that accommodate (`[eye.user.accommodation]`, docs/EYE.md), and the fixed eyes'
//! focus: a stated focus within 1e-4 D of the focus a fixed eye has is accepted, and the error
//! for one farther away prints a value that, typed back, is accepted.

use inimtrace::optics::eye::accommodation::FOCUS_MATCH_D;
use inimtrace::optics::eye::user::UserEye;
use inimtrace::optics::eye::{EyeModel, FocusCriterion, SchematicEye};

fn arizona_law() -> UserEye {
    let text = std::fs::read_to_string("tests/data/eyes/arizona-law.toml").unwrap();
    toml::from_str(&text).unwrap()
}

fn user(u: UserEye) -> EyeModel {
    EyeModel::parse("user", Some(u), "eye.toml").unwrap()
}

fn paraxial_focus(model: &EyeModel, a: f64) -> f64 {
    SchematicEye::new(model, a, "t").unwrap().paraxial(555.0).conjugate_vergence_d
}

#[test]
fn the_arizona_eye_as_a_user_eye_with_its_law_focuses_as_the_arizona_model() {
    let model = user(arizona_law());
    assert_eq!(model.accommodation_range(), (0.0, 8.0));
    for a in [0.0, 1.0, 2.5, 5.0, 7.75, 8.0] {
        let (mine, theirs) = (paraxial_focus(&model, a), paraxial_focus(&EyeModel::Arizona, a));
        assert!((mine - theirs).abs() < 1e-9, "A = {a}: user {mine} D, Arizona {theirs} D");
    }
    // Focusing solves for the same accommodation.
    let at = |m: &EyeModel| {
        SchematicEye::focused(m, 3.0, 555.0, FocusCriterion::Paraxial, 4.0, "t", "focus_diopters").unwrap().1
    };
    let (mine, theirs) = (at(&model), at(&EyeModel::Arizona));
    assert!(mine > 0.0 && (mine - theirs).abs() < 1e-7, "{mine} vs {theirs}");
    // Without the law the same eye has one focus, its A = 0 one.
    let mut fixed = arizona_law();
    fixed.accommodation = None;
    let fixed = user(fixed);
    assert_eq!(fixed.accommodation_range(), (0.0, 0.0));
    assert!((paraxial_focus(&fixed, 0.0) - paraxial_focus(&EyeModel::Arizona, 0.0)).abs() < 1e-9);
    let e = SchematicEye::focused(&fixed, 3.0, 555.0, FocusCriterion::Paraxial, 4.0, "t", "focus_diopters")
        .unwrap_err()
        .to_string();
    assert!(e.contains("does not accommodate") && e.contains("accommodation law"), "{e}");
}

#[test]
fn bad_accommodation_laws_name_the_field() {
    let bad = |edit: &dyn Fn(&mut UserEye), field: &str| {
        let mut u = arizona_law();
        edit(&mut u);
        let e = EyeModel::parse("user", Some(u), "eye.toml").unwrap_err().to_string();
        assert!(e.contains("eye.toml") && e.contains(field), "{field}: {e}");
    };
    bad(&|u| u.accommodation.as_mut().unwrap().range = [5.0, 1.0], "eye.accommodation.range");
    bad(&|u| u.accommodation.as_mut().unwrap().laws[0].surface = "lens".into(), "eye.accommodation.laws[0].surface");
    bad(
        &|u| u.accommodation.as_mut().unwrap().laws[5].table.as_mut().unwrap().accommodation[1] = 7.0,
        "eye.accommodation.laws[5].table.accommodation",
    );
    bad(&|u| u.accommodation.as_mut().unwrap().laws[1].polynomial = Some(vec![f64::NAN]), "laws[1].polynomial");
    // A law that makes an impossible eye somewhere in the range says at which A: this lens front
    // steepens until it crosses the lens back inside their semi-diameters (the clearance rules).
    bad(
        &|u| u.accommodation.as_mut().unwrap().laws[1].polynomial = Some(vec![12.0, -1.19]),
        "eye.surfaces[2].thickness (eye.accommodation at A = ",
    );
    // An index law needs a medium whose index it can set.
    bad(
        &|u| u.surfaces[2].medium = inimtrace::optics::eye::medium::Dispersion::Cauchy { a: 1.41, b: 0.004, c: 0.0 },
        "eye.accommodation.laws[4].parameter",
    );
}

#[test]
fn a_fixed_eyes_focus_is_accepted_within_a_ten_thousandth_of_a_dioptre_and_printed_to_round_trip() {
    let focus = |m: &EyeModel, v: f64| SchematicEye::focused(m, v, 555.0, FocusCriterion::Paraxial, 5.0, "e", "f");
    for model in [
        EyeModel::LeGrand,
        user({
            let mut u = arizona_law();
            u.accommodation = None;
            u
        }),
    ] {
        let exact = paraxial_focus(&model, 0.0);
        // The focus rounded to 4 decimals, as a table or an earlier message shows it (Le Grand's
        // 0.1735): accepted, the eye the same.
        let rounded = (exact * 1e4).round() / 1e4;
        assert!((rounded - exact).abs() <= 0.5e-4 + 1e-15);
        focus(&model, rounded).unwrap_or_else(|e| panic!("{}: {rounded} refused: {e}", model.name()));
        focus(&model, exact + 0.9 * FOCUS_MATCH_D).unwrap();
        // Farther away: refused, and the message's value typed back is accepted.
        let e = focus(&model, exact + 0.01).unwrap_err().to_string();
        let printed: f64 = e
            .split("focuses ")
            .nth(1)
            .and_then(|t| t.split(" D").next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no focus value in: {e}"));
        assert_eq!(printed, exact, "{e}");
        focus(&model, printed).unwrap();
    }
    assert!(format!("{:.4}", paraxial_focus(&EyeModel::LeGrand, 0.0)) == "0.1735");
}
