//! Display images for real (thick) lenslets (paper Sec. 3 with the display's own optics): each
//! method's camera rays go through the same real lenslet the eye looks through
//! ([`ThickLenslet::camera_ray`]), each colour channel at its primary's median wavelength, so
//! each method renders for the optics the display has.
//!
//! - LC: the ray from the LCD point through the lenslet's centre on its back vertex plane;
//! - PC: the point of the back vertex plane whose ray reaches the pupil centre, by Newton's
//!   method ([`ThickLenslet::pupil_center_point`]) from the thin lens's closed form; where the
//!   real lenslet sends no light from the pixel to the pupil centre (the point would lie where
//!   the rays are totally reflected or miss the lens), LC's ray;
//! - LA: the k x k cell-centre points of the lenslet's pitch cell on the back vertex plane.
//!
//! The pixel's lenslet is its elemental image's, treated as extended (as eq. (1b) does). A ray
//! the lenslet blocks (total internal reflection, a missed surface) brings black and no depth. Every ray is traced on its own (no ray families: the real lens is
//! not affine in the lenslet point).

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::display_image::{DisplayRenderSettings, Method};
use super::field::{BundleSum, RadianceField, Sample};
use crate::error::Result;
use crate::optics::eye::stratified;
use crate::optics::lenslet::ThickLenslet;
use crate::optics::transfer::pupil_center_point;
use crate::optics::Display;
use crate::progress::Progress;
use crate::raster::RgbImage;

/// Renders `method`'s display image through `lens` into `dst` (row-major), its depths into
/// `depth`; returns `depth` and whether the depths are known.
#[allow(clippy::too_many_arguments)]
pub(super) fn render_into<R: RadianceField + ?Sized>(
    display: &Display,
    lens: &ThickLenslet,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
    progress: &Progress,
    dst: &mut [[f32; 3]],
    mut depth: Vec<f32>,
) -> Result<(Vec<f32>, bool)> {
    let lcd = display.lcd;
    let (nx, ny) = (lcd.columns(), lcd.rows());
    let pixel_samples = stratified(settings.samples_per_pixel);
    let offsets: Vec<DVec2> = match method {
        Method::LensletAverage { grid } => {
            stratified(grid).into_iter().map(|f| display.lenslets.reduced_matrix() * (f - DVec2::splat(0.5))).collect()
        }
        _ => vec![DVec2::ZERO],
    };
    let nm = display.channel_wavelengths();
    let (front_z, lcd_z, z_ref, eye) =
        (display.lenslet_z(), display.lcd_z(), settings.reference_plane_z, settings.eye_position);
    let inv_count = 1.0 / (pixel_samples.len() * offsets.len()) as f64;
    depth.resize(nx * ny, 0.0);
    let depth_known = std::sync::atomic::AtomicBool::new(true);
    dst.par_chunks_mut(nx).zip(depth.par_chunks_mut(nx)).enumerate().for_each(|(row, (out, zout))| {
        if progress.cancelled() {
            return;
        }
        for (col, (px, z)) in out.iter_mut().zip(zout.iter_mut()).enumerate() {
            let center = display.lenslets.center(display.elemental_image_of(lcd.pixel_center(row, col)));
            let mut acc = BundleSum::default();
            for frac in &pixel_samples {
                let x3 = lcd.pixel_point(row, col, *frac);
                for (c, &nm) in nm.iter().enumerate() {
                    let mut trace = |p: Option<DVec2>| {
                        let ray = p.and_then(|p| lens.camera_ray(center, front_z, lcd_z, x3, p, z_ref, nm));
                        let s = match ray {
                            Some(r) => tracer.sample(&r),
                            None => Sample { radiance: DVec3::ZERO, depth: f64::INFINITY },
                        };
                        let mut one = DVec3::ZERO;
                        one[c] = s.radiance[c];
                        acc.add(Sample { radiance: one, depth: s.depth });
                    };
                    match method {
                        Method::PupilCenter => {
                            let guess = pupil_center_point(display, x3, center, eye);
                            let p = lens.pupil_center_point(center, front_z, lcd_z, x3, eye, guess, nm);
                            trace(p.or(Some(center)));
                        }
                        _ => offsets.iter().for_each(|o| trace(Some(center + *o))),
                    }
                }
            }
            if !acc.depth_known {
                depth_known.store(false, std::sync::atomic::Ordering::Relaxed);
            }
            let v = acc.radiance * inv_count;
            *px = [v.x as f32, v.y as f32, v.z as f32];
            *z = if acc.hits > 0 { (acc.depth / acc.hits as f64) as f32 } else { f32::INFINITY };
        }
        progress.inc(1);
    });
    progress.check()?;
    Ok((depth, depth_known.into_inner()))
}

/// A display image of `method` through `lens` (the one-image twin of the renderer's buffer form).
pub fn render<R: RadianceField + ?Sized>(
    display: &Display,
    lens: &ThickLenslet,
    method: Method,
    settings: &DisplayRenderSettings,
    tracer: &R,
) -> Result<RgbImage> {
    let mut image = RgbImage::new(display.lcd.columns(), display.lcd.rows());
    render_into(display, lens, method, settings, tracer, &Progress::hidden(), &mut image.pixels, Vec::new())?;
    Ok(image)
}
