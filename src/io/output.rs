//! The output folder of a run: owned, written atomically, and described by a manifest.
//!
//! A run either finishes with complete files or leaves nothing that looks complete:
//! - **Owned**: opening a folder takes an exclusive lock on `.inimtrace.lock` inside it (an OS
//!   file lock, released when the process ends, even by SIGKILL). A second run into the same
//!   folder fails at once and names the holder (its process id and command line).
//! - **Atomic**: every file is written in a hidden private folder made for it beside its final
//!   name (`.inimtrace-tmp-<random>/`, created new with mode 0700, so nothing can be planted in
//!   it), under its own name (so that format writers that look at the extension still work),
//!   and renamed to its final name only when complete. A killed run leaves at most temporary
//!   folders, which the next run into the folder removes.
//! - **No links followed**: the lock is opened with `O_NOFOLLOW` and must be a regular file with
//!   one link; an output name (or the lock, or the report) that is a symbolic link, a FIFO, a
//!   directory or a device is refused with its name, before any work, and again before each
//!   rename, so a planted link can neither be written through nor truncate its target.
//! - **Manifest**: every file written is recorded with its size and CRC-32; the run's report
//!   (`results.json` for `assess`, `study.json` for `resolution`) is written last and lists them,
//!   so its presence marks a complete run and a reader can verify the set.
//! - **One command per folder**: a folder holding another command's report (or the leftovers of
//!   another command's interrupted run) is refused, naming that command, unless the run is forced
//!   (`--force`); a report that is not an inimtrace report (no manifest) is always refused, never
//!   deleted. Opening a folder removes the previous run's report first, then the files its
//!   manifest listed, so no earlier output stands next to a new report. Files are only ever
//!   removed because a manifest lists them, and only while their size and CRC-32 still match
//!   the listing ([`crate::io::manifest`]): a listed file changed since makes the run refuse
//!   the folder, naming it, before anything is removed.
//! - **Journal**: before each file is renamed into place it is added, with its size and CRC-32,
//!   to a journal (`.inimtrace-journal.json`, with the command), removed when the report is
//!   written. A killed run therefore leaves a journal, and the next run into the folder removes
//!   exactly the files it lists (or refuses, when another command left them).
//! - **Released**: the lock file is removed when the run ends (the OS lock goes with the
//!   process), so a finished folder holds only the run's files.
//!
//! Atomic renames protect against a killed process and a full disk, not against power loss
//! (files are not fsynced, which would cost seconds per run).

use std::fs::{self, File, TryLockError};
use std::io::{Read, Write};
use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::io::input::file_kind;
use crate::io::manifest::{describe, Listed, ListedState};
pub use crate::io::manifest::{verify, OutputFile};

/// Name of the lock file inside an output folder.
pub const LOCK_FILE: &str = ".inimtrace.lock";
/// Name of the journal of the files a run has written so far (see the module documentation).
pub const JOURNAL_FILE: &str = ".inimtrace-journal.json";

/// The command whose results an output folder holds: each writes its own report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunKind {
    /// `inimtrace assess`, whose report is `results.json`.
    Assess,
    /// `inimtrace resolution`, whose report is `study.json`.
    Resolution,
}

impl RunKind {
    const ALL: [RunKind; 2] = [RunKind::Assess, RunKind::Resolution];

    /// The command, as users type it.
    pub fn command(self) -> &'static str {
        match self {
            RunKind::Assess => "inimtrace assess",
            RunKind::Resolution => "inimtrace resolution",
        }
    }

    /// The name of the report the command writes last.
    pub fn report(self) -> &'static str {
        match self {
            RunKind::Assess => "results.json",
            RunKind::Resolution => "study.json",
        }
    }

    fn from_command(command: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.command() == command)
    }
}

/// The journal's content: the command of the run and the files it has put (or is about to put)
/// in the folder, each with its size and CRC-32 (taken before the rename).
#[derive(Debug, Default, Serialize, Deserialize)]
struct Journal {
    command: String,
    files: Vec<Listed>,
}
/// Prefix of temporary folders inside an output folder.
pub const TEMP_PREFIX: &str = ".inimtrace-tmp-";
/// Extensions of the files runs write: an entry of the output folder with a plain name and one
/// of these that is not a regular file is refused when the folder is opened.
const OUTPUT_EXTENSIONS: &[&str] = &["exr", "png", "svg", "md", "csv", "json", "sbatch", "html"];

