//! The resolved settings of a run (the experiment of Sec. 4.1 as data): one TOML document
//! holding the experiment with its scene and display inlined as tables, with `--set` overrides
//! ([`crate::overrides`]) applied, then deserialized through the same spec types and built with
//! the same validation as the files. An unknown key or a wrong type is an error naming the
//! `--set` key that caused it. The canonical form of the resolved specs gives a content hash,
//! which identifies a sweep point.
//!
//! A display from the framework's OpenCV YAML, or stated by intent, is inlined through
//! [`DisplaySpec`] (the explicit display), so its keys are ours (`display.lenslets.pitch`).
//! Relative paths in an inlined scene (meshes, textures, bar lists) stay relative to the scene
//! file they came from. `scene` or `display` set to a string loads that file (relative to the
//! override's base) and inlines it.

use std::path::{Path, PathBuf};

use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::error::{Error, Result};
use crate::experiment::{Experiment, ExperimentSpec};
use crate::io::display_file::{is_opencv_yaml, parse_opencv_display, DisplaySpec};
use crate::io::scene_file::SceneSpec;
use crate::io::text::{base_dir, read_text, toml_error};
use crate::optics::Display;
use crate::overrides::Override;
use crate::scene::Scene;

const BUILTIN: &str = "builtin:paper";

/// Where an inlined scene or display came from: its reference as written (a path or
/// `builtin:paper`), a label for errors, and the folder its relative paths resolve against.
#[derive(Clone, Debug, PartialEq)]
struct Origin {
    reference: String,
    label: String,
    base: PathBuf,
    /// Overrides changed it (its errors then name the key in the experiment: `scene.objects[1].size`).
    changed: bool,
}

/// The origins of the parts a document holds.
#[derive(Clone, Debug, Default)]
struct Origins {
    scene: Option<Origin>,
    display: Option<Origin>,
}

/// The experiment (or, for the single-stage commands, just a scene and a display) as one TOML
/// document, and the overrides to apply to it.
#[derive(Clone, Debug)]
pub struct Settings {
    root: toml::Value,
    origins: Origins,
    /// Names the experiment in errors: its file, or what built it in.
    source: String,
    overrides: Vec<Override>,
    /// Only a scene and/or a display, no experiment (the single-stage commands).
    parts_only: bool,
    /// `source` was given by [`Settings::labelled`] and is used as it is.
    labelled: bool,
}

/// Resolved specs: what a run does, deserialized from the document with its overrides.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// `scene` and `display` hold the references of the parts as first given (paths or
    /// `builtin:paper`); the parts themselves are `scene` and `display` below.
    pub experiment: ExperimentSpec,
    /// The scene, inline.
    pub scene: SceneSpec,
    /// The display, inline.
    pub display: DisplaySpec,
    /// The resolved document (experiment with scene and display inline), as deserialized.
    pub document: toml::Value,
    /// Content hash of the settings: 16 hex digits of the SHA-256 of their canonical JSON (the
    /// experiment's `name` and `description` left out: they change no result).
    pub id: String,
    /// Hash of the scene and the folder its files resolve against: points with the same key
    /// share one built scene.
    pub scene_key: String,
    source: String,
    origins: Origins,
}

impl Settings {
    /// An experiment file; its scene and display are inlined (file errors name their line).
    pub fn experiment_file(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        // The file's own errors first, with line numbers, exactly as `Experiment::load`.
        let spec: ExperimentSpec = toml::from_str(&text).map_err(|e| toml_error(path, &text, &e))?;
        let root: toml::Table = toml::from_str(&text).map_err(|e| toml_error(path, &text, &e))?;
        Self::from_table(root, &spec, &path.display().to_string(), &base_dir(path))
    }

    /// A built-in experiment (`source` names it in errors); paths in it are relative to `base`.
    pub fn builtin(spec: &ExperimentSpec, source: &str, base: &Path) -> Result<Self> {
        let root = match to_value(spec)? {
            toml::Value::Table(t) => t,
            _ => return Err(Error::serialize("express the experiment as TOML", "it is not a table")),
        };
        Self::from_table(root, spec, source, base)
    }

