//! A display designed from its intent (paper Sec. 2.2, Fig. 1d and 2a): the central depth plane
//! (CDP), the eye relief v1, the lenslets (their focal length, or a real thick lenslet), pitch and
//! lattice, and the LCD. The lenslet-to-LCD gap v2, the elemental-image pitch and both pitch
//! matrices follow paraxially, from the lenslet's principal planes (Gaussian optics: W. J. Smith,
//! "Modern Optical Engineering", 4th ed., Sec. 2.3-2.4). The thin lens of eq. (1) has both principal
//! planes at the lenslet plane; a thick lenslet ([`ThickLenslet`]) at the reference wavelength
//! [`D_LINE_NM`] has its effective focal length `f`, its front principal plane `h1` mm beyond its
//! front vertex and its back principal plane `h2` mm beyond its back vertex (both may be negative),
//! while the display's v1 runs to the front vertex and v2 from the back vertex. In air on both
//! sides the nodal points are the principal points. So, with `d = z_cdp - v1`:
//!
//! * **v2**: each lenslet images the LCD to a virtual image at the CDP, `d - h1` beyond its front
//!   principal plane, from `v2 - h2` behind its back principal plane:
//!   `1/(v2 - h2) = 1/f + 1/(d - h1)` (`v2 = h2 + f`, the back focal distance, for a CDP at
//!   infinity). This is the inverse of [`Display::central_depth_plane`]; for the thin lens
//!   (`h1 = h2 = 0`) it is `1/v2 = 1/f + 1/d`.
//! * **Elemental-image pitch**: lenslet (i, j)'s elemental image is centred where the ray from
//!   the eye's pupil centre through the lenslet's centre (its nodal points: aimed at the front
//!   one, it leaves the back one undeviated) meets the LCD, so the elemental-image lattice is the
//!   lenslet lattice scaled by `(v1 + h1 + v2 - h2) / (v1 + h1)` (`(v1 + v2) / v1` for the thin
//!   lens; the pitch matrix as a whole: square, hexagonal or any lattice keeps its shape).
//! * **Views across the pupil** (the paper's `l1 / W`, "4 x 4 rays within the pupil"): a point
//!   on the axis at the CDP sends rays through neighbouring lenslets' nodal points; they reach
//!   the pupil plane `W = p z / (z - v1 - h1)` apart, so a pupil of diameter `D` holds
//!   `N = D (z - v1 - h1) / (p z)` of them along the lattice's first axis (`D / p` for a CDP at
//!   infinity). Stated instead of the pitch, it gives `p = D (z - v1 - h1) / (N z)`. This is the
//!   same quantity as the resolution study's `views_across_pupil` (`resolution::limits`).
//!
//! Lattices by name: `square` (pitch matrix `p I`) and `hexagonal` (rows along x, the second
//! vector at 60 degrees: `[[p, p/2], [0, p sqrt(3)/2]]`, every lenslet's six neighbours at
//! distance `p`). Every input is checked here, naming the file and the field.

use glam::{DMat2, DVec2};
use serde::Serialize;

use super::display::{Display, Lcd};
use super::lattice::Lattice;
use super::lenslet::{LensletOptics, ThickLenslet, D_LINE_NM};
use crate::error::{Error, Result};

/// The lenslet lattice by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LatticeKind {
    /// Square cells of side `p`.
    Square,
    /// Hexagonal cells, neighbours `p` apart, rows along x.
    Hexagonal,
}

impl LatticeKind {
    /// Its name in a display file.
    pub fn name(self) -> &'static str {
        match self {
            LatticeKind::Square => "square",
            LatticeKind::Hexagonal => "hexagonal",
        }
    }

    /// The pitch matrix of this lattice with neighbour distance `p` (columns: lattice vectors).
    pub fn matrix(self, p: f64) -> DMat2 {
        match self {
            LatticeKind::Square => DMat2::from_diagonal(DVec2::splat(p)),
            LatticeKind::Hexagonal => DMat2::from_cols(DVec2::new(p, 0.0), DVec2::new(0.5 * p, 0.75f64.sqrt() * p)),
        }
    }
}