/// An output folder owned by this run (see the module documentation).
#[derive(Debug)]
pub struct OutputDir {
    root: PathBuf,
    kind: RunKind,
    /// Held for the lifetime of the run: the OS lock lives as long as this handle.
    _lock: File,
    written: Mutex<Vec<OutputFile>>,
    /// Every name put in the journal so far (guarded with the journal file's writes).
    journal: Mutex<Vec<Listed>>,
}

impl Drop for OutputDir {
    /// Removes the lock file while the lock is still held (the handle closes after this).
    fn drop(&mut self) {
        let _ = fs::remove_file(self.root.join(LOCK_FILE));
    }
}

impl OutputDir {
    /// Creates (if needed) and takes the folder `root` for a run of `kind`, removes what a
    /// previous run of the same command left there (its report, the files its manifest or
    /// journal listed, temporary files), and checks that it can be written. A folder holding
    /// another command's results is refused unless `force`.
    pub fn open(root: &Path, run: RunKind, force: bool) -> Result<Self> {
        fs::create_dir_all(root).map_err(|e| Error::io(root, e))?;
        if !root.is_dir() {
            return Err(Error::io(root, std::io::Error::other("is not a directory")));
        }
        refuse_outputs_that_are_not_files(root)?;
        let lock_path = root.join(LOCK_FILE);
        let mut lock = fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
            .open(&lock_path)
            .map_err(|e| not_a_file_error(&lock_path).unwrap_or_else(|| Error::io(&lock_path, e)))?;
        let meta = lock.metadata().map_err(|e| Error::io(&lock_path, e))?;
        if !meta.is_file() || meta.nlink() != 1 {
            let what =
                if meta.is_file() { "a regular file with other hard links" } else { file_kind(&meta.file_type()) };
            return Err(refusal(&lock_path, what));
        }
        match lock.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = lock.read_to_string(&mut holder);
                let holder = holder.trim();
                let holder = if holder.is_empty() { "another process" } else { holder };
                return Err(Error::io(
                    root,
                    std::io::Error::other(format!("output folder is in use by {holder}; choose another --out")),
                ));
            }
            Err(TryLockError::Error(e)) => return Err(Error::io(&lock_path, e)),
        }
        let holder =
            format!("inimtrace process {} ({})", std::process::id(), std::env::args().collect::<Vec<_>>().join(" "));
        lock.set_len(0).and_then(|_| lock.write_all(holder.as_bytes())).map_err(|e| Error::io(&lock_path, e))?;
        let dir = Self {
            root: root.to_path_buf(),
            kind: run,
            _lock: lock,
            written: Mutex::new(Vec::new()),
            journal: Mutex::new(Vec::new()),
        };
        dir.remove_previous_run(force)?;
        Ok(dir)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.root
    }

    /// The final path of `name` in the folder.
    pub fn join(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    /// Writes `name` atomically: `write` gets a temporary path with the same extension and must
    /// leave a complete file there; it is then renamed to `name` and recorded in the manifest.
    /// On error the temporary file is removed and nothing appears under `name`.
    pub fn write_with(&self, name: &str, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let mut entry = None;
        write_atomic(&self.root.join(name), |temp| {
            write(temp)?;
            let described = describe(temp, name)?;
            // Journaled with its size and CRC-32 before it takes its name.
            self.journal(&described)?;
            entry = Some(described);
            Ok(())
        })?;
        let entry = entry.expect("described before the rename");
        let mut written = self.written.lock().unwrap_or_else(|p| p.into_inner());
        written.retain(|f| f.name != entry.name);
        written.push(entry);
        Ok(())
    }

    /// Writes `bytes` to `name` atomically.
    pub fn write_bytes(&self, name: &str, bytes: &[u8]) -> Result<()> {
        self.write_with(name, |p| fs::write(p, bytes).map_err(|e| Error::io(p, e)))
    }

    /// Every file written so far, sorted by name.
    pub fn manifest(&self) -> Vec<OutputFile> {
        let mut files = self.written.lock().unwrap_or_else(|p| p.into_inner()).clone();
        files.sort_by(|a, b| a.name.cmp(&b.name));
        files
    }

    /// Writes the run's report `name` last, from the manifest of every other file, and
    /// releases the folder.
    pub fn finish(self, name: &str, report: impl FnOnce(&[OutputFile]) -> Result<Vec<u8>>) -> Result<()> {
        self.finish_report(name, report)
    }

    /// Writes the run's report `name` from the manifest of every file written so far (the folder
    /// stays owned until this handle is dropped).
    pub fn finish_report(&self, name: &str, report: impl FnOnce(&[OutputFile]) -> Result<Vec<u8>>) -> Result<()> {
        let bytes = report(&self.manifest())?;
        self.write_bytes(name, &bytes)?;
        // The report lists every file now: the journal has done its work.
        let journal = self.root.join(JOURNAL_FILE);
        match fs::remove_file(&journal) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(Error::io(&journal, e)),
        }
    }

    /// Adds `file` to the journal (written atomically) before it is put in place.
    fn journal(&self, file: &OutputFile) -> Result<()> {
        let mut names = self.journal.lock().unwrap_or_else(|p| p.into_inner());
        names.retain(|n| n.name() != file.name);
        names.push(Listed::File(file.clone()));
        let journal = Journal { command: self.kind.command().to_string(), files: names.clone() };
        let bytes =
            serde_json::to_vec(&journal).map_err(|e| Error::parse(self.root.join(JOURNAL_FILE), e.to_string()))?;
        write_atomic(&self.root.join(JOURNAL_FILE), |p| fs::write(p, &bytes).map_err(|e| Error::io(p, e)))
    }

    /// What earlier runs left in the folder: each command's report with the files its manifest
    /// lists, and an interrupted run's journal. Refuses reports inimtrace did not write, and
    /// (unless `force`) another command's results.
    fn previous_runs(&self, force: bool) -> Result<Vec<(PathBuf, Vec<Listed>)>> {
        let mut found = Vec::new();
        let other = |path: &Path, kind: RunKind, what: &str| {
            Error::io(
                &self.root,
                std::io::Error::other(format!(
                    "holds {what} of `{}` ({}); choose a new --out for `{}`, or pass --force to replace them \
                     (only the files that run listed are removed)",
                    kind.command(),
                    path.file_name().unwrap_or_default().to_string_lossy(),
                    self.kind.command()
                )),
            )
        };
        for kind in RunKind::ALL {
            let report = self.root.join(kind.report());
            let Some(bytes) = read_regular(&report)? else { continue };
            let files = serde_json::from_slice::<serde_json::Value>(&bytes)
                .ok()
                .and_then(|v| v.get("files").cloned())
                .and_then(|f| serde_json::from_value::<Vec<OutputFile>>(f).ok())
                .ok_or_else(|| {
                    Error::io(
                        &report,
                        std::io::Error::other(
                            "is not a report written by inimtrace (it lists no files), and inimtrace never \
                             deletes a file it did not write: move it away or choose another --out",
                        ),
                    )
                })?;
            if kind != self.kind && !force {
                return Err(other(&report, kind, "the results"));
            }
            found.push((report, files.into_iter().map(Listed::File).collect()));
        }
        let journal_path = self.root.join(JOURNAL_FILE);
        if let Some(bytes) = read_regular(&journal_path)? {
            let journal: Journal = serde_json::from_slice(&bytes).map_err(|_| {
                Error::parse(
                    &journal_path,
                    "is not an inimtrace journal (it cannot be read): remove it or choose another --out",
                )
            })?;
            let kind = RunKind::from_command(&journal.command).ok_or_else(|| {
                Error::parse(&journal_path, format!("names an unknown command {:?}", journal.command))
            })?;
            if kind != self.kind && !force {
                return Err(other(&journal_path, kind, "the files of an interrupted run"));
            }
            found.push((journal_path, journal.files));
        }
        Ok(found)
    }

    /// Removes each previous run's report (or journal) first, so that nothing looks complete,
    /// then every file it listed, and left-over temporary files. Every listed file is checked
    /// first: one whose size or CRC-32 no longer matches its listing was changed since inimtrace
    /// wrote it, and the run is refused (naming it) before anything is removed.
    fn remove_previous_run(&self, force: bool) -> Result<()> {
        let previous = self.previous_runs(force)?;
        // Only plain names inside the folder: a crafted manifest must not reach outside it.
        let plain = |l: &&Listed| is_plain_name(l.name());
        let changed: Vec<(String, String, &PathBuf)> = previous
            .iter()
            .flat_map(|(record, listed)| listed.iter().filter(plain).map(move |l| (l, record)))
            .filter_map(|(l, record)| match l.state(&self.root) {
                ListedState::Changed(why) => Some((l.name().to_string(), why, record)),
                _ => None,
            })
            .collect();
        if let Some((name, why, record)) = changed.first() {
            return Err(Error::io(
                self.root.join(name),
                std::io::Error::other(format!(
                    "{} listed by {} changed since inimtrace wrote {} ({why}); inimtrace deletes only the files \
                     it wrote, unchanged, so {} kept: move {} away or choose another --out",
                    crate::count::count(changed.len(), "file"),
                    record.file_name().unwrap_or_default().to_string_lossy(),
                    if changed.len() == 1 { "it" } else { "them" },
                    if changed.len() == 1 { "it is" } else { "they are all" },
                    if changed.len() == 1 { "it".to_string() } else { format!("them (the first: {name})") },
                )),
            ));
        }
        for (record, listed) in previous {
            match fs::remove_file(&record) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(Error::io(&record, e)),
            }
            remove_page(&self.root);
            for l in listed.iter().filter(plain) {
                if l.state(&self.root) == ListedState::Unchanged {
                    let _ = fs::remove_file(self.root.join(l.name()));
                }
            }
        }
        if let Ok(entries) = fs::read_dir(&self.root) {
            for entry in entries.flatten() {
                if entry.file_name().to_string_lossy().starts_with(TEMP_PREFIX) {
                    remove_temporary(&entry.path());
                }
            }
        }
        // The folder can be written (before any long computation).
        let probe = self.root.join(".inimtrace-write-test");
        write_atomic(&probe, |p| fs::write(p, b"").map_err(|e| Error::io(p, e)))?;
        let _ = fs::remove_file(probe);
        Ok(())
    }
}

