//! Provenance of a run: what it read and how it was asked to run, so that a result can be traced
//! back to its inputs and checked against them later. Every input file passes the input gate
//! (`io::input`), EXR images included; while a [`recording`] is active on the thread, the gate
//! notes in its log (`io::input_log`) each file's path (as it was opened) and the SHA-256 of the
//! bytes it read, so the hashes are of exactly what the run used (the experiment, scene and
//! display files, every mesh, material library, glTF buffer, texture and input image). A
//! [`Provenance`] holds those with the scene's name and path as given, the `--set` overrides, the
//! measurement's budgets and targets and the seed; [`check`] hashes the files on disk again and
//! says which changed (`inimtrace info
//! --provenance RUN_DIR`, for an `assess` run, a sweep or a resolution study). The gate's log is the lower layer:
//! `io` never imports this module.

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use crate::io::input_log::{recording, sha256_hex, InputFile};

/// The measurement's budgets and targets (`[measurement]`; see `measure::spec`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Budgets {
    /// `grid` or `converged`.
    pub estimator: String,
    /// Target: PSNR 95% half-width, dB (converged).
    pub psnr_ci95_db: f64,
    /// Target: SSIM 95% half-width (converged).
    pub ssim_ci95: f64,
    /// Budget: samples per retina pixel over all replicates (converged).
    pub max_samples_per_pixel: u64,
    /// Budget: wall seconds of the measurement (converged).
    pub max_seconds: f64,
    /// The memory budget the run was checked against, bytes.
    pub memory_bytes: u64,
}

/// Where a run's results come from.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The experiment file as given (`None`: a built-in experiment).
    #[serde(default)]
    pub experiment_path: Option<String>,
    /// A resolution study's file as given (`builtin:paper` for the built-in study); absent for
    /// an experiment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub study_path: Option<String>,
    /// The scene's name.
    pub scene_name: String,
    /// The scene as the experiment (or `--scene`) gives it: a path relative to the experiment
    /// file, or `builtin:paper`.
    pub scene_path: String,
    /// The display as the experiment gives it.
    pub display_path: String,
    /// Every file read to set the run up, in the order first read, with its content hash.
    pub files: Vec<InputFile>,
    /// The `--set` overrides applied, in order, as `KEY=VALUE`.
    pub set: Vec<String>,
    /// The measurement's budgets and targets.
    pub budgets: Budgets,
    /// The seed of the converged estimator's scrambles.
    pub seed: u64,
    /// The folder the run started in: relative paths of `files` are relative to it.
    #[serde(default)]
    pub working_directory: String,
}

impl Provenance {
    /// The hash of the scene file, if the scene came from a file this run read.
    pub fn scene_sha256(&self) -> Option<&str> {
        // The scene's path is as given (relative to the experiment's folder): the file read
        // under it ends with it.
        let scene = Path::new(&self.scene_path);
        self.files.iter().find(|f| Path::new(&f.path).ends_with(scene)).map(|f| f.sha256.as_str())
    }
}

/// What a file of a provenance is now.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FileState {
    /// The same bytes.
    Unchanged,
    /// Other bytes: the hash now.
    Changed(String),
    /// Not there, or not readable: why.
    Missing(String),
}

/// Hashes every file of `provenance` again, its relative paths resolved against `base` (the
/// folder the run was started from); returns each file with its state.
pub fn check(provenance: &Provenance, base: &Path) -> Vec<(InputFile, FileState)> {
    provenance
        .files
        .iter()
        .map(|f| {
            let path = base.join(&f.path);
            let state = match crate::io::input::read_regular(&path) {
                Ok(bytes) => {
                    let now = sha256_hex(&bytes);
                    if now == f.sha256 {
                        FileState::Unchanged
                    } else {
                        FileState::Changed(now)
                    }
                }
                Err(e) => FileState::Missing(e.to_string()),
            };
            (f.clone(), state)
        })
        .collect()
}

