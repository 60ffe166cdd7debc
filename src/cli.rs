//! The command line's shared pieces (the CLI of the paper's pipeline, Sec. 4): the scene and display
//! arguments, the eye arguments (the experiment file's `[eye]` settings), output checks and writers.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use glam::DVec3;

use inimtrace::io::exr::{Attributes, ExrCompression};
use inimtrace::optics::{Aperture, Display, Eye, Retina};
use inimtrace::overrides::Override;
use inimtrace::render::{with_fields, BackendChoice, Fields};
use inimtrace::scene::Scene;
use inimtrace::settings::{load_display_part, load_scene_part, setup_with};

pub(crate) mod assess;
pub(crate) mod bench;
pub(crate) mod compare;
pub(crate) mod info;
pub(crate) mod render;
pub(crate) mod resolution;
pub(crate) mod sweep;
pub(crate) mod values;

/// Refuses an image of `pixels` pixels at `bytes_each` bytes that would not fit in the memory
/// budget ([`inimtrace::budget::memory_budget`]), naming the setting, before anything is allocated.
pub(crate) fn check_memory(what: &str, setting: &str, pixels: usize, bytes_each: u64) -> Result<()> {
    Ok(inimtrace::budget::check_buffer(what, setting, pixels, bytes_each, "command line")?)
}

/// An output image path: it must end in `.exr` (the PNG preview goes beside it), so that the
/// preview can never overwrite the EXR.
pub(crate) fn exr_path(text: &str) -> std::result::Result<PathBuf, String> {
    let path = PathBuf::from(text);
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("exr") => Ok(path),
        _ => Err(format!("`{text}` must name an .exr file (a PNG preview is written beside it)")),
    }
}

/// Scene and display.
#[derive(Args)]
pub(crate) struct Setup {
    /// Scene TOML (default: the paper's scene).
    #[arg(long)]
    pub(crate) scene: Option<PathBuf>,
    /// Display TOML or OpenCV YAML (default: the paper's display).
    #[arg(long)]
    pub(crate) display: Option<PathBuf>,
}

/// The eye.
#[derive(Args)]
pub(crate) struct EyeArgs {
    /// A pinhole eye (everything in focus).
    #[arg(long, conflicts_with_all = ["focus_mm", "focus_diopters"])]
    pub(crate) pinhole: bool,
    /// Focus distance, mm.
    #[arg(long)]
    pub(crate) focus_mm: Option<f64>,
    /// Focus in diopters (0 = infinity).
    #[arg(long, conflicts_with = "focus_mm")]
    pub(crate) focus_diopters: Option<f64>,
    /// Pupil diameter, mm.
    #[arg(long, default_value_t = 5.0)]
    pub(crate) pupil: f64,
    /// n x n pupil grid, kept inside the circle.
    #[arg(long, default_value_t = 8)]
    pub(crate) pupil_grid: usize,
    /// Retina pixels per side.
    #[arg(long, default_value_t = 512)]
    pub(crate) retina: usize,
    /// Retina half field, as a tangent.
    #[arg(long, default_value_t = 0.3)]
    pub(crate) half_tangent: f64,
    /// k x k samples per retina pixel.
    #[arg(long, default_value_t = 1)]
    pub(crate) retina_samples: usize,
    /// Pupil-to-retina distance v0, mm.
    #[arg(long, default_value_t = 17.0)]
    pub(crate) retina_distance: f64,
    /// Pupil centre, mm.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    pub(crate) eye_position: DVec3,
    /// The eye model, as `[eye] model` (thin-lens, navarro, navarro-1999, arizona, le-grand;
    /// docs/EYE.md): a schematic eye focused at --focus-mm / --focus-diopters (--pupil is its
    /// entrance pupil).
    #[arg(long)]
    pub(crate) eye_model: Option<String>,
    /// As `[eye] spectrum`: "primaries" (a schematic eye's default; the display file's
    /// `[primaries]`, or the default LCD's) or "single".
    #[arg(long)]
    pub(crate) spectrum: Option<String>,
    /// As `[eye] stiles_crawford_rho`, 1/mm^2.
    #[arg(long)]
    pub(crate) stiles_crawford_rho: Option<f64>,
}

