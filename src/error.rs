//! The library's error type. Every error that comes from user input names the file and, where
//! it applies, the field, line or element. Each kind of failure is its own variant with the
//! parts it names as fields (file, field, cause), so callers (the Python exceptions among them)
//! decide by variant, never by reading the message; a file that fails to load because of a file
//! it names keeps the inner error whole ([`Error::Load`]).

use std::path::{Path, PathBuf};

/// An error of the library: what went wrong, with the file, field and cause it concerns.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },

    /// A file was read but its content is malformed (syntax, wrong type, truncated data).
    /// `message` says where (line, field or element) and what.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where in the file (line, field or element) and what is wrong.
        message: String,
    },

    /// A value is present and well-formed but physically or logically impossible.
    /// `source_name` is a file path or a description such as "built-in display".
    #[error("{source_name}: field `{field}`: {message}")]
    Invalid {
        /// The file, or what stands for one (`command line`, `built-in display`, `Eye()`).
        source_name: String,
        /// The field (a key path such as `eye.pupil_diameter`, or a flag such as `--threads`).
        field: String,
        /// What is wrong with its value.
        message: String,
    },

    /// A file named by a field of another file (or of the command line) could not be loaded:
    /// the inner error, whole, with the field that named the file.
    #[error("{source_name}: field `{field}`: cannot load `{reference}`: {source}")]
    Load {
        /// The file (or command line) whose field names the file.
        source_name: String,
        /// The field naming it.
        field: String,
        /// The file as the field names it.
        reference: String,
        /// Why it could not be loaded.
        source: Box<Error>,
    },

    /// A file named by a field of another file could not be loaded, said in the inner error's
    /// own words after the field (as for a mesh object's `file`, whose mesh errors name the
    /// mesh file and its line or element themselves).
    #[error("{source_name}: field `{field}`: {source}")]
    InField {
        /// The file whose field names the other file.
        source_name: String,
        /// The field naming it.
        field: String,
        /// The inner error.
        source: Box<Error>,
    },

    /// An optical configuration for which the requested computation has no answer.
    #[error("singular configuration: {0}")]
    Singular(String),

    /// A lattice whose pitch matrix cannot describe one (singular or not finite).
    #[error("{source_name}: field `{field}`: {message}")]
    Lattice {
        /// The display file, or what stands for one.
        source_name: String,
        /// The pitch field.
        field: String,
        /// The matrix and what is wrong with it.
        message: String,
    },

    /// An error reported by Intel Embree (code and message from its error callback).
    #[error("Embree error {code}: {message}")]
    Embree {
        /// The name of Embree's error code (`RTC_ERROR_...`).
        code: String,
        /// Embree's message, with the API call that failed.
        message: String,
    },

    /// A large buffer the system would not allocate (the memory budget let it through, but the
    /// memory was not there): what it was for and its size.
    #[error("{0}")]
    Alloc(String),

    /// Settings or inputs whose estimated memory exceeds the memory budget (`--max-memory` and the
    /// system's limits, `crate::budget`), refused before anything was allocated: the field whose
    /// value makes the largest part, and the estimate against the limit.
    #[error("{source_name}: field `{field}`: {message}")]
    Memory {
        /// The file, or what stands for one (`command line`, `simulate()`).
        source_name: String,
        /// The setting that makes the largest part of the estimate.
        field: String,
        /// The estimate, the limit and the largest part.
        message: String,
    },

    /// The caller cancelled the run through its progress sink (`crate::progress::ProgressSink::cancelled`,
    /// the Python package's Ctrl-C): the work stopped early and its results were discarded.
    #[error("cancelled")]
    Cancelled,

    /// A scene that the chosen intersection backend cannot render (`--backend`).
    #[error("{message}")]
    Backend {
        /// The scene's name.
        scene: String,
        /// What the backend cannot do and which backend to use instead.
        message: String,
    },

    /// A file whose format is not known from its name.
    #[error("{}: unknown {kind} format (expected {expected})", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// What kind of file it should be (`mesh`).
        kind: &'static str,
        /// The formats that are known, as the user would name them.
        expected: &'static str,
    },

    /// Data given to a library function does not fit the rest of its arguments (an image of
    /// another size than the display's LCD, a stack of other images): a caller's mistake, not a
    /// file's.
    #[error("{0}")]
    Mismatch(String),

    /// A result could not be expressed in its output format (JSON, TOML).
    #[error("cannot {what}: {message}")]
    Serialize {
        /// What was being done (`serialise the report`, `hash settings`).
        what: String,
        /// The serialiser's message.
        message: String,
    },

    /// A plot, figure or text label could not be drawn.
    #[error("{target}: cannot draw {what}: {message}")]
    Draw {
        /// The file being drawn.
        target: String,
        /// What was being drawn (`plot`, `montage labels`).
        what: &'static str,
        /// The drawing library's message, with what to install where that is the cause.
        message: String,
    },

    /// An external program (Slurm's `sbatch` or `squeue`) could not be run or failed, or the
    /// process's own environment (its executable, its folder) could not be read.
    #[error("{message}")]
    External {
        /// The program or the environment item (`sbatch`, `squeue`, `current_exe`).
        program: &'static str,
        /// What happened and what to do about it.
        message: String,
    },

    /// A distributed run ended without all of its work done (Slurm tasks that failed, timed out
    /// or were cancelled).
    #[error("{0}")]
    Incomplete(String),
}

