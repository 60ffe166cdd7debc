//! Text input shared by every file format: reading a file with its path in the error, TOML
//! errors that name the line, and the directory that relative paths inside a file resolve
//! against. Paths inside a file are relative to that file.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Reads a whole file, with the path in the error.
pub fn read_text(path: &Path) -> Result<String> {
    if path.is_dir() {
        return Err(Error::io(path, std::io::Error::other("is a directory, expected a file")));
    }
    let bytes = crate::io::input::read_regular(path)?;
    String::from_utf8(bytes)
        .map_err(|e| Error::parse(path, format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to())))
}

/// A TOML error on one line: `line L, column C: message (in `the line`)`, plus the table the
/// error is in when toml names it.
pub fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let message = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let start = span.start.min(text.len());
            let line = text[..start].matches('\n').count() + 1;
            let line_start = text[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
            let column = text[line_start..start].chars().count() + 1;
            let snippet = text[line_start..].lines().next().unwrap_or("").trim();
            if snippet.is_empty() {
                Error::parse(path, format!("line {line}, column {column}: {message}"))
            } else {
                Error::parse(path, format!("line {line}, column {column}: {message} (in `{snippet}`)"))
            }
        }
        None => Error::parse(path, message),
    }
}

/// Directory of a file, for resolving relative paths inside it.
pub fn base_dir(path: &Path) -> PathBuf {
    path.parent().map(Path::to_path_buf).unwrap_or_default()
}
