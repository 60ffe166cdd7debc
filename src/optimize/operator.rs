//! The perceived-image simulation as a linear operator on the display image, and its exact
//! adjoint (paper Sec. 2.3, eq. (1)): for one eye state, retina pixel `p` of the perceived image
//! is the weighted mean of the LCD pixels its eye rays reach, `(A x)_p = sum_e w_e x_{l_e}` over
//! the pixel's samples `e` (retina sub-pixel point x pupil point, and for an eye beyond the thin
//! lens its wavelengths and Stiles-Crawford weight). `A^T r` splats each residual back along the
//! same rays: `(A^T r)_l = sum_{e : l_e = l} w_e r_{p_e}`.
//!
//! Matrix-free: the samples of a band of retina rows are traced afresh on every application
//! (the same eye-to-LCD trace as `crate::render::simulate_stack`: [`FastTransfer`] for the thin
//! lens, the eye's own rays ([`crate::optics::eye::EyeOptics::rays`]) otherwise, through real
//! lenslets each channel's own exact trace) and dropped; only a bounded wave of bands is held at
//! once. With diffraction (which only the converged estimator models) each sample carries a fixed
//! pseudo-random draw of the pupil's and the lenslet aperture's deviations
//! ([`diffraction_numbers`]), and its LCD pixels are those the estimator finds for that sample. The sample pattern is fixed, so the forward operator
//! and the adjoint are the same matrix, transposed. Both are deterministic bit for bit at any
//! thread count: the forward sums each retina pixel's samples in trace order, and the adjoint adds
//! into each LCD pixel in the global order of the samples (bands in order, samples in trace order),
//! whichever thread owns that pixel.

use glam::DVec2;
use rayon::prelude::*;

use crate::measure::estimator::EyeSample;
use crate::optics::diffraction::ApertureShape;
use crate::optics::eye::EyeOptics;
use crate::optics::transfer::FastTransfer;
use crate::optics::{Display, Eye, Retina};
use crate::ray::Ray;
use crate::render::retina::through_optics;
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
/// a fixed sample pattern (the eye's pupil grid, the retina's sub-pixel grid).
pub struct EyeOperator<'a> {
    display: &'a Display,
    eye: Eye,
    retina: Retina,
    fast: FastTransfer<'a>,
    pupil: Vec<DVec2>,
    subpixels: Vec<DVec2>,
    /// Weight of one sample of the thin lens: 1 / (sub-pixel samples x pupil samples).
    inv_count: f64,
    /// The thin-lens eye's `EyeOptics` when the display has real lenslets and the eye no optics
    /// of its own (each colour channel then finds its own LCD pixel).
    thin: Option<EyeOptics>,
    /// The lenslet aperture when it diffracts (`[optics] diffraction = "apertures"`).
    lenslet: Option<ApertureShape>,
}

impl<'a> EyeOperator<'a> {
    /// The operator of `eye` looking at `display` with `retina`'s pixels and sub-pixel grid.
    pub fn new(display: &'a Display, eye: &Eye, retina: &Retina) -> Self {
        let pupil = eye.pupil_samples();
        let subpixels = retina.subpixel_offsets();
        let inv_count = 1.0 / (pupil.len() * subpixels.len()) as f64;
        let thin = (eye.optics.is_none() && display.thick_lenslet().is_some()).then(|| EyeOptics::thin_lens(eye));
        let fast = match (&eye.optics, &thin) {
            (None, None) => FastTransfer::new(display, eye, &pupil),
            _ => FastTransfer::for_eye(display, eye),
        };
        let lenslet = eye
            .optics
            .as_ref()
            .filter(|o| o.diffraction.lenslets())
            .map(|_| ApertureShape::of_lattice(&display.lenslets));
        Self { display, eye: eye.clone(), retina: *retina, fast, pupil, subpixels, inv_count, thin, lenslet }
    }

    /// The number of bands of retina rows.
    fn bands(&self) -> usize {
        self.retina.resolution.div_ceil(BAND)
    }

