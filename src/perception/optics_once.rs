//! The eye's optics counted once. The contrast sensitivity inside ColorVideoVDP (castleCSF) and
//! FLIP was measured through a typical eye's optics, so it already holds that eye's in-focus
//! blur; a retinal image formed through a schematic eye's aberrations holds it a second time.
//! Barten (*Contrast sensitivity of the human eye and its effects on image quality*, SPIE 1999,
//! eq. 3.5-3.6) separates the optical modulation transfer of the eye from the neural factors:
//!
//! ```text
//! M_opt(u) = exp(-2 pi^2 sigma^2 u^2),   sigma = sqrt(sigma_0^2 + (C_ab d)^2)
//! sigma_0 = 0.5 arcmin,  C_ab = 0.08 arcmin/mm,  d: pupil diameter (mm),  u: cycles/degree
//! ```
//!
//! so a CSF divided by `M_opt` is the neural sensitivity alone. Filtering both images by
//! `1 / M_opt` before the metric does exactly that division for every spatial frequency (the
//! metric is linear up to its contrast computation): the metric's CSF then meets the retinal
//! image's own optics once. The Gaussian is separable, so is its inverse: one symmetric FIR
//! (the Fourier series of `exp(a f^2)` over the pixel's frequencies, `2 K + 1` taps) along rows
//! and one along columns, mirrored at the edges. The gain is capped at [`MAX_GAIN`] (noise and
//! frequencies far beyond the typical eye's cutoff are not amplified without bound).

pub use crate::measure::scores::OpticsCount;
use crate::raster::RgbImage;
use rayon::prelude::*;

/// Barten's sigma_0, arcmin.
pub const SIGMA_0_ARCMIN: f64 = 0.5;
/// Barten's C_ab, arcmin per mm of pupil.
pub const C_AB_ARCMIN_PER_MM: f64 = 0.08;
/// The largest gain of the compensation, `1 / M_opt` (reached only where `M_opt < 0.1`).
pub const MAX_GAIN: f64 = 10.0;
/// Half the taps of the FIR. The periodic extension of `exp(a f^2)` has a kink at the Nyquist
/// frequency, so its Fourier series converges as `1 / K` there: 24 keeps the response within 1%
/// of `1 / M_opt` up to Nyquist for pupils of 2-8 mm at 15-60 pixels per degree (6 missed it by
/// 2.5% at 30 pixels per degree).
const K: usize = 24;

/// Barten's optical spread of a typical eye with a `pupil_mm` pupil, degrees.
pub fn barten_sigma_deg(pupil_mm: f64) -> f64 {
    (SIGMA_0_ARCMIN.powi(2) + (C_AB_ARCMIN_PER_MM * pupil_mm).powi(2)).sqrt() / 60.0
}

/// Barten's optical MTF at `u` cycles per degree for a `pupil_mm` pupil.
pub fn barten_mtf(u: f64, pupil_mm: f64) -> f64 {
    let s = barten_sigma_deg(pupil_mm);
    (-2.0 * std::f64::consts::PI.powi(2) * s * s * u * u).exp()
}

/// The compensation filter for one pupil at `ppd` pixels per degree: the 1-D taps `h[0..=K]`
/// (symmetric, `h[-j] = h[j]`) whose response is `min(1 / M_opt, MAX_GAIN)` per axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Compensation {
    taps: [f64; K + 1],
}

