//! `report.html`: one static page per run folder that tells its story (docs/REPORT.md): what was
//! simulated in words (the scene, the display and its optics and photometry, the eye per eye
//! case, the spectrum, diffraction, the estimator and its targets), the table of scores with
//! their intervals and missed targets marked, the images (the paper's Fig. 3, each perceived
//! image beside its ground truth), the plots, and the provenance (each file's hash, the command
//! that reproduces the run).
//!
//! The page is built from the folder's own files only (`results.json` of `assess`, `study.json`
//! of `resolution`, `sweep.json` of `sweep`, and the images and tables they list), with nothing
//! of the moment (no date, no absolute path of the folder), so `inimtrace report DIR` rebuilds
//! it byte for byte. It is one file: its images inlined as `data:` URIs, its style inline, no
//! script, a Content-Security-Policy that forbids every fetch.

mod assess;
pub mod page;
mod resolution;
mod sweep;

use std::path::Path;

use serde_json::Value;

use crate::error::{Error, Result};

/// The page's file name in a run folder.
pub const REPORT_HTML: &str = "report.html";

/// The kind of run a folder holds, known by its report file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunFolder {
    /// `assess`: `results.json`.
    Assess,
    /// `resolution`: `study.json`.
    Resolution,
    /// `sweep`: `sweep.json`.
    Sweep,
}

impl RunFolder {
    /// The report file each kind of run writes last.
    pub fn report_file(self) -> &'static str {
        match self {
            RunFolder::Assess => "results.json",
            RunFolder::Resolution => "study.json",
            RunFolder::Sweep => "sweep.json",
        }
    }

    /// The kind of run in `dir`, by the report file it holds.
    pub fn of(dir: &Path) -> Result<Self> {
        [RunFolder::Assess, RunFolder::Resolution, RunFolder::Sweep]
            .into_iter()
            .find(|k| dir.join(k.report_file()).is_file())
            .ok_or_else(|| {
                Error::invalid(
                    dir.display().to_string(),
                    "report",
                    "holds no results.json, study.json or sweep.json: not a finished assess, resolution or sweep run",
                )
            })
    }
}

/// The page of the run folder `dir`.
pub fn build(dir: &Path) -> Result<String> {
    let kind = RunFolder::of(dir)?;
    let path = dir.join(kind.report_file());
    let bytes = crate::io::input::read_regular(&path)?;
    let value: Value = serde_json::from_slice(&bytes)
        .map_err(|e| Error::invalid(path.display().to_string(), "JSON", format!("not JSON: {e}")))?;
    match kind {
        RunFolder::Assess => assess::page(dir, &value),
        RunFolder::Resolution => resolution::page(dir, &value),
        RunFolder::Sweep => sweep::page(dir, &value),
    }
}

/// Builds the page of `dir` and writes it to `dir/report.html` atomically; returns its path.
pub fn write(dir: &Path) -> Result<std::path::PathBuf> {
    let html = build(dir)?;
    let path = dir.join(REPORT_HTML);
    crate::io::output::write_atomic(&path, |p| std::fs::write(p, html.as_bytes()).map_err(|e| Error::io(p, e)))?;
    Ok(path)
}
