//! Where the Embree 4 shared library (`libembree4.so`) of the `embree4` feature is found:
//! `EMBREE4_DIR` (the folder itself, or its `lib/` / `lib64/`), else the system linker path, else
//! `target/embree4/` (where `scripts/embree4-from-wheel.sh` puts the library of the `embreex`
//! wheel). Shared by `build.rs`, `python/build.rs` and the test `tests/embree4_locate.rs`; it
//! only looks at the file system, so the test can hand it fixture folders.

use std::path::{Path, PathBuf};

/// The file the linker needs for `-lembree4`.
pub const LIB_FILE: &str = "libembree4.so";

/// Where the library was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Embree4Lib {
    /// On the system linker path: nothing to add.
    System(PathBuf),
    /// In this folder (from `EMBREE4_DIR` or `target/embree4/`): the build adds it to the link
    /// search path and to the binaries' rpath.
    Dir(PathBuf),
}

/// The folder holding `libembree4.so`: `env_dir` (the value of `EMBREE4_DIR`, when set and not
/// empty) and its `lib/` or `lib64/`; else the first of `system_dirs`; else `fallback`. The error
/// is one line naming `EMBREE4_DIR` and the script that fetches the library.
pub fn locate(env_dir: Option<&Path>, system_dirs: &[PathBuf], fallback: &Path) -> Result<Embree4Lib, String> {
    if let Some(dir) = env_dir {
        return [dir.to_path_buf(), dir.join("lib"), dir.join("lib64")]
            .into_iter()
            .find(|d| d.join(LIB_FILE).exists())
            .map(Embree4Lib::Dir)
            .ok_or_else(|| {
                format!(
                    "EMBREE4_DIR={} holds no {LIB_FILE} (nor does its lib/ or lib64/): point EMBREE4_DIR at the \
                     folder with libembree4.so*, or unset it to use the system's Embree 4 or the one \
                     scripts/embree4-from-wheel.sh puts in target/embree4/",
                    dir.display()
                )
            });
    }
    if let Some(dir) = system_dirs.iter().find(|d| d.join(LIB_FILE).exists()) {
        return Ok(Embree4Lib::System(dir.clone()));
    }
    if fallback.join(LIB_FILE).exists() {
        return Ok(Embree4Lib::Dir(fallback.to_path_buf()));
    }
    Err(format!(
        "the `embree4` feature needs Intel Embree 4 ({LIB_FILE}), found neither in EMBREE4_DIR (not set), on the \
         system linker path nor in {}: run scripts/embree4-from-wheel.sh (or scripts/install-deps.sh), install \
         your system's Embree 4, or set EMBREE4_DIR to the folder with libembree4.so*",
        fallback.display()
    ))
}

/// The system linker's usual library folders on Linux, plus `LIBRARY_PATH`'s entries first.
pub fn system_dirs(library_path: Option<&std::ffi::OsStr>) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = library_path
        .map(|p| std::env::split_paths(p).filter(|d| !d.as_os_str().is_empty()).collect())
        .unwrap_or_default();
    dirs.extend(
        ["/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib", "/usr/local/lib", "/lib"]
            .iter()
            .map(PathBuf::from),
    );
    dirs
}
