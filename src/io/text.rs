//! Text input shared by every file format: reading a file with its path in the error, TOML
//! errors that name the line, and the directory that relative paths inside a file resolve
//! against. Paths inside a file are relative to that file.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Reads a whole settings text through the input gate ([`crate::io::input::read_settings`]:
/// at most [`crate::io::input::MAX_SETTINGS_BYTES`]), with the path in the error.
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = crate::io::input::read_settings(path)?;
    String::from_utf8(bytes)
        .map_err(|e| Error::parse(path, format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to())))
}

/// A TOML error on one line: `line L, column C: field `table.key`: message`. The file's own
/// lines are never quoted (a file named by mistake, or on purpose, must not have its content
/// echoed): the field is named only when the line is a TOML key-value pair.
pub fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let message = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let start = span.start.min(text.len());
            let line = text[..start].matches('\n').count() + 1;
            let line_start = text[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
            let column = text[line_start..start].chars().count() + 1;
            match field_at(text, line_start) {
                Some(field) => Error::parse(path, format!("line {line}, column {column}: field `{field}`: {message}")),
                None => Error::parse(path, format!("line {line}, column {column}: {message}")),
            }
        }
        None => Error::parse(path, message),
    }
}

/// The key path of the key-value line starting at `line_start` (`eye.pupil_diameter`, with the
/// table above it), when the line is one: a bare or dotted key of at most 100 characters.
fn field_at(text: &str, line_start: usize) -> Option<String> {
    let is_key =
        |k: &str| !k.is_empty() && k.len() <= 100 && k.chars().all(|c| c.is_ascii_alphanumeric() || "_-. ".contains(c));
    let line = text[line_start..].lines().next()?;
    let key = line.split_once('=')?.0.trim();
    if !is_key(key) {
        return None;
    }
    let table = text[..line_start].lines().rev().map(str::trim).find(|l| l.starts_with('[')).and_then(|l| {
        let name = l.trim_start_matches('[').split(']').next()?.trim();
        is_key(name).then_some(name)
    });
    Some(match table {
        Some(t) => format!("{t}.{key}"),
        None => key.to_string(),
    })
}

/// Directory of a file, for resolving relative paths inside it.
pub fn base_dir(path: &Path) -> PathBuf {
    path.parent().map(Path::to_path_buf).unwrap_or_default()
}
