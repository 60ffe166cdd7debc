//! The input gate: every file inimtrace reads as input (experiment, sweep, study, scene and
//! display files, meshes, the files a mesh names (glTF buffers and images, OBJ `mtllib` and
//! `map_Kd`), textures, bar lists, EXR images, and files named by `--set`) is opened here, and
//! read through the handle it checked (no reader opens an input by its path again; OpenEXR
//! files are read whole and parsed from memory, `io::exr_file`). What it reads is noted in its
//! log (`io::input_log`), the provenance of a run.
//!
//! * Only regular files: a FIFO, socket, device (`/dev/zero`) or folder is refused with its
//!   name. The file is opened without blocking and checked through its own handle, so nothing
//!   can be swapped in between the check and the read.
//! * Nothing under `/proc` or `/sys` (by path after links, and by the device the handle is on): their files claim a size of zero and hold the process's and the machine's state.
//! * A byte limit: a file larger than the memory budget ([`crate::budget::memory_budget`]) is
//!   refused before it is read, and no read goes past the size the file had when opened. Settings
//!   texts (TOML, YAML, bar lists) have a tighter limit, [`MAX_SETTINGS_BYTES`]: parsing TOML
//!   takes about 25 times the text's size in memory, and no real settings file comes near it.
//! * [`Reach`]: where the files a scene names may be. A reference is resolved against the
//!   folder of the file that names it; an absolute path, or one that leaves the scene file's
//!   folder (by `..` or through a link), is refused unless the scene sets
//!   `allow_outside_paths = true`, and the refusal says so.

use std::fs::File;
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};

/// The file systems whose files are the kernel's state, not data: `proc` and `sysfs`.
const SYSTEM_ROOTS: [&str; 2] = ["/proc", "/sys"];

fn refuse(path: &Path, why: impl Into<String>) -> Error {
    Error::io(path, std::io::Error::other(why.into()))
}

/// Refuses a path that leads (after links) into `/proc` or `/sys`.
fn refuse_system_path(path: &Path) -> Result<()> {
    let real = std::fs::canonicalize(path).map_err(|e| Error::io(path, e))?;
    match SYSTEM_ROOTS.iter().find(|root| real.starts_with(root)) {
        Some(root) => Err(refuse(path, format!("is in {root}, which holds system state, not input files; refused"))),
        None => Ok(()),
    }
}

/// What a non-regular file is, for its refusal (the one wording the input gate and the output
/// folder share).
pub(crate) fn file_kind(t: &std::fs::FileType) -> &'static str {
    if t.is_symlink() {
        "a symbolic link"
    } else if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device (like /dev/zero)"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Opens `path` through the gate (see the module comment, less the byte limit): returns the
/// open file and its size in bytes.
pub fn open_regular(path: &Path) -> Result<(File, u64)> {
    refuse_system_path(path)?;
    // O_NONBLOCK: opening a FIFO with no writer returns at once instead of waiting for one.
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(refuse(path, format!("is {}; expected a regular file", file_kind(&meta.file_type()))));
    }
    if on_system_fs(&meta) {
        return Err(refuse(path, "is on /proc or /sys, which hold system state, not input files; refused"));
    }
    Ok((file, meta.len()))
}

/// Whether an open file is on the file system of `/proc` or `/sys` (a bind mount elsewhere
/// included): the same device number.
fn on_system_fs(meta: &std::fs::Metadata) -> bool {
    SYSTEM_ROOTS.iter().any(|root| std::fs::metadata(root).is_ok_and(|m| m.dev() == meta.dev()))
}

/// The most bytes an input file may have: the memory budget, since it is read whole.
fn byte_limit() -> crate::budget::Budget {
    crate::budget::memory_budget()
}

/// The most bytes a settings text (experiment, study, sweep, scene or display file, bar list)
/// may have: 1 MiB, about 20,000 eye cases. Its TOML parse needs about 25 times that in memory
/// (the parser's tokens and events), so a larger file is refused before it is read.
pub const MAX_SETTINGS_BYTES: u64 = 1 << 20;

/// Reads a whole file through the gate: a regular file outside `/proc` and `/sys`, no larger
/// than the memory budget, read no further than the size it had when opened.
pub fn read_regular(path: &Path) -> Result<Vec<u8>> {
    let (file, size) = open_regular(path)?;
    let limit = byte_limit();
    if size > limit.bytes {
        return Err(refuse(
            path,
            format!("is {}, more than the memory budget of {limit}; refused", crate::budget::Bytes(size)),
        ));
    }
    read_open(path, file, size)
}

/// Reads a whole settings text through the gate, refusing one over [`MAX_SETTINGS_BYTES`].
pub fn read_settings(path: &Path) -> Result<Vec<u8>> {
    let (file, size) = open_regular(path)?;
    if size > MAX_SETTINGS_BYTES {
        return Err(refuse(
            path,
            format!(
                "is {}, more than the {} a settings file may have (its parse needs about 25 times its size \
                 in memory); refused",
                crate::budget::Bytes(size),
                crate::budget::Bytes(MAX_SETTINGS_BYTES)
            ),
        ));
    }
    read_open(path, file, size)
}