    fn from_table(mut root: toml::Table, spec: &ExperimentSpec, source: &str, base: &Path) -> Result<Self> {
        let (scene, scene_origin) =
            inline_scene(&spec.scene, base).map_err(|e| Error::load(source, "scene", &spec.scene, e))?;
        let (display, display_origin) =
            inline_display(&spec.display, base).map_err(|e| Error::load(source, "display", &spec.display, e))?;
        root.insert("scene".into(), scene);
        root.insert("display".into(), display);
        Ok(Self {
            root: toml::Value::Table(root),
            origins: Origins { scene: Some(scene_origin), display: Some(display_origin) },
            source: source.into(),
            overrides: Vec::new(),
            parts_only: false,
            labelled: false,
        })
    }

    /// Only a scene and/or a display (the single-stage commands): `None` for a part the
    /// command does not read, `Some(None)` for the built-in one, `Some(Some(path))` for a file.
    /// Overrides must then start with `scene.` or `display.` (and name a part that is there).
    pub fn parts(scene: Option<Option<&Path>>, display: Option<Option<&Path>>) -> Result<Self> {
        let mut root = toml::Table::new();
        let mut origins = Origins::default();
        let reference = |p: Option<&Path>| p.map(|p| p.display().to_string()).unwrap_or_else(|| BUILTIN.into());
        if let Some(p) = scene {
            let (v, o) = inline_scene(&reference(p), Path::new(""))?;
            root.insert("scene".into(), v);
            origins.scene = Some(o);
        }
        if let Some(p) = display {
            let (v, o) = inline_display(&reference(p), Path::new(""))?;
            root.insert("display".into(), v);
            origins.display = Some(o);
        }
        Ok(Self {
            root: toml::Value::Table(root),
            origins,
            source: "command line".into(),
            overrides: Vec::new(),
            parts_only: true,
            labelled: false,
        })
    }

    /// Replaces the experiment's scene by the file `path` (`assess --scene`).
    pub fn replace_scene(&mut self, path: &Path) -> Result<()> {
        let (v, o) = inline_scene(&path.display().to_string(), Path::new(""))?;
        if let toml::Value::Table(t) = &mut self.root {
            t.insert("scene".into(), v);
        }
        self.origins.scene = Some(o);
        Ok(())
    }

