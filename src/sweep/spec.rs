//! The sweep file: a base experiment, overrides of it, and axes of values, expanded into
//! points (each a fully resolved experiment of Sec. 4.1 with some settings changed).
//!
//! ```toml
//! name = "pupil-focus"                          # output folder out/<name> (default: file stem)
//! experiment = "../experiments/paper.toml"      # base experiment, relative to this file
//! images = false                                # true: every point's images (points/<id>/)
//!
//! [set]                                         # overrides of the base, before the axes
//! "eye_cases" = [{ name = "Eye", focus_diopters = 0.0 }]
//!
//! [[axes]]                                      # axes combine as a product (first = slowest)
//! "eye.pupil_diameter" = [2, 3, 4, 5, 6]        # a list of values ...
//!
//! [[axes]]                                      # ... keys declared together are zipped
//! "eye_cases[0].focus_diopters" = { from = 0.5, to = 4, step = 0.5 }   # ... or a range
//! "eye_cases[0].name" = ["D05", "D10", "D15", "D20", "D25", "D30", "D35", "D40"]
//! ```
//!
//! A range is `{ from, to, count }` (count values, both ends included) or `{ from, to, step }`
//! (from, from + step, ... up to `to`); values from a range are rounded to 12 significant
//! digits, and stay integers when every bound is an integer.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::io::text::{base_dir, read_text, toml_error};
use crate::overrides::Override;

/// Most points one sweep may hold.
pub const MAX_POINTS: usize = 1_000_000;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    experiment: Option<String>,
    #[serde(default)]
    study: Option<String>,
    #[serde(default)]
    images: bool,
    #[serde(default)]
    set: toml::Table,
    #[serde(default)]
    axes: Vec<toml::Table>,
}

/// One key of an axis and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisKey {
    /// The settings key (`eye.pupil_diameter`, `eye_cases[0].focus_diopters`).
    pub key: String,
    /// Its values, in order.
    pub values: Vec<toml::Value>,
}

/// An axis: one key, or several declared together (zipped: value i of each key goes together).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The keys, all with the same number of values.
    pub keys: Vec<AxisKey>,
}

impl Axis {
    /// Values along the axis.
    pub fn len(&self) -> usize {
        self.keys.first().map(|k| k.values.len()).unwrap_or(0)
    }

    /// True for an axis without values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One point: its index in the expansion and the value of every swept key.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Index in the expansion (the product of the axes, the first axis slowest).
    pub index: usize,
    /// `(key, value)` of every swept key.
    pub values: Vec<(String, toml::Value)>,
}

/// A parsed sweep file.
#[derive(Clone, Debug)]
pub struct SweepSpec {
    /// The sweep file.
    pub path: PathBuf,
    /// Names the default output folder `out/<name>`.
    pub name: String,
    /// One line for reports.
    pub description: Option<String>,
    /// The base experiment as written (a path relative to the sweep file, or `builtin:paper`);
    /// empty when the sweep names a study.
    pub experiment: String,
    /// The base resolution study as written (a path relative to the sweep file, or
    /// `builtin:paper`), in place of an experiment: each point runs `inimtrace resolution`.
    pub study: Option<String>,
    /// Write every point's images too.
    pub images: bool,
    /// `[set]`, in order, paths relative to the sweep file.
    pub set: Vec<Override>,
    /// The axes, in order (the first varies slowest).
    pub axes: Vec<Axis>,
}

/// The base a sweep file names: its experiment (empty for a study) and its study, exactly one
/// of them; `images` only with an experiment. Errors name `src` and the field.
fn base_of(file: &SweepFile, src: &str) -> Result<(String, Option<String>)> {
    match (&file.experiment, &file.study) {
        (Some(e), None) => Ok((e.clone(), None)),
        (None, Some(_)) if file.images => Err(Error::invalid(
            src,
            "images",
            "a study sweep writes tables only (run `inimtrace resolution` on a point for its files)",
        )),
        (None, Some(s)) => Ok((String::new(), Some(s.clone()))),
        (Some(_), Some(_)) => Err(Error::invalid(src, "study", "give `experiment` or `study`, not both")),
        (None, None) => Err(Error::invalid(
            src,
            "experiment",
            "missing: name the base `experiment` (or a resolution `study`) the points change",
        )),
    }
}

