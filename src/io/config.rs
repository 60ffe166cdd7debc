//! Configuration files: displays (our TOML, and the paper framework's OpenCV FileStorage YAML),
//! scenes (TOML) and experiments (TOML). Every error names the file and the field or line.
//!
//! Paths inside a file are relative to that file. `builtin:paper` names the paper's display or
//! scene (Sec. 4.1) without a file.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat2, DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::optics::{Display, Lattice, Lcd};
use crate::scene::image_texture::{Filter, ImageTexture, Wrap};
use crate::scene::mesh_io::{self, Transform};
use crate::scene::usaf::{self, ChartScale};
use crate::scene::{procedural, Light, Material, Object, Rect, Scene, Shape};

/// Reads a whole file, with the path in the error.
pub fn read_text(path: &Path) -> Result<String> {
    if path.is_dir() {
        return Err(Error::io(path, std::io::Error::other("is a directory, expected a file")));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
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

// ---------------------------------------------------------------------------------------------
// Displays

/// A lattice's pitch: a number (square), a pair (rectangular) or a row-major 2x2 matrix.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum PitchSpec {
    Square(f64),
    Rectangular([f64; 2]),
    Matrix([[f64; 2]; 2]),
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LatticeSpec {
    #[serde(default)]
    pub shift: [f64; 2],
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
        Lattice::new(DVec2::from_array(self.shift), m).ok_or_else(|| {
            Error::invalid(
                source,
                format!("{field}.pitch"),
                format!("pitch matrix is singular or not finite (determinant {det}) or shift is not finite"),
            )
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

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LensletSpec {
    pub focal_length: f64,
    #[serde(default)]
    pub shift: [f64; 2],
    pub pitch: PitchSpec,
}

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
    #[serde(default)]
    pub name: Option<String>,
    /// v1: pupil plane to lenslet plane, mm.
    pub eye_to_lenslets: f64,
    /// v2: lenslet plane to LCD, mm.
    pub lenslets_to_lcd: f64,
    pub lenslets: LensletSpec,
    pub elemental_images: LatticeSpec,
    pub lcd: LcdSpec,
}

impl DisplaySpec {
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
        };
        d.validate(source)?;
        Ok(d)
    }

    pub fn from_display(d: &Display) -> Self {
        let l = LatticeSpec::from_lattice(&d.lenslets);
        Self {
            name: Some(d.name.clone()),
            eye_to_lenslets: d.eye_to_lenslets,
            lenslets_to_lcd: d.lenslets_to_lcd,
            lenslets: LensletSpec { focal_length: d.focal_length, shift: l.shift, pitch: l.pitch },
            elemental_images: LatticeSpec::from_lattice(&d.elemental_images),
            lcd: LcdSpec { size: d.lcd.size.to_array(), resolution: d.lcd.resolution },
        }
    }
}

/// Loads a display: `builtin:paper`, an OpenCV FileStorage YAML file (first line `%YAML:1.0`
/// or extension .yaml/.yml), or our TOML.
pub fn load_display(spec: &str, base: &Path) -> Result<Display> {
    if spec == "builtin:paper" {
        return Ok(Display::paper());
    }
    let path = base.join(spec);
    let text = read_text(&path)?;
    let is_yaml = text.trim_start().starts_with("%YAML")
        || matches!(path.extension().and_then(|e| e.to_str()), Some("yaml" | "yml"));
    if is_yaml {
        parse_opencv_display(&text, &path)
    } else {
        let spec: DisplaySpec = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
        spec.to_display(&path.display().to_string())
    }
}

/// Parses the paper framework's display file (OpenCV FileStorage YAML; keys `lenslettolcd`,
/// `lenslettoorigin`, `sizelcd`, `resolutionlcd`, `islensletvertical`, `lensletshift`,
/// `lensletorientation` (row-major 2x2), `lensletfocallength`, `eishift`, `eiorientation`).
pub fn parse_opencv_display(text: &str, path: &Path) -> Result<Display> {
    use serde_yaml_ng::Value;
    // OpenCV writes a YAML 1.0 directive (`%YAML:1.0`) that YAML 1.2 parsers reject.
    let body: String = text
        .lines()
        .skip_while(|l| l.trim().is_empty())
        .enumerate()
        .map(|(i, l)| if i == 0 && l.trim_start().starts_with("%YAML") { "" } else { l })
        .collect::<Vec<_>>()
        .join("\n");
    let doc: Value = serde_yaml_ng::from_str(&body).map_err(|e| Error::parse(path, format!("malformed YAML: {e}")))?;
    let Value::Mapping(map) = doc else {
        return Err(Error::parse(path, "expected a mapping of display keys at the top level"));
    };
    let src = path.display().to_string();
    for key in map.keys() {
        let k = key.as_str().unwrap_or("?");
        const KNOWN: [&str; 10] = [
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
        if !KNOWN.contains(&k) {
            return Err(Error::invalid(&src, k, format!("unknown key; expected one of {}", KNOWN.join(", "))));
        }
    }
    let numbers = |key: &str, n: usize| -> Result<Vec<f64>> {
        let v = map.get(key).ok_or_else(|| Error::invalid(&src, key, "missing"))?;
        // OpenCV matrices may be written as `!!opencv-matrix {rows, cols, dt, data: [...]}`.
        let v = match v {
            Value::Tagged(t) => &t.value,
            other => other,
        };
        let v = match v {
            Value::Mapping(m) => m.get("data").ok_or_else(|| Error::invalid(&src, key, "matrix without `data`"))?,
            other => other,
        };
        let list: Vec<&Value> = match v {
            Value::Sequence(s) => s.iter().collect(),
            other => vec![other],
        };
        if list.len() != n {
            return Err(Error::invalid(&src, key, format!("expected {n} number(s), got {}", list.len())));
        }
        list.iter()
            .map(|x| match x {
                Value::Number(num) => num.as_f64().ok_or_else(|| Error::invalid(&src, key, "not a number")),
                other => Err(Error::invalid(&src, key, format!("expected a number, got {other:?}"))),
            })
            .collect()
    };
    let vertical = map.get("islensletvertical").map(|_| numbers("islensletvertical", 1)).transpose()?;
    if let Some(v) = vertical {
        if v[0] != 0.0 {
            return Err(Error::invalid(
                &src,
                "islensletvertical",
                "cylindrical (vertical lenticular) lenslets are not supported; only spherical lenslet arrays (0)",
            ));
        }
    }
    let res = numbers("resolutionlcd", 2)?;
    for (i, r) in res.iter().enumerate() {
        if !(r.fract() == 0.0 && *r >= 0.0 && *r <= 65536.0) {
            return Err(Error::invalid(
                &src,
                format!("resolutionlcd[{i}]"),
                format!("must be a whole number of pixels, got {r}"),
            ));
        }
    }
    let shift = |k: &str| -> Result<DVec2> { numbers(k, 2).map(|v| DVec2::new(v[0], v[1])) };
    let lattice = |shift_key: &str, key: &str| -> Result<Lattice> {
        let m = numbers(key, 4)?;
        Lattice::from_row_major(shift(shift_key)?, [m[0], m[1], m[2], m[3]])
            .ok_or_else(|| Error::invalid(&src, key, format!("pitch matrix {m:?} is singular or not finite")))
    };
    let size = numbers("sizelcd", 2)?;
    let d = Display {
        name: path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        eye_to_lenslets: numbers("lenslettoorigin", 1)?[0],
        lenslets_to_lcd: numbers("lenslettolcd", 1)?[0],
        focal_length: numbers("lensletfocallength", 1)?[0],
        lenslets: lattice("lensletshift", "lensletorientation")?,
        elemental_images: lattice("eishift", "eiorientation")?,
        lcd: Lcd { size: DVec2::new(size[0], size[1]), resolution: [res[0] as usize, res[1] as usize] },
    };
    // Name the framework's keys in validation errors.
    d.validate(&src).map_err(|e| match e {
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
    })?;
    Ok(d)
}

// ---------------------------------------------------------------------------------------------
// Scenes

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum ChartKind {
    /// The paper framework's chart (146 bars).
    Framework,
    /// A procedural MIL-STD-150A chart; see `groups` and `scale`.
    Usaf,
    /// Bars from a text file (`minx miny maxx maxy` per line), see `file`.
    File,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum ChartScaleSpec {
    Fit,
    Physical,
}

/// An object's material: `albedo = [r, g, b]`, or a chart.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chart: Option<ChartKind>,
    /// Procedural chart: first and last group (inclusive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<[i32; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ChartScaleSpec>,
    /// Bar-list file for `chart = "file"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Bar albedo (default black) and backing albedo (default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bar_albedo: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backing_albedo: Option<[f64; 3]>,
    /// Meshes: interpolate the file's per-vertex colours (`vertex_color = true`; the file must
    /// have colours).
    #[serde(default, alias = "vertex-color", skip_serializing_if = "Option::is_none")]
    pub vertex_color: Option<bool>,
    /// Meshes: a PNG texture looked up by the file's uvs (relative to the scene file), or
    /// `"mtl"` for the OBJ material's `map_Kd`. See [`crate::scene::image_texture`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<PathBuf>,
    /// Texture filter: "bilinear" (default) or "nearest".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub filter: Option<Filter>,
    /// UVs outside [0, 1]: "repeat" (default) or "clamp".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrap: Option<Wrap>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    Rect,
    Mesh,
    SphereGrid,
}

/// One scene object.
/// - `type = "rect"`: facing the eye, given by `center` and `size` (width along x, height
///   along y); any other orientation by `center`, `half_u` and `half_v`.
/// - `type = "mesh"`: a triangle mesh from `file` (OBJ or PLY, relative to the scene file),
///   placed by `transform = { scale, rotation_deg, translation }` (see
///   [`crate::scene::mesh_io::Transform`]).
/// - `type = "sphere-grid"`: `count = [nx, ny]` UV spheres of `radius` with `segments`
///   longitudes, `spacing` mm apart in the plane `z = center.z`, centred on `center`
///   ([`crate::scene::procedural::sphere_grid`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    #[serde(default)]
    pub name: Option<String>,
    #[serde(rename = "type")]
    pub kind: ShapeKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<Transform>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<[usize; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_u: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_v: Option<[f64; 3]>,
    pub material: MaterialSpec,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub name: String,
    /// Radiance of rays that hit nothing (default black).
    #[serde(default)]
    pub background: [f64; 3],
    /// Optional distant light (`[light] type = "distant"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightSpec>,
    #[serde(rename = "objects")]
    pub objects: Vec<ObjectSpec>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum LightKind {
    Distant,
}

/// `[light]`: a distant light travelling along `direction` (normalised on load) with linear
/// RGB `radiance`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    #[serde(rename = "type")]
    pub kind: LightKind,
    pub direction: [f64; 3],
    pub radiance: [f64; 3],
}

fn finite3(src: &str, field: &str, v: [f64; 3]) -> Result<DVec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from_array(v))
    } else {
        Err(Error::invalid(src, field, format!("must be finite, got {v:?}")))
    }
}

