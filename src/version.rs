//! Which inimtrace made an output: the package version and the git revision it was built from
//! (fixed at build time by `build.rs`, so a binary run outside the checkout still knows it).
//! Written into every EXR header, `results.json` and the bench reports.

use serde::Serialize;

/// The package version (`Cargo.toml`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// `git describe --always --dirty --abbrev=7` of the source tree at build time (`-dirty` when
/// it had uncommitted changes), `$INIMTRACE_GIT_REVISION` when that was set at build time, or
/// `unknown` when built outside a git checkout.
pub const GIT_REVISION: &str = env!("INIMTRACE_GIT_REVISION");

/// The tool that wrote an output, as reports record it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Tool {
    /// "inimtrace".
    pub name: &'static str,
    /// The crate version.
    pub version: &'static str,
    /// The git revision it was built from (`unknown` outside a checkout).
    pub git_revision: &'static str,
}

/// This build.
pub const TOOL: Tool = Tool { name: "inimtrace", version: VERSION, git_revision: GIT_REVISION };

/// `"inimtrace 0.1.0 (git abc1234)"`: the EXR `software` attribute.
pub fn software() -> String {
    format!("inimtrace {VERSION} (git {GIT_REVISION})")
}

/// The Embree library this process loads, as `inimtrace --version` and `inimtrace info` print
/// it: `"Embree 4.4.0"` (the version the library itself reports through
/// `rtcGetDeviceProperty`, which starts an Embree device), `"without Embree"` without the
/// `embree` feature, or why it cannot start.
pub fn embree_loaded() -> String {
    #[cfg(feature = "embree")]
    {
        match crate::accel::embree::Device::with_config("threads=1") {
            Ok(device) => format!("Embree {}", device.version_text()),
            Err(e) => format!("Embree {}.x: cannot start ({e})", crate::accel::embree::EMBREE_MAJOR),
        }
    }
    #[cfg(not(feature = "embree"))]
    {
        "without Embree".to_string()
    }
}

/// The text of `inimtrace --version` after the program's name: the package version, the git
/// revision and the Embree library loaded (`"0.1.0 (git abc1234; Embree 4.4.0)"`).
pub fn long() -> String {
    format!("{VERSION} (git {GIT_REVISION}; {})", embree_loaded())
}
