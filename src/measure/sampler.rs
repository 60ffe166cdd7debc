//! The randomized quasi-Monte Carlo points of the converged measurement (the paper's
//! perceived and ground-truth retinal images of Sec. 2.3 and 4.1, integrated instead of sampled
//! on grids).
//!
//! A retina pixel's value is an integral over a four-dimensional domain: a point of the pixel's
//! square (in tangent coordinates) times a point of the pupil disk, with uniform weight. Every
//! (seed, eye case, replicate, pixel) gets its own Owen scramble of the 4-D Sobol sequence (the
//! direction numbers and the hash-based Owen scramble of [`sobol_burley`], Burley 2020). Sample
//! `i` is Sobol point `gray(i) = i ^ (i >> 1)` (Gray-code order, so each sample costs one XOR
//! of direction numbers before its scramble; the first `2^m` samples are exactly the first `2^m`
//! Sobol points, a (0, m, 2)-net in the pixel). Dimensions 0 and 1 give the pixel point, 2 and 3
//! the pupil point, mapped onto the disk by the area-preserving concentric map of Shirley and
//! Chiu. Each scrambled point is uniformly distributed over the domain, so the mean over any
//! number of points is an unbiased estimate of the pixel's value; scrambles of different
//! replicates are independent, which is what the statistics need. Sample `i` does not depend on
//! how many samples are taken: doubling the count adds points `N..2N` of the same sequences
//! (nested), keeping all earlier work.
//!
//! The pinhole eye uses the pupil centre for every sample (only dimensions 0 and 1 matter).

use std::f64::consts::FRAC_PI_4;

use glam::DVec2;
use sobol_burley::parts::{
    hash, hash_int4, owen_scramble_int4_rev, owen_scramble_rev, sobol_int4_rev, sobol_rev, u32_to_f32_norm, Int4,
};

/// Largest number of samples per replicate and pixel (the Sobol sequence's length in
/// [`sobol_burley`]).
pub const MAX_SAMPLES_PER_REPLICATE: u64 = 1 << 16;

/// The scrambled Sobol points of one measurement (one seed and one eye case).
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    pupil_radius: f64,
    /// Direction numbers of dimensions 0-3, bit-reversed: `directions[j]` is Sobol point `2^j`.
    directions: [Int4; 16],
    /// Plain Monte Carlo: independent uniform points instead of scrambled Sobol points.
    independent: bool,
}

impl Sampler {
    /// Points for `seed` and `stream` (the eye case's index, so that eye cases get independent
    /// scrambles), over a pupil disk of `pupil_radius` mm (`None`: the pinhole eye, pupil point
    /// always the centre).
    pub fn new(seed: u64, stream: u64, pupil_radius: Option<f64>) -> Self {
        Self {
            key: mix64(mix64(seed) ^ stream.wrapping_mul(0xd6e8_feb8_6659_fd93)),
            pupil_radius: pupil_radius.unwrap_or(0.0),
            directions: std::array::from_fn(|j| sobol_int4_rev((1u32 << j).reverse_bits(), 0)),
            independent: false,
        }
    }

    /// Plain random sampling for the same seed and stream: every sample of every replicate and
    /// pixel an independent uniform point of the domain (a hash of the scramble seed and the
    /// sample's index), with the same seeding discipline as [`Sampler::new`] (replicates and
    /// pixels get distinct seeds; sample `i` does not depend on how many are taken). The bench's
    /// baseline for what the Sobol points gain.
    pub fn independent(seed: u64, stream: u64, pupil_radius: Option<f64>) -> Self {
        Self { independent: true, ..Self::new(seed, stream, pupil_radius) }
    }

    /// Whether the points are independent uniform ones ([`Sampler::independent`]).
    pub fn is_independent(&self) -> bool {
        self.independent
    }

    /// The pupil radius in mm (0 for the pinhole eye).
    pub fn pupil_radius(&self) -> f64 {
        self.pupil_radius
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

    /// Samples `start, start + 1, ...` of the sequence of one replicate of one pixel.
    #[inline]
    pub fn points(&self, pixel: u64, replicate: u32, start: u32) -> Points<'_> {
        self.points_of(self.scramble(pixel, replicate), start)
    }

