//! `inimtrace info`: what a display design (paper Sec. 2.2, Fig. 2a) offers an eye at the
//! pupil plane, and what a scene holds (Sec. 4.1), as data ([`DisplayDesign`],
//! [`SceneSummary`], both serialisable to JSON) and as text.
//!
//! Display quantities (the eye's pupil centre at the origin, lenslets at `z = v1`, LCD at
//! `z = v1 + v2`; `m = v1 / v2`):
//! * **viewing zone** of a lenslet: the eye-plane region from which the lenslet shows its own
//!   elemental image: the elemental-image cell projected through the lenslet's centre,
//!   `(1 + m) c_lenslet - m x` for LCD points `x` of the cell; its width along x and y is `m`
//!   times the cell's;
//! * **eye box** at the eye relief `v1`: the intersection of the viewing zones of every lenslet
//!   whose elemental image is on the LCD (per axis), where the eye sees every lenslet show its
//!   own elemental image;
//! * **field of view**: the angle the LCD subtends at the pupil centre, `2 atan(W / 2 (v1 + v2))`;
//! * **angular pixel pitch at the central depth plane** (CDP at `z`): an LCD pixel `p` magnified
//!   by the lenslet, `p (z - v1) / v2`, seen from the pupil centre, `p (z - v1) / (v2 z)` rad;
//!   pixels per degree is its inverse (LCD in the focal plane: `p / f`);
//! * **pixels per elemental image**: cell area over pixel area, and cell widths over pixel pitch;
//! * **views across the pupil** (the integral-imaging quantity, the paper's "4 x 4 rays within
//!   the pupil"): a point on the axis at the CDP sends one ray through each lenslet centre; the
//!   pupil diameter over their spacing at the pupil plane, per axis, and how many enter the pupil
//!   disk (the resolution study reports the same numbers);
//! * **pixel beams of one lenslet in the pupil** (pupil diameter `D`, centred on the axis): the
//!   pixels of the central elemental image whose rays through the lenslet's centre enter the
//!   pupil (spots `m p` apart), a different, much larger count.
//! * **real lenslets**: a thick lenslet enters through its principal planes (d line,
//!   `optics::lenslet_paraxial`): `v1 + h1` and `v2 - h2` for `v1` and `v2`, rays through its
//!   nodal points for rays through lenslet centres: the optically equivalent thin design's numbers.
//! * A warning when the elemental-image lattice is not a scaled copy of the lenslet lattice
//!   (square elemental images under hexagonal lenslets), or the eye box is empty.

use glam::{DVec2, IVec2};
use serde::Serialize;

use crate::count::count;
use crate::optics::diffraction::{ApertureShape, Diffraction};
use crate::optics::{Display, Lattice};
mod scene;

pub use scene::{scene_summary, scene_summary_text, ObjectSummary, SceneSummary};

/// A lattice as numbers: centre of cell (0, 0) and the row-major pitch matrix `[a, b, c, d]`
/// (`centre(i, j) = shift + [[a, b], [c, d]] (i, j)`), mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LatticeParameters {
    /// Centre of cell (0, 0), mm.
    pub shift_mm: [f64; 2],
    /// The pitch matrix `[a, b, c, d]`, row-major, mm.
    pub pitch_matrix_mm: [f64; 4],
}

impl From<&Lattice> for LatticeParameters {
    fn from(l: &Lattice) -> Self {
        Self { shift_mm: l.shift.to_array(), pitch_matrix_mm: l.row_major() }
    }
}

