//! Display files stated by intent (the design of paper Sec. 2.2): a display TOML with an
//! `[intent]` table instead of `eye_to_lenslets`, `lenslets_to_lcd`, `[lenslets]` and
//! `[elemental_images]`. [`crate::optics::intent`] derives the explicit display; the rest of
//! inimtrace (and `--set`, sweeps and studies) sees that explicit display, as it sees the
//! framework's OpenCV YAML through our format. `info --write-display` writes it out.
//!
//! A `[lenslet]` table of kind `"thick"` (as in an explicit file, [`super::display_lenslet`]) makes
//! the derivation use the real lenslet's focal properties at the d line; `focal_length` may then be
//! omitted (the surfaces give it) and is checked against them when given.
//!
//! ```toml
//! name = "hexagonal 1 mm"          # optional
//! [intent]
//! central_depth_plane = 500.0      # z of the CDP from the pupil, mm (inf: at infinity)
//! eye_to_lenslets = 20.0           # v1, the eye relief
//! focal_length = 4.0               # the lenslets' f
//! lattice = "hexagonal"            # or "square"
//! lenslet_pitch = 1.0              # neighbour distance; or views_across_pupil (+ pupil_diameter)
//! [lcd]
//! size = [21.6, 21.6]
//! resolution = [2160, 2160]
//! ```

use std::path::Path;

use glam::DVec2;
use serde::Deserialize;

use super::display_file::{DisplaySpec, LcdSpec};
use super::text::toml_error;
use crate::error::{Error, Result};
use crate::optics::intent::{Derivation, DisplayIntent, LatticeKind, PitchIntent, DEFAULT_PUPIL_MM};
use crate::optics::lenslet::{LensletOptics, D_LINE_NM};
use crate::optics::{Display, Lcd};

/// The `[intent]` table.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IntentSpec {
    /// z of the central depth plane from the pupil centre, mm.
    pub central_depth_plane: f64,
    /// v1, mm.
    pub eye_to_lenslets: f64,
    /// The lenslets' focal length, mm (optional with a thick lenslet: its effective focal length).
    #[serde(default)]
    pub focal_length: Option<f64>,
    /// `"square"` or `"hexagonal"`.
    pub lattice: LatticeName,
    /// Lenslet neighbour distance, mm.
    #[serde(default)]
    pub lenslet_pitch: Option<f64>,
    /// Views across the pupil (instead of `lenslet_pitch`).
    #[serde(default)]
    pub views_across_pupil: Option<f64>,
    /// The pupil of `views_across_pupil`, mm (default 5).
    #[serde(default)]
    pub pupil_diameter: Option<f64>,
}

/// A lattice's name in the file.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LatticeName {
    /// Square.
    Square,
    /// Hexagonal, rows along x.
    Hexagonal,
}

/// A display file stated by intent.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IntentDisplaySpec {
    /// Display name (default: the file's path).
    #[serde(default)]
    pub name: Option<String>,
    /// `[intent]`.
    pub intent: IntentSpec,
    /// `[lcd]`.
    pub lcd: LcdSpec,
    /// `[primaries]`.
    #[serde(default)]
    pub primaries: Option<crate::optics::spectrum::Primaries>,
    /// `[lenslet]`: the paraxial lenslet (the default) or a thick one, whose focal properties the
    /// derivation uses.
    #[serde(default)]
    pub lenslet: Option<super::display_lenslet::LensletOpticsSpec>,
    /// `[photometry]`, passed through.
    #[serde(default)]
    pub photometry: Option<crate::optics::photometry::PhotometrySpec>,
}

