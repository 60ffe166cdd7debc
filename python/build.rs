//! Build script of the Python module: with the `embree4` feature, gives the extension module an
//! rpath to the folder holding `libembree4.so` (found as the main crate's `build.rs` finds it,
//! `build/embree4_lib.rs`), so that Python loads it without `LD_LIBRARY_PATH`. Without the
//! feature it does nothing (Debian's Embree 3 is on the system path).

#[cfg(feature = "embree4")]
#[path = "../build/embree4_lib.rs"]
mod embree4_lib;

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    #[cfg(feature = "embree4")]
    {
        use std::path::PathBuf;
        println!("cargo::rerun-if-env-changed=EMBREE4_DIR");
        let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
        let fallback = manifest.join("..").join("target").join("embree4");
        let env_dir = std::env::var_os("EMBREE4_DIR").filter(|d| !d.is_empty()).map(PathBuf::from);
        let library_path = std::env::var_os("LIBRARY_PATH");
        let dirs = embree4_lib::system_dirs(library_path.as_deref());
        // A missing library is reported by the main crate's build script, which runs first.
        if let Ok(embree4_lib::Embree4Lib::Dir(dir)) = embree4_lib::locate(env_dir.as_deref(), &dirs, &fallback) {
            let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
            println!("cargo::rustc-link-arg-cdylib=-Wl,-rpath,{}", dir.display());
        }
    }
}