/// The library's result type.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// An [`Error::Io`] for `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io { path: path.as_ref().to_path_buf(), source }
    }
    /// An [`Error::Parse`] for `path`.
    pub fn parse(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Parse { path: path.as_ref().to_path_buf(), message: message.into() }
    }
    /// An [`Error::Invalid`] naming the source and the field.
    pub fn invalid(source_name: impl Into<String>, field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid { source_name: source_name.into(), field: field.into(), message: message.into() }
    }
    /// An [`Error::Load`]: `source_name`'s field `field` names `reference`, which failed with `source`.
    pub fn load(
        source_name: impl Into<String>,
        field: impl Into<String>,
        reference: impl Into<String>,
        source: Error,
    ) -> Self {
        Error::Load {
            source_name: source_name.into(),
            field: field.into(),
            reference: reference.into(),
            source: Box::new(source),
        }
    }
    /// An [`Error::InField`]: `source_name`'s field `field` led to `source`.
    pub fn in_field(source_name: impl Into<String>, field: impl Into<String>, source: Error) -> Self {
        Error::InField { source_name: source_name.into(), field: field.into(), source: Box::new(source) }
    }
    /// An [`Error::Serialize`]: `what` could not be done (`serialise the report`).
    pub fn serialize(what: impl Into<String>, message: impl std::fmt::Display) -> Self {
        Error::Serialize { what: what.into(), message: message.to_string() }
    }
    /// An [`Error::Draw`] of `what` into `target`.
    pub fn draw(target: impl std::fmt::Display, what: &'static str, message: impl std::fmt::Display) -> Self {
        Error::Draw { target: target.to_string(), what, message: message.to_string() }
    }

    /// The error at the bottom of a chain of [`Error::Load`] and [`Error::InField`]: the one that
    /// says what was wrong.
    pub fn innermost(&self) -> &Error {
        match self {
            Error::Load { source, .. } | Error::InField { source, .. } => source.innermost(),
            e => e,
        }
    }

    /// The file (or what stands for one) and the field the error names, outermost first: the
    /// file the user gave and the field in it.
    pub fn source_and_field(&self) -> (Option<String>, Option<String>) {
        match self {
            Error::Io { path, .. } | Error::Parse { path, .. } | Error::UnknownFormat { path, .. } => {
                (Some(path.display().to_string()), None)
            }
            Error::Invalid { source_name, field, .. }
            | Error::Memory { source_name, field, .. }
            | Error::Lattice { source_name, field, .. }
            | Error::Load { source_name, field, .. }
            | Error::InField { source_name, field, .. } => (Some(source_name.clone()), Some(field.clone())),
            _ => (None, None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_load_error_reads_as_the_wrapped_message_did_and_keeps_its_cause() {
        let inner = Error::parse("mesh.obj", "line 3: bad face");
        let e = Error::load("exp.toml", "scene", "s.toml", Error::in_field("s.toml", "objects[0].file", inner));
        assert_eq!(
            e.to_string(),
            "exp.toml: field `scene`: cannot load `s.toml`: s.toml: field `objects[0].file`: mesh.obj: line 3: bad face"
        );
        assert!(matches!(e.innermost(), Error::Parse { path, .. } if path == Path::new("mesh.obj")));
        assert_eq!(e.source_and_field(), (Some("exp.toml".into()), Some("scene".into())));
        assert!(std::error::Error::source(&e).is_some(), "the chain is visible to std::error::Error");
    }
}
