//! `assess`: runs one experiment (Sec. 4) through the stages and writes every output: the
//! display, ground-truth and perceived images as EXR + PNG preview, the Fig. 3 montage, and the
//! reports.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use super::report::write_reports;
use super::stages::{pack_display_images, render_display_images, stage_time, table1};
use super::{AssessReport, Experiment, EyeCase};
use crate::accel::analytic::AnalyticRects;
use crate::error::{Error, Result};
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
    attributes: Vec<(&'static str, String)>,
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
    let common = |kind: &str| -> Vec<(&'static str, String)> {
        vec![
            ("inimtrace:kind", kind.to_string()),
            ("inimtrace:experiment", exp.name.clone()),
            ("inimtrace:units", "linear radiance (albedo units); lengths in mm".into()),
            ("inimtrace:version", env!("CARGO_PKG_VERSION").into()),
        ]
    };
    let eye_attrs = |case: &EyeCase| -> Vec<(&'static str, String)> {
        let mut v = vec![("inimtrace:eye_case", case.name.clone())];
        match case.eye.aperture {
            Aperture::Pinhole => v.push(("inimtrace:eye", "pinhole".into())),
            Aperture::ThinLens { pupil_diameter, focus } => {
                v.push(("inimtrace:eye", "thin lens".into()));
                v.push(("inimtrace:focus_mm", format!("{}", focus.distance_mm())));
                v.push(("inimtrace:focus_diopters", format!("{}", focus.diopters())));
                v.push(("inimtrace:pupil_diameter_mm", format!("{pupil_diameter}")));
            }
        }
        match scores.iter().find(|s| s.eye_case == case.name).and_then(|s| s.samples_per_pixel) {
            Some(spp) => v.extend(crate::measure::run::exr_attributes(exp, spp)),
            None => {
                v.push(("inimtrace:pupil_samples", case.eye.pupil_samples().len().to_string()));
                v.push(("inimtrace:retina_samples_per_pixel", (exp.retina.samples_per_pixel.pow(2)).to_string()));
            }
        }
        v.push(("inimtrace:retina_half_tangent", exp.retina.half_tangent.to_string()));
        v
    };
    for ((m, img), depth) in exp.methods.iter().zip(&displays).zip(&depths) {
        let mut attributes = common("display image");
        attributes.push(("inimtrace:method", m.to_string()));
        attributes.push(("inimtrace:display", display.summary()));
        attributes.push(("inimtrace:samples_per_pixel", exp.render.samples_per_pixel.pow(2).to_string()));
        attributes.push(("inimtrace:backend", backend_name.to_string()));
        if depth.is_some() {
            attributes.push(("inimtrace:Z", Z_CHANNEL_NOTE.into()));
        }
        jobs.push(Job { stem: format!("display_{}", m.short_name()), image: img, depth: depth.as_deref(), attributes });
    }
    for (c, case) in exp.cases.iter().enumerate() {
        let mut attributes = common("ground truth retinal image");
        attributes.extend(eye_attrs(case));
        jobs.push(Job { stem: format!("gt_{}", case.name), image: &gts[c], depth: None, attributes });
        for (k, m) in exp.methods.iter().enumerate() {
            let mut attributes = common("simulated retinal image");
            attributes.push(("inimtrace:method", m.to_string()));
            attributes.extend(eye_attrs(case));
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
    let figure_rows: Vec<(&str, Vec<&RgbImage>)> = exp
        .cases
        .iter()
        .enumerate()
        .map(|(c, case)| (case.name.as_str(), std::iter::once(&gts[c]).chain(sims[c].iter()).collect()))
        .collect();
    let mut labels = vec!["GT"];
    labels.extend(exp.methods.iter().map(|m| m.short_name()));
    let (image_result, figure_result) = rayon::join(
        || {
            jobs.par_iter().try_for_each(|j| -> Result<()> {
                let attrs: Vec<(&str, String)> = j.attributes.iter().map(|(k, v)| (*k, v.clone())).collect();
                crate::io::exr::write_rgb(&out.join(format!("{}.exr", j.stem)), j.image, j.depth, &attrs)?;
                crate::io::png::write_preview(&out.join(format!("{}.png", j.stem)), j.image)
            })
        },
        || crate::io::figure::write_montage(&out.join("figure.png"), &figure_rows, &labels),
    );
    image_result?;
    figure_result?;
    stage_time(&mut stages, "write_images", None, None, t);

    let report = AssessReport {
        experiment: exp.name.clone(),
        ssim_constants: exp.ssim.name().into(),
        backend: backend_name.into(),
        threads: rayon::current_num_threads(),
        display: display.summary(),
        central_depth_plane_mm: display.central_depth_plane(),
        scores,
        stages,
        total_seconds: start.elapsed().as_secs_f64(),
        settings: exp.spec.clone(),
    };
    write_reports(&report, exp, out)?;
    Ok(report)
}
