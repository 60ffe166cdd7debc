//! The converged estimator over the chart's windows: for each patch of the study's
//! chart, the perceived retinal image of every source (paper Sec. 2.3, 4.1: the ground truth and
//! each method's display image seen through eq. (1)) over that patch's window only, as
//! per-replicate pixel means.
//!
//! The points are the measurement's own: [`Sampler`] gives each (window pixel, replicate) its
//! Owen-scrambled Sobol points over the pixel's square and the pupil disk, and one eye ray per
//! point goes to every source at once ([`PairedSource`], paired as in `assess`). Windows are not
//! centred on the axis, so this is a rectangle-of-pixels twin of
//! [`crate::measure::estimator::Replicates::extend`], with the same sums in `f64` per pixel in
//! sample order (results do not depend on the thread count). The windows of a turned chart
//! ([`Chart::turned`]) are its layout's windows turned with it: every sample's tangent is turned;
//! those of a chart off axis ([`Chart::at_field`]) are carried to the eye's tangents.
//!
//! **Channels.** A window's value per pixel is one grey, combined from the three colour channels
//! as the eye combines them for accommodation and visibility ([`Grey`]): by default the
//! luminance, each channel weighted by its display primary's share of the luminance (its spectrum
//! weighted by the CIE 1924 photopic V(lambda), [`crate::optics::spectrum`]); the plain mean of
//! R, G and B is the named alternative (`[measurement] channels = "mean"`). On an achromatic
//! chart seen without chromatic aberration the three channels are equal and both give the same
//! grey (to rounding).

use glam::DVec2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::chart::Chart;
use crate::measure::estimator::{EyeSample, PairedSource, Replicates};
use crate::measure::sampler::Sampler;
use crate::progress::Progress;

/// `[measurement] channels` of a study: how the colour channels combine into the grey whose
/// contrasts are measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Channels {
    /// The luminance: the primaries' luminance shares (the default).
    #[default]
    Luminance,
    /// The plain mean of R, G and B.
    Mean,
}

/// How the colour channels of a sample combine into one grey (module comment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Grey {
    /// `(R + G + B) / 3`.
    Mean,
    /// `w_R R + w_G G + w_B B`, the weights summing to 1.
    Weighted([f64; 3]),
}

impl Grey {
    /// The grey of `channels` for `display` (its primaries' luminance shares).
    pub fn of_display(channels: Channels, display: &crate::optics::Display) -> Self {
        match channels {
            Channels::Mean => Grey::Mean,
            Channels::Luminance => Grey::Weighted(display.luminance_weights()),
        }
    }

    /// The grey of one sample's linear RGB. A grey sample (three equal channels) is its own
    /// luminance; it is taken as the channel mean's arithmetic, so that an achromatic image gives
    /// the channel mean's numbers bit for bit (the weighted sum of equal channels differs from it
    /// by rounding, which the `f32` window values would turn into differences of 1e-10).
    #[inline(always)]
    pub fn of(&self, rgb: [f64; 3]) -> f64 {
        match self {
            Grey::Weighted(w) if rgb[0] != rgb[1] || rgb[1] != rgb[2] => w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2],
            _ => (rgb[0] + rgb[1] + rgb[2]) / 3.0,
        }
    }
}

/// Rows of a window traced as one task.
const BAND: usize = 4;
/// Samples handed to the source at once.
const BATCH: usize = 2048;

/// One window's measurement: the grey ([`Grey`]) per replicate, source and pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct WindowSamples {
    /// Window columns, retina pixels.
    pub cols: usize,
    /// Window rows.
    pub rows: usize,
    /// Independent replicates.
    pub replicates: usize,
    /// Sources (the ground truth, then each method).
    pub sources: usize,
    /// `[replicate][source][row * cols + col]`.
    pub values: Vec<f32>,
}

impl WindowSamples {
    /// The grey (mean of R, G and B) of every image of a square retina's replicates, as one
    /// window covering the whole retina.
    pub fn from_replicates(reps: &Replicates) -> Self {
        Self::from_replicates_as(reps, Grey::Mean)
    }