/// How the lenslet pitch is stated: directly, or by the views a pupil should hold.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PitchIntent {
    /// The lenslets' centre-to-centre distance, mm.
    Pitch(f64),
    /// Views across a pupil of this diameter (module documentation).
    Views {
        /// Views across the pupil, per axis.
        views: f64,
        /// The pupil's diameter, mm.
        pupil_diameter: f64,
    },
}

/// A display stated by intent (module documentation). Distances in mm from the pupil centre.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayIntent {
    /// Display name.
    pub name: String,
    /// z of the central depth plane from the pupil, mm (`inf`: at infinity).
    pub central_depth_plane: f64,
    /// v1: the eye relief, pupil plane to lenslet plane, mm.
    pub eye_to_lenslets: f64,
    /// The lenslets' focal length, mm (a thick lenslet's effective focal length at the d line,
    /// checked by [`DisplayIntent::validate`]).
    pub focal_length: f64,
    /// The lenslets' optics: the thin lens, or a real lenslet whose paraxial focal properties
    /// the derivation uses (its `design_cdp_mm` is set to the intent's CDP).
    pub lenslet: LensletOptics,
    /// The lenslet pitch, or the views it should give.
    pub pitch: PitchIntent,
    /// The lenslet lattice.
    pub lattice: LatticeKind,
    /// The LCD panel.
    pub lcd: Lcd,
    /// The LCD primaries, passed through.
    pub primaries: Option<super::spectrum::Primaries>,
    /// The panel's photometry, passed through.
    pub photometry: Option<super::photometry::Photometry>,
}

/// How the explicit display follows from the intent: every derived number, for `info`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Derivation {
    /// The CDP from the pupil, mm (`None`: at infinity).
    pub central_depth_plane_mm: Option<f64>,
    /// The CDP from the lenslets, `z - v1`, mm (`None`: at infinity).
    pub cdp_from_lenslets_mm: Option<f64>,
    /// v1, mm.
    pub eye_to_lenslets_mm: f64,
    /// f, mm (a thick lenslet's effective focal length at the d line).
    pub focal_length_mm: f64,
    /// The lenslet the derivation is for: "paraxial" or a thick lenslet's material.
    pub lenslet: String,
    /// The wavelength of a thick lenslet's focal properties, nm (`None`: the thin lens).
    pub reference_wavelength_nm: Option<f64>,
    /// The front principal plane, mm beyond the front vertex (0 for the thin lens).
    pub front_principal_plane_mm: f64,
    /// The back principal plane, mm beyond the back vertex (0 for the thin lens).
    pub back_principal_plane_mm: f64,
    /// Derived v2, mm: `h2 + 1 / (1/f + 1/(z - v1 - h1))`.
    pub lenslets_to_lcd_mm: f64,
    /// The lattice's name.
    pub lattice: LatticeKind,
    /// Lenslet neighbour distance, mm (stated, or from the views).
    pub lenslet_pitch_mm: f64,
    /// `(v1 + h1 + v2 - h2) / (v1 + h1)`: the elemental-image lattice over the lenslet lattice.
    pub projection_scale: f64,
    /// Elemental-image neighbour distance, mm.
    pub elemental_image_pitch_mm: f64,
    /// Lenslet pitch matrix, row-major, mm.
    pub lenslet_matrix_mm: [f64; 4],
    /// Elemental-image pitch matrix, row-major, mm.
    pub elemental_image_matrix_mm: [f64; 4],
    /// The pupil the views are counted for, mm.
    pub pupil_diameter_mm: f64,
    /// Views across that pupil along the lattice's first axis.
    pub views_across_pupil: f64,
    /// Lateral magnification of the LCD at the CDP, `(d - h1) / (v2 - h2)` (`None`: CDP at infinity).
    pub magnification: Option<f64>,
}

