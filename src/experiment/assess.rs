//! `assess`: runs one experiment (Sec. 4) through the stages and writes every output: the
//! display, ground-truth and perceived images as EXR + PNG preview, the Fig. 3 montage, and the
//! reports.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use super::metadata;
use super::report::write_reports;
use super::stages::{render_display_stack, stage_time, table1_each};
use super::{AssessReport, Experiment};
use crate::budget::Estimate;
use crate::error::Result;
use crate::io::exr::{Attributes, ExrCompression};
use crate::io::output::{OutputDir, RunKind};
use crate::optics::Aperture;
use crate::progress::with_installed;
use crate::raster::RgbImage;
use crate::render::{with_scene_fields, BackendChoice, FieldUser, RadianceField};

/// What the display EXRs' `Z` channel holds (also written into their headers).
pub const Z_CHANNEL_NOTE: &str = "hit distance in mm along each camera ray from its start on the reference plane; \
     mean over the pixel's rays that hit (LA, multi-sample), +inf where none hit";

/// Options of a run.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunOptions {
    /// No progress bars or notes on stderr.
    pub quiet: bool,
    /// Scene intersection backend (`auto`: analytic for rectangle-only scenes, else Embree).
    pub backend: BackendChoice,
    /// Compression of the EXR files (default lossless ZIP).
    pub exr_compression: ExrCompression,
    /// Replace another command's results in the output folder (`--force`; see
    /// [`crate::io::output`]).
    pub force: bool,
    /// Also write each converged image's replicates (`*.replicates.exr`, see
    /// [`crate::io::exr_replicates`]), from which `compare` recomputes the table's scores.
    pub keep_replicates: bool,
}

/// Everything an assessment computed: its report and its images, in the experiment's order.
pub struct Assessment {
    /// Table 1, stage times and the settings, as `results.json` holds them.
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

/// Runs an experiment and writes every output into `out`. Each image is written as soon as it
/// is made and then dropped, so the run holds the display images once (in the simulation's
/// stack) and one eye case's retinal images at a time.
pub fn assess(exp: &Experiment, out: &Path, opts: RunOptions) -> Result<AssessReport> {
    run(exp, Some(out), opts, false).map(|a| a.report)
}

/// Runs an experiment and returns its report and images; with `out`, also writes every output
/// there exactly as [`assess`] does (the same code path: the images and scores are the same bit
/// for bit). Keeping the images costs one more copy of the display images.
pub fn assess_images(exp: &Experiment, out: Option<&Path>, opts: RunOptions) -> Result<Assessment> {
    run(exp, out, opts, true)
}

fn run(exp: &Experiment, out: Option<&Path>, opts: RunOptions, keep: bool) -> Result<Assessment> {
    let start = Instant::now();
    // Refuse settings that cannot fit in memory before anything is allocated; say so when the
    // run will be long, even when stderr is not a terminal.
    let estimate = check(exp)?;
    crate::long_run::announce(estimate.rays);
    // The folder is owned by this run (a second run into it fails at once) and every file
    // appears under its final name only when complete; `results.json` comes last.
    let dir = out.map(|o| OutputDir::open(o, RunKind::Assess, opts.force)).transpose()?;
    let dir = dir.as_ref();
    // The fields `with_scene_fields` chooses (the paper's kind of scene: the fused planar
    // kernel), called with their concrete types: no virtual call per ray.
    struct Assess<'a> {
        exp: &'a Experiment,
        dir: Option<&'a OutputDir>,
        opts: RunOptions,
        keep: bool,
        start: Instant,
    }
    impl FieldUser for Assess<'_> {
        type Output = Assessment;
        fn run<S: RadianceField, D: RadianceField>(
            self,
            shade: &S,
            with_depth: &D,
            name: &'static str,
        ) -> Result<Assessment> {
            assess_with(self.exp, self.dir, self.opts, self.keep, shade, with_depth, name, self.start)
        }
    }
    with_scene_fields(&exp.scene, opts.backend, Assess { exp, dir, opts, keep, start })
}

/// Creates the output directory and checks it can be written, before any long computation
/// (and removes what an earlier run left there; see [`OutputDir::open`]).
pub fn prepare_output_dir(out: &Path, force: bool) -> Result<()> {
    OutputDir::open(out, RunKind::Assess, force).map(|_| ())
}

