//! The near-eye integral-imaging display model (paper Sec. 2.2, 4.1; Fig. 2a planes P2, P3):
//! a lenslet array at `z = v1` in front of an LCD at `z = v1 + v2`.
//!
//! Lenslet (i, j) is centred at `lenslet shift + M (i, j)`; elemental image (i, j) is centred at
//! `EI shift + M_EI (i, j)` on the LCD and belongs to lenslet (i, j). A display pixel belongs to
//! the elemental image whose centre is nearest. LCD pixels are boxes; pixel (row r, column c)
//! has its centre at `x = -W/2 + (c + 0.5) W/Nx`, `y = H/2 - (r + 0.5) H/Ny` (row 0 at the top).

use glam::{DVec2, IVec2};

use super::lattice::Lattice;
use super::lenslet::{LensletOptics, ThickLenslet, D_LINE_NM};
use super::limits;
use crate::error::{Error, Result};

/// The LCD panel: physical size and resolution, box pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lcd {
    /// Width and height, mm.
    pub size: DVec2,
    /// Columns (x) and rows (y).
    pub resolution: [usize; 2],
}

impl Lcd {
    /// Pixels per row (x).
    pub fn columns(&self) -> usize {
        self.resolution[0]
    }
    /// Pixel rows (y).
    pub fn rows(&self) -> usize {
        self.resolution[1]
    }
    /// Columns x rows.
    pub fn pixel_count(&self) -> usize {
        self.resolution[0] * self.resolution[1]
    }
    /// Pixel pitch (mm) along x and y.
    pub fn pixel_pitch(&self) -> DVec2 {
        self.size / DVec2::new(self.resolution[0] as f64, self.resolution[1] as f64)
    }

    /// Centre of pixel (row, column) on the LCD plane.
    #[inline]
    pub fn pixel_center(&self, row: usize, col: usize) -> DVec2 {
        self.pixel_point(row, col, DVec2::splat(0.5))
    }

    /// A point inside pixel (row, column): `frac` in `[0, 1]^2` runs left-to-right, top-to-bottom.
    #[inline]
    pub fn pixel_point(&self, row: usize, col: usize, frac: DVec2) -> DVec2 {
        let pitch = self.pixel_pitch();
        DVec2::new(
            -0.5 * self.size.x + (col as f64 + frac.x) * pitch.x,
            0.5 * self.size.y - (row as f64 + frac.y) * pitch.y,
        )
    }

    /// The pixel (row-major linear index) containing point `p`, or `None` off the panel.
    ///
    /// The panel is the closed rectangle `|x| <= W/2, |y| <= H/2`; inside it pixels are
    /// half-open boxes `[left, right) x (bottom, top]`, and points on the panel's right or bottom
    /// outer edge belong to the last column or row, so no index is ever out of range.
    #[inline]
    pub fn pixel_index(&self, p: DVec2) -> Option<usize> {
        PixelIndexer::new(self).index(p)
    }
}

/// [`Lcd::pixel_index`] with its reciprocals computed once, for hot loops.
#[derive(Clone, Copy, Debug)]
pub struct PixelIndexer {
    scale: DVec2,
    half: DVec2,
    nx: usize,
    ny: usize,
    /// Whether [`PixelIndexer::index_u32`] may take its branch-free path (see there).
    fits_u32: bool,
}

impl PixelIndexer {
    /// The indexer of `lcd`'s pixel grid (see the README's LCD pixel convention).
    pub fn new(lcd: &Lcd) -> Self {
        let n = DVec2::new(lcd.resolution[0] as f64, lcd.resolution[1] as f64);
        let (nx, ny) = (lcd.resolution[0], lcd.resolution[1]);
        // Rows and columns below 2^31 and every index below u32::MAX.
        let fits_u32 = nx < (1 << 31) && ny < (1 << 31) && (nx as u64) * (ny as u64) < u64::from(u32::MAX);
        Self { scale: n / lcd.size, half: 0.5 * n, nx, ny, fits_u32 }
    }

    /// The row-major index of the pixel holding LCD point `p` (world x, y, mm); `None` off the panel or for NaN.
    #[inline(always)]
    pub fn index(&self, p: DVec2) -> Option<usize> {
        let fx = p.x * self.scale.x + self.half.x;
        let fy = self.half.y - p.y * self.scale.y;
        // Written so that NaN fails the test.
        if !(fx >= 0.0 && fx <= 2.0 * self.half.x && fy >= 0.0 && fy <= 2.0 * self.half.y) {
            return None;
        }
        let c = (fx as u32 as usize).min(self.nx - 1);
        let r = (fy as u32 as usize).min(self.ny - 1);
        Some(r * self.nx + c)
    }

