//! Opening the files a user names (experiment, scene, display, mesh, texture, EXR): only
//! regular files, so a FIFO, a device or a folder given by mistake is an error naming it
//! instead of a read that blocks forever or never ends.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};

/// Checks that `path` is a regular file (after following links) and returns its size in bytes.
pub fn check_regular(path: &Path) -> Result<u64> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_file() {
        return Ok(meta.len());
    }
    let what = if meta.is_dir() { "a directory" } else { "not a regular file (a FIFO, socket or device)" };
    Err(Error::io(path, std::io::Error::other(format!("is {what}; expected a file"))))
}

/// Opens a regular file for reading ([`check_regular`] first, so nothing blocks).
pub fn open_regular(path: &Path) -> Result<(File, u64)> {
    let size = check_regular(path)?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    Ok((file, size))
}

/// Reads a whole regular file.
pub fn read_regular(path: &Path) -> Result<Vec<u8>> {
    let (mut file, size) = open_regular(path)?;
    let mut bytes = Vec::with_capacity(size as usize);
    file.read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_and_fifos_are_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_regular(dir.path()).unwrap_err().to_string();
        assert!(e.contains("directory") && e.contains(&dir.path().display().to_string()), "{e}");
        let fifo = dir.path().join("mesh.obj");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false);
        if made {
            let e = read_regular(&fifo).unwrap_err().to_string();
            assert!(e.contains("FIFO") && e.contains("mesh.obj"), "{e}");
        }
        let file = dir.path().join("a.txt");
        std::fs::write(&file, b"abc").unwrap();
        assert_eq!(read_regular(&file).unwrap(), b"abc");
        let e = read_regular(&dir.path().join("missing.toml")).unwrap_err().to_string();
        assert!(e.contains("missing.toml"), "{e}");
    }
}
