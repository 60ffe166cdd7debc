//! The CPU instructions this build assumes, so that a CPU without them gets one clear line
//! instead of "illegal instruction".
//!
//! The release build targets x86-64-v3 (AVX2, FMA, BMI1/2, ...; set in `.cargo/config.toml` for
//! x86_64 Linux): the compiler vectorises the hot loops (the SSIM filtering, eq. (1) over a
//! batch of eye rays, the sample sums) four `f64` wide instead of two. It never fuses a
//! multiply and an add that the source writes apart, so the numbers are the same bit for bit as
//! with any other x86-64 target.
//!
//! The CPU is asked directly (`CPUID`): `is_x86_feature_detected!` answers "yes" without asking
//! for every feature the build was compiled to assume. The CLI runs [`exit_if_unsupported`]
//! first. It is itself compiled for x86-64-v3, so it is written to need nothing past plain
//! x86-64: integer code, and text written by the standard library's own code (`tests/cpu.rs`
//! runs the binary on emulated CPUs down to the x86-64 of 2003). The Python module checks
//! [`lacks_assumed_features`] first and raises `ImportError` with a static text; PyO3's module
//! set-up runs before that, which works on CPUs with AVX (`python/tests/test_cpu.py`).

/// A feature the build may assume: its name (as `target_feature` names it), whether the build
/// assumes it, and where `CPUID` reports it (leaf, register: 1 = EBX, 2 = ECX, bit).
struct Feature {
    name: &'static str,
    assumed: bool,
    leaf: u32,
    register: u8,
    bit: u8,
}

macro_rules! feature {
    ($name:tt, $leaf:expr, $register:expr, $bit:expr) => {
        Feature { name: $name, assumed: cfg!(target_feature = $name), leaf: $leaf, register: $register, bit: $bit }
    };
}

/// Everything up to x86-64-v3, plus the AVX-512 subsets a `target-cpu=native` build may add.
const FEATURES: [Feature; 20] = [
    feature!("sse3", 1, 2, 0),
    feature!("ssse3", 1, 2, 9),
    feature!("fma", 1, 2, 12),
    feature!("cmpxchg16b", 1, 2, 13),
    feature!("sse4.1", 1, 2, 19),
    feature!("sse4.2", 1, 2, 20),
    feature!("movbe", 1, 2, 22),
    feature!("popcnt", 1, 2, 23),
    feature!("xsave", 1, 2, 26),
    feature!("avx", 1, 2, 28),
    feature!("f16c", 1, 2, 29),
    feature!("bmi1", 7, 1, 3),
    feature!("avx2", 7, 1, 5),
    feature!("bmi2", 7, 1, 8),
    feature!("avx512f", 7, 1, 16),
    feature!("avx512dq", 7, 1, 17),
    feature!("avx512cd", 7, 1, 28),
    feature!("avx512bw", 7, 1, 30),
    feature!("avx512vl", 7, 1, 31),
    feature!("lzcnt", 0x8000_0001, 2, 5),
];

/// The `CPUID` registers EBX and ECX of leaves 1, 7 (sub-leaf 0) and 0x8000_0001, as
/// `[leaf][register - 1]` (zeros for a leaf the CPU does not have). Leaf 1's ECX has the AVX bit
/// cleared unless the operating system saves the AVX registers (its OSXSAVE bit), since AVX
/// code cannot run otherwise.
#[cfg(target_arch = "x86_64")]
fn cpuid() -> [[u32; 2]; 3] {
    use std::arch::x86_64::{__cpuid, __cpuid_count};
    let max = __cpuid(0).eax;
    let max_ext = __cpuid(0x8000_0000).eax;
    let one = __cpuid(1);
    let os_avx = one.ecx >> 27 & 1 == 1;
    let ebx_ecx = |r: std::arch::x86_64::CpuidResult| [r.ebx, r.ecx];
    [
        [one.ebx, if os_avx { one.ecx } else { one.ecx & !(1 << 28) }],
        if max >= 7 { ebx_ecx(__cpuid_count(7, 0)) } else { [0, 0] },
        if max_ext >= 0x8000_0001 { ebx_ecx(__cpuid(0x8000_0001)) } else { [0, 0] },
    ]
}

#[cfg(not(target_arch = "x86_64"))]
fn cpuid() -> [[u32; 2]; 3] {
    [[0; 2]; 3]
}

/// Where `f`'s bit is in [`cpuid`]'s answer: `regs[i][j]`.
fn word(f: &Feature) -> (usize, usize) {
    let leaf = match f.leaf {
        1 => 0,
        7 => 1,
        _ => 2,
    };
    (leaf, usize::from(f.register - 1))
}

/// Whether `regs` (as [`cpuid`] gives them) report `f`.
fn reported(regs: &[[u32; 2]; 3], f: &Feature) -> bool {
    let (i, j) = word(f);
    regs[i][j] >> f.bit & 1 == 1
}

/// Bit `i` set: the build assumes `FEATURES[i]` and `regs` do not report it.
fn missing_mask(regs: &[[u32; 2]; 3]) -> u32 {
    let mut mask = 0;
    for (i, f) in FEATURES.iter().enumerate() {
        if f.assumed && !reported(regs, f) {
            mask |= 1 << i;
        }
    }
    mask
}

