//! The perceived-image simulation as a linear operator on the display image, and its exact
//! adjoint (paper Sec. 2.3, eq. (1)): for one eye state, retina pixel `p` of the perceived image
//! is the weighted mean of the LCD pixels its eye rays reach, `(A x)_p = sum_e w_e x_{l_e}` over
//! the pixel's samples `e` (retina sub-pixel point x pupil point, and for an eye beyond the thin
//! lens its wavelengths and Stiles-Crawford weight). `A^T r` splats each residual back along the
//! same rays: `(A^T r)_l = sum_{e : l_e = l} w_e r_{p_e}`.
//!
//! Matrix-free: the samples of a band of retina rows are traced afresh on every application
//! through the eye state's [`crate::optics::system::OpticalSystem`] (its grid, the same trace as
//! `crate::render::simulate_stack`) and dropped; only a bounded wave of bands is held at once. With diffraction (which only the converged estimator models) each sample carries a fixed
//! pseudo-random draw of the pupil's and the lenslet aperture's deviations
//! ([`diffraction_numbers`]), and its LCD pixels are those the estimator finds for that sample. The sample pattern is fixed, so the forward operator
//! and the adjoint are the same matrix, transposed. Both are deterministic bit for bit at any
//! thread count: the forward sums each retina pixel's samples in trace order, and the adjoint adds
//! into each LCD pixel in the global order of the samples (bands in order, samples in trace order),
//! whichever thread owns that pixel.

use rayon::prelude::*;

use crate::optics::system::{GridBuffers, OpticalSystem, MISS};
use crate::optics::{Display, Eye, Retina};
use crate::render::RadianceField;

/// One value per pixel and channel (R, G, B), in `f64`.
pub type Rgb = [f64; 3];

/// Retina rows traced together: one unit of parallel work.
const BAND: usize = 8;

/// The samples of a band: sample `i` adds `weight` times LCD pixel `lcd[i]` to retina pixel
/// `pixel[i]` in channel `channel` (3: all). For the thin lens every sample has the same weight
/// and all channels, and `each` is empty (8 bytes a sample); otherwise `each[i]` holds them.
#[derive(Default)]
struct Entries {
    pairs: Vec<(u32, u32)>,
    each: Vec<(u8, f64)>,
}

impl Entries {
    fn clear(&mut self) {
        self.pairs.clear();
        self.each.clear();
    }

    /// Calls `f(lcd, pixel, channel, weight)` for every sample in order.
    #[inline(always)]
    fn for_each(&self, common: f64, mut f: impl FnMut(u32, u32, u8, f64)) {
        if self.each.is_empty() {
            for &(l, p) in &self.pairs {
                f(l, p, 3, common);
            }
        } else {
            for (&(l, p), &(c, w)) in self.pairs.iter().zip(&self.each) {
                f(l, p, c, w);
            }
        }
    }
}

/// A linear map from display images (LCD pixels x RGB) to retinal images (retina pixels x RGB)
/// with an exact adjoint: what the solver needs of the simulation.
pub trait Operator: Sync {
    /// Retina pixels (rows of `A`).
    fn rows(&self) -> usize;
    /// LCD pixels (columns of `A`).
    fn cols(&self) -> usize;
    /// `y = A x` (`x`: `cols()` values, `y`: `rows()` values, overwritten).
    fn forward(&self, x: &[Rgb], y: &mut [Rgb]);
    /// `out += scale A^T r` (`r`: `rows()` values, `out`: `cols()` values).
    fn adjoint_add(&self, r: &[Rgb], scale: f64, out: &mut [Rgb]);
    /// `out += scale diag(A^T A)`: for each column (and channel) the sum over rows of the
    /// squared entry, `sum_p A_pl^2` (the Jacobi preconditioner's diagonal).
    fn diagonal_add(&self, scale: f64, out: &mut [Rgb]);
}

/// The perceived-image operator `A_s` of one eye state on one display: the simulation's trace on
/// a fixed sample pattern (the eye's pupil grid, the retina's sub-pixel grid, with diffraction a
/// fixed draw of its numbers), through the eye state's [`OpticalSystem`].
pub struct EyeOperator<'a> {
    display: &'a Display,
    system: OpticalSystem<'a>,
    retina: Retina,
    /// Weight of one sample: 1 / (grid samples per pixel).
    inv_count: f64,
    /// Every sample carries weight 1 and one LCD pixel for the three channels: the entries
    /// are pairs only.
    compact: bool,
}

impl<'a> EyeOperator<'a> {
    /// The operator of `eye` looking at `display` with `retina`'s pixels and sub-pixel grid.
    pub fn new(display: &'a Display, eye: &Eye, retina: &Retina) -> Self {
        let system = OpticalSystem::new(display, eye);
        let inv_count = 1.0 / system.grid_samples_per_pixel(retina) as f64;
        let compact = system.samples_are_plain();
        Self { display, system, retina: *retina, inv_count, compact }
    }

