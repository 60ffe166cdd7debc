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
use crate::error::{Error, Result};
use crate::io::exr::{Attributes, ExrCompression};
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

/// Runs an experiment and writes every output into `out`.
pub fn assess(exp: &Experiment, out: &Path, opts: RunOptions) -> Result<AssessReport> {
    let start = Instant::now();
    prepare_output_dir(out)?;
    // The paper's kind of scene: the fused planar kernel, called directly (no virtual call per
    // ray) for both images and depths. Everything else: the backend chosen by `with_fields`.
    if resolve(&exp.scene, opts.backend) == BackendChoice::Analytic && exp.scene.is_analytic() {
        let backend = AnalyticRects::new(&exp.scene)?;
        if let Some(fast) = FacingPlanes::new(&exp.scene, &backend) {
            return assess_with(exp, out, opts, &fast, &fast, "analytic (fused planar kernel)", start);
        }
    }
    with_fields(&exp.scene, opts.backend, |fields| {
        assess_with(exp, out, opts, fields.shade, fields.with_depth, fields.name, start)
    })
}

/// Creates the output directory and checks it can be written, before any long computation.
pub fn prepare_output_dir(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let probe = out.join(".inimtrace-write-test");
    std::fs::write(&probe, b"").map_err(|e| Error::io(out, e))?;
    let _ = std::fs::remove_file(&probe);
    // An interrupted earlier run must not look complete: the report is written last.
    let _ = std::fs::remove_file(out.join("results.json"));
    Ok(())
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
    out: &Path,
    opts: RunOptions,
    shade: &S,
    with_depth: &D,
    backend_name: &str,
    start: Instant,
) -> Result<AssessReport> {
    let mut stages = Vec::new();
    let display = &exp.display;

    // 1-3. Display images, then per eye case the ground truth and the perceived image of every
    // method, then the scores: the same stage functions `inimtrace bench` times.
    let (displays, depths) = render_display_images(exp, with_depth, opts.quiet, &mut stages)?;
    let stack = pack_display_images(exp, &displays.iter().collect::<Vec<_>>(), &mut stages)?;
    let (gts, sims, scores) = table1(exp, shade, &stack, opts.quiet, &mut stages)?;
    drop(stack);

    // 4. Images: EXR + PNG preview each, written in parallel.
    let t = Instant::now();
    let mut jobs = Vec::new();
    let name = Some(exp.name.as_str());
    for ((m, img), depth) in exp.methods.iter().zip(&displays).zip(&depths) {
        let mut attributes = metadata::common("display image", name);
        attributes.extend(metadata::display_image(*m, display, &exp.render, backend_name, depth.is_some()));
        jobs.push(Job { stem: format!("display_{}", m.short_name()), image: img, depth: depth.as_deref(), attributes });
    }
    for (c, case) in exp.cases.iter().enumerate() {
        // Samples per retina pixel when the eye case was measured converged.
        let converged = scores.iter().find(|s| s.eye_case == case.name).and_then(|s| s.samples_per_pixel);
        let measured = |mut a: crate::io::exr::Attributes| {
            if let Some(spp) = converged {
                crate::measure::run::set_exr_attributes(&mut a, exp, spp);
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
    let figure = figure(exp, &gts, &sims, &scores);
    let (image_result, figure_result) = rayon::join(
        || {
            jobs.par_iter().try_for_each(|j| -> Result<()> {
                let path = out.join(format!("{}.exr", j.stem));
                crate::io::exr::write_rgb_with(&path, j.image, j.depth, &j.attributes, opts.exr_compression)?;
                crate::io::png::write_preview(&out.join(format!("{}.png", j.stem)), j.image)
            })
        },
        || crate::io::figure::write_figure(&out.join("figure.png"), &figure),
    );
    image_result?;
    figure_result?;
    stage_time(&mut stages, "write_images", None, None, t);

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
    write_reports(&report, exp, out)?;
    Ok(report)
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