/// The page of the run (`report.html`, built from its report after it), removed with the report
/// it was built from: only a regular file that inimtrace wrote (it names inimtrace as its
/// generator), so no page describes results that are gone.
fn remove_page(root: &Path) {
    let page = root.join("report.html");
    if let Ok(Some(bytes)) = read_regular(&page) {
        if bytes.windows(PAGE_MARK.len()).take(2048).any(|w| w == PAGE_MARK.as_bytes()) {
            let _ = fs::remove_file(&page);
        }
    }
}

/// What every `report.html` of inimtrace holds near its start.
pub const PAGE_MARK: &str = "<meta name=\"generator\" content=\"inimtrace\">";

/// Writes the single file `path` atomically: `write` gets a path of the same name in a new
/// private hidden folder beside it (a file created there new, never through a link) and must
/// leave a complete file there, which is then renamed to `path`. On error nothing appears under
/// `path` and the temporary folder is removed. A `path` that exists and is not a regular file (a
/// symbolic link, a FIFO, a directory) is refused, before `write` runs and again before the rename.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    refuse_if_not_a_file(path)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let folder = private_folder(path)?;
    let temp = folder.join(&name);
    let result = fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(&temp)
        .map_err(|e| Error::io(&temp, e))
        .and_then(|_| write(&temp))
        .and_then(|_| refuse_if_not_a_file(&temp))
        .and_then(|_| refuse_if_not_a_file(path))
        .and_then(|_| fs::rename(&temp, path).map_err(|e| Error::io(path, e)));
    remove_temporary(&folder);
    // Errors name the file the user asked for, not the temporary one.
    result.map_err(|e| rename_in_error(e, &temp, path))
}

