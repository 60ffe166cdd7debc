//! A CPU without the instructions this build assumes (x86-64-v3 by `.cargo/config.toml`) gets
//! one line naming what it lacks and exit status 1, not "illegal instruction": the binary run
//! under qemu-user emulating older CPUs (Debian's `qemu-user`, which `scripts/install-deps.sh`
//! installs; skipped, saying so, without it unless `INIMTRACE_REQUIRE_QEMU` is set, as in CI).

use std::process::Command;

/// `inimtrace --version` on the emulated `cpu`: (exit code, stdout, stderr); `None` when
/// qemu-user is not installed.
fn run_on(cpu: &str) -> Option<(Option<i32>, String, String)> {
    let out =
        match Command::new("qemu-x86_64").args(["-cpu", cpu, env!("CARGO_BIN_EXE_inimtrace"), "--version"]).output() {
            Ok(out) => out,
            Err(e) => {
                assert!(
                    std::env::var_os("INIMTRACE_REQUIRE_QEMU").is_none(),
                    "INIMTRACE_REQUIRE_QEMU is set: qemu-x86_64: {e}"
                );
                eprintln!("skipped: qemu-x86_64 (Debian's qemu-user) cannot be run: {e}");
                return None;
            }
        };
    // qemu's own warnings (features its emulator leaves out) are not the program's.
    let stderr = String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| !l.starts_with("qemu-x86_64: warning"))
        .collect::<Vec<_>>()
        .join("\n");
    Some((out.status.code(), String::from_utf8_lossy(&out.stdout).into_owned(), stderr))
}

#[test]
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
fn an_older_cpu_gets_one_line_naming_what_it_lacks() {
    let assumed = inimtrace::cpu::assumed();
    if assumed.iter().any(|f| f.starts_with("avx512")) {
        eprintln!("skipped: this build assumes AVX-512 ({assumed:?}), which qemu-user does not emulate");
        return;
    }
    // The emulation itself works: a CPU with everything x86-64-v3 has runs the binary.
    let Some((code, stdout, stderr)) = run_on("Haswell-noTSX") else { return };
    assert_eq!(code, Some(0), "Haswell: {stdout} {stderr}");
    assert!(stdout.starts_with("inimtrace "), "{stdout}");
    // Sandy Bridge (AVX, no AVX2/FMA/BMI) and the baseline x86-64 of 2003 (SSE2 only).
    for (cpu, lacks) in [("SandyBridge", &["fma", "avx2", "bmi2"][..]), ("qemu64", &["sse4.2", "avx", "avx2"][..])] {
        let (code, stdout, stderr) = run_on(cpu).unwrap();
        let lacking: Vec<_> = lacks.iter().filter(|f| assumed.contains(f)).collect();
        if lacking.is_empty() {
            // A build that does not assume them (RUSTFLAGS overriding the configuration) runs.
            assert_eq!(code, Some(0), "{cpu}: {stdout} {stderr}");
            continue;
        }
        assert_eq!(code, Some(1), "{cpu}: {stdout} {stderr}");
        assert!(stdout.is_empty(), "{cpu}: {stdout}");
        assert_eq!(stderr.lines().count(), 1, "{cpu}: {stderr}");
        assert!(stderr.starts_with("error: this inimtrace was built for x86-64-v3 CPUs"), "{cpu}: {stderr}");
        assert!(stderr.contains("target-cpu=native"), "{cpu}: {stderr}");
        for f in lacking {
            assert!(stderr.contains(&format!(" {f}")), "{cpu} should be said to lack {f}: {stderr}");
        }
    }
}