    /// The columns and rows (inclusive ranges) of every pixel [`PixelIndexer::index`] gives a
    /// point of the box `lo..=hi` (world x, y, mm), or `None` when part of the box is off the
    /// panel (or NaN). The index's arithmetic is monotone in each coordinate, so the box's
    /// corners bound the pixels of every point inside.
    pub fn box_pixels(&self, lo: DVec2, hi: DVec2) -> Option<([usize; 2], [usize; 2])> {
        let (fx0, fx1) = (lo.x * self.scale.x + self.half.x, hi.x * self.scale.x + self.half.x);
        let (fy0, fy1) = (self.half.y - hi.y * self.scale.y, self.half.y - lo.y * self.scale.y);
        if !(fx0 >= 0.0
            && fx1 <= 2.0 * self.half.x
            && fy0 >= 0.0
            && fy1 <= 2.0 * self.half.y
            && fx0 <= fx1
            && fy0 <= fy1)
        {
            return None;
        }
        let col = |f: f64| (f as u32 as usize).min(self.nx - 1);
        let row = |f: f64| (f as u32 as usize).min(self.ny - 1);
        Some(([col(fx0), col(fx1)], [row(fy0), row(fy1)]))
    }

    /// The number of pixels per row.
    pub fn columns(&self) -> usize {
        self.nx
    }

    /// [`PixelIndexer::index`] as a `u32`, `u32::MAX` for a point off the LCD (or NaN). For
    /// every LCD with fewer than `2^31` pixels per row and column and `u32::MAX` in all (any real
    /// one; the test is made once, in [`PixelIndexer::new`]) it has no branch, so loops over many
    /// points vectorise: inside the LCD the coordinates are below `2^31`, so converting through
    /// `i32` truncates as through `u32` does. Other sizes take the checked path.
    #[inline(always)]
    pub fn index_u32(&self, p: DVec2) -> u32 {
        if !self.fits_u32 {
            return self.index(p).map_or(u32::MAX, |i| i as u32);
        }
        let fx = p.x * self.scale.x + self.half.x;
        let fy = self.half.y - p.y * self.scale.y;
        let inside = fx >= 0.0 && fx <= 2.0 * self.half.x && fy >= 0.0 && fy <= 2.0 * self.half.y;
        let c = (fx as i32 as u32).min(self.nx as u32 - 1);
        let r = (fy as i32 as u32).min(self.ny as u32 - 1);
        if inside {
            r * self.nx as u32 + c
        } else {
            u32::MAX
        }
    }
}

/// A near-eye InIm display.
#[derive(Clone, Debug, PartialEq)]
pub struct Display {
    /// Display name, for reports and EXR headers.
    pub name: String,
    /// v1: distance from the eye's pupil plane (z = 0) to the lenslet plane, mm.
    pub eye_to_lenslets: f64,
    /// v2: distance from the lenslet plane to the LCD, mm.
    pub lenslets_to_lcd: f64,
    /// Lenslet focal length f, mm (optical power d2 = 1/f).
    pub focal_length: f64,
    /// Lenslet centres.
    pub lenslets: Lattice,
    /// Elemental-image centres on the LCD.
    pub elemental_images: Lattice,
    /// The LCD panel.
    pub lcd: Lcd,
    /// The emission spectra of the LCD's red, green and blue primaries (`[primaries]`; `None`:
    /// the documented default, [`crate::optics::spectrum::Primaries::typical_lcd`]). Only the
    /// schematic eyes read them, tracing each channel at its primary's wavelengths.
    pub primaries: Option<crate::optics::spectrum::Primaries>,
    /// The lenslets' optics: the paper's thin lens of `focal_length` (the default), or a real
    /// thick lenslet traced exactly ([`crate::optics::lenslet`]).
    pub lenslet: LensletOptics,
    /// The panel's photometry (`[photometry]`; `None`: the documented default,
    /// [`crate::optics::photometry::Photometry::typical_near_eye_lcd`]): how its values become
    /// cd/m^2. No rendered or simulated value reads it.
    pub photometry: Option<super::photometry::Photometry>,
}

impl Display {
    /// The framework's display from the paper (`lensletdisplay.yaml`): v1 20, v2 6.316,
    /// f 6.427, lenslet pitch 1.2, EI pitch 1.58, LCD 21.6 mm square at 2160 x 2160.
    pub fn paper() -> Self {
        Self {
            name: "paper (LFDisplay lensletdisplay.yaml)".into(),
            eye_to_lenslets: 20.0,
            lenslets_to_lcd: 6.316,
            focal_length: 6.427,
            lenslets: Lattice::square(1.2).expect("valid built-in lattice"),
            elemental_images: Lattice::square(1.58).expect("valid built-in lattice"),
            lcd: Lcd { size: DVec2::splat(21.6), resolution: [2160, 2160] },
            primaries: None,
            lenslet: LensletOptics::Paraxial,
            photometry: None,
        }
    }