/// The pupil diameter the views are reported for when the intent states a pitch (the paper's).
pub const DEFAULT_PUPIL_MM: f64 = 5.0;

/// How far (relative) a stated `focal_length` may be from a thick lenslet's effective focal
/// length at the d line.
pub const FOCAL_LENGTH_AGREEMENT: f64 = 1e-3;

impl DisplayIntent {
    /// Checks the intent, naming `source` and the field (`intent.central_depth_plane`).
    pub fn validate(&self, source: &str) -> Result<()> {
        let positive = |field: &str, v: f64| -> Result<()> {
            if !v.is_finite() {
                Err(Error::invalid(source, format!("intent.{field}"), format!("must be a finite number, got {v}")))
            } else if v <= 0.0 {
                Err(Error::invalid(source, format!("intent.{field}"), format!("must be positive, got {v}")))
            } else {
                Ok(())
            }
        };
        positive("eye_to_lenslets", self.eye_to_lenslets)?;
        if let Some(t) = self.lenslet.thick() {
            self.validate_thick(t, source)?;
        }
        positive("focal_length", self.focal_length)?;
        let z = self.central_depth_plane;
        if z.is_nan() || z == f64::NEG_INFINITY {
            return Err(Error::invalid(
                source,
                "intent.central_depth_plane",
                format!("must be a distance from the pupil in mm (or inf), got {z}"),
            ));
        }
        if z <= self.eye_to_lenslets {
            return Err(Error::invalid(
                source,
                "intent.central_depth_plane",
                format!(
                    "{z} mm is not beyond the lenslets at v1 = {} mm: the central depth plane is the lenslets' \
                     virtual image of the LCD, behind the lenslets as seen from the eye (a real image in front of \
                     them is not a near-eye InIm display)",
                    self.eye_to_lenslets
                ),
            ));
        }
        match self.pitch {
            PitchIntent::Pitch(p) => positive("lenslet_pitch", p)?,
            PitchIntent::Views { views, pupil_diameter } => {
                positive("views_across_pupil", views)?;
                positive("pupil_diameter", pupil_diameter)?;
            }
        }
        Ok(())
    }

    /// A thick lenslet's own checks before the derivation (the display's validation checks it
    /// against the lattice afterwards): a positive thickness, a converging lenslet, and no second
    /// statement of the focal length or the CDP that disagrees with it.
    fn validate_thick(&self, t: &ThickLenslet, source: &str) -> Result<()> {
        if !(t.thickness.is_finite() && t.thickness > 0.0) {
            return Err(Error::invalid(
                source,
                "lenslet.thickness",
                format!("must be positive and finite, got {}", t.thickness),
            ));
        }
        if t.design_cdp_mm.is_some() {
            return Err(Error::invalid(
                source,
                "lenslet.design_cdp_mm",
                "a display stated by [intent] designs for intent.central_depth_plane; remove lenslet.design_cdp_mm",
            ));
        }
        let efl = t.paraxial(D_LINE_NM).efl;
        if !(efl.is_finite() && efl > 0.0) {
            return Err(Error::invalid(
                source,
                "lenslet.front",
                format!(
                    "the lenslet's effective focal length at the d line is {efl} mm: a display stated by [intent] \
                     needs converging lenslets"
                ),
            ));
        }
        if (self.focal_length - efl).abs() > FOCAL_LENGTH_AGREEMENT * efl {
            return Err(Error::invalid(
                source,
                "intent.focal_length",
                format!(
                    "{} mm disagrees with the thick lenslet's effective focal length {efl:.6} mm (d line, {D_LINE_NM} \
                     nm) by more than {}%: omit intent.focal_length (the lenslet's surfaces give it) or change the \
                     lenslet",
                    self.focal_length,
                    100.0 * FOCAL_LENGTH_AGREEMENT
                ),
            ));
        }
        Ok(())
    }

