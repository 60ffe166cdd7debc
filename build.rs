//! Build script: generates Rust bindings for the system's Intel Embree (feature `embree`).
//!
//! With the `embree` feature (on by default) it finds Embree's headers, runs bindgen over
//! `wrapper.h` (keeping only `rtc*` functions and `RTC*` types and constants), writes the
//! bindings to `$OUT_DIR/embree_bindings.rs`, links `libembree3` or `libembree4` and sets the cfg
//! `embree4` when it found Embree 4. Nothing is downloaded and no prebuilt bindings are used.
//! Without the feature (`--no-default-features`) it does nothing, so the crate then builds
//! without Embree or libclang.
//!
//! It also records the git revision the package is built from (`git describe --always --dirty`,
//! or `$INIMTRACE_GIT_REVISION` when set, else `unknown` outside a checkout) as the compile-time
//! variable `INIMTRACE_GIT_REVISION` (see `src/version.rs`), so that a binary run anywhere
//! names the source it was built from. It reruns when HEAD moves or a source file changes; the
//! Embree bindings are then reused from the previous run when their inputs are unchanged.
//!
//! With the `embree4` feature the bindings come from the `embree4-sys` crate instead (no
//! `wrapper.h`, no Embree headers needed); this script then only finds `libembree4.so`
//! (`build/embree4_lib.rs`: `EMBREE4_DIR`, the system linker path, or `target/embree4/` from
//! `scripts/embree4-from-wheel.sh`), adds its folder to the link search path and the binaries'
//! rpath, and sets `cfg(embree4)`; when it finds none it stops with one error naming
//! `EMBREE4_DIR` and the script.
//!
//! Where Embree is looked for: `$EMBREE_DIR/include/embree{4,3}` with libraries in
//! `$EMBREE_DIR/lib` (or `lib64`) when `EMBREE_DIR` is set; otherwise the system include
//! directories. Embree 4 is preferred when both versions are installed.
#![deny(unsafe_code)]

fn main() {
    // Declared unconditionally so that `cfg(embree4)` never trips the `unexpected_cfgs` lint.
    println!("cargo::rustc-check-cfg=cfg(embree4)");
    println!("cargo::rerun-if-changed=build.rs");
    revision::record();

    // Cargo compiles build scripts with the package's features, so `cfg(feature = "embree")` here
    // is the same switch as the `CARGO_FEATURE_EMBREE` environment variable; bindgen (an optional
    // build-dependency) only exists when it is on.
    #[cfg(all(feature = "embree", not(feature = "embree4")))]
    embree::generate();
    #[cfg(feature = "embree4")]
    embree4::link();
}

#[cfg(feature = "embree4")]
#[path = "build/embree4_lib.rs"]
mod embree4_lib;

#[cfg(feature = "embree4")]
mod embree4 {
    use super::embree4_lib::{locate, system_dirs, Embree4Lib};
    use std::path::PathBuf;

    /// Finds libembree4 and tells the linker where it is (the `embree4-sys` crate itself asks for
    /// `-lembree4`); sets `cfg(embree4)`.
    pub fn link() {
        println!("cargo::rerun-if-env-changed=EMBREE4_DIR");
        println!("cargo::rerun-if-env-changed=LIBRARY_PATH");
        let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
        let fallback = manifest.join("target").join("embree4");
        println!("cargo::rerun-if-changed={}", fallback.display());
        let env_dir = std::env::var_os("EMBREE4_DIR").filter(|d| !d.is_empty()).map(PathBuf::from);
        let library_path = std::env::var_os("LIBRARY_PATH");
        match locate(env_dir.as_deref(), &system_dirs(library_path.as_deref()), &fallback) {
            Ok(Embree4Lib::System(_)) => {}
            Ok(Embree4Lib::Dir(dir)) => {
                let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
                println!("cargo::rustc-link-search=native={}", dir.display());
                // The binaries, tests and examples find it at run time without LD_LIBRARY_PATH.
                println!("cargo::rustc-link-arg=-Wl,-rpath,{}", dir.display());
            }
            Err(message) => {
                println!("cargo::warning={message}");
                // One clear line, no link-error wall (a panic would add a backtrace hint).
                eprintln!("error: {message}");
                std::process::exit(1);
            }
        }
        println!("cargo::rustc-cfg=embree4");
    }
}

