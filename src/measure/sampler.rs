//! The randomized quasi-Monte Carlo points of the converged measurement (issue 11; the paper's
//! perceived and ground-truth retinal images of Sec. 2.3 and 4.1, integrated instead of sampled
//! on grids).
//!
//! A retina pixel's value is an integral over a four-dimensional domain: a point of the pixel's
//! square (in tangent coordinates) times a point of the pupil disk, with uniform weight. Every
//! (seed, eye case, replicate, pixel) gets its own Owen scramble of the Sobol sequence
//! ([`sobol_burley`], Burley 2020): sample `i` of that sequence gives the pixel point from
//! dimensions 0 and 1 and the pupil point from dimensions 2 and 3, mapped onto the disk by the
//! area-preserving concentric map of Shirley and Chiu. Each scrambled point is uniformly
//! distributed over the domain, so the mean over any number of points is an unbiased estimate of
//! the pixel's value; scrambles of different replicates are independent, which is what the
//! statistics need. Sample `i` does not depend on how many samples are taken: doubling the count
//! adds points `N..2N` of the same sequences (nested), keeping all earlier work.
//!
//! The pinhole eye uses the pupil centre for every sample (only dimensions 0 and 1 matter).

use std::f64::consts::FRAC_PI_4;

use glam::DVec2;

/// Largest number of samples per replicate and pixel (the Sobol sequence's length in
/// [`sobol_burley`]).
pub const MAX_SAMPLES_PER_REPLICATE: u64 = 1 << 16;

/// The scrambled Sobol points of one measurement (one seed and one eye case).
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    pupil_radius: f64,
}

impl Sampler {
    /// Points for `seed` and `stream` (the eye case's index, so that eye cases get independent
    /// scrambles), over a pupil disk of `pupil_radius` mm (`None`: the pinhole eye, pupil point
    /// always the centre).
    pub fn new(seed: u64, stream: u64, pupil_radius: Option<f64>) -> Self {
        Self {
            key: mix64(mix64(seed) ^ stream.wrapping_mul(0xd6e8_feb8_6659_fd93)),
            pupil_radius: pupil_radius.unwrap_or(0.0),
        }
    }

    /// Whether pupil points are all the centre.
    pub fn is_pinhole(&self) -> bool {
        self.pupil_radius == 0.0
    }

    /// The scramble seed of one replicate of one pixel. For a fixed pixel, different replicates
    /// always get different seeds (an odd multiple of the replicate is added), so no two
    /// replicates of a pixel can share a sequence.
    #[inline]
    pub fn scramble(&self, pixel: u64, replicate: u32) -> u32 {
        let base = (mix64(self.key ^ pixel.wrapping_mul(0x9e37_79b9_7f4a_7c15)) >> 32) as u32;
        base.wrapping_add(replicate.wrapping_mul(0x9e37_79b9))
    }

    /// Sample `index` of the sequence with scramble `scramble`: the point of the pixel square
    /// (fractions in [0, 1)^2, x right, y down as [`crate::optics::Retina::tangent`] takes them)
    /// and the pupil point (mm from the pupil centre).
    #[inline]
    pub fn point(&self, scramble: u32, index: u32) -> (DVec2, DVec2) {
        debug_assert!(u64::from(index) < MAX_SAMPLES_PER_REPLICATE);
        let [a, b, c, d] = sobol_burley::sample_4d(index, 0, scramble);
        let frac = DVec2::new(f64::from(a), f64::from(b));
        if self.pupil_radius == 0.0 {
            return (frac, DVec2::ZERO);
        }
        (frac, concentric_disk(f64::from(c), f64::from(d)) * self.pupil_radius)
    }
}

/// The Shirley-Chiu concentric map of the unit square onto the unit disk: area-preserving
/// (uniform points stay uniform), continuous, and it keeps strata compact.
#[inline]
pub fn concentric_disk(u: f64, v: f64) -> DVec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if a == 0.0 && b == 0.0 {
        return DVec2::ZERO;
    }
    if a.abs() > b.abs() {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (b / a));
        DVec2::new(a * c, a * s)
    } else {
        // phi = pi/2 - (pi/4)(a/b): cos phi = sin x, sin phi = cos x.
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (a / b));
        DVec2::new(b * s, b * c)
    }
}

