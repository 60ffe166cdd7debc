//! Runs a small sweep locally: `sweeps/tiny.toml`, the paper's experiment at small sizes over
//! three pupil diameters, two eye focus settings and two eye positions (12 points), and prints
//! the collection summary. Each point is recorded in `<out>/points/` as it finishes, and
//! `<out>/scores.csv` holds every point's Table 1.
//!
//! ```text
//! cargo run --release --example small_sweep [-- OUT_DIR]   # default: out/examples/tiny
//! ```

use std::path::{Path, PathBuf};
use std::time::Instant;

use inimtrace::sweep::{execute, SweepCommand};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| root.join("out/examples/tiny"));
    let cmd = SweepCommand {
        sweep: root.join("sweeps/tiny.toml"),
        out: Some(out.clone()),
        quiet: true,
        ..SweepCommand::default()
    };
    let start = Instant::now();
    // The library does not print: progress messages come to this closure.
    let summary = execute(&cmd, &mut |message| eprintln!("{message}"))?;
    println!("{}", summary.stdout);
    println!("sweep written to {} in {:.1} s", out.display(), start.elapsed().as_secs_f64());
    Ok(())
}
