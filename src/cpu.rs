//! The CPU instructions this build assumes, so that a CPU without them gets one clear line
//! instead of "illegal instruction".
//!
//! The release build targets x86-64-v3 (AVX2, FMA, BMI1/2, ...; set in `.cargo/config.toml` for
//! x86_64 Linux): the compiler vectorises the hot loops (the SSIM filtering, eq. (1) over a
//! batch of eye rays, the sample sums) four `f64` wide instead of two. It never fuses a
//! multiply and an add that the source writes apart, so the numbers are the same bit for bit as
//! with any other x86-64 target. The CLI and the Python module check [`missing`] before doing
//! anything else.

/// The x86 features a build may assume, as `is_x86_feature_detected!` names them: whether the
/// compiler was told to assume it, and whether this CPU has it.
#[cfg(target_arch = "x86_64")]
macro_rules! features {
    ($($f:tt),* $(,)?) => {
        fn table() -> Vec<(&'static str, bool, bool)> {
            vec![$(($f, cfg!(target_feature = $f), std::arch::is_x86_feature_detected!($f))),*]
        }
    };
}

// Everything up to x86-64-v3, plus the AVX-512 subsets a `target-cpu=native` build may add.
#[cfg(target_arch = "x86_64")]
features!(
    "sse3",
    "ssse3",
    "sse4.1",
    "sse4.2",
    "popcnt",
    "cmpxchg16b",
    "avx",
    "avx2",
    "bmi1",
    "bmi2",
    "fma",
    "f16c",
    "lzcnt",
    "movbe",
    "xsave",
    "avx512f",
    "avx512bw",
    "avx512cd",
    "avx512dq",
    "avx512vl",
);

#[cfg(not(target_arch = "x86_64"))]
fn table() -> Vec<(&'static str, bool, bool)> {
    Vec::new()
}

/// The features this build assumes (those of the table the compiler was told to assume).
pub fn assumed() -> Vec<&'static str> {
    table().into_iter().filter(|&(_, assumed, _)| assumed).map(|(f, ..)| f).collect()
}

/// The features of `assumed` that `has` says the CPU lacks.
fn missing_from(assumed: &[&'static str], has: impl Fn(&str) -> bool) -> Vec<&'static str> {
    assumed.iter().copied().filter(|f| !has(f)).collect()
}

/// The features this build assumes that this CPU lacks (empty: it can run here).
pub fn missing() -> Vec<&'static str> {
    let table = table();
    missing_from(&assumed(), |f| table.iter().any(|&(g, _, has)| g == f && has))
}

/// Why this build cannot run on this CPU, or `None` when it can.
pub fn unsupported() -> Option<String> {
    let missing = missing();
    (!missing.is_empty()).then(|| message(&missing))
}

fn message(missing: &[&str]) -> String {
    format!(
        "this inimtrace was built for CPUs with {} (x86-64-v3, see .cargo/config.toml), which this CPU lacks; \
         rebuild it for this machine: RUSTFLAGS=\"-C target-cpu=native\" cargo build --release",
        missing.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cpu_without_the_assumed_features_is_told_which_it_lacks() {
        let v3 = ["sse4.2", "avx", "avx2", "bmi2", "fma"];
        assert_eq!(missing_from(&v3, |_| true), Vec::<&str>::new());
        assert_eq!(missing_from(&v3, |_| false), v3.to_vec());
        // A CPU with AVX but neither AVX2 nor FMA.
        let lacks = missing_from(&v3, |f| f != "avx2" && f != "fma");
        assert_eq!(lacks, vec!["avx2", "fma"]);
        let m = message(&lacks);
        assert!(m.contains("with avx2, fma (x86-64-v3") && m.contains("target-cpu=native"), "{m}");
        // Every feature the build assumes is one the table knows; these tests run, so this CPU
        // has them all.
        let known: Vec<_> = table().into_iter().map(|(f, ..)| f).collect();
        assert!(assumed().iter().all(|f| known.contains(f)));
        assert_eq!(missing(), Vec::<&str>::new());
        assert_eq!(unsupported(), None);
    }
}