/// The line of key `key` of axis `i` in a sweep file's text (`None` when it cannot be told).
fn axis_key_line(text: &str, i: usize, key: &str) -> Option<usize> {
    #[derive(Deserialize)]
    struct Spans {
        #[serde(default)]
        axes: Vec<std::collections::BTreeMap<String, toml::Spanned<toml::Value>>>,
    }
    let spans: Spans = toml::from_str(text).ok()?;
    let start = spans.axes.get(i)?.get(key)?.span().start.min(text.len());
    Some(text[..start].matches('\n').count() + 1)
}

impl SweepSpec {
    /// Reads and checks a sweep file; every error names the file and the field.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        let file: SweepFile = toml::from_str(&text).map_err(|e| toml_error(path, &text, &e))?;
        let src = path.display().to_string();
        let (experiment, study) = base_of(&file, &src)?;
        let base = base_dir(path);
        let name = match file.name {
            Some(n) => n,
            None => path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        };
        if !crate::io::output::is_plain_name(&name) || name.contains("..") {
            return Err(Error::invalid(
                &src,
                "name",
                format!("`{name}` must start with a letter or digit and use only letters, digits, -, _ and . (it names the output folder)"),
            ));
        }
        let mut set = Vec::new();
        for (key, value) in file.set {
            let o = Override::new(&key, value).map_err(|e| Error::invalid(&src, format!("set.\"{key}\""), e))?;
            set.push(o.relative_to(&base));
        }
        let mut axes = Vec::new();
        let mut seen = BTreeSet::new();
        for (i, table) in file.axes.iter().enumerate() {
            if table.is_empty() {
                return Err(Error::invalid(&src, format!("axes[{i}]"), "an axis needs at least one key"));
            }
            let mut keys = Vec::new();
            for (key, spec) in table {
                let field = format!("axes[{i}].\"{key}\"");
                // At the key's line when the file shows it (an axis written as a [[axes]] table).
                let bad = |e: String| match axis_key_line(&text, i, key) {
                    Some(line) => Error::parse(path, format!("line {line}: field `{field}`: {e}")),
                    None => Error::invalid(&src, &field, e),
                };
                crate::overrides::parse_key(key).map_err(|e| bad(e.to_string()))?;
                if !seen.insert(key.clone()) {
                    return Err(bad("the key is swept by another axis too".into()));
                }
                let values = axis_values(spec).map_err(|e| bad(e.to_string()))?;
                if values.is_empty() {
                    return Err(bad("no values".into()));
                }
                keys.push(AxisKey { key: key.clone(), values });
            }
            let n = keys[0].values.len();
            // The same point twice would run once and be counted twice.
            let mut points = std::collections::HashMap::new();
            for j in 0..n {
                let tuple: Vec<String> =
                    keys.iter().map(|k| k.values.get(j).map(same_value).unwrap_or_default()).collect();
                if let Some(first) = points.insert(tuple, j) {
                    let shown: Vec<String> = keys
                        .iter()
                        .filter_map(|k| k.values.get(j).map(|v| (k, v)))
                        .map(|(k, v)| {
                            if keys.len() == 1 {
                                crate::overrides::value_text(v)
                            } else {
                                format!("{} = {}", k.key, crate::overrides::value_text(v))
                            }
                        })
                        .collect();
                    return Err(Error::invalid(
                        &src,
                        format!("axes[{i}]"),
                        format!(
                            "duplicate value {} in axis {i} (values {first} and {j}): each value must appear once",
                            shown.join(", ")
                        ),
                    ));
                }
            }
            if let Some(k) = keys.iter().find(|k| k.values.len() != n) {
                return Err(Error::invalid(
                    &src,
                    format!("axes[{i}].\"{}\"", k.key),
                    format!(
                        "has {} values but `{}` has {n}: keys declared in one axis are zipped and need the same number of values",
                        k.values.len(),
                        keys[0].key
                    ),
                ));
            }
            axes.push(Axis { keys });
        }
        let spec = Self {
            path: path.to_path_buf(),
            name,
            description: file.description,
            experiment,
            study,
            images: file.images,
            set,
            axes,
        };
        let n = spec.axes.iter().try_fold(1usize, |acc, a| acc.checked_mul(a.len()));
        match n {
            Some(n) if n <= MAX_POINTS => Ok(spec),
            _ => Err(Error::invalid(&src, "axes", format!("more than {MAX_POINTS} points"))),
        }
    }

    /// The folder the sweep file is in: relative paths in it resolve against it.
    pub fn base(&self) -> PathBuf {
        base_dir(&self.path)
    }

    /// How many points the axes make (their product; checked on load to be at most
    /// `MAX_POINTS`).
    pub fn point_count(&self) -> usize {
        self.axes.iter().map(Axis::len).product()
    }

    /// Point `index` of the expansion (below [`SweepSpec::point_count`]).
    pub fn point(&self, index: usize) -> Point {
        let mut rest = index;
        let mut picks = vec![0; self.axes.len()];
        for (a, axis) in self.axes.iter().enumerate().rev() {
            picks[a] = rest % axis.len();
            rest /= axis.len();
        }
        let values = self
            .axes
            .iter()
            .zip(&picks)
            .flat_map(|(axis, &i)| axis.keys.iter().map(move |k| (k.key.clone(), k.values[i].clone())))
            .collect();
        Point { index, values }
    }

    /// Every point, in order: the product of the axes, the first axis varying slowest.
    pub fn points(&self) -> Vec<Point> {
        (0..self.point_count()).map(|index| self.point(index)).collect()
    }

    /// Every swept key, in axis order.
    pub fn keys(&self) -> Vec<String> {
        self.axes.iter().flat_map(|a| a.keys.iter().map(|k| k.key.clone())).collect()
    }

    /// A point's values as overrides (relative to the sweep file).
    pub fn point_overrides(&self, point: &Point) -> Vec<Override> {
        point
            .values
            .iter()
            .map(|(k, v)| Override::new(k, v.clone()).expect("keys checked on load").relative_to(self.base()))
            .collect()
    }
}

