//! The single-stage commands: `render-display` (one display image), `simulate` (the retinal
//! image of a display image) and `ground-truth` (the eye's view of the scene itself).

use std::path::PathBuf;

use anyhow::{Context, Result};
use glam::DVec3;

use inimtrace::experiment::metadata;
use inimtrace::optimize::Optimization;
use inimtrace::progress::Progress;
use inimtrace::render::retina::simulate;
use inimtrace::render::{ground_truth, DisplayRenderSettings, Method};

use super::{announce, check_memory, load_setup, read_exr_input, with_field, write_image, EyeArgs, Setup};
use crate::{BackendArg, Globals};
use inimtrace::io::exr::ExrFile;

/// `inimtrace render-display`; returns whether it printed its own total time.
#[allow(clippy::too_many_arguments)] // the command's flags, as clap parsed them
pub(crate) fn render_display(
    g: &Globals,
    method: Method,
    setup: Setup,
    samples_per_pixel: usize,
    reference_plane: f64,
    eye_position: DVec3,
    out: PathBuf,
    backend: BackendArg,
) -> Result<bool> {
    let (set, quiet) = (&g.set[..], g.quiet);
    let backend = backend.choice()?;
    let (scene, display) = load_setup(&setup, set)?;
    announce(&scene, backend, quiet);
    inimtrace::optics::limits::REFERENCE_PLANE_Z.check("command line", "--reference-plane", reference_plane)?;
    check_memory(
        "the display image, its depth plane and its preview",
        &format!("lcd.resolution = {:?} of the display", display.lcd.resolution),
        display.lcd.pixel_count(),
        32,
    )?;
    inimtrace::optics::transfer::check_eye_in_front(&display, eye_position.z, "command line", "--eye-position")?;
    let settings = DisplayRenderSettings { samples_per_pixel, reference_plane_z: reference_plane, eye_position };
    let per_pixel = match method {
        Method::LensletAverage { grid } => grid as u64 * grid as u64,
        _ => 1,
    };
    inimtrace::long_run::announce(
        (display.lcd.pixel_count() as u64)
            .saturating_mul((samples_per_pixel as u64).saturating_pow(2))
            .saturating_mul(per_pixel),
    );
    // Without an experiment, OPT trains on the paper's eye states around the eye position.
    let training = (method == Method::Optimized).then(|| Optimization::paper_default(eye_position));
    let (img, depth, name) = with_field(&scene, backend, |fields| {
        let p = inimtrace::methods::progress(&display, method, training.as_ref(), quiet);
        let (img, depth, _) =
            inimtrace::methods::render(&display, method, &settings, training.as_ref(), fields.with_depth, &p)?;
        p.finish();
        Ok((img, depth, fields.name))
    })?;
    let mut attrs = metadata::common("display image", None);
    attrs.extend(metadata::display_image(method, &display, &settings, name, depth.is_some()));
    write_image(&out, &img, depth.as_deref(), &attrs, g.exr_compression)?;
    Ok(false)
}

/// `inimtrace simulate`; returns whether it printed its own total time.
pub(crate) fn simulate_command(
    g: &Globals,
    display_image: PathBuf,
    part: Option<&str>,
    setup: Setup,
    eye: EyeArgs,
    out: PathBuf,
) -> Result<bool> {
    let (set, quiet) = (&g.set[..], g.quiet);
    // Every input (the display image too) is read once through the input gate and recorded:
    // the output's header lists them with their SHA-256.
    let (loaded, files) = inimtrace::provenance::recording(|| -> Result<_> {
        let (scene, display) = load_setup(&setup, set)?;
        Ok((scene, display, ExrFile::open(&display_image)?))
    });
    let (scene, display, file) = loaded?;
    let (eye, retina) = eye.eye(&display)?;
    inimtrace::optics::transfer::check_eye_in_front(&display, eye.position.z, "command line", "--eye-position")?;
    check_memory("the retinal image", "--retina", retina.resolution * retina.resolution, 24)?;
    let img = read_exr_input(&file, part)?;
    let pupil = eye.pupil_samples().len();
    inimtrace::long_run::announce(inimtrace::long_run::retina_rays(
        retina.resolution,
        retina.samples_per_pixel,
        pupil,
        1,
    ));
    // The method, when the display image says which.
    let method = file
        .attributes()?
        .into_iter()
        .find(|(k, _)| k == "inimtrace:method")
        .and_then(|(_, v)| v.parse::<Method>().ok());
    let p = Progress::new(retina.resolution as u64, "simulate", quiet);
    let sim = simulate(&display, &eye, &retina, &[&img], &p)
        .with_context(|| format!("simulating {}", display_image.display()))?;
    p.finish();
    let source = display_image.display().to_string();
    let mut attrs = metadata::perceived(None, method, None, &eye, &retina, &display, Some(&source));
    let provenance = inimtrace::provenance::Provenance {
        scene_name: scene.name.clone(),
        scene_path: setup.scene.as_ref().map_or_else(|| "builtin:paper".into(), |p| p.display().to_string()),
        display_path: setup.display.as_ref().map_or_else(|| "builtin:paper".into(), |p| p.display().to_string()),
        files,
        set: set.iter().map(inimtrace::overrides::Override::to_arg).collect(),
        working_directory: std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default(),
        ..Default::default()
    };
    attrs.extend(metadata::provenance(&provenance));
    write_image(&out, &sim[0], None, &attrs, g.exr_compression)?;
    Ok(false)
}

/// `inimtrace ground-truth`; returns whether it printed its own total time.
pub(crate) fn ground_truth_command(
    g: &Globals,
    setup: Setup,
    eye: EyeArgs,
    out: PathBuf,
    backend: BackendArg,
) -> Result<bool> {
    let (set, quiet) = (&g.set[..], g.quiet);
    let backend = backend.choice()?;
    let (scene, display) = load_setup(&setup, set)?;
    let (eye, retina) = eye.eye(&display)?;
    check_memory("the retinal image", "--retina", retina.resolution * retina.resolution, 24)?;
    let pupil = eye.pupil_samples().len();
    inimtrace::long_run::announce(inimtrace::long_run::retina_rays(
        retina.resolution,
        retina.samples_per_pixel,
        pupil,
        1,
    ));
    announce(&scene, backend, quiet);
    let (img, name) = with_field(&scene, backend, |fields| {
        let p = Progress::new(retina.resolution as u64, "ground truth", quiet);
        let img = ground_truth(&eye, &retina, fields.shade, &p);
        p.finish();
        Ok((img, fields.name))
    })?;
    let attrs = metadata::ground_truth(None, None, &eye, &retina, name);
    write_image(&out, &img, None, &attrs, g.exr_compression)?;
    Ok(false)
}
