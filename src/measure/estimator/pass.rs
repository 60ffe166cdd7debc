//! One pass of [`super::Replicates::extend`] (paper Sec. 4.1, the converged measurement): samples
//! `N..total` of every replicate's sequences for every retina pixel, through a paired source.
//! Bands of TILE rows run in parallel; inside, TILE x TILE tiles with every replicate and sample:
//! the rays of one tile meet the LCD in a few small patches (one per lenslet the pupil covers),
//! which then stay in cache. Each pixel sums its samples in index order, so the result does not
//! depend on the thread count, the tiling or where the batches are cut.

use glam::DVec2;

use super::{EyeSample, PairedSource};
use crate::measure::sampler::{self, Sampler};
use crate::optics::Retina;
use crate::progress::Progress;

/// Adds every sample's `K` images (`vals[i * K..][..K]`) into the sums of its owner pixel
/// (`sums[o * 3K..][..3K]`), in sample order. A pixel's samples come in runs, so each run is
/// summed in registers, starting from the pixel's stored sums (the same additions in the same
/// order as adding into memory sample by sample, without a store-to-load round trip per sample).
#[inline(always)]
pub(super) fn accumulate<const K: usize>(vals: &[[f64; 3]], owners: &[u32], sums: &mut [f64]) {
    let mut i = 0;
    while i < owners.len() {
        let o = owners[i] as usize;
        let dst: &mut [f64] = &mut sums[o * K * 3..(o + 1) * K * 3];
        let mut acc: [[f64; 3]; K] = std::array::from_fn(|j| [dst[3 * j], dst[3 * j + 1], dst[3 * j + 2]]);
        while i < owners.len() && owners[i] as usize == o {
            let v = &vals[i * K..(i + 1) * K];
            for j in 0..K {
                acc[j][0] += v[j][0];
                acc[j][1] += v[j][1];
                acc[j][2] += v[j][2];
            }
            i += 1;
        }
        for j in 0..K {
            dst[3 * j..3 * j + 3].copy_from_slice(&acc[j]);
        }
    }
}

/// Slow, obviously correct twin of [`accumulate`] for any number of images `k`: each sample
/// added into its owner's sums in memory, one after the other.
pub(super) fn accumulate_each(vals: &[[f64; 3]], k: usize, owners: &[u32], sums: &mut [f64]) {
    for (v, &o) in vals.chunks_exact(k).zip(owners) {
        let dst = &mut sums[o as usize * k * 3..(o as usize + 1) * k * 3];
        for (d, rgb) in dst.chunks_exact_mut(3).zip(v) {
            d[0] += rgb[0];
            d[1] += rgb[1];
            d[2] += rgb[2];
        }
    }
}

/// Samples handed to a source at once (per worker).
pub(super) const BATCH: usize = 2048;
/// Side of the square tiles of retina pixels traced together.
pub(super) const TILE: usize = 16;

/// What every band of a pass shares.
pub(super) struct Pass<'a, S: PairedSource + ?Sized> {
    source: &'a S,
    sampler: &'a Sampler,
    retina: &'a Retina,
    /// Replicates and images.
    nr: usize,
    k: usize,
    /// Samples per pixel before and after the pass.
    old: u32,
    total: u32,
    /// The retina's tangent step per pixel.
    step: f64,
    /// Samples handed to the source at once.
    batch: usize,
}

/// A band's buffers.
struct Worker {
    samples: Vec<EyeSample>,
    owners: Vec<u32>,
    values: Vec<[f64; 3]>,
    sums: Vec<f64>,
    pupils: Vec<DVec2>,
    /// Image 0 of each sample, when known for its whole pixel (`reference_over`).
    known: Vec<Option<[f64; 3]>>,
    pixel_known: Vec<Option<[f64; 3]>>,
    /// The other images' handle, when known for the whole pixel too (`images_over`).
    images: Vec<u32>,
    pixel_images: Vec<u32>,
    /// Samples in the buffers.
    filled: usize,
}

impl<'a, S: PairedSource + ?Sized> Pass<'a, S> {
    /// The pass from `old` to `total` samples per pixel of `(replicates, images)`.
    pub(super) fn new(
        source: &'a S,
        sampler: &'a Sampler,
        retina: &'a Retina,
        (nr, k): (usize, usize),
        (old, total): (u32, u32),
    ) -> Self {
        let fresh = (total - old) as usize;
        let step = 2.0 * retina.half_tangent / retina.resolution as f64;
        let batch = BATCH.min(TILE * TILE * fresh);
        Self { source, sampler, retina, nr, k, old, total, step, batch }
    }

    /// Band `band` (TILE rows) of every plane (`planes`: `[replicate][image][channel]`).
    pub(super) fn band(&self, band: usize, planes: &mut [&mut [f32]], progress: &Progress) {
        let n = self.retina.resolution;
        let row0 = band * TILE;
        let rows = planes[0].len() / n;
        let (batch, k) = (self.batch, self.k);
        let mut w = Worker {
            samples: vec![EyeSample::default(); batch],
            owners: vec![0u32; batch],
            values: vec![[0.0f64; 3]; batch * k],
            sums: vec![0.0f64; TILE * TILE * k * 3],
            pupils: vec![DVec2::ZERO; batch],
            known: vec![None; batch],
            pixel_known: vec![None; TILE * TILE],
            images: vec![u32::MAX; batch],
            pixel_images: vec![u32::MAX; TILE * TILE],
            filled: 0,
        };
        for col0 in (0..n).step_by(TILE) {
            if progress.cancelled() {
                return;
            }
            let tile = (row0, rows, col0, TILE.min(n - col0));
            self.tile_hints(tile, &mut w);
            for r in 0..self.nr {
                w.sums.iter_mut().for_each(|s| *s = 0.0);
                self.trace_tile(tile, r, &mut w);
                self.write_tile(tile, &w.sums, &mut planes[r * k * 3..(r + 1) * k * 3]);
            }
        }
        progress.inc(rows as u64);
    }