    /// [`WindowSamples::from_replicates`] with the channels combined into `grey`.
    pub fn from_replicates_as(reps: &Replicates, grey: Grey) -> Self {
        let n = reps.resolution();
        let (replicates, sources) = (reps.replicates(), reps.images());
        let mut values = Vec::with_capacity(replicates * sources * n * n);
        for r in 0..replicates {
            for k in 0..sources {
                let [pr, pg, pb] = [0, 1, 2].map(|c| reps.plane(r, k, c));
                values.extend(
                    pr.iter()
                        .zip(pg)
                        .zip(pb)
                        .map(|((a, b), c)| grey.of([f64::from(*a), f64::from(*b), f64::from(*c)]) as f32),
                );
            }
        }
        Self { cols: n, rows: n, replicates, sources, values }
    }

    /// Source `k`'s pixels in replicate `r`, row-major.
    pub fn plane(&self, r: usize, k: usize) -> &[f32] {
        let n = self.cols * self.rows;
        let i = r * self.sources + k;
        &self.values[i * n..(i + 1) * n]
    }

    /// Source `k`'s image averaged over the replicates for which `keep(r)`, in `f64`.
    pub fn mean_image(&self, k: usize, keep: impl Fn(usize) -> bool) -> Vec<f64> {
        let n = self.cols * self.rows;
        let mut out = vec![0.0; n];
        let mut count = 0usize;
        for r in (0..self.replicates).filter(|&r| keep(r)) {
            count += 1;
            for (o, v) in out.iter_mut().zip(self.plane(r, k)) {
                *o += f64::from(*v);
            }
        }
        let inv = 1.0 / count.max(1) as f64;
        out.iter_mut().for_each(|o| *o *= inv);
        out
    }
}

/// Measures every patch window of `chart` through `source` with `samples` samples per pixel and
/// replicate, each sample's channels averaged ([`Grey::Mean`]; [`measure_windows_as`] for
/// another grey). Pixel `p` of window `w` uses the sampler's pixel index `offset(w) + p`, so that
/// no two pixels of a case share a scramble. `progress` advances once per band of rows.
pub fn measure_windows<S: PairedSource + ?Sized>(
    source: &S,
    sampler: &Sampler,
    chart: &Chart,
    replicates: usize,
    samples: u32,
    progress: &Progress,
) -> Vec<WindowSamples> {
    measure_windows_as(source, sampler, chart, (replicates, samples), Grey::Mean, progress)
}

/// [`measure_windows`] with each sample's channels combined into `grey`; `(replicates,
/// samples)` per pixel.
pub fn measure_windows_as<S: PairedSource + ?Sized>(
    source: &S,
    sampler: &Sampler,
    chart: &Chart,
    (replicates, samples): (usize, u32),
    grey: Grey,
    progress: &Progress,
) -> Vec<WindowSamples> {
    let (offsets, tasks) = band_tasks(chart);
    let measure = BandMeasure { source, sampler, chart, replicates, samples, grey, progress };
    let bands: Vec<Vec<f32>> = tasks.par_iter().map(|&(w, row0)| measure.band(w, row0, offsets[w])).collect();
    assemble_windows(chart, replicates, source.images(), &tasks, &bands)
}

/// The sampler's pixel index of each window's first pixel (the windows' pixels counted in
/// order), and the tasks: (window, first row) of every band of [`BAND`] rows.
fn band_tasks(chart: &Chart) -> (Vec<u64>, Vec<(usize, usize)>) {
    let mut offsets = Vec::with_capacity(chart.patches.len());
    let mut tasks = Vec::new();
    let mut offset = 0u64;
    for (w, p) in chart.patches.iter().enumerate() {
        offsets.push(offset);
        offset += (p.cols * p.rows) as u64;
        for row0 in (0..p.rows).step_by(BAND) {
            tasks.push((w, row0));
        }
    }
    (offsets, tasks)
}

