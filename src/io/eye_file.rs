//! A user-defined schematic eye read from a TOML file's `[eye.user]` table (the table an
//! experiment or a study holds, [`crate::optics::eye::user`]), for `info --eye user --eye-file`:
//! any other tables and keys of the file are left alone; errors name the file, the line and
//! the field.

use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::io::text::{read_text, toml_error};
use crate::optics::eye::{EyeModel, UserEye};

/// The file: only its `[eye]` table is read.
#[derive(Deserialize)]
struct EyeFile {
    eye: Option<EyeTable>,
}

/// Its `[eye]` table: only `[eye.user]` is read.
#[derive(Deserialize)]
struct EyeTable {
    user: Option<UserEye>,
}

/// The user eye of `path`'s `[eye.user]` table, validated, as an [`EyeModel`].
pub fn load_user_eye(path: &Path) -> Result<EyeModel> {
    let text = read_text(path)?;
    let file: EyeFile = toml::from_str(&text).map_err(|e| toml_error(path, &text, &e))?;
    let source = path.display().to_string();
    match file.eye.and_then(|e| e.user) {
        Some(user) => EyeModel::parse("user", Some(user), &source),
        None => Err(Error::invalid(source, "eye.user", "the file has no [eye.user] surface table")),
    }
}