    /// The fixed samples of retina pixel (row, col), in trace order (sub-pixel point, then pupil
    /// point, then wavelength), with diffraction their four diffraction numbers, a fixed
    /// pseudo-random pattern ([`diffraction_numbers`]).
    pub fn pixel_samples(&self, row: usize, col: usize) -> Vec<crate::optics::system::EyeSample> {
        let mut out = Vec::new();
        self.system.grid_samples(&self.retina, (row, col), &diffraction_numbers, &mut out);
        out
    }

    /// The number of bands of retina rows.
    fn bands(&self) -> usize {
        self.retina.resolution.div_ceil(BAND)
    }

    /// With diffraction, the ground truth on the operator's own samples: each pixel the mean of
    /// the scene along its samples' pupil-diffracted rays (as the converged estimator's reference
    /// is, sample by sample); `None` without diffraction (the grid's ground truth then sees the
    /// same rays).
    pub fn diffracted_target<R: RadianceField + ?Sized>(&self, field: &R) -> Option<Vec<Rgb>> {
        if !self.system.needs_diffraction() {
            return None;
        }
        let n = self.retina.resolution;
        let inv = self.inv_count;
        let mut out = vec![[0.0; 3]; n * n];
        out.par_chunks_mut(n).enumerate().for_each_init(GridBuffers::default, |buf, (row, out)| {
            let mut radiance = Vec::new();
            self.system.trace_grid(&self.retina, row..row + 1, n, true, &diffraction_numbers, buf, |pixels, t| {
                radiance.clear();
                radiance.extend(t.scene.iter().map(|r| field.radiance(r)));
                for (&p, s) in pixels.iter().zip(&t.samples) {
                    let sum = &mut out[p as usize - row * n];
                    for (c, v) in sum.iter_mut().enumerate() {
                        if let Some(j) = s.scene_ray(c) {
                            *v += radiance[j][c] * s.weight;
                        }
                    }
                }
            });
            for px in out.iter_mut() {
                *px = px.map(|v| v * inv);
            }
        });
        Some(out)
    }

    /// Every sample of the retina rows of band `band`, in the system's grid order (each pixel's
    /// in its order: sub-pixel point, pupil point, wavelength), into `out` (cleared first): the
    /// LCD pixels of the grid simulation (`crate::render::simulate_stack`) without diffraction,
    /// the converged estimator's for the same samples with it.
    fn band_entries(&self, band: usize, out: &mut Entries, buf: &mut GridBuffers) {
        out.clear();
        let n = self.retina.resolution;
        let rows = band * BAND..((band + 1) * BAND).min(n);
        let inv = self.inv_count;
        // Whole rows at a time: the order in which each LCD pixel receives its samples is part
        // of the adjoint's bits.
        self.system.trace_grid(&self.retina, rows, n, false, &diffraction_numbers, buf, |pixels, t| {
            for (&p, s) in pixels.iter().zip(&t.samples) {
                if self.compact {
                    if s.lcd[0] != MISS {
                        out.pairs.push((s.lcd[0], p));
                    }
                    continue;
                }
                let w = s.weight * inv;
                if s.shared {
                    if s.lcd[0] != MISS {
                        out.pairs.push((s.lcd[0], p));
                        out.each.push((3, w));
                    }
                    continue;
                }
                for (c, &l) in s.lcd.iter().enumerate() {
                    if l != MISS {
                        out.pairs.push((l, p));
                        out.each.push((c as u8, w));
                    }
                }
            }
        });
    }

    /// Bands traced at once by the adjoint (bounds its memory; the result does not depend on it).
    fn wave(&self) -> usize {
        (2 * rayon::current_num_threads()).max(4)
    }

    /// The matrix entries of band `band`, `(A_pl` per channel), one per distinct (LCD pixel,
    /// retina pixel) pair, sorted by (retina pixel, LCD pixel): the band's samples summed per
    /// pair (in trace order within a pair).
    fn band_matrix(&self, band: usize, scratch: &mut GridBuffers) -> Vec<(u32, Rgb)> {
        let mut entries = Entries::default();
        self.band_entries(band, &mut entries, scratch);
        let mut samples: Vec<(u32, u32, u8, f64)> = Vec::with_capacity(entries.pairs.len());
        entries.for_each(self.inv_count, |l, p, c, w| samples.push((p, l, c, w)));
        drop(entries);
        // Stable: samples of one pair keep their trace order, so the sums are deterministic.
        samples.sort_by_key(|&(p, l, _, _)| (p, l));
        let mut out: Vec<(u32, Rgb)> = Vec::new();
        let mut last = None;
        for (p, l, c, w) in samples {
            if last != Some((p, l)) {
                out.push((l, [0.0; 3]));
                last = Some((p, l));
            }
            if let Some((_, v)) = out.last_mut() {
                add(v, c, w, &[1.0; 3]);
            }
        }
        out
    }
}