fn albedo3(src: &str, field: &str, v: [f64; 3]) -> Result<DVec3> {
    let a = finite3(src, field, v)?;
    if a.min_element() < 0.0 {
        return Err(Error::invalid(src, field, format!("albedo must be >= 0, got {v:?}")));
    }
    Ok(a)
}

impl SceneSpec {
    /// Builds the scene; `base` resolves relative file paths.
    pub fn to_scene(&self, src: &str, base: &Path) -> Result<Scene> {
        let background = albedo3(src, "background", self.background)?;
        let mut objects = Vec::with_capacity(self.objects.len());
        let mut framework_chart = None;
        let mut warnings = Vec::new();
        for (i, o) in self.objects.iter().enumerate() {
            let f = |name: &str| format!("objects[{i}].{name}");
            let only = |allowed: &[&str]| -> Result<()> {
                let given = [
                    ("center", o.center.is_some()),
                    ("size", o.size.is_some()),
                    ("half_u", o.half_u.is_some()),
                    ("half_v", o.half_v.is_some()),
                    ("file", o.file.is_some()),
                    ("transform", o.transform.is_some()),
                    ("count", o.count.is_some()),
                    ("spacing", o.spacing.is_some()),
                    ("radius", o.radius.is_some()),
                    ("segments", o.segments.is_some()),
                ];
                match given.iter().find(|(name, set)| *set && !allowed.contains(name)) {
                    Some((name, _)) => Err(Error::invalid(
                        src,
                        f(name),
                        format!("not a field of a `{:?}` object (allowed: {})", o.kind, allowed.join(", "))
                            .to_lowercase(),
                    )),
                    None => Ok(()),
                }
            };
            let mut mesh_texture = None;
            let shape = match o.kind {
                ShapeKind::Rect => {
                    only(&["center", "size", "half_u", "half_v"])?;
                    let center = finite3(
                        src,
                        &f("center"),
                        o.center.ok_or_else(|| Error::invalid(src, f("center"), "missing (a rect needs `center`)"))?,
                    )?;
                    Shape::Rect(self.rect(src, i, center, o)?)
                }
                ShapeKind::Mesh => {
                    only(&["file", "transform"])?;
                    let file = o.file.as_ref().ok_or_else(|| {
                        Error::invalid(src, f("file"), "missing (a mesh needs `file = \"path.obj\"` or .ply)")
                    })?;
                    let transform = o.transform.unwrap_or_default();
                    transform.validate(src).map_err(|e| match e {
                        Error::Invalid { source_name, field, message } => {
                            Error::invalid(source_name, f(&format!("transform.{field}")), message)
                        }
                        other => other,
                    })?;
                    let path = base.join(file);
                    // Name the scene file and field as well as the mesh file and its line/element.
                    let loaded =
                        mesh_io::load_mesh(&path).map_err(|e| Error::invalid(src, f("file"), e.to_string()))?;
                    if loaded.dropped_degenerate > 0 {
                        warnings.push(format!(
                            "{}: dropped {} degenerate (zero-area) triangle(s) of {} (objects[{i}])",
                            src,
                            loaded.dropped_degenerate,
                            path.display()
                        ));
                    }
                    mesh_texture = loaded.texture;
                    let mut mesh = loaded.mesh;
                    transform.apply(&mut mesh);
                    // A transform can push finite vertices past f64 range, or flatten triangles.
                    mesh.validate(&format!("{} (objects[{i}], {} after transform)", src, path.display()))?;
                    let flattened = mesh.remove_degenerate();
                    if mesh.triangles.is_empty() {
                        return Err(Error::invalid(src, f("transform"), "leaves no triangle with non-zero area"));
                    }
                    if flattened > 0 {
                        warnings.push(format!(
                            "{src}: the transform of objects[{i}] made {flattened} triangle(s) of {} degenerate; dropped",
                            path.display()
                        ));
                    }
                    Shape::Mesh(Arc::new(mesh))
                }
                ShapeKind::SphereGrid => {
                    only(&["center", "count", "spacing", "radius", "segments"])?;
                    let center = finite3(
                        src,
                        &f("center"),
                        o.center.ok_or_else(|| Error::invalid(src, f("center"), "missing"))?,
                    )?;
                    let count = o.count.ok_or_else(|| Error::invalid(src, f("count"), "missing ([nx, ny])"))?;
                    if count[0] == 0 || count[1] == 0 || count[0] * count[1] > 1_000_000 {
                        return Err(Error::invalid(src, f("count"), format!("need 1..=1e6 spheres, got {count:?}")));
                    }
                    let positive = |name: &str, v: Option<f64>| -> Result<f64> {
                        match v {
                            Some(x) if x.is_finite() && x > 0.0 => Ok(x),
                            Some(x) => {
                                Err(Error::invalid(src, f(name), format!("must be positive and finite, got {x}")))
                            }
                            None => Err(Error::invalid(src, f(name), "missing")),
                        }
                    };
                    let radius = positive("radius", o.radius)?;
                    let spacing = positive("spacing", o.spacing)?;
                    let segments = o.segments.unwrap_or(32);
                    if !(4..=4096).contains(&segments) {
                        return Err(Error::invalid(src, f("segments"), format!("must be 4..=4096, got {segments}")));
                    }
                    let tris = count[0] * count[1] * 2 * segments * (segments / 2 - 1);
                    if tris > 100_000_000 {
                        return Err(Error::invalid(src, f("count"), format!("{tris} triangles is over 1e8")));
                    }
                    Shape::Mesh(Arc::new(procedural::sphere_grid(center, count, spacing, radius, segments)))
                }
            };
            let rect = match &shape {
                Shape::Rect(r) => Some(*r),
                Shape::Mesh(_) => None,
            };
            let m = &o.material;
            let texture_fields = m.texture.is_some() || m.filter.is_some() || m.wrap.is_some();
            let vertex_color = m.vertex_color.unwrap_or(false);
            let material = match (&m.albedo, &m.chart, vertex_color, texture_fields) {
                (Some(a), None, false, false) => Material::Albedo(albedo3(src, &f("material.albedo"), *a)?),
                (None, None, true, false) => match &shape {
                    Shape::Mesh(mesh) if mesh.colors.is_some() => Material::VertexColor,
                    Shape::Mesh(_) => {
                        return Err(Error::invalid(
                            src,
                            f("material.vertex_color"),
                            "the mesh has no per-vertex colours (give `albedo` instead)",
                        ))
                    }
                    Shape::Rect(_) => {
                        return Err(Error::invalid(src, f("material.vertex_color"), "only meshes have vertex colours"))
                    }
                },
                (None, None, false, true) => {
                    let Shape::Mesh(mesh) = &shape else {
                        return Err(Error::invalid(src, f("material.texture"), "image textures are for meshes"));
                    };
                    let texture = m
                        .texture
                        .as_ref()
                        .ok_or_else(|| Error::invalid(src, f("material.texture"), "missing (a PNG path or \"mtl\")"))?;
                    let path = if texture.as_os_str() == "mtl" {
                        mesh_texture.clone().ok_or_else(|| {
                            Error::invalid(src, f("material.texture"), "\"mtl\": the OBJ's material has no map_Kd")
                        })?
                    } else {
                        base.join(texture)
                    };
                    if mesh.uvs.is_none() {
                        return Err(Error::invalid(
                            src,
                            f("material.texture"),
                            "the mesh file has no texture coordinates (vt / u v) to look the texture up with",
                        ));
                    }
                    let tex = ImageTexture::load(&path, m.filter.unwrap_or_default(), m.wrap.unwrap_or_default())
                        .map_err(|e| Error::invalid(src, f("material.texture"), e.to_string()))?;
                    Material::Texture(Arc::new(tex))
                }
                (None, Some(kind), false, false) => {
                    let Some(rect) = rect else {
                        return Err(Error::invalid(src, f("material.chart"), "charts are for rects"));
                    };
                    let chart = match kind {
                        ChartKind::Framework => {
                            framework_chart.get_or_insert_with(|| Arc::new(usaf::framework_chart())).clone()
                        }
                        ChartKind::Usaf => {
                            let [g0, g1] = m.groups.unwrap_or([-2, 1]);
                            if g0 > g1 || g0 < -10 || g1 > 10 {
                                return Err(Error::invalid(
                                    src,
                                    f("material.groups"),
                                    format!("expected [first, last] with -10 <= first <= last <= 10, got [{g0}, {g1}]"),
                                ));
                            }
                            let scale = match m.scale.clone().unwrap_or(ChartScaleSpec::Fit) {
                                ChartScaleSpec::Fit => ChartScale::Fit,
                                ChartScaleSpec::Physical => ChartScale::Physical {
                                    half_size: DVec2::new(rect.half_u.length(), rect.half_v.length()),
                                },
                            };
                            Arc::new(usaf::procedural_chart(g0..=g1, scale))
                        }
                        ChartKind::File => {
                            let file = m.file.as_ref().ok_or_else(|| {
                                Error::invalid(src, f("material.file"), "chart = \"file\" needs `file`")
                            })?;
                            let path = base.join(file);
                            let text = read_text(&path)?;
                            Arc::new(crate::scene::BarChart::new(usaf::parse_bar_list(
                                &text,
                                &path.display().to_string(),
                            )?))
                        }
                    };
                    Material::Chart {
                        chart,
                        bar: albedo3(src, &f("material.bar_albedo"), m.bar_albedo.unwrap_or([0.0; 3]))?,
                        backing: albedo3(src, &f("material.backing_albedo"), m.backing_albedo.unwrap_or([1.0; 3]))?,
                    }
                }
                _ => {
                    return Err(Error::invalid(
                        src,
                        f("material"),
                        "give exactly one of `albedo = [r, g, b]`, `chart = \"framework\" | \"usaf\" | \"file\"` \
                         (rects), `vertex_color = true` or `texture = \"file.png\"` (meshes)",
                    ))
                }
            };
            objects.push(Object { name: o.name.clone().unwrap_or_else(|| format!("object {i}")), shape, material });
        }
        if objects.is_empty() {
            return Err(Error::invalid(src, "objects", "a scene needs at least one object"));
        }
        let light = match &self.light {
            None => None,
            Some(l) => {
                let d = finite3(src, "light.direction", l.direction)?;
                if d.length() == 0.0 {
                    return Err(Error::invalid(src, "light.direction", "must be non-zero"));
                }
                let radiance = albedo3(src, "light.radiance", l.radiance)?;
                Some(Light { direction: d.normalize(), radiance })
            }
        };
        Ok(Scene { name: self.name.clone(), objects, background, light, warnings })
    }

