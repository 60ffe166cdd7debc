//! The eye: a thin lens at the pupil plane with the retina behind it (paper Sec. 2.3, planes P0
//! and P1 of Fig. 2a; Sec. 4.1 "Pinhole" and "Realistic" camera models).
//!
//! The pupil centre is at `position` (the origin by default); the optical axis is +z. The retina
//! lies at `z = -v0`. Retinal images are stored upright: pixel (r, c) is the direction with
//! tangents `tx = -T + (c + 0.5) 2T/n`, `ty = T - (r + 0.5) 2T/n`; the physical retina point is
//! `-v0` times that. The lens power is `d1 = 1/v0 + 1/z_focus`, so every ray from one retina
//! point leaves the lens toward one point of the focal plane `z = z_focus`.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::limits;

pub mod accommodation;
pub mod arizona;
pub mod conic;
pub mod describe;
pub mod gaze;
pub mod le_grand;
pub mod medium;
pub mod model;
mod monomials;
pub mod navarro;
pub mod oblique;
pub mod paraxial;
pub mod pupil;
pub mod ray_map;
pub mod refract;
pub mod schematic;
pub mod settings;
pub mod stiles_crawford;
pub mod trace;
pub mod user;
pub mod user_accommodation;

use crate::error::{Error, Result};
pub use gaze::{CentreOfRotation, EyePose, Gaze};
pub use medium::Dispersion;
pub use model::{EyeModel, FocusCriterion};
pub use oblique::{oblique_foci, ObliqueFoci};
pub use paraxial::Paraxial;
pub use schematic::SchematicEye;
pub use trace::EyeAtWavelength;
pub use user::{UserEye, UserIris, UserSurface};

pub mod rays;
pub use rays::{EyeOptics, EyeOpticsSpec};

/// Where the eye is focused.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Focus {
    /// Focus distance from the pupil, mm (`f64::INFINITY` allowed).
    Millimetres(f64),
    /// Focus in diopters (1000 / mm); 0 D is infinity.
    Diopters(f64),
}

impl Focus {
    /// Vergence of the focal plane, 1/mm (0 for infinity).
    pub fn vergence(&self) -> f64 {
        match *self {
            Focus::Millimetres(z) => 1.0 / z,
            Focus::Diopters(d) => d / 1000.0,
        }
    }
    /// Focus distance in mm (infinite for 0 D).
    pub fn distance_mm(&self) -> f64 {
        match *self {
            Focus::Millimetres(z) => z,
            Focus::Diopters(d) => 1000.0 / d,
        }
    }
    /// The focus as vergence in dioptres (1000 / mm; 0 D for infinity).
    pub fn diopters(&self) -> f64 {
        1000.0 * self.vergence()
    }
}

/// The eye's aperture model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aperture {
    /// A pinhole at the pupil centre: everything in focus.
    Pinhole,
    /// A thin lens with a circular pupil.
    ThinLens {
        /// Pupil diameter, mm.
        pupil_diameter: f64,
        /// Where the lens is focused.
        focus: Focus,
    },
}

impl Aperture {
    /// The aperture an eye is stated with everywhere (experiment `eye_cases`, the CLI's eye
    /// flags, Python's `Eye`): exactly one of a pinhole, a focus distance in mm or a focus in
    /// diopters, the lens with a pupil of `pupil_diameter` mm. `None` when not exactly one is
    /// given; the caller names its own fields in the error. The values are checked with the
    /// rest of the eye ([`Eye::validate`]).
    pub fn stated(
        pinhole: bool,
        focus_mm: Option<f64>,
        focus_diopters: Option<f64>,
        pupil_diameter: f64,
    ) -> Option<Self> {
        match (pinhole, focus_mm, focus_diopters) {
            (true, None, None) => Some(Aperture::Pinhole),
            (false, Some(mm), None) => Some(Aperture::ThinLens { pupil_diameter, focus: Focus::Millimetres(mm) }),
            (false, None, Some(d)) => Some(Aperture::ThinLens { pupil_diameter, focus: Focus::Diopters(d) }),
            _ => None,
        }
    }
}

/// The eye model.
#[derive(Clone, Debug, PartialEq)]
pub struct Eye {
    /// v0: pupil-to-retina distance, mm (17 mm by default).
    pub retina_distance: f64,
    /// Pinhole or thin lens.
    pub aperture: Aperture,
    /// Pupil sampling: an n x n grid of cell centres over the pupil's bounding square, keeping
    /// those inside the circle (n = 8 gives 52 samples).
    pub pupil_grid: usize,
    /// Pupil centre (the origin by default).
    pub position: DVec3,
    /// A schematic eye, the display primaries' wavelengths or the Stiles-Crawford effect
    /// ([`rays`]); `None`: the paper's thin lens, traced by the fast paths.
    pub optics: Option<std::sync::Arc<EyeOptics>>,
    /// The eye turned to a gaze about its centre of rotation ([`gaze`]): every ray of the eye at
    /// rest moved by it. `None`: straight ahead, the eye at rest.
    pub pose: Option<EyePose>,
}