    /// Samples `start, start + 1, ...` of the sequence with scramble seed `scramble`.
    #[inline]
    pub fn points_of(&self, scramble: u32, start: u32) -> Points<'_> {
        debug_assert!(u64::from(start) < MAX_SAMPLES_PER_REPLICATE);
        let mut gray = start ^ (start >> 1);
        let mut x = sobol_int4_rev(0, 0);
        while gray != 0 {
            x ^= self.directions[gray.trailing_zeros() as usize];
            gray &= gray - 1;
        }
        Points { sampler: self, scramble: scramble_of(scramble), seed: scramble, index: start, sobol_rev: x }
    }

    /// Sample `index` of the sequence with scramble seed `scramble` (random access; the
    /// [`Points`] iterator is the fast way through consecutive samples).
    pub fn point(&self, scramble: u32, index: u32) -> (DVec2, DVec2) {
        self.points_of(scramble, index).next_point()
    }
}

/// The per-dimension Owen scramble values of a seed, as `sobol_burley::sample_4d` derives them
/// for dimension set 0.
#[inline]
fn scramble_of(seed: u32) -> Int4 {
    let s: Int4 = [seed.wrapping_mul(0x9c8f_2d3b); 4].into();
    hash_int4(s ^ [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8].into())
}

/// Consecutive samples of one scrambled sequence.
pub struct Points<'a> {
    sampler: &'a Sampler,
    scramble: Int4,
    /// The scramble seed (the key of independent points).
    seed: u32,
    index: u32,
    /// Sobol point `gray(index)`, bit-reversed.
    sobol_rev: Int4,
}

