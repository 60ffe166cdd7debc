//! Where the `embree4` feature's build finds `libembree4.so` (`build/embree4_lib.rs`, shared with
//! `build.rs`): `EMBREE4_DIR` first, then the system linker path, then `target/embree4/`; and
//! when none has it, one error line naming `EMBREE4_DIR` and the script that fetches it.

#[path = "../build/embree4_lib.rs"]
#[allow(dead_code)]
mod embree4_lib;

use embree4_lib::{locate, system_dirs, Embree4Lib, LIB_FILE};
use std::path::{Path, PathBuf};

fn with_lib(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join(LIB_FILE), b"").unwrap();
    dir.to_path_buf()
}

#[test]
fn embree4_dir_then_system_then_target_embree4() {
    let t = tempfile::tempdir().unwrap();
    let env = with_lib(&t.path().join("env"));
    let system = with_lib(&t.path().join("system"));
    let fallback = with_lib(&t.path().join("target/embree4"));
    let empty = t.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let systems = vec![empty.clone(), system.clone()];
    assert_eq!(locate(Some(&env), &systems, &fallback), Ok(Embree4Lib::Dir(env.clone())));
    assert_eq!(locate(None, &systems, &fallback), Ok(Embree4Lib::System(system.clone())));
    assert_eq!(locate(None, std::slice::from_ref(&empty), &fallback), Ok(Embree4Lib::Dir(fallback.clone())));
    // An install prefix: the library in its lib/ (or lib64/).
    let prefix = t.path().join("prefix");
    let lib = with_lib(&prefix.join("lib64"));
    assert_eq!(locate(Some(&prefix), &systems, &fallback), Ok(Embree4Lib::Dir(lib)));
    // LIBRARY_PATH's folders come before the usual ones.
    let joined = std::env::join_paths([&env]).unwrap();
    assert_eq!(system_dirs(Some(&joined))[0], env);
}

#[test]
fn a_missing_library_is_one_line_naming_embree4_dir_and_the_script() {
    let t = tempfile::tempdir().unwrap();
    let empty = t.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let fallback = t.path().join("target/embree4");
    // Nowhere at all.
    let message = locate(None, std::slice::from_ref(&empty), &fallback).unwrap_err();
    assert_eq!(message.lines().count(), 1, "{message}");
    for needle in ["EMBREE4_DIR", "scripts/embree4-from-wheel.sh", "libembree4.so"] {
        assert!(message.contains(needle), "{needle}: {message}");
    }
    // EMBREE4_DIR set to a folder without it: that folder is named, and nothing else is tried
    // (a library elsewhere must not be picked silently).
    with_lib(&fallback);
    let message = locate(Some(&empty), std::slice::from_ref(&empty), &fallback).unwrap_err();
    assert_eq!(message.lines().count(), 1, "{message}");
    assert!(message.contains(&format!("EMBREE4_DIR={}", empty.display())), "{message}");
}