/// An axis's values: an array, or a range table.
fn axis_values(spec: &toml::Value) -> std::result::Result<Vec<toml::Value>, String> {
    match spec {
        toml::Value::Array(values) => Ok(values.clone()),
        toml::Value::Table(t) => range(t),
        other => Err(format!(
            "expected a list of values or a range {{ from, to, count }} / {{ from, to, step }}, got {}",
            other.type_str()
        )),
    }
}

fn range(t: &toml::Table) -> std::result::Result<Vec<toml::Value>, String> {
    for k in t.keys() {
        if !matches!(k.as_str(), "from" | "to" | "count" | "step") {
            return Err(format!("unknown range field `{k}`: a range is {{ from, to, count }} or {{ from, to, step }}"));
        }
    }
    let number = |k: &str| -> std::result::Result<Option<(f64, bool)>, String> {
        match t.get(k) {
            None => Ok(None),
            Some(toml::Value::Integer(i)) => Ok(Some((*i as f64, true))),
            Some(toml::Value::Float(f)) if f.is_finite() => Ok(Some((*f, false))),
            Some(other) => Err(format!("range `{k}` must be a finite number, got {other}")),
        }
    };
    let (from, from_int) = number("from")?.ok_or("a range needs `from`")?;
    let (to, to_int) = number("to")?.ok_or("a range needs `to`")?;
    let count = number("count")?;
    let step = number("step")?;
    let (xs, all_int): (Vec<f64>, bool) = match (count, step) {
        (Some((c, true)), None) => {
            if !(1.0..=MAX_POINTS as f64).contains(&c) {
                return Err(format!("range `count` must be between 1 and {MAX_POINTS}, got {c}"));
            }
            let c = c as usize;
            if c == 1 && from != to {
                return Err("a range of count 1 needs `from` = `to`".into());
            }
            let xs: Vec<f64> =
                (0..c).map(|i| if c == 1 { from } else { from + (to - from) * i as f64 / (c - 1) as f64 }).collect();
            let ints = from_int && to_int && xs.iter().all(|x| x.fract() == 0.0);
            (xs, ints)
        }
        (None, Some((s, s_int))) => {
            if s == 0.0 || (to - from) * s < 0.0 {
                return Err(format!("range `step` {s} never gets from {from} to {to}"));
            }
            let count = ((to - from) / s * (1.0 + 1e-12) + 1e-9).floor() + 1.0;
            if count.is_nan() || count > MAX_POINTS as f64 {
                let count = if count < 1e15 { format!("{}", count as u64) } else { format!("{count:.3e}") };
                return Err(format!("the range would have {count} values, more than the limit of {MAX_POINTS}"));
            }
            let n = count as usize;
            ((0..n).map(|i| from + s * i as f64).collect(), from_int && to_int && s_int)
        }
        (Some((c, false)), None) => return Err(format!("range `count` must be a whole number, got {c}")),
        _ => return Err("a range needs exactly one of `count` and `step`".into()),
    };
    Ok(xs
        .into_iter()
        .map(|x| if all_int { toml::Value::Integer(x.round() as i64) } else { toml::Value::Float(round12(x)) })
        .collect())
}

