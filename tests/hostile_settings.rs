//! Settings later stages cannot honour (issue #30, round two): refused when the settings are
//! read, naming the field, for every method and every command, instead of images that are all
//! black and a PSNR of inf.

use std::process::{Command, Output};

use inimtrace::overrides::Override;

fn inimtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().expect("run inimtrace")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The paper's experiment with `sets` applied, resolved and validated.
fn load(sets: &[&str]) -> inimtrace::error::Result<inimtrace::experiment::Experiment> {
    let overrides: Vec<Override> = sets.iter().map(|s| s.parse().unwrap()).collect();
    inimtrace::settings::load_experiment(None, None, &overrides)
}

#[test]
fn an_eye_at_or_beyond_the_lenslet_plane_is_refused_for_every_method() {
    // The paper's lenslets are at z = 20 mm.
    for z in ["1e4", "20.0", "25", "19.9999999"] {
        for methods in ["[\"LC\"]", "[\"PC\"]", "[\"LA\"]", "[\"LA3\", \"LC\"]"] {
            let position = format!("eye.position=[0, 0, {z}]");
            let method_set = format!("methods={methods}");
            let e = load(&[&position, &method_set]).err().unwrap_or_else(|| panic!("z = {z}, {methods}: accepted"));
            let text = e.to_string();
            assert!(text.contains("eye.position") && text.contains("lenslet plane"), "z = {z}, {methods}: {text}");
        }
    }
    // In front of the lenslets, off axis and nearer than the paper's eye: accepted.
    for z in ["19.9", "5", "-3"] {
        let position = format!("eye.position=[1, 0, {z}]");
        load(&[&position, "methods=[\"LC\", \"PC\", \"LA\"]"]).unwrap_or_else(|e| panic!("z = {z}: {e}"));
    }
    // A PupilCenter aim beyond the lenslets, given on its own.
    let e = load(&["display_render.eye_position=[0, 0, 30]", "methods=[\"LC\"]"]).err().unwrap().to_string();
    assert!(e.contains("display_render.eye_position"), "{e}");
}

#[test]
fn single_stage_commands_refuse_an_eye_beyond_the_lenslets_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("d.exr");
    let display = format!("{}/displays/paper.toml", env!("CARGO_MANIFEST_DIR"));
    let small = ["--set", "display.lcd.resolution=[64, 64]"];
    // A display image to simulate (small LCD).
    let mut args = vec!["--quiet"];
    args.extend(small);
    args.extend(["render-display", "--display", &display, "--out", image.to_str().unwrap()]);
    let o = inimtrace(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    for method in ["LC", "LA", "PC"] {
        let out = dir.path().join(format!("x_{method}.exr"));
        let mut args = vec!["--quiet"];
        args.extend(small);
        args.extend(["render-display", "--display", &display, "--method", method, "--eye-position", "0,0,1e4"]);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = inimtrace(&args);
        assert_eq!(o.status.code(), Some(1), "{method}: {}", stderr(&o));
        assert!(stderr(&o).contains("--eye-position") && stderr(&o).contains("lenslet plane"), "{}", stderr(&o));
        assert!(!out.exists());
    }
    let out = dir.path().join("sim.exr");
    let mut args = vec!["--quiet"];
    args.extend(small);
    args.extend(["simulate", image.to_str().unwrap(), "--display", &display, "--pinhole", "--retina", "8"]);
    args.extend(["--eye-position", "0,0,20", "--out", out.to_str().unwrap()]);
    let o = inimtrace(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--eye-position") && stderr(&o).contains("lenslet plane"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn the_library_stages_refuse_it_too() {
    use inimtrace::optics::{Display, Eye};
    let display = Display::paper();
    let mut eye = Eye::pinhole();
    eye.position.z = 20.0;
    let e = inimtrace::optics::transfer::check_eye_in_front(&display, eye.position.z, "eye", "position").unwrap_err();
    assert!(e.to_string().contains("position"), "{e}");
    assert!(inimtrace::optics::transfer::check_eye_in_front(&display, f64::NAN, "eye", "position").is_err());
    assert!(inimtrace::optics::transfer::check_eye_in_front(&display, 19.99, "eye", "position").is_ok());
}

#[test]
fn a_retina_smaller_than_the_ssim_window_is_refused_before_any_image_naming_the_field() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let set: Vec<inimtrace::overrides::Override> = vec!["eye.retina_resolution=8".parse().unwrap()];
    let err = inimtrace::settings::load_experiment(Some(&path), None, &set).unwrap_err().to_string();
    assert!(err.contains("eye.retina_resolution") && err.contains("SSIM") && err.contains("got 8"), "{err}");
    let set: Vec<inimtrace::overrides::Override> = vec!["eye.retina_resolution=11".parse().unwrap()];
    inimtrace::settings::load_experiment(Some(&path), None, &set).unwrap();
}