    /// The lenslets' focal length and principal planes `(f, h1, h2)`: the thin lens's `(f, 0, 0)`,
    /// or a thick lenslet's at the d line (module documentation).
    pub fn focal_properties(&self) -> (f64, f64, f64) {
        match self.lenslet.thick() {
            None => (self.focal_length, 0.0, 0.0),
            Some(t) => {
                let p = t.paraxial(D_LINE_NM);
                let (h1, h2) = p.principal_planes();
                (p.efl, h1, h2)
            }
        }
    }

    /// The derivation (module documentation); call [`DisplayIntent::validate`] first.
    pub fn derive(&self) -> Derivation {
        let (z, v1) = (self.central_depth_plane, self.eye_to_lenslets);
        let (f, h1, h2) = self.focal_properties();
        let d = z - v1;
        // The CDP from the front principal plane, the LCD from the back one (both d and v2 for the thin lens).
        let image = d - h1;
        let v2 = h2 + 1.0 / (1.0 / f + 1.0 / image);
        // Rays from the CDP's axial point through neighbouring lenslets' nodal points are p z / (z - v1 - h1)
        // apart at the pupil.
        let spread = if z.is_finite() { image / z } else { 1.0 };
        let (p, pupil) = match self.pitch {
            PitchIntent::Pitch(p) => (p, DEFAULT_PUPIL_MM),
            PitchIntent::Views { views, pupil_diameter } => (pupil_diameter * spread / views, pupil_diameter),
        };
        let scale = (v1 + h1 + v2 - h2) / (v1 + h1);
        let lenslets = self.lattice.matrix(p);
        let eis = lenslets * scale;
        let row_major = |m: DMat2| [m.x_axis.x, m.y_axis.x, m.x_axis.y, m.y_axis.y];
        Derivation {
            central_depth_plane_mm: z.is_finite().then_some(z),
            cdp_from_lenslets_mm: z.is_finite().then_some(d),
            eye_to_lenslets_mm: v1,
            focal_length_mm: f,
            lenslet: match self.lenslet.thick() {
                None => "paraxial".into(),
                Some(t) => format!("thick {}", t.material.name),
            },
            reference_wavelength_nm: self.lenslet.thick().map(|_| D_LINE_NM),
            front_principal_plane_mm: h1,
            back_principal_plane_mm: h2,
            lenslets_to_lcd_mm: v2,
            lattice: self.lattice,
            lenslet_pitch_mm: p,
            projection_scale: scale,
            elemental_image_pitch_mm: p * scale,
            lenslet_matrix_mm: row_major(lenslets),
            elemental_image_matrix_mm: row_major(eis),
            pupil_diameter_mm: pupil,
            views_across_pupil: pupil * spread / p,
            magnification: z.is_finite().then_some(image / (v2 - h2)),
        }
    }

