//! `inimtrace resolution [STUDY.toml] [--out DIR]`: load the study (or the built-in
//! `studies/paper.toml`), run it, and write every file into an owned output folder, atomically
//! (`crate::io::output`), `study.json` last. The CLI only parses flags and prints what this
//! returns.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::limits::{depth_ranges, display_limits};
use super::report::{accommodation_csv, accommodation_rows, display_json, display_md, mtf50_csv, mtf_csv, study_json};
use super::run::{run_study, StudyResults, Timing};
use super::study::Study;
use crate::error::{Error, Result};
use crate::io::output::{OutputDir, RunKind};
use crate::overrides::Override;
use crate::provenance::{Budgets, InputFile, Provenance};

/// What `inimtrace resolution` was asked.
#[derive(Clone, Debug, Default)]
pub struct ResolutionCommand {
    /// The study file (`None`: the built-in `studies/paper.toml`).
    pub study: Option<PathBuf>,
    /// Output folder (`None`: `out/resolution-<study name>`).
    pub out: Option<PathBuf>,
    /// `--set` overrides, applied to the study file.
    pub overrides: Vec<Override>,
    /// No progress bars.
    pub quiet: bool,
    /// Replace another command's results in the output folder (`--force`).
    pub force: bool,
}

/// What a run produced.
pub struct ResolutionRun {
    /// The output folder written.
    pub out: PathBuf,
    /// Every measured number.
    pub results: StudyResults,
    /// Every stage, the files last.
    pub timings: Vec<Timing>,
}

impl ResolutionRun {
    /// The stage timings as lines (`--timings` style).
    pub fn timings_text(&self) -> String {
        let mut s = String::new();
        for t in &self.timings {
            s += &format!("{:>8.3} s  {}\n", t.seconds, t.stage);
        }
        s += &format!("{:>8.3} s  total\n", self.timings.iter().map(|t| t.seconds).sum::<f64>());
        s
    }
}

/// Loads the study of `cmd`; an error names the `--set` overrides too.
pub fn load_study(cmd: &ResolutionCommand) -> Result<Study> {
    load_recorded(cmd).0
}

/// [`load_study`], with the files it read.
fn load_recorded(cmd: &ResolutionCommand) -> (Result<Study>, Vec<InputFile>) {
    let (study, files) = crate::provenance::recording(|| match &cmd.study {
        Some(p) => Study::load(p, &cmd.overrides),
        None => Study::paper(&cmd.overrides),
    });
    (study.map_err(|e| with_overrides(e, &cmd.overrides)), files)
}

/// `e` with the `--set` overrides of the run named after the file it names (as `assess` labels
/// its errors): the file alone did not make it fail.
pub fn with_overrides(e: Error, overrides: &[Override]) -> Error {
    if overrides.is_empty() {
        return e;
    }
    let set = format!(" with --set {}", overrides.iter().map(Override::to_arg).collect::<Vec<_>>().join(" --set "));
    match e {
        Error::Invalid { source_name, field, message } => {
            Error::Invalid { source_name: source_name + &set, field, message }
        }
        Error::Load { source_name, field, reference, source } => {
            Error::Load { source_name: source_name + &set, field, reference, source }
        }
        Error::InField { source_name, field, source } => {
            Error::InField { source_name: source_name + &set, field, source }
        }
        Error::Lattice { source_name, field, message } => {
            Error::Lattice { source_name: source_name + &set, field, message }
        }
        Error::Parse { path, message } => Error::Parse { path, message: format!("{message}{set}") },
        other => other,
    }
}

/// The provenance of a study run: the files read to set it up, with their hashes, and how it
/// was asked to run.
fn provenance(cmd: &ResolutionCommand, study: &Study, files: Vec<InputFile>) -> Provenance {
    Provenance {
        experiment_path: None,
        study_path: Some(cmd.study.as_ref().map_or_else(|| "builtin:paper".into(), |p| p.display().to_string())),
        scene_name: "resolution chart".into(),
        scene_path: String::new(),
        display_path: study.display_source.clone(),
        files,
        set: cmd.overrides.iter().map(Override::to_arg).collect(),
        budgets: Budgets {
            estimator: "converged".into(),
            max_samples_per_pixel: super::report::samples_per_pixel(study),
            ..Default::default()
        },
        seed: study.measurement.seed,
        working_directory: std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default(),
    }
}

