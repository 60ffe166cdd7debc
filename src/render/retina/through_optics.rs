//! The grid estimator's retinal images through an eye beyond the thin lens's fast paths (a
//! schematic eye, the display primaries' wavelengths, Stiles-Crawford; `optics::eye::rays`): for
//! every retina sub-pixel sample, pupil-grid point and wavelength quantile of each primary, the
//! sample's rays ([`EyeOptics::rays`]) into the scene (the ground truth) or on through the
//! lenslets to the LCD (the perceived images, eq. (1) from the lenslet plane on, or the exact
//! trace through real lenslets, channel by channel at each channel's wavelength). The pixel is
//! the plain mean over those samples, as on the thin lens's grid; a ray blocked inside the eye
//! carries black.

use glam::DVec3;
use rayon::prelude::*;

use crate::optics::eye::rays::SampleRays;
use crate::optics::eye::EyeOptics;
use crate::optics::{Eye, PlaneRay, Retina};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::ray::Ray;
use crate::render::RadianceField;

/// Every sample of pixel (row, col): its spectral coordinate and rays.
pub(crate) fn pixel_samples<'a>(
    optics: &'a EyeOptics,
    eye: &'a Eye,
    retina: &'a Retina,
    row: usize,
    col: usize,
) -> impl Iterator<Item = (f64, SampleRays)> + 'a {
    let pupil = eye.pupil_samples();
    let spectral = optics.grid_spectral();
    retina.subpixel_offsets().into_iter().flat_map(move |frac| {
        let t = retina.tangent(row, col, frac);
        let spectral = spectral.clone();
        pupil
            .clone()
            .into_iter()
            .flat_map(move |s| spectral.clone().into_iter().map(move |u| (u, optics.rays(t, s, u))))
    })
}

/// The number of samples per pixel.
pub(crate) fn per_pixel(optics: &EyeOptics, eye: &Eye, retina: &Retina) -> f64 {
    (retina.subpixel_offsets().len() * eye.pupil_samples().len() * optics.grid_spectral().len()) as f64
}

/// `ray` (eye coordinates, at the eye's plane) in world coordinates.
pub(crate) fn world(eye: &Eye, r: PlaneRay) -> PlaneRay {
    PlaneRay { position: r.position + eye.position.truncate(), slope: r.slope }
}

/// Calls `f(channels, ray)` for each ray of a sample: all three channels for one ray, else each
/// channel with its own.
pub(crate) fn each_ray(sr: &SampleRays, mut f: impl FnMut(std::ops::Range<usize>, PlaneRay)) {
    if sr.single {
        if let Some(r) = sr.rays[0] {
            f(0..3, r);
        }
    } else {
        for c in 0..3 {
            if let Some(r) = sr.rays[c] {
                f(c..c + 1, r);
            }
        }
    }
}

/// The ground-truth retinal image (grid estimator).
pub(super) fn ground_truth<R: RadianceField + ?Sized>(
    eye: &Eye,
    optics: &EyeOptics,
    retina: &Retina,
    field: &R,
    progress: &Progress,
) -> RgbImage {
    let n = retina.resolution;
    let inv = 1.0 / per_pixel(optics, eye, retina);
    let z = eye.position.z;
    let mut image = RgbImage::new(n, n);
    image.pixels.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
        for (col, px) in out.iter_mut().enumerate() {
            if progress.cancelled() {
                break;
            }
            let mut sum = DVec3::ZERO;
            for (_, sr) in pixel_samples(optics, eye, retina, row, col) {
                each_ray(&sr, |channels, r| {
                    let w = world(eye, r);
                    let l = field.radiance(&Ray { origin: w.position.extend(z), dir: w.slope.extend(1.0) });
                    for c in channels {
                        sum[c] += l[c] * sr.weight;
                    }
                });
            }
            let v = sum * inv;
            *px = [v.x as f32, v.y as f32, v.z as f32];
        }
        progress.inc(1);
    });
    image
}