    /// Adds overrides, applied in order after those already given.
    pub fn with_overrides<'a>(mut self, overrides: impl IntoIterator<Item = &'a Override>) -> Self {
        self.overrides.extend(overrides.into_iter().cloned());
        self
    }

    /// Names the run in validation errors (a sweep point: "sweeps/tiny.toml point 3").
    pub fn labelled(mut self, label: impl Into<String>) -> Self {
        self.source = label.into();
        self.labelled = true;
        self
    }

    /// The overrides given so far.
    pub fn overrides(&self) -> &[Override] {
        &self.overrides
    }

    /// The document after the first `k` overrides.
    fn applied(&self, k: usize) -> Result<(toml::Value, Origins)> {
        let mut root = self.root.clone();
        let mut origins = self.origins.clone();
        for o in &self.overrides[..k] {
            let top = o.top();
            let present = root.as_table().is_some_and(|t| t.contains_key(top));
            if self.parts_only && !present {
                let keys: Vec<&str> =
                    root.as_table().map(|t| t.keys().map(String::as_str).collect()).unwrap_or_default();
                let what = keys.iter().map(|k| format!("`{k}.`")).collect::<Vec<_>>().join(" or ");
                return Err(Error::invalid(
                    &o.origin,
                    &o.key,
                    format!("this command reads no experiment: keys start with {what}"),
                ));
            }
            o.apply(&mut root).map_err(|m| Error::invalid(&o.origin, &o.key, m))?;
            for part in ["scene", "display"] {
                let Some(toml::Value::String(reference)) = root.get(part).cloned() else { continue };
                let loaded = if part == "scene" {
                    inline_scene(&reference, &o.base)
                } else {
                    inline_display(&reference, &o.base)
                };
                let (v, origin) = loaded.map_err(|e| Error::load(&o.origin, &o.key, &reference, e))?;
                root.as_table_mut().expect("a table").insert(part.into(), v);
                if part == "scene" {
                    origins.scene = Some(origin);
                } else {
                    origins.display = Some(origin);
                }
            }
        }
        Ok((root, origins))
    }

    /// Applies the overrides and deserializes the result through the spec types. A failure is
    /// blamed on the first override after which the document no longer deserializes.
    fn decode<T>(
        &self,
        decode: impl Fn(&toml::Value) -> std::result::Result<T, String>,
    ) -> Result<(T, toml::Value, Origins)> {
        let (root, origins) = self.applied(self.overrides.len())?;
        match decode(&root) {
            Ok(t) => Ok((t, root, origins)),
            Err(message) => {
                for k in 1..=self.overrides.len() {
                    let (partial, _) = self.applied(k)?;
                    if let Err(m) = decode(&partial) {
                        let o = &self.overrides[k - 1];
                        return Err(Error::invalid(&o.origin, &o.key, m));
                    }
                }
                Err(Error::invalid(&self.source, "", message))
            }
        }
    }

    /// The label of validation errors: the experiment (or a part's file) and, unless the run
    /// is labelled, the overrides that changed it.
    fn label(&self, part: Option<&Origin>, prefix: &str) -> String {
        let touched: Vec<String> =
            self.overrides.iter().filter(|o| prefix.is_empty() || o.top() == prefix).map(|o| o.to_arg()).collect();
        match (part, touched.is_empty(), self.labelled) {
            (None, _, true) => self.source.clone(),
            (None, true, false) => self.source.clone(),
            (None, false, false) => format!("{} with --set {}", self.source, touched.join(" --set ")),
            (Some(o), true, _) => o.label.clone(),
            (Some(o), false, true) => format!("{} as changed by {}", o.label, self.source),
            (Some(o), false, false) => format!("{} with --set {}", o.label, touched.join(" --set ")),
        }
    }

    /// Resolves the experiment document (errors if this holds only parts).
    pub fn resolve(&self) -> Result<Resolved> {
        let ((experiment, scene, display), document, origins) = self.decode(decode_experiment)?;
        let (scene_origin, display_origin) = match (&origins.scene, &origins.display) {
            (Some(s), Some(d)) => (s.clone(), d.clone()),
            _ => return Err(Error::Mismatch("not an experiment: it has no scene or no display".into())),
        };
        let mut experiment = experiment;
        experiment.scene = scene_origin.reference.clone();
        experiment.display = display_origin.reference.clone();
        let id = content_hash(&experiment, &scene, &display)?;
        let scene_key = hash_json(&(&scene, scene_origin.base.display().to_string()))?;
        Ok(Resolved {
            experiment,
            scene,
            display,
            document,
            id,
            scene_key,
            source: self.label(None, ""),
            origins: Origins {
                scene: Some(Origin {
                    label: self.label(Some(&scene_origin), "scene"),
                    changed: self.overrides.iter().any(|o| o.top() == "scene"),
                    ..scene_origin
                }),
                display: Some(Origin {
                    label: self.label(Some(&display_origin), "display"),
                    changed: self.overrides.iter().any(|o| o.top() == "display"),
                    ..display_origin
                }),
            },
        })
    }

    /// The scene of a parts-only document, built.
    pub fn scene(&self) -> Result<Scene> {
        let (spec, _, origins) = self.decode(|v| decode_part::<SceneSpec>(v, "scene"))?;
        let o = origins.scene.ok_or_else(|| Error::Mismatch("no scene".into()))?;
        spec.to_scene(&self.label(Some(&o), "scene"), &o.base)
    }

    /// The display of a parts-only document, built.
    pub fn display(&self) -> Result<Display> {
        let (spec, _, origins) = self.decode(|v| decode_part::<DisplaySpec>(v, "display"))?;
        let o = origins.display.ok_or_else(|| Error::Mismatch("no display".into()))?;
        spec.to_display(&self.label(Some(&o), "display"))
    }
}

impl Resolved {
    /// Builds the scene (meshes and textures loaded from their files).
    pub fn build_scene(&self) -> Result<Scene> {
        let o = self.origins.scene.as_ref().expect("resolved with a scene");
        self.scene.to_scene(&o.label, &o.base).map_err(|e| self.part_error(e, o, "scene"))
    }

    /// An error of a part: in a part that overrides changed, the key in the experiment
    /// (`scene.objects[1].size`); otherwise the part's file inside the experiment's field.
    fn part_error(&self, e: Error, o: &Origin, part: &str) -> Error {
        match e {
            Error::Invalid { field, message, .. } if o.changed => {
                Error::invalid(&self.source, format!("{part}.{field}"), message)
            }
            Error::Lattice { field, message, .. } if o.changed => {
                Error::Lattice { source_name: self.source.clone(), field: format!("{part}.{field}"), message }
            }
            Error::Memory { field, message, .. } if o.changed => {
                Error::Memory { source_name: self.source.clone(), field: format!("{part}.{field}"), message }
            }
            e => Error::load(&self.source, part, &o.reference, e),
        }
    }