/// What [`measure_windows_as`] measures each band of a window with.
struct BandMeasure<'a, S: ?Sized> {
    source: &'a S,
    sampler: &'a Sampler,
    chart: &'a Chart,
    replicates: usize,
    samples: u32,
    grey: Grey,
    progress: &'a Progress,
}

impl<S: PairedSource + ?Sized> BandMeasure<'_, S> {
    /// The rows `row0..row0 + BAND` of window `w` (pixel `p` of the window is the sampler's
    /// pixel `offset + p`): for each replicate and image, the band's pixels in row order, each
    /// the mean grey of its samples, evaluated in batches of [`BATCH`].
    fn band(&self, w: usize, row0: usize, offset: u64) -> Vec<f32> {
        let (source, chart, grey, progress) = (self.source, self.chart, self.grey, self.progress);
        let (replicates, samples) = (self.replicates, self.samples);
        let k = source.images();
        let step = chart.pixel_tangent();
        let turned = chart.orientation_deg != 0.0;
        let off_axis = !chart.field.is_ahead();
        let deg = std::f64::consts::PI / 180.0;
        let p = &chart.patches[w];
        let rows = BAND.min(p.rows - row0);
        let n = rows * p.cols;
        // Top-left corner of the window, tangent.
        let corner = DVec2::new(
            p.center_deg.x * deg - 0.5 * p.cols as f64 * step,
            p.center_deg.y * deg + 0.5 * p.rows as f64 * step,
        );
        let mut out = vec![0f32; replicates * k * n];
        let mut batch = Vec::with_capacity(BATCH);
        let mut owners = Vec::with_capacity(BATCH);
        let mut values = vec![[0.0f64; 3]; BATCH * k];
        let mut sums = vec![0.0f64; n * k];
        let spectral = source.spectral();
        let diffraction = source.diffraction();
        let flush = |batch: &mut Vec<EyeSample>, owners: &mut Vec<u32>, sums: &mut [f64], values: &mut [[f64; 3]]| {
            let vals = &mut values[..batch.len() * k];
            source.eval(batch, vals);
            for (v, &o) in vals.chunks_exact(k).zip(owners.iter()) {
                for (j, rgb) in v.iter().enumerate() {
                    sums[o as usize * k + j] += grey.of(*rgb);
                }
            }
            batch.clear();
            owners.clear();
        };
        for r in 0..replicates {
            sums.iter_mut().for_each(|s| *s = 0.0);
            for dr in 0..rows {
                // A cancelled run (`crate::progress`) skips the rest; the caller discards it.
                if progress.cancelled() {
                    break;
                }
                let row = row0 + dr;
                for c in 0..p.cols {
                    let pixel = offset + (row * p.cols + c) as u64;
                    let mut points = self.sampler.points(pixel, r as u32, 0);
                    for _ in 0..samples {
                        let (frac, pupil) = points.next_point();
                        let tangent =
                            DVec2::new(corner.x + (c as f64 + frac.x) * step, corner.y - (row as f64 + frac.y) * step);
                        let tangent = if turned { chart.turn(tangent) } else { tangent };
                        let tangent = if off_axis { chart.eye_tangent(tangent) } else { tangent };
                        let spectral = if spectral { points.spectral_of_last() } else { 0.0 };
                        let diffraction = if diffraction { points.diffraction_of_last() } else { [0.0; 4] };
                        batch.push(EyeSample { tangent, pupil, spectral, diffraction });
                        owners.push((dr * p.cols + c) as u32);
                        if batch.len() == BATCH {
                            flush(&mut batch, &mut owners, &mut sums, &mut values);
                        }
                    }
                }
            }
            if !batch.is_empty() {
                flush(&mut batch, &mut owners, &mut sums, &mut values);
            }
            let inv = 1.0 / f64::from(samples);
            for j in 0..k {
                let dst = &mut out[(r * k + j) * n..(r * k + j + 1) * n];
                for (i, d) in dst.iter_mut().enumerate() {
                    *d = (sums[i * k + j] * inv) as f32;
                }
            }
        }
        progress.inc(1);
        out
    }
}

