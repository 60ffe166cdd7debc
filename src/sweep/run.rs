//! Running sweep points on this machine: the paper's stages (Sec. 4: display image, ground
//! truth, perceived image, scores) for every point not yet recorded, on all cores. Points that
//! render the same display image (same scene, display, method and display-render settings; for
//! PupilCenter also the same eye position, for OPT also the same `[optimize]` training states and
//! solver) share it: it is rendered once, and the points that
//! use it run in parallel on it. Each point is recorded atomically as soon as it is done.

use std::collections::{HashMap, HashSet};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::store::{host_name, unix_now, PointRecord, ScoreRow, Store};
use crate::error::Result;
use crate::experiment::{self, Experiment, Score};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::retina::DisplayStack;
use crate::render::{with_scene_fields, BackendChoice, FieldUser, Method, RadianceField};
use crate::scene::Scene;
use crate::settings::hash_json;

use super::PointSpec;

/// How points run.
#[derive(Clone, Copy, Debug, Default)]
pub struct LocalOptions {
    /// Scene intersection backend.
    pub backend: BackendChoice,
    /// No progress bars.
    pub quiet: bool,
    /// Write every point's images (a full `assess` output in `points/<id>/`).
    pub images: bool,
    /// Compression of those images.
    pub exr_compression: crate::io::exr::ExrCompression,
}

/// What a sweep read before its points are built, for their provenance
/// ([`crate::provenance`]): the files (sweep, experiment, scene, display) and the overrides every
/// point shares (the sweep's `[set]`, then the command line's `--set`).
#[derive(Clone, Debug, Default)]
pub struct SweepInputs {
    /// The base experiment file as given (`None`: built in).
    pub experiment_path: Option<String>,
    /// The files read, with their hashes.
    pub files: Vec<crate::provenance::InputFile>,
    /// The shared overrides, as `KEY=VALUE`.
    pub set: Vec<String>,
}

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct RunSummary {
    /// Points asked for, already complete before the run, and run now.
    pub selected: usize,
    /// Points already complete before the run.
    pub already_complete: usize,
    /// Points run now.
    pub ran: usize,
    /// Display images rendered (each shared by the points that use it).
    pub display_images: usize,
    /// Wall time of the run, s.
    pub seconds: f64,
    /// What loading the scenes noticed.
    pub warnings: Vec<String>,
    /// The points run again because their record could not be verified: `point I: why`.
    pub redone: Vec<String>,
}

/// A point ready to run.
struct Job {
    index: usize,
    id: String,
    values: Vec<String>,
    exp: Experiment,
}

/// The points of one scene, built.
type SceneJobs = (String, Scene, Vec<Job>);

/// Builds (and so validates) the experiments of the points `todo`, each scene once; each
/// point's provenance is `inputs` with the files its scene read and its own values.
fn build(
    resolved: &[PointSpec],
    values: &[Vec<String>],
    todo: &[usize],
    inputs: &SweepInputs,
) -> Result<(Vec<SceneJobs>, Vec<String>)> {
    let mut scenes: Vec<SceneJobs> = Vec::new();
    let mut scene_files: Vec<Vec<crate::provenance::InputFile>> = Vec::new();
    let mut warnings = Vec::new();
    let mut unit_mistakes: Vec<(String, String, Vec<usize>)> = Vec::new();
    for &i in todo {
        let Some(r) = resolved[i].resolved() else { continue };
        let slot = match scenes.iter().position(|(key, _, _)| *key == r.scene_key) {
            Some(s) => s,
            None => {
                let (scene, files) = crate::provenance::recording(|| r.build_scene());
                let scene = scene?;
                warnings.extend(scene.warnings.iter().cloned());
                scenes.push((r.scene_key.clone(), scene, Vec::new()));
                scene_files.push(files);
                scenes.len() - 1
            }
        };
        let mut exp = r.experiment_with(scenes[slot].1.clone())?;
        // Likely unit mistakes, each once however many points share the value: a display file's
        // as it is, a point's with the points it concerns.
        let point = format!(" point {i}");
        for w in exp.plausibility_warnings() {
            let of_point = exp.source.strip_suffix(&point).zip(w.strip_prefix(&format!("{}: ", exp.source)));
            match of_point {
                Some((file, tail)) => match unit_mistakes.iter_mut().find(|(f, t, _)| f == file && t == tail) {
                    Some((_, _, points)) => points.push(i),
                    None => unit_mistakes.push((file.to_string(), tail.to_string(), vec![i])),
                },
                None if !warnings.contains(&w) => warnings.push(w),
                None => {}
            }
        }
        let values = values.get(i).cloned().unwrap_or_default();
        let mut files = inputs.files.clone();
        files.extend(scene_files[slot].iter().filter(|f| !inputs.files.iter().any(|g| g.path == f.path)).cloned());
        let mut p = crate::settings::provenance_of(&exp, inputs.experiment_path.clone(), files, &[]);
        p.set = inputs.set.iter().chain(&values).cloned().collect();
        exp.provenance = p;
        scenes[slot].2.push(Job { index: i, id: r.id.clone(), values, exp });
    }
    for (file, tail, mut points) in unit_mistakes {
        points.sort_unstable();
        let which = match points.len() {
            1 => format!("point {}", points[0]),
            _ => format!("points {}", super::spec::format_selection(&points)),
        };
        warnings.push(format!("{file} {which}: {tail}"));
    }
    Ok((scenes, warnings))
}