    /// Builds the experiment around an already built scene (points sharing a scene).
    pub fn experiment_with(&self, scene: Scene) -> Result<Experiment> {
        let o = self.origins.display.as_ref().expect("resolved with a display");
        let display = self.display.to_display(&o.label).map_err(|e| self.part_error(e, o, "display"))?;
        Experiment::from_parts(self.experiment.clone(), scene, display, &self.source)
    }

    /// Builds the experiment.
    pub fn experiment(&self) -> Result<Experiment> {
        self.experiment_with(self.build_scene()?)
    }
}

/// Loads a single-stage command's scene (`--scene`, default the paper's) with `overrides`
/// (keys `scene.…`).
pub fn scene_with(path: Option<&Path>, overrides: &[Override]) -> Result<Scene> {
    Settings::parts(Some(path), None)?.with_overrides(overrides).scene()
}

/// Loads a single-stage command's display (`--display`, default the paper's) with `overrides`
/// (keys `display.…`).
pub fn display_with(path: Option<&Path>, overrides: &[Override]) -> Result<Display> {
    Settings::parts(None, Some(path))?.with_overrides(overrides).display()
}

/// Loads a single-stage command's scene and display with `overrides` (keys `scene.…` or
/// `display.…`).
pub fn setup_with(scene: Option<&Path>, display: Option<&Path>, overrides: &[Override]) -> Result<(Scene, Display)> {
    let s = Settings::parts(Some(scene), Some(display))?.with_overrides(overrides);
    Ok((s.scene()?, s.display()?))
}

/// A scene as the single-stage commands load it: `path` (`None`: the paper's) with `overrides`
/// (keys `scene.…`); without overrides the file is read directly, its errors naming it.
pub fn load_scene_part(path: Option<&Path>, overrides: &[Override]) -> Result<Scene> {
    match path {
        _ if !overrides.is_empty() => scene_with(path, overrides),
        Some(p) => crate::io::load_scene(&p.to_string_lossy(), Path::new("")),
        None => Ok(Scene::paper()),
    }
}

/// A display as the single-stage commands load it: `path` (`None`: the paper's) with
/// `overrides` (keys `display.…`); without overrides the file is read directly.
pub fn load_display_part(path: Option<&Path>, overrides: &[Override]) -> Result<Display> {
    match path {
        _ if !overrides.is_empty() => display_with(path, overrides),
        Some(p) => crate::io::load_display(&p.to_string_lossy(), Path::new("")),
        None => Ok(Display::paper()),
    }
}

/// An experiment as `inimtrace assess` loads it: the file at `path` (`None`: the paper's
/// experiment measured converged), its scene replaced by the file `scene` when given, then
/// `overrides` applied (through the resolved settings, so errors name the key).
///
/// ```
/// use inimtrace::optics::Aperture;
/// use inimtrace::overrides::{parse_value, Override};
/// use inimtrace::settings::load_experiment;
///
/// // The built-in experiment: the paper's four eye cases and three methods.
/// let exp = load_experiment(None, None, &[])?;
/// let names: Vec<&str> = exp.cases.iter().map(|c| c.name.as_str()).collect();
/// assert_eq!(names, ["Pin", "Near", "Cen", "Far"]);
/// assert_eq!(exp.methods.len(), 3);
///
/// // `--set eye.pupil_diameter=3`: a 3 mm pupil for every thin-lens eye case.
/// let set = [Override::new("eye.pupil_diameter", parse_value("3").unwrap()).unwrap()];
/// let exp = load_experiment(None, None, &set)?;
/// let near = exp.cases[1].eye.aperture;
/// assert!(matches!(near, Aperture::ThinLens { pupil_diameter, .. } if pupil_diameter == 3.0));
///
/// // A bad value is refused, naming the key.
/// let bad = [Override::new("eye.pupil_diameter", parse_value("-1").unwrap()).unwrap()];
/// let err = load_experiment(None, None, &bad).unwrap_err().to_string();
/// assert!(err.contains("pupil_diameter"), "{err}");
/// # Ok::<(), inimtrace::Error>(())
/// ```
pub fn load_experiment(path: Option<&Path>, scene: Option<&Path>, overrides: &[Override]) -> Result<Experiment> {
    let (exp, files) = crate::provenance::recording(|| load_experiment_files(path, scene, overrides));
    let mut exp = exp?;
    exp.provenance = provenance_of(&exp, path.map(|p| p.display().to_string()), files, overrides);
    Ok(exp)
}

