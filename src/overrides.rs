//! `--set KEY=VALUE`: one setting of the experiment (Sec. 4.1's parameters: the eye, the eye
//! cases, the display, the scene) changed from the command line or by a sweep axis. KEY is a
//! dotted path into the resolved experiment, with `[i]` indexing arrays
//! (`eye.pupil_diameter`, `eye_cases[1].focus_diopters`, `display.lenslets.pitch`,
//! `scene.objects[0].center`); VALUE is in TOML syntax (`3`, `2.5`, `[0, 0, 350]`, `"Near"`,
//! `{ albedo = [1, 1, 1] }`; a bare word such as `framework-8bit` is a string).
//!
//! This file parses overrides and applies them to a TOML value. The result is then
//! deserialized through the same spec types and validation as the files
//! (`src/settings.rs`), so an unknown key or a wrong type is an error there, naming the key.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

/// One step of a key path: a table key or an array index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Segment {
    /// A table key (`eye`, `pupil_diameter`).
    Key(String),
    /// An array index (`[1]`).
    Index(usize),
}

/// `KEY=VALUE`, parsed.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The key as written (`eye_cases[1].focus_diopters`).
    pub key: String,
    /// The key as a path of table keys and array indices.
    pub path: Vec<Segment>,
    /// The value, parsed as TOML.
    pub value: toml::Value,
    /// Directory that a `scene` or `display` set to a file path is relative to: the current
    /// directory for `--set`, the sweep file's folder for a sweep.
    pub base: PathBuf,
    /// Where it was given, for errors: `--set`, or a sweep file and its table.
    pub origin: String,
}

impl Override {
    /// An override of `key` (a dotted, indexed path) with `value`.
    pub fn new(key: &str, value: toml::Value) -> Result<Self, String> {
        Ok(Self {
            key: key.trim().to_string(),
            path: parse_key(key)?,
            value,
            base: PathBuf::new(),
            origin: "--set".into(),
        })
    }

    /// The same override, named as given in `origin` (a sweep file and its table) in errors.
    pub fn from_origin(mut self, origin: impl Into<String>) -> Self {
        self.origin = origin.into();
        self
    }

    /// The same override with paths in its value relative to `base`.
    pub fn relative_to(mut self, base: impl Into<PathBuf>) -> Self {
        self.base = base.into();
        self
    }

    /// The first key of the path (`eye` for `eye.pupil_diameter`).
    pub fn top(&self) -> &str {
        match self.path.first() {
            Some(Segment::Key(k)) => k,
            _ => "",
        }
    }

    /// Sets the value at the path in `root` (a table). Missing tables on the way are created
    /// (an unknown key is then reported when the result is deserialized); an index may point
    /// one past the end of an array to append a whole element. Errors say which part of the
    /// path does not fit the value found there.
    pub fn apply(&self, root: &mut toml::Value) -> Result<(), String> {
        let mut cursor = root;
        let mut walked = String::new();
        for (i, seg) in self.path.iter().enumerate() {
            let last = i + 1 == self.path.len();
            match seg {
                Segment::Key(k) => {
                    let what = describe(cursor);
                    let toml::Value::Table(table) = cursor else {
                        return Err(format!("`{walked}` is {what}, not a table, so it has no key `{k}`"));
                    };
                    if last {
                        table.insert(k.clone(), self.value.clone());
                        return Ok(());
                    }
                    cursor = table.entry(k.clone()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
                    if !walked.is_empty() {
                        walked.push('.');
                    }
                    walked.push_str(k);
                }
                Segment::Index(n) => {
                    let what = describe(cursor);
                    let toml::Value::Array(array) = cursor else {
                        return Err(format!("`{walked}` is {what}, not an array, so it cannot be indexed by [{n}]"));
                    };
                    let len = array.len();
                    if *n == len && last {
                        array.push(self.value.clone());
                        return Ok(());
                    }
                    if *n >= len {
                        let append = if last { format!(" ([{len}] appends an entry)") } else { String::new() };
                        return Err(format!("index [{n}] is out of range: `{walked}` has {len} entries{append}"));
                    }
                    if last {
                        array[*n] = self.value.clone();
                        return Ok(());
                    }
                    cursor = &mut array[*n];
                    walked.push_str(&format!("[{n}]"));
                }
            }
        }
        Err("empty key".into())
    }

    /// `KEY=VALUE` with the value in TOML syntax: the same override when parsed back.
    pub fn to_arg(&self) -> String {
        format!("{}={}", self.key, value_text(&self.value))
    }
}

impl FromStr for Override {
    type Err = String;

