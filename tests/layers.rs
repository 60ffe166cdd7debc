//! The library's layers hold (docs/ARCHITECTURE.md, "Layers"): every `crate::` path in a module of
//! `src/` names a module of a strictly lower layer, so no import runs upward and no circle crosses
//! folders. The table below is the diagram in ARCHITECTURE.md; a new top-level module must be
//! placed in it. Read from the source text: `use crate::...`, `crate::{...}` groups and inline
//! `crate::x::...` paths, outside comments and `#[cfg(test)] mod tests` blocks.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Bottom up: a module may use the modules of the layers before its own.
const LAYERS: &[&[&str]] = &[
    &["error", "count", "long_run", "overrides", "ray", "cpu"],
    &["budget", "progress"],
    &["optics", "raster"],
    &["metrics", "scene"],
    &["accel", "fixtures", "info"],
    &["render", "version"],
    &["measure"],
    &["perception", "io"],
    &["optimize", "provenance"],
    &["methods", "report"],
    &["experiment"],
    &["bench", "resolution", "settings"],
    &["sweep"],
];

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a file of `src/` belongs to (`None` for the crate root and the binary).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel.components().next()?.as_os_str().to_str()?.trim_end_matches(".rs").to_string();
    (!matches!(first.as_str(), "lib" | "main" | "cli")).then_some(first)
}

/// The source without comment lines, trailing comments and the unit-test module.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]\nmod tests {").next().unwrap();
    text.lines()
        .map(|l| if l.trim_start().starts_with("//") { "" } else { l.split(" // ").next().unwrap() })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The top-level modules a piece of code names through `crate::`.
fn used_modules(code: &str) -> BTreeSet<String> {
    let ident = |s: &str| s.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect::<String>();
    let mut out = BTreeSet::new();
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            // `crate::{a, b::c, d::{e, f}}`: the first name of each top-level item.
            let mut depth = 0usize;
            let mut item_start = true;
            for (j, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => item_start = true,
                    c if item_start && (c.is_ascii_alphanumeric() || c == '_') => {
                        out.insert(ident(&group[j..]));
                        item_start = false;
                    }
                    _ => {}
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

#[test]
fn the_parser_reads_paths_groups_and_skips_comments_and_tests() {
    let src = "use crate::optics::Eye;\nuse crate::{error::Result, io::{a, b}, ray};\n// crate::sweep\nlet x = crate::render::f(); // crate::bench\n#[cfg(test)]\nmod tests {\n    use crate::experiment;\n}\n";
    let want: BTreeSet<String> = ["optics", "error", "io", "ray", "render"].iter().map(|s| s.to_string()).collect();
    assert_eq!(used_modules(&code(src)), want);
}

#[test]
fn no_module_imports_from_its_own_layer_or_above() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut unplaced = BTreeSet::new();
    let mut upward = Vec::new();
    for f in &files {
        let Some(m) = module_of(&src, f) else { continue };
        if f.file_name().is_some_and(|n| n == "tests.rs") {
            continue;
        }
        let Some(own) = layer(&m) else {
            unplaced.insert(m);
            continue;
        };
        for used in used_modules(&code(&std::fs::read_to_string(f).unwrap())) {
            if used == m || used == "self" || used == "super" {
                continue;
            }
            match layer(&used) {
                Some(l) if l < own => {}
                Some(l) => upward.push(format!(
                    "{} (module `{m}`, layer {own}) uses `crate::{used}` (layer {l})",
                    f.strip_prefix(&src).unwrap().display()
                )),
                None => {
                    unplaced.insert(used);
                }
            }
        }
    }
    assert!(unplaced.is_empty(), "modules missing from the layer table: {unplaced:?}");
    assert!(upward.is_empty(), "imports that do not run downward:\n{}", upward.join("\n"));
}