/// A value as a sweep point sees it: numbers by their value (`1` and `1.0` are one point).
fn same_value(v: &toml::Value) -> String {
    match v {
        toml::Value::Integer(i) => format!("{}", *i as f64),
        toml::Value::Float(f) => format!("{f}"),
        other => other.to_string(),
    }
}

/// `x` rounded to 12 significant digits: 2 + 3 * 0.8 is 4.4, not 4.3999999999999995.
fn round12(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    format!("{x:.11e}").parse().unwrap_or(x)
}

/// Parses `--points`: indices and half-open ranges, comma-separated (`0..4`, `7`, `3,5,8..10`),
/// each below `n`; returns them sorted, without repeats.
pub fn parse_selection(text: &str, n: usize) -> std::result::Result<Vec<usize>, String> {
    let mut out = BTreeSet::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let parse = |s: &str| -> std::result::Result<usize, String> {
            s.trim().parse().map_err(|_| format!("`{part}` is not an index or a range I..J"))
        };
        let (a, b) = match part.split_once("..") {
            Some((a, b)) => (parse(a)?, parse(b)?),
            None => {
                let i = parse(part)?;
                (i, i + 1)
            }
        };
        if a >= b || b > n {
            return Err(format!("`{part}`: the sweep has points 0..{n} (I..J includes I, excludes J)"));
        }
        out.extend(a..b);
    }
    if out.is_empty() {
        return Err("no points selected".into());
    }
    Ok(out.into_iter().collect())
}