/// A display's parameters as structured fields (`results.json`, `info --json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DisplayParameters {
    /// Display name.
    pub name: String,
    /// v1: pupil plane to lenslet plane.
    pub eye_to_lenslets_mm: f64,
    /// v2: lenslet plane to LCD.
    pub lenslets_to_lcd_mm: f64,
    /// f: the lenslets' focal length, mm.
    pub focal_length_mm: f64,
    /// The lenslet lattice.
    pub lenslets: LatticeParameters,
    /// The elemental-image lattice.
    pub elemental_images: LatticeParameters,
    /// LCD width and height, mm.
    pub lcd_size_mm: [f64; 2],
    /// Columns, rows.
    pub lcd_resolution: [usize; 2],
    /// `None`: at infinity or real (LCD at or beyond the lenslets' focal plane).
    pub central_depth_plane_mm: Option<f64>,
    /// The central depth plane in dioptres.
    pub central_depth_plane_diopters: Option<f64>,
}

impl From<&Display> for DisplayParameters {
    fn from(d: &Display) -> Self {
        let cdp = d.central_depth_plane();
        Self {
            name: d.name.clone(),
            eye_to_lenslets_mm: d.eye_to_lenslets,
            lenslets_to_lcd_mm: d.lenslets_to_lcd,
            focal_length_mm: d.focal_length,
            lenslets: (&d.lenslets).into(),
            elemental_images: (&d.elemental_images).into(),
            lcd_size_mm: d.lcd.size.to_array(),
            lcd_resolution: d.lcd.resolution,
            central_depth_plane_mm: cdp,
            central_depth_plane_diopters: cdp.map(|z| 1000.0 / z),
        }
    }
}

/// What a display design offers the eye (see the module comment for the definitions).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DisplayDesign {
    /// The display's parameters.
    pub display: DisplayParameters,
    /// v1.
    pub eye_relief_mm: f64,
    /// Width (x) and height (y) of one lenslet's viewing zone.
    pub viewing_zone_mm: [f64; 2],
    /// Width and height of the eye box; `None` when the viewing zones have no common point.
    pub eye_box_mm: Option<[f64; 2]>,
    /// Centre of the eye box, mm.
    pub eye_box_center_mm: Option<[f64; 2]>,
    /// How many lenslets (with their elemental image on the LCD) the eye box accounts for.
    pub lenslets_on_lcd: usize,
    /// Horizontal and vertical.
    pub field_of_view_deg: [f64; 2],
    /// LCD pixel pitch, x and y, mm.
    pub pixel_pitch_mm: [f64; 2],
    /// At the central depth plane, x and y; `None` when the image is real.
    pub angular_pixel_pitch_arcmin: Option<[f64; 2]>,
    /// Pixels per degree at the central depth plane, x and y; `None` when the image is real.
    pub pixels_per_degree: Option<[f64; 2]>,
    /// Elemental-image cell area over pixel area.
    pub pixels_per_elemental_image: f64,
    /// Cell width along x and y over the pixel pitch.
    pub pixels_per_elemental_image_xy: [f64; 2],
    /// The pupil the views and pixel beams are counted through, mm.
    pub pupil_diameter_mm: f64,
    /// Views per axis a point on the axis at the CDP sends through the pupil: the pupil diameter
    /// over the spacing of its rays through neighbouring lenslet centres at the pupil (`None`:
    /// the CDP is at infinity or real).
    pub views_across_pupil: Option<[f64; 2]>,
    /// Rays of that point through lenslet centres that enter the pupil disk.
    pub views_in_pupil: Option<usize>,
    /// Eye-plane spacing of one lenslet's pixel beams (one per LCD pixel), `m p`.
    pub pixel_beam_spacing_mm: [f64; 2],
    /// Pixel beams of one lenslet in the pupil: pixels of the central elemental image whose rays
    /// through the lenslet's centre enter the pupil.
    pub lenslet_pixel_beams_in_pupil: usize,
    /// Diffraction's angles at the pupil and the lenslet aperture, per colour channel.
    pub diffraction: DiffractionInfo,
    /// The panel's luminance: peak, black, ambient light, the primaries' luminance shares.
    pub photometry: crate::optics::photometry::PhotometryInfo,
    /// A real lenslet's principal planes `[h1, h2]` (d line; module documentation), mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub principal_planes_mm: Option<[f64; 2]>,
    /// A real lenslet's focal properties (absent for the paper's thin lens).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lenslet: Option<LensletReport>,
    /// Design warnings (lattices that do not match).
    pub warnings: Vec<String>,
}