    /// z of the lenslet plane.
    pub fn lenslet_z(&self) -> f64 {
        self.eye_to_lenslets
    }
    /// z of the LCD plane (v1 + v2, plus a real lenslet's thickness: v1 runs to its front
    /// vertex, v2 from its back vertex).
    pub fn lcd_z(&self) -> f64 {
        self.eye_to_lenslets + self.lenslet.thickness() + self.lenslets_to_lcd
    }

    /// The samplers of the red, green and blue primaries' spectra (`primaries`, or the typical
    /// LCD's): the wavelengths a real lenslet refracts each channel at.
    pub fn channel_samplers(&self) -> [crate::optics::spectrum::SpectrumSampler; 3] {
        let typical = crate::optics::spectrum::Primaries::typical_lcd();
        let p = self.primaries.as_ref().unwrap_or(&typical);
        p.samplers("display").or_else(|_| typical.samplers("display")).expect("the typical LCD's primaries are valid")
    }

    /// The median wavelength of each channel's primary, nm: where a real lenslet refracts the
    /// camera rays of display rendering and the eye rays of the grid estimator.
    pub fn channel_wavelengths(&self) -> [f64; 3] {
        self.channel_samplers().map(|s| s.wavelength(0.5))
    }

    /// The half angles (radians) of the display's field of view along x and y, seen from the
    /// pupil centre: `atan(W / 2 (v1 + v2))` and `atan(H / 2 (v1 + v2))`.
    pub fn field_half_angles(&self) -> [f64; 2] {
        let distance = self.eye_to_lenslets + self.lenslets_to_lcd;
        [(0.5 * self.lcd.size.x / distance).atan(), (0.5 * self.lcd.size.y / distance).atan()]
    }

    /// Checks that an eye turned to `pose` looks at the display: its line of sight, from the
    /// turned pupil's centre, meets the LCD plane inside the panel. Errors name `source` and
    /// `field` (the gaze).
    pub fn check_gaze(&self, pose: &super::eye::EyePose, source: &str, field: &str) -> crate::error::Result<()> {
        let (p, l) = (pose.pupil_centre, pose.line_of_sight);
        let at = p.truncate() + l.truncate() * ((self.lcd_z() - p.z) / l.z);
        let half = 0.5 * self.lcd.size;
        if l.z > 0.0 && at.x.abs() <= half.x && at.y.abs() <= half.y {
            return Ok(());
        }
        let [h, v] = <[f64; 2]>::from(pose.gaze);
        Err(crate::error::Error::invalid(
            source,
            field,
            format!(
                "the line of sight at [{h}, {v}] degrees meets the LCD plane at ({:.2}, {:.2}) mm, off the \
                 {} x {} mm panel of display `{}`: the eye would look past the display",
                at.x, at.y, self.lcd.size.x, self.lcd.size.y, self.name
            ),
        ))
    }

    /// The area of the display's field of view, deg^2 (its angular width times its angular
    /// height): the adapting field of the light-adapted pupil ([`super::eye::pupil`]).
    pub fn field_area_deg2(&self) -> f64 {
        let half = self.field_half_angles();
        4.0 * half[0].to_degrees() * half[1].to_degrees()
    }

    /// The panel's photometry (`photometry`, or the typical near-eye LCD's).
    pub fn photometry(&self) -> super::photometry::Photometry {
        self.photometry.unwrap_or_default()
    }

    /// Each channel's share of the display's luminance, from its primary's spectrum (`primaries`,
    /// or the typical LCD's) weighted by V(lambda); sums to 1.
    pub fn luminance_weights(&self) -> [f64; 3] {
        match &self.primaries {
            Some(p) if p.validate("display").is_ok() => p.luminance_weights(),
            _ => crate::optics::spectrum::Primaries::typical_lcd().luminance_weights(),
        }
    }

