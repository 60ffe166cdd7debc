//! `inimtrace info`: a display's design figures, a scene's summary, a schematic eye's data (on
//! axis and at field angles), or the built-in files.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use inimtrace::experiment::ExperimentSpec;
use inimtrace::io::display_file::DisplaySpec;
use inimtrace::io::scene_file::SceneSpec;
use inimtrace::io::{load_display, load_scene};
use inimtrace::optics::Display;
use inimtrace::settings::{display_with, scene_with};

use crate::{Globals, PrintTarget};

/// `inimtrace info`; returns whether it printed its own total time.
pub(crate) fn info(
    g: &Globals,
    display: Option<PathBuf>,
    scene: Option<PathBuf>,
    (pupil, diffraction): (String, inimtrace::optics::diffraction::Diffraction),
    json: bool,
    print: Option<PrintTarget>,
    write_display: Option<(PathBuf, bool)>,
) -> Result<bool> {
    let set = &g.set[..];
    if let Some(what) = print {
        if !set.is_empty() {
            bail!("--set does not apply to --print (it prints the built-in files as they are)");
        }
        let text = match what {
            PrintTarget::PaperExperiment => ExperimentSpec::paper_converged().to_toml(),
            PrintTarget::PaperGridExperiment => ExperimentSpec::paper().to_toml(),
            PrintTarget::Framework2020Experiment => ExperimentSpec::framework_2020().to_toml(),
            PrintTarget::PaperScene => toml::to_string_pretty(&SceneSpec::paper())?,
            PrintTarget::PaperDisplay => toml::to_string_pretty(&DisplaySpec::from_display(&Display::paper()))?,
        };
        out!("{text}");
        return Ok(true);
    }
    let auto = pupil == "auto";
    if let (Some(p), false) = (&scene, auto) {
        if display.is_some() {
            bail!("--display with --scene needs --pupil auto (the scene then sets the adapting luminance)");
        }
        let scene = match set.is_empty() {
            true => load_scene(&p.to_string_lossy(), Path::new(""))?,
            false => scene_with(Some(p), set)?,
        };
        // What loading noticed (an unreadable texture or material library), always.
        for w in &scene.warnings {
            eprintln!("warning: {w}");
        }
        let summary = inimtrace::info::scene_summary(&scene);
        match json {
            true => outln!("{}", serde_json::to_string_pretty(&summary)?),
            false => {
                out!("{}", inimtrace::info::scene_summary_text(&summary));
                outln!("backend library: {}", inimtrace::version::embree_loaded());
            }
        }
        return Ok(true);
    }
    let d = match display {
        _ if !set.is_empty() => display_with(display.as_deref(), set)?,
        Some(ref p) => load_display(&p.to_string_lossy(), Path::new(""))?,
        None => Display::paper(),
    };
    let auto_pupil = match auto {
        true => Some(auto_pupil(scene.as_deref(), &d)?),
        false => None,
    };
    let pupil = match (&auto_pupil, pupil.parse::<f64>()) {
        (Some(a), _) => (a.diameter_mm * 1000.0).round() / 1000.0,
        (None, Ok(p)) if p.is_finite() && p > 0.0 => p,
        _ => bail!("--pupil must be a positive number of mm or `auto`, got {pupil}"),
    };
    let source = display.as_ref().map_or_else(|| "builtin:paper".to_string(), |p| p.display().to_string());
    for w in inimtrace::optics::plausibility::display_warnings(&d, &source) {
        eprintln!("warning: {w}");
    }
    // A display stated by intent: how the explicit one follows (the file's, before any --set).
    let derivation = match &display {
        Some(p) if set.is_empty() => inimtrace::io::display_intent::derivation_of(p)?,
        _ => None,
    };
    if let Some((path, force)) = write_display {
        let mut header = format!(
            "The explicit display of {source}{}, written by inimtrace info --write-display.\n",
            if set.is_empty() { "" } else { " with --set overrides" }
        );
        if let Some(x) = &derivation {
            header += &x.text();
        }
        inimtrace::io::display_intent::write_display_file(&d, &header, &path, force)?;
        eprintln!("wrote {}", path.display());
    }
    let mut design = inimtrace::info::display_design(&d, pupil);
    design.diffraction = inimtrace::info::diffraction_info(&d, pupil, diffraction);
    match json {
        true => {
            let mut v = serde_json::to_value(&design)?;
            if let (Some(x), Some(map)) = (&derivation, v.as_object_mut()) {
                map.insert("intent_derivation".into(), serde_json::to_value(x)?);
            }
            if let (Some(p), Some(map)) = (&auto_pupil, v.as_object_mut()) {
                map.insert("auto_pupil".into(), serde_json::to_value(p)?);
            }
            outln!("{}", serde_json::to_string_pretty(&v)?)
        }
        false => {
            if let Some(x) = &derivation {
                out!("{}", x.text());
            }
            out!("{}", inimtrace::info::display_design_text(&design, &d.summary()));
            if let Some(p) = &auto_pupil {
                outln!("{}", p.text());
            }
            outln!("backend library: {}", inimtrace::version::embree_loaded());
        }
    }
    Ok(false)
}

/// `--pupil auto`: the light-adapted pupil of the default observer for `scene` (a file, or the
/// paper's scene) shown by `d` to an eye at the origin.
fn auto_pupil(scene: Option<&Path>, d: &Display) -> Result<inimtrace::optics::eye::pupil::AutoPupil> {
    let scene = match scene {
        Some(p) => load_scene(&p.to_string_lossy(), Path::new(""))?,
        None => load_scene("builtin:paper", Path::new(""))?,
    };
    let observer = inimtrace::optics::eye::pupil::Observer::default();
    Ok(inimtrace::render::adapting::auto_pupil(&scene, d, glam::DVec3::ZERO, observer)?)
}

/// `inimtrace info --eye MODEL`: the schematic eye's data at `focus_diopters` (default the
/// relaxed eye's paraxial focus) and its off-axis foci at `fields_deg`, as text or JSON; `--eye
/// user` reads its surface table from `eye_file`.
pub(crate) fn eye_info(
    model: &str,
    eye_file: Option<&Path>,
    focus_diopters: Option<f64>,
    fields_deg: &[f64],
    pupil: &str,
    json: bool,
) -> Result<()> {
    use inimtrace::optics::eye::{describe::describe, EyeModel, FocusCriterion, SchematicEye};
    let model = match (model, eye_file) {
        ("user", Some(path)) => inimtrace::io::eye_file::load_user_eye(path)?,
        ("user", None) => bail!("--eye user needs --eye-file FILE (a TOML file with an [eye.user] table)"),
        (name, Some(_)) => bail!("--eye-file is read only with --eye user, not --eye {name}"),
        (name, None) => EyeModel::parse(name, None, "--eye")?,
    };
    let pupil = match pupil.parse::<f64>() {
        Ok(p) if p.is_finite() && p > 0.0 => p,
        _ => bail!("--pupil must be a diameter in mm with --eye, got `{pupil}`"),
    };
    let focus = match focus_diopters {
        Some(f) => f,
        None => SchematicEye::new(&model, model.accommodation_range().0, "--eye")?.paraxial(555.0).conjugate_vergence_d,
    };
    let d = describe(&model, focus, pupil, FocusCriterion::Paraxial, 555.0, (fields_deg, "--field-deg"))?;
    match json {
        true => outln!("{}", serde_json::to_string_pretty(&d)?),
        false => out!("{}", d.text()),
    }
    Ok(())
}