/// The bands of `tasks` (of [`BandMeasure::band`], `k` images) assembled into the chart's windows.
fn assemble_windows(
    chart: &Chart,
    replicates: usize,
    k: usize,
    tasks: &[(usize, usize)],
    bands: &[Vec<f32>],
) -> Vec<WindowSamples> {
    let mut windows: Vec<WindowSamples> = chart
        .patches
        .iter()
        .map(|p| WindowSamples {
            cols: p.cols,
            rows: p.rows,
            replicates,
            sources: k,
            values: vec![0.0; replicates * k * p.cols * p.rows],
        })
        .collect();
    for (&(w, row0), band) in tasks.iter().zip(bands) {
        let win = &mut windows[w];
        let rows = BAND.min(win.rows - row0);
        let n = rows * win.cols;
        let plane = win.cols * win.rows;
        for rk in 0..replicates * k {
            let dst = &mut win.values[rk * plane + row0 * win.cols..rk * plane + row0 * win.cols + n];
            dst.copy_from_slice(&band[rk * n..(rk + 1) * n]);
        }
    }
    windows
}

/// Progress steps [`measure_windows`] takes for `chart`.
pub fn progress_steps(chart: &Chart) -> u64 {
    chart.patches.iter().map(|p| p.rows.div_ceil(BAND) as u64).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resolution::chart::Pattern;

    /// A source whose images are known functions of the ray: image 0 the tangent's x (deg),
    /// image 1 its y.
    struct Coordinates;
    impl PairedSource for Coordinates {
        fn images(&self) -> usize {
            2
        }
        fn eval(&self, samples: &[EyeSample], out: &mut [[f64; 3]]) {
            for (s, o) in samples.iter().zip(out.chunks_exact_mut(2)) {
                let d = s.tangent * (180.0 / std::f64::consts::PI);
                o[0] = [d.x; 3];
                o[1] = [d.y; 3];
            }
        }
    }

    #[test]
    fn windows_see_their_own_directions_pixel_by_pixel() {
        let items = [
            (Pattern::Grating { frequency_cpd: 1.0 }, DVec2::new(1.0, 0.25)),
            (Pattern::Edge { angle_deg: 5.0 }, DVec2::new(0.5, 0.5)),
        ];
        let chart = Chart::layout(&items, 0.5, 16.0, 0.5, 0.5);
        let sampler = Sampler::new(3, 0, Some(2.5));
        let w = measure_windows(&Coordinates, &sampler, &chart, 3, 64, &Progress::hidden());
        for (win, p) in w.iter().zip(&chart.patches) {
            assert_eq!((win.cols, win.rows), (p.cols, p.rows));
            for r in 0..3 {
                for row in 0..p.rows {
                    for c in 0..p.cols {
                        // The mean of x over a pixel is its centre: 64 points stratified in each dimension
                        // put the mean within half a stratum (1/128 pixel) of it.
                        let x = p.center_deg.x + (c as f64 + 0.5 - 0.5 * p.cols as f64) / 16.0;
                        let y = p.center_deg.y - (row as f64 + 0.5 - 0.5 * p.rows as f64) / 16.0;
                        let i = row * p.cols + c;
                        assert!((f64::from(win.plane(r, 0)[i]) - x).abs() < 1.0 / 128.0 / 16.0, "x {r} {row} {c}");
                        assert!((f64::from(win.plane(r, 1)[i]) - y).abs() < 1.0 / 128.0 / 16.0, "y {r} {row} {c}");
                    }
                }
            }
        }
        // The same in any thread count: a single-thread pool gives the same bits.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let again = pool.install(|| measure_windows(&Coordinates, &sampler, &chart, 3, 64, &Progress::hidden()));
        assert_eq!(again, w);
    }
}