    /// The eye the optics path traces through: the eye's own optics, or for real lenslets seen by
    /// the thin lens its `EyeOptics` (as `crate::render::simulate_stack`); `None`: the thin
    /// lens's fast path.
    fn optics(&self) -> Option<&EyeOptics> {
        self.eye.optics.as_deref().or(self.thin.as_ref())
    }

    /// The fixed samples of retina pixel (row, col) through `optics`, in trace order (sub-pixel
    /// point, then pupil point, then wavelength): those of the grid simulation
    /// (`through_optics::pixel_samples`), and with diffraction their four diffraction numbers,
    /// a fixed pseudo-random pattern ([`diffraction_numbers`]). Without diffraction they are 0,
    /// and unused.
    pub fn pixel_samples(&self, row: usize, col: usize) -> Vec<EyeSample> {
        let Some(optics) = self.optics() else {
            return Vec::new();
        };
        let spectral = optics.grid_spectral();
        let diffraction = optics.diffraction.is_on();
        let pixel = (row * self.retina.resolution + col) as u64;
        let mut out = Vec::with_capacity(self.subpixels.len() * self.pupil.len() * spectral.len());
        for frac in &self.subpixels {
            let tangent = self.retina.tangent(row, col, *frac);
            for &pupil in &self.pupil {
                for &u in &spectral {
                    let k = out.len() as u64;
                    let numbers = if diffraction { diffraction_numbers(pixel, k) } else { [0.0; 4] };
                    out.push(EyeSample { tangent, pupil, spectral: u, diffraction: numbers });
                }
            }
        }
        out
    }