impl Compensation {
    /// The filter for a `pupil_mm` pupil seen at `ppd` pixels per degree.
    pub fn new(pupil_mm: f64, ppd: f64) -> Self {
        // Per axis: exp(2 pi^2 s^2 u^2) with u = f ppd (f: cycles per pixel, |f| <= 1/2); the 2-D
        // gain is the product of the two axes' (the Gaussian separates). Each axis is capped at
        // sqrt(MAX_GAIN) so that the product stays within MAX_GAIN.
        let s = barten_sigma_deg(pupil_mm) * ppd;
        let a = 2.0 * std::f64::consts::PI.powi(2) * s * s;
        let cap = MAX_GAIN.sqrt();
        let response = |f: f64| (a * f * f).exp().min(cap);
        // Fourier coefficients over f in [-1/2, 1/2]: h_j = 2 int_0^{1/2} H(f) cos(2 pi j f) df,
        // by the composite Simpson rule.
        let n = 2000;
        let mut taps: [f64; K + 1] = std::array::from_fn(|j| {
            let g = |f: f64| response(f) * (2.0 * std::f64::consts::PI * j as f64 * f).cos();
            let h = 0.5 / n as f64;
            let mut sum = g(0.0) + g(0.5);
            for i in 1..n {
                sum += g(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            2.0 * sum * h / 3.0
        });
        // The truncated series' gain at zero frequency is not exactly 1: a constant offset of
        // the response (well below its error near Nyquist) makes it 1, so a uniform image, and
        // every image's mean luminance, pass unchanged.
        let dc = taps[0] + 2.0 * taps[1..].iter().sum::<f64>();
        taps[0] -= dc - 1.0;
        Self { taps }
    }

    /// The filter's response at `f` cycles per pixel along one axis.
    pub fn response(&self, f: f64) -> f64 {
        self.taps[0]
            + 2.0 * (1..=K).map(|j| self.taps[j] * (2.0 * std::f64::consts::PI * j as f64 * f).cos()).sum::<f64>()
    }

    /// `img` filtered along rows, then columns (edges mirrored), negative results (ringing at
    /// an edge) set to 0: linear light is never negative.
    pub fn apply(&self, img: &RgbImage) -> RgbImage {
        let (w, h) = (img.width, img.height);
        let mirror = |i: isize, n: usize| -> usize {
            let n = n as isize;
            let mut i = i;
            while i < 0 || i >= n {
                i = if i < 0 { -i - 1 } else { 2 * n - i - 1 };
            }
            i as usize
        };
        let mut rows = vec![[0.0f64; 3]; w * h];
        rows.par_chunks_mut(w).enumerate().for_each(|(y, out)| {
            for (x, o) in out.iter_mut().enumerate() {
                *o = std::array::from_fn(|c| {
                    let px = |dx: isize| f64::from(img.pixels[y * w + mirror(x as isize + dx, w)][c]);
                    self.taps[0] * px(0)
                        + (1..=K).map(|j| self.taps[j] * (px(j as isize) + px(-(j as isize)))).sum::<f64>()
                });
            }
        });
        let mut out = RgbImage::new(w, h);
        out.pixels.par_chunks_mut(w).enumerate().for_each(|(y, o)| {
            for (x, p) in o.iter_mut().enumerate() {
                *p = std::array::from_fn(|c| {
                    let px = |dy: isize| rows[mirror(y as isize + dy, h) * w + x][c];
                    let v = self.taps[0] * px(0)
                        + (1..=K).map(|j| self.taps[j] * (px(j as isize) + px(-(j as isize)))).sum::<f64>();
                    v.max(0.0) as f32
                });
            }
        });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barten_values() {
        // 3 mm pupil: sigma = sqrt(0.25 + 0.0576) arcmin = 0.5546 arcmin.
        assert!((barten_sigma_deg(3.0) * 60.0 - 0.5546).abs() < 1e-4);
        assert!((barten_mtf(0.0, 3.0) - 1.0).abs() < 1e-15);
        assert!(barten_mtf(30.0, 5.0) < barten_mtf(30.0, 2.0));
    }

    #[test]
    fn the_filter_inverts_the_typical_optics_at_every_frequency() {
        for (pupil, ppd) in [(5.0, 14.9), (3.0, 30.0), (5.0, 60.0), (2.0, 14.9), (8.0, 60.0)] {
            let c = Compensation::new(pupil, ppd);
            let cap = MAX_GAIN.sqrt();
            for i in 0..=40 {
                let f = 0.5 * i as f64 / 40.0;
                // Per axis the optics' Gaussian (one factor of the separable 2-D MTF).
                let s = barten_sigma_deg(pupil) * ppd;
                let want = (2.0 * std::f64::consts::PI.powi(2) * s * s * f * f).exp().min(cap);
                let tol = if want < cap * 0.95 { 0.01 } else { 0.15 };
                assert!((c.response(f) - want).abs() < tol * want, "{pupil} {ppd} f {f}: {} vs {want}", c.response(f));
            }
        }
    }

    #[test]
    fn uniform_images_pass_unchanged() {
        let c = Compensation::new(5.0, 14.9);
        let img = RgbImage::filled(20, 17, [0.25, 0.5, 1.0]);
        let out = c.apply(&img);
        for p in &out.pixels {
            for (a, b) in p.iter().zip([0.25f32, 0.5, 1.0]) {
                assert!((a - b).abs() < 1e-5, "{p:?}");
            }
        }
    }
}
