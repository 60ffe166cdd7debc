//! The display images as the simulation reads them (paper Sec. 2.3: every eye ray that lands on
//! the LCD reads each method's display image at the pixel it meets).
//!
//! [`DisplayStack`] interleaves the display images pixel by pixel, so one LCD lookup reads every
//! method's value from one place. It is held in one of two layouts with the same values, bit for
//! bit:
//! - **dense**: `3 * count` `f32` per LCD pixel ([`DisplayStack::new`]);
//! - **palette** ([`StackBuilder`]): each LCD pixel a 16-bit index into a table of the
//!   distinct pixel tuples (every method's RGB at one pixel). Display images of flat-shaded
//!   scenes, such as the paper's charts on plain backgrounds, hold few distinct tuples (143 for
//!   the paper's LC, PC and LA 5 x 5 together), so the stack then takes 2 bytes per pixel
//!   instead of 36, and the simulation's random reads hit a far smaller working set;
//! - **wide palette**: the same with 32-bit indices, for images with more than 65,536 distinct
//!   tuples but at most a quarter as many as pixels (real lenslets' images: dispersion and
//!   aberrations blend the scene's few colours into many), 4 bytes per pixel plus the table.
//!   Images with more tuples than that (textures, smooth shading) stay dense.
//!
//! [`StackBuilder`] takes the display images one at a time, each from one reused image buffer,
//! and keeps only the palette indices of those pushed so far (switching to the dense layout if
//! the tuples outgrow the palette), so the dense stack is never held for images that do not
//! need it.

use rustc_hash::FxHashMap;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::optics::Display;
use crate::raster::{RgbImage, RgbView};

/// Display images interleaved pixel by pixel (see the module documentation).
pub struct DisplayStack {
    count: usize,
    width: usize,
    height: usize,
    layout: Layout,
}

enum Layout {
    /// `values[i * 3 * count..][..3 * count]`: pixel `i`'s tuple.
    Dense(Vec<f32>),
    /// Pixel `i`'s tuple is `palette[index[i] * 3 * count..][..3 * count]`.
    Palette { index: Vec<u16>, palette: Vec<f32> },
    /// The same with 32-bit indices.
    Wide { index: Vec<u32>, palette: Vec<f32> },
}

/// Most distinct pixel tuples a palette stack holds.
const MAX_PALETTE: usize = 1 << 16;

/// Most distinct pixel tuples a wide palette holds, as a fraction of the pixels: beyond it the
/// table and the indices would save too little over the dense layout.
const WIDE_FRACTION: usize = 4;

/// A palette index: `u16` (the palette layout) or `u32` (the wide one).
trait PaletteIndex: Copy + Send + Sync + Eq + std::hash::Hash {
    fn get(self) -> usize;
    fn make(i: usize) -> Self;
}
impl PaletteIndex for u16 {
    #[inline(always)]
    fn get(self) -> usize {
        usize::from(self)
    }
    #[inline(always)]
    fn make(i: usize) -> Self {
        i as u16
    }
}
impl PaletteIndex for u32 {
    #[inline(always)]
    fn get(self) -> usize {
        self as usize
    }
    #[inline(always)]
    fn make(i: usize) -> Self {
        i as u32
    }
}

impl DisplayStack {
    /// Packs display images that must all have the LCD's resolution (dense layout).
    pub fn new(display: &Display, images: &[&RgbImage]) -> Result<Self> {
        let lcd = display.lcd;
        for (k, img) in images.iter().enumerate() {
            if img.width != lcd.columns() || img.height != lcd.rows() {
                return Err(Error::Mismatch(format!(
                    "display image {k} is {} x {} pixels but the display's LCD is {} x {}",
                    img.width,
                    img.height,
                    lcd.columns(),
                    lcd.rows()
                )));
            }
        }
        let stride = 3 * images.len();
        let mut values = crate::budget::try_vec(lcd.pixel_count() * stride, 0f32, "the display stack")?;
        if stride > 0 {
            values.par_chunks_mut(stride).enumerate().for_each(|(i, dst)| {
                for (k, img) in images.iter().enumerate() {
                    dst[3 * k..3 * k + 3].copy_from_slice(&img.pixels[i]);
                }
            });
        }
        Ok(Self { count: images.len(), width: lcd.columns(), height: lcd.rows(), layout: Layout::Dense(values) })
    }

