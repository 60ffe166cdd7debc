//! The library's error type. Every error that comes from user input names the file and, where
//! it applies, the field, line or element.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },

    /// A file was read but its content is malformed (syntax, wrong type, truncated data).
    /// `message` says where (line, field or element) and what.
    #[error("{}: {message}", path.display())]
    Parse { path: PathBuf, message: String },

    /// A value is present and well-formed but physically or logically impossible.
    /// `source_name` is a file path or a description such as "built-in display".
    #[error("{source_name}: field `{field}`: {message}")]
    Invalid { source_name: String, field: String, message: String },

    /// An optical configuration for which the requested computation has no answer.
    #[error("singular configuration: {0}")]
    Singular(String),

    /// An error reported by Intel Embree (code and message from its error callback).
    #[error("Embree error {code}: {message}")]
    Embree { code: String, message: String },

    /// A large buffer the system would not allocate (the memory budget let it through, but the
    /// memory was not there): what it was for and its size.
    #[error("{0}")]
    Alloc(String),

    /// A scene that the chosen backend cannot render, or similar mismatch of request and data.
    #[error("{0}")]
    Unsupported(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io { path: path.as_ref().to_path_buf(), source }
    }
    pub fn parse(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Parse { path: path.as_ref().to_path_buf(), message: message.into() }
    }
    pub fn invalid(source_name: impl Into<String>, field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid { source_name: source_name.into(), field: field.into(), message: message.into() }
    }
}