/// The provenance of `exp`: its experiment file as given (`None`: built in), the files read to
/// load it, the overrides applied, its budgets and seed.
pub fn provenance_of(
    exp: &Experiment,
    experiment_path: Option<String>,
    files: Vec<crate::provenance::InputFile>,
    overrides: &[Override],
) -> crate::provenance::Provenance {
    let m = &exp.measurement;
    crate::provenance::Provenance {
        experiment_path,
        study_path: None,
        scene_name: exp.scene.name.clone(),
        scene_path: exp.spec.scene.clone(),
        display_path: exp.spec.display.clone(),
        files,
        set: overrides.iter().map(Override::to_arg).collect(),
        budgets: crate::provenance::Budgets {
            estimator: m.estimator.name().to_string(),
            psnr_ci95_db: m.psnr_ci95_db,
            ssim_ci95: m.ssim_ci95,
            max_samples_per_pixel: m.max_samples_per_pixel,
            max_seconds: m.max_seconds,
            memory_bytes: crate::budget::memory_budget().bytes,
        },
        seed: m.seed,
        working_directory: std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default(),
    }
}

/// [`load_experiment`] without its provenance.
fn load_experiment_files(path: Option<&Path>, scene: Option<&Path>, overrides: &[Override]) -> Result<Experiment> {
    if !overrides.is_empty() {
        let mut s = match path {
            Some(p) => Settings::experiment_file(p)?,
            None => Settings::builtin(
                &ExperimentSpec::paper_converged(),
                "built-in paper-converged experiment",
                Path::new("."),
            )?,
        };
        if let Some(p) = scene {
            s.replace_scene(p)?;
        }
        return s.with_overrides(overrides).resolve()?.experiment();
    }
    let mut exp = match path {
        Some(p) => Experiment::load(p)?,
        None => Experiment::paper_converged(),
    };
    if let Some(p) = scene {
        exp.scene = crate::io::load_scene(&p.to_string_lossy(), Path::new(""))?;
        exp.spec.scene = p.display().to_string();
    }
    Ok(exp)
}

type ExperimentSpecs = (ExperimentSpec, SceneSpec, DisplaySpec);

fn decode_experiment(root: &toml::Value) -> std::result::Result<ExperimentSpecs, String> {
    let mut table = root.as_table().cloned().unwrap_or_default();
    let scene = table.remove("scene").unwrap_or(toml::Value::Boolean(false));
    let display = table.remove("display").unwrap_or(toml::Value::Boolean(false));
    let experiment: ExperimentSpec = toml::Value::Table(table).try_into().map_err(|e: toml::de::Error| message(&e))?;
    let scene =
        decode_part::<SceneSpec>(&toml::Value::Table([("scene".to_string(), scene)].into_iter().collect()), "scene")?;
    let display = decode_part::<DisplaySpec>(
        &toml::Value::Table([("display".to_string(), display)].into_iter().collect()),
        "display",
    )?;
    Ok((experiment, scene, display))
}

fn decode_part<T: serde::de::DeserializeOwned>(root: &toml::Value, part: &str) -> std::result::Result<T, String> {
    match root.get(part) {
        Some(v @ toml::Value::Table(_)) => {
            v.clone().try_into().map_err(|e: toml::de::Error| format!("{part}: {}", message(&e)))
        }
        Some(other) => Err(format!("`{part}` must be a table or a file path, got {}", other.type_str())),
        None => Err(format!("no `{part}`")),
    }
}

fn message(e: &toml::de::Error) -> String {
    e.message().trim().replace('\n', " ")
}

fn to_value<T: Serialize>(v: &T) -> Result<toml::Value> {
    toml::Value::try_from(v).map_err(|e| Error::serialize("express settings as TOML", e))
}

/// A scene reference (`builtin:paper` or a TOML path relative to `base`) as a TOML table.
fn inline_scene(reference: &str, base: &Path) -> Result<(toml::Value, Origin)> {
    if reference == BUILTIN {
        let origin = Origin {
            reference: reference.into(),
            label: "built-in paper scene".into(),
            base: ".".into(),
            changed: false,
        };
        return Ok((to_value(&SceneSpec::paper())?, origin));
    }
    let path = base.join(reference);
    let text = read_text(&path)?;
    let _: SceneSpec = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
    let scene_base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let origin =
        Origin { reference: reference.into(), label: path.display().to_string(), base: scene_base, changed: false };
    Ok((toml::Value::Table(table), origin))
}