impl Points<'_> {
    /// Skips `n` samples and returns the next one (tests).
    #[cfg(test)]
    fn nth_point(&mut self, n: u32) -> (DVec2, DVec2) {
        for _ in 0..n {
            self.next_raw();
        }
        self.next_point()
    }

    /// The four coordinates in [0, 1) of the current sample, then step to the next.
    #[inline(always)]
    pub fn next_raw(&mut self) -> [f32; 4] {
        debug_assert!(u64::from(self.index) < MAX_SAMPLES_PER_REPLICATE);
        if self.sampler.independent {
            let h = mix64((u64::from(self.seed) << 32 | u64::from(self.index)) ^ self.sampler.key);
            let g = mix64(h ^ 0x2545_f491_4f6c_dd1d);
            self.index += 1;
            // 24 bits per coordinate: exactly representable, uniform on [0, 1).
            let unit = |x: u64| (x & 0xff_ffff) as f32 * (1.0 / 16_777_216.0);
            return [unit(h), unit(h >> 32), unit(g), unit(g >> 32)];
        }
        let out = owen_scramble_int4_rev(self.sobol_rev, self.scramble).reverse_bits().to_f32_norm();
        self.index += 1;
        // gray(i + 1) = gray(i) ^ 2^ctz(i + 1).
        self.sobol_rev ^= self.sampler.directions[(self.index.trailing_zeros() & 15) as usize];
        out
    }

    /// The current sample: the point of the pixel square (fractions in [0, 1)^2, x right, y down
    /// as [`crate::optics::Retina::tangent`] takes them) and the pupil point (mm from the pupil
    /// centre); then step to the next.
    /// The fifth coordinate in [0, 1) of the sample the last call to [`Points::next_raw`] (or
    /// a `next_point` method) returned: the spectral dimension that picks a schematic eye's
    /// wavelengths. It is dimension 4 of the same seed's Owen-scrambled Sobol sequence in
    /// [`sobol_burley::sample`], whose second dimension set is index-shuffled independently of
    /// the first (Burley 2020's padding): a stratified 1-D sequence over every pixel's samples,
    /// uncorrelated with the pixel and pupil points. Independent points hash instead.
    #[inline]
    pub fn spectral_of_last(&self) -> f64 {
        let i = self.index.wrapping_sub(1);
        if self.sampler.independent {
            let h = mix64((u64::from(self.seed) << 32 | u64::from(i)) ^ self.sampler.key ^ 0x5bd1_e995_7f4a_7c15);
            return (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        }
        f64::from(sobol_burley::sample(i, 4, self.seed))
    }

    /// Coordinates 5 to 8 in [0, 1) of the sample the last call to [`Points::next_raw`] returned:
    /// the diffraction dimensions (the pupil's deviation, then the lenslet's;
    /// `optics::diffraction`), dimensions 5-8 of the same seed's scrambled Sobol sequence in
    /// [`sobol_burley::sample`] as [`Points::spectral_of_last`] takes dimension 4. Independent
    /// points hash instead.
    #[inline]
    pub fn diffraction_of_last(&self) -> [f64; 4] {
        let i = self.index.wrapping_sub(1);
        if self.sampler.independent {
            return std::array::from_fn(|d| {
                let h = mix64(
                    (u64::from(self.seed) << 32 | u64::from(i))
                        ^ self.sampler.key
                        ^ (0x3c6e_f372_fe94_f82b_u64.wrapping_mul(d as u64 + 1)),
                );
                (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
            });
        }
        std::array::from_fn(|d| f64::from(sobol_burley::sample(i, 5 + d as u32, self.seed)))
    }

    /// [`Points::spectral_of_last`] and [`Points::diffraction_of_last`] at once, the same
    /// numbers: dimensions 4-7 are one of [`sobol_burley`]'s 4-D sets, drawn together by
    /// [`sobol_burley::sample_4d`] (one index shuffle and one Sobol walk instead of four).
    #[inline]
    pub fn spectral_and_diffraction_of_last(&self) -> (f64, [f64; 4]) {
        if self.sampler.independent {
            return (self.spectral_of_last(), self.diffraction_of_last());
        }
        let i = self.index.wrapping_sub(1);
        let [d4, d5, d6, d7] = sobol_burley::sample_4d(i, 1, self.seed);
        let d8 = sobol_burley::sample(i, 8, self.seed);
        (f64::from(d4), [f64::from(d5), f64::from(d6), f64::from(d7), f64::from(d8)])
    }

    /// The later dimensions of this sequence's samples ([`LaterDims`]): built once per sequence,
    /// then [`Points::spectral_and_diffraction_with`] gives what
    /// [`Points::spectral_and_diffraction_of_last`] gives, bit for bit, without recomputing
    /// the seed's hashes and the Sobol point bit by bit for every sample.
    #[inline]
    pub fn later_dims(&self) -> LaterDims {
        LaterDims::new(self.seed)
    }

    /// [`Points::spectral_and_diffraction_of_last`] through `later` (this sequence's
    /// [`Points::later_dims`]): the same numbers, bit for bit (tested).
    #[inline(always)]
    pub fn spectral_and_diffraction_with(&self, later: &LaterDims) -> (f64, [f64; 4]) {
        if self.sampler.independent {
            return self.spectral_and_diffraction_of_last();
        }
        later.at(self.index.wrapping_sub(1))
    }

    /// The current sample's pixel point and the raw uniform pair of its pupil point (to map with
    /// [`concentric_disk_batch`]; `None` for the pinhole eye); then step to the next.
    #[inline(always)]
    pub fn next_point_raw(&mut self) -> (DVec2, Option<DVec2>) {
        let [a, b, c, d] = self.next_raw();
        let frac = DVec2::new(f64::from(a), f64::from(b));
        (frac, (self.sampler.pupil_radius != 0.0).then(|| DVec2::new(f64::from(c), f64::from(d))))
    }

    /// The next sample: the point in the pixel (fractions) and the point on the unit pupil disk.
    #[inline(always)]
    pub fn next_point(&mut self) -> (DVec2, DVec2) {
        let [a, b, c, d] = self.next_raw();
        let frac = DVec2::new(f64::from(a), f64::from(b));
        let r = self.sampler.pupil_radius;
        if r == 0.0 {
            return (frac, DVec2::ZERO);
        }
        (frac, concentric_disk(f64::from(c), f64::from(d)) * r)
    }
}

/// Dimensions 4 to 8 of one seed's Owen-scrambled Sobol sequence, exactly as
/// [`sobol_burley::sample_4d`] (dimension set 1) and [`sobol_burley::sample`] (dimension 8)
/// compute them (Burley 2020: the sample index shuffled by a nested uniform scramble, the Sobol
/// point of the shuffled index, each dimension Owen-scrambled), with the seed's three hashes
/// computed once per sequence and the Sobol point of the shuffled index from two byte tables
/// instead of one step per set bit: the point is the XOR of the direction numbers of the index's
/// set bits (its top 16 bits, as `sobol_burley` takes them), so the XOR of the tables' entries for
/// the index's two top bytes is the same point.
#[derive(Clone, Copy)]
pub struct LaterDims {
    tables: &'static ByteTables,
    index: u32,
    set1: Int4,
    dim8: u32,
}

/// The Sobol points of the index's top byte (`hi`) and second byte (`lo`), dimensions 4-7 and 8.
struct ByteTables {
    hi4: [Int4; 256],
    lo4: [Int4; 256],
    hi8: [u32; 256],
    lo8: [u32; 256],
}

fn byte_tables() -> &'static ByteTables {
    static T: std::sync::OnceLock<ByteTables> = std::sync::OnceLock::new();
    T.get_or_init(|| ByteTables {
        hi4: std::array::from_fn(|b| sobol_int4_rev((b as u32) << 24, 1)),
        lo4: std::array::from_fn(|b| sobol_int4_rev((b as u32) << 16, 1)),
        hi8: std::array::from_fn(|b| sobol_rev((b as u32) << 24, 8)),
        lo8: std::array::from_fn(|b| sobol_rev((b as u32) << 16, 8)),
    })
}