/// Diffraction at the pupil and at the lenslet aperture (`optics::diffraction`): whether it is
/// on and its angle lambda / width per colour channel, at the mean wavelength of each primary.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiffractionInfo {
    /// `[optics] diffraction` ("none", "pupil" or "apertures").
    pub mode: &'static str,
    /// The lenslet aperture's shape from the lattice's cell ("square", "rectangle", "hexagonal").
    pub lenslet_aperture: &'static str,
    /// Red, green and blue.
    pub channels: Vec<ChannelDiffraction>,
}

/// One colour channel's diffraction angles.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChannelDiffraction {
    /// "red", "green" or "blue".
    pub channel: &'static str,
    /// The primary's mean wavelength, nm.
    pub wavelength_nm: f64,
    /// lambda / D of the pupil, arcmin.
    pub pupil_arcmin: f64,
    /// lambda / w of the lenslet aperture (its side or flat-to-flat width), arcmin.
    pub lenslet_arcmin: f64,
}

/// The diffraction angles of display `d` and a pupil of `pupil_diameter` mm, `mode` stated.
pub fn diffraction_info(d: &Display, pupil_diameter: f64, mode: Diffraction) -> DiffractionInfo {
    let shape = ApertureShape::of_lattice(&d.lenslets);
    let primaries = d.primaries.clone().unwrap_or_default();
    let means: [f64; 3] = match primaries.samplers("display") {
        Ok(s) => std::array::from_fn(|c| s[c].mean_nm()),
        Err(_) => [610.0, 535.0, 450.0],
    };
    let arcmin = |rad: f64| rad.to_degrees() * 60.0;
    let channels = ["red", "green", "blue"]
        .iter()
        .zip(means)
        .map(|(&channel, nm)| ChannelDiffraction {
            channel,
            wavelength_nm: nm,
            pupil_arcmin: arcmin(nm * 1e-6 / pupil_diameter),
            lenslet_arcmin: arcmin(shape.angle(nm)),
        })
        .collect();
    DiffractionInfo { mode: mode.name(), lenslet_aperture: shape.name(), channels }
}

/// A real lenslet's first-order properties, at the d line and at each channel's median wavelength.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LensletReport {
    /// The material's name.
    pub material: String,
    /// Centre thickness, mm.
    pub thickness_mm: f64,
    /// The index at the d line (587.56 nm).
    pub index_d: f64,
    /// Effective focal length at the d line, mm.
    pub efl_mm: f64,
    /// Back focal distance (back vertex to the LCD-side focus) at the d line, mm.
    pub bfd_mm: f64,
    /// The red, green and blue primaries' median wavelengths, nm.
    pub channel_wavelengths_nm: [f64; 3],
    /// Effective focal length per channel, mm.
    pub channel_efl_mm: [f64; 3],
    /// The lenslets' image of the LCD per channel, mm from the pupil (`None`: at infinity or real).
    pub channel_cdp_mm: [Option<f64>; 3],
    /// The central depth plane the design intends (`design_cdp_mm`, else eq. (1)'s from
    /// `focal_length` and `v2`), mm from the pupil.
    pub intended_cdp_mm: Option<f64>,
    /// The v2 that puts the real lenslet's image of the LCD (d line) at the intended plane, mm.
    pub v2_for_intended_cdp_mm: Option<f64>,
}

/// The difference (dioptres) between the real lenslet's central depth plane and the intended
/// one above which `info` warns: a tenth of the eye's depth of field at a 5 mm pupil (about 0.1 D).
pub const CDP_MISMATCH_DIOPTERS: f64 = 0.01;