/// A display reference (`builtin:paper`, our TOML or the framework's OpenCV YAML, relative to
/// `base`) as a TOML table in our display format (a display stated by intent as the explicit
/// display derived from it).
fn inline_display(reference: &str, base: &Path) -> Result<(toml::Value, Origin)> {
    let builtin = reference == BUILTIN;
    let path = base.join(reference);
    let label = if builtin { "built-in paper display".to_string() } else { path.display().to_string() };
    let origin = Origin { reference: reference.into(), label, base: base_dir(&path), changed: false };
    if builtin {
        return Ok((to_value(&DisplaySpec::from_display(&Display::paper()))?, origin));
    }
    let text = read_text(&path)?;
    if is_opencv_yaml(&text, &path) {
        let display = parse_opencv_display(&text, &path)?;
        return Ok((to_value(&DisplaySpec::from_display(&display))?, origin));
    }
    if crate::io::display_intent::states_intent(&text) {
        let (display, _) = crate::io::display_intent::parse_intent_display(&text, &path)?;
        return Ok((to_value(&DisplaySpec::from_display(&display))?, origin));
    }
    let _: DisplaySpec = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| toml_error(&path, &text, &e))?;
    Ok((toml::Value::Table(table), origin))
}

/// The settings' content hash (see [`Resolved::id`]).
fn content_hash(experiment: &ExperimentSpec, scene: &SceneSpec, display: &DisplaySpec) -> Result<String> {
    #[derive(Serialize)]
    struct Canonical<'a> {
        experiment: &'a ExperimentSpec,
        scene: &'a SceneSpec,
        display: &'a DisplaySpec,
    }
    let experiment = ExperimentSpec {
        name: String::new(),
        description: None,
        scene: String::new(),
        display: String::new(),
        ..experiment.clone()
    };
    hash_json(&Canonical { experiment: &experiment, scene, display })
}