/// The provenances a run folder holds: its `results.json` (an `assess` run), its `study.json`
/// (a resolution study) or the records in `points/` (a sweep), each with the file it came from.
pub fn of_run(dir: &Path) -> crate::error::Result<Vec<(std::path::PathBuf, Provenance)>> {
    use crate::error::Error;
    let read = |path: &Path| -> crate::error::Result<Option<Provenance>> {
        let bytes = crate::io::input::read_regular(path)?;
        let value: serde_json::Value = serde_json::from_slice(&bytes)
            .map_err(|e| Error::invalid(path.display().to_string(), "provenance", format!("not JSON: {e}")))?;
        match value.get("provenance") {
            None | Some(serde_json::Value::Null) => Ok(None),
            Some(p) => serde_json::from_value(p.clone()).map(Some).map_err(|e| {
                Error::invalid(path.display().to_string(), "provenance", format!("not a provenance record: {e}"))
            }),
        }
    };
    let results = dir.join("results.json");
    let study = dir.join("study.json");
    let mut out = Vec::new();
    if results.is_file() {
        if let Some(p) = read(&results)? {
            out.push((results, p));
        }
    } else if study.is_file() {
        if let Some(p) = read(&study)? {
            out.push((study, p));
        }
    } else if dir.join("points").is_dir() {
        let mut records: Vec<std::path::PathBuf> = std::fs::read_dir(dir.join("points"))
            .map_err(|e| Error::io(dir.join("points"), e))?
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "json") && p.is_file())
            .filter(|p| !p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')))
            .collect();
        records.sort();
        for r in records {
            if let Some(p) = read(&r)? {
                out.push((r, p));
            }
        }
    } else {
        return Err(Error::invalid(
            dir.display().to_string(),
            "RUN_DIR",
            "holds neither results.json (an assess run), study.json (a resolution study) nor points/ (a sweep)",
        ));
    }
    if out.is_empty() {
        return Err(Error::invalid(
            dir.display().to_string(),
            "provenance",
            "no record in it holds a provenance (written by an older inimtrace?)",
        ));
    }
    Ok(out)
}

/// `inimtrace info --provenance RUN_DIR`: every input file of the run hashed again, and what
/// changed. Returns the report and the number of files changed or missing.
pub fn report(dir: &Path) -> crate::error::Result<(String, usize)> {
    use std::fmt::Write;
    let runs = of_run(dir)?;
    let mut text = String::new();
    let first = &runs[0].1;
    let what = match &first.study_path {
        Some(study) => format!("study {study}"),
        None => format!("scene `{}` ({})", first.scene_name, first.scene_path),
    };
    let _ = writeln!(
        text,
        "{}: {what}, display {}{}; seed {}; {}",
        dir.display(),
        first.display_path,
        if first.set.is_empty() { String::new() } else { format!("; --set {}", first.set.join(" ")) },
        first.seed,
        crate::count::count(runs.len(), "record")
    );
    // Each file once, as the first record that read it saw it.
    let mut seen: Vec<(InputFile, String)> = Vec::new();
    for (_, p) in &runs {
        for f in &p.files {
            if !seen.iter().any(|(g, base)| g.path == f.path && *base == p.working_directory) {
                seen.push((f.clone(), p.working_directory.clone()));
            }
        }
    }
    let mut bad = 0;
    for (f, base) in &seen {
        let p = Provenance { files: vec![f.clone()], ..Default::default() };
        let (_, state) = check(&p, Path::new(base)).remove(0);
        let line = match state {
            FileState::Unchanged => format!("  unchanged  {}  {}", f.sha256, f.path),
            FileState::Changed(now) => {
                bad += 1;
                format!("  CHANGED    {}  {} (now {now})", f.sha256, f.path)
            }
            FileState::Missing(why) => {
                bad += 1;
                format!("  MISSING    {}  {} ({why})", f.sha256, f.path)
            }
        };
        let _ = writeln!(text, "{line}");
    }
    let _ = if bad == 0 {
        writeln!(text, "all {} unchanged", crate::count::count(seen.len(), "input file"))
    } else {
        writeln!(text, "{bad} of {} changed or missing since the run", crate::count::count(seen.len(), "input file"))
    };
    Ok((text, bad))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_sees_the_files_the_gate_reads_and_their_hashes() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.txt");
        std::fs::write(&a, b"abc").unwrap();
        let (bytes, files) = recording(|| crate::io::input::read_regular(&a).unwrap());
        assert_eq!(bytes, b"abc");
        assert_eq!(files.len(), 1);
        // SHA-256("abc"), FIPS 180-2 appendix B.1.
        assert_eq!(files[0].sha256, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
        assert_eq!(files[0].bytes, 3);
        // Nested: the outer recording sees the inner one's reads, each file once.
        let ((_, inner), outer) = recording(|| {
            let _ = crate::io::input::read_regular(&a);
            recording(|| crate::io::input::read_regular(&a))
        });
        assert_eq!((inner.len(), outer.len()), (1, 1));
        // No recording, no note.
        let _ = crate::io::input::read_regular(&a);
        let p = Provenance { files, ..Default::default() };
        assert_eq!(check(&p, Path::new(""))[0].1, FileState::Unchanged);
        std::fs::write(&a, b"abd").unwrap();
        assert!(matches!(check(&p, Path::new(""))[0].1, FileState::Changed(_)));
        std::fs::remove_file(&a).unwrap();
        assert!(matches!(check(&p, Path::new(""))[0].1, FileState::Missing(_)));
    }
}