/// Creates a new private folder (mode 0700, a random name that did not exist) beside `path`.
fn private_folder(path: &Path) -> Result<PathBuf> {
    let mut last = None;
    for _ in 0..16 {
        let folder = path.with_file_name(format!("{TEMP_PREFIX}{:016x}", random_u64()));
        match fs::DirBuilder::new().mode(0o700).create(&folder) {
            Ok(()) => return Ok(folder),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(Error::io(path, e)),
        }
    }
    Err(Error::io(path, last.unwrap_or_else(|| std::io::Error::other("no free temporary name"))))
}

/// An unpredictable 64-bit number: the process id, the time and a counter, hashed with the
/// standard library's randomly keyed SipHash (its keys come from the operating system).
fn random_u64() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u32(std::process::id());
    h.write_u128(std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos()));
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    h.finish()
}

/// Removes a temporary entry without following it: a folder with what is in it, else the entry.
fn remove_temporary(path: &Path) {
    match fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => {
            let _ = fs::remove_dir_all(path);
        }
        Ok(_) => {
            let _ = fs::remove_file(path);
        }
        Err(_) => {}
    }
}

fn refusal(path: &Path, what: &str) -> Error {
    Error::io(
        path,
        std::io::Error::other(format!(
            "is {what}, where inimtrace writes a regular file (it never follows links or writes \
             through special files in its output): remove it or choose another output"
        )),
    )
}

