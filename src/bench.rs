//! `inimtrace bench`: every rendering method reported as speed against error, and the
//! convergence of each sampling parameter (LA's k x k lenslet grid, the eye's n x n pupil grid,
//! samples per retina pixel) against a high-sample reference of the same quantity, so a user can
//! pick the cheapest setting that is accurate enough. Writes `bench.csv`, `bench.json` and
//! plots (PNG and SVG, plotters).

use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::prelude::*;
use serde::Serialize;

use crate::accel::analytic::AnalyticRects;
use crate::error::{Error, Result};
use crate::metrics::{self, SsimConstants};
use crate::optics::{Display, Eye, Focus, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::retina::simulate;
use crate::render::{
    ground_truth, render_display_image, DisplayRenderSettings, FacingPlanes, Method, RadianceField, SceneTracer,
};
use crate::scene::Scene;

/// Settings of a bench run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Small sizes (LCD 540 x 540, retina 128 x 128): finishes in well under a minute.
    pub quick: bool,
    pub out: PathBuf,
    pub quiet: bool,
}

/// One measured point.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    /// "method", "la_grid", "pupil_grid", "retina_samples".
    pub series: String,
    pub backend: String,
    pub method: String,
    /// The swept parameter's value (k, n, or samples per axis).
    pub parameter: usize,
    pub seconds: f64,
    pub rays: u64,
    pub rays_per_second: f64,
    pub psnr_db: f64,
    pub ssim: f64,
    pub threads: usize,
    pub git_revision: String,
    pub lcd_resolution: usize,
    pub retina_resolution: usize,
}

fn git_revision() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

fn score(a: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
    let p = metrics::psnr(a, reference)?.mean;
    let s = metrics::ssim(a, reference, SsimConstants::Wang2004)?.mean;
    // Identical images: report a large finite PSNR so tables and plots stay finite.
    Ok((if p.is_finite() { p } else { 200.0 }, s))
}

/// Runs the benchmark on the paper's scene and display.
pub fn run(opts: &BenchOptions) -> Result<Vec<BenchRow>> {
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let scene = Scene::paper();
    let mut display = Display::paper();
    let (lcd, ret) = if opts.quick { (540, 128) } else { (2160, 512) };
    display.lcd.resolution = [lcd, lcd];
    let retina = Retina { resolution: ret, ..Retina::default() };
    let analytic = AnalyticRects::new(&scene)?;
    let fused = FacingPlanes::new(&scene, &analytic).ok_or_else(|| Error::Unsupported("paper scene".into()))?;
    let generic = SceneTracer { scene: &scene, backend: &analytic };
    let backends: Vec<(&str, &dyn RadianceField)> = vec![("analytic-fused", &fused), ("analytic", &generic)];
    let rev = git_revision();
    let threads = rayon::current_num_threads();
    let eye = |n: usize| Eye::thin_lens(5.0, Focus::Millimetres(300.0), n);
    let s1 = DisplayRenderSettings::default();
    let hidden = Progress::hidden();
    let mut rows = Vec::new();
    let mut row =
        |series: &str, backend: &str, method: &str, parameter: usize, seconds: f64, rays: u64, q: (f64, f64)| {
            rows.push(BenchRow {
                series: series.into(),
                backend: backend.into(),
                method: method.into(),
                parameter,
                seconds,
                rays,
                rays_per_second: rays as f64 / seconds.max(1e-9),
                psnr_db: q.0,
                ssim: q.1,
                threads,
                git_revision: rev.clone(),
                lcd_resolution: lcd,
                retina_resolution: ret,
            })
        };
    let progress = Progress::new(4, "bench", opts.quiet);

    // 1. Speed against error per method and backend: the perceived image at Near focus (display
    //    render + simulation) against the same method rendered and simulated with many samples.
    let reference_eye = eye(16);
    let reference_retina = Retina { samples_per_pixel: 4, ..retina };
    let s4 = DisplayRenderSettings { samples_per_pixel: 4, ..s1 };
    for method in [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 5 }] {
        let ref_method = match method {
            Method::LensletAverage { .. } => Method::LensletAverage { grid: 10 },
            m => m,
        };
        let ref_display = render_display_image(&display, ref_method, &s4, &fused, &hidden)?;
        let reference = simulate(&display, &reference_eye, &reference_retina, &[&ref_display], &hidden)?.remove(0);
        for (name, field) in &backends {
            let t = Instant::now();
            let img = render_display_image(&display, method, &s1, *field, &hidden)?;
            let sim = simulate(&display, &eye(8), &retina, &[&img], &hidden)?.remove(0);
            let secs = t.elapsed().as_secs_f64();
            let rays = (lcd * lcd * method.lenslet_samples()) as u64;
            row("method", name, method.short_name(), method.lenslet_samples(), secs, rays, score(&sim, &reference)?);
        }
    }
    progress.inc(1);

    // 2. LA's k x k grid: the display image against k = 16.
    let reference = render_display_image(&display, Method::LensletAverage { grid: 16 }, &s1, &fused, &hidden)?;
    for k in 1..=8 {
        let t = Instant::now();
        let img = render_display_image(&display, Method::LensletAverage { grid: k }, &s1, &fused, &hidden)?;
        let secs = t.elapsed().as_secs_f64();
        row("la_grid", "analytic-fused", "LA", k, secs, (lcd * lcd * k * k) as u64, score(&img, &reference)?);
    }
    progress.inc(1);

    // 3. The eye's n x n pupil grid: the LC perceived image at Near against n = 32.
    let lc = render_display_image(&display, Method::LensletCenter, &s1, &fused, &hidden)?;
    let reference = simulate(&display, &eye(32), &retina, &[&lc], &hidden)?.remove(0);
    for n in [2, 3, 4, 5, 6, 8, 10, 12, 16] {
        let e = eye(n);
        let t = Instant::now();
        let sim = simulate(&display, &e, &retina, &[&lc], &hidden)?.remove(0);
        let secs = t.elapsed().as_secs_f64();
        let rays = (ret * ret * e.pupil_samples().len()) as u64;
        row("pupil_grid", "analytic-fused", "LC", n, secs, rays, score(&sim, &reference)?);
    }
    progress.inc(1);

    // 4. Samples per retina pixel: the Near ground truth against 16 x 16 samples.
    let reference = ground_truth(&eye(8), &Retina { samples_per_pixel: 16, ..retina }, &fused, &hidden);
    for k in [1, 2, 4, 8] {
        let r = Retina { samples_per_pixel: k, ..retina };
        let t = Instant::now();
        let gt = ground_truth(&eye(8), &r, &fused, &hidden);
        let secs = t.elapsed().as_secs_f64();
        let rays = (ret * ret * k * k * eye(8).pupil_samples().len()) as u64;
        row("retina_samples", "analytic-fused", "GT", k, secs, rays, score(&gt, &reference)?);
    }
    progress.inc(1);
    progress.finish();

    write_reports(&rows, &opts.out)?;
    Ok(rows)
}

