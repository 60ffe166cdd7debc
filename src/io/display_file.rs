//! Display files (the display model of Sec. 2 and Table 1's parameters): our TOML format and
//! the paper framework's OpenCV FileStorage YAML, both read into an [`optics::Display`]. Every
//! error names the file and the field or key. `builtin:paper` names the paper's display (Sec.
//! 4.1) without a file.
//!
//! [`optics::Display`]: crate::optics::Display

use std::path::Path;

use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};

use super::text::{read_text, toml_error};
use crate::error::{Error, Result};
use crate::optics::photometry::PhotometrySpec;
use crate::optics::{Display, Lattice, Lcd};

/// A lattice's pitch: a number (square), a pair (rectangular) or a row-major 2x2 matrix.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum PitchSpec {
    /// Square cells of this pitch, mm.
    Square(f64),
    /// Rectangular cells, `[x, y]` pitch, mm.
    Rectangular([f64; 2]),
    /// The row-major pitch matrix `[[a, b], [c, d]]`, mm: cell (i, j) is centred at `shift + M (i, j)`.
    Matrix([[f64; 2]; 2]),
}

/// A lattice of cells (`[elemental_images]`): its shift and pitch.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LatticeSpec {
    /// Centre of cell (0, 0), mm (default the origin).
    #[serde(default)]
    pub shift: [f64; 2],
    /// The pitch.
    pub pitch: PitchSpec,
}

impl LatticeSpec {
    fn to_lattice(&self, source: &str, field: &str) -> Result<Lattice> {
        let m = match &self.pitch {
            PitchSpec::Square(p) => DMat2::from_diagonal(DVec2::splat(*p)),
            PitchSpec::Rectangular([px, py]) => DMat2::from_diagonal(DVec2::new(*px, *py)),
            PitchSpec::Matrix([[a, b], [c, d]]) => DMat2::from_cols(DVec2::new(*a, *c), DVec2::new(*b, *d)),
        };
        let det = m.determinant();
        if let PitchSpec::Square(p) | PitchSpec::Rectangular([p, _]) = &self.pitch {
            if !(p.is_finite() && *p > 0.0) {
                return Err(Error::invalid(
                    source,
                    format!("{field}.pitch"),
                    format!("must be positive and finite, got {p}"),
                ));
            }
        }
        if let PitchSpec::Rectangular([_, p]) = &self.pitch {
            if !(p.is_finite() && *p > 0.0) {
                return Err(Error::invalid(
                    source,
                    format!("{field}.pitch[1]"),
                    format!("must be positive and finite, got {p}"),
                ));
            }
        }
        Lattice::new(DVec2::from_array(self.shift), m).ok_or_else(|| Error::Lattice {
            source_name: source.to_string(),
            field: format!("{field}.pitch"),
            message: format!("pitch matrix is singular or not finite (determinant {det}) or shift is not finite"),
        })
    }

    fn from_lattice(l: &Lattice) -> Self {
        let [a, b, c, d] = l.row_major();
        let pitch = if b == 0.0 && c == 0.0 {
            if a == d {
                PitchSpec::Square(a)
            } else {
                PitchSpec::Rectangular([a, d])
            }
        } else {
            PitchSpec::Matrix([[a, b], [c, d]])
        };
        Self { shift: l.shift.to_array(), pitch }
    }
}

/// `[lenslets]`: the lenslet array, a lattice of thin lenses.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LensletSpec {
    /// f: focal length of every lenslet, mm.
    pub focal_length: f64,
    /// Centre of lenslet (0, 0), mm (default the origin).
    #[serde(default)]
    pub shift: [f64; 2],
    /// The lenslets' pitch.
    pub pitch: PitchSpec,
}

/// `[lcd]`: the panel.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LcdSpec {
    /// Width and height, mm.
    pub size: [f64; 2],
    /// Columns and rows.
    pub resolution: [usize; 2],
}

/// Our display file (TOML).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DisplaySpec {
    /// Display name (default: the file's name).
    #[serde(default)]
    pub name: Option<String>,
    /// v1: pupil plane to lenslet plane, mm.
    pub eye_to_lenslets: f64,
    /// v2: lenslet plane to LCD, mm.
    pub lenslets_to_lcd: f64,
    /// `[lenslets]`.
    pub lenslets: LensletSpec,
    /// `[elemental_images]`.
    pub elemental_images: LatticeSpec,
    /// `[lcd]`.
    pub lcd: LcdSpec,
    /// `[primaries]`: the red, green and blue emission spectra (default: a typical LCD's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub primaries: Option<crate::optics::spectrum::Primaries>,
    /// `[lenslet]`: the lenslets' optics (default: the paper's thin lens).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lenslet: Option<super::display_lenslet::LensletOpticsSpec>,
    /// `[photometry]`: peak white, black level or contrast ratio, ambient light (default: a
    /// typical near-eye LCD's, [`crate::optics::photometry`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub photometry: Option<PhotometrySpec>,
}