/// Reads `size` bytes of an open file, the buffer allocated fallibly.
fn read_open(path: &Path, file: File, size: u64) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(size as usize).map_err(|_| {
        Error::Alloc(format!(
            "cannot allocate {} to read {}: the system refused the memory",
            crate::budget::Bytes(size),
            path.display()
        ))
    })?;
    file.take(size).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    super::input_log::note_read(path, &bytes);
    Ok(bytes)
}

/// Where the files a scene names may be: inside the scene file's folder tree, or anywhere when
/// the scene says `allow_outside_paths = true` (and for a file named on the command line).
#[derive(Clone, Debug)]
pub struct Reach {
    /// The folder (as given, and with links resolved) references must stay in; `None`: anywhere.
    root: Option<(PathBuf, PathBuf)>,
}

impl Reach {
    /// No rule: any path (a scene with `allow_outside_paths = true`).
    pub fn anywhere() -> Self {
        Reach { root: None }
    }

    /// References must stay inside `folder`.
    pub fn within(folder: &Path) -> Self {
        let shown = if folder.as_os_str().is_empty() { PathBuf::from(".") } else { folder.to_path_buf() };
        let real = std::fs::canonicalize(&shown).unwrap_or_else(|_| shown.clone());
        Reach { root: Some((shown, real)) }
    }

    /// The rule a scene sets: `allow` is its `allow_outside_paths`; its folder is `folder`.
    pub fn for_scene(folder: &Path, allow: bool) -> Self {
        if allow {
            Reach::anywhere()
        } else {
            Reach::within(folder)
        }
    }

    /// The file `reference` names when written in a file in folder `dir`: `dir/reference`, or
    /// why it is refused (absolute, or outside the folder, lexically or through a link).
    pub fn resolve(&self, dir: &Path, reference: &Path) -> std::result::Result<PathBuf, String> {
        let joined = dir.join(reference);
        let Some((shown, real_root)) = &self.root else { return Ok(joined) };
        let allow = "a scene may name only files inside its folder unless it sets `allow_outside_paths = true`";
        if reference.has_root() {
            return Err(format!(
                "`{}` is an absolute path, outside the scene's folder `{}`; {allow}",
                reference.display(),
                shown.display()
            ));
        }
        let real_dir = std::fs::canonicalize(if dir.as_os_str().is_empty() { Path::new(".") } else { dir })
            .unwrap_or_else(|_| dir.to_path_buf());
        let lexical = normalize(&real_dir.join(reference));
        let real = std::fs::canonicalize(&joined).ok();
        let inside = lexical.starts_with(real_root) && real.as_ref().is_none_or(|r| r.starts_with(real_root));
        if inside {
            return Ok(joined);
        }
        let how = if lexical.starts_with(real_root) { "leads (through a link)" } else { "leads" };
        Err(format!("`{}` {how} outside the scene's folder `{}`; {allow}", reference.display(), shown.display()))
    }
}

/// `..` and `.` removed lexically from an absolute path.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other.as_os_str()),
        }
    }
    out
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

    #[test]
    fn devices_and_system_files_are_refused_even_through_links() {
        let e = read_regular(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("/dev/zero") && e.contains("character device"), "{e}");
        for p in ["/proc/self/status", "/proc/cpuinfo", "/sys/kernel/mm/transparent_hugepage/enabled"] {
            if Path::new(p).exists() {
                let e = read_regular(Path::new(p)).unwrap_err().to_string();
                assert!(e.contains(p) && e.contains("system state"), "{e}");
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("status.toml");
        std::os::unix::fs::symlink("/proc/self/status", &link).unwrap();
        let e = read_regular(&link).unwrap_err().to_string();
        assert!(e.contains("status.toml") && e.contains("/proc"), "{e}");
        assert!(!e.contains("VmRSS") && !e.contains("Name:"), "{e}");
    }

    #[test]
    fn a_reach_keeps_references_inside_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene");
        std::fs::create_dir_all(scene.join("meshes")).unwrap();
        std::fs::write(scene.join("meshes/a.obj"), b"").unwrap();
        std::fs::write(dir.path().join("secret.txt"), b"").unwrap();
        std::os::unix::fs::symlink(dir.path().join("secret.txt"), scene.join("meshes/link.obj")).unwrap();
        let reach = Reach::within(&scene);
        let meshes = scene.join("meshes");
        assert_eq!(reach.resolve(&meshes, Path::new("a.obj")).unwrap(), meshes.join("a.obj"));
        assert_eq!(reach.resolve(&meshes, Path::new("../meshes/./a.obj")).unwrap(), meshes.join("../meshes/./a.obj"));
        // Missing files inside are not refused here (the read names them).
        assert!(reach.resolve(&meshes, Path::new("missing.obj")).is_ok());
        for (r, says) in [
            ("../../secret.txt", "outside"),
            ("../../../../../../../../etc/hostname", "outside"),
            ("/etc/hostname", "absolute"),
            ("link.obj", "through a link"),
        ] {
            let e = reach.resolve(&meshes, Path::new(r)).unwrap_err();
            assert!(e.contains(says) && e.contains("allow_outside_paths = true") && e.contains(r), "{r}: {e}");
        }
        let anywhere = Reach::for_scene(&scene, true);
        assert_eq!(anywhere.resolve(&meshes, Path::new("/etc/hostname")).unwrap(), PathBuf::from("/etc/hostname"));
    }
}