/// The run's estimate ([`estimate`]), refused when its memory exceeds the budget: what a run
/// checks before it allocates anything.
pub fn check(exp: &Experiment) -> Result<Estimate> {
    let e = estimate(exp);
    e.check_memory(&crate::budget::memory_budget(), &exp.source)?;
    Ok(e)
}

/// `assess --check`: the experiment checked ([`check`]) and one line saying what would run.
pub fn check_text(exp: &Experiment) -> Result<String> {
    let e = check(exp)?;
    Ok(format!(
        "{}: valid; {} x {}, about {} of memory and {:.2e} rays (nothing run)",
        exp.source,
        crate::count::count(exp.methods.len(), "method"),
        crate::count::count(exp.cases.len(), "eye case"),
        crate::budget::Bytes(e.bytes()),
        e.rays as f64
    ))
}

/// The run's peak memory and its rays, from the settings alone (before anything is allocated).
pub fn estimate(exp: &Experiment) -> Estimate {
    let mut e = Estimate::default();
    let lcd = exp.display.lcd.pixel_count() as u64;
    let methods = exp.methods.len() as u64;
    let lcd_setting = format!("lcd.resolution = {:?} of display `{}`", exp.display.lcd.resolution, exp.spec.display);
    // The display image being rendered and written, its depth plane, and the stack the
    // simulation reads (at most dense: palette indices take far less when the images allow).
    e.add("the display images packed for the simulation", lcd_setting.clone(), lcd * methods, 12);
    e.add("the display image being rendered", lcd_setting.clone(), lcd, 12);
    e.add("a display image's depth plane", lcd_setting, lcd, 4);
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
    if let Some(opt) = &exp.optimize {
        opt.add_to_estimate(&mut e, lcd);
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
    attributes: Attributes,
}

#[allow(clippy::too_many_arguments)]
fn assess_with<S: RadianceField + ?Sized, D: RadianceField + ?Sized>(
    exp: &Experiment,
    dir: Option<&OutputDir>,
    opts: RunOptions,
    keep: bool,
    shade: &S,
    with_depth: &D,
    backend_name: &str,
    start: Instant,
) -> Result<Assessment> {
    let mut stages = Vec::new();
    let display = &exp.display;
    let name = Some(exp.name.as_str());
    // What `assess_images` hands back (nothing for `assess`).
    let (mut displays, mut depths, mut ground_truths, mut perceived) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());

    // 1. Display images, each rendered into the stack the simulation reads and written at once
    // (EXR + PNG preview), so it is held once and its depth plane only while it is written: the
    // same stage functions `inimtrace bench` times.
    let (stack, optimization) = render_display_stack(exp, with_depth, opts.quiet, &mut stages, |k, image, depth| {
        if keep {
            displays.push(image.to_image());
            depths.push(depth.map(<[f32]>::to_vec));
        }
        let Some(dir) = dir else { return Ok(()) };
        let m = exp.methods[k];
        let mut attributes = metadata::common("display image", name);
        attributes.extend(metadata::display_image(m, display, &exp.render, backend_name, depth.is_some()));
        attributes.extend(metadata::provenance(&exp.provenance));
        let stem = format!("display_{}", m.name());
        // The writes run on rayon's workers: they carry the progress sink, which may cancel them.
        let sink = crate::progress::installed();
        let (exr, png) = rayon::join(
            || {
                with_installed(sink.clone(), || {
                    dir.write_with(&format!("{stem}.exr"), |p| {
                        crate::io::exr::write_view(p, image, depth, &attributes, opts.exr_compression)
                    })
                })
            },
            || {
                with_installed(sink.clone(), || {
                    dir.write_with(&format!("{stem}.png"), |p| crate::io::png::write_preview_view(p, image))
                })
            },
        );
        exr?;
        png
    })?;

    // 2-3. Per eye case the ground truth, the perceived image of every method and the scores;
    // its retinal images are written (EXR + PNG preview each, in parallel) as soon as it is
    // measured, and only their figure cells are kept.
    if let (Some(dir), Some(o)) = (dir, &optimization) {
        let stem = format!("optimize_{}", o.method);
        dir.write_bytes(&format!("{stem}.csv"), o.csv().as_bytes())?;
        dir.write_with(&format!("{stem}.png"), |p| o.write_plot(p))?;
    }
    let mut cells: Vec<Vec<RgbImage>> = Vec::new();
    let mut scores = Vec::new();
    let mut write_seconds = Vec::new();
    table1_each(exp, shade, &stack, opts.quiet, opts.keep_replicates, &mut stages, |c, result| {
        if let Some(dir) = dir {
            let t = Instant::now();
            write_case(exp, dir, opts, backend_name, c, &result)?;
            let images = std::iter::once(&result.ground_truth).chain(&result.perceived).collect::<Vec<_>>();
            cells.push(images.par_iter().map(|img| crate::io::figure::cell_image(img)).collect());
            write_seconds.push((exp.cases[c].name.clone(), t.elapsed().as_secs_f64()));
        }
        scores.extend(result.scores);
        if keep {
            ground_truths.push(result.ground_truth);
            perceived.push(result.perceived);
        }
        Ok(())
    })?;
    drop(stack);
    for (case, seconds) in write_seconds {
        stages.push(super::StageTime { stage: "write_images".into(), method: None, eye_case: Some(case), seconds });
    }

    // 4. Fig. 3 from the cells.
    if let Some(dir) = dir {
        let t = Instant::now();
        let figure = figure(exp, &cells, &scores);
        dir.write_with("figure.png", |p| crate::io::figure::write_figure(p, &figure))?;
        stage_time(&mut stages, "write_figure", None, None, t);
    }

    let report = AssessReport {
        tool: crate::version::TOOL,
        experiment: exp.name.clone(),
        ssim_constants: exp.ssim.name().into(),
        backend: backend_name.into(),
        threads: rayon::current_num_threads(),
        display: super::simulated::DisplayReport::of(
            display,
            exp.spec.optics.as_ref().map(|o| o.diffraction).unwrap_or_default(),
        ),
        simulated: super::simulated::Simulated::of(exp),
        central_depth_plane_mm: display.central_depth_plane(),
        eyes: super::report::EyeReport::of(exp),
        pupil: exp.auto_pupil,
        scores,
        stages,
        total_seconds: start.elapsed().as_secs_f64(),
        settings: exp.spec.clone(),
        optimization,
        provenance: exp.provenance.clone(),
    };
    if let Some(dir) = dir {
        write_reports(&report, exp, dir)?;
        // The page, from the files just written (results.json included), outside its manifest.
        crate::report::write(dir.path())?;
    }
    Ok(Assessment { report, displays, depths, ground_truths, perceived })
}

