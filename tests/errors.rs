//! The library's errors keep their structure: a file that fails because of a file it names
//! keeps the inner error whole (`Error::Load`, `Error::InField`), each kind of failure is its own
//! variant, and the message reads as the CLI has always printed it.

use std::fs;
use std::path::Path;

use inimtrace::error::Error;
use inimtrace::settings::load_experiment;

fn write(dir: &Path, name: &str, text: &str) {
    fs::write(dir.join(name), text).unwrap();
}

const DISPLAY: &str = "name = \"d\"\neye_to_lenslets = 20.0\nlenslets_to_lcd = 6.316\n\
[lenslets]\nfocal_length = 6.427\npitch = 1.2\n[elemental_images]\npitch = 1.58\n\
[lcd]\nsize = [21.6, 21.6]\nresolution = [216, 216]\n";

fn experiment(dir: &Path, scene: &str, display: &str) -> std::path::PathBuf {
    let text = format!(
        "name = \"e\"\nscene = \"{scene}\"\ndisplay = \"{display}\"\nmethods = [\"LC\"]\n\
         [eye]\nretina_resolution = 16\n[[eye_cases]]\nname = \"Pin\"\npinhole = true\n"
    );
    write(dir, "exp.toml", &text);
    dir.join("exp.toml")
}

#[test]
fn a_broken_mesh_named_by_a_scene_named_by_an_experiment_keeps_the_whole_chain() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "d.toml", DISPLAY);
    write(dir.path(), "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    write(
        dir.path(),
        "s.toml",
        "name = \"s\"\n[[objects]]\nname = \"m\"\ntype = \"mesh\"\nfile = \"m.obj\"\nmaterial = { albedo = [1, 1, 1] }\n",
    );
    let exp = experiment(dir.path(), "s.toml", "d.toml");
    let err = load_experiment(Some(&exp), None, &[]).expect_err("the face names a vertex that does not exist");
    let Error::Load { field, reference, source, .. } = &err else { panic!("expected Error::Load, got {err:?}") };
    assert_eq!((field.as_str(), reference.as_str()), ("scene", "s.toml"));
    let Error::InField { field, .. } = source.as_ref() else { panic!("expected Error::InField, got {source:?}") };
    assert!(field.ends_with("file"), "{field}");
    let Error::Parse { path, .. } = err.innermost() else { panic!("expected a parse error at the bottom: {err:?}") };
    assert!(path.ends_with("m.obj"), "{path:?}");
    // The message reads as before: every file and field, outermost first.
    let text = err.to_string();
    let (exp_at, scene_at, mesh_at) =
        (text.find("exp.toml").unwrap(), text.find("cannot load `s.toml`").unwrap(), text.find("m.obj").unwrap());
    assert!(exp_at < scene_at && scene_at < mesh_at, "{text}");
    assert_eq!(err.source_and_field().1.as_deref(), Some("scene"));
}

#[test]
fn a_missing_display_is_an_io_error_inside_a_load() {
    let dir = tempfile::tempdir().unwrap();
    let exp = experiment(dir.path(), "builtin:paper", "nowhere.toml");
    let err = load_experiment(Some(&exp), None, &[]).unwrap_err();
    assert!(matches!(&err, Error::Load { field, .. } if field == "display"), "{err:?}");
    assert!(
        matches!(err.innermost(), Error::Io { path, source } if path.ends_with("nowhere.toml") && source.kind() == std::io::ErrorKind::NotFound),
        "{err:?}"
    );
}

#[test]
fn a_singular_pitch_matrix_is_a_lattice_error_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "d.toml", &DISPLAY.replace("pitch = 1.2", "pitch = [[1.2, 2.4], [0.6, 1.2]]"));
    let exp = experiment(dir.path(), "builtin:paper", "d.toml");
    let err = load_experiment(Some(&exp), None, &[]).unwrap_err();
    match err.innermost() {
        Error::Lattice { field, message, .. } => {
            assert!(field.starts_with("lenslets.pitch"), "{field}");
            assert!(message.contains("singular"), "{message}");
        }
        other => panic!("expected Error::Lattice, got {other:?}"),
    }
}