/// The shortest `--points` text for sorted indices (`0..3,5,7..9`).
pub fn format_selection(indices: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if j == i { indices[i].to_string() } else { format!("{}..{}", indices[i], indices[j] + 1) });
        i = j + 1;
    }
    parts.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> Result<SweepSpec> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.toml");
        std::fs::write(&p, text).unwrap();
        SweepSpec::load(&p)
    }

    #[test]
    fn axes_combine_as_a_product_and_zip_when_declared_together() {
        let s = spec(
            "experiment = \"builtin:paper\"\n[[axes]]\n\"eye.pupil_diameter\" = [2, 4, 6]\n[[axes]]\n\"eye_cases[0].focus_diopters\" = [0.0, 2.5]\n\"eye_cases[0].name\" = [\"Far\", \"Near\"]\n",
        )
        .unwrap();
        assert_eq!(s.name, "s");
        let pts = s.points();
        assert_eq!(pts.len(), 6);
        assert_eq!(s.keys(), ["eye.pupil_diameter", "eye_cases[0].focus_diopters", "eye_cases[0].name"]);
        // First axis slowest; zipped keys move together.
        let v = |p: &Point, k: usize| p.values[k].1.to_string();
        assert_eq!((v(&pts[0], 0), v(&pts[0], 1), v(&pts[0], 2)), ("2".into(), "0.0".into(), "\"Far\"".into()));
        assert_eq!((v(&pts[1], 0), v(&pts[1], 1), v(&pts[1], 2)), ("2".into(), "2.5".into(), "\"Near\"".into()));
        assert_eq!((v(&pts[5], 0), v(&pts[5], 2)), ("6".into(), "\"Near\"".into()));
        assert!(pts.iter().enumerate().all(|(i, p)| p.index == i));
    }

    #[test]
    fn ranges_by_count_and_by_step() {
        let s = spec("experiment = \"x\"\n[[axes]]\na = { from = 2, to = 6, count = 6 }\n[[axes]]\nb = { from = 0.5, to = 4, step = 0.5 }\n[[axes]]\nc = { from = 1, to = 7, step = 3 }\n").unwrap();
        let f = |a: usize| s.axes[a].keys[0].values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" ");
        assert_eq!(f(0), "2.0 2.8 3.6 4.4 5.2 6.0");
        assert_eq!(f(1), "0.5 1.0 1.5 2.0 2.5 3.0 3.5 4.0");
        assert_eq!(f(2), "1 4 7");
        assert_eq!(s.points().len(), 6 * 8 * 3);
    }

    #[test]
    fn bad_sweep_files_name_the_field() {
        for (text, words) in [
            ("experiment = \"x\"\n[[axes]]\na = [1, 2]\nb = [1]\n", vec!["axes[0].\"b\"", "zipped"]),
            ("experiment = \"x\"\n[[axes]]\na = [1]\n[[axes]]\na = [2]\n", vec!["axes[1].\"a\"", "another axis"]),
            ("experiment = \"x\"\n[[axes]]\na = { from = 1, to = 2 }\n", vec!["axes[0].\"a\"", "count"]),
            ("experiment = \"x\"\n[[axes]]\na = { from = 1, to = 2, step = -1 }\n", vec!["never"]),
            ("experiment = \"x\"\n[[axes]]\na = 3\n", vec!["axes[0].\"a\"", "list of values"]),
            ("experiment = \"x\"\n[[axes]]\n\"a[x]\" = [1]\n", vec!["axes[0]", "index"]),
            ("experiment = \"x\"\n[[axes]]\na = []\n", vec!["no values"]),
            ("experiment = \"x\"\nname = \"../up\"\n", vec!["name"]),
            ("experiment = \"x\"\naxis = []\n", vec!["unknown field `axis`"]),
            ("[[axes]]\na = [1]\n", vec!["experiment"]),
            ("experiment = \"x\"\nstudy = \"y\"\n", vec!["study", "not both"]),
            ("study = \"y\"\nimages = true\n", vec!["images"]),
        ] {
            let e = spec(text).unwrap_err().to_string();
            for w in words {
                assert!(e.contains(w), "{text:?}: `{e}` lacks {w}");
            }
        }
    }

    #[test]
    fn point_selections_parse_and_print() {
        assert_eq!(parse_selection("0..3", 12).unwrap(), vec![0, 1, 2]);
        assert_eq!(parse_selection("3, 5,8..10,5", 12).unwrap(), vec![3, 5, 8, 9]);
        assert!(parse_selection("10..13", 12).is_err());
        assert!(parse_selection("3..3", 12).is_err());
        assert!(parse_selection("x", 12).is_err());
        assert!(parse_selection("", 12).is_err());
        assert_eq!(format_selection(&[0, 1, 2, 5, 7, 8]), "0..3,5,7..9");
        assert_eq!(parse_selection(&format_selection(&[0, 1, 2, 5, 7, 8]), 12).unwrap(), vec![0, 1, 2, 5, 7, 8]);
    }
}