    fn rect(&self, src: &str, i: usize, center: DVec3, o: &ObjectSpec) -> Result<Rect> {
        let f = |name: &str| format!("objects[{i}].{name}");
        Ok(match (o.size, o.half_u, o.half_v) {
            (Some([w, h]), None, None) => {
                if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
                    return Err(Error::invalid(
                        src,
                        f("size"),
                        format!("width and height must be positive and finite, got [{w}, {h}]"),
                    ));
                }
                Rect::facing_eye(center, w, h)
            }
            (None, Some(u), Some(v)) => {
                let (hu, hv) = (finite3(src, &f("half_u"), u)?, finite3(src, &f("half_v"), v)?);
                if hu.cross(hv).length() == 0.0 {
                    return Err(Error::invalid(
                        src,
                        f("half_u"),
                        "half_u and half_v must be non-zero and not parallel",
                    ));
                }
                Rect { center, half_u: hu, half_v: hv }
            }
            _ => {
                return Err(Error::invalid(
                    src,
                    f("size"),
                    "give either `size = [width, height]` (facing the eye) or both `half_u` and `half_v`",
                ))
            }
        })
    }

    /// The paper's scene as a file (written to `scenes/paper.toml`).
    pub fn paper() -> Self {
        let chart = |name: &str, c: [f64; 3], w: f64| ObjectSpec {
            name: Some(name.into()),
            kind: ShapeKind::Rect,
            center: Some(c),
            size: Some([w, w]),
            material: MaterialSpec { chart: Some(ChartKind::Framework), ..Default::default() },
            ..ObjectSpec::rect_default()
        };
        SceneSpec {
            name: "paper".into(),
            background: [0.0; 3],
            light: None,
            objects: vec![
                chart("near chart", [-45.0, -45.0, 300.0], 90.0),
                chart("centre chart", [0.0, 0.0, 400.0], 120.0),
                chart("far chart", [90.0, 90.0, 600.0], 180.0),
                ObjectSpec {
                    name: Some("background".into()),
                    kind: ShapeKind::Rect,
                    center: Some([200.0, 0.0, 1302.0]),
                    size: Some([2000.0, 2000.0]),
                    material: MaterialSpec { albedo: Some([0.2, 0.7, 0.8]), ..Default::default() },
                    ..ObjectSpec::rect_default()
                },
            ],
        }
    }
}

impl ObjectSpec {
    fn rect_default() -> Self {
        ObjectSpec {
            name: None,
            kind: ShapeKind::Rect,
            center: None,
            file: None,
            transform: None,
            count: None,
            spacing: None,
            radius: None,
            segments: None,
            size: None,
            half_u: None,
            half_v: None,
            material: MaterialSpec::default(),
        }
    }
}

/// Loads a scene: `builtin:paper` or a TOML file.
pub fn load_scene(spec: &str, base: &Path) -> Result<Scene> {
    if spec == "builtin:paper" {
        return Ok(Scene::paper());
    }
    let path = base.join(spec);
    let text = read_text(&path)?;
    let s: SceneSpec = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
    s.to_scene(&path.display().to_string(), path.parent().unwrap_or(Path::new(".")))
}

/// Directory of a file, for resolving relative paths inside it.
pub fn base_dir(path: &Path) -> PathBuf {
    path.parent().map(Path::to_path_buf).unwrap_or_default()
}