impl IntentDisplaySpec {
    /// The intent, checked for what the file alone can tell (which fields were given).
    pub fn to_intent(&self, source: &str) -> Result<DisplayIntent> {
        let lenslet = match &self.lenslet {
            Some(l) => l.to_optics(source)?,
            None => LensletOptics::Paraxial,
        };
        let focal_length = match (self.intent.focal_length, lenslet.thick()) {
            (Some(f), _) => f,
            (None, Some(t)) => t.paraxial(D_LINE_NM).efl,
            (None, None) => {
                return Err(Error::invalid(
                    source,
                    "intent.focal_length",
                    "missing: give the lenslets' focal length in mm (or a thick [lenslet], whose surfaces give it)",
                ))
            }
        };
        let i = &self.intent;
        let pitch = match (i.lenslet_pitch, i.views_across_pupil) {
            (Some(p), None) => {
                if i.pupil_diameter.is_some() {
                    return Err(Error::invalid(
                        source,
                        "intent.pupil_diameter",
                        "only goes with intent.views_across_pupil (the pitch is stated)",
                    ));
                }
                PitchIntent::Pitch(p)
            }
            (None, Some(views)) => {
                PitchIntent::Views { views, pupil_diameter: i.pupil_diameter.unwrap_or(DEFAULT_PUPIL_MM) }
            }
            (Some(_), Some(_)) => {
                return Err(Error::invalid(
                    source,
                    "intent.views_across_pupil",
                    "give either intent.lenslet_pitch or intent.views_across_pupil, not both (each determines \
                     the other)",
                ))
            }
            (None, None) => {
                return Err(Error::invalid(
                    source,
                    "intent.lenslet_pitch",
                    "missing: give intent.lenslet_pitch (mm) or intent.views_across_pupil",
                ))
            }
        };
        Ok(DisplayIntent {
            name: self.name.clone().unwrap_or_else(|| source.to_string()),
            central_depth_plane: i.central_depth_plane,
            eye_to_lenslets: i.eye_to_lenslets,
            focal_length,
            lenslet,
            pitch,
            lattice: match i.lattice {
                LatticeName::Square => LatticeKind::Square,
                LatticeName::Hexagonal => LatticeKind::Hexagonal,
            },
            lcd: Lcd { size: DVec2::from_array(self.lcd.size), resolution: self.lcd.resolution },
            primaries: self.primaries.clone(),
            photometry: self.photometry.as_ref().map(|p| p.resolve(source)).transpose()?,
        })
    }

    /// The explicit display and its derivation; errors name `source` and the field.
    pub fn to_display(&self, source: &str) -> Result<(Display, Derivation)> {
        self.to_intent(source)?.to_display(source)
    }
}

/// Whether a display TOML states intent (has an `[intent]` table) rather than the explicit display.
pub fn states_intent(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| t.contains_key("intent"))
}

/// Reads a display TOML stated by intent (`text` read from `path`): the explicit display and
/// its derivation.
pub fn parse_intent_display(text: &str, path: &Path) -> Result<(Display, Derivation)> {
    let spec: IntentDisplaySpec = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    spec.to_display(&path.display().to_string())
}

/// The explicit display file of `d` as TOML, headed by comments naming where it came from.
pub fn explicit_display_toml(d: &Display, header: &str) -> Result<String> {
    let body =
        toml::to_string(&DisplaySpec::from_display(d)).map_err(|e| Error::serialize("write the display as TOML", e))?;
    let comments: String = header.lines().map(|l| format!("# {l}\n").replace("# \n", "#\n")).collect();
    Ok(format!("{comments}{body}"))
}

/// The derivation of the display file at `path` when it states intent; `None` for any other
/// display file.
pub fn derivation_of(path: &Path) -> Result<Option<Derivation>> {
    let text = super::text::read_text(path)?;
    if super::display_file::is_opencv_yaml(&text, path) || !states_intent(&text) {
        return Ok(None);
    }
    parse_intent_display(&text, path).map(|(_, x)| Some(x))
}

/// Writes `d` as an explicit display TOML to `path` atomically (headed by `header` as comments);
/// an existing file is refused unless `force`.
pub fn write_display_file(d: &Display, header: &str, path: &Path, force: bool) -> Result<()> {
    if !force && std::fs::symlink_metadata(path).is_ok() {
        return Err(Error::invalid(
            path.display().to_string(),
            "--write-display",
            "the file exists; give --force to replace it",
        ));
    }
    let text = explicit_display_toml(d, header)?;
    super::output::write_atomic(path, |p| std::fs::write(p, &text).map_err(|e| Error::io(p, e)))
}