/// Builds every point's experiment, as a run would, and reports the first invalid one (before
/// a sweep is submitted anywhere).
pub fn validate(resolved: &[PointSpec]) -> Result<()> {
    point_costs(resolved).map(|_| ())
}

/// `sweep --check`: builds (and so validates) every point's experiment and checks its memory
/// estimate ([`experiment::check`]); returns the rays of all points and what building them
/// noticed (a scene's warnings). Nothing runs.
pub fn check_points(resolved: &[PointSpec]) -> Result<(u64, Vec<String>)> {
    let mut rays = 0u64;
    for p in resolved {
        if let PointSpec::Study(s) = p {
            rays = rays.saturating_add(super::study::check_point(s)?);
        }
    }
    let all: Vec<usize> = (0..resolved.len()).collect();
    let (scenes, warnings) = build(resolved, &[], &all, &SweepInputs::default())?;
    for job in scenes.iter().flat_map(|(_, _, jobs)| jobs) {
        rays = rays.saturating_add(experiment::check(&job.exp)?.rays);
    }
    Ok((rays, warnings))
}

/// Builds (and so validates) every point's experiment and returns its estimated cost: the rays
/// its display images and its retinal images trace ([`experiment::estimate`]), by index.
pub fn point_costs(resolved: &[PointSpec]) -> Result<Vec<u64>> {
    let all: Vec<usize> = (0..resolved.len()).collect();
    let (scenes, _) = build(resolved, &[], &all, &SweepInputs::default())?;
    let mut costs = vec![0; resolved.len()];
    for (i, p) in resolved.iter().enumerate() {
        if let PointSpec::Study(s) = p {
            costs[i] = super::study::point_rays(s)?;
        }
    }
    for job in scenes.iter().flat_map(|(_, _, jobs)| jobs) {
        costs[job.index] = experiment::estimate(&job.exp).rays;
    }
    Ok(costs)
}