    /// The real lenslet, if the display has one.
    pub fn thick_lenslet(&self) -> Option<&ThickLenslet> {
        self.lenslet.thick()
    }
    /// The distances eq. (1)'s angular quantities use, `(v1', v2')`: pupil to the lenslets' front
    /// principal plane and back principal plane to the LCD. The thin lens's are `(v1, v2)`; a real
    /// lenslet's principal planes `h1`, `h2` (at the d line, [`Paraxial::principal_planes`]) give
    /// `(v1 + h1, v2 - h2)`, the thin design it is paraxially equivalent to.
    ///
    /// [`Paraxial::principal_planes`]: super::lenslet::Paraxial::principal_planes
    pub fn principal_plane_distances(&self) -> (f64, f64) {
        match self.thick_lenslet() {
            None => (self.eye_to_lenslets, self.lenslets_to_lcd),
            Some(t) => {
                let (h1, h2) = t.paraxial(D_LINE_NM).principal_planes();
                (self.eye_to_lenslets + h1, self.lenslets_to_lcd - h2)
            }
        }
    }

    /// Lenslet optical power d2 = 1/f.
    pub fn lenslet_power(&self) -> f64 {
        1.0 / self.focal_length
    }

    /// z (from the pupil) of the central depth plane, the lenslets' image of the LCD:
    /// `1/v2 - 1/f = 1/d` with the virtual image at `z = v1 + d`. `None` when the LCD is in the
    /// lenslets' focal plane (image at infinity) or the image is real (LCD beyond the focus).
    /// With a real lenslet: its paraxial image of the LCD at the d line.
    pub fn central_depth_plane(&self) -> Option<f64> {
        if let Some(t) = self.thick_lenslet() {
            return t.lcd_image_distance(self.lenslets_to_lcd, D_LINE_NM).map(|d| self.eye_to_lenslets + d);
        }
        let inv = 1.0 / self.lenslets_to_lcd - 1.0 / self.focal_length;
        if inv <= 0.0 {
            None
        } else {
            Some(self.eye_to_lenslets + 1.0 / inv)
        }
    }

    /// Index of the elemental image (and so of the lenslet) that owns LCD point `p`.
    #[inline]
    pub fn elemental_image_of(&self, p: DVec2) -> IVec2 {
        self.elemental_images.nearest(p)
    }

    /// Checks that the optics is possible; `source` names where it came from (a file path).
    pub fn validate(&self, source: &str) -> Result<()> {
        let positive = |field: &str, v: f64| -> Result<()> {
            if !v.is_finite() {
                Err(Error::invalid(source, field, format!("must be a finite number, got {v}")))
            } else if v <= 0.0 {
                Err(Error::invalid(source, field, format!("must be positive, got {v}")))
            } else {
                Ok(())
            }
        };
        positive("eye_to_lenslets (v1)", self.eye_to_lenslets)?;
        positive("lenslets_to_lcd (v2)", self.lenslets_to_lcd)?;
        positive("focal_length (f)", self.focal_length)?;
        positive("lcd.size[0] (width)", self.lcd.size.x)?;
        positive("lcd.size[1] (height)", self.lcd.size.y)?;
        limits::EYE_TO_LENSLETS.check(source, "eye_to_lenslets (v1)", self.eye_to_lenslets)?;
        limits::LENSLETS_TO_LCD.check(source, "lenslets_to_lcd (v2)", self.lenslets_to_lcd)?;
        limits::FOCAL_LENGTH.check(source, "focal_length (f)", self.focal_length)?;
        limits::LCD_SIZE.check(source, "lcd.size[0] (width)", self.lcd.size.x)?;
        limits::LCD_SIZE.check(source, "lcd.size[1] (height)", self.lcd.size.y)?;
        if let Some(t) = self.thick_lenslet() {
            t.validate(&self.lenslets, source, "lenslet")?;
        }
        if let Some(p) = &self.photometry {
            p.validate(source)?;
        }
        for (i, n) in self.lcd.resolution.iter().enumerate() {
            if *n == 0 {
                return Err(Error::invalid(source, format!("lcd.resolution[{i}]"), "must be at least 1 pixel"));
            }
            if *n > 1 << 16 {
                return Err(Error::invalid(
                    source,
                    format!("lcd.resolution[{i}]"),
                    format!("{n} pixels is beyond the supported 65536"),
                ));
            }
        }
        Ok(())
    }

