//! A display designed from its intent (paper Sec. 2.2, Fig. 1d and 2a): the central depth plane
//! (CDP), the eye relief v1, the lenslets' focal length, pitch and lattice, and the LCD. The
//! lenslet-to-LCD gap v2, the elemental-image pitch and both pitch matrices follow paraxially:
//!
//! * **v2**: each lenslet, a thin lens of focal length `f` (eq. (1)'s `d2 = 1/f`), images the
//!   LCD to a virtual image at the CDP, `d = z_cdp - v1` in front of the lenslets:
//!   `1/v2 = 1/f + 1/d` (`v2 = f` for a CDP at infinity). This is the inverse of
//!   [`Display::central_depth_plane`].
//! * **Elemental-image pitch**: lenslet (i, j)'s elemental image is centred where the ray from
//!   the eye's pupil centre through the lenslet's centre meets the LCD, so the elemental-image
//!   lattice is the lenslet lattice scaled by `(v1 + v2) / v1` (the pitch matrix as a whole:
//!   square, hexagonal or any lattice keeps its shape).
//! * **Views across the pupil** (the paper's `l1 / W`, "4 x 4 rays within the pupil"): a point
//!   on the axis at the CDP sends rays through neighbouring lenslet centres; they reach the
//!   pupil plane `W = p z / (z - v1)` apart, so a pupil of diameter `D` holds
//!   `N = D (z - v1) / (p z)` of them along the lattice's first axis (`D / p` for a CDP at
//!   infinity). Stated instead of the pitch, it gives `p = D (z - v1) / (N z)`. This is the
//!   same quantity as the resolution study's `views_across_pupil` (`resolution::limits`).
//!
//! Lattices by name: `square` (pitch matrix `p I`) and `hexagonal` (rows along x, the second
//! vector at 60 degrees: `[[p, p/2], [0, p sqrt(3)/2]]`, every lenslet's six neighbours at
//! distance `p`). Every input is checked here, naming the file and the field.

use glam::{DMat2, DVec2};
use serde::Serialize;

use super::display::{Display, Lcd};
use super::lattice::Lattice;
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
    /// The lenslets' focal length, mm.
    pub focal_length: f64,
    /// The lenslet pitch, or the views it should give.
    pub pitch: PitchIntent,
    /// The lenslet lattice.
    pub lattice: LatticeKind,
    /// The LCD panel.
    pub lcd: Lcd,
    /// The LCD primaries, passed through.
    pub primaries: Option<super::spectrum::Primaries>,
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
    /// f, mm.
    pub focal_length_mm: f64,
    /// Derived v2, mm: `1 / (1/f + 1/(z - v1))`.
    pub lenslets_to_lcd_mm: f64,
    /// The lattice's name.
    pub lattice: LatticeKind,
    /// Lenslet neighbour distance, mm (stated, or from the views).
    pub lenslet_pitch_mm: f64,
    /// `(v1 + v2) / v1`: the elemental-image lattice over the lenslet lattice.
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
    /// Lateral magnification of the LCD at the CDP, `d / v2` (`None`: CDP at infinity).
    pub magnification: Option<f64>,
}

/// The pupil diameter the views are reported for when the intent states a pitch (the paper's).
pub const DEFAULT_PUPIL_MM: f64 = 5.0;

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

    /// The derivation (module documentation); call [`DisplayIntent::validate`] first.
    pub fn derive(&self) -> Derivation {
        let (z, v1, f) = (self.central_depth_plane, self.eye_to_lenslets, self.focal_length);
        let d = z - v1;
        let v2 = 1.0 / (1.0 / f + 1.0 / d);
        // Rays from the CDP's axial point through neighbouring lenslets are p z / (z - v1) apart at the pupil.
        let spread = if z.is_finite() { d / z } else { 1.0 };
        let (p, pupil) = match self.pitch {
            PitchIntent::Pitch(p) => (p, DEFAULT_PUPIL_MM),
            PitchIntent::Views { views, pupil_diameter } => (pupil_diameter * spread / views, pupil_diameter),
        };
        let scale = (v1 + v2) / v1;
        let lenslets = self.lattice.matrix(p);
        let eis = lenslets * scale;
        let row_major = |m: DMat2| [m.x_axis.x, m.y_axis.x, m.x_axis.y, m.y_axis.y];
        Derivation {
            central_depth_plane_mm: z.is_finite().then_some(z),
            cdp_from_lenslets_mm: z.is_finite().then_some(d),
            eye_to_lenslets_mm: v1,
            focal_length_mm: f,
            lenslets_to_lcd_mm: v2,
            lattice: self.lattice,
            lenslet_pitch_mm: p,
            projection_scale: scale,
            elemental_image_pitch_mm: p * scale,
            lenslet_matrix_mm: row_major(lenslets),
            elemental_image_matrix_mm: row_major(eis),
            pupil_diameter_mm: pupil,
            views_across_pupil: pupil * spread / p,
            magnification: z.is_finite().then_some(d / v2),
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
            lenslet: super::lenslet::LensletOptics::Paraxial,
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
        let m = |a: [f64; 4]| format!("[[{:.6}, {:.6}], [{:.6}, {:.6}]]", a[0], a[1], a[2], a[3]);
        s += &format!("  lenslet pitch matrix {} mm\n", m(self.lenslet_matrix_mm));
        s += &format!("  elemental-image pitch matrix {} mm\n", m(self.elemental_image_matrix_mm));
        s += &format!(
            "  views across a {} mm pupil from a point at the CDP: {:.3} (pupil x (z_cdp - v1) / (pitch x z_cdp))\n",
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