impl Eye {
    /// The paper's pinhole eye: v0 = 17 mm, one chief ray through the pupil centre at the origin.
    pub fn pinhole() -> Self {
        Self {
            retina_distance: 17.0,
            aperture: Aperture::Pinhole,
            pupil_grid: 1,
            position: DVec3::ZERO,
            optics: None,
            pose: None,
        }
    }

    /// A thin-lens eye (v0 = 17 mm, pupil centre at the origin): pupil diameter in mm, its focus,
    /// and an n x n pupil grid (kept inside the circle; n = 8 gives 52 samples).
    pub fn thin_lens(pupil_diameter: f64, focus: Focus, pupil_grid: usize) -> Self {
        Self {
            retina_distance: 17.0,
            aperture: Aperture::ThinLens { pupil_diameter, focus },
            pupil_grid,
            position: DVec3::ZERO,
            optics: None,
            pose: None,
        }
    }

    /// Optical power d1 (1/mm) of the eye lens: `1/v0 + 1/z_focus` (pinhole: `1/v0`, which
    /// leaves the chief ray's slope unchanged).
    pub fn power(&self) -> f64 {
        match self.aperture {
            Aperture::Pinhole => 1.0 / self.retina_distance,
            Aperture::ThinLens { focus, .. } => 1.0 / self.retina_distance + focus.vergence(),
        }
    }

    /// Pupil sample offsets from the pupil centre, in the pupil plane (mm).
    pub fn pupil_samples(&self) -> Vec<DVec2> {
        match self.aperture {
            Aperture::Pinhole => vec![DVec2::ZERO],
            Aperture::ThinLens { pupil_diameter, .. } => pupil_grid(pupil_diameter, self.pupil_grid),
        }
    }

    /// Checks the eye's parameters; `source` names where they came from.
    pub fn validate(&self, source: &str) -> Result<()> {
        if !(self.retina_distance.is_finite() && self.retina_distance > 0.0) {
            return Err(Error::invalid(
                source,
                "retina_distance",
                format!("must be a positive finite number, got {}", self.retina_distance),
            ));
        }
        if !self.position.is_finite() {
            return Err(Error::invalid(source, "eye_position", "must be finite"));
        }
        limits::RETINA_DISTANCE.check(source, "retina_distance", self.retina_distance)?;
        for (axis, v) in ["x", "y", "z"].iter().zip(self.position.to_array()) {
            limits::EYE_POSITION.check(source, &format!("position.{axis}"), v)?;
        }
        if let Aperture::ThinLens { pupil_diameter, focus } = self.aperture {
            if !(pupil_diameter.is_finite() && pupil_diameter > 0.0) {
                return Err(Error::invalid(
                    source,
                    "pupil_diameter",
                    format!("must be a positive finite number (use a pinhole eye for zero), got {pupil_diameter}"),
                ));
            }
            match focus {
                Focus::Millimetres(z) if z.is_nan() || z <= 0.0 => {
                    return Err(Error::invalid(
                        source,
                        "focus_mm",
                        format!("must be positive (inf for infinity), got {z}"),
                    ))
                }
                Focus::Diopters(d) if !d.is_finite() || d < 0.0 => {
                    return Err(Error::invalid(
                        source,
                        "focus_diopters",
                        format!("must be finite and >= 0 (0 D is infinity), got {d}"),
                    ))
                }
                _ => {}
            }
            limits::PUPIL_DIAMETER.check(source, "pupil_diameter", pupil_diameter)?;
            match focus {
                Focus::Millimetres(z) if z.is_finite() => limits::FOCUS_MM.check(source, "focus_mm", z)?,
                Focus::Diopters(d) => limits::FOCUS_DIOPTERS.check(source, "focus_diopters", d)?,
                _ => {}
            }
            if self.pupil_grid == 0 || self.pupil_grid > 1024 {
                return Err(Error::invalid(
                    source,
                    "pupil_grid",
                    format!("must be between 1 and 1024, got {}", self.pupil_grid),
                ));
            }
        }
        Ok(())
    }
}

/// Cell centres of an n x n grid over the square [-D/2, D/2]^2, kept when inside the pupil
/// circle (distance <= D/2). Rows are emitted top to bottom, columns left to right.
pub fn pupil_grid(diameter: f64, n: usize) -> Vec<DVec2> {
    let r = 0.5 * diameter;
    let mut out = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let p = DVec2::new(-r + (i as f64 + 0.5) * diameter / n as f64, r - (j as f64 + 0.5) * diameter / n as f64);
            if p.length_squared() <= r * r {
                out.push(p);
            }
        }
    }
    out
}

/// The retina's sampling: n x n pixels over tangents +-T, with k x k stratified samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Retina {
    /// n: retina pixels per side.
    pub resolution: usize,
    /// T: the retina covers tangents -T..T in x and y.
    pub half_tangent: f64,
    /// k: k x k samples per pixel, at the centres of a k x k subdivision (1 = pixel centre).
    pub samples_per_pixel: usize,
}

impl Default for Retina {
    fn default() -> Self {
        Self { resolution: 512, half_tangent: 0.3, samples_per_pixel: 1 }
    }
}