/// Whether this CPU lacks any feature the build assumes (integer code only).
#[inline(never)]
pub fn lacks_assumed_features() -> bool {
    missing_mask(&cpuid()) != 0
}

/// The start of every message: what the build assumes.
macro_rules! built_for {
    () => {
        "this inimtrace was built for x86-64-v3 CPUs (see .cargo/config.toml)"
    };
}

/// How to build for this machine, with `$command` (`cargo build --release`, `pip install .`).
macro_rules! rebuild {
    ($command:literal) => {
        concat!("rebuild it for this machine: RUSTFLAGS=\"-C target-cpu=native\" ", $command)
    };
}

/// What to say when [`lacks_assumed_features`], without naming the features (a static text).
pub const UNSUPPORTED: &str =
    concat!(built_for!(), ", which this CPU is not (AVX2, FMA, BMI1/2); ", rebuild!("pip install ."));

/// The features this build assumes.
pub fn assumed() -> Vec<&'static str> {
    FEATURES.iter().filter(|f| f.assumed).map(|f| f.name).collect()
}

const HEAD: &str = concat!(built_for!(), "; this CPU lacks ");
const TAIL: &str = concat!("; ", rebuild!("cargo build --release"));

/// Stops the process with one line on stderr (exit status 1) naming what this CPU lacks of what
/// the build assumes, and how to build for it. Integer code only and no allocation: the standard
/// library's own (baseline x86-64) code writes the text.
#[inline(never)]
pub fn exit_if_unsupported() {
    let mask = missing_mask(&cpuid());
    if mask == 0 {
        return;
    }
    let mut err = std::io::stderr();
    let mut write = |text: &str| {
        let _ = std::io::Write::write_all(&mut err, text.as_bytes());
    };
    write("error: ");
    write(HEAD);
    let mut first = true;
    for (i, f) in FEATURES.iter().enumerate() {
        if mask >> i & 1 == 1 {
            if !first {
                write(", ");
            }
            write(f.name);
            first = false;
        }
    }
    write(TAIL);
    write("\n");
    std::process::exit(1);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(mask: u32) -> Vec<&'static str> {
        FEATURES.iter().enumerate().filter(|(i, _)| mask >> i & 1 == 1).map(|(_, f)| f.name).collect()
    }

    fn clear(regs: &mut [[u32; 2]; 3], f: &Feature) {
        let (i, j) = word(f);
        regs[i][j] &= !(1 << f.bit);
    }

    #[test]
    fn the_cpuid_table_and_the_missing_features_of_a_lesser_cpu() {
        // Every name is a target feature the compiler knows (`cfg!` of an unknown name is
        // always false, so a typo would silently never be checked): the x86-64-v3 build
        // assumes each of the v3 ones.
        let v3 = ["sse3", "ssse3", "fma", "cmpxchg16b", "sse4.1", "sse4.2", "movbe", "popcnt", "xsave", "avx"];
        let v3 = v3.iter().chain(&["f16c", "bmi1", "avx2", "bmi2", "lzcnt"]);
        if cfg!(target_feature = "avx2") {
            for f in v3.clone() {
                assert!(assumed().contains(f), "{f} not assumed: {:?}", assumed());
            }
        }
        // A CPU reporting everything misses nothing; one reporting nothing misses all assumed.
        let all = [[u32::MAX; 2]; 3];
        assert_eq!(missing_mask(&all), 0);
        assert_eq!(names(missing_mask(&[[0; 2]; 3])), assumed());
        // Each feature is read from its own bit: clearing it alone makes exactly it missing.
        for f in FEATURES.iter().filter(|f| f.assumed) {
            let mut regs = all;
            clear(&mut regs, f);
            assert_eq!(names(missing_mask(&regs)), vec![f.name]);
        }
        // The real CPU: these tests run, so it has everything the build assumes.
        assert_eq!(names(missing_mask(&cpuid())), Vec::<&str>::new());
        assert!(!lacks_assumed_features());
        exit_if_unsupported();
    }

    /// Every bit read from `CPUID` against the kernel's reading of the same CPU (the flags of
    /// `/proc/cpuinfo`, Linux's names).
    #[test]
    #[cfg(all(target_arch = "x86_64", target_os = "linux"))]
    fn cpuid_bits_agree_with_the_kernels_cpu_flags() {
        let info = std::fs::read_to_string("/proc/cpuinfo").unwrap();
        let flags: Vec<&str> = info.lines().find(|l| l.starts_with("flags")).unwrap().split_whitespace().collect();
        let regs = cpuid();
        for f in &FEATURES {
            let linux = match f.name {
                "sse3" => "pni",
                "cmpxchg16b" => "cx16",
                "sse4.1" => "sse4_1",
                "sse4.2" => "sse4_2",
                "lzcnt" => "abm",
                name => name,
            };
            assert_eq!(reported(&regs, f), flags.contains(&linux), "{} ({linux})", f.name);
        }
    }
}