mod revision {
    use std::process::Command;

    fn git(args: &[&str]) -> Option<String> {
        let out = Command::new("git").args(args).output().ok().filter(|o| o.status.success())?;
        Some(String::from_utf8_lossy(&out.stdout).trim().to_string()).filter(|s| !s.is_empty())
    }

    /// Sets `INIMTRACE_GIT_REVISION` and asks to be rerun when it may change.
    pub fn record() {
        println!("cargo::rerun-if-env-changed=INIMTRACE_GIT_REVISION");
        for watched in ["src", "Cargo.toml", "Cargo.lock", "wrapper.h"] {
            println!("cargo::rerun-if-changed={watched}");
        }
        if let Some(dir) = git(&["rev-parse", "--git-dir"]) {
            println!("cargo::rerun-if-changed={dir}/HEAD");
            println!("cargo::rerun-if-changed={dir}/index");
        }
        if let (Some(common), Some(reference)) =
            (git(&["rev-parse", "--git-common-dir"]), git(&["symbolic-ref", "-q", "HEAD"]))
        {
            println!("cargo::rerun-if-changed={common}/{reference}");
            // Only when it exists: Cargo counts a watched file that is missing as changed, which
            // would rebuild the crate on every build in a repository without packed refs.
            if std::path::Path::new(&format!("{common}/packed-refs")).exists() {
                println!("cargo::rerun-if-changed={common}/packed-refs");
            }
        }
        let revision = std::env::var("INIMTRACE_GIT_REVISION")
            .ok()
            .filter(|s| !s.trim().is_empty())
            .or_else(|| git(&["describe", "--always", "--dirty", "--abbrev=7", "--exclude=*"]))
            .unwrap_or_else(|| "unknown".into());
        println!("cargo::rustc-env=INIMTRACE_GIT_REVISION={}", revision.trim());
    }
}

#[cfg(all(feature = "embree", not(feature = "embree4")))]
mod embree {
    use std::env;
    use std::path::{Path, PathBuf};

    /// The package a Debian/Ubuntu user installs to get what this script needs.
    const INSTALL_HINT: &str = "apt-get install libembree-dev libclang-dev";

    /// One Embree installation: its major version, the directory that holds `embreeN/`, and
    /// (for `EMBREE_DIR`) the directory with the shared library.
    struct Found {
        major: u32,
        include_root: PathBuf,
        lib_dir: Option<PathBuf>,
    }

    /// Prints one clear line and stops the build (a panic would add a backtrace hint).
    fn fail(message: &str) -> ! {
        eprintln!("error: {message}");
        std::process::exit(1);
    }

    fn locate() -> Found {
        println!("cargo::rerun-if-env-changed=EMBREE_DIR");
        if let Some(dir) = env::var_os("EMBREE_DIR").filter(|d| !d.is_empty()) {
            let dir = PathBuf::from(dir);
            let include_root = dir.join("include");
            let Some(major) = header_version(&include_root) else {
                fail(&format!(
                    "EMBREE_DIR={} has no include/embree4/rtcore.h or include/embree3/rtcore.h \
                     (unset it to use the system's, from `{INSTALL_HINT}`)",
                    dir.display()
                ));
            };
            let lib_dir =
                ["lib", "lib64"].iter().map(|l| dir.join(l)).find(|p| p.is_dir()).unwrap_or_else(|| dir.join("lib"));
            return Found { major, include_root, lib_dir: Some(lib_dir) };
        }
        let mut roots: Vec<PathBuf> =
            ["/usr/include", "/usr/local/include", "/opt/homebrew/include"].iter().map(PathBuf::from).collect();
        // Honour extra include paths from the usual compiler variables, searched first.
        for var in ["CPATH", "C_INCLUDE_PATH"] {
            println!("cargo::rerun-if-env-changed={var}");
            if let Some(paths) = env::var_os(var) {
                let extra: Vec<PathBuf> = env::split_paths(&paths).filter(|p| !p.as_os_str().is_empty()).collect();
                roots.splice(0..0, extra);
            }
        }
        for major in [4, 3] {
            if let Some(root) = roots.iter().find(|r| has_header(r, major)) {
                return Found { major, include_root: root.clone(), lib_dir: None };
            }
        }
        fail(&format!(
            "Intel Embree headers (embree3/rtcore.h or embree4/rtcore.h) not found; install them with \
             `{INSTALL_HINT}`, set EMBREE_DIR to an Embree install, or build with --no-default-features"
        ));
    }