    /// The explicit display and its derivation; errors name `source` and the field.
    pub fn to_display(&self, source: &str) -> Result<(Display, Derivation)> {
        self.validate(source)?;
        let x = self.derive();
        let lattice = |m: [f64; 4], field: &str| {
            Lattice::from_row_major(DVec2::ZERO, m).ok_or_else(|| Error::Lattice {
                source_name: source.to_string(),
                field: field.to_string(),
                message: format!("the derived pitch matrix {m:?} is singular or not finite"),
            })
        };
        let d = Display {
            name: self.name.clone(),
            eye_to_lenslets: x.eye_to_lenslets_mm,
            lenslets_to_lcd: x.lenslets_to_lcd_mm,
            focal_length: x.focal_length_mm,
            lenslets: lattice(x.lenslet_matrix_mm, "intent.lenslet_pitch")?,
            elemental_images: lattice(x.elemental_image_matrix_mm, "intent.lenslet_pitch")?,
            lcd: self.lcd,
            primaries: self.primaries.clone(),
            photometry: self.photometry,
            lenslet: match &self.lenslet {
                LensletOptics::Paraxial => LensletOptics::Paraxial,
                LensletOptics::Thick(t) => LensletOptics::Thick(Box::new(ThickLenslet {
                    design_cdp_mm: self.central_depth_plane.is_finite().then_some(self.central_depth_plane),
                    ..(**t).clone()
                })),
            },
        };
        if let Some(p) = &d.primaries {
            p.validate(source)?;
        }
        d.validate(source).map_err(|e| match e {
            // Name the intent's fields; v2 is derived: name the fields it came from.
            Error::Invalid { source_name, field, message } => {
                let (field, message) = match field.split(' ').next().unwrap_or("") {
                    "lenslets_to_lcd" => (
                        "intent.central_depth_plane".to_string(),
                        format!("with intent.focal_length gives lenslets_to_lcd (v2), which {message}"),
                    ),
                    "eye_to_lenslets" => ("intent.eye_to_lenslets".into(), message),
                    "focal_length" => ("intent.focal_length".into(), message),
                    _ => (field, message),
                };
                Error::Invalid { source_name, field, message }
            }
            other => other,
        })?;
        Ok((d, x))
    }
}

impl Derivation {
    /// The derivation as the lines `info` prints.
    pub fn text(&self) -> String {
        let v1 = self.eye_to_lenslets_mm;
        if let Some(nm) = self.reference_wavelength_nm {
            return self.thick_text(nm);
        }
        let mut s = String::from("display stated by intent; derived paraxially (thin lenslets):\n");
        s += &match (self.central_depth_plane_mm, self.cdp_from_lenslets_mm) {
            (Some(z), Some(d)) => format!(
                "  v2 = 1 / (1/f + 1/(z_cdp - v1)) = 1 / (1/{} + 1/({z} - {v1})) = {:.6} mm (the LCD imaged {d} mm \
                 beyond the lenslets, magnified {:.3}x)\n",
                self.focal_length_mm,
                self.lenslets_to_lcd_mm,
                self.magnification.unwrap_or(f64::NAN)
            ),
            _ => format!("  v2 = f = {} mm (central depth plane at infinity)\n", self.lenslets_to_lcd_mm),
        };
        s += &format!(
            "  elemental-image pitch = lenslet pitch x (v1 + v2) / v1 = {} x {:.9} = {:.6} mm ({} lattice)\n",
            self.lenslet_pitch_mm,
            self.projection_scale,
            self.elemental_image_pitch_mm,
            self.lattice.name()
        );
        s += &self.matrices_text();
        s += &format!(
            "  views across a {} mm pupil from a point at the CDP: {:.3} (pupil x (z_cdp - v1) / (pitch x z_cdp))\n",
            self.pupil_diameter_mm, self.views_across_pupil
        );
        s
    }

    fn matrices_text(&self) -> String {
        let m = |a: [f64; 4]| format!("[[{:.6}, {:.6}], [{:.6}, {:.6}]]", a[0], a[1], a[2], a[3]);
        format!(
            "  lenslet pitch matrix {} mm\n  elemental-image pitch matrix {} mm\n",
            m(self.lenslet_matrix_mm),
            m(self.elemental_image_matrix_mm)
        )
    }