impl Retina {
    /// Tangents of the direction seen by the point `frac` (in `[0, 1]^2`) of pixel (row, col).
    #[inline]
    pub fn tangent(&self, row: usize, col: usize, frac: DVec2) -> DVec2 {
        let step = 2.0 * self.half_tangent / self.resolution as f64;
        DVec2::new(-self.half_tangent + (col as f64 + frac.x) * step, self.half_tangent - (row as f64 + frac.y) * step)
    }

    /// Sub-pixel sample positions (fractions of a pixel).
    pub fn subpixel_offsets(&self) -> Vec<DVec2> {
        stratified(self.samples_per_pixel)
    }

    /// Checks the resolution (1 to 32768), the half tangent and the samples per pixel; errors name `source`.
    pub fn validate(&self, source: &str) -> Result<()> {
        if self.resolution == 0 || self.resolution > 1 << 15 {
            return Err(Error::invalid(
                source,
                "retina_resolution",
                format!("must be between 1 and 32768, got {}", self.resolution),
            ));
        }
        if !(self.half_tangent.is_finite() && self.half_tangent > 0.0) {
            return Err(Error::invalid(
                source,
                "retina_half_tangent",
                format!("must be a positive finite number, got {}", self.half_tangent),
            ));
        }
        limits::RETINA_HALF_TANGENT.check(source, "retina_half_tangent", self.half_tangent)?;
        if self.samples_per_pixel == 0 || self.samples_per_pixel > 64 {
            return Err(Error::invalid(
                source,
                "retina_samples",
                format!("must be between 1 and 64, got {}", self.samples_per_pixel),
            ));
        }
        Ok(())
    }
}

/// Centres of a k x k subdivision of the unit square, row by row.
pub fn stratified(k: usize) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(k * k);
    for j in 0..k {
        for i in 0..k {
            out.push(DVec2::new((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_aperture_is_stated_by_exactly_one_of_pinhole_focus_mm_focus_diopters() {
        let lens = |focus| Some(Aperture::ThinLens { pupil_diameter: 4.0, focus });
        assert_eq!(Aperture::stated(true, None, None, 4.0), Some(Aperture::Pinhole));
        assert_eq!(Aperture::stated(false, Some(300.0), None, 4.0), lens(Focus::Millimetres(300.0)));
        assert_eq!(Aperture::stated(false, None, Some(2.5), 4.0), lens(Focus::Diopters(2.5)));
        for (pinhole, mm, d) in [
            (false, None, None),
            (true, Some(300.0), None),
            (true, None, Some(2.5)),
            (false, Some(300.0), Some(2.5)),
            (true, Some(300.0), Some(2.5)),
        ] {
            assert_eq!(Aperture::stated(pinhole, mm, d, 4.0), None, "{pinhole} {mm:?} {d:?}");
        }
    }

    #[test]
    fn pupil_grid_counts_match_the_paper_and_the_framework() {
        assert_eq!(pupil_grid(5.0, 8).len(), 52);
        assert_eq!(pupil_grid(2.0, 5).len(), 21);
        assert_eq!(pupil_grid(5.0, 1).len(), 1);
        // Symmetric about the centre: the samples average to zero.
        let mean: DVec2 = pupil_grid(5.0, 8).iter().copied().sum::<DVec2>() / 52.0;
        assert!(mean.length() < 1e-12);
    }

    #[test]
    fn diopters_and_millimetres_agree_and_zero_diopters_is_infinity() {
        let a = Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8).power();
        let b = Eye::thin_lens(5.0, Focus::Diopters(2.5), 8).power();
        assert!((a - b).abs() < 1e-15);
        let inf = Eye::thin_lens(5.0, Focus::Diopters(0.0), 8);
        assert_eq!(inf.power(), 1.0 / 17.0);
        assert_eq!(Focus::Diopters(0.0).distance_mm(), f64::INFINITY);
        assert_eq!(Eye::thin_lens(5.0, Focus::Millimetres(f64::INFINITY), 8).power(), 1.0 / 17.0);
        inf.validate("t").unwrap();
    }

    #[test]
    fn retina_tangents_follow_the_convention() {
        let r = Retina::default();
        let t = r.tangent(0, 0, DVec2::splat(0.5));
        assert!((t - DVec2::new(-0.3 + 0.3 / 512.0, 0.3 - 0.3 / 512.0)).length() < 1e-15);
        let t = r.tangent(511, 511, DVec2::ONE);
        assert!((t - DVec2::new(0.3, -0.3)).length() < 1e-15);
    }

    #[test]
    fn bad_eyes_name_the_field() {
        let e = Eye::thin_lens(-1.0, Focus::Millimetres(300.0), 8).validate("e.toml").unwrap_err().to_string();
        assert!(e.contains("pupil_diameter") && e.contains("e.toml"), "{e}");
        let e = Eye::thin_lens(5.0, Focus::Diopters(f64::NAN), 8).validate("e").unwrap_err().to_string();
        assert!(e.contains("focus_diopters"), "{e}");
    }
}