impl EyeArgs {
    /// The eye and retina; a schematic eye's channels take `display`'s primaries.
    pub(crate) fn eye(&self, display: &inimtrace::optics::Display) -> Result<(Eye, Retina)> {
        let Some(aperture) = Aperture::stated(self.pinhole, self.focus_mm, self.focus_diopters, self.pupil) else {
            bail!("give exactly one of --pinhole, --focus-mm or --focus-diopters")
        };
        let mut eye = Eye {
            retina_distance: self.retina_distance,
            aperture,
            pupil_grid: self.pupil_grid,
            position: self.eye_position,
            optics: None,
            pose: None,
        };
        eye.validate("command line")?;
        // The plausibility warning every command gives a pupil it uses, whatever the eye model.
        if let Aperture::ThinLens { pupil_diameter, .. } = eye.aperture {
            use inimtrace::optics::plausibility::{check, PUPIL_DIAMETER};
            if let Some(w) = check("command line", "--pupil", pupil_diameter, PUPIL_DIAMETER) {
                eprintln!("warning: {w}");
            }
        }
        let model = inimtrace::experiment::EyeModelSettings {
            model: self.eye_model.clone(),
            spectrum: self.spectrum.clone(),
            stiles_crawford_rho: self.stiles_crawford_rho,
            ..Default::default()
        };
        let focus = if self.focus_mm.is_some() { "--focus-mm" } else { "--focus-diopters" };
        let primaries = display.primaries.clone().unwrap_or_default();
        eye.optics = model.optics_for(&eye, self.half_tangent, &primaries, "command line", focus)?;
        let retina =
            Retina { resolution: self.retina, half_tangent: self.half_tangent, samples_per_pixel: self.retina_samples };
        retina.validate("command line")?;
        Ok((eye, retina))
    }
}

/// `X,Y,Z` (mm) on the command line: three finite numbers.
pub(crate) fn parse_vec3(s: &str) -> std::result::Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|_| format!("`{x}` is not a number (expected X,Y,Z in mm)")))
        .collect::<std::result::Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(*x, *y, *z)),
        _ => Err(format!("expected three finite numbers X,Y,Z in mm, got `{s}`")),
    }
}

/// The scene and display of a single-stage command; the display's plausibility warnings go to
/// stderr.
pub(crate) fn load_setup(setup: &Setup, set: &[Override]) -> Result<(Scene, Display)> {
    let (scene, display) = if !set.is_empty() {
        setup_with(setup.scene.as_deref(), setup.display.as_deref(), set)?
    } else {
        (load_scene_part(setup.scene.as_deref(), set)?, load_display_part(setup.display.as_deref(), set)?)
    };
    let source = setup.display.as_ref().map_or_else(|| "builtin:paper".to_string(), |p| p.display().to_string());
    for w in inimtrace::optics::plausibility::display_warnings(&display, &source) {
        eprintln!("warning: {w}");
    }
    Ok((scene, display))
}

/// Runs `f` with the radiance fields of the chosen backend.
pub(crate) fn with_field<T>(
    scene: &Scene,
    backend: BackendChoice,
    f: impl FnOnce(Fields<'_>) -> Result<T>,
) -> Result<T> {
    let mut out = None;
    with_fields(scene, backend, |fields| {
        out = Some(f(fields));
        Ok(())
    })?;
    out.expect("with_fields ran the closure")
}

pub(crate) fn write_image(
    path: &Path,
    img: &inimtrace::raster::RgbImage,
    depth: Option<&[f32]>,
    attrs: &Attributes,
    compression: ExrCompression,
) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    use inimtrace::io::output::write_atomic;
    write_atomic(path, |tmp| inimtrace::io::exr::write_rgb_with(tmp, img, depth, attrs, compression))?;
    write_atomic(&path.with_extension("png"), |tmp| inimtrace::io::png::write_preview(tmp, img))?;
    Ok(())
}

/// The error and its causes on one line, leaving out a cause its message already ends with
/// (an I/O error is both the message's tail and its source).
pub(crate) fn error_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !line.ends_with(&text) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&text);
        }
    }
    line
}

/// Prints what loading the scene noticed (always) and which backend runs (unless quiet).
pub(crate) fn announce(scene: &Scene, backend: BackendChoice, quiet: bool) {
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if !quiet {
        let picked = inimtrace::render::backend::resolve(scene, backend);
        let how = if backend == BackendChoice::Auto { "picked by auto" } else { "as asked" };
        eprintln!(
            "backend: {picked} ({how}; scene `{}`: {}, {} when tessellated)",
            scene.name,
            inimtrace::count::count(scene.objects.len(), "object"),
            inimtrace::count::count(scene.triangle_count(), "triangle")
        );
    }
}

/// The RGB image of an input EXR read through the gate (of part `part`), printing the reader's
/// note on a multipart file.
pub(crate) fn read_exr_input(
    file: &inimtrace::io::exr::ExrFile,
    part: Option<&str>,
) -> Result<inimtrace::raster::RgbImage> {
    let input = file.input(part)?;
    if let Some(note) = input.note {
        eprintln!("{note}");
    }
    Ok(input.image)
}