    /// A short human-readable summary (printed by `inimtrace info` and at the start of `assess`).
    pub fn summary(&self) -> String {
        let cdp = match self.central_depth_plane() {
            Some(z) => format!("{z:.1} mm from the pupil ({:.3} D)", 1000.0 / z),
            None => "at infinity or real (LCD at or beyond the lenslet focal plane)".into(),
        };
        let [a, b, c, d] = self.lenslets.row_major();
        let [ea, eb, ec, ed] = self.elemental_images.row_major();
        let lenslet = match self.thick_lenslet() {
            None => String::new(),
            Some(t) => format!(
                "; real lenslets: {} {} mm thick, front radius {} conic {}, back radius {} conic {}, EFL {:.4} mm \
                 (d line)",
                t.material.name,
                t.thickness,
                t.front.radius,
                t.front.conic,
                t.back.radius,
                t.back.conic,
                t.paraxial(D_LINE_NM).efl
            ),
        };
        format!(
            "display {}: v1 {} mm, v2 {} mm, f {} mm; lenslets shift ({}, {}) M [{a} {b}; {c} {d}]; \
             EIs shift ({}, {}) M [{ea} {eb}; {ec} {ed}]; LCD {} x {} mm, {} x {} px; central depth plane {cdp}{lenslet}",
            self.name,
            self.eye_to_lenslets,
            self.lenslets_to_lcd,
            self.focal_length,
            self.lenslets.shift.x,
            self.lenslets.shift.y,
            self.elemental_images.shift.x,
            self.elemental_images.shift.y,
            self.lcd.size.x,
            self.lcd.size.y,
            self.lcd.resolution[0],
            self.lcd.resolution[1],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn branch_free_pixel_index_equals_the_checked_one() {
        for lcd in [Display::paper().lcd, Lcd { resolution: [7, 3], size: DVec2::new(2.1, 0.9) }] {
            let ix = PixelIndexer::new(&lcd);
            assert!(ix.fits_u32);
            let (hx, hy) = (0.5 * lcd.size.x, 0.5 * lcd.size.y);
            let mut pts = vec![
                DVec2::new(-hx, hy),
                DVec2::new(hx, -hy),
                DVec2::new(hx, hy),
                DVec2::new(-hx, -hy),
                DVec2::new(f64::NAN, 0.0),
                DVec2::new(0.0, f64::INFINITY),
                DVec2::new(f64::NEG_INFINITY, 0.0),
                DVec2::new(1e300, -1e300),
                DVec2::new(-hx * (1.0 + f64::EPSILON), 0.0),
                DVec2::new(hx * (1.0 + f64::EPSILON), 0.0),
            ];
            for i in 0..=400 {
                for j in 0..=40 {
                    pts.push(DVec2::new((i as f64 / 200.0 - 1.0) * hx * 1.1, (j as f64 / 20.0 - 1.0) * hy * 1.1));
                }
            }
            for p in pts {
                assert_eq!(ix.index_u32(p), ix.index(p).map_or(u32::MAX, |i| i as u32), "{p}");
            }
        }
    }

    #[test]
    fn paper_display_central_depth_plane_near_386_mm() {
        let z = Display::paper().central_depth_plane().unwrap();
        assert!((z - 385.8).abs() < 0.5, "{z}");
        // With the paper text's v2 = 6.32 mm it is at 400 mm, as the paper says.
        let mut d = Display::paper();
        d.lenslets_to_lcd = 6.32;
        let z = d.central_depth_plane().unwrap();
        assert!((z - 400.0).abs() < 1.0, "{z}");
    }

    #[test]
    fn pixel_centres_follow_the_convention_and_index_back() {
        let lcd = Display::paper().lcd;
        let p = lcd.pixel_center(0, 0);
        assert!((p - DVec2::new(-10.795, 10.795)).length() < 1e-12);
        for (r, c) in [(0, 0), (5, 2159), (2159, 0), (1080, 1079)] {
            assert_eq!(lcd.pixel_index(lcd.pixel_center(r, c)), Some(r * 2160 + c));
        }
        // Outer edges stay in range; beyond them is off the panel.
        assert_eq!(lcd.pixel_index(DVec2::new(10.8, -10.8)), Some(2159 * 2160 + 2159));
        assert_eq!(lcd.pixel_index(DVec2::new(-10.8, 10.8)), Some(0));
        assert_eq!(lcd.pixel_index(DVec2::new(10.800001, 0.0)), None);
        assert_eq!(lcd.pixel_index(DVec2::new(f64::NAN, 0.0)), None);
    }

    #[test]
    fn impossible_optics_names_the_field() {
        let mut d = Display::paper();
        d.focal_length = -1.0;
        let e = d.validate("x.toml").unwrap_err().to_string();
        assert!(e.contains("x.toml") && e.contains("focal_length"), "{e}");
        let mut d = Display::paper();
        d.lcd.resolution = [0, 10];
        assert!(d.validate("x").unwrap_err().to_string().contains("lcd.resolution[0]"));
        let mut d = Display::paper();
        d.eye_to_lenslets = f64::NAN;
        assert!(d.validate("x").unwrap_err().to_string().contains("eye_to_lenslets"));
    }
}
