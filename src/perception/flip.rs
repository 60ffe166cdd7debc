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
    let map = result.error_map.into_pixels();
    Ok(FlipMap { mean: f64::from(mean_f32(&map)), map })
}

/// The mean of a FLIP map as `flip-rs`'s `ErrorMap::statistics` (and NVIDIA's tool) gives it: an
/// `f32` sum in pixel order over the count, bit for bit; without the sorted copy `statistics`
/// makes for its percentiles, which no score uses (a tenth of an evaluation's instructions).
fn mean_f32(map: &[f32]) -> f32 {
    map.iter().fold(0.0f32, |sum, v| sum + v) / map.len() as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_is_the_crates_mean_bit_for_bit() {
        // Maps of uneven values whose f32 sum rounds at many steps, and a real map.
        let mut state = 12345u64;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        for (w, h) in [(1, 1), (7, 3), (64, 64), (301, 211)] {
            let values: Vec<f32> = (0..w * h).map(|_| uniform().powi(3)).collect();
            let crate_mean = flip_rs::ErrorMap::new(w, h, values.clone()).unwrap().statistics().mean;
            assert_eq!(mean_f32(&values).to_bits(), crate_mean.to_bits(), "{w}x{h}");
        }
        let viewing = Viewing::of_retina(
            &crate::optics::Retina { resolution: 32, half_tangent: 0.05, ..Default::default() },
            Default::default(),
        );
        let (mut reference, mut test) = (RgbImage::new(32, 32), RgbImage::new(32, 32));
        for (i, (r, t)) in reference.pixels.iter_mut().zip(&mut test.pixels).enumerate() {
            let (x, y) = ((i % 32) as f32, (i / 32) as f32);
            *r = [0.2 + 0.02 * x, 0.5, 0.1 + 0.02 * y];
            *t = [0.2 + 0.021 * x, 0.45, 0.1 + 0.04 * (y / 2.0).floor()];
        }
        let ours = flip(&test, &reference, &viewing).unwrap();
        let crate_mean = flip_rs::ErrorMap::new(32, 32, ours.map.clone()).unwrap().statistics().mean;
        assert!(ours.mean > 0.0);
        assert_eq!(ours.mean.to_bits(), f64::from(crate_mean).to_bits());
    }
}
