//! The display images as the simulation reads them (paper Sec. 2.3: every eye ray that lands on
//! the LCD reads each method's display image at the pixel it meets).
//!
//! [`DisplayStack`] interleaves the display images pixel by pixel, so one LCD lookup reads every
//! method's value from one place. It is held in one of two layouts with the same values, bit for
//! bit:
//! - **dense**: `3 * count` `f32` per LCD pixel (what rendering writes into);
//! - **palette** ([`DisplayStack::compact`]): each LCD pixel a 16-bit index into a table of the
//!   distinct pixel tuples (every method's RGB at one pixel). Display images of flat-shaded
//!   scenes, such as the paper's charts on plain backgrounds, hold few distinct tuples (a few
//!   thousand for LC, PC and LA 5 x 5 together), so the stack then takes 2 bytes per pixel
//!   instead of 36, and the simulation's random reads hit a far smaller working set. Images
//!   with more than 65,536 distinct tuples (textures, smooth shading) stay dense.

use std::collections::HashMap;

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
}

/// Most distinct pixel tuples a palette stack holds.
const MAX_PALETTE: usize = 1 << 16;

impl DisplayStack {
    /// Packs display images that must all have the LCD's resolution (dense layout).
    pub fn new(display: &Display, images: &[&RgbImage]) -> Result<Self> {
        let lcd = display.lcd;
        for (k, img) in images.iter().enumerate() {
            if img.width != lcd.columns() || img.height != lcd.rows() {
                return Err(Error::Unsupported(format!(
                    "display image {k} is {} x {} pixels but the display's LCD is {} x {}",
                    img.width,
                    img.height,
                    lcd.columns(),
                    lcd.rows()
                )));
            }
        }
        let stride = 3 * images.len();
        let mut values = vec![0f32; lcd.pixel_count() * stride];
        if stride > 0 {
            values.par_chunks_mut(stride).enumerate().for_each(|(i, dst)| {
                for (k, img) in images.iter().enumerate() {
                    dst[3 * k..3 * k + 3].copy_from_slice(&img.pixels[i]);
                }
            });
        }
        Ok(Self { count: images.len(), width: lcd.columns(), height: lcd.rows(), layout: Layout::Dense(values) })
    }

    /// `count` black display images of the LCD's size (dense layout), to be rendered in place
    /// by [`crate::render::render_display_image_into_stack`].
    pub fn black(display: &Display, count: usize) -> Self {
        let lcd = display.lcd;
        let values = vec![0f32; lcd.pixel_count() * 3 * count];
        Self { count, width: lcd.columns(), height: lcd.rows(), layout: Layout::Dense(values) }
    }

    /// LCD pixels per row.
    pub fn width(&self) -> usize {
        self.width
    }
    /// LCD pixel rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The dense values to render display image `slot` into: pixel `i`'s RGB goes to
    /// `[i * stride + 3 * slot..][..3]`, `stride = 3 * len()`. `None` for a palette stack.
    pub(super) fn dense_mut(&mut self) -> Option<&mut [f32]> {
        match &mut self.layout {
            Layout::Dense(values) => Some(values),
            Layout::Palette { .. } => None,
        }
    }

    /// Display image `k`, read in place (`None` once the stack is a palette stack: see
    /// [`DisplayStack::image`]).
    pub fn view(&self, k: usize) -> Option<RgbView<'_>> {
        assert!(k < self.count, "display stack has {} images, not {}", self.count, k + 1);
        match &self.layout {
            Layout::Dense(values) => Some(
                RgbView::strided(self.width, self.height, values, 3 * self.count, 3 * k)
                    .expect("a stack holds every pixel of each of its images"),
            ),
            Layout::Palette { .. } => None,
        }
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
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Whether the stack holds palette indices ([`DisplayStack::compact`]).
    pub fn is_palette(&self) -> bool {
        matches!(self.layout, Layout::Palette { .. })
    }