    /// LCD pixels per row.
    pub fn width(&self) -> usize {
        self.width
    }
    /// LCD pixel rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// A copy of display image `k`, in either layout.
    pub fn image(&self, k: usize) -> RgbImage {
        assert!(k < self.count, "display stack has {} images, not {}", self.count, k + 1);
        let pixels = (0..self.width * self.height)
            .map(|i| {
                let p = &self.pixel(i)[3 * k..3 * k + 3];
                [p[0], p[1], p[2]]
            })
            .collect();
        RgbImage { width: self.width, height: self.height, pixels }
    }

    /// Number of display images.
    pub fn len(&self) -> usize {
        self.count
    }
    /// True when the stack holds no display image.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Whether the stack holds palette indices (see [`StackBuilder`]).
    pub fn is_palette(&self) -> bool {
        matches!(self.layout, Layout::Palette { .. } | Layout::Wide { .. })
    }

    /// Whether the palette's indices are 32-bit.
    pub fn is_wide(&self) -> bool {
        matches!(self.layout, Layout::Wide { .. })
    }

    /// Bytes of pixel data held.
    pub fn bytes(&self) -> usize {
        match &self.layout {
            Layout::Dense(values) => values.len() * 4,
            Layout::Palette { index, palette } => index.len() * 2 + palette.len() * 4,
            Layout::Wide { index, palette } => index.len() * 4 + palette.len() * 4,
        }
    }

    /// Whether LCD pixels `a` and `b` hold the same values in every display image, bit for bit
    /// (the same palette entry; without a palette, the same bits).
    #[inline]
    pub fn same_values(&self, a: usize, b: usize) -> bool {
        match &self.layout {
            Layout::Palette { index, .. } => index[a] == index[b],
            Layout::Wide { index, .. } => index[a] == index[b],
            Layout::Dense(_) => self.pixel(a).iter().zip(self.pixel(b)).all(|(x, y)| x.to_bits() == y.to_bits()),
        }
    }

    /// Every display image's value at LCD pixel `index` (row-major): `[image][channel]`.
    #[inline(always)]
    pub fn pixel(&self, index: usize) -> &[f32] {
        let stride = 3 * self.count;
        match &self.layout {
            Layout::Dense(values) => &values[index * stride..(index + 1) * stride],
            Layout::Palette { index: ix, palette } => {
                let j = usize::from(ix[index]);
                &palette[j * stride..(j + 1) * stride]
            }
            Layout::Wide { index: ix, palette } => {
                let j = ix[index] as usize;
                &palette[j * stride..(j + 1) * stride]
            }
        }
    }
}

/// Builds a [`DisplayStack`] one display image at a time ([`StackBuilder::push`]), in the palette
/// layout while the tuples of the images pushed so far fit it, else dense.
pub struct StackBuilder {
    count: usize,
    width: usize,
    height: usize,
    pushed: usize,
    state: Building,
}

enum Building {
    /// The tuples of the first `pushed` images: `palette[index[i] * 3 * pushed..][..3 * pushed]`.
    Palette { index: Vec<u16>, palette: Vec<f32> },
    /// The same with 32-bit indices.
    Wide { index: Vec<u32>, palette: Vec<f32> },
    /// `3 * count` floats per pixel; slots `0..pushed` filled.
    Dense(Vec<f32>),
}

impl StackBuilder {
    /// A stack of `count` display images of `display`'s LCD, none pushed yet.
    pub fn new(display: &Display, count: usize) -> Self {
        let (width, height) = (display.lcd.columns(), display.lcd.rows());
        // Before the first image every pixel holds the empty tuple, entry 0.
        let state = Building::Palette { index: vec![0; width * height], palette: Vec::new() };
        Self { count, width, height, pushed: 0, state }
    }