#[test]
fn an_unknown_mesh_format_names_the_file_and_the_formats() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.xyz", "1 2 3\n");
    let err = inimtrace::io::mesh::load_mesh(&dir.path().join("m.xyz")).unwrap_err();
    match &err {
        Error::UnknownFormat { path, kind, .. } => assert!(path.ends_with("m.xyz") && *kind == "mesh"),
        other => panic!("expected Error::UnknownFormat, got {other:?}"),
    }
    assert!(err.to_string().ends_with("unknown mesh format (expected extension .obj, .ply, .stl, .gltf or .glb)"));
}

/// Settings errors speak the settings' words: the field and the form its value must take (never a
/// Rust type such as `usize` or `untagged enum PitchSpec`), at the line of the key, and a missing
/// key with the table that lacks it.
#[test]
fn settings_errors_name_the_field_and_the_expected_form_at_the_keys_line() {
    let dir = tempfile::tempdir().unwrap();
    let paper = fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("displays/paper.toml")).unwrap();
    let line_of = |prefix: &str| paper.lines().position(|l| l.starts_with(prefix)).unwrap() + 1;
    let edit = |name: &str, from: &str, to: &str| {
        let l = paper.lines().find(|l| l.starts_with(from)).unwrap();
        let text = paper.replacen(l, to, 1);
        write(dir.path(), name, &text);
        let e = inimtrace::io::load_display(dir.path().join(name).to_str().unwrap(), Path::new("")).unwrap_err();
        e.to_string()
    };
    let cases = [
        (
            "pitch.toml",
            "pitch = 1.2",
            "pitch = \"big\"",
            "lenslets.pitch",
            "a number (square), [x, y]",
            line_of("pitch = 1.2"),
        ),
        (
            "res.toml",
            "resolution =",
            "resolution = [2160.5, 2160]",
            "lcd.resolution",
            "expected a whole number",
            line_of("resolution ="),
        ),
        (
            "neg.toml",
            "resolution =",
            "resolution = [-3, 2160]",
            "lcd.resolution",
            "expected a whole number",
            line_of("resolution ="),
        ),
    ];
    for (name, from, to, field, form, line) in cases {
        let e = edit(name, from, to);
        assert!(e.contains(name) && e.contains(&format!("field `{field}`")) && e.contains(form), "{e}");
        assert!(e.contains(&format!("line {line},")), "{e}: not at line {line}");
        for serde in ["untagged", "enum", "usize", "PitchSpec", "floating point"] {
            assert!(!e.contains(serde), "{e}: says {serde}");
        }
    }
    // Missing keys: the table that lacks one, or the top level; never "line 1, column 1".
    let e = edit("nof.toml", "focal_length", "");
    assert!(e.contains("missing field `lenslets.focal_length`") && e.contains("[lenslets] at line"), "{e}");
    let e = edit("nov1.toml", "eye_to_lenslets", "");
    assert!(e.contains("missing field `eye_to_lenslets`") && e.contains("top-level"), "{e}");
    assert!(!e.contains("line 1, column 1"), "{e}");
}