    /// With diffraction, the ground truth on the operator's own samples: each pixel the mean of
    /// the scene along its samples' pupil-diffracted rays (as the converged estimator's reference
    /// is, sample by sample); `None` without diffraction (the grid's ground truth then sees the
    /// same rays).
    pub fn diffracted_target<R: RadianceField + ?Sized>(&self, field: &R) -> Option<Vec<Rgb>> {
        let optics = self.optics().filter(|o| o.diffraction.is_on())?;
        let n = self.retina.resolution;
        let inv = 1.0 / through_optics::per_pixel(optics, &self.eye, &self.retina);
        let z = self.eye.position.z;
        let mut out = vec![[0.0; 3]; n * n];
        out.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
            for (col, px) in out.iter_mut().enumerate() {
                let mut sum = [0.0; 3];
                for s in self.pixel_samples(row, col) {
                    let sr =
                        optics.rays_diffracted(s.tangent, s.pupil, s.spectral, [s.diffraction[0], s.diffraction[1]]);
                    through_optics::each_ray(&sr, |channels, r| {
                        let w = through_optics::world(&self.eye, r);
                        let l = field.radiance(&Ray { origin: w.position.extend(z), dir: w.slope.extend(1.0) });
                        for c in channels {
                            sum[c] += l[c] * sr.weight;
                        }
                    });
                }
                *px = sum.map(|v| v * inv);
            }
        });
        Some(out)
    }

    /// Every sample of the retina rows of band `band`, in trace order (per pixel: sub-pixel
    /// point, then pupil point, then wavelength), into `out` (cleared first). Through `optics`
    /// each sample's LCD pixels are those of the perceived-image simulation: the grid
    /// simulation's (`crate::render::simulate_stack`) without diffraction, the converged
    /// estimator's (`measure::estimator::through_optics`) for the same samples with it.
    fn band_entries(&self, band: usize, out: &mut Entries, scratch: &mut (Vec<DVec2>, Vec<DVec2>, Vec<u32>)) {
        out.clear();
        let n = self.retina.resolution;
        let rows = band * BAND..((band + 1) * BAND).min(n);
        if let Some(optics) = self.optics() {
            let inv = 1.0 / through_optics::per_pixel(optics, &self.eye, &self.retina);
            let thick = self.fast.is_thick();
            let diffraction = optics.diffraction.is_on();
            let single = optics.is_single_wavelength();
            // Each channel finds its own LCD pixel through a real lenslet, and through a
            // diffracting lenslet when the channels' wavelengths differ.
            let per_channel = thick || (self.lenslet.is_some() && !single);
            let fast = &self.fast;
            for row in rows {
                for col in 0..n {
                    let pixel = (row * n + col) as u32;
                    for s in self.pixel_samples(row, col) {
                        let sr = if diffraction {
                            optics.rays_diffracted(s.tangent, s.pupil, s.spectral, [s.diffraction[0], s.diffraction[1]])
                        } else {
                            optics.rays(s.tangent, s.pupil, s.spectral)
                        };
                        let w = sr.weight * inv;
                        let draw = self
                            .lenslet
                            .as_ref()
                            .map(|shape| (shape, shape.draw([s.diffraction[2], s.diffraction[3]])));
                        // Real lenslets: each channel at the sampled wavelength, else its primary's median.
                        let u_lens = if single { 0.5 } else { s.spectral };
                        through_optics::each_ray(&sr, |channels, r| {
                            let r = through_optics::world(&self.eye, r);
                            let index = |ch: usize| match (thick, draw) {
                                (false, None) => fast.pixel_index_of(r),
                                (false, Some((shape, draw))) => {
                                    fast.pixel_index_deviated(r, shape.scaled(draw, optics.wavelength(ch, s.spectral)))
                                }
                                (true, None) => fast.pixel_index_in(r, ch, u_lens),
                                (true, Some((shape, draw))) => {
                                    let deviation = shape.scaled(draw, optics.wavelength(ch, s.spectral));
                                    fast.pixel_index_in_deviated(r, ch, u_lens, deviation)
                                }
                            };
                            if per_channel {
                                for ch in channels {
                                    if let Some(i) = index(ch) {
                                        out.pairs.push((i as u32, pixel));
                                        out.each.push((ch as u8, w));
                                    }
                                }
                            } else if let Some(i) = index(channels.start) {
                                let channel = if channels.len() == 3 { 3 } else { channels.start as u8 };
                                out.pairs.push((i as u32, pixel));
                                out.each.push((channel, w));
                            }
                        });
                    }
                }
            }
            return;
        }
        let (tangents, trace, lcd) = scratch;
        lcd.resize(n, 0);
        // A row per (sub-pixel point, pupil point) in one batch: each pixel's samples still come
        // in its own order (sub-pixel point, then pupil point), interleaved with its row's.
        for row in rows {
            for frac in &self.subpixels {
                tangents.clear();
                tangents.extend((0..n).map(|col| self.retina.tangent(row, col, *frac)));
                for k in 0..self.pupil.len() {
                    self.fast.pixel_indices(tangents, k, trace, lcd);
                    let base = (row * n) as u32;
                    out.pairs.extend(
                        lcd.iter().enumerate().filter(|(_, &i)| i != u32::MAX).map(|(col, &i)| (i, base + col as u32)),
                    );
                }
            }
        }
    }

    /// Bands traced at once by the adjoint (bounds its memory; the result does not depend on it).
    fn wave(&self) -> usize {
        (2 * rayon::current_num_threads()).max(4)
    }

    /// The matrix entries of band `band`, `(A_pl` per channel), one per distinct (LCD pixel,
    /// retina pixel) pair, sorted by (retina pixel, LCD pixel): the band's samples summed per
    /// pair (in trace order within a pair).
    fn band_matrix(&self, band: usize, scratch: &mut (Vec<DVec2>, Vec<DVec2>, Vec<u32>)) -> Vec<(u32, Rgb)> {
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
/// deviation (0, 1) and the lenslet's (2, 3), as [`EyeSample::diffraction`]. A fixed
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
            || (Entries::default(), (Vec::new(), Vec::new(), Vec::new())),
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
            lists[..count].par_iter_mut().enumerate().for_each_init(
                || (Vec::new(), Vec::new(), Vec::new()),
                |scratch, (b, list)| self.band_entries(first + b, list, scratch),
            );
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
                .map_init(|| (Vec::new(), Vec::new(), Vec::new()), |scratch, b| self.band_matrix(b, scratch))
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