/// [`LensletReport`] of `d`'s real lenslet, and the warning when it misses the intended plane.
fn lenslet_report(d: &Display) -> Option<(LensletReport, Option<String>)> {
    use crate::optics::lenslet::D_LINE_NM;
    let t = d.thick_lenslet()?;
    let (v1, v2) = (d.eye_to_lenslets, d.lenslets_to_lcd);
    let p = t.paraxial(D_LINE_NM);
    let nm = d.channel_wavelengths();
    let intended = t.design_cdp_mm.or_else(|| {
        let inv = 1.0 / v2 - 1.0 / d.focal_length;
        (inv > 0.0).then(|| v1 + 1.0 / inv)
    });
    let real = d.central_depth_plane();
    let v2_for = intended.map(|z| t.v2_for_image_distance(z - v1, D_LINE_NM)).filter(|v| v.is_finite() && *v > 0.0);
    let dioptres = |z: Option<f64>| z.map_or(0.0, |z| 1000.0 / z);
    let warning = intended.and_then(|z| {
        let off = (dioptres(real) - dioptres(Some(z))).abs();
        (off > CDP_MISMATCH_DIOPTERS).then(|| {
            format!(
                "v2 = {v2} mm puts the real lenslet's image of the LCD (d line) {}, not at the intended central depth \
                 plane {z:.1} mm from the pupil ({:.3} D; {off:.3} D apart){}",
                match real {
                    Some(r) => format!("{r:.1} mm from the pupil ({:.3} D)", 1000.0 / r),
                    None => "at infinity or on the eye's side (a real image)".into(),
                },
                1000.0 / z,
                v2_for.map_or(String::new(), |v| format!(": v2 = {v:.4} mm would put it there")),
            )
        })
    });
    let report = LensletReport {
        material: t.material.name.clone(),
        thickness_mm: t.thickness,
        index_d: p.index,
        efl_mm: p.efl,
        bfd_mm: p.bfd,
        channel_wavelengths_nm: nm,
        channel_efl_mm: nm.map(|w| t.paraxial(w).efl),
        channel_cdp_mm: nm.map(|w| t.lcd_image_distance(v2, w).map(|z| v1 + z)),
        intended_cdp_mm: intended,
        v2_for_intended_cdp_mm: v2_for,
    };
    Some((report, warning))
}

