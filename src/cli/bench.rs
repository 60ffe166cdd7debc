//! `inimtrace bench`: the speed benchmark of one scene, or with `--backends` the comparison of
//! the mesh backends (the library's `bench::backends`).

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

/// `inimtrace bench --backends`: the mesh backends compared on each scene (default: the bunny and
/// two million spheres), the table printed and written into `out`.
pub(crate) fn bench_backends(
    g: &Globals,
    quick: bool,
    scene: Vec<PathBuf>,
    out: Option<PathBuf>,
    also: Option<PathBuf>,
    embree_only: bool,
    embree_input: Option<PathBuf>,
) -> Result<()> {
    let scenes = match scene.is_empty() {
        true => vec![PathBuf::from("scenes/bunny.toml"), PathBuf::from("scenes/spheres-2m.toml")],
        false => scene,
    };
    let out = out.unwrap_or_else(|| PathBuf::from("out/bench-backends"));
    let opts = inimtrace::bench::BackendsOptions { scenes, quick, also, embree_only, out: out.clone(), embree_input };
    let rows = inimtrace::bench::backends::run(&opts)?;
    out!("{}", inimtrace::bench::backends::markdown(&rows));
    if !g.quiet {
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}