    /// What the source knows of each pixel of the tile `(row0, rows, col0, cols)`.
    fn tile_hints(&self, (row0, rows, col0, cols): (usize, usize, usize, usize), w: &mut Worker) {
        let radius = self.sampler.pupil_radius();
        for dr in 0..rows {
            for dc in 0..cols {
                // The pixel's square of tangents.
                let (row, col) = (row0 + dr, col0 + dc);
                let square = (self.retina.tangent(row, col, DVec2::ZERO), self.retina.tangent(row, col, DVec2::ONE));
                let k = self.source.reference_over(square, radius);
                w.pixel_known[dr * TILE + dc] = k;
                w.pixel_images[dr * TILE + dc] =
                    if k.is_some() { self.source.images_over(square, radius).unwrap_or(u32::MAX) } else { u32::MAX };
            }
        }
    }

    /// Every sample of replicate `r` for the tile's pixels into `w.sums`: (pixel, sample) pairs
    /// in pixel order, cut into batches anywhere.
    fn trace_tile(&self, (row0, rows, col0, cols): (usize, usize, usize, usize), r: usize, w: &mut Worker) {
        let n = self.retina.resolution;
        let (spectral, diffraction) = (self.source.spectral(), self.source.diffraction());
        let half = self.retina.half_tangent;
        w.filled = 0;
        for dr in 0..rows {
            let row = row0 + dr;
            for dc in 0..cols {
                let c = col0 + dc;
                let owner = (dr * TILE + dc) as u32;
                let mut points = self.sampler.points((row * n + c) as u64, r as u32, self.old);
                let later = diffraction.then(|| points.later_dims());
                for _ in self.old..self.total {
                    let (frac, raw) = points.next_point_raw();
                    // Retina::tangent, with the step hoisted.
                    let tangent =
                        DVec2::new(-half + (c as f64 + frac.x) * self.step, half - (row as f64 + frac.y) * self.step);
                    let (spectral, diffraction) = if let Some(later) = &later {
                        let (u, d) = points.spectral_and_diffraction_with(later);
                        (if spectral { u } else { 0.0 }, d)
                    } else {
                        (if spectral { points.spectral_of_last() } else { 0.0 }, [0.0; 4])
                    };
                    let i = w.filled;
                    w.samples[i] = EyeSample { tangent, pupil: DVec2::ZERO, spectral, diffraction };
                    w.pupils[i] = raw.unwrap_or(DVec2::ZERO);
                    w.owners[i] = owner;
                    w.known[i] = w.pixel_known[owner as usize];
                    w.images[i] = w.pixel_images[owner as usize];
                    w.filled += 1;
                    if w.filled == self.batch {
                        self.flush(w);
                    }
                }
            }
        }
        if w.filled > 0 {
            self.flush(w);
        }
    }

    /// The buffered samples' pupil points, their values through the source, added to their
    /// pixels' sums.
    fn flush(&self, w: &mut Worker) {
        let (m, k) = (w.filled, self.k);
        w.filled = 0;
        let radius = self.sampler.pupil_radius();
        let (samples, pupils) = (&mut w.samples[..m], &mut w.pupils[..m]);
        if radius != 0.0 {
            sampler::concentric_disk_batch(pupils, radius);
            for (s, p) in samples.iter_mut().zip(pupils.iter()) {
                s.pupil = *p;
            }
        }
        let vals = &mut w.values[..m * k];
        self.source.eval_known_images(samples, &w.known[..m], &w.images[..m], vals);
        let (owners, sums) = (&w.owners[..m], &mut w.sums);
        match k {
            2 => accumulate::<2>(vals, owners, sums),
            3 => accumulate::<3>(vals, owners, sums),
            4 => accumulate::<4>(vals, owners, sums),
            _ => accumulate_each(vals, k, owners, sums),
        }
    }

    /// The tile's sums of one replicate into its planes (`planes`: `[image][channel]`), as the
    /// running mean over `total` samples.
    fn write_tile(&self, (_, rows, col0, cols): (usize, usize, usize, usize), sums: &[f64], planes: &mut [&mut [f32]]) {
        let n = self.retina.resolution;
        let k = self.k;
        let inv_total = 1.0 / f64::from(self.total);
        let old_weight = f64::from(self.old);
        for (j, plane) in planes.iter_mut().enumerate() {
            for dr in 0..rows {
                let dst = &mut plane[dr * n + col0..dr * n + col0 + cols];
                let src = sums[dr * TILE * k * 3 + j..].iter().step_by(k * 3);
                if self.old == 0 {
                    // The first pass writes without reading: the storage may hold anything (a
                    // recycled case), and a page written before it is read is faulted in once,
                    // not twice. (0 * 0 + s) * w == s * w.
                    for (d, &s) in dst.iter_mut().zip(src) {
                        *d = (s * inv_total) as f32;
                    }
                } else {
                    for (d, &s) in dst.iter_mut().zip(src) {
                        *d = ((f64::from(*d) * old_weight + s) * inv_total) as f32;
                    }
                }
            }
        }
    }
}