/// The cases the display test above leaves: a value written over several lines (the element's
/// line, and the key it belongs to), a list given as one value, a missing key of an `[[array]]`
/// table, and a sweep file's axis (its key's line, not the file alone). Never a serde word.
#[test]
fn experiment_display_and_sweep_errors_point_at_the_keys_line() {
    let dir = tempfile::tempdir().unwrap();
    let serde_words =
        ["untagged", "enum", "usize", "u32", "f64", "sequence", "map,", "floating point", "line 1, column 1"];
    let clean = |e: &str| {
        for w in serde_words {
            assert!(!e.contains(w), "{e}: says `{w}`");
        }
    };
    // A display whose LCD resolution spans lines 11 to 14, with a fraction at line 12.
    let display = DISPLAY.replace("resolution = [216, 216]", "resolution = [\n    216.5,\n    216,\n]");
    write(dir.path(), "multi.toml", &display);
    let e = inimtrace::io::load_display(dir.path().join("multi.toml").to_str().unwrap(), Path::new(""))
        .unwrap_err()
        .to_string();
    assert!(e.contains("multi.toml: line 12, column 5: field `lcd.resolution` (its value starts at line 11)"), "{e}");
    assert!(e.contains("expected a whole number"), "{e}");
    clean(&e);

    // Experiments: a list given as one string, a wrong type, a missing key of an [[eye_cases]] table.
    write(dir.path(), "d.toml", DISPLAY);
    let exp = |name: &str, text: &str| {
        write(dir.path(), name, text);
        load_experiment(Some(&dir.path().join(name)), None, &[]).unwrap_err().to_string()
    };
    let base = "name = \"e\"\nscene = \"builtin:paper\"\ndisplay = \"d.toml\"\nmethods = [\"LC\"]\n\
                [eye]\nretina_resolution = 16\n[[eye_cases]]\nname = \"Pin\"\npinhole = true\n";
    let e = exp("methods.toml", &base.replace("methods = [\"LC\"]", "methods = \"LC\""));
    assert!(e.contains("line 4, column 11: field `methods`") && e.contains("expected a list"), "{e}");
    clean(&e);
    let e = exp("res.toml", &base.replace("retina_resolution = 16", "retina_resolution = \"big\""));
    assert!(e.contains("line 6, column 21: field `eye.retina_resolution`"), "{e}");
    assert!(e.contains("expected a whole number"), "{e}");
    clean(&e);
    let e = exp("pupil.toml", &base.replace("retina_resolution = 16", "retina_resolution = 16\npupil_diameter = [5]"));
    assert!(
        e.contains("line 7, column 18: field `eye.pupil_diameter`: invalid type: a list, expected a number"),
        "{e}"
    );
    clean(&e);
    let e = exp("noname.toml", &base.replace("name = \"Pin\"\n", ""));
    assert!(e.contains("missing field `eye_cases.name`") && e.contains("[eye_cases] at line 7"), "{e}");
    clean(&e);

    // Sweeps: an axis's error at its key's line.
    let sweep = |name: &str, axis: &str| {
        let text = format!("name = \"s\"\nexperiment = \"builtin:paper\"\n\n[[axes]]\n{axis}\n");
        write(dir.path(), name, &text);
        inimtrace::sweep::SweepSpec::load(&dir.path().join(name)).unwrap_err().to_string()
    };
    for (name, axis, says) in [
        ("string.toml", "\"eye.pupil_diameter\" = \"big\"", "expected a list of values or a range"),
        (
            "to.toml",
            "\"eye.pupil_diameter\" = { from = 1, to = \"x\", step = 1 }",
            "range `to` must be a finite number",
        ),
        ("noto.toml", "\"eye.pupil_diameter\" = { from = 1, step = 1 }", "a range needs `to`"),
        ("empty.toml", "\"eye.pupil_diameter\" = []", "no values"),
        ("key.toml", "\"eye..pupil\" = [1, 2]", ""),
    ] {
        let e = sweep(name, axis);
        let field = if name == "key.toml" { "axes[0].\"eye..pupil\"" } else { "axes[0].\"eye.pupil_diameter\"" };
        assert!(e.contains(&format!("{name}: line 5: field `{field}`: {says}")), "{e}");
        clean(&e);
    }
    let e = sweep("type.toml", "\"eye.pupil_diameter\" = [2.0, 3.0]\n[[axes]]\n\"eye.position\" = 3");
    assert!(e.contains("type.toml: line 7: field `axes[1].\"eye.position\"`"), "{e}");
}
