//! FLIP (Andersson, Nilsson, Akenine-Moller, Oskarsson, Astrom and Fairchild, *FLIP: a
//! difference evaluator for alternating images*, Proc. ACM Comput. Graph. Interact. Tech. 3(2),
//! HPG 2020) in its HDR variant for linear light (Andersson, Nilsson, Shirley and
//! Akenine-Moller, *Visualizing errors in rendered high dynamic range images*, Eurographics 2021
//! short papers): the per-pixel difference a viewer sees when flipping between the perceived
//! retinal image and its ground truth, 0 (none) to 1, and its mean.
//!
//! The metric is the `flip-rs` crate (a port of NVIDIA's FLIP 1.7), checked against NVIDIA's
//! `flip-evaluator` on this tool's own images by `tests/perception_reference.rs`. The images
//! enter as absolute linear RGB in cd/m^2 (panel and reflected ambient light, [`Viewing`]);
//! HDR-FLIP chooses its exposures from the reference's luminance (its start from the maximum,
//! its stop from the median), so a common scale of both images changes nothing but rounding.
//! Pixels per degree: the retina image's.

use flip_rs::{HdrOptions, RgbImage as FlipImage};

use super::cvvdp::check_image;
use super::viewing::Viewing;
use crate::error::{Error, Result};
use crate::raster::RgbImage;

/// A mean FLIP and its per-pixel map (row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    /// The mean of the map (accumulated as the reference tool does, in `f32`).
    pub mean: f64,
    /// The per-pixel map.
    pub map: Vec<f32>,
}

fn flip_error(what: &str, e: impl std::fmt::Display) -> Error {
    Error::invalid("FLIP", what, e.to_string())
}

/// What HDR-FLIP is handed of `img`: absolute linear RGB, cd/m^2, panel and reflection
/// (interleaved, row 0 first).
pub fn absolute_rgb(viewing: &Viewing, img: &RgbImage) -> Vec<f32> {
    let l = &viewing.luminance;
    img.pixels.iter().flat_map(|p| p.map(|v| l.absolute(f64::from(v)) as f32)).collect()
}

fn input(img: &RgbImage, viewing: &Viewing, which: &str) -> Result<FlipImage<f32>> {
    FlipImage::new(img.width, img.height, absolute_rgb(viewing, img)).map_err(|e| flip_error(which, e))
}

/// HDR-FLIP of `test` against `reference` seen as `viewing` says.
pub fn flip(test: &RgbImage, reference: &RgbImage, viewing: &Viewing) -> Result<FlipMap> {
    viewing.validate("FLIP", "luminance")?;
    let size = (reference.width, reference.height);
    if size.0 == 0 || size.1 == 0 {
        return Err(Error::invalid("FLIP", "image size", "images are empty"));
    }
    check_image(reference, size, "reference image", "FLIP")?;
    check_image(test, size, "test image", "FLIP")?;
    let (r, t) = (input(reference, viewing, "reference image")?, input(test, viewing, "test image")?);
    let mut options = HdrOptions::default();
    options.ppd = viewing.pixels_per_degree as f32;
    options.return_exposure_map = false;
    let result = flip_rs::hdr_flip(&r, &t, options).map_err(|e| flip_error("evaluation", e))?;
    let stats = result.error_map.statistics();
    Ok(FlipMap { mean: f64::from(stats.mean), map: result.error_map.into_pixels() })
}
