//! ColorVideoVDP (Mantiuk, Hanji, Ashraf, Asano and Chapiro, *ColorVideoVDP: a visual difference
//! predictor for image, video and display distortions*, ACM TOG 43(4):129, SIGGRAPH 2024) of a
//! perceived retinal image against its ground truth, in just-objectionable differences (JOD:
//! 10 is no visible difference, one JOD less is chosen as worse by 75% of observers).
//!
//! The metric is the `colorvideovdp` crate (a port of the authors' PyTorch code, base model
//! 0.5.7), checked against the authors' `cvvdp` on this tool's own images by
//! `tests/perception_reference.rs` and `scripts/perception-reference.py`. Its display model is
//! built from [`Viewing`]: the retina image's pixels per degree and the display's absolute
//! luminance (the images enter as BT.709 linear RGB in cd/m^2, the panel's black added; the
//! reflected ambient light is the model's own `E_amb k / pi`).

use colorvideovdp::{Color, DisplayModel, Geometry, Image, Options, Photometry};

use super::viewing::Viewing;
use crate::error::{Error, Result};
use crate::raster::RgbImage;

/// The lowest luminance ColorVideoVDP's display model takes (its linear input's floor), cd/m^2.
pub const MIN_LUMINANCE: f64 = 0.005;

/// A ColorVideoVDP evaluator for one viewing (build once, score many image pairs).
pub struct Cvvdp {
    metric: colorvideovdp::Cvvdp,
    viewing: Viewing,
    size: (usize, usize),
}

/// A JOD and, when asked for, the per-pixel distortion map (`1 - JOD_pixel / 10`, row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct JodMap {
    /// The image's JOD.
    pub jod: f64,
    /// The distortion map, when asked for.
    pub map: Option<Vec<f32>>,
}

fn metric_error(what: &str, e: impl std::fmt::Display) -> Error {
    Error::invalid("ColorVideoVDP", what, e.to_string())
}

impl Cvvdp {
    /// An evaluator of `width x height` images seen as `viewing` says; `with_map` also returns
    /// the distortion map. Errors name the bad field (a luminance below the model's floor, pixels
    /// per degree, an image under 4 x 4 pixels).
    pub fn new(viewing: &Viewing, width: usize, height: usize, with_map: bool) -> Result<Self> {
        viewing.validate("ColorVideoVDP", "luminance")?;
        let l = &viewing.luminance;
        if l.peak_white < MIN_LUMINANCE {
            return Err(Error::invalid(
                "ColorVideoVDP",
                "luminance.peak_white",
                format!("must be at least {MIN_LUMINANCE} cd/m^2 (the metric's floor), got {}", l.peak_white),
            ));
        }
        if width < 4 || height < 4 {
            return Err(Error::invalid(
                "ColorVideoVDP",
                "image size",
                format!("{width}x{height} image is smaller than the metric's 4x4 minimum"),
            ));
        }
        let photometry = Photometry::new(l.peak_white, contrast(viewing), l.ambient_lux, l.reflectance, 1.0)
            .map_err(|e| metric_error("luminance", e))?;
        let geometry =
            Geometry::from_ppd([width, height], viewing.pixels_per_degree).map_err(|e| metric_error("geometry", e))?;
        let display = DisplayModel::new("inimtrace retina", photometry, geometry, "BT.709-linear")
            .map_err(|e| metric_error("display", e))?;
        let options = Options::default().with_distortion_map(with_map);
        let metric = colorvideovdp::Cvvdp::new(display, options).map_err(|e| metric_error("display", e))?;
        Ok(Self { metric, viewing: *viewing, size: (width, height) })
    }

    /// The images as the model's input: absolute BT.709 linear RGB of the panel, cd/m^2.
    fn input(&self, img: &RgbImage, which: &str) -> Result<Image> {
        check_image(img, self.size, which, "ColorVideoVDP")?;
        Image::new(img.width, img.height, 3, panel_rgb(&self.viewing, img)).map_err(|e| metric_error(which, e))
    }

    /// The JOD of `test` against `reference` (and the map when the evaluator was built for it).
    pub fn score(&self, test: &RgbImage, reference: &RgbImage) -> Result<JodMap> {
        let (t, r) = (self.input(test, "test image")?, self.input(reference, "reference image")?);
        let p = self.metric.predict_image(&t, &r, Color::Linear).map_err(|e| metric_error("prediction", e))?;
        Ok(JodMap { jod: f64::from(p.jod), map: p.distortion_map.map(|m| m.data) })
    }
}

/// The display model's contrast, peak white over black (its black at least the model's floor).
pub fn contrast(viewing: &Viewing) -> f64 {
    let l = &viewing.luminance;
    (l.peak_white / l.black.max(MIN_LUMINANCE.min(l.peak_white))).max(1.0)
}

/// What ColorVideoVDP is handed of `img`: the panel's absolute BT.709 linear RGB, cd/m^2
/// (`black + (peak - black) v`, interleaved, row 0 first); the model adds the reflection.
pub fn panel_rgb(viewing: &Viewing, img: &RgbImage) -> Vec<f32> {
    let l = &viewing.luminance;
    let (black, span) = (l.black, l.peak_white - l.black);
    img.pixels.iter().flat_map(|p| p.map(|v| (black + span * f64::from(v)) as f32)).collect()
}

/// Both images `size` (width, height) and every sample finite and not negative.
pub(crate) fn check_image(img: &RgbImage, size: (usize, usize), which: &str, metric: &str) -> Result<()> {
    if (img.width, img.height) != size || img.pixels.len() != img.width * img.height {
        return Err(Error::invalid(
            metric,
            "image size",
            format!("cannot compare a {}x{} {which} with a {}x{} image", img.width, img.height, size.0, size.1),
        ));
    }
    if let Some(i) = img.pixels.iter().position(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0)) {
        return Err(Error::invalid(
            metric,
            "pixels",
            format!(
                "{which} has a negative or non-finite sample at (row {}, col {}): linear light cannot be",
                i / img.width,
                i % img.width
            ),
        ));
    }
    Ok(())
}
