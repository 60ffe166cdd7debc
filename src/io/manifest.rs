//! The manifest of an output folder: every file a run wrote, listed with its size and CRC-32
//! (IEEE 802.3, the `crc32fast` crate) in the run's report (and, while the run is under way, in
//! its journal). A reader verifies a finished folder against it ([`verify`]), and a later run
//! removes a listed file only when the file still matches its listing ([`Listed::state`]):
//! a file changed since inimtrace wrote it is someone else's now, and is kept.

use std::io::Read;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One complete file of a run, as the manifest lists it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputFile {
    /// Name relative to the output folder.
    pub name: String,
    /// Size, bytes.
    pub bytes: u64,
    /// CRC-32 (IEEE) of the file's bytes, 8 lowercase hex digits.
    pub crc32: String,
}

/// A file as a report or a journal lists it: with its size and CRC-32, or (a journal written by
/// an older inimtrace) by name only, which cannot be checked.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Listed {
    /// Name, size and CRC-32.
    File(OutputFile),
    /// A name alone.
    Name(String),
}

/// What a listed file is on disk now.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ListedState {
    /// Not there (nothing to remove).
    Missing,
    /// The very bytes the listing describes: inimtrace's file, safe to remove.
    Unchanged,
    /// Something else: what differs (kept).
    Changed(String),
}

impl Listed {
    /// The listed name.
    pub fn name(&self) -> &str {
        match self {
            Listed::File(f) => &f.name,
            Listed::Name(n) => n,
        }
    }

    /// The file `root/name` against this listing (never through a link: a link, a FIFO or a
    /// folder under a listed name is not the listed file).
    pub fn state(&self, root: &Path) -> ListedState {
        let path = root.join(self.name());
        match std::fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return ListedState::Missing,
            Err(e) => return ListedState::Changed(e.to_string()),
            Ok(m) if !m.is_file() => return ListedState::Changed("it is not a regular file".into()),
            Ok(_) => {}
        }
        let Listed::File(f) = self else {
            return ListedState::Changed("its listing (by an older inimtrace) gives no size or CRC-32 to check".into());
        };
        match describe(&path, &f.name) {
            Ok(now) if now == *f => ListedState::Unchanged,
            Ok(now) => ListedState::Changed(format!(
                "it has {} bytes and CRC-32 {}, the listing says {} bytes and {}",
                now.bytes, now.crc32, f.bytes, f.crc32
            )),
            Err(e) => ListedState::Changed(e.to_string()),
        }
    }
}

/// Size and CRC-32 of the file at `path`, listed as `name`.
pub fn describe(path: &Path, name: &str) -> Result<OutputFile> {
    let mut file = super::output::open_regular(path)?;
    let mut hasher = crc32fast::Hasher::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buf).map_err(|e| Error::io(path, e))?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        bytes += n as u64;
    }
    Ok(OutputFile { name: name.to_string(), bytes, crc32: format!("{:08x}", hasher.finalize()) })
}

/// Checks a finished folder against the manifest of its report: every listed file exists with
/// its size and CRC-32. Returns the first mismatch as an error.
pub fn verify(root: &Path, files: &[OutputFile]) -> Result<()> {
    for f in files {
        let path = root.join(&f.name);
        let actual = describe(&path, &f.name)?;
        if actual != *f {
            return Err(Error::parse(
                &path,
                format!("does not match the manifest (expected {} bytes, crc32 {})", f.bytes, f.crc32),
            ));
        }
    }
    Ok(())
}