/// Runs the points `selection` (indices into `resolved`; `values` are their swept values as
/// `KEY=VALUE`) that `store` has no record of. Every point is built and validated before the
/// first one runs; what building them noticed (a scene's warnings, a likely unit mistake) goes to
/// `log` before any point runs.
pub fn run_points(
    resolved: &[PointSpec],
    values: &[Vec<String>],
    selection: &[usize],
    store: &Store,
    opts: LocalOptions,
    inputs: &SweepInputs,
    log: &mut dyn FnMut(String),
) -> Result<RunSummary> {
    let start = Instant::now();
    let mut summary = RunSummary { selected: selection.len(), ..Default::default() };
    let mut seen = HashSet::new();
    // Points already recorded are skipped; two points with the same settings (a repeated axis
    // value) run once.
    let mut redone = Vec::new();
    let todo: Vec<usize> = selection
        .iter()
        .copied()
        .filter(|&i| seen.insert(resolved[i].id().to_string()))
        .filter(|&i| match store.state(&resolved[i]) {
            super::store::RecordState::Complete(_) => false,
            super::store::RecordState::Missing => true,
            super::store::RecordState::Invalid(why) => {
                redone.push(format!("point {i}: {why}"));
                true
            }
        })
        .collect();
    summary.redone = redone;
    summary.already_complete = selection.len() - todo.len();
    if resolved.iter().any(|p| matches!(p, PointSpec::Study(_))) {
        run_study_points(resolved, values, &todo, store, opts.quiet)?;
        summary.ran = todo.len();
        summary.seconds = start.elapsed().as_secs_f64();
        return Ok(summary);
    }
    let (scenes, warnings) = build(resolved, values, &todo, inputs)?;
    for w in &warnings {
        log(format!("warning: {w}"));
    }
    let rays = scenes
        .iter()
        .flat_map(|(_, _, jobs)| jobs.iter())
        .fold(0u64, |acc, job| acc.saturating_add(experiment::estimate(&job.exp).rays));
    crate::long_run::announce(rays);
    summary.warnings = warnings;
    let progress = Progress::new(todo.len() as u64, "sweep points", opts.quiet);
    for (_, scene, jobs) in &scenes {
        if opts.images {
            for job in jobs {
                run_with_images(job, store, opts)?;
                progress.inc(1);
            }
        } else {
            summary.display_images +=
                with_scene_fields(scene, opts.backend, SharedDisplays { jobs, store, progress: &progress })?;
        }
    }
    progress.finish();
    summary.ran = todo.len();
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

/// The points `todo` of a study's sweep, one after another (each study runs on all threads),
/// each recorded as soon as it is done. Every point's setup is checked before the first runs.
fn run_study_points(
    resolved: &[PointSpec],
    values: &[Vec<String>],
    todo: &[usize],
    store: &Store,
    quiet: bool,
) -> Result<()> {
    let points: Vec<(usize, &super::study::StudyPoint)> = todo
        .iter()
        .filter_map(|&i| match &resolved[i] {
            PointSpec::Study(s) => Some((i, &**s)),
            PointSpec::Experiment(_) => None,
        })
        .collect();
    let mut rays = 0u64;
    for (_, p) in &points {
        rays = rays.saturating_add(super::study::check_point(p)?);
    }
    crate::long_run::announce(rays);
    let progress = Progress::new(points.len() as u64, "sweep points", quiet);
    for (i, p) in points {
        let record = super::study::run_point(p, i, values.get(i).map(Vec::as_slice).unwrap_or_default())?;
        store.write(&record)?;
        progress.inc(1);
    }
    progress.finish();
    Ok(())
}

/// A full `assess` of one point into `points/<id>/`, then its record.
fn run_with_images(job: &Job, store: &Store, local: LocalOptions) -> Result<()> {
    let t = Instant::now();
    let opts = experiment::RunOptions {
        quiet: true,
        backend: local.backend,
        exr_compression: local.exr_compression,
        force: false,
        keep_replicates: false,
    };
    let report = experiment::assess(&job.exp, &store.images_dir(&job.id), opts)?;
    store.write(&record(job, &report.scores, t.elapsed(), &report.backend))
}

fn record(job: &Job, scores: &[Score], elapsed: Duration, backend: &str) -> PointRecord {
    PointRecord {
        format: super::store::RECORD_FORMAT,
        id: job.id.clone(),
        index: job.index,
        values: job.values.clone(),
        scores: scores.iter().map(ScoreRow::from).collect(),
        seconds: elapsed.as_secs_f64(),
        backend: backend.to_string(),
        threads: rayon::current_num_threads(),
        host: host_name(),
        finished_unix: unix_now(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        provenance: Some(Box::new(job.exp.provenance.clone())),
        mtf50: Vec::new(),
    }
}

/// The key of one display image: everything it depends on (display, method, display-render
/// settings; the eye position only for PupilCenter, the one method that aims at it). OPT's also
/// holds its resolved `[optimize]` settings (training states with their eyes, retinas and
/// weights, starting image, solver) and the eye position (its starting image may be PC's).
/// Points of one scene with equal keys share the image.
fn image_key(exp: &Experiment, method: Method) -> String {
    let aims = matches!(method, Method::PupilCenter | Method::Optimized);
    let eye = if aims { Some(exp.render.eye_position.to_array()) } else { None };
    // Debug of f64 is exact (shortest round-trip), so equal text means equal settings.
    let optimize = if method == Method::Optimized { Some(format!("{:?}", exp.optimize)) } else { None };
    let display = crate::io::display_file::DisplaySpec::from_display(&exp.display);
    let settings = (&display, format!("{method:?}"), exp.render.samples_per_pixel, exp.render.reference_plane_z, eye);
    match optimize {
        None => hash_json(&settings).unwrap_or_else(|_| format!("{settings:?}")),
        Some(o) => hash_json(&(settings, o)).unwrap_or_else(|e| format!("{e}")),
    }
}

/// Bytes of the images one point holds while it runs: per eye case the ground truth and one
/// perceived image per method, f32 RGB.
fn point_bytes(exp: &Experiment) -> u64 {
    let pixels = (exp.retina.resolution as u64).pow(2);
    pixels * 12 * (1 + exp.methods.len() as u64) * exp.cases.len() as u64
}

/// The points of one scene, run on shared display images.
struct SharedDisplays<'a> {
    jobs: &'a [Job],
    store: &'a Store,
    progress: &'a Progress,
}

impl FieldUser for SharedDisplays<'_> {
    /// Display images rendered.
    type Output = usize;

    fn run<S: RadianceField, D: RadianceField>(self, shade: &S, with_depth: &D, name: &'static str) -> Result<usize> {
        // Points grouped by the display images they need, in order of first appearance.
        let mut groups: Vec<(Vec<String>, Vec<&Job>)> = Vec::new();
        for job in self.jobs {
            let keys: Vec<String> = job.exp.methods.iter().map(|m| image_key(&job.exp, *m)).collect();
            match groups.iter_mut().find(|(k, _)| *k == keys) {
                Some((_, members)) => members.push(job),
                None => groups.push((keys, vec![job])),
            }
        }
        let mut cache: HashMap<String, RgbImage> = HashMap::new();
        let mut rendered = 0;
        for (g, (keys, members)) in groups.iter().enumerate() {
            let first = &members[0].exp;
            let t = Instant::now();
            for (method, key) in first.methods.iter().zip(keys) {
                if !cache.contains_key(key) {
                    let (image, _, _) = crate::methods::render(
                        &first.display,
                        *method,
                        &first.render,
                        first.optimize.as_ref(),
                        with_depth,
                        &Progress::hidden(),
                    )?;
                    cache.insert(key.clone(), image);
                    rendered += 1;
                }
            }
            let images: Vec<&RgbImage> = keys.iter().map(|k| &cache[k]).collect();
            let stack = DisplayStack::new(&first.display, &images)?;
            let shared = t.elapsed() / members.len() as u32;
            // As many points at once as threads, and as the memory limit allows for their images.
            let at_once = (crate::budget::memory_limit() / (2 * point_bytes(first)).max(1))
                .clamp(1, rayon::current_num_threads() as u64) as usize;
            for batch in members.chunks(at_once) {
                batch.par_iter().try_for_each(|job| -> Result<()> {
                    let t = Instant::now();
                    let mut stages = Vec::new();
                    let (_, _, scores) = experiment::table1(&job.exp, shade, &stack, true, &mut stages)?;
                    self.store.write(&record(job, &scores, shared + t.elapsed(), name))?;
                    self.progress.inc(1);
                    Ok(())
                })?;
            }
            drop(stack);
            // Keep only the images a later group still needs.
            let later: HashSet<&String> = groups[g + 1..].iter().flat_map(|(k, _)| k).collect();
            cache.retain(|k, _| later.contains(k));
        }
        Ok(rendered)
    }
}
