//! Renders a mesh scene with the Embree backend: `scenes/bunny.toml` (the Stanford bunny of the
//! Debian package glmark2-data in front of a USAF-1951 chart) on the paper's display. Renders
//! the LensletCenter display image, simulates what a 5 mm pupil focused at 400 mm perceives of
//! it (eq. (1) through the lenslets), renders the ground truth (the same eye looking straight
//! at the scene) and prints PSNR and SSIM; writes PNG previews of the three images.
//!
//! ```text
//! cargo run --release --example mesh_embree [-- OUT_DIR]   # default: out/examples/bunny
//! ```
//!
//! Needs the `embree` feature (the default) and the system's Intel Embree.

use std::path::{Path, PathBuf};
use std::time::Instant;

use inimtrace::metrics::{psnr, ssim, SsimConstants};
use inimtrace::optics::{Display, Eye, Focus, Retina};
use inimtrace::progress::Progress;
use inimtrace::render::{ground_truth, render_display_image, simulate, with_fields, BackendChoice};
use inimtrace::render::{DisplayRenderSettings, Method};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| root.join("out/examples/bunny"));
    let scene = inimtrace::io::load_scene("scenes/bunny.toml", root)?;
    println!("scene `{}`: {} triangles", scene.name, scene.triangle_count());

    // The paper's display with a quarter of its LCD pixels per side (same size in millimetres).
    let mut display = Display::paper();
    display.lcd.resolution = [540, 540];
    let eye = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 4);
    let retina = Retina { resolution: 128, ..Retina::default() };
    let progress = Progress::hidden();

    let start = Instant::now();
    let (display_image, perceived, truth) = with_fields(&scene, BackendChoice::Embree, |fields| {
        let settings = DisplayRenderSettings::default();
        let shown = render_display_image(&display, Method::LensletCenter, &settings, fields.shade, &progress)?;
        let perceived = simulate(&display, &eye, &retina, &[&shown], &progress)?.remove(0);
        let truth = ground_truth(&eye, &retina, fields.shade, &progress);
        Ok((shown, perceived, truth))
    })?;
    let seconds = start.elapsed().as_secs_f64();

    let p = psnr(&perceived, &truth)?;
    let s = ssim(&perceived, &truth, SsimConstants::Wang2004)?;
    println!("LC, 5 mm pupil focused at 400 mm: PSNR {} dB, SSIM {:.4} ({seconds:.1} s)", p.mean_text(2), s.mean);

    std::fs::create_dir_all(&out)?;
    for (name, img) in [("display_lc", &display_image), ("perceived_lc", &perceived), ("ground_truth", &truth)] {
        let path = out.join(format!("{name}.png"));
        inimtrace::io::png::write_preview(&path, img)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
