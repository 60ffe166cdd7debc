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
    let message = plain_message(e.message().trim().replace('\n', " "));
    match e.span() {
        Some(span) => {
            let start = span.start.min(text.len());
            let line = text[..start].matches('\n').count() + 1;
            let line_start = text[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
            let column = text[line_start..start].chars().count() + 1;
            if let Some(key) = message.strip_prefix("missing field `").and_then(|m| m.strip_suffix('`')) {
                // serde points a missing key at the table that lacks it (line 1 for the top level).
                return Error::parse(path, missing_key(text, line_start, key));
            }
            match field_at(text, line_start) {
                Some(field) => Error::parse(path, format!("line {line}, column {column}: field `{field}`: {message}")),
                None => match value_of_key_above(text, line_start) {
                    // An element of a value written over several lines: the key it belongs to.
                    Some((field, key_line)) => Error::parse(
                        path,
                        format!("line {line}, column {column}: field `{field}` (its value starts at line {key_line}): {message}"),
                    ),
                    None => Error::parse(path, format!("line {line}, column {column}: {message}")),
                },
            }
        }
        None => Error::parse(path, message),
    }
}

/// A missing key: named with its table (`[lenslets]`, at its line), or as a top-level key.
fn missing_key(text: &str, line_start: usize, key: &str) -> String {
    let header = text[line_start..].lines().next().unwrap_or("").trim();
    let table = header.strip_prefix('[').and_then(|h| h.trim_start_matches('[').split(']').next()).map(str::trim);
    match table {
        Some(t) if !t.is_empty() => {
            let line = text[..line_start].matches('\n').count() + 1;
            format!("missing field `{t}.{key}` (the table [{t}] at line {line} has no `{key}` key)")
        }
        _ => format!("missing field `{key}` (a top-level key, before any [table])"),
    }
}

/// A serde message in the words of the settings: the form a value must take instead of a Rust
/// type (`usize`, `untagged enum PitchSpec`).
fn plain_message(message: String) -> String {
    const FORMS: [(&str, &str); 3] = [
        ("PitchSpec", "a pitch in mm: a number (square), [x, y] (rectangular) or a row-major matrix [[a, b], [c, d]]"),
        ("Values", "a list of numbers [a, b, ...] or a range { from, to, step }"),
        ("MaterialSpec", "a material name (\"pmma\", \"n-bk7\") or a dispersion formula table"),
    ];
    if let Some(name) = message.strip_prefix("data did not match any variant of untagged enum ") {
        let form =
            FORMS.iter().find(|(n, _)| *n == name.trim()).map_or("one of the forms the documentation lists", |f| f.1);
        return format!("expected {form}");
    }
    let mut m = message;
    for (rust, words) in [
        ("usize", "a whole number, 0 or more"),
        ("u64", "a whole number, 0 or more"),
        ("u32", "a whole number, 0 or more"),
        ("u16", "a whole number, 0 or more"),
        ("u8", "a whole number, 0 or more"),
        ("i64", "a whole number"),
        ("i32", "a whole number"),
        ("f64", "a number"),
        ("f32", "a number"),
    ] {
        if let Some(head) = m.strip_suffix(&format!("expected {rust}")) {
            m = format!("{head}expected {words}");
        }
    }
    for (rust, words) in
        [("expected struct ", "expected a table"), ("expected enum ", "expected one of the documented values")]
    {
        if let Some(i) = m.find(rust) {
            m = format!("{}{words}", &m[..i]);
        }
    }
    for (serde, words) in [
        ("invalid type: sequence", "invalid type: a list"),
        ("invalid type: map", "invalid type: a table"),
        ("expected a sequence", "expected a list [a, b, ...]"),
        ("expected a map", "expected a table"),
    ] {
        m = m.replace(serde, words);
    }
    m.replace("floating point `", "number `")
}

/// The key whose value (a list or inline table written over several lines) holds the line
/// starting at `line_start`, and that key's line: the nearest key-value line above whose
/// brackets are still open at `line_start` (strings holding brackets aside, which settings
/// values do not). `None` when a table header or a closed value comes first.
fn value_of_key_above(text: &str, line_start: usize) -> Option<(String, usize)> {
    let mut depth = 0i64;
    let mut start = line_start;
    for _ in 0..10_000 {
        if start == 0 {
            return None;
        }
        let prev = text[..start - 1].rfind('\n').map_or(0, |i| i + 1);
        let line = text[prev..start - 1].split('#').next().unwrap_or("");
        depth += line.matches(['[', '{']).count() as i64 - line.matches([']', '}']).count() as i64;
        let header = line.trim().trim_start_matches('[').trim_end_matches(']');
        if line.trim().starts_with('[')
            && header.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_' || c == '"')
            && !header.contains([',', '='])
        {
            return None; // a [table] header
        }
        if line.contains('=') {
            let field = field_at(text, prev)?;
            let key_line = text[..prev].matches('\n').count() + 1;
            return (depth > 0).then_some((field, key_line));
        }
        start = prev;
    }
    None
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