/// The refusal of `path` if it exists and is not a regular file.
fn not_a_file_error(path: &Path) -> Option<Error> {
    let meta = fs::symlink_metadata(path).ok()?;
    (!meta.is_file()).then(|| refusal(path, file_kind(&meta.file_type())))
}

/// Refuses `path` if it exists and is not a regular file (a link is not followed).
pub fn refuse_if_not_a_file(path: &Path) -> Result<()> {
    not_a_file_error(path).map_or(Ok(()), Err)
}

/// Refuses every entry of the folder `root` that a run may write or read (the lock, a plain name
/// with an output extension) and that is not a regular file.
fn refuse_outputs_that_are_not_files(root: &Path) -> Result<()> {
    let entries = fs::read_dir(root).map_err(|e| Error::io(root, e))?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let output_like = name == LOCK_FILE
            || (is_plain_name(&name)
                && Path::new(&name).extension().is_some_and(|x| OUTPUT_EXTENSIONS.iter().any(|o| x == *o)));
        if output_like {
            refuse_if_not_a_file(&entry.path())?;
        }
    }
    Ok(())
}

/// Opens `path` for reading without following a link or blocking on a FIFO; anything but a
/// regular file is refused with its name.
pub fn open_regular(path: &Path) -> Result<File> {
    let file = fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| not_a_file_error(path).unwrap_or_else(|| Error::io(path, e)))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(refusal(path, file_kind(&meta.file_type())));
    }
    Ok(file)
}

/// The bytes of the regular file `path` (see [`open_regular`]); `None` when it does not exist.
pub fn read_regular(path: &Path) -> Result<Option<Vec<u8>>> {
    let mut file = match open_regular(path) {
        Ok(f) => f,
        Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e),
    };
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    Ok(Some(bytes))
}

fn rename_in_error(e: Error, temp: &Path, path: &Path) -> Error {
    let temp_text = temp.display().to_string();
    match e {
        Error::Io { path: p, source } if p == temp => Error::Io { path: path.to_path_buf(), source },
        Error::Parse { path: p, message } if p == temp => Error::Parse { path: path.to_path_buf(), message },
        Error::Invalid { source_name, field, message } if source_name == temp_text => {
            Error::Invalid { source_name: path.display().to_string(), field, message }
        }
        other => other,
    }
}