impl DisplaySpec {
    /// Resolves the file into a display and validates it; errors name `source` and the field.
    pub fn to_display(&self, source: &str) -> Result<Display> {
        let lenslets = LatticeSpec { shift: self.lenslets.shift, pitch: self.lenslets.pitch.clone() }
            .to_lattice(source, "lenslets")?;
        let elemental_images = self.elemental_images.to_lattice(source, "elemental_images")?;
        let d = Display {
            name: self.name.clone().unwrap_or_else(|| source.to_string()),
            eye_to_lenslets: self.eye_to_lenslets,
            lenslets_to_lcd: self.lenslets_to_lcd,
            focal_length: self.lenslets.focal_length,
            lenslets,
            elemental_images,
            lcd: Lcd { size: DVec2::from_array(self.lcd.size), resolution: self.lcd.resolution },
            primaries: self.primaries.clone(),
            lenslet: match &self.lenslet {
                Some(l) => l.to_optics(source)?,
                None => crate::optics::lenslet::LensletOptics::Paraxial,
            },
            photometry: self.photometry.as_ref().map(|p| p.resolve(source)).transpose()?,
        };
        if let Some(p) = &d.primaries {
            p.validate(source)?;
        }
        d.validate(source)?;
        Ok(d)
    }

    /// The file of `d` (what `info --print paper-display` prints).
    pub fn from_display(d: &Display) -> Self {
        let l = LatticeSpec::from_lattice(&d.lenslets);
        Self {
            name: Some(d.name.clone()),
            eye_to_lenslets: d.eye_to_lenslets,
            lenslets_to_lcd: d.lenslets_to_lcd,
            lenslets: LensletSpec { focal_length: d.focal_length, shift: l.shift, pitch: l.pitch },
            elemental_images: LatticeSpec::from_lattice(&d.elemental_images),
            lcd: LcdSpec { size: d.lcd.size.to_array(), resolution: d.lcd.resolution },
            primaries: d.primaries.clone(),
            lenslet: super::display_lenslet::LensletOpticsSpec::from_optics(&d.lenslet),
            photometry: d.photometry.as_ref().map(PhotometrySpec::of),
        }
    }
}

/// Loads a display: `builtin:paper`, an OpenCV FileStorage YAML file (first line `%YAML:1.0`
/// or extension .yaml/.yml), or our TOML, explicit or stated by intent (an `[intent]` table,
/// [`super::display_intent`]).
pub fn load_display(spec: &str, base: &Path) -> Result<Display> {
    if spec == "builtin:paper" {
        return Ok(Display::paper());
    }
    let path = base.join(spec);
    let text = read_text(&path)?;
    if is_opencv_yaml(&text, &path) {
        parse_opencv_display(&text, &path)
    } else if super::display_intent::states_intent(&text) {
        super::display_intent::parse_intent_display(&text, &path).map(|(d, _)| d)
    } else {
        let spec: DisplaySpec = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
        spec.to_display(&path.display().to_string())
    }
}

/// Whether a display file is the framework's OpenCV YAML (first line `%YAML` or extension
/// .yaml/.yml) rather than our TOML.
pub fn is_opencv_yaml(text: &str, path: &Path) -> bool {
    text.trim_start().starts_with("%YAML") || matches!(path.extension().and_then(|e| e.to_str()), Some("yaml" | "yml"))
}

/// The deepest nesting [`parse_opencv_display`] reads: the YAML parser's time grows with the
/// square of the depth, and the framework's display file is 2 levels deep.
pub const MAX_YAML_NESTING: usize = 128;

