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
