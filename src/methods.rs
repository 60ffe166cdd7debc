//! A method's display image, routed once (paper Sec. 3 for LC, PC and LA; docs/OPTIMAL.md for
//! OPT): LensletCenter, PupilCenter and LensletAverage trace camera rays into the scene
//! ([`crate::render::display_image`], through real lenslets [`crate::render::display_thick`]);
//! Optimized solves for the image from the perceived-image simulation itself
//! ([`crate::optimize`]), on every display (paraxial or real lenslets) and every eye its training
//! states name (thin lens, schematic eyes, diffraction). Every command, the experiment's stages,
//! sweeps, the resolution study and Python ask here, so no method is ever silently replaced by
//! another: the render layer refuses OPT rather than guess its training states.

use crate::error::{Error, Result};
use crate::optics::Display;
use crate::optimize::{Optimization, OptimizationReport};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::{render_display_image_into, DisplayRenderSettings, Method, RadianceField};

/// What one method's display image came with.
#[derive(Debug, Default)]
pub struct Rendered {
    /// Whether the depth plane holds the field's depths (camera-ray methods on a field that
    /// knows them); OPT's image has none.
    pub depth_known: bool,
    /// OPT's convergence record.
    pub optimization: Option<OptimizationReport>,
}

/// The progress bar of `method`'s display image: its LCD rows for the camera-ray methods, the
/// solver's iterations for OPT (`training`'s budget).
pub fn progress(display: &Display, method: Method, training: Option<&Optimization>, quiet: bool) -> Progress {
    match (method, training) {
        (Method::Optimized, Some(opt)) => {
            Progress::new(opt.solver.max_iterations as u64, "display image OPT (iterations)", quiet)
        }
        _ => Progress::new(display.lcd.rows() as u64, &format!("display image {}", method.name()), quiet),
    }
}

/// `method`'s display image of `field` on `display` into `image` (the LCD's size) and its depth
/// plane into `depth`. OPT trains on `training` (an experiment's `[optimize]`, or
/// [`Optimization::paper_default`] where none is stated) and errors without it; the other methods
/// ignore it. `progress` counts what [`progress`] says.
#[allow(clippy::too_many_arguments)]
pub fn render_into<R: RadianceField + ?Sized>(
    display: &Display,
    method: Method,
    settings: &DisplayRenderSettings,
    training: Option<&Optimization>,
    field: &R,
    progress: &Progress,
    image: &mut RgbImage,
    depth: &mut Vec<f32>,
) -> Result<Rendered> {
    if method != Method::Optimized {
        let depth_known = render_display_image_into(display, method, settings, field, progress, image, depth)?;
        return Ok(Rendered { depth_known, optimization: None });
    }
    let Some(opt) = training else {
        return Err(Error::Mismatch(
            "OPT's display image needs its training states (an experiment's [optimize] table)".into(),
        ));
    };
    let report = crate::optimize::render_optimal_into(display, settings, opt, field, progress, image)?;
    depth.clear();
    depth.resize(display.lcd.pixel_count(), f32::INFINITY);
    Ok(Rendered { depth_known: false, optimization: Some(report) })
}

/// [`render_into`] into a new image: the image, its depth plane when known, and OPT's record.
pub fn render<R: RadianceField + ?Sized>(
    display: &Display,
    method: Method,
    settings: &DisplayRenderSettings,
    training: Option<&Optimization>,
    field: &R,
    progress: &Progress,
) -> Result<(RgbImage, Option<Vec<f32>>, Option<OptimizationReport>)> {
    let mut image = RgbImage::try_new(display.lcd.columns(), display.lcd.rows(), "the display image")?;
    let mut depth = Vec::new();
    let r = render_into(display, method, settings, training, field, progress, &mut image, &mut depth)?;
    Ok((image, r.depth_known.then_some(depth), r.optimization))
}
