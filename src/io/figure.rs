//! Paper-style image grids: a PNG montage like the paper's Figure 3, with one row per eye case
//! and one column per image (ground truth, LC, PC, LA), row labels on the left and column labels
//! on top; [`write_figure`] adds a title above and a caption under each cell (`assess` puts each
//! panel's PSNR and SSIM there, and the eye case's focus in the row label).
//!
//! Layout (all sizes in pixels, see [`montage_size`] and [`cell_origin`]): a white canvas; a
//! label strip of [`ROW_LABEL_WIDTH`] on the left and [`COLUMN_LABEL_HEIGHT`] on top; cells of
//! [`CELL_SIZE`]² separated by white gaps of [`SEPARATOR`], and a [`SEPARATOR`] margin right and
//! below. With a title, a strip of [`TITLE_HEIGHT`] comes first; with captions, each row of cells
//! is followed by a caption strip of [`CAPTION_HEIGHT`] ([`Layout`]). Every source image is scaled, in linear light, to fit its cell with its aspect ratio
//! kept (centred, black bars if not square) by area averaging (an exact box filter: downscaling
//! averages the covered source pixels, integer upscaling replicates them), then sRGB-encoded
//! like [`super::png::write_preview`].
//!
//! Text is drawn with plotters' bitmap backend and its `ttf` feature, which finds the
//! `sans-serif` font through fontconfig: building needs `pkg-config`, `libfontconfig1-dev` and
//! `libfreetype-dev`; running needs a font (Debian `fonts-dejavu-core`). Without a usable font,
//! [`write_montage`] returns an error saying so rather than a figure without labels.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{Error, Result};
use crate::io::png::{to_srgb8, write_rgb8};
use crate::raster::RgbImage;

/// Side of one square cell.
pub const CELL_SIZE: usize = 256;
/// Gap between cells, and margin right and below the grid.
pub const SEPARATOR: usize = 4;
/// Width of the row-label strip on the left.
pub const ROW_LABEL_WIDTH: usize = 180;
/// Height of the column-label strip on top.
pub const COLUMN_LABEL_HEIGHT: usize = 40;
/// Height of the title strip of [`write_figure`].
pub const TITLE_HEIGHT: usize = 44;
/// Height of the caption strip under each row of cells in [`write_figure`].
pub const CAPTION_HEIGHT: usize = 24;

const FONT: &str = "sans-serif";
const COLUMN_FONT_SIZE: f64 = 24.0;
const ROW_FONT_SIZE: f64 = 20.0;
const TITLE_FONT_SIZE: f64 = 24.0;
const CAPTION_FONT_SIZE: f64 = 16.0;

/// Where things go: the strips above the cells and the height of one row of cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Title strip height (0 without a title).
    pub title: usize,
    /// Caption strip height under each row (0 without captions).
    pub caption: usize,
}

impl Layout {
    /// The montage of [`write_montage`]: no title, no captions.
    pub const PLAIN: Layout = Layout { title: 0, caption: 0 };

    fn top(&self) -> usize {
        self.title + COLUMN_LABEL_HEIGHT
    }

    fn row_pitch(&self) -> usize {
        CELL_SIZE + self.caption + SEPARATOR
    }

    /// `(width, height)` with `n_rows` rows and `n_cols` columns.
    pub fn size(&self, n_rows: usize, n_cols: usize) -> (usize, usize) {
        (ROW_LABEL_WIDTH + n_cols * (CELL_SIZE + SEPARATOR), self.top() + n_rows * self.row_pitch())
    }

    /// `(x, y)` of the top-left pixel of cell (`row`, `col`); its caption starts at
    /// `y + CELL_SIZE`.
    pub fn cell_origin(&self, row: usize, col: usize) -> (usize, usize) {
        (ROW_LABEL_WIDTH + col * (CELL_SIZE + SEPARATOR), self.top() + row * self.row_pitch())
    }
}

/// `(width, height)` of a montage with `n_rows` rows and `n_cols` columns:
/// `width = ROW_LABEL_WIDTH + n_cols * (CELL_SIZE + SEPARATOR)`,
/// `height = COLUMN_LABEL_HEIGHT + n_rows * (CELL_SIZE + SEPARATOR)`.
pub fn montage_size(n_rows: usize, n_cols: usize) -> (usize, usize) {
    Layout::PLAIN.size(n_rows, n_cols)
}

/// `(x, y)` of the top-left pixel of cell (`row`, `col`) of a montage.
pub fn cell_origin(row: usize, col: usize) -> (usize, usize) {
    Layout::PLAIN.cell_origin(row, col)
}

