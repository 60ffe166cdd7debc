//! Counts read as English wherever inimtrace prints one: "1 lenslet", "2 lenslets", never
//! "lenslet(s)" or "1 lenslets". Every count goes through `inimtrace::count` (its unit test has
//! the rules); this test keeps the hedged plural out of every message in the sources and checks
//! the words of two commands' real output.

use std::path::Path;
use std::process::Command;

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn one_is_singular_and_every_other_count_plural() {
    use inimtrace::count::{count, count_as};
    assert_eq!(count(1usize, "lenslet"), "1 lenslet");
    assert_eq!(count(2usize, "lenslet"), "2 lenslets");
    assert_eq!(count(0u64, "triangle"), "0 triangles");
    assert_eq!(count(1u64, "point record"), "1 point record");
    assert_eq!(count(21usize, "point record"), "21 point records");
    assert_eq!(count(2usize, "mesh"), "2 meshes");
    assert_eq!(count(3usize, "array task"), "3 array tasks");
    assert_eq!(count(2usize, "entry"), "2 entries");
    assert_eq!(count(2usize, "day"), "2 days");
    assert_eq!(count(5usize, "index"), "5 indexes");
    assert_eq!(count_as(1usize, "vertex", "vertices"), "1 vertex");
    assert_eq!(count_as(7usize, "vertex", "vertices"), "7 vertices");
    assert_eq!(count(-1i64, "step"), "-1 steps");
}

#[test]
fn no_message_hedges_its_plural() {
    let mut files = Vec::new();
    sources(Path::new("src"), &mut files);
    sources(Path::new("python/src"), &mut files);
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in text.lines().enumerate() {
            let code = line.trim_start();
            if code.starts_with("//") {
                continue;
            }
            // A string literal's word followed by (s) or (es): `point(s)`, `mesh(es)`.
            let hedged = ["(s)", "(es)"].iter().any(|h| {
                line.match_indices(h).any(|(at, _)| {
                    line[..at].ends_with(|c: char| c.is_ascii_alphabetic()) && line[..at].matches('"').count() % 2 == 1
                })
            });
            if hedged {
                found.push(format!("{}:{}: {}", f.display(), i + 1, code));
            }
        }
    }
    assert!(found.is_empty(), "hedged plurals (use inimtrace::count::count):\n{}", found.join("\n"));
}

#[test]
fn one_object_and_one_triangle_read_in_the_singular() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("one.toml");
    std::fs::write(
        &scene,
        "name = \"one\"\n[[objects]]\nname = \"card\"\ntype = \"rect\"\ncenter = [0.0, 0.0, 400.0]\n\
         size = [100.0, 100.0]\nmaterial = { albedo = [0.5, 0.5, 0.5] }\n",
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(["info", "--scene"]).arg(&scene).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("scene one: 1 object, 2 triangles"), "{text}");
}