    /// Bytes of pixel data held.
    pub fn bytes(&self) -> usize {
        match &self.layout {
            Layout::Dense(values) => values.len() * 4,
            Layout::Palette { index, palette } => index.len() * 2 + palette.len() * 4,
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
        }
    }

    /// The same stack in the palette layout when its images hold at most 65,536 distinct pixel
    /// tuples (compared bit for bit), else unchanged. The dense values are freed.
    pub fn compact(self) -> Self {
        let Layout::Dense(values) = &self.layout else { return self };
        let stride = 3 * self.count;
        if stride == 0 {
            return self;
        }
        let Some((index, palette)) = palette_of(values, stride) else { return self };
        Self { layout: Layout::Palette { index, palette }, ..self }
    }
}

/// Pixel tuples of `values` (`stride` floats each) as indices into a table of the distinct
/// ones, in order of first appearance; `None` when there are more than [`MAX_PALETTE`].
fn palette_of(values: &[f32], stride: usize) -> Option<(Vec<u16>, Vec<f32>)> {
    let pixels = values.len() / stride;
    let mut table: HashMap<Box<[u32]>, u16> = HashMap::new();
    let mut palette = Vec::new();
    let mut index = Vec::with_capacity(pixels);
    let mut key: Vec<u32> = Vec::with_capacity(stride);
    let mut last: Option<(&[f32], u16)> = None;
    for px in values.chunks_exact(stride) {
        // Neighbouring pixels often hold the same tuple: compare bits with the last one first.
        if let Some((prev, j)) = last {
            if prev.iter().zip(px).all(|(a, b)| a.to_bits() == b.to_bits()) {
                index.push(j);
                continue;
            }
        }
        key.clear();
        key.extend(px.iter().map(|v| v.to_bits()));
        let j = match table.get(key.as_slice()) {
            Some(&j) => j,
            None => {
                if table.len() == MAX_PALETTE {
                    return None;
                }
                let j = table.len() as u16;
                table.insert(key.as_slice().into(), j);
                palette.extend_from_slice(px);
                j
            }
        };
        index.push(j);
        last = Some((px, j));
    }
    Some((index, palette))
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
        let packed = DisplayStack::new(&d, &[&a, &b, &c3]).unwrap().compact();
        assert!(packed.is_palette() && packed.bytes() < dense.bytes() / 4);
        for (i, w) in want.iter().enumerate() {
            let got: Vec<u32> = packed.pixel(i).iter().map(|v| v.to_bits()).collect();
            assert_eq!(&got, w, "pixel {i}");
        }
        for (k, img) in [&a, &b, &c3].iter().enumerate() {
            let back = packed.image(k);
            assert!(back.pixels.iter().zip(&img.pixels).all(|(p, q)| (0..3).all(|c| p[c].to_bits() == q[c].to_bits())));
        }
        assert!(packed.view(0).is_none() && dense.view(0).is_some());
    }

    #[test]
    fn too_many_distinct_tuples_stay_dense() {
        let (nx, ny) = (300, 250);
        let d = display(nx, ny);
        // 75,000 distinct values: more than a 16-bit index can tell apart.
        let a = image(nx, ny, |r, c| [(r * nx + c) as f32, 0.0, 0.0]);
        let stack = DisplayStack::new(&d, &[&a]).unwrap().compact();
        assert!(!stack.is_palette());
        assert_eq!(stack.pixel(74_999)[0], 74_999.0);
        // Exactly 65,536 distinct tuples still fit.
        let b = image(nx, ny, |r, c| [((r * nx + c) % MAX_PALETTE) as f32, 1.0, 2.0]);
        let stack = DisplayStack::new(&d, &[&b]).unwrap().compact();
        assert!(stack.is_palette());
        assert_eq!(stack.pixel(MAX_PALETTE + 5), &[5.0, 1.0, 2.0]);
    }
}
