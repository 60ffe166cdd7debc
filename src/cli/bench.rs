//! `inimtrace bench`: the speed benchmark of one scene (the backends comparison is run from
//! `main.rs`, by the library's `bench::backends`).

use std::path::{Path, PathBuf};

use anyhow::Result;

use inimtrace::io::load_scene;
use inimtrace::scene::Scene;
use inimtrace::settings::scene_with;

use crate::Globals;

/// `inimtrace bench`; returns whether it printed its own total time.
pub(crate) fn bench(g: &Globals, quick: bool, scene: Option<PathBuf>, out: Option<PathBuf>) -> Result<bool> {
    let (set, quiet) = (&g.set[..], g.quiet);
    let mut printed_total = false;
    let (scene, label) = match &scene {
        _ if !set.is_empty() => (scene_with(scene.as_deref(), set)?, "--set".to_string()),
        Some(p) => (load_scene(&p.to_string_lossy(), Path::new(""))?, p.display().to_string()),
        None => (Scene::paper(), "builtin:paper".to_string()),
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let out = out.unwrap_or_else(|| PathBuf::from(if quick { "out/bench-quick" } else { "out/bench" }));
    let opts = inimtrace::bench::BenchOptions::new(quick, out.clone(), quiet);
    let report = inimtrace::bench::run(&opts, &scene, &label)?;
    out!("{}", inimtrace::bench::console_table(&report));
    if g.timings {
        printed_total = true;
        eprintln!("{:>8.3} s  bench ({} run)", report.total_seconds, report.mode);
    }
    if !quiet {
        eprintln!("wrote {}", out.display());
    }
    Ok(printed_total)
}