    /// Parses `KEY=VALUE` (the first `=` separates them).
    fn from_str(text: &str) -> Result<Self, String> {
        let Some((key, value)) = text.split_once('=') else {
            return Err(format!("`{text}`: expected KEY=VALUE, e.g. eye.pupil_diameter=3"));
        };
        let value = parse_value(value).map_err(|e| format!("`{text}`: {e}"))?;
        Self::new(key, value).map_err(|e| format!("`{text}`: {e}"))
    }
}

impl fmt::Display for Override {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_arg())
    }
}

/// Parses a key path: names of letters, digits, `_` and `-` separated by `.`, each followed by
/// any number of `[index]`.
pub fn parse_key(key: &str) -> Result<Vec<Segment>, String> {
    let key = key.trim();
    if key.is_empty() {
        return Err("empty key".into());
    }
    let mut path = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
            return Err(format!(
                "key `{key}`: `{part}` is not a name (letters, digits, _ and -, then optional [index])"
            ));
        }
        path.push(Segment::Key(name.to_string()));
        while !rest.is_empty() {
            let close = rest.find(']').filter(|_| rest.starts_with('['));
            let Some(close) = close else {
                return Err(format!("key `{key}`: expected [index] after `{name}`, found `{rest}`"));
            };
            let index: usize = rest[1..close]
                .trim()
                .parse()
                .map_err(|_| format!("key `{key}`: `{}` is not an array index", &rest[..=close]))?;
            path.push(Segment::Index(index));
            rest = &rest[close + 1..];
        }
    }
    Ok(path)
}

/// Parses a value in TOML syntax. A bare word that is not TOML (`framework-8bit`, `LC`,
/// `scenes/bunny.toml`) is taken as a string.
pub fn parse_value(text: &str) -> Result<toml::Value, String> {
    let trimmed = text.trim();
    if trimmed.is_empty() {
        return Err("missing value after `=`".into());
    }
    match format!("value = {trimmed}").parse::<toml::Table>() {
        Ok(mut t) if t.len() == 1 => return Ok(t.remove("value").expect("one key")),
        Ok(_) => {}
        Err(e) => {
            let digits = trimmed.strip_prefix(['+', '-']).unwrap_or(trimmed);
            if digits.starts_with(|c: char| c.is_ascii_digit())
                && digits.bytes().all(|b| b.is_ascii_digit() || b == b'_')
            {
                return Err(format!(
                    "`{trimmed}` is an integer out of range (integers are 64-bit: {} to {})",
                    i64::MIN,
                    i64::MAX
                ));
            }
            let bare = !trimmed.contains(|c: char| "[]{}\"'=,#".contains(c) || c.is_whitespace());
            if bare {
                return Ok(toml::Value::String(trimmed.to_string()));
            }
            return Err(format!("`{trimmed}` is not a TOML value: {}", e.message().trim()));
        }
    }
    Err(format!("`{trimmed}` is not a single TOML value"))
}

/// A value in TOML syntax on one line (`2.5`, `"Near"`, `[0, 0, 350]`).
pub fn value_text(v: &toml::Value) -> String {
    match v {
        // Whole floats keep their `.0`: written back they must still be floats.
        toml::Value::Float(f) if f.is_finite() && f.fract() == 0.0 && f.abs() < 1e15 => format!("{f:.1}"),
        other => other.to_string(),
    }
}