    /// Adds the next display image (slot `pushed`), which must have the LCD's size.
    pub fn push(&mut self, image: RgbView<'_>) -> Result<()> {
        if self.pushed == self.count || image.width != self.width || image.height != self.height || !image.is_complete()
        {
            return Err(Error::Mismatch(format!(
                "display stack of {} images of {} x {} pixels cannot take a {} x {} image as image {}",
                self.count,
                self.width,
                self.height,
                image.width,
                image.height,
                self.pushed + 1
            )));
        }
        let (k, stride) = (self.pushed, 3 * self.count);
        let wide_max = (self.width * self.height / WIDE_FRACTION).max(MAX_PALETTE);
        match &mut self.state {
            Building::Palette { index, palette } => match extend_palette(index, palette, k, image, MAX_PALETTE) {
                Some((new_index, new_palette)) => (*index, *palette) = (new_index, new_palette),
                None => {
                    // Too many tuples for 16 bits: try 32, else dense.
                    let wide: Vec<u32> = index.par_iter().map(|&j| u32::from(j)).collect();
                    self.state = match extend_palette(&wide, palette, k, image, wide_max) {
                        Some((index, palette)) => Building::Wide { index, palette },
                        None => Building::Dense(dense(&wide, palette, k, stride, image)?),
                    };
                }
            },
            Building::Wide { index, palette } => match extend_palette(index, palette, k, image, wide_max) {
                Some((new_index, new_palette)) => (*index, *palette) = (new_index, new_palette),
                None => self.state = Building::Dense(dense(index, palette, k, stride, image)?),
            },
            Building::Dense(values) => {
                values.par_chunks_mut(stride).enumerate().for_each(|(i, dst)| {
                    dst[3 * k..3 * k + 3].copy_from_slice(&image.pixel(i));
                });
            }
        }
        self.pushed += 1;
        Ok(())
    }

    /// The stack, once every image is pushed.
    pub fn finish(self) -> Result<DisplayStack> {
        if self.pushed != self.count {
            return Err(Error::Mismatch(format!(
                "display stack of {} images finished after {}",
                self.count, self.pushed
            )));
        }
        let layout = match self.state {
            Building::Palette { index, palette } => Layout::Palette { index, palette },
            Building::Wide { index, palette } => Layout::Wide { index, palette },
            Building::Dense(values) => Layout::Dense(values),
        };
        Ok(DisplayStack { count: self.count, width: self.width, height: self.height, layout })
    }
}

/// The dense stack of the `k` images held as `index`/`palette` and image `k` (slot `k`).
fn dense<I: PaletteIndex>(
    index: &[I],
    palette: &[f32],
    k: usize,
    stride: usize,
    image: RgbView<'_>,
) -> Result<Vec<f32>> {
    let mut values = crate::budget::try_vec(index.len() * stride, 0f32, "the display stack")?;
    let old = 3 * k;
    values.par_chunks_mut(stride).zip(index.par_iter()).enumerate().for_each(|(i, (dst, &j))| {
        let j = j.get();
        dst[..old].copy_from_slice(&palette[j * old..(j + 1) * old]);
        dst[old..old + 3].copy_from_slice(&image.pixel(i));
    });
    Ok(values)
}

/// Pixels per chunk of [`extend_palette`] (a fixed size, so the work does not depend on the
/// thread count).
const CHUNK: usize = 1 << 16;

/// A pixel's key while the palette grows: its tuple so far and its RGB in image `k`, as bits.
type Key<I> = (I, [u32; 3]);