/// An upper bound on the nesting depth of a YAML text, in one pass over its bytes, before any
/// parsing: block levels (distinct indentations open on the stack, plus `- ` and `? ` entries
/// that open a collection on the same line) and flow levels (`[` and `{` open outside quoted
/// scalars and comments) add up.
fn yaml_nesting(text: &str) -> usize {
    let (mut indents, mut flow, mut deepest) = (Vec::<usize>::new(), 0usize, 0usize);
    for line in text.lines() {
        let content = line.trim_start_matches(' ');
        let indent = line.len() - content.len();
        if flow == 0 && !content.is_empty() && !content.starts_with('#') {
            while indents.last().is_some_and(|&i| i >= indent) {
                indents.pop();
            }
            indents.push(indent);
            let (mut rest, mut entries) = (content, 0);
            while let Some(r) = rest.strip_prefix("- ").or_else(|| rest.strip_prefix("? ")) {
                entries += 1;
                rest = r.trim_start_matches(' ');
            }
            deepest = deepest.max(indents.len() + entries);
        }
        let (mut quote, mut previous) = (None::<u8>, b' ');
        let mut bytes = content.bytes().peekable();
        while let Some(b) = bytes.next() {
            match quote {
                Some(b'"') if b == b'\\' => {
                    bytes.next();
                }
                Some(q) if b == q => {
                    // '' inside a single-quoted scalar is an escaped quote.
                    if q == b'\'' && bytes.peek() == Some(&b'\'') {
                        bytes.next();
                    } else {
                        quote = None;
                    }
                }
                Some(_) => {}
                None => match b {
                    b'"' | b'\'' if matches!(previous, b' ' | b'\t' | b':' | b',' | b'[' | b'{' | b'-') => {
                        quote = Some(b)
                    }
                    b'#' if matches!(previous, b' ' | b'\t') => break,
                    b'[' | b'{' => {
                        flow += 1;
                        deepest = deepest.max(indents.len() + flow);
                    }
                    b']' | b'}' => flow = flow.saturating_sub(1),
                    _ => {}
                },
            }
            previous = b;
        }
    }
    deepest
}

/// The framework's display keys.
const FRAMEWORK_KEYS: [&str; 10] = [
    "lenslettolcd",
    "lenslettoorigin",
    "sizelcd",
    "resolutionlcd",
    "islensletvertical",
    "lensletshift",
    "lensletorientation",
    "lensletfocallength",
    "eishift",
    "eiorientation",
];

/// Parses the paper framework's display file (OpenCV FileStorage YAML; keys `lenslettolcd`,
/// `lenslettoorigin`, `sizelcd`, `resolutionlcd`, `islensletvertical`, `lensletshift`,
/// `lensletorientation` (row-major 2x2), `lensletfocallength`, `eishift`, `eiorientation`).
pub fn parse_opencv_display(text: &str, path: &Path) -> Result<Display> {
    let map = framework_mapping(text, path)?;
    let keys = FrameworkFile { map: &map, src: path.display().to_string() };
    let src = &keys.src;
    let vertical = map.get("islensletvertical").map(|_| keys.numbers("islensletvertical", 1)).transpose()?;
    if let Some(v) = vertical {
        if v[0] != 0.0 {
            return Err(Error::invalid(
                src,
                "islensletvertical",
                "cylindrical (vertical lenticular) lenslets are not supported; only spherical lenslet arrays (0)",
            ));
        }
    }
    let res = keys.numbers("resolutionlcd", 2)?;
    for (i, r) in res.iter().enumerate() {
        if !(r.fract() == 0.0 && *r >= 0.0 && *r <= 65536.0) {
            return Err(Error::invalid(
                src,
                format!("resolutionlcd[{i}]"),
                format!("must be a whole number of pixels, got {r}"),
            ));
        }
    }
    let size = keys.numbers("sizelcd", 2)?;
    let d = Display {
        name: path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        eye_to_lenslets: keys.numbers("lenslettoorigin", 1)?[0],
        lenslets_to_lcd: keys.numbers("lenslettolcd", 1)?[0],
        focal_length: keys.numbers("lensletfocallength", 1)?[0],
        lenslets: keys.lattice("lensletshift", "lensletorientation")?,
        elemental_images: keys.lattice("eishift", "eiorientation")?,
        lcd: Lcd { size: DVec2::new(size[0], size[1]), resolution: [res[0] as usize, res[1] as usize] },
        primaries: None,
        lenslet: crate::optics::lenslet::LensletOptics::Paraxial,
        photometry: None,
    };
    d.validate(src).map_err(with_framework_key)?;
    Ok(d)
}

/// The top-level mapping of a framework display file, every key one of [`FRAMEWORK_KEYS`]; a
/// file nested deeper than [`MAX_YAML_NESTING`] is refused before it is parsed.
fn framework_mapping(text: &str, path: &Path) -> Result<serde_yaml_ng::Mapping> {
    let depth = yaml_nesting(text);
    if depth > MAX_YAML_NESTING {
        return Err(Error::parse(
            path,
            format!("YAML nested {depth} levels deep: at most {MAX_YAML_NESTING} are read (a display file needs 2)"),
        ));
    }
    // OpenCV writes a YAML 1.0 directive (`%YAML:1.0`) that YAML 1.2 parsers reject.
    let body: String = text
        .lines()
        .skip_while(|l| l.trim().is_empty())
        .enumerate()
        .map(|(i, l)| if i == 0 && l.trim_start().starts_with("%YAML") { "" } else { l })
        .collect::<Vec<_>>()
        .join("\n");
    let doc: serde_yaml_ng::Value =
        serde_yaml_ng::from_str(&body).map_err(|e| Error::parse(path, format!("malformed YAML: {e}")))?;
    let serde_yaml_ng::Value::Mapping(map) = doc else {
        return Err(Error::parse(path, "expected a mapping of display keys at the top level"));
    };
    let src = path.display().to_string();
    for key in map.keys() {
        let k = key.as_str().unwrap_or("?");
        if !FRAMEWORK_KEYS.contains(&k) {
            return Err(Error::invalid(&src, k, format!("unknown key; expected one of {}", FRAMEWORK_KEYS.join(", "))));
        }
    }
    Ok(map)
}