fn write_reports(rows: &[BenchRow], out: &Path) -> Result<()> {
    let mut csv = String::from(
        "series,backend,method,parameter,seconds,rays,rays_per_second,psnr_db,ssim,threads,git_revision,lcd_resolution,retina_resolution\n",
    );
    for r in rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.series,
            r.backend,
            r.method,
            r.parameter,
            r.seconds,
            r.rays,
            r.rays_per_second,
            r.psnr_db,
            r.ssim,
            r.threads,
            r.git_revision,
            r.lcd_resolution,
            r.retina_resolution
        ));
    }
    let write = |name: &str, text: String| -> Result<()> {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| Error::io(&p, e))
    };
    write("bench.csv", csv)?;
    write("bench.json", serde_json::to_string_pretty(rows).map_err(|e| Error::Unsupported(e.to_string()))?)?;
    for series in ["method", "la_grid", "pupil_grid", "retina_samples"] {
        let pts: Vec<&BenchRow> = rows.iter().filter(|r| r.series == series).collect();
        for ext in ["png", "svg"] {
            let path = out.join(format!("{series}.{ext}"));
            let res = if ext == "png" {
                plot(BitMapBackend::new(&path, (900, 560)).into_drawing_area(), series, &pts)
            } else {
                plot(SVGBackend::new(&path, (900, 560)).into_drawing_area(), series, &pts)
            };
            res.map_err(|e| Error::Unsupported(format!("{}: cannot draw plot: {e}", path.display())))?;
        }
    }
    Ok(())
}

/// PSNR against wall time (log x), one series per method and backend (or one sweep).
fn plot<DB: DrawingBackend>(
    area: DrawingArea<DB, plotters::coord::Shift>,
    series: &str,
    pts: &[&BenchRow],
) -> std::result::Result<(), String>
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(|e| e.to_string())?;
    let (t0, t1) = pts.iter().fold((f64::INFINITY, 0f64), |(a, b), r| (a.min(r.seconds), b.max(r.seconds)));
    let (p0, p1) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| (a.min(r.psnr_db), b.max(r.psnr_db.min(120.0))));
    let title = match series {
        "method" => "Speed against error: perceived image (Near) vs high-sample reference",
        "la_grid" => "LensletAverage k x k grid: display image vs k = 16",
        "pupil_grid" => "Pupil n x n grid: perceived LC image (Near) vs n = 32",
        _ => "Samples per retina pixel: ground truth (Near) vs 16 x 16",
    };
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d((t0 * 0.8..t1 * 1.25).log_scale(), (p0 - 1.0)..(p1 + 1.0))
        .map_err(|e| e.to_string())?;
    chart.configure_mesh().x_desc("wall time (s, log)").y_desc("PSNR (dB)").draw().map_err(|e| e.to_string())?;
    let mut groups: Vec<(String, Vec<&BenchRow>)> = Vec::new();
    for r in pts {
        let key = format!("{} {}", r.method, r.backend);
        match groups.iter_mut().find(|g| g.0 == key) {
            Some(g) => g.1.push(r),
            None => groups.push((key, vec![r])),
        }
    }
    for (i, (key, g)) in groups.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let line: Vec<(f64, f64)> = g.iter().map(|r| (r.seconds, r.psnr_db.min(120.0))).collect();
        chart
            .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(key.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(line.iter().map(|p| Circle::new(*p, 4, color.filled()))).map_err(|e| e.to_string())?;
        for r in g {
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{}", r.parameter),
                    (r.seconds, r.psnr_db.min(120.0) + 0.3),
                    ("sans-serif", 12),
                )))
                .map_err(|e| e.to_string())?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    area.present().map_err(|e| e.to_string())
}