/// The plausibility warnings of `study`: its display's fields and its pupil (likely unit
/// mistakes, `crate::optics::plausibility`), and a chart off axis beyond the display. The CLI
/// and Python give them before the run starts.
pub fn plausibility_warnings(study: &Study) -> Vec<String> {
    use crate::optics::plausibility::{check, display_warnings, PUPIL_DIAMETER};
    let mut w = display_warnings(&study.display, &study.display_source);
    w.extend(check(&study.source, "pupil_diameter_mm", study.pupil_diameter_mm, PUPIL_DIAMETER));
    w.extend(super::field::display_warning(study));
    w
}

/// `resolution --check`: the study's optics built (every focus's eye, the LCD crop) and its
/// memory estimate checked, in one line; nothing is traced or written.
pub fn check_text(study: &Study) -> Result<String> {
    let setup = super::run::StudySetup::new(study)?;
    let memory = setup.memory(study);
    memory.check_memory(&crate::budget::memory_budget(), &study.source)?;
    Ok(format!(
        "{}: valid; about {} of memory and {:.2e} rays (nothing run)",
        study.source,
        crate::budget::Bytes(memory.bytes()),
        setup.rays(study) as f64
    ))
}

/// Runs the study and writes its files.
pub fn execute(cmd: &ResolutionCommand) -> Result<ResolutionRun> {
    let t = Instant::now();
    let (study, files) = load_recorded(cmd);
    let study = study?;
    let provenance = provenance(cmd, &study, files);
    let out = cmd.out.clone().unwrap_or_else(|| Path::new("out").join(format!("resolution-{}", study.name)));
    let dir = OutputDir::open(&out, RunKind::Resolution, cmd.force)?;
    let setup = t.elapsed().as_secs_f64();
    let mut results = run_study(&study, cmd.quiet).map_err(|e| with_overrides(e, &cmd.overrides))?;
    let mut timings = vec![Timing { stage: "study and output folder".into(), seconds: setup }];
    timings.append(&mut results.timings.clone());

    let t = Instant::now();
    let accommodation = accommodation_rows(&results);
    let mut limits = display_limits(&study.display, study.pupil_diameter_mm);
    limits.depth_ranges = depth_ranges(&results);
    timings.push(Timing { stage: "accommodation and display limits".into(), seconds: t.elapsed().as_secs_f64() });

    let t = Instant::now();
    dir.write_bytes("mtf.csv", mtf_csv(&results).as_bytes())?;
    dir.write_bytes("mtf50.csv", mtf50_csv(&results).as_bytes())?;
    dir.write_bytes("accommodation.csv", accommodation_csv(&accommodation, &study).as_bytes())?;
    dir.write_bytes("display.json", display_json(&limits).as_bytes())?;
    let md = display_md(&limits, &study) + &super::report::orientations_md(&results);
    dir.write_bytes("display.md", md.as_bytes())?;
    timings.push(Timing { stage: "tables".into(), seconds: t.elapsed().as_secs_f64() });
    let t = Instant::now();
    super::plots::write_plots(&results, &accommodation, &dir)?;
    timings.push(Timing { stage: "plots (PNG, SVG)".into(), seconds: t.elapsed().as_secs_f64() });
    // study.json last: its presence marks a complete run.
    dir.finish_report("study.json", |files| Ok(study_json(&results, &timings, files, &provenance).into_bytes()))?;
    // The page, from the files just written (study.json included), outside its manifest.
    crate::report::write(dir.path())?;
    drop(dir);
    results.timings = timings.clone();
    Ok(ResolutionRun { out, results, timings })
}