/// The palette of `k + 1`-tuples from that of the first `k` images (`index`, `palette`, tuples of
/// `3 * k` floats) and image `k`: every pixel's tuple extended by its RGB, numbered in order of
/// first appearance. `None` when there are more than `max` tuples. Chunks of pixels
/// number their own keys in parallel; merging them in chunk order gives the numbers one pass
/// over all pixels would.
fn extend_palette<I: PaletteIndex>(
    index: &[I],
    palette: &[f32],
    k: usize,
    image: RgbView<'_>,
    max: usize,
) -> Option<(Vec<I>, Vec<f32>)> {
    let old = 3 * k;
    let parts: Vec<(Vec<u16>, Vec<Key<I>>)> = index
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, ids)| local_keys(ids, |i| image.pixel(c * CHUNK + i).map(f32::to_bits)))
        .collect::<Option<_>>()?;
    let mut table: FxHashMap<Key<I>, I> = FxHashMap::default();
    let mut next = Vec::new();
    let mut maps = Vec::with_capacity(parts.len());
    for (_, keys) in &parts {
        let mut map = Vec::with_capacity(keys.len());
        for key in keys {
            let id = table.len();
            let id = *table.entry(*key).or_insert_with(|| {
                let j = key.0.get();
                next.extend_from_slice(&palette[j * old..(j + 1) * old]);
                next.extend(key.1.map(f32::from_bits));
                I::make(id)
            });
            if table.len() > max {
                return None;
            }
            map.push(id);
        }
        maps.push(map);
    }
    let mut out = vec![I::make(0); index.len()];
    out.par_chunks_mut(CHUNK).zip(parts.par_iter().zip(&maps)).for_each(|(dst, ((local, _), map))| {
        for (d, &l) in dst.iter_mut().zip(local) {
            *d = map[usize::from(l)];
        }
    });
    Some((out, next))
}

