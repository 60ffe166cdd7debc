//! The record of what the input gate (`super::input`) read: while a [`recording`] is active on
//! the thread, the gate notes each file's path (as it was opened) and the SHA-256 (FIPS 180-4)
//! of exactly the bytes it read. The gate writes this log and [`crate::provenance`] reads it, so
//! the input layer knows nothing of provenance records.

use std::cell::RefCell;
use std::path::Path;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// A file a run read.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFile {
    /// The path as it was opened (relative to the working directory of the run, or absolute).
    pub path: String,
    /// SHA-256 of its bytes, 64 hex digits.
    pub sha256: String,
    /// Its size, bytes.
    pub bytes: u64,
}

thread_local! {
    /// The recordings active on this thread, innermost last.
    static RECORDINGS: RefCell<Vec<Vec<InputFile>>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f`, returning with its result every file the input gate read on this thread meanwhile
/// (each once, in the order first read). Recordings nest: an outer one sees the inner one's files.
pub fn recording<T>(f: impl FnOnce() -> T) -> (T, Vec<InputFile>) {
    RECORDINGS.with(|r| r.borrow_mut().push(Vec::new()));
    let out = f();
    let files = RECORDINGS.with(|r| r.borrow_mut().pop()).unwrap_or_default();
    (out, files)
}

/// Notes that the input gate read `bytes` from `path` (nothing when no recording is active).
pub(crate) fn note_read(path: &Path, bytes: &[u8]) {
    let active = RECORDINGS.with(|r| !r.borrow().is_empty());
    if !active {
        return;
    }
    let file = InputFile { path: path.display().to_string(), sha256: sha256_hex(bytes), bytes: bytes.len() as u64 };
    RECORDINGS.with(|r| {
        for level in r.borrow_mut().iter_mut() {
            if !level.iter().any(|f| f.path == file.path) {
                level.push(file.clone());
            }
        }
    });
}

/// SHA-256 of `bytes` as 64 lower-case hex digits.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}