/// `(sin x, cos x)` for `|x| <= pi/4` by their Taylor series to x^17 and x^18, whose truncation
/// error there (below 2e-19) is under half an ulp: as exact as the library's, without its
/// range reduction.
#[inline]
fn sin_cos_quarter(x: f64) -> (f64, f64) {
    let x2 = x * x;
    // Horner in x^2: sin x = x (1 - x^2/3! (1 - x^2/(4*5) (1 - ...))).
    let mut s = 1.0;
    let mut c = 1.0;
    for k in (1..=8).rev() {
        let k = k as f64;
        s = 1.0 - x2 / ((2.0 * k) * (2.0 * k + 1.0)) * s;
        c = 1.0 - x2 / ((2.0 * k - 1.0) * (2.0 * k)) * c;
    }
    (x * s, c)
}

/// SplitMix64's finaliser: a bijective 64-bit mixer.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_sin_cos_matches_the_library() {
        for i in -1000..=1000 {
            let x = FRAC_PI_4 * i as f64 / 1000.0;
            let (s, c) = sin_cos_quarter(x);
            assert!((s - x.sin()).abs() <= 2e-16 && (c - x.cos()).abs() <= 2e-16, "{x}");
        }
    }

    #[test]
    fn concentric_map_is_uniform_on_the_disk() {
        // Midpoint rule over the unit square: the moments of the image must be the disk's.
        let n = 1000;
        let (mut mx, mut my, mut mxx, mut myy, mut mxy, mut mr4) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut inner = 0usize;
        let mut quadrant = [0usize; 4];
        for j in 0..n {
            for i in 0..n {
                let p = concentric_disk((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                assert!(p.length() <= 1.0 + 1e-15);
                mx += p.x;
                my += p.y;
                mxx += p.x * p.x;
                myy += p.y * p.y;
                mxy += p.x * p.y;
                mr4 += p.length_squared().powi(2);
                inner += (p.length() < 0.5) as usize;
                quadrant[(p.x < 0.0) as usize * 2 + (p.y < 0.0) as usize] += 1;
            }
        }
        let m = (n * n) as f64;
        assert!((mx / m).abs() < 1e-9 && (my / m).abs() < 1e-9 && (mxy / m).abs() < 1e-9);
        // E[x^2] = E[y^2] = 1/4, E[r^4] = 1/3, P(r < 1/2) = 1/4 for the uniform unit disk.
        assert!((mxx / m - 0.25).abs() < 1e-5, "{}", mxx / m);
        assert!((myy / m - 0.25).abs() < 1e-5, "{}", myy / m);
        assert!((mr4 / m - 1.0 / 3.0).abs() < 1e-5, "{}", mr4 / m);
        assert!((inner as f64 / m - 0.25).abs() < 1e-3, "{}", inner as f64 / m);
        assert!(quadrant.iter().all(|&q| q == n * n / 4), "{quadrant:?}");
    }

    #[test]
    fn samples_are_nested_and_replicates_differ() {
        let s = Sampler::new(7, 1, Some(2.5));
        let a = s.scramble(12345, 0);
        let b = s.scramble(12345, 1);
        assert_ne!(a, b);
        // A point depends only on its index: nothing else about the run changes it.
        assert_eq!(s.point(a, 17), s.point(a, 17));
        assert_ne!(s.point(a, 17), s.point(b, 17));
        for i in 0..256 {
            let (f, p) = s.point(a, i);
            assert!((0.0..1.0).contains(&f.x) && (0.0..1.0).contains(&f.y));
            assert!(p.length() <= 2.5 + 1e-12);
        }
        let pin = Sampler::new(7, 1, None);
        assert!(pin.is_pinhole());
        assert_eq!(pin.point(a, 3).1, DVec2::ZERO);
        assert_eq!(pin.point(a, 3).0, s.point(a, 3).0);
    }

    #[test]
    fn every_power_of_two_prefix_stratifies_the_pixel() {
        // Owen-scrambled Sobol: the first 2^m points of a scrambled sequence put exactly one
        // point in each of the 2^m cells of every 2^a x 2^(m-a) grid of the pixel.
        let s = Sampler::new(3, 0, Some(1.0));
        for scramble in [s.scramble(0, 0), s.scramble(99, 5), s.scramble(7, 2)] {
            for m in 1..=8u32 {
                let pts: Vec<DVec2> = (0..1u32 << m).map(|i| s.point(scramble, i).0).collect();
                for a in 0..=m {
                    let (nx, ny) = (1usize << a, 1usize << (m - a));
                    let mut cells = vec![0u8; nx * ny];
                    for p in &pts {
                        cells[(p.y * ny as f64) as usize * nx + (p.x * nx as f64) as usize] += 1;
                    }
                    assert!(cells.iter().all(|&c| c == 1), "m = {m}, a = {a}");
                }
            }
        }
    }
}