/// Writes the retinal images of eye case `c` (EXR + PNG preview each, in parallel).
fn write_case(
    exp: &Experiment,
    dir: &OutputDir,
    opts: RunOptions,
    backend_name: &str,
    c: usize,
    result: &super::CaseResult,
) -> Result<()> {
    let case = &exp.cases[c];
    let name = Some(exp.name.as_str());
    // Samples per retina pixel when the eye case was measured converged.
    let converged = result.scores.first().and_then(|s| s.samples_per_pixel);
    let measured = |mut a: crate::io::exr::Attributes| {
        if let Some(spp) = converged {
            crate::experiment::converged::set_exr_attributes(&mut a, exp, spp);
        }
        a.extend(metadata::provenance(&exp.provenance));
        a
    };
    let mut jobs = Vec::new();
    let attributes = measured(metadata::ground_truth(name, Some(&case.name), &case.eye, &exp.retina, backend_name));
    jobs.push(Job { stem: format!("gt_{}", case.name), image: &result.ground_truth, attributes });
    for (m, image) in exp.methods.iter().zip(&result.perceived) {
        let attributes =
            measured(metadata::perceived(name, Some(*m), Some(&case.name), &case.eye, &exp.retina, &exp.display, None));
        jobs.push(Job { stem: format!("sim_{}_{}", m.name(), case.name), image, attributes });
    }
    // The writes run on rayon's workers: they carry the progress sink, which may cancel them.
    let sink = crate::progress::installed();
    jobs.par_iter().enumerate().try_for_each(|(k, j)| -> Result<()> {
        with_installed(sink.clone(), || {
            dir.write_with(&format!("{}.exr", j.stem), |p| {
                crate::io::exr::write_rgb_with(p, j.image, None, &j.attributes, opts.exr_compression)
            })?;
            if let Some(reps) = &result.replicates {
                let mut a = j.attributes.clone();
                a.0.retain(|(name, _)| name != "inimtrace:value");
                a.set("inimtrace:value", "one replicate's mean (the image is their mean)");
                dir.write_with(&format!("{}.replicates.exr", j.stem), |p| {
                    crate::io::exr_replicates::write(p, reps, k, &a, opts.exr_compression)
                })?;
            }
            dir.write_with(&format!("{}.png", j.stem), |p| crate::io::png::write_preview(p, j.image))
        })
    })?;
    write_maps(exp, dir, opts, c, result)
}

