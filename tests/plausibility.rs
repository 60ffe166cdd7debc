//! Unit mistakes pass validation (the values are positive and finite) but not unnoticed: a
//! lenslet pitch in micrometres, a focal length in metres, an LCD size in centimetres and
//! `focus_mm = 1.5` each give a warning naming the file, the field and the likely unit, and the
//! run goes on (exit 0). The paper's own files give none.

use std::path::Path;
use std::process::{Command, Output};

fn inimtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The paper's display file with `key = value` replaced in the line that starts with `key`.
fn display_with(dir: &Path, name: &str, key: &str, value: &str) -> String {
    let text = std::fs::read_to_string("displays/paper.toml").unwrap();
    let mut hit = false;
    let text: String = text
        .lines()
        .map(|l| {
            if l.starts_with(&format!("{key} ")) && !hit {
                hit = true;
                format!("{key} = {value}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    assert!(hit, "{key} not in displays/paper.toml");
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn display_unit_mistakes_are_warned_naming_field_and_unit() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("pitch-um.toml", "pitch", "1200", "lenslets.pitch", "micrometres? 1200 µm = 1.2 mm"),
        ("f-m.toml", "focal_length", "0.006427", "lenslets.focal_length", "metres? 0.006427 m = 6.427 mm"),
        ("lcd-cm.toml", "size", "[2.16, 2.16]", "lcd.size", "centimetres? 2.16 cm = 21.6 mm"),
    ];
    for (file, key, value, field, unit) in cases {
        let p = display_with(dir.path(), file, key, value);
        let o = inimtrace(&["info", "--display", &p]);
        let e = stderr(&o);
        assert!(o.status.success(), "{file}: {e}");
        let line = e
            .lines()
            .find(|l| l.starts_with("warning:") && l.contains(field))
            .unwrap_or_else(|| panic!("{file}: no warning on {field}: {e}"));
        assert!(line.contains(file) && line.contains(unit), "{file}: {line}");
    }
    // The paper's display: no warning.
    let o = inimtrace(&["info", "--display", "displays/paper.toml"]);
    assert!(o.status.success() && !stderr(&o).contains("warning"), "{}", stderr(&o));
}

#[test]
fn a_central_depth_plane_at_infinity_or_real_is_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let p = display_with(dir.path(), "inf.toml", "lenslets_to_lcd", "6.427");
    let e = stderr(&inimtrace(&["info", "--display", &p]));
    assert!(e.contains("warning:") && e.contains("central depth plane is at infinity"), "{e}");
    let p = display_with(dir.path(), "real.toml", "lenslets_to_lcd", "7.0");
    let e = stderr(&inimtrace(&["info", "--display", &p]));
    assert!(e.contains("warning:") && e.contains("no virtual central depth plane"), "{e}");
}

#[test]
fn focus_mm_of_one_and_a_half_is_warned_as_metres_or_diopters() {
    let dir = tempfile::tempdir().unwrap();
    let exp = dir.path().join("exp.toml");
    std::fs::write(
        &exp,
        "name = \"tiny\"\nscene = \"builtin:paper\"\ndisplay = \"builtin:paper\"\nmethods = [\"LC\"]\n\
         [eye]\nretina_resolution = 16\n[[eye_cases]]\nname = \"Near\"\nfocus_mm = 1.5\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = inimtrace(&["--quiet", "assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let line = e.lines().find(|l| l.contains("eye_cases[0].focus_mm")).unwrap_or_else(|| panic!("no warning: {e}"));
    assert!(line.starts_with("warning:") && line.contains("exp.toml"), "{line}");
    assert!(line.contains("metres? 1.5 m = 1500 mm") && line.contains("focus_diopters = 1.5"), "{line}");
}

#[test]
fn the_resolution_study_warns_of_its_displays_and_pupils_unit_mistakes() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study.toml");
    let text = std::fs::read_to_string("studies/tiny.toml")
        .unwrap()
        .replace("pupil_diameter_mm = 5.0", "pupil_diameter_mm = 0.9");
    assert!(text.contains("pupil_diameter_mm = 0.9"));
    std::fs::write(&study, text).unwrap();
    let out = dir.path().join("out");
    let o = inimtrace(&["--quiet", "resolution", study.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let line = e.lines().find(|l| l.contains("pupil_diameter_mm")).unwrap_or_else(|| panic!("no warning: {e}"));
    assert!(line.starts_with("warning:") && line.contains("study.toml"), "{line}");
    assert!(line.contains("centimetres? 0.9 cm = 9 mm"), "{line}");
    // The built-in display and a 5 mm pupil: none.
    let o =
        inimtrace(&["--quiet", "resolution", "studies/tiny.toml", "--out", dir.path().join("ok").to_str().unwrap()]);
    assert!(o.status.success() && !stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// Each example mistake is warned of by every command that reads a display (`assess`,
/// `resolution`, `sweep`; `info` above), naming the field and the likely unit. `resolution`
/// warns before its run (here the run is then refused: the folder holds another command's
/// results), and a sweep warns once, before its points run, however many points share the value.
#[test]
fn assess_resolution_and_sweep_warn_of_each_unit_mistake() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "pitch-um.toml",
            "pitch",
            "1200",
            "display.lenslets.pitch=1200",
            "lenslets.pitch",
            "micrometres? 1200 µm = 1.2 mm",
        ),
        (
            "f-m.toml",
            "focal_length",
            "0.006427",
            "display.lenslets.focal_length=0.006427",
            "lenslets.focal_length",
            "metres? 0.006427 m = 6.427 mm",
        ),
        (
            "lcd-cm.toml",
            "size",
            "[2.16, 2.16]",
            "display.lcd.size=[2.16, 2.16]",
            "lcd.size",
            "centimetres? 2.16 cm = 21.6 mm",
        ),
    ];
    let tiny =
        ["--set", "display.lcd.resolution=[54, 54]", "--set", "eye.retina_resolution=16", "--set", "eye.pupil_grid=2"];
    let warned = |what: &str, e: &str, field: &str, unit: &str| {
        let lines: Vec<&str> = e.lines().filter(|l| l.starts_with("warning:") && l.contains(field)).collect();
        assert_eq!(lines.len(), 1, "{what}: one warning on {field}: {e}");
        assert!(lines[0].contains(unit), "{what}: {}", lines[0]);
    };
    // A folder that holds an assess run, which resolution refuses.
    let taken = dir.path().join("taken");
    let o = inimtrace(
        &[&["--quiet", "assess", "experiments/paper.toml", "--out", taken.to_str().unwrap()][..], &tiny].concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for (file, key, value, set, field, unit) in cases {
        let out = dir.path().join(file.replace(".toml", ""));
        let args = [
            &["--quiet", "assess", "experiments/paper.toml", "--set", set, "--out"][..],
            &[out.to_str().unwrap()],
            &tiny,
        ];
        let o = inimtrace(&args.concat());
        assert!(o.status.success(), "assess {file}: {}", stderr(&o));
        warned(&format!("assess {file}"), &stderr(&o), field, unit);

        let p = display_with(dir.path(), file, key, value);
        let o = inimtrace(&[
            "--quiet",
            "resolution",
            "studies/tiny.toml",
            "--set",
            &format!("display=\"{p}\""),
            "--out",
            taken.to_str().unwrap(),
        ]);
        let e = stderr(&o);
        assert!(!o.status.success() && e.contains("error:"), "resolution {file}: refused: {e}");
        warned(&format!("resolution {file}"), &e, field, unit);
        assert!(e.find("warning:") < e.find("error:"), "resolution {file}: warns before: {e}");

        let sweep = dir.path().join(format!("sweep-{file}"));
        std::fs::write(
            &sweep,
            format!(
                "name = \"units\"\nexperiment = \"{}\"\n[set]\n\"display.lcd.resolution\" = [54, 54]\n\
                 \"eye.retina_resolution\" = 16\n\"eye.pupil_grid\" = 2\n\"eye_cases\" = [{{ name = \"Eye\", focus_mm = 1.5 }}]\n\
                 [[axes]]\n\"eye.pupil_diameter\" = [4.0, 5.0]\n[[axes]]\n\"{}\" = [{}]\n",
                std::fs::canonicalize("experiments/paper.toml").unwrap().display(),
                set.split('=').next().unwrap(),
                set.split_once('=').unwrap().1
            ),
        )
        .unwrap();
        let o = inimtrace(&[
            "sweep",
            sweep.to_str().unwrap(),
            "--out",
            dir.path().join(format!("sw-{file}")).to_str().unwrap(),
        ]);
        let e = stderr(&o);
        assert!(o.status.success(), "sweep {file}: {e}");
        warned(&format!("sweep {file}"), &e, field, unit);
        warned(&format!("sweep {file}"), &e, "focus_mm", "metres? 1.5 m = 1500 mm");
        assert!(e.find("warning:") < e.find("asked for"), "sweep {file}: warns before the run: {e}");
    }
}

#[test]
fn a_colour_channel_without_central_depth_plane_is_warned_by_assess_even_quiet() {
    // displays/paper-pmma.toml: PMMA's dispersion puts the blue channel's back focal distance
    // before the LCD, so blue has no central depth plane; red and green have one.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pmma");
    let o = inimtrace(&[
        "--quiet",
        "assess",
        "experiments/paper-pmma.toml",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "display.lcd.resolution=[54, 54]",
        "--set",
        "eye.retina_resolution=12",
        "--set",
        "eye.pupil_grid=2",
        "--set",
        "measurement.estimator=\"grid\"",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let lines: Vec<&str> =
        e.lines().filter(|l| l.starts_with("warning:") && l.contains("no central depth plane")).collect();
    assert_eq!(lines.len(), 1, "{e}");
    assert!(lines[0].contains("blue") && !lines[0].contains("red") && !lines[0].contains("green ("), "{}", lines[0]);
    // The thin design has a central depth plane in every channel.
    let e = stderr(&inimtrace(&["info", "--display", "displays/paper.toml"]));
    assert!(!e.contains("no central depth plane"), "{e}");
}

#[test]
fn a_case_whose_eye_aims_every_ray_exactly_is_warned_with_the_reason() {
    // The Arizona eye focused at 300 mm (A = 3.17 D): its fitted ray map fails its checks, so
    // every ray of that case is aimed exactly (issue #53: 10x the time of the 400 mm case). The
    // other cases have the map.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("arizona");
    let o = inimtrace(&[
        "--quiet",
        "assess",
        "experiments/paper.toml",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "eye.model=\"arizona\"",
        "--set",
        "display.lcd.resolution=[54, 54]",
        "--set",
        "eye.retina_resolution=12",
        "--set",
        "eye.pupil_grid=2",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let lines: Vec<&str> = e.lines().filter(|l| l.starts_with("warning:") && l.contains("aimed exactly")).collect();
    assert_eq!(lines.len(), 1, "{e}");
    assert!(
        lines[0].contains("eye case `Near`") && lines[0].contains("arizona") && lines[0].contains("ray map"),
        "{}",
        lines[0]
    );
}