/// The keys of a framework display file (`src` names it in errors).
struct FrameworkFile<'a> {
    map: &'a serde_yaml_ng::Mapping,
    src: String,
}

impl FrameworkFile<'_> {
    /// The `n` numbers of `key`: a number, a sequence of them, or an OpenCV matrix
    /// (`!!opencv-matrix {rows, cols, dt, data: [...]}`).
    fn numbers(&self, key: &str, n: usize) -> Result<Vec<f64>> {
        use serde_yaml_ng::Value;
        let src = &self.src;
        let v = self.map.get(key).ok_or_else(|| Error::invalid(src, key, "missing"))?;
        // OpenCV matrices may be written as `!!opencv-matrix {rows, cols, dt, data: [...]}`.
        let v = match v {
            Value::Tagged(t) => &t.value,
            other => other,
        };
        let v = match v {
            Value::Mapping(m) => m.get("data").ok_or_else(|| Error::invalid(src, key, "matrix without `data`"))?,
            other => other,
        };
        let list: Vec<&Value> = match v {
            Value::Sequence(s) => s.iter().collect(),
            other => vec![other],
        };
        if list.len() != n {
            return Err(Error::invalid(
                src,
                key,
                format!("expected {}, got {}", crate::count::count(n, "number"), list.len()),
            ));
        }
        list.iter()
            .map(|x| match x {
                Value::Number(num) => num.as_f64().ok_or_else(|| Error::invalid(src, key, "not a number")),
                other => Err(Error::invalid(src, key, format!("expected a number, got {other:?}"))),
            })
            .collect()
    }

    /// The lattice of shift `shift_key` (2 numbers) and row-major pitch matrix `key` (4 numbers).
    fn lattice(&self, shift_key: &str, key: &str) -> Result<Lattice> {
        let m = self.numbers(key, 4)?;
        let shift = self.numbers(shift_key, 2).map(|v| DVec2::new(v[0], v[1]))?;
        Lattice::from_row_major(shift, [m[0], m[1], m[2], m[3]]).ok_or_else(|| Error::Lattice {
            source_name: self.src.clone(),
            field: key.to_string(),
            message: format!("pitch matrix {m:?} is singular or not finite"),
        })
    }
}

/// A validation error of the display with the framework's key for the field it names.
fn with_framework_key(e: Error) -> Error {
    match e {
        Error::Invalid { source_name, field, message } => {
            let key = match field.split(' ').next().unwrap_or("") {
                "eye_to_lenslets" => "lenslettoorigin",
                "lenslets_to_lcd" => "lenslettolcd",
                "focal_length" => "lensletfocallength",
                f if f.starts_with("lcd.size") => "sizelcd",
                f if f.starts_with("lcd.resolution") => "resolutionlcd",
                _ => "",
            };
            Error::Invalid { source_name, field: if key.is_empty() { field } else { key.to_string() }, message }
        }
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaml_nesting_counts_block_and_flow_levels_outside_quotes_and_comments() {
        let paper = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/lensletdisplay.yaml")).unwrap();
        assert!((2..=4).contains(&yaml_nesting(&paper)), "{}", yaml_nesting(&paper));
        assert_eq!(yaml_nesting("a: 1\nb:\n  c:\n    d: 2\ne: 3\n"), 3);
        assert_eq!(yaml_nesting("a: [1, [2, {b: 3}]]\n"), 4);
        assert_eq!(yaml_nesting("a: \"[[[[\" # [[[[\nb: '[{''[' \n"), 1);
        assert_eq!(yaml_nesting(&format!("a: {}1{}\n", "[".repeat(500), "]".repeat(500))), 501);
        assert_eq!(yaml_nesting(&format!("{}x\n", "- ".repeat(300))), 301);
        let deep: String = (0..200).map(|i| format!("{}k{i}:\n", " ".repeat(i))).collect();
        assert_eq!(yaml_nesting(&deep), 200);
    }
}