    /// [`Derivation::text`] for a thick lenslet: the same steps through its principal planes.
    fn thick_text(&self, nm: f64) -> String {
        let (v1, f, h1, h2) = (
            self.eye_to_lenslets_mm,
            self.focal_length_mm,
            self.front_principal_plane_mm,
            self.back_principal_plane_mm,
        );
        let mut s = format!(
            "display stated by intent; derived paraxially from the {} lenslet's focal properties at {nm} nm: \
             EFL f = {f:.6} mm, front principal plane h1 = {h1:.6} mm beyond the front vertex, back principal plane \
             h2 = {h2:.6} mm beyond the back vertex (v1 to the front vertex, v2 from the back vertex):\n",
            self.lenslet
        );
        s += &match self.central_depth_plane_mm {
            Some(z) => format!(
                "  v2 = h2 + 1 / (1/f + 1/(z_cdp - v1 - h1)) = {h2:.6} + 1 / (1/{f:.6} + 1/({z} - {v1} - {h1:.6})) = \
                 {:.6} mm (the LCD imaged at the CDP, magnified {:.3}x)\n",
                self.lenslets_to_lcd_mm,
                self.magnification.unwrap_or(f64::NAN)
            ),
            None => format!(
                "  v2 = h2 + f = {:.6} mm, the back focal distance (central depth plane at infinity)\n",
                self.lenslets_to_lcd_mm
            ),
        };
        s += &format!(
            "  elemental-image pitch = lenslet pitch x (v1 + h1 + v2 - h2) / (v1 + h1) = {} x {:.9} = {:.6} mm ({} \
             lattice; the ray from the pupil centre through each lenslet's nodal points)\n",
            self.lenslet_pitch_mm,
            self.projection_scale,
            self.elemental_image_pitch_mm,
            self.lattice.name()
        );
        s += &self.matrices_text();
        s += &format!(
            "  views across a {} mm pupil from a point at the CDP: {:.3} (pupil x (z_cdp - v1 - h1) / (pitch x \
             z_cdp))\n",
            self.pupil_diameter_mm, self.views_across_pupil
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> DisplayIntent {
        DisplayIntent {
            name: "paper by intent".into(),
            central_depth_plane: 385.7,
            eye_to_lenslets: 20.0,
            focal_length: 6.427,
            pitch: PitchIntent::Pitch(1.2),
            lattice: LatticeKind::Square,
            lcd: Display::paper().lcd,
            primaries: None,
            photometry: None,
            lenslet: LensletOptics::Paraxial,
        }
    }

    #[test]
    fn the_derived_gap_puts_the_cdp_back_where_it_was_stated() {
        for z in [385.7, 30.0, 1e4] {
            let i = DisplayIntent { central_depth_plane: z, ..paper() };
            let (d, _) = i.to_display("x").unwrap();
            assert!((d.central_depth_plane().unwrap() - z).abs() < 1e-9 * z, "{z}");
        }
        let i = DisplayIntent { central_depth_plane: f64::INFINITY, ..paper() };
        let (d, x) = i.to_display("x").unwrap();
        assert_eq!(d.lenslets_to_lcd, 6.427);
        assert!((x.views_across_pupil - 5.0 / 1.2).abs() < 1e-12);
    }

    #[test]
    fn views_give_the_pitch_that_gives_them_back() {
        let i = DisplayIntent { pitch: PitchIntent::Views { views: 4.0, pupil_diameter: 5.0 }, ..paper() };
        let x = i.derive();
        // p = 5 x 365.7 / (4 x 385.7).
        assert!((x.lenslet_pitch_mm - 5.0 * 365.7 / (4.0 * 385.7)).abs() < 1e-12);
        assert!((x.views_across_pupil - 4.0).abs() < 1e-12);
        let stated = DisplayIntent { pitch: PitchIntent::Pitch(x.lenslet_pitch_mm), ..paper() }.derive();
        assert!((stated.views_across_pupil - 4.0).abs() < 1e-12);
    }

    #[test]
    fn hexagonal_neighbours_are_one_pitch_apart_and_the_eis_scale_with_them() {
        let i = DisplayIntent { lattice: LatticeKind::Hexagonal, pitch: PitchIntent::Pitch(1.0), ..paper() };
        let (d, x) = i.to_display("x").unwrap();
        let m = d.lenslets.matrix;
        for v in [m.x_axis, m.y_axis, m.y_axis - m.x_axis] {
            assert!((v.length() - 1.0).abs() < 1e-15, "{v}");
        }
        let e = d.elemental_images.matrix;
        assert!((e - m * x.projection_scale).abs_diff_eq(DMat2::ZERO, 0.0));
        assert!((x.projection_scale - (20.0 + d.lenslets_to_lcd) / 20.0).abs() < 1e-15);
    }

    #[test]
    fn a_thick_lenslet_of_zero_thickness_derives_the_thin_lens_display() {
        use super::super::lenslet::{Material, Surface};
        // Biconvex, equal radii: f = R / (2 (n - 1)) at zero thickness.
        let m = Material::n_bk7();
        let n = m.index(D_LINE_NM);
        let thin = DisplayIntent { focal_length: 5.0, lattice: LatticeKind::Hexagonal, ..paper() };
        let r = 2.0 * (n - 1.0) * 5.0;
        let t = ThickLenslet {
            front: Surface { radius: r, conic: -0.3 },
            back: Surface { radius: -r, conic: 0.0 },
            thickness: 0.0,
            material: m,
            design_cdp_mm: None,
        };
        for pitch in [PitchIntent::Pitch(1.0), PitchIntent::Views { views: 4.0, pupil_diameter: 5.0 }] {
            for z in [385.7, 1e4, f64::INFINITY] {
                let a = DisplayIntent { pitch, central_depth_plane: z, ..thin.clone() };
                let b = DisplayIntent { lenslet: LensletOptics::Thick(Box::new(t.clone())), ..a.clone() };
                let (x, y) = (a.derive(), b.derive());
                assert_eq!((y.front_principal_plane_mm, y.back_principal_plane_mm), (0.0, 0.0));
                assert!((x.focal_length_mm - y.focal_length_mm).abs() < 1e-12);
                for (p, q) in [
                    (x.lenslets_to_lcd_mm, y.lenslets_to_lcd_mm),
                    (x.projection_scale, y.projection_scale),
                    (x.lenslet_pitch_mm, y.lenslet_pitch_mm),
                    (x.views_across_pupil, y.views_across_pupil),
                ] {
                    assert!((p - q).abs() < 1e-12, "{z}: {p} {q}");
                }
                for (p, q) in x.elemental_image_matrix_mm.iter().zip(y.elemental_image_matrix_mm) {
                    assert!((p - q).abs() < 1e-12, "{z}: {p} {q}");
                }
            }
        }
    }

    #[test]
    fn hostile_intent_is_refused_naming_the_field() {
        let cases: Vec<(DisplayIntent, &str)> = vec![
            (DisplayIntent { central_depth_plane: 15.0, ..paper() }, "intent.central_depth_plane"),
            (DisplayIntent { central_depth_plane: 20.0, ..paper() }, "intent.central_depth_plane"),
            (DisplayIntent { central_depth_plane: -400.0, ..paper() }, "intent.central_depth_plane"),
            (DisplayIntent { central_depth_plane: f64::NAN, ..paper() }, "intent.central_depth_plane"),
            (DisplayIntent { focal_length: -6.0, ..paper() }, "intent.focal_length"),
            (DisplayIntent { focal_length: f64::NAN, ..paper() }, "intent.focal_length"),
            (DisplayIntent { eye_to_lenslets: 0.0, ..paper() }, "intent.eye_to_lenslets"),
            (DisplayIntent { pitch: PitchIntent::Pitch(f64::INFINITY), ..paper() }, "intent.lenslet_pitch"),
            (
                DisplayIntent { pitch: PitchIntent::Views { views: -4.0, pupil_diameter: 5.0 }, ..paper() },
                "intent.views_across_pupil",
            ),
            (
                DisplayIntent { pitch: PitchIntent::Views { views: 4.0, pupil_diameter: f64::NAN }, ..paper() },
                "intent.pupil_diameter",
            ),
        ];
        for (i, field) in cases {
            let e = i.to_display("d.toml").unwrap_err().to_string();
            assert!(e.contains("d.toml") && e.contains(field), "{field}: {e}");
        }
    }
}