/// One row of a [`Figure`]: its label, and its images with their captions.
pub type FigureRow<'a> = (String, Vec<(&'a RgbImage, Option<String>)>);

/// A figure: a title, column labels, and rows of images with a label each and an optional
/// caption per image.
#[derive(Clone, Debug, Default)]
pub struct Figure<'a> {
    /// Title line above the grid, if any.
    pub title: Option<String>,
    /// One label per image column.
    pub column_labels: Vec<String>,
    /// The rows, top to bottom.
    pub rows: Vec<FigureRow<'a>>,
}

impl Figure<'_> {
    /// The layout this figure is drawn with.
    pub fn layout(&self) -> Layout {
        let captions = self.rows.iter().any(|(_, cells)| cells.iter().any(|(_, c)| c.is_some()));
        Layout {
            title: if self.title.is_some() { TITLE_HEIGHT } else { 0 },
            caption: if captions { CAPTION_HEIGHT } else { 0 },
        }
    }
}

/// Box-filter weights mapping `src` samples onto `dst` samples along one axis: for each output
/// sample, the `(source index, weight)` pairs, weights summing to 1.
fn box_weights(src: usize, dst: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|i| {
            let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
            let first = a.floor() as usize;
            let last = (b.ceil() as usize).min(src);
            (first..last)
                .filter_map(|j| {
                    let overlap = (b.min(j as f64 + 1.0) - a.max(j as f64)) / scale;
                    (overlap > 0.0).then_some((j, overlap))
                })
                .collect()
        })
        .collect()
}

/// `src` resampled to `width` × `height` by area averaging (separable box filter).
fn resample(src: &RgbImage, width: usize, height: usize) -> RgbImage {
    let wx = box_weights(src.width, width);
    let wy = box_weights(src.height, height);
    // Horizontal pass: src.height rows of `width` pixels.
    let mut tmp = vec![[0.0f64; 3]; src.height * width];
    for r in 0..src.height {
        for (c, weights) in wx.iter().enumerate() {
            let mut acc = [0.0f64; 3];
            for &(j, w) in weights {
                let p = src.get(r, j);
                for k in 0..3 {
                    acc[k] += w * p[k] as f64;
                }
            }
            tmp[r * width + c] = acc;
        }
    }
    let mut out = RgbImage::new(width, height);
    for (r, weights) in wy.iter().enumerate() {
        for c in 0..width {
            let mut acc = [0.0f64; 3];
            for &(i, w) in weights {
                for k in 0..3 {
                    acc[k] += w * tmp[i * width + c][k];
                }
            }
            out.set(r, c, [acc[0] as f32, acc[1] as f32, acc[2] as f32]);
        }
    }
    out
}

/// `img` as one cell of a figure: scaled to fit a [`CELL_SIZE`]² cell with its aspect ratio
/// kept (area averaging), centred on black. A cell image is its own cell image, so a caller may
/// shrink its images early (keeping 256² cells instead of full images) and draw the same figure.
pub fn cell_image(img: &RgbImage) -> RgbImage {
    let scale = (CELL_SIZE as f64 / img.width as f64).min(CELL_SIZE as f64 / img.height as f64);
    let w = ((img.width as f64 * scale).round() as usize).clamp(1, CELL_SIZE);
    let h = ((img.height as f64 * scale).round() as usize).clamp(1, CELL_SIZE);
    if w == img.width && h == img.height && w == CELL_SIZE && h == CELL_SIZE {
        return img.clone();
    }
    let cell = if w == img.width && h == img.height { img.clone() } else { resample(img, w, h) };
    let mut padded = RgbImage::new(CELL_SIZE, CELL_SIZE);
    let (ox, oy) = ((CELL_SIZE - w) / 2, (CELL_SIZE - h) / 2);
    for y in 0..h {
        for x in 0..w {
            padded.set(oy + y, ox + x, cell.get(y, x));
        }
    }
    padded
}

/// Splits `text` at spaces into lines no wider than `max_width` according to `measure`.
/// `measure`'s error is the font library's message.
fn wrap(
    text: &str,
    max_width: u32,
    measure: &dyn Fn(&str) -> std::result::Result<u32, String>,
) -> std::result::Result<Vec<String>, String> {
    let mut lines: Vec<String> = Vec::new();
    let mut current = String::new();
    for word in text.split_whitespace() {
        let candidate = if current.is_empty() { word.to_string() } else { format!("{current} {word}") };
        if current.is_empty() || measure(&candidate)? <= max_width {
            current = candidate;
        } else {
            lines.push(std::mem::replace(&mut current, word.to_string()));
        }
    }
    if !current.is_empty() {
        lines.push(current);
    }
    Ok(lines)
}