/// The distortion maps of eye case `c`'s perceptual scores, one per score and method
/// (`map_<score>_<method>_<case>.exr` with the values, `.png` a heatmap); none unless
/// `[measurement] scores` names `cvvdp` or `flip`.
fn write_maps(exp: &Experiment, dir: &OutputDir, opts: RunOptions, c: usize, result: &super::CaseResult) -> Result<()> {
    if !exp.extra_scores.any_perceptual() {
        return Ok(());
    }
    let Some(p) = super::perceptual::for_case(exp, c)? else { return Ok(()) };
    let case = &exp.cases[c];
    for (m, sim) in exp.methods.iter().zip(&result.perceived) {
        for map in p.maps(sim, &result.ground_truth)? {
            let stem = format!("map_{}_{}_{}", map.score, m.name(), case.name);
            let mut a = metadata::common("distortion map", Some(exp.name.as_str()));
            a.0.retain(|(k, _)| k != "inimtrace:units");
            let what = match map.score {
                crate::perception::ScoreName::Cvvdp => "ColorVideoVDP: 1 - JOD_pixel / 10 (0: no visible difference)",
                _ => "HDR-FLIP error per pixel (0: none, 1: largest)",
            };
            a.set("inimtrace:units", what)
                .set("inimtrace:method", m.name())
                .set("inimtrace:eye_case", case.name.as_str());
            a.extend(metadata::provenance(&exp.provenance));
            let (w, h) = map.size;
            dir.write_with(&format!("{stem}.exr"), |path| {
                crate::io::exr_map::write_map_exr(path, w, h, &map.values, &a, opts.exr_compression)
            })?;
            dir.write_with(&format!("{stem}.png"), |path| crate::io::exr_map::write_map_png(path, w, h, &map.values))?;
        }
    }
    Ok(())
}

/// Fig. 3 as `assess` draws it: a title, one row per eye case labelled with its focus, and each
/// perceived image captioned with its PSNR and SSIM against the ground truth.
/// `cells[case]` holds the figure cells ([`crate::io::figure::cell_image`]) of the ground truth,
/// then of each method's perceived image.
fn figure<'a>(exp: &Experiment, cells: &'a [Vec<RgbImage>], scores: &[super::Score]) -> crate::io::figure::Figure<'a> {
    let mut column_labels = vec!["GT".to_string()];
    column_labels.extend(exp.methods.iter().map(|m| m.name()));
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
            let label = match case.eye.optics.as_ref().and_then(|o| Some((o.model.name(), o.accommodation?))) {
                Some((model, a)) => format!("{label}, {model} A {a:.2} D"),
                None => label,
            };
            let mut row = vec![(&cells[c][0], None)];
            for (k, m) in exp.methods.iter().enumerate() {
                let caption = scores.iter().find(|s| s.method == m.name() && s.eye_case == case.name).map(|s| {
                    let mut c =
                        format!("PSNR {} dB, SSIM {:.3}", crate::metrics::format_db(s.psnr.mean, 2), s.ssim.mean);
                    c.push_str(&super::perceptual::caption(s));
                    c
                });
                row.push((&cells[c][k + 1], caption));
            }
            (label, row)
        })
        .collect();
    crate::io::figure::Figure {
        title: Some(format!(
            "{} ({}): perceived retinal images; PSNR and SSIM ({}) against the ground truth (GT)",
            exp.name,
            super::simulated::Simulated::of(exp).figure_part(),
            exp.ssim.name()
        )),
        column_labels,
        rows,
    }
}
