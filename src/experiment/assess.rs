//! `assess`: runs one experiment (Sec. 4) through the stages and writes every output: the
//! display, ground-truth and perceived images as EXR + PNG preview, the Fig. 3 montage, and the
//! reports.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use super::metadata;
use super::report::write_reports;
use super::stages::{pack_display_images, render_display_images, stage_time, table1};
use super::{AssessReport, Experiment};
use crate::accel::analytic::AnalyticRects;
use crate::budget::Estimate;
use crate::error::Result;
use crate::io::exr::{Attributes, ExrCompression};
use crate::io::output::OutputDir;
use crate::optics::Aperture;
use crate::raster::RgbImage;
use crate::render::backend::resolve;
use crate::render::{with_fields, BackendChoice, FacingPlanes, RadianceField};

/// What the display EXRs' `Z` channel holds (also written into their headers).
pub const Z_CHANNEL_NOTE: &str = "hit distance in mm along each camera ray from its start on the reference plane; \
     mean over the pixel's rays that hit (LA, multi-sample), +inf where none hit";

/// Options of a run.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunOptions {
    pub quiet: bool,
    /// Scene intersection backend (`auto`: analytic for rectangle-only scenes, else Embree).
    pub backend: BackendChoice,
    /// Compression of the EXR files (default lossless ZIP).
    pub exr_compression: ExrCompression,
}

/// Everything an assessment computed: its report and its images, in the experiment's order.
pub struct Assessment {
    pub report: AssessReport,
    /// The display image of every method.
    pub displays: Vec<RgbImage>,
    /// The depth plane of every display image (`None` where the backend knows no depths).
    pub depths: Vec<Option<Vec<f32>>>,
    /// The ground truth of every eye case.
    pub ground_truths: Vec<RgbImage>,
    /// `perceived[case][method]`: what each eye case perceives of each display image.
    pub perceived: Vec<Vec<RgbImage>>,
}

/// Runs an experiment and writes every output into `out`.
pub fn assess(exp: &Experiment, out: &Path, opts: RunOptions) -> Result<AssessReport> {
    assess_images(exp, Some(out), opts).map(|a| a.report)
}

/// Runs an experiment and returns its report and images; with `out`, also writes every output
/// there exactly as [`assess`] does (the same code path: the images and scores are the same bit
/// for bit).
pub fn assess_images(exp: &Experiment, out: Option<&Path>, opts: RunOptions) -> Result<Assessment> {
    let start = Instant::now();
    // Refuse settings that cannot fit in memory before anything is allocated; say so when the
    // run will be long, even when stderr is not a terminal.
    let estimate = estimate(exp);
    estimate.check_memory(crate::budget::memory_limit(), &exp.source)?;
    let seconds = estimate.seconds(RAYS_PER_SECOND * rayon::current_num_threads() as f64);
    if seconds > 60.0 {
        eprintln!(
            "note: this run traces about {:.2e} rays: roughly {} on this machine",
            estimate.rays as f64,
            if seconds < 3600.0 {
                format!("{:.0} minutes", seconds / 60.0)
            } else {
                format!("{:.1} hours", seconds / 3600.0)
            }
        );
    }
    // The folder is owned by this run (a second run into it fails at once) and every file
    // appears under its final name only when complete; `results.json` comes last.
    let dir = out.map(OutputDir::open).transpose()?;
    let dir = dir.as_ref();
    // The paper's kind of scene: the fused planar kernel, called directly (no virtual call per
    // ray) for both images and depths. Everything else: the backend chosen by `with_fields`.
    if resolve(&exp.scene, opts.backend) == BackendChoice::Analytic && exp.scene.is_analytic() {
        let backend = AnalyticRects::new(&exp.scene)?;
        if let Some(fast) = FacingPlanes::new(&exp.scene, &backend) {
            return assess_with(exp, dir, opts, &fast, &fast, "analytic (fused planar kernel)", start);
        }
    }
    with_fields(&exp.scene, opts.backend, |fields| {
        assess_with(exp, dir, opts, fields.shade, fields.with_depth, fields.name, start)
    })
}

/// Creates the output directory and checks it can be written, before any long computation
/// (and removes what an earlier run left there; see [`OutputDir::open`]).
pub fn prepare_output_dir(out: &Path) -> Result<()> {
    OutputDir::open(out).map(|_| ())
}

