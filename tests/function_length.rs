//! No function outside tests runs over 120 lines (the engineering standard; issue #49), as
//! `scripts/long-functions.py` counts them: from the `fn` line to the closing brace, outside
//! `#[cfg(test)]` modules. The script itself is checked on a made-up crate whose lengths are known.

use std::path::Path;
use std::process::{Command, Output};

fn script(root: &Path, limit: &str) -> Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/long-functions.py");
    Command::new("python3").arg(script).args(["--root", root.to_str().unwrap(), "--limit", limit]).output().unwrap()
}

/// A function named `name` of exactly `lines` lines (its `fn` line to its closing brace), whose
/// body holds braces in strings, characters, comments and raw strings, a lifetime and a closure.
fn function(name: &str, lines: usize) -> String {
    let tricky = [
        "    let _s = \"}}} \\\" {\";",
        "    let _c = ('{', '}', '\\'', '\\u{7d}');",
        "    // } a comment's brace",
        "    /* { a block comment's brace /* nested } */ */",
        "    let _r = r#\"}\"# ;",
        "    let _f = |x: &'static str| -> usize { x.len() };",
    ];
    let mut body: Vec<String> = tricky.iter().map(|s| s.to_string()).collect();
    while body.len() < lines - 3 {
        body.push(format!("    let _x{} = {};", body.len(), body.len()));
    }
    // The `;` of `[u8; 4]` in the signature does not end it.
    format!("fn {name}<'a>(_f: fn(u32) -> u32, v: &'a [u8; 4]) -> [u8; 4] {{\n{}\n    *v\n}}\n", body.join("\n"))
}

#[test]
fn the_script_counts_from_fn_to_its_closing_brace_outside_test_modules() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir_all(&src).unwrap();
    let lib = format!(
        "//! A crate.\nmod other;\n#[cfg(test)]\nmod unit;\n\ntrait T {{\n    fn declared(&self);\n}}\n\n{}\n{}\n\
         #[cfg(test)]\nmod tests {{\n    use super::*;\n{}}}\n",
        function("exactly_120", 120),
        function("over_120", 121),
        function("a_long_test", 300),
    );
    std::fs::write(src.join("lib.rs"), &lib).unwrap();
    std::fs::write(src.join("other.rs"), function("other_long", 130)).unwrap();
    std::fs::write(src.join("unit.rs"), function("unit_test_file", 200)).unwrap();
    let over_120_line = lib.lines().position(|l| l.starts_with("fn over_120")).unwrap() + 1;

    let out = script(dir.path(), "120");
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        stdout,
        format!("src/other.rs:1: fn other_long is 130 lines\nsrc/lib.rs:{over_120_line}: fn over_120 is 121 lines\n")
    );
    // Under a higher limit nothing is listed, and the script succeeds.
    let out = script(dir.path(), "130");
    assert!(out.status.success() && out.stdout.is_empty(), "{}", String::from_utf8_lossy(&out.stdout));
}

#[test]
fn no_function_outside_tests_is_over_120_lines() {
    let out = script(Path::new(env!("CARGO_MANIFEST_DIR")), "120");
    assert!(
        out.status.success(),
        "functions over 120 lines (split them into named steps):\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