/// One chunk of [`extend_palette`]: each pixel's local number and the distinct keys in order of
/// first appearance (`rgb(i)`: the bits of the chunk's pixel `i`).
fn local_keys<I: PaletteIndex>(ids: &[I], rgb: impl Fn(usize) -> [u32; 3]) -> Option<(Vec<u16>, Vec<Key<I>>)> {
    let mut table: FxHashMap<Key<I>, u16> = FxHashMap::default();
    let mut keys = Vec::new();
    let mut local = Vec::with_capacity(ids.len());
    let mut last: Option<(Key<I>, u16)> = None;
    for (i, &j) in ids.iter().enumerate() {
        let key = (j, rgb(i));
        // Neighbouring pixels often hold the same tuple: compare with the last one first.
        if let Some((prev, id)) = last {
            if prev == key {
                local.push(id);
                continue;
            }
        }
        let id = match table.get(&key) {
            Some(&id) => id,
            None => {
                if table.len() == MAX_PALETTE {
                    return None;
                }
                let id = table.len() as u16;
                table.insert(key, id);
                keys.push(key);
                id
            }
        };
        local.push(id);
        last = Some((key, id));
    }
    Some((local, keys))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::display::Lcd;
    use glam::DVec2;

    fn display(nx: usize, ny: usize) -> Display {
        let mut d = Display::paper();
        d.lcd = Lcd { size: DVec2::new(nx as f64 * 0.01, ny as f64 * 0.01), resolution: [nx, ny] };
        d
    }

    fn image(nx: usize, ny: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> RgbImage {
        let mut img = RgbImage::new(nx, ny);
        for r in 0..ny {
            for c in 0..nx {
                img.pixels[r * nx + c] = f(r, c);
            }
        }
        img
    }

    /// `images` pushed one by one into a [`StackBuilder`].
    fn built(d: &Display, images: &[&RgbImage]) -> DisplayStack {
        let mut b = StackBuilder::new(d, images.len());
        for img in images {
            b.push(RgbView::from(*img)).unwrap();
        }
        b.finish().unwrap()
    }

    #[test]
    fn the_palette_layout_holds_the_same_values_bit_for_bit() {
        let (nx, ny) = (203, 151);
        let d = display(nx, ny);
        // Few distinct values, including -0.0 next to 0.0 and a NaN, which must stay distinct.
        let a = image(nx, ny, |r, c| [((r / 3 + c / 5) % 4) as f32 * 0.25, if c % 7 == 0 { -0.0 } else { 0.0 }, 1.0]);
        let b = image(nx, ny, |r, c| [0.2, 0.7, if (r * c) % 11 == 0 { f32::NAN } else { 0.8 }]);
        let c3 = image(nx, ny, |r, c| [(r % 5) as f32 / 25.0, (c % 3) as f32 / 7.0, 0.5]);
        let dense = DisplayStack::new(&d, &[&a, &b, &c3]).unwrap();
        let want: Vec<Vec<u32>> = (0..nx * ny).map(|i| dense.pixel(i).iter().map(|v| v.to_bits()).collect()).collect();
        let packed = built(&d, &[&a, &b, &c3]);
        assert!(packed.is_palette() && packed.bytes() < dense.bytes() / 4);
        for (i, w) in want.iter().enumerate() {
            let got: Vec<u32> = packed.pixel(i).iter().map(|v| v.to_bits()).collect();
            assert_eq!(&got, w, "pixel {i}");
        }
        for (k, img) in [&a, &b, &c3].iter().enumerate() {
            let back = packed.image(k);
            assert!(back.pixels.iter().zip(&img.pixels).all(|(p, q)| (0..3).all(|c| p[c].to_bits() == q[c].to_bits())));
        }
    }

    #[test]
    fn a_stack_built_image_by_image_reads_as_the_packed_one() {
        let (nx, ny) = (300, 250);
        let d = display(nx, ny);
        let a = image(nx, ny, |r, c| [((r / 3 + c / 5) % 4) as f32 * 0.25, if c % 7 == 0 { -0.0 } else { 0.0 }, 1.0]);
        let b = image(nx, ny, |r, c| [0.2, 0.7, if (r * c) % 11 == 0 { f32::NAN } else { 0.8 }]);
        let few = image(nx, ny, |r, c| [(r % 5) as f32 / 25.0, (c % 3) as f32 / 7.0, 0.5]);
        // 75,000 distinct values: more tuples than the palette holds.
        let many = image(nx, ny, |r, c| [(r * nx + c) as f32, 0.5, 0.25]);
        let cases: [(Vec<&RgbImage>, bool); 4] =
            [(vec![&a, &b, &few], true), (vec![&a, &b], true), (vec![&a, &b, &many], false), (vec![&many, &a], false)];
        for (imgs, palette) in cases {
            let dense = DisplayStack::new(&d, &imgs).unwrap();
            let mut builder = StackBuilder::new(&d, imgs.len());
            for img in &imgs {
                builder.push(RgbView::from(*img)).unwrap();
            }
            assert!(builder.push(RgbView::from(&a)).is_err(), "one image too many");
            let built = builder.finish().unwrap();
            assert_eq!(built.is_palette(), palette, "{} images", imgs.len());
            for i in 0..nx * ny {
                let (x, y) = (dense.pixel(i), built.pixel(i));
                assert!(x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()), "pixel {i}: {x:?} vs {y:?}");
            }
        }
        assert!(StackBuilder::new(&d, 2).finish().is_err());
        let wrong = image(nx - 1, ny, |_, _| [0.0; 3]);
        assert!(StackBuilder::new(&d, 1).push(RgbView::from(&wrong)).is_err());
    }

    #[test]
    fn too_many_distinct_tuples_stay_dense() {
        let (nx, ny) = (300, 250);
        let d = display(nx, ny);
        // 75,000 distinct values: more than a 16-bit index can tell apart.
        let a = image(nx, ny, |r, c| [(r * nx + c) as f32, 0.0, 0.0]);
        let stack = built(&d, &[&a]);
        assert!(!stack.is_palette());
        assert_eq!(stack.pixel(74_999)[0], 74_999.0);
        // Exactly 65,536 distinct tuples still fit.
        let b = image(nx, ny, |r, c| [((r * nx + c) % MAX_PALETTE) as f32, 1.0, 2.0]);
        let stack = built(&d, &[&b]);
        assert!(stack.is_palette());
        assert_eq!(stack.pixel(MAX_PALETTE + 5), &[5.0, 1.0, 2.0]);
    }
}