/// 16 hex digits of the SHA-256 of a value's JSON (struct fields in declaration order, floats
/// in shortest round-trip form: the same settings always give the same text).
pub fn hash_json<T: Serialize>(v: &T) -> Result<String> {
    let text = serde_json::to_string(v).map_err(|e| Error::serialize("hash settings", e))?;
    let digest = Sha256::digest(text.as_bytes());
    Ok(digest.iter().take(8).map(|b| format!("{b:02x}")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    fn set(texts: &[&str]) -> Vec<Override> {
        texts.iter().map(|t| t.parse().unwrap()).collect()
    }

    fn paper_file() -> Settings {
        Settings::experiment_file(&root().join("experiments/paper.toml")).unwrap()
    }

    #[test]
    fn without_overrides_the_file_resolves_as_it_loads() {
        let r = paper_file().resolve().unwrap();
        let loaded = Experiment::load(&root().join("experiments/paper.toml")).unwrap();
        assert_eq!(r.experiment, loaded.spec);
        let exp = r.experiment().unwrap();
        assert_eq!(format!("{:?}", exp.display), format!("{:?}", loaded.display));
        assert_eq!(format!("{:?}", exp.scene.objects), format!("{:?}", loaded.scene.objects));
        assert_eq!(format!("{:?}", exp.cases), format!("{:?}", loaded.cases));
        // The built-in experiment is the file (same settings, same hash).
        let builtin =
            Settings::builtin(&ExperimentSpec::paper(), "built-in", Path::new(".")).unwrap().resolve().unwrap();
        assert_eq!(builtin.id, r.id);
        assert_eq!(format!("{:?}", builtin.experiment().unwrap().scene.objects), format!("{:?}", loaded.scene.objects));
    }

    #[test]
    fn overrides_reach_the_eye_cases_display_and_scene() {
        let s = paper_file().with_overrides(&set(&[
            "eye.pupil_diameter=3",
            "eye_cases[1].focus_mm=250",
            "display.lenslets.pitch=1.0",
            "scene.objects[0].center=[0, 0, 350]",
            "display_render.la_grid=3",
        ]));
        let r = s.resolve().unwrap();
        assert_eq!(r.experiment.eye.pupil_diameter, crate::optics::eye::pupil::PupilSetting::Mm(3.0));
        assert_eq!(r.experiment.eye_cases[1].focus_mm, Some(250.0));
        assert_eq!(r.experiment.display_render.la_grid, 3);
        let exp = r.experiment().unwrap();
        assert_eq!(exp.display.lenslets.row_major(), [1.0, 0.0, 0.0, 1.0]);
        assert!(
            matches!(exp.cases[1].eye.aperture, crate::optics::Aperture::ThinLens { pupil_diameter, .. } if pupil_diameter == 3.0)
        );
        assert!(format!("{:?}", exp.scene.objects[0].shape).contains("350.0"));
        assert_ne!(r.id, paper_file().resolve().unwrap().id);
    }

    #[test]
    fn unknown_keys_and_wrong_types_name_the_key() {
        for (arg, words) in [
            ("eye.pupil_diam=3", vec!["eye.pupil_diam", "pupil_diam"]),
            ("eye.pupil_diameter=\"big\"", vec!["eye.pupil_diameter", "big"]),
            ("eye.pupil_grid=2.5", vec!["eye.pupil_grid"]),
            ("display.lenslets.focal=3", vec!["display.lenslets.focal", "focal"]),
            ("scene.objects[0].centre=[0, 0, 1]", vec!["scene.objects[0].centre", "centre"]),
            ("colour=1", vec!["colour"]),
            ("eye_cases[9].focus_mm=1", vec!["eye_cases[9]", "4 entries"]),
        ] {
            let e =
                paper_file().with_overrides(&set(&["eye.pupil_diameter=4", arg])).resolve().unwrap_err().to_string();
            for w in words {
                assert!(e.contains(w), "--set {arg}: `{e}` does not mention {w}");
            }
        }
        // A value that deserializes but is impossible: the experiment's own validation.
        let e = paper_file().with_overrides(&set(&["eye.pupil_diameter=-1"])).resolve().unwrap().experiment();
        let e = e.unwrap_err().to_string();
        assert!(e.contains("pupil_diameter") && e.contains("--set eye.pupil_diameter=-1"), "{e}");
    }

    #[test]
    fn a_scene_or_display_set_to_a_path_is_loaded_and_inlined() {
        let yaml = root().join("data/lensletdisplay.yaml");
        let over = vec![
            Override::new("display", toml::Value::String(yaml.display().to_string())).unwrap(),
            "display.lenslets_to_lcd=6.2".parse().unwrap(),
        ];
        let r = paper_file().with_overrides(&over).resolve().unwrap();
        assert_eq!(r.display.lenslets_to_lcd, 6.2);
        assert_eq!(r.display.lcd.resolution, [2160, 2160]);
        let e = paper_file().with_overrides(&set(&["scene=missing-scene.toml"])).resolve().unwrap_err().to_string();
        assert!(e.contains("missing-scene.toml") && e.contains("--set"), "{e}");
    }

    #[test]
    fn single_stage_commands_take_scene_and_display_keys_only() {
        let (s, d) = setup_with(None, None, &set(&["display.lcd.resolution=[540, 540]", "scene.name=\"x\""])).unwrap();
        assert_eq!(d.lcd.resolution, [540, 540]);
        assert_eq!(s.name, "x");
        let e = display_with(None, &set(&["scene.name=\"x\""])).unwrap_err().to_string();
        assert!(e.contains("scene.name") && e.contains("`display.`"), "{e}");
        let s = scene_with(None, &set(&["scene.objects[1].size=[10, 10]"])).unwrap();
        assert!(format!("{:?}", s.objects[1].shape).contains("5.0"));
        let e = display_with(None, &set(&["eye.pupil_diameter=3"])).unwrap_err().to_string();
        assert!(e.contains("eye.pupil_diameter") && e.contains("`display.`"), "{e}");
        let e = display_with(None, &set(&["display.lcd.size=3"])).unwrap_err().to_string();
        assert!(e.contains("display.lcd.size"), "{e}");
    }

    #[test]
    fn the_hash_depends_on_settings_not_on_how_they_are_written() {
        let a = paper_file().resolve().unwrap().id;
        // Setting a value to what it already is, or renaming the experiment, keeps the hash.
        let b = paper_file().with_overrides(&set(&["eye.pupil_diameter=5.0", "name=\"other\""])).resolve().unwrap();
        assert_eq!(a, b.id);
        let c = paper_file().with_overrides(&set(&["eye.pupil_diameter=5.000001"])).resolve().unwrap().id;
        assert_ne!(a, c);
        assert_eq!(a.len(), 16);
    }
}
