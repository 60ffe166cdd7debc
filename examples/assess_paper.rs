//! Assesses the paper's experiment (Sec. 4.1, `experiments/paper.toml`: the grid estimator) and
//! prints Table 1: PSNR and SSIM of what each eye case perceives of each method's display image,
//! against the eye looking straight at the scene.
//!
//! ```text
//! cargo run --release --example assess_paper            # small sizes, a few seconds
//! cargo run --release --example assess_paper -- --full  # the paper's sizes (minutes)
//! ```
//!
//! The small run gives the LCD 540 x 540 pixels instead of 2160 x 2160, the retina 64 x 64
//! pixels instead of 512 x 512 and the pupil a 4 x 4 grid instead of 8 x 8, through the same
//! `--set` overrides the command line takes.

use std::path::Path;
use std::time::Instant;

use inimtrace::experiment::{assess_images, table_markdown, RunOptions};
use inimtrace::overrides::{parse_value, Override};
use inimtrace::settings::load_experiment;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let full = std::env::args().any(|a| a == "--full");
    let mut overrides = Vec::new();
    if !full {
        for (key, value) in
            [("display.lcd.resolution", "[540, 540]"), ("eye.retina_resolution", "64"), ("eye.pupil_grid", "4")]
        {
            overrides.push(Override::new(key, parse_value(value).expect("a TOML value")).expect("a settings key"));
        }
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper.toml");
    let exp = load_experiment(Some(&path), None, &overrides)?;
    println!("{}", exp.display.summary());

    let start = Instant::now();
    // `out: None`: keep the images in memory and write nothing (`assess` writes every output).
    let run = assess_images(&exp, None, RunOptions { quiet: true, ..RunOptions::default() })?;
    println!("{}", table_markdown(&run.report, &exp));
    println!(
        "{} eye cases x {} methods on the {} backend in {:.1} s",
        run.ground_truths.len(),
        run.displays.len(),
        run.report.backend,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