    fn has_header(root: &Path, major: u32) -> bool {
        root.join(format!("embree{major}")).join("rtcore.h").is_file()
    }

    fn header_version(root: &Path) -> Option<u32> {
        [4, 3].into_iter().find(|&m| has_header(root, m))
    }

    pub fn generate() {
        let found = locate();
        let header_dir = found.include_root.join(format!("embree{}", found.major));
        println!("cargo::rerun-if-changed=wrapper.h");
        println!("cargo::rerun-if-changed={}", header_dir.display());
        println!("cargo::rerun-if-env-changed=LIBCLANG_PATH");

        let out = PathBuf::from(env::var_os("OUT_DIR").unwrap_or_else(|| fail("OUT_DIR is not set")))
            .join("embree_bindings.rs");
        // Reruns for the git revision need not regenerate the bindings: reuse them when the
        // header, its version and wrapper.h are what they were.
        let stamp_path = out.with_extension("stamp");
        let stamp = format!(
            "{} {} {:?} {:?}",
            header_dir.display(),
            found.major,
            std::fs::metadata(header_dir.join("rtcore.h")).and_then(|m| m.modified()).ok(),
            std::fs::read("wrapper.h").unwrap_or_default()
        );
        let fresh = out.is_file() && std::fs::read_to_string(&stamp_path).is_ok_and(|s| s == stamp);
        if !fresh {
            generate_bindings(&found, &header_dir, &out);
            let _ = std::fs::write(&stamp_path, &stamp);
        }

        if let Some(lib_dir) = &found.lib_dir {
            println!("cargo::rustc-link-search=native={}", lib_dir.display());
            // Let this package's tests, examples and binaries find a non-system Embree at run time.
            println!("cargo::rustc-link-arg=-Wl,-rpath,{}", lib_dir.display());
        }
        println!("cargo::rustc-link-lib=dylib=embree{}", found.major);
        if found.major >= 4 {
            println!("cargo::rustc-cfg=embree4");
        }
    }

    fn generate_bindings(found: &Found, header_dir: &Path, out: &Path) {
        let mut builder = bindgen::Builder::default()
            .header("wrapper.h")
            .clang_arg(format!("-I{}", found.include_root.display()))
            .allowlist_function("rtc.*")
            .allowlist_type("RTC.*")
            .allowlist_var("RTC.*")
            // C enums become plain integer constants (`RTC_ERROR_NONE: RTCError`): a Rust enum
            // would be undefined behaviour if Embree ever returned a value it does not list.
            .default_enum_style(bindgen::EnumVariation::Consts)
            .prepend_enum_name(false)
            .derive_default(true)
            .derive_debug(true)
            .generate_comments(false)
            .layout_tests(true)
            .rust_target(bindgen::RustTarget::stable(80, 0).unwrap_or_else(|e| fail(&format!("bindgen: {e}"))))
            .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
        if found.major >= 4 {
            builder = builder.clang_arg("-DINIMTRACE_EMBREE4");
        }

        // bindgen panics when libclang cannot be loaded; turn that into the same one-line error.
        let default_hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || builder.generate()));
        std::panic::set_hook(default_hook);
        let bindings = match result {
            Ok(Ok(b)) => b,
            Ok(Err(e)) => fail(&format!(
                "bindgen failed on {} ({e}); is `{INSTALL_HINT}` complete?",
                header_dir.join("rtcore.h").display()
            )),
            Err(panic) => {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                fail(&format!("bindgen could not run ({what}); install libclang with `{INSTALL_HINT}`"))
            }
        };
        if let Err(e) = bindings.write_to_file(out) {
            fail(&format!("cannot write {}: {e}", out.display()));
        }
    }
}