/// A file name without directories, `..` or a leading dot: the names a run writes.
pub fn is_plain_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_appear_only_when_complete_and_are_listed() {
        let dir = tempfile::tempdir().unwrap();
        let out = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap();
        out.write_bytes("a.txt", b"hello").unwrap();
        let err = out.write_with("b.txt", |p| {
            fs::write(p, b"half").unwrap();
            Err(Error::Mismatch("disk full".into()))
        });
        assert!(err.is_err());
        assert!(!dir.path().join("b.txt").exists(), "a failed write left a final-named file");
        let names: Vec<String> =
            fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        assert!(names.iter().all(|n| !n.starts_with(TEMP_PREFIX)), "temporary file left: {names:?}");
        let m = out.manifest();
        assert_eq!(m.len(), 1);
        assert_eq!(m[0], OutputFile { name: "a.txt".into(), bytes: 5, crc32: "3610a686".into() });
        verify(dir.path(), &m).unwrap();
        fs::write(dir.path().join("a.txt"), b"hellO").unwrap();
        assert!(verify(dir.path(), &m).is_err());
    }

    #[test]
    fn a_second_run_into_the_folder_fails_at_once_naming_the_holder() {
        let dir = tempfile::tempdir().unwrap();
        let first = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap();
        let e = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap_err().to_string();
        assert!(e.contains("in use by inimtrace process") && e.contains(&std::process::id().to_string()), "{e}");
        drop(first);
        OutputDir::open(dir.path(), RunKind::Assess, false).unwrap();
    }

    #[test]
    fn a_new_run_removes_the_previous_runs_files_and_report() {
        let dir = tempfile::tempdir().unwrap();
        let out = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap();
        out.write_bytes("old.exr", b"x").unwrap();
        out.finish("results.json", |files| Ok(serde_json::to_vec(&serde_json::json!({ "files": files })).unwrap()))
            .unwrap();
        fs::write(dir.path().join("users-notes.txt"), b"keep").unwrap();
        fs::write(dir.path().join(format!("{TEMP_PREFIX}1-x.exr")), b"partial").unwrap();
        let _again = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap();
        assert!(!dir.path().join("results.json").exists());
        assert!(!dir.path().join("old.exr").exists());
        assert!(!dir.path().join(format!("{TEMP_PREFIX}1-x.exr")).exists());
        assert!(dir.path().join("users-notes.txt").exists(), "a file no run wrote was removed");
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut n: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        n.sort();
        n
    }

    fn report(files: &[OutputFile]) -> Result<Vec<u8>> {
        Ok(serde_json::to_vec(&serde_json::json!({ "files": files })).unwrap())
    }

    #[test]
    fn another_commands_folder_is_refused_and_kept_unless_forced() {
        let dir = tempfile::tempdir().unwrap();
        let out = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap();
        out.write_bytes("sim_LC_Near.exr", b"x").unwrap();
        out.finish(RunKind::Assess.report(), report).unwrap();
        fs::write(dir.path().join("notes.txt"), b"mine").unwrap();
        let before = names(dir.path());
        assert_eq!(before, ["notes.txt", "results.json", "sim_LC_Near.exr"], "the lock stayed behind: {before:?}");
        let e = OutputDir::open(dir.path(), RunKind::Resolution, false).unwrap_err().to_string();
        assert!(e.contains("`inimtrace assess`") && e.contains("results.json") && e.contains("--force"), "{e}");
        assert_eq!(names(dir.path()), before, "a refused run changed the folder");
        // Forced: only what the first run's manifest listed goes.
        let forced = OutputDir::open(dir.path(), RunKind::Resolution, true).unwrap();
        forced.write_bytes("mtf.csv", b"m").unwrap();
        forced.finish(RunKind::Resolution.report(), report).unwrap();
        assert_eq!(names(dir.path()), ["mtf.csv", "notes.txt", "study.json"]);
        // And back: assess refuses the resolution folder.
        let e = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap_err().to_string();
        assert!(e.contains("`inimtrace resolution`") && e.contains("study.json"), "{e}");
    }

    #[test]
    fn a_report_inimtrace_did_not_write_is_refused_and_never_deleted() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("results.json"), b"{\"my\": \"data\"}").unwrap();
        for force in [false, true] {
            let e = OutputDir::open(dir.path(), RunKind::Assess, force).unwrap_err().to_string();
            assert!(e.contains("results.json") && e.contains("not a report written by inimtrace"), "{e}");
            assert_eq!(fs::read(dir.path().join("results.json")).unwrap(), b"{\"my\": \"data\"}");
        }
    }

    #[test]
    fn an_interrupted_runs_files_are_removed_by_the_next_run_of_its_command_only() {
        let dir = tempfile::tempdir().unwrap();
        {
            let out = OutputDir::open(dir.path(), RunKind::Resolution, false).unwrap();
            out.write_bytes("mtf.csv", b"m").unwrap();
            out.write_bytes("mtf.png", b"p").unwrap();
            // Dropped without a report: an interrupted run.
        }
        fs::write(dir.path().join("notes.txt"), b"mine").unwrap();
        assert_eq!(names(dir.path()), [JOURNAL_FILE, "mtf.csv", "mtf.png", "notes.txt"]);
        let e = OutputDir::open(dir.path(), RunKind::Assess, false).unwrap_err().to_string();
        assert!(e.contains("interrupted") && e.contains("`inimtrace resolution`"), "{e}");
        let again = OutputDir::open(dir.path(), RunKind::Resolution, false).unwrap();
        assert_eq!(names(dir.path()), [LOCK_FILE, "notes.txt"]);
        drop(again);
        assert_eq!(names(dir.path()), ["notes.txt"]);
    }

    #[test]
    fn manifests_cannot_reach_outside_the_folder() {
        assert!(is_plain_name("sim_LC_Near.exr"));
        for bad in ["../x", "/etc/passwd", "a/b", "", ".hidden", "..", "a\\b"] {
            assert!(!is_plain_name(bad), "{bad}");
        }
    }
}