/// The four diffraction numbers in [0, 1) of sample `k` of retina pixel `pixel`: the pupil's
/// deviation (0, 1) and the lenslet's (2, 3), as [`crate::optics::system::EyeSample::diffraction`]. A fixed
/// pseudo-random pattern (SplitMix64 of the pixel, the sample and the dimension), so the
/// deviations are part of the operator's fixed sample pattern: the forward operator and its
/// adjoint see the same rays.
pub fn diffraction_numbers(pixel: u64, k: u64) -> [f64; 4] {
    const SEED: u64 = 0x4f50_545f_6469_6666; // "OPT_diff"
    let base = crate::measure::sampler::mix64(SEED ^ pixel.wrapping_mul(0x1_0000_0001)).wrapping_add(k << 2);
    std::array::from_fn(|d| {
        (crate::measure::sampler::mix64(base + d as u64) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    })
}

/// `acc += w * v` in `channel` (3: all).
#[inline(always)]
fn add(acc: &mut Rgb, channel: u8, w: f64, v: &Rgb) {
    if channel == 3 {
        for c in 0..3 {
            acc[c] += w * v[c];
        }
    } else {
        let c = channel as usize;
        acc[c] += w * v[c];
    }
}

impl Operator for EyeOperator<'_> {
    fn rows(&self) -> usize {
        self.retina.resolution * self.retina.resolution
    }

    fn cols(&self) -> usize {
        self.display.lcd.pixel_count()
    }

    fn forward(&self, x: &[Rgb], y: &mut [Rgb]) {
        assert!(x.len() == self.cols() && y.len() == self.rows(), "operator sizes");
        let n = self.retina.resolution;
        y.par_chunks_mut(BAND * n).enumerate().for_each_init(
            || (Entries::default(), GridBuffers::default()),
            |(entries, scratch), (band, out)| {
                self.band_entries(band, entries, scratch);
                out.iter_mut().for_each(|v| *v = [0.0; 3]);
                let base = band * BAND * n;
                entries.for_each(self.inv_count, |l, p, c, w| add(&mut out[p as usize - base], c, w, &x[l as usize]));
            },
        );
    }

    fn adjoint_add(&self, r: &[Rgb], scale: f64, out: &mut [Rgb]) {
        assert!(r.len() == self.rows() && out.len() == self.cols(), "operator sizes");
        let wave = self.wave();
        let parts = rayon::current_num_threads().max(1);
        let chunk = out.len().div_ceil(parts).max(1);
        let mut lists: Vec<Entries> = (0..wave).map(|_| Entries::default()).collect();
        for first in (0..self.bands()).step_by(wave) {
            let count = wave.min(self.bands() - first);
            lists[..count]
                .par_iter_mut()
                .enumerate()
                .for_each_init(GridBuffers::default, |scratch, (b, list)| self.band_entries(first + b, list, scratch));
            // Each part of the LCD walks every sample in order and keeps its own: every LCD
            // pixel receives its additions in the samples' global order.
            let lists = &lists[..count];
            out.par_chunks_mut(chunk).enumerate().for_each(|(part, dst)| {
                let lo = (part * chunk) as u32;
                let hi = lo + dst.len() as u32;
                for list in lists {
                    list.for_each(self.inv_count, |l, p, c, w| {
                        if l >= lo && l < hi {
                            add(&mut dst[(l - lo) as usize], c, scale * w, &r[p as usize]);
                        }
                    });
                }
            });
        }
    }

    fn diagonal_add(&self, scale: f64, out: &mut [Rgb]) {
        assert!(out.len() == self.cols(), "operator sizes");
        let wave = self.wave();
        let parts = rayon::current_num_threads().max(1);
        let chunk = out.len().div_ceil(parts).max(1);
        for first in (0..self.bands()).step_by(wave) {
            let count = wave.min(self.bands() - first);
            let lists: Vec<Vec<(u32, Rgb)>> = (first..first + count)
                .into_par_iter()
                .map_init(GridBuffers::default, |scratch, b| self.band_matrix(b, scratch))
                .collect();
            // As the adjoint: every LCD pixel receives its additions in one global order.
            out.par_chunks_mut(chunk).enumerate().for_each(|(part, dst)| {
                let lo = (part * chunk) as u32;
                let hi = lo + dst.len() as u32;
                for &(l, v) in lists.iter().flatten() {
                    if l >= lo && l < hi {
                        let d = &mut dst[(l - lo) as usize];
                        for c in 0..3 {
                            d[c] += scale * v[c] * v[c];
                        }
                    }
                }
            });
        }
    }
}