/// Half-width of the lattice's cell (0, 0) along `dir` from its centre (bisection on the
/// nearest-centre rule).
fn cell_half_extent(l: &Lattice, dir: DVec2) -> f64 {
    let home = l.nearest(l.shift);
    let (mut inside, mut outside) = (0.0, l.reduced_matrix().x_axis.length() + l.reduced_matrix().y_axis.length());
    for _ in 0..60 {
        let mid = 0.5 * (inside + outside);
        if l.nearest(l.shift + mid * dir) == home {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    0.5 * (inside + outside)
}

/// The design quantities of `d` for a pupil of `pupil_diameter` mm centred on the axis.
pub fn display_design(d: &Display, pupil_diameter: f64) -> DisplayDesign {
    // Through a real lenslet's principal planes (module documentation); the eye relief stays v1.
    let (v1, v2) = d.principal_plane_distances();
    let m = v1 / v2;
    let pitch = d.lcd.pixel_pitch();
    let half =
        DVec2::new(cell_half_extent(&d.elemental_images, DVec2::X), cell_half_extent(&d.elemental_images, DVec2::Y));
    let zone = 2.0 * m * half;
    let mut warnings = Vec::new();
    let lenslet = lenslet_report(d).map(|(report, warning)| {
        warnings.extend(warning);
        report
    });

    // Viewing zones of every lenslet whose elemental-image centre is on the LCD.
    let (w, h) = (0.5 * d.lcd.size.x, 0.5 * d.lcd.size.y);
    let corners = [DVec2::new(-w, -h), DVec2::new(w, -h), DVec2::new(w, h), DVec2::new(-w, h)];
    let uv: Vec<DVec2> = corners.iter().map(|c| d.elemental_images.coordinates(*c)).collect();
    let lo = uv.iter().fold(DVec2::INFINITY, |a, b| a.min(*b)).floor();
    let hi = uv.iter().fold(DVec2::NEG_INFINITY, |a, b| a.max(*b)).ceil();
    let (mut box_lo, mut box_hi, mut count) = (DVec2::NEG_INFINITY, DVec2::INFINITY, 0usize);
    let range = |a: f64, b: f64| (a.max(-1e6) as i32)..=(b.min(1e6) as i32);
    for j in range(lo.y, hi.y) {
        for i in range(lo.x, hi.x) {
            let idx = IVec2::new(i, j);
            let e = d.elemental_images.center(idx);
            if e.x.abs() > w || e.y.abs() > h {
                continue;
            }
            let centre = (1.0 + m) * d.lenslets.center(idx) - m * e;
            box_lo = box_lo.max(centre - 0.5 * zone);
            box_hi = box_hi.min(centre + 0.5 * zone);
            count += 1;
        }
    }
    let eye_box = (count > 0 && box_hi.cmpgt(box_lo).all()).then(|| (box_hi - box_lo, 0.5 * (box_lo + box_hi)));
    if eye_box.is_none() {
        warnings.push(format!(
            "no eye box: the viewing zones of the {} do not overlap at the eye relief ({} mm); \
             the elemental-image pitch does not suit the lenslet pitch and distances (ideal ratio (v1 + v2) / v1 = {:.5})",
            crate::count::count(count, "lenslet"),
            d.eye_to_lenslets,
            (v1 + v2) / v1
        ));
    }

    // Is the elemental-image lattice a scaled copy of the lenslet lattice?
    let (ml, me) = (d.lenslets.row_major(), d.elemental_images.row_major());
    let dot = |a: &[f64; 4], b: &[f64; 4]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let k = dot(&me, &ml) / dot(&ml, &ml);
    let residual = me.iter().zip(&ml).map(|(e, l)| (e - k * l).powi(2)).sum::<f64>().sqrt() / dot(&me, &me).sqrt();
    if residual.is_nan() || residual > 1e-3 {
        warnings.push(format!(
            "the elemental-image lattice {me:?} is not a scaled copy of the lenslet lattice {ml:?} (e.g. square \
             elemental images under hexagonal lenslets): pixels near elemental-image borders are seen through \
             other lenslets"
        ));
    }

    let cdp = d.central_depth_plane();
    let angular = match cdp {
        Some(z) => Some(pitch * (z - v1) / (v2 * z)),
        None if (1.0 / v2 - 1.0 / d.focal_length).abs() <= 1e-12 => Some(pitch / d.focal_length),
        None => None,
    };
    let to_deg = |r: DVec2| r * (180.0 / std::f64::consts::PI);

    let (views_across_pupil, views_in_pupil) = views_of_a_cdp_point(d, pupil_diameter);

    // Pixel beams: pixels of the central elemental image whose rays enter the pupil.
    let home = d.lenslets.nearest(DVec2::ZERO);
    let (cl, ce) = (d.lenslets.center(home), d.elemental_images.center(home));
    let r2 = (0.5 * pupil_diameter).powi(2);
    let reach = half.max_element() * 1.5 + pitch.max_element();
    let col = |x: f64| ((x + w) / pitch.x).floor() as i64;
    let row = |y: f64| ((h - y) / pitch.y).floor() as i64;
    let (c0, c1) = (col(ce.x - reach).max(0), col(ce.x + reach).min(d.lcd.columns() as i64 - 1));
    let (r0, r1) = (row(ce.y + reach).max(0), row(ce.y - reach).min(d.lcd.rows() as i64 - 1));
    let mut views = 0;
    for r in r0..=r1 {
        for c in c0..=c1 {
            let x = d.lcd.pixel_center(r as usize, c as usize);
            if d.elemental_image_of(x) == home && ((1.0 + m) * cl - m * x).length_squared() <= r2 {
                views += 1;
            }
        }
    }

    DisplayDesign {
        display: d.into(),
        eye_relief_mm: d.eye_to_lenslets,
        viewing_zone_mm: zone.to_array(),
        eye_box_mm: eye_box.map(|(s, _)| s.to_array()),
        eye_box_center_mm: eye_box.map(|(_, c)| c.to_array()),
        lenslets_on_lcd: count,
        field_of_view_deg: [2.0 * (w / (v1 + v2)).atan().to_degrees(), 2.0 * (h / (v1 + v2)).atan().to_degrees()],
        pixel_pitch_mm: pitch.to_array(),
        angular_pixel_pitch_arcmin: angular.map(|a| (to_deg(a) * 60.0).to_array()),
        pixels_per_degree: angular.map(|a| (DVec2::ONE / to_deg(a)).to_array()),
        pixels_per_elemental_image: d.elemental_images.cell_area() / (pitch.x * pitch.y),
        pixels_per_elemental_image_xy: (2.0 * half / pitch).to_array(),
        pupil_diameter_mm: pupil_diameter,
        views_across_pupil,
        views_in_pupil,
        pixel_beam_spacing_mm: (m * pitch).to_array(),
        lenslet_pixel_beams_in_pupil: views,
        diffraction: diffraction_info(d, pupil_diameter, Diffraction::None),
        photometry: crate::optics::photometry::PhotometryInfo::of(d),
        principal_planes_mm: d.thick_lenslet().map(|_| [v1 - d.eye_to_lenslets, d.lenslets_to_lcd - v2]),
        lenslet,
        warnings,
    }
}

/// The views a point on the axis at the central depth plane sends through a pupil of
/// `pupil_diameter` mm: per axis (the pupil diameter over the spacing at the pupil plane of its
/// rays through neighbouring lenslet centres or nodal points) and the rays that enter the pupil
/// disk; `None` when the central depth plane is at infinity or real.
pub fn views_of_a_cdp_point(display: &Display, pupil_diameter: f64) -> (Option<[f64; 2]>, Option<usize>) {
    let cdp = display.central_depth_plane();
    let (v1, _) = display.principal_plane_distances();
    let lenslet = display.lenslets.reduced_matrix();
    let pitch = [lenslet.x_axis.length(), lenslet.y_axis.length()];
    // Rays from (0, 0, z) through lenslet centres c (nodal points) reach the pupil at c z / (z - v1).
    let scale = cdp.map(|z| z / (z - v1));
    let views_across = scale.map(|s| [pupil_diameter / (pitch[0] * s), pupil_diameter / (pitch[1] * s)]);
    let views_in = scale.map(|s| {
        let r = 0.5 * pupil_diameter;
        let reach = (r / (s * pitch[0].min(pitch[1]))).ceil() as i32 + 2;
        let mut n = 0;
        for j in -reach..=reach {
            for i in -reach..=reach {
                let c = display.lenslets.center(IVec2::new(i, j));
                if (c * s).length() <= r {
                    n += 1;
                }
            }
        }
        n
    });
    (views_across, views_in)
}

/// [`DisplayDesign`] as the text `inimtrace info` prints.
pub fn display_design_text(x: &DisplayDesign, summary: &str) -> String {
    let pair = |v: [f64; 2], digits: usize| format!("{:.digits$} x {:.digits$}", v[0], v[1]);
    let mut s = format!("{summary}\n");
    if let Some([h1, h2]) = x.principal_planes_mm {
        let (v1, v2) = (x.display.eye_to_lenslets_mm + h1, x.display.lenslets_to_lcd_mm - h2);
        s += &format!(
            "real lenslet: the quantities below are paraxial, through its principal planes (d line): front {h1:.4} \
             mm beyond the front vertex, back {h2:.4} mm beyond the back vertex, so v1 + h1 = {v1:.4} mm and v2 - h2 \
             = {v2:.4} mm stand for the thin lens's v1 and v2\n"
        );
    }
    s += &format!(
        "eye box at the eye relief ({} mm): {}\n",
        x.eye_relief_mm,
        match (x.eye_box_mm, x.eye_box_center_mm) {
            (Some(b), Some(c)) => format!(
                "{} mm centred at ({:.3}, {:.3}) (one lenslet's viewing zone {} mm; {} on the LCD)",
                pair(b, 3),
                c[0],
                c[1],
                pair(x.viewing_zone_mm, 3),
                count(x.lenslets_on_lcd, "lenslet")
            ),
            _ => "none".into(),
        }
    );
    s += &format!("field of view: {} degrees (horizontal x vertical)\n", pair(x.field_of_view_deg, 2));
    s += &match (x.angular_pixel_pitch_arcmin, x.pixels_per_degree) {
        (Some(a), Some(p)) => format!(
            "angular pixel pitch at the central depth plane: {} arcmin ({} pixels per degree)\n",
            pair(a, 3),
            pair(p, 2)
        ),
        _ => "angular pixel pitch: undefined (the lenslets form a real image of the LCD)\n".into(),
    };
    s += &format!(
        "pixels per elemental image: {:.1} ({} across)\n",
        x.pixels_per_elemental_image,
        pair(x.pixels_per_elemental_image_xy, 1)
    );
    s += &format!(
        "views through a {} mm pupil (a point at the central depth plane): {}\n",
        x.pupil_diameter_mm,
        match (x.views_across_pupil, x.views_in_pupil) {
            (Some(v), Some(n)) => format!("{} across; {n} in the pupil disk", pair(v, 2)),
            _ => "none (the central depth plane is at infinity or real)".into(),
        }
    );
    s += &format!(
        "pixel beams of one lenslet in a {} mm pupil: {} ({} mm apart at the pupil)\n",
        x.pupil_diameter_mm,
        x.lenslet_pixel_beams_in_pupil,
        pair(x.pixel_beam_spacing_mm, 4)
    );
    let dx = &x.diffraction;
    s += &format!(
        "diffraction: {} ([optics] diffraction = \"{}\"); lambda / D at the {} mm pupil and lambda / w at the {} \
         lenslet aperture, arcmin:",
        if dx.mode == "none" { "off" } else { "on" },
        dx.mode,
        x.pupil_diameter_mm,
        dx.lenslet_aperture
    );
    for c in &dx.channels {
        s += &format!(" {} {:.0} nm {:.3} / {:.3};", c.channel, c.wavelength_nm, c.pupil_arcmin, c.lenslet_arcmin);
    }
    s.pop();
    s += "\n";
    s += &x.photometry.text();
    if let Some(l) = &x.lenslet {
        let cdp = |z: Option<f64>| z.map_or("none".to_string(), |z| format!("{z:.1}"));
        s += &format!(
            "real lenslet: {} (n_d {:.5}), {} mm thick: EFL {:.4} mm, back focal distance {:.4} mm (d line, 587.56 nm)\n",
            l.material, l.index_d, l.thickness_mm, l.efl_mm, l.bfd_mm
        );
        s += &format!(
            "  per channel at {:.1} / {:.1} / {:.1} nm (R / G / B): EFL {:.4} / {:.4} / {:.4} mm, central depth plane \
             {} / {} / {} mm\n",
            l.channel_wavelengths_nm[0],
            l.channel_wavelengths_nm[1],
            l.channel_wavelengths_nm[2],
            l.channel_efl_mm[0],
            l.channel_efl_mm[1],
            l.channel_efl_mm[2],
            cdp(l.channel_cdp_mm[0]),
            cdp(l.channel_cdp_mm[1]),
            cdp(l.channel_cdp_mm[2]),
        );
        if let (Some(z), Some(v)) = (l.intended_cdp_mm, l.v2_for_intended_cdp_mm) {
            s += &format!("  intended central depth plane {z:.1} mm (v2 = {v:.4} mm puts the d-line image there)\n");
        }
    }
    for w in &x.warnings {
        s += &format!("warning: {w}\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_display_design_numbers() {
        let x = display_design(&Display::paper(), 5.0);
        // One lenslet's viewing zone: m * EI pitch = 20 / 6.316 * 1.58 mm.
        let zone = 20.0 / 6.316 * 1.58;
        assert!((x.viewing_zone_mm[0] - zone).abs() < 1e-9, "{:?}", x.viewing_zone_mm);
        // The pitches are pupil-centred to 0.06 %: the eye box is the zone less the small drift.
        let b = x.eye_box_mm.unwrap();
        assert!(b[0] < zone && b[0] > zone - 0.1, "{b:?}");
        assert_eq!(b[0], b[1]);
        // LCD 21.6 mm at 26.316 mm: 2 atan(10.8 / 26.316) = 44.6 degrees.
        assert!((x.field_of_view_deg[0] - 2.0 * (10.8f64 / 26.316).atan().to_degrees()).abs() < 1e-12);
        // 0.01 mm pixels: 158 x 158 per elemental image, 24,964 in area.
        assert!((x.pixels_per_elemental_image - 24964.0).abs() < 1e-6);
        assert!((x.pixels_per_elemental_image_xy[0] - 158.0).abs() < 1e-6);
        // Views 0.0317 mm apart at the pupil: a 5 mm pupil holds about pi/4 (5 / 0.0317)^2.
        let spacing: f64 = 0.01 * 20.0 / 6.316;
        let disc = std::f64::consts::FRAC_PI_4 * (5.0 / spacing).powi(2);
        let beams = x.lenslet_pixel_beams_in_pupil as f64;
        assert!((beams - disc).abs() < 0.03 * disc, "{beams} vs {disc}");
        // Views across the pupil: 5 mm over 1.2 mm lenslets seen from the CDP, 1.2 z / (z - 20).
        let z = Display::paper().central_depth_plane().unwrap();
        let across = 5.0 / (1.2 * z / (z - 20.0));
        assert!((x.views_across_pupil.unwrap()[0] - across).abs() < 1e-12, "{:?}", x.views_across_pupil);
        assert!((3.9..4.0).contains(&across), "{across}");
        // CDP 385.7 mm: a pixel magnified by (385.7 - 20) / 6.316, seen from 385.7 mm.
        let z = Display::paper().central_depth_plane().unwrap();
        let ppd = 1.0 / (0.01 * (z - 20.0) / (6.316 * z)).to_degrees();
        assert!((x.pixels_per_degree.unwrap()[0] - ppd).abs() < 1e-9);
        assert!(ppd > 11.0 && ppd < 12.0, "{ppd}");
        assert!(x.warnings.is_empty(), "{:?}", x.warnings);
    }

    #[test]
    fn square_elemental_images_under_hexagonal_lenslets_warn() {
        let mut d = Display::paper();
        let p = 1.2;
        d.lenslets = Lattice::from_row_major(DVec2::ZERO, [p, 0.5 * p, 0.0, 0.75f64.sqrt() * p]).unwrap();
        let x = display_design(&d, 5.0);
        assert!(x.warnings.iter().any(|w| w.contains("hexagonal")), "{:?}", x.warnings);
        // A mismatched pitch ratio leaves no common eye box.
        let mut d = Display::paper();
        d.elemental_images = Lattice::square(2.0).unwrap();
        let x = display_design(&d, 5.0);
        assert!(x.eye_box_mm.is_none() && x.warnings.iter().any(|w| w.contains("no eye box")), "{x:?}");
    }
}
