//! The fixed grid of samples of the grid estimator (paper Sec. 4.1: every retina pixel's
//! sub-pixel points x the eye's pupil grid x, for an eye that separates the channels'
//! wavelengths, their spectral quantiles) and of the OPT operator (the same grid, with a fixed
//! draw of the diffraction numbers), traced by the system's kernel in the order that kernel
//! traces them best: the paper's thin lens through paraxial lenslets a block of a row's columns
//! at a time, pupil point by pupil point (eq. (1)'s constants per pupil point, the LCD patch of
//! one pupil point in cache); every other kernel pixel by pixel. Each retina pixel's samples come
//! in one order either way (sub-pixel point, pupil point, spectral number), so sums over a pixel
//! do not depend on it.

use std::ops::Range;

use glam::DVec2;

use super::trace::{index_u32, Traced, Traces, MISS};
use super::{EyeSample, Kernel, OpticalSystem};
use crate::optics::transfer::eye_scene_ray;
use crate::optics::Retina;

/// A worker's buffers for [`OpticalSystem::trace_grid`], kept between calls.
#[derive(Default)]
pub struct GridBuffers {
    samples: Vec<EyeSample>,
    pixels: Vec<u32>,
    tangents: Vec<DVec2>,
    lcd: Vec<u32>,
    scratch: Vec<DVec2>,
    traces: Traces,
}

impl OpticalSystem<'_> {
    /// The grid samples of retina pixel (`row`, `col`) into `out` (cleared first), in order:
    /// sub-pixel point, pupil point, spectral number; sample `k`'s diffraction numbers
    /// `draws(pixel, k)` when the system models diffraction (`pixel`: `row * n + col`), else 0.
    pub fn grid_samples(
        &self,
        retina: &Retina,
        (row, col): (usize, usize),
        draws: &dyn Fn(u64, u64) -> [f64; 4],
        out: &mut Vec<EyeSample>,
    ) {
        out.clear();
        let spectral = self.grid_spectral();
        let pixel = (row * retina.resolution + col) as u64;
        for frac in retina.subpixel_offsets() {
            let tangent = retina.tangent(row, col, frac);
            for &pupil in &self.pupil {
                for &u in &spectral {
                    let k = out.len() as u64;
                    let diffraction = if self.diffraction { draws(pixel, k) } else { [0.0; 4] };
                    out.push(EyeSample { tangent, pupil, spectral: u, diffraction });
                }
            }
        }
    }

    /// Traces the grid samples of the retina rows `rows`, calling `each(pixels, traces)` for
    /// each batch (`pixels[i]`: the retina pixel, `row * n + col`, of `traces.samples[i]`), in
    /// the kernel's order (see the module comment; blocks of `block` columns for the thin lens's
    /// closed form). The scene rays are traced only when `scene` is true; diffraction numbers
    /// as [`OpticalSystem::grid_samples`].
    #[allow(clippy::too_many_arguments)]
    pub fn trace_grid(
        &self,
        retina: &Retina,
        rows: Range<usize>,
        block: usize,
        scene: bool,
        draws: &dyn Fn(u64, u64) -> [f64; 4],
        buf: &mut GridBuffers,
        mut each: impl FnMut(&[u32], &Traces),
    ) {
        let n = retina.resolution;
        if self.kernel != Kernel::Paraxial {
            for row in rows {
                for col in 0..n {
                    self.grid_samples(retina, (row, col), draws, &mut buf.samples);
                    self.trace(&buf.samples, &[], &mut buf.traces);
                    buf.pixels.clear();
                    buf.pixels.resize(buf.samples.len(), (row * n + col) as u32);
                    each(&buf.pixels, &buf.traces);
                }
            }
            return;
        }
        let subpixels = retina.subpixel_offsets();
        let block = block.max(1);
        for row in rows {
            for col0 in (0..n).step_by(block) {
                let cols = col0..(col0 + block).min(n);
                let (t, pixels) = (&mut buf.traces, &mut buf.pixels);
                t.samples.clear();
                t.scene.clear();
                pixels.clear();
                for frac in &subpixels {
                    buf.tangents.clear();
                    buf.tangents.extend(cols.clone().map(|col| retina.tangent(row, col, *frac)));
                    buf.lcd.resize(buf.tangents.len(), MISS);
                    for (k, &pupil) in self.pupil.iter().enumerate() {
                        match &self.transfer {
                            Some(t) => t.pixel_indices(&buf.tangents, k, &mut buf.scratch, &mut buf.lcd),
                            None => buf.lcd.fill(MISS),
                        }
                        for ((col, &tangent), &lcd) in cols.clone().zip(&buf.tangents).zip(&buf.lcd) {
                            let first = t.scene.len() as u32;
                            if scene {
                                t.scene.push(eye_scene_ray(&self.eye, tangent, pupil));
                            }
                            let lcd = index_u32((lcd != MISS).then_some(lcd as usize));
                            t.samples.push(Traced {
                                weight: 1.0,
                                first,
                                rays: 0b111,
                                single: true,
                                lcd: [lcd; 3],
                                shared: true,
                            });
                            pixels.push((row * n + col) as u32);
                        }
                    }
                }
                each(pixels, t);
            }
        }
    }
}