/// Writes a labelled grid of images as an sRGB PNG (see the module comment for the layout).
///
/// `rows` are `(row label, images)`; every row must hold `column_labels.len()` images (sizes may
/// differ). Errors: no rows or columns, a row of the wrong length, an empty or non-finite image,
/// no usable font, or a file-system failure, each naming `path`.
pub fn write_montage(path: &Path, rows: &[(&str, Vec<&RgbImage>)], column_labels: &[&str]) -> Result<()> {
    let figure = Figure {
        title: None,
        column_labels: column_labels.iter().map(|s| s.to_string()).collect(),
        rows: rows.iter().map(|(l, imgs)| (l.to_string(), imgs.iter().map(|i| (*i, None)).collect())).collect(),
    };
    write_figure(path, &figure)
}

/// Writes a [`Figure`] as an sRGB PNG: the montage of [`write_montage`] with the title and
/// captions (see the module comment for the layout). Same errors as [`write_montage`].
pub fn write_figure(path: &Path, figure: &Figure) -> Result<()> {
    let source = path.display().to_string();
    let column_labels = &figure.column_labels;
    let rows = &figure.rows;
    let n_cols = column_labels.len();
    if rows.is_empty() || n_cols == 0 {
        return Err(Error::invalid(source, "montage", "needs at least one row and one column"));
    }
    for (label, images) in rows {
        if images.len() != n_cols {
            return Err(Error::invalid(
                source,
                format!("row `{label}`"),
                format!("has {} images but there are {n_cols} column labels", images.len()),
            ));
        }
        for (c, (img, _)) in images.iter().enumerate() {
            if img.width == 0 || img.height == 0 || img.pixels.len() != img.width * img.height || !img.all_finite() {
                return Err(Error::invalid(
                    source,
                    format!("row `{label}`, column `{}`", column_labels[c]),
                    format!("image ({}x{}) is empty, inconsistent or has non-finite samples", img.width, img.height),
                ));
            }
        }
    }

    let layout = figure.layout();
    let (width, height) = layout.size(rows.len(), n_cols);
    let mut canvas = vec![255u8; width * height * 3];
    for (r, (_, images)) in rows.iter().enumerate() {
        for (c, (img, _)) in images.iter().enumerate() {
            let padded = cell_image(img);
            let bytes = to_srgb8(&padded);
            let (x0, y0) = layout.cell_origin(r, c);
            for y in 0..CELL_SIZE {
                let dst = ((y0 + y) * width + x0) * 3;
                canvas[dst..dst + CELL_SIZE * 3].copy_from_slice(&bytes[y * CELL_SIZE * 3..(y + 1) * CELL_SIZE * 3]);
            }
        }
    }

    draw_labels(&mut canvas, (width, height), figure, layout).map_err(|message| {
        Error::draw(
            source,
            "montage labels",
            format!("{message} (needs fontconfig and a sans-serif font, e.g. Debian package fonts-dejavu-core)"),
        )
    })?;
    write_rgb8(path, width, height, &canvas)
}