/// Rays per second per thread assumed by the announcement of long runs (a conservative figure
/// for the generic tracers; the fused planar kernel is faster).
const RAYS_PER_SECOND: f64 = 10e6;

/// The run's peak memory and its rays, from the settings alone (before anything is allocated).
pub fn estimate(exp: &Experiment) -> Estimate {
    let mut e = Estimate::default();
    let lcd = exp.display.lcd.pixel_count() as u64;
    let methods = exp.methods.len() as u64;
    let lcd_setting = format!("lcd.resolution = {:?} of display `{}`", exp.display.lcd.resolution, exp.spec.display);
    // Display images (RGB f32 + depth), and their interleaved copy for the simulation.
    e.add("the display images and their depth planes", lcd_setting.clone(), lcd * methods, 16);
    e.add("the display images packed for the simulation", lcd_setting, lcd * methods, 12);
    let n = exp.retina.resolution as u64;
    let cases = exp.cases.len() as u64;
    let retina_setting = format!("eye.retina_resolution = {n}");
    e.add("the retinal images", retina_setting.clone(), n * n * cases * (1 + methods), 12);
    let spp = (exp.render.samples_per_pixel as u64).pow(2);
    for m in &exp.methods {
        let per_pixel = match m {
            crate::render::Method::LensletAverage { grid } => (*grid as u64).pow(2),
            _ => 1,
        };
        e.add_rays(lcd.saturating_mul(spp).saturating_mul(per_pixel));
    }
    if exp.measurement.estimator == crate::measure::spec::EstimatorKind::Converged {
        let r = exp.measurement.replicates as u64;
        e.add("the converged estimator's replicates", retina_setting, n * n * r * (1 + methods), 12);
        e.add_rays(n * n * cases * exp.measurement.max_samples_per_pixel.min(256) * (1 + methods));
    } else {
        let per_pixel = (exp.retina.samples_per_pixel as u64).pow(2);
        for case in &exp.cases {
            e.add_rays(n * n * per_pixel * case.eye.pupil_samples().len() as u64 * (1 + methods));
        }
    }
    e
}

struct Job<'a> {
    stem: String,
    image: &'a RgbImage,
    depth: Option<&'a [f32]>,
    attributes: Attributes,
}

#[allow(clippy::too_many_arguments)]
fn assess_with<S: RadianceField + ?Sized, D: RadianceField + ?Sized>(
    exp: &Experiment,
    dir: Option<&OutputDir>,
    opts: RunOptions,
    shade: &S,
    with_depth: &D,
    backend_name: &str,
    start: Instant,
) -> Result<Assessment> {
    let mut stages = Vec::new();
    let display = &exp.display;

    // 1-3. Display images, then per eye case the ground truth and the perceived image of every
    // method, then the scores: the same stage functions `inimtrace bench` times.
    let (displays, depths) = render_display_images(exp, with_depth, opts.quiet, &mut stages)?;
    let stack = pack_display_images(exp, &displays.iter().collect::<Vec<_>>(), &mut stages)?;
    let (gts, sims, scores) = table1(exp, shade, &stack, opts.quiet, &mut stages)?;
    drop(stack);

    // 4. Images: EXR + PNG preview each, written in parallel.
    if let Some(dir) = dir {
        let t_images = Instant::now();
        write_images(exp, dir, opts, backend_name, (&displays, &depths), &gts, &sims, &scores)?;
        stage_time(&mut stages, "write_images", None, None, t_images);
    }

    let report = AssessReport {
        tool: crate::version::TOOL,
        experiment: exp.name.clone(),
        ssim_constants: exp.ssim.name().into(),
        backend: backend_name.into(),
        threads: rayon::current_num_threads(),
        display: display.into(),
        central_depth_plane_mm: display.central_depth_plane(),
        scores,
        stages,
        total_seconds: start.elapsed().as_secs_f64(),
        settings: exp.spec.clone(),
    };
    if let Some(dir) = dir {
        write_reports(&report, exp, dir)?;
    }
    Ok(Assessment { report, displays, depths, ground_truths: gts, perceived: sims })
}