impl LaterDims {
    /// The later dimensions of the sequence with scramble seed `seed`.
    pub fn new(seed: u32) -> Self {
        let s = seed.wrapping_mul(0x9c8f_2d3b);
        let set1: Int4 = [s; 4].into();
        let ds: Int4 = [1u32; 4].into();
        Self {
            tables: byte_tables(),
            index: hash(seed ^ 0x79c6_8e4a),
            set1: hash_int4(set1 ^ ds ^ [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8].into()),
            dim8: hash(2 ^ s ^ 0x912f_69ba),
        }
    }

    /// Dimension 4 and dimensions 5-8 of sample `i`.
    #[inline(always)]
    pub fn at(&self, i: u32) -> (f64, [f64; 4]) {
        let t = self.tables;
        let rev = owen_scramble_rev(i.reverse_bits(), self.index);
        let (hi, lo) = ((rev >> 24) as usize, ((rev >> 16) & 0xff) as usize);
        let [d4, d5, d6, d7] = owen_scramble_int4_rev(t.hi4[hi] ^ t.lo4[lo], self.set1).reverse_bits().to_f32_norm();
        let d8 = u32_to_f32_norm(owen_scramble_rev(t.hi8[hi] ^ t.lo8[lo], self.dim8).reverse_bits());
        (f64::from(d4), [f64::from(d5), f64::from(d6), f64::from(d7), f64::from(d8)])
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

/// [`concentric_disk`] scaled by `radius` for a batch of points in place (each `(u, v)` in
/// `[0, 1)^2` becomes its disk point): the same arithmetic, so the same bits, with selects instead
/// of branches so the loop vectorises and no random branch is mispredicted.
#[inline(always)]
pub fn concentric_disk_batch(points: &mut [DVec2], radius: f64) {
    for p in points {
        let a = 2.0 * p.x - 1.0;
        let b = 2.0 * p.y - 1.0;
        let first = a.abs() > b.abs();
        let (num, den) = if first { (b, a) } else { (a, b) };
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (num / den));
        let (x, y) = if first { (a * c, a * s) } else { (b * s, b * c) };
        let centre = a == 0.0 && b == 0.0;
        *p = DVec2::new(if centre { 0.0 } else { x * radius }, if centre { 0.0 } else { y * radius });
    }
}

/// `(sin x, cos x)` for `|x| <= pi/4` by their Taylor series to x^13 and x^14, whose truncation
/// error there (below 3e-14) is far below what matters (the points come from 24-bit uniforms),
/// without the library's range reduction. Estrin's scheme keeps the dependency chains short.
#[inline(always)]
fn sin_cos_quarter(x: f64) -> (f64, f64) {
    /// Coefficients of the series in y = x^2: sin x = x sum SIN[k] y^k, cos x = sum COS[k] y^k.
    const SIN: [f64; 8] = {
        let mut c = [0.0; 8];
        let (mut k, mut f) = (0, 1.0);
        while k < 7 {
            c[k] = if k % 2 == 0 { 1.0 / f } else { -1.0 / f };
            f *= ((2 * k + 2) * (2 * k + 3)) as f64;
            k += 1;
        }
        c
    };
    const COS: [f64; 8] = {
        let mut c = [0.0; 8];
        let (mut k, mut f) = (0, 1.0);
        while k < 8 {
            c[k] = if k % 2 == 0 { 1.0 / f } else { -1.0 / f };
            f *= ((2 * k + 1) * (2 * k + 2)) as f64;
            k += 1;
        }
        c
    };
    #[inline(always)]
    fn estrin(a: &[f64; 8], y: f64) -> f64 {
        let y2 = y * y;
        let y4 = y2 * y2;
        ((a[0] + a[1] * y) + y2 * (a[2] + a[3] * y)) + y4 * ((a[4] + a[5] * y) + y2 * (a[6] + a[7] * y))
    }
    let y = x * x;
    (x * estrin(&SIN, y), estrin(&COS, y))
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
    fn later_dims_from_byte_tables_equal_sobol_burley_bit_for_bit() {
        // Every index of a replicate's first 4096 samples and the sequence's last ones,
        // several scrambles, both samplers.
        for sampler in [Sampler::new(3, 1, Some(2.5)), Sampler::independent(3, 1, Some(2.5))] {
            for scramble in [0u32, 1, 0x9e37_79b9, 0x1234_5678, u32::MAX] {
                let mut points = sampler.points_of(scramble, 0);
                let later = points.later_dims();
                for i in 0..(1u32 << 16) {
                    points.next_raw();
                    if (4096..(1 << 16) - 256).contains(&i) {
                        continue;
                    }
                    let (u, d) = points.spectral_and_diffraction_with(&later);
                    let (v, e) = points.spectral_and_diffraction_of_last();
                    assert_eq!(u.to_bits(), v.to_bits(), "scramble {scramble}, sample {i}");
                    assert_eq!(d.map(f64::to_bits), e.map(f64::to_bits), "scramble {scramble}, sample {i}");
                    if !sampler.is_independent() {
                        let [a, b, c, x] = sobol_burley::sample_4d(i, 1, scramble);
                        assert_eq!([u, d[0], d[1], d[2]], [a, b, c, x].map(f64::from));
                        assert_eq!(d[3], f64::from(sobol_burley::sample(i, 8, scramble)));
                    }
                }
            }
        }
    }

    #[test]
    fn spectral_and_diffraction_together_equal_them_one_by_one_bit_for_bit() {
        // Every index of a replicate's first 4096 samples, several scrambles, both samplers.
        for sampler in [Sampler::new(3, 1, Some(2.5)), Sampler::independent(3, 1, Some(2.5))] {
            for scramble in [0u32, 1, 0x9e37_79b9, u32::MAX] {
                let mut points = sampler.points_of(scramble, 0);
                for _ in 0..4096 {
                    points.next_raw();
                    let (u, d) = points.spectral_and_diffraction_of_last();
                    assert_eq!(u.to_bits(), points.spectral_of_last().to_bits());
                    assert_eq!(d.map(f64::to_bits), points.diffraction_of_last().map(f64::to_bits));
                }
            }
        }
    }

    #[test]
    fn quarter_sin_cos_matches_the_library() {
        for i in -1000..=1000 {
            let x = FRAC_PI_4 * i as f64 / 1000.0;
            let (s, c) = sin_cos_quarter(x);
            assert!((s - x.sin()).abs() <= 3e-14 && (c - x.cos()).abs() <= 3e-14, "{x}");
        }
    }

    #[test]
    fn batched_concentric_map_equals_the_single_point_map_bit_for_bit() {
        // The centre (0/0 in the branch-free form), both diagonals (|a| == |b|, the branches'
        // boundary), the square's edges and 24-bit uniforms like the sampler's.
        let mut uv = vec![DVec2::splat(0.5), DVec2::new(0.0, 0.0), DVec2::new(0.0, 0.5), DVec2::new(0.5, 0.0)];
        for i in 0..=64 {
            let t = i as f64 / 64.0;
            uv.extend([DVec2::new(t, t), DVec2::new(t, 1.0 - t), DVec2::new(t, 0.0), DVec2::new(1.0, t)]);
        }
        let mut s = 7u64;
        for _ in 0..100_000 {
            s = mix64(s);
            let unit = |x: u64| (x & 0xff_ffff) as f64 / 16_777_216.0;
            uv.push(DVec2::new(unit(s), unit(s >> 32)));
        }
        for radius in [2.5, 1.0, 1e-3] {
            let mut batch = uv.clone();
            concentric_disk_batch(&mut batch, radius);
            for (p, q) in uv.iter().zip(&batch) {
                let want = concentric_disk(p.x, p.y) * radius;
                assert_eq!((want.x.to_bits(), want.y.to_bits()), (q.x.to_bits(), q.y.to_bits()), "{p} r {radius}");
            }
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
    fn samples_are_sobol_burleys_scrambled_points_in_gray_code_order() {
        let s = Sampler::new(9, 2, Some(1.0));
        for seed in [0u32, 1, 0xdead_beef, 77] {
            let mut it = s.points_of(seed, 0);
            for i in 0..5000u32 {
                let gray = i ^ (i >> 1);
                let want = owen_scramble_int4_rev(sobol_int4_rev(gray.reverse_bits(), 0), scramble_of(seed))
                    .reverse_bits()
                    .to_f32_norm();
                assert_eq!(it.next_raw(), want, "{seed} {i}");
            }
            // Starting anywhere gives the same samples.
            for start in [1u32, 2, 3, 64, 1000, 65_535] {
                let mut a = s.points_of(seed, start);
                let mut b = s.points_of(seed, 0);
                for _ in 0..start {
                    b.next_raw();
                }
                assert_eq!(a.next_raw(), b.next_raw(), "{seed} {start}");
            }
        }
    }

    #[test]
    fn sobol_burleys_scramble_is_reproduced() {
        // With the index shuffle of `sample_4d` undone, our scramble is the crate's own.
        for seed in [3u32, 1234] {
            let a = sobol_burley::sample_4d(0, 0, seed);
            let shuffled = sobol_burley::parts::owen_scramble_rev(0, sobol_burley::parts::hash(seed ^ 0x79c6_8e4a));
            let b = owen_scramble_int4_rev(sobol_int4_rev(shuffled, 0), scramble_of(seed)).reverse_bits().to_f32_norm();
            assert_eq!(a, b);
        }
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

    #[test]
    fn independent_points_are_uniform_reproducible_and_unstratified() {
        let s = Sampler::independent(3, 0, Some(1.0));
        assert!(s.is_independent() && !Sampler::new(3, 0, Some(1.0)).is_independent());
        let scramble = s.scramble(5, 1);
        // Sample i does not depend on where the sequence starts.
        assert_eq!(s.point(scramble, 37), s.points_of(scramble, 30).nth_point(7));
        let n = 1u32 << 14;
        let raw: Vec<[f32; 4]> = {
            let mut p = s.points_of(scramble, 0);
            (0..n).map(|_| p.next_raw()).collect()
        };
        for d in 0..4 {
            let mean = raw.iter().map(|x| f64::from(x[d])).sum::<f64>() / f64::from(n);
            // Uniform on [0, 1): mean 1/2, standard error sqrt(1/12/n) = 0.0023.
            assert!((mean - 0.5).abs() < 0.01, "dimension {d}: mean {mean}");
            assert!(raw.iter().all(|x| (0.0..1.0).contains(&x[d])));
        }
        // Not a net: the first 16 points leave some cell of the 4 x 4 grid empty (Sobol's fill
        // every cell; independent points do with probability 16!/16^16, about 1e-6).
        let mut cells = [0u8; 16];
        for x in &raw[..16] {
            cells[(x[1] * 4.0) as usize * 4 + (x[0] * 4.0) as usize] += 1;
        }
        assert!(cells.contains(&0));
        // Other replicates get other points.
        assert_ne!(s.point(s.scramble(5, 2), 0), s.point(scramble, 0));
    }
}