fn draw_labels(
    canvas: &mut [u8],
    (width, height): (usize, usize),
    figure: &Figure,
    layout: Layout,
) -> std::result::Result<(), String> {
    let (rows, column_labels) = (&figure.rows, &figure.column_labels);
    super::plot::register_font()?;
    let root = BitMapBackend::with_buffer(canvas, (width as u32, height as u32)).into_drawing_area();
    let column_style =
        TextStyle::from((FONT, COLUMN_FONT_SIZE).into_font()).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Center));
    let row_style =
        TextStyle::from((FONT, ROW_FONT_SIZE).into_font()).color(&BLACK).pos(Pos::new(HPos::Right, VPos::Center));
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();

    if let Some(title) = &figure.title {
        let style =
            TextStyle::from((FONT, TITLE_FONT_SIZE).into_font()).color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        root.draw_text(title, &style, (2 * SEPARATOR as i32, (TITLE_HEIGHT / 2) as i32)).map_err(err)?;
    }
    for (c, label) in column_labels.iter().enumerate() {
        let (x0, _) = layout.cell_origin(0, c);
        let centre = ((x0 + CELL_SIZE / 2) as i32, (layout.title + COLUMN_LABEL_HEIGHT / 2) as i32);
        root.draw_text(label, &column_style, centre).map_err(err)?;
    }
    let caption_style =
        TextStyle::from((FONT, CAPTION_FONT_SIZE).into_font()).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Center));
    for (r, (_, cells)) in rows.iter().enumerate() {
        for (c, (_, caption)) in cells.iter().enumerate() {
            if let Some(caption) = caption {
                let (x0, y0) = layout.cell_origin(r, c);
                let centre = ((x0 + CELL_SIZE / 2) as i32, (y0 + CELL_SIZE + CAPTION_HEIGHT / 2) as i32);
                root.draw_text(caption, &caption_style, centre).map_err(err)?;
            }
        }
    }
    let max_width = (ROW_LABEL_WIDTH - 3 * SEPARATOR) as u32;
    let measure = |s: &str| -> std::result::Result<u32, String> {
        root.estimate_text_size(s, &row_style).map(|(w, _)| w).map_err(|e| e.to_string())
    };
    for (r, (label, _)) in rows.iter().enumerate() {
        let lines = wrap(label, max_width, &measure)?;
        let line_height = (ROW_FONT_SIZE * 1.25) as i32;
        let (_, y0) = layout.cell_origin(r, 0);
        let centre_y = (y0 + CELL_SIZE / 2) as i32;
        let top = centre_y - line_height * (lines.len() as i32 - 1) / 2;
        let x = (ROW_LABEL_WIDTH - 2 * SEPARATOR) as i32;
        for (i, line) in lines.iter().enumerate() {
            root.draw_text(line, &row_style, (x, top + i as i32 * line_height)).map_err(err)?;
        }
    }
    root.present().map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_weights_sum_to_one_and_cover_source() {
        for (src, dst) in [(2160, 256), (512, 256), (64, 256), (7, 3), (3, 7)] {
            let w = box_weights(src, dst);
            let mut per_source = vec![0.0; src];
            for ws in &w {
                let s: f64 = ws.iter().map(|&(_, x)| x).sum();
                assert!((s - 1.0).abs() < 1e-12, "{src}->{dst}: {s}");
                for &(j, x) in ws {
                    per_source[j] += x;
                }
            }
            // Every source pixel contributes in total dst/src of one output pixel.
            for v in per_source {
                assert!((v - dst as f64 / src as f64).abs() < 1e-9, "{src}->{dst}: {v}");
            }
        }
    }

    #[test]
    fn a_cell_image_is_its_own_cell_image_and_draws_the_same_figure() {
        // `assess` keeps only cells: the figure drawn from them must be the figure drawn from
        // the full images, byte for byte.
        let mut imgs = Vec::new();
        for (w, h) in [(512, 512), (300, 200), (256, 256), (97, 131)] {
            let mut img = RgbImage::new(w, h);
            for (i, p) in img.pixels.iter_mut().enumerate() {
                *p = [((i * 7919) % 1000) as f32 / 1000.0, (i % w) as f32 / w as f32, 0.25];
            }
            imgs.push(img);
        }
        let cells: Vec<RgbImage> = imgs.iter().map(cell_image).collect();
        for (cell, img) in cells.iter().zip(&imgs) {
            assert_eq!((cell.width, cell.height), (CELL_SIZE, CELL_SIZE));
            assert!(cell_image(cell) == *cell, "{}x{}", img.width, img.height);
        }
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        let labels = ["w", "x", "y", "z"];
        match write_montage(&a, &[("row", imgs.iter().collect())], &labels) {
            // No font on this machine: the montage cannot be drawn either way.
            Err(e) if e.to_string().contains("font") => return,
            r => r.unwrap(),
        }
        write_montage(&b, &[("row", cells.iter().collect())], &labels).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    }

    #[test]
    fn resample_averages_blocks() {
        // 4x4 -> 2x2: each output is the mean of a 2x2 block.
        let mut img = RgbImage::new(4, 4);
        for r in 0..4 {
            for c in 0..4 {
                img.set(r, c, [(r * 4 + c) as f32, 0.0, 1.0]);
            }
        }
        let out = resample(&img, 2, 2);
        assert_eq!(out.get(0, 0), [(0.0 + 1.0 + 4.0 + 5.0) / 4.0, 0.0, 1.0]);
        assert_eq!(out.get(1, 1), [(10.0 + 11.0 + 14.0 + 15.0) / 4.0, 0.0, 1.0]);
        // 2x2 -> 4x4: pixel replication.
        let up = resample(&out, 4, 4);
        assert_eq!(up.get(3, 2), out.get(1, 1));
    }
}