/// "a number", "an array", ...: what a value is, for errors.
fn describe(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("a string (\"{s}\")"),
        toml::Value::Integer(i) => format!("a number ({i})"),
        toml::Value::Float(f) => format!("a number ({f})"),
        toml::Value::Boolean(b) => format!("a boolean ({b})"),
        toml::Value::Datetime(d) => format!("a date ({d})"),
        toml::Value::Array(_) => "an array".into(),
        toml::Value::Table(_) => "a table".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(text: &str) -> toml::Value {
        toml::Value::Table(text.parse::<toml::Table>().unwrap())
    }

    #[test]
    fn keys_parse_into_names_and_indices() {
        assert_eq!(
            parse_key("scene.objects[0].center").unwrap(),
            vec![
                Segment::Key("scene".into()),
                Segment::Key("objects".into()),
                Segment::Index(0),
                Segment::Key("center".into())
            ]
        );
        assert_eq!(parse_key("a[1][2]").unwrap(), vec![Segment::Key("a".into()), Segment::Index(1), Segment::Index(2)]);
        for bad in ["", "a..b", "a.", ".a", "a[", "a[x]", "a[-1]", "a]b", "[0]", "a b", "a[0]b"] {
            assert!(parse_key(bad).is_err(), "{bad:?} parsed");
        }
    }

    #[test]
    fn values_are_toml_and_bare_words_are_strings() {
        assert_eq!(parse_value("3").unwrap(), toml::Value::Integer(3));
        assert_eq!(parse_value(" 2.5 ").unwrap(), toml::Value::Float(2.5));
        assert_eq!(parse_value("[0, 0, 350]").unwrap().as_array().unwrap().len(), 3);
        assert_eq!(parse_value("\"Near\"").unwrap(), toml::Value::String("Near".into()));
        assert_eq!(parse_value("framework-8bit").unwrap(), toml::Value::String("framework-8bit".into()));
        assert_eq!(parse_value("true").unwrap(), toml::Value::Boolean(true));
        assert_eq!(parse_value("{ albedo = [1, 1, 1] }").unwrap().as_table().unwrap().len(), 1);
        assert!(parse_value("").is_err());
        assert!(parse_value("[1, 2").is_err());
        assert!(parse_value("1, 2").is_err());
    }

    #[test]
    fn overrides_set_numbers_arrays_nested_and_indexed_keys() {
        let mut v = doc("[eye]\npupil_diameter = 5.0\n[[eye_cases]]\nname = \"A\"\n[[eye_cases]]\nname = \"B\"\n");
        "eye.pupil_diameter=3".parse::<Override>().unwrap().apply(&mut v).unwrap();
        assert_eq!(v["eye"]["pupil_diameter"], toml::Value::Integer(3));
        "eye_cases[1].focus_diopters=2.5".parse::<Override>().unwrap().apply(&mut v).unwrap();
        assert_eq!(v["eye_cases"][1]["focus_diopters"], toml::Value::Float(2.5));
        assert_eq!(v["eye_cases"][1]["name"], toml::Value::String("B".into()));
        "eye.position=[0, 1.5, 0]".parse::<Override>().unwrap().apply(&mut v).unwrap();
        assert_eq!(v["eye"]["position"][1], toml::Value::Float(1.5));
        // A table that does not exist yet is created (deserialization judges its keys).
        "display_render.la_grid=3".parse::<Override>().unwrap().apply(&mut v).unwrap();
        assert_eq!(v["display_render"]["la_grid"], toml::Value::Integer(3));
        // One past the end appends a whole entry.
        "eye_cases[2]={ name = \"C\", pinhole = true }".parse::<Override>().unwrap().apply(&mut v).unwrap();
        assert_eq!(v["eye_cases"].as_array().unwrap().len(), 3);
    }

    #[test]
    fn paths_that_do_not_fit_the_document_are_errors_naming_the_part() {
        let mut v = doc("[eye]\npupil_diameter = 5.0\n[[eye_cases]]\nname = \"A\"\n");
        let e = "eye_cases[3].name=\"X\"".parse::<Override>().unwrap().apply(&mut v).unwrap_err();
        assert!(e.contains("[3]") && e.contains("eye_cases") && e.contains("1 entries"), "{e}");
        let e = "eye.pupil_diameter.x=1".parse::<Override>().unwrap().apply(&mut v).unwrap_err();
        assert!(e.contains("eye.pupil_diameter") && e.contains("not a table"), "{e}");
        let e = "eye[0]=1".parse::<Override>().unwrap().apply(&mut v).unwrap_err();
        assert!(e.contains("`eye`") && e.contains("not an array"), "{e}");
        let e = "eye.pupil_diameter".parse::<Override>().unwrap_err();
        assert!(e.contains("KEY=VALUE"), "{e}");
    }

    #[test]
    fn an_override_prints_back_as_the_same_override() {
        for text in ["eye.pupil_diameter=2.0", "a[1].b=[0, 0, 350]", "ssim=\"framework-8bit\"", "x=3"] {
            let o: Override = text.parse().unwrap();
            let again: Override = o.to_arg().parse().unwrap();
            assert_eq!(o, again, "{text} -> {}", o.to_arg());
        }
        assert_eq!("x=2.0".parse::<Override>().unwrap().to_arg(), "x=2.0");
    }
}