/// Writes every image of a run into `dir` (EXR + PNG preview each, in parallel) and the figure.
#[allow(clippy::too_many_arguments)]
fn write_images(
    exp: &Experiment,
    dir: &OutputDir,
    opts: RunOptions,
    backend_name: &str,
    (displays, depths): (&[RgbImage], &[Option<Vec<f32>>]),
    gts: &[RgbImage],
    sims: &[Vec<RgbImage>],
    scores: &[super::Score],
) -> Result<()> {
    let display = &exp.display;
    let mut jobs = Vec::new();
    let name = Some(exp.name.as_str());
    for ((m, img), depth) in exp.methods.iter().zip(displays).zip(depths) {
        let mut attributes = metadata::common("display image", name);
        attributes.extend(metadata::display_image(*m, display, &exp.render, backend_name, depth.is_some()));
        jobs.push(Job { stem: format!("display_{}", m.short_name()), image: img, depth: depth.as_deref(), attributes });
    }
    for (c, case) in exp.cases.iter().enumerate() {
        // Samples per retina pixel when the eye case was measured converged.
        let converged = scores.iter().find(|s| s.eye_case == case.name).and_then(|s| s.samples_per_pixel);
        let measured = |mut a: crate::io::exr::Attributes| {
            if let Some(spp) = converged {
                crate::experiment::converged::set_exr_attributes(&mut a, exp, spp);
            }
            a
        };
        let attributes = measured(metadata::ground_truth(name, Some(&case.name), &case.eye, &exp.retina, backend_name));
        jobs.push(Job { stem: format!("gt_{}", case.name), image: &gts[c], depth: None, attributes });
        for (k, m) in exp.methods.iter().enumerate() {
            let attributes =
                measured(metadata::perceived(name, Some(*m), Some(&case.name), &case.eye, &exp.retina, display, None));
            jobs.push(Job {
                stem: format!("sim_{}_{}", m.short_name(), case.name),
                image: &sims[c][k],
                depth: None,
                attributes,
            });
        }
    }
    // Biggest first so the two cores finish together.
    jobs.sort_by_key(|j| std::cmp::Reverse(j.image.pixels.len()));
    let figure = figure(exp, gts, sims, scores);
    let (image_result, figure_result) = rayon::join(
        || {
            jobs.par_iter().try_for_each(|j| -> Result<()> {
                dir.write_with(&format!("{}.exr", j.stem), |p| {
                    crate::io::exr::write_rgb_with(p, j.image, j.depth, &j.attributes, opts.exr_compression)
                })?;
                dir.write_with(&format!("{}.png", j.stem), |p| crate::io::png::write_preview(p, j.image))
            })
        },
        || dir.write_with("figure.png", |p| crate::io::figure::write_figure(p, &figure)),
    );
    image_result?;
    figure_result
}

/// Fig. 3 as `assess` draws it: a title, one row per eye case labelled with its focus, and each
/// perceived image captioned with its PSNR and SSIM against the ground truth.
fn figure<'a>(
    exp: &Experiment,
    gts: &'a [RgbImage],
    sims: &'a [Vec<RgbImage>],
    scores: &[super::Score],
) -> crate::io::figure::Figure<'a> {
    let mut column_labels = vec!["GT".to_string()];
    column_labels.extend(exp.methods.iter().map(|m| m.short_name().to_string()));
    let rows = exp
        .cases
        .iter()
        .enumerate()
        .map(|(c, case)| {
            let label = match case.eye.aperture {
                Aperture::Pinhole => format!("{}: pinhole", case.name),
                Aperture::ThinLens { focus, .. } => {
                    format!("{}: focus {:.0} mm ({:.2} D)", case.name, focus.distance_mm(), focus.diopters())
                }
            };
            let mut cells = vec![(&gts[c], None)];
            for (k, m) in exp.methods.iter().enumerate() {
                let caption = scores
                    .iter()
                    .find(|s| s.method == m.short_name() && s.eye_case == case.name)
                    .map(|s| format!("PSNR {} dB, SSIM {:.3}", crate::metrics::format_db(s.psnr.mean, 2), s.ssim.mean));
                cells.push((&sims[c][k], caption));
            }
            (label, cells)
        })
        .collect();
    crate::io::figure::Figure {
        title: Some(format!(
            "{}: perceived retinal images; PSNR and SSIM ({}) against the ground truth (GT)",
            exp.name,
            exp.ssim.name()
        )),
        column_labels,
        rows,
    }
}
