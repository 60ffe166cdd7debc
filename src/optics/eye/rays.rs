//! The eye's rays when they are not the thin lens's fast paths (docs/EYE.md): a schematic eye
//! (Navarro, Arizona, Le Grand or a user's, traced exactly), the display primaries' wavelengths
//! and the Stiles-Crawford effect. One measurement, more dimensions: a sample is still a point of
//! the retina pixel's square (its tangent in visual space) and a point of the entrance pupil, and
//! now also a uniform number that picks each channel's wavelength from its primary's spectrum
//! (`optics::spectrum`). The ray is the same object-space line for the ground truth and for
//! every method's perceived image, so chromatic aberration and the eye's aberrations enter both
//! alike and nothing is added on top.
//!
//! - Retina pixel (r, c) keeps meaning a direction in visual space: its tangent is mapped to the
//!   curved retina through the model's chief ray at the reference wavelength
//!   ([`SchematicEye::retina_point`]), and the ray from that retina point through the iris point
//!   (the entrance-pupil point scaled by the paraxial pupil magnification) is traced out of the
//!   eye ([`SchematicEye::ray_out`]).
//! - The Stiles-Crawford effect of the first kind ([`super::stiles_crawford`]): a centred peak
//!   warps the uniform pupil point to the effect's density (a uniform scene stays exactly
//!   uniform); an off-centre peak keeps the point uniform and weights it by the effect over its
//!   exact mean over the disk, bounded wherever the peak lies.
//! - A thin-lens eye with the Stiles-Crawford weight also comes here (`Lens::ThinLens`, the
//!   paper's eq. (1b) with d1); without it, the thin lens keeps its fast paths and this module is
//!   not used, so the paper's numbers stay bit for bit.

use std::sync::Arc;

use glam::DVec2;

use super::ray_map::RayMap;
pub use super::stiles_crawford::StilesCrawford;
use super::{Aperture, EyeModel, FocusCriterion, SchematicEye};
use crate::error::{Error, Result};
use crate::optics::diffraction::{disk_deviation, disk_draw, Diffraction};
use crate::optics::spectrum::{Primaries, SpectrumSampler};
use crate::optics::transfer::PlaneRay;

/// The fraction of each primary's power at either end of its spectrum that the fitted ray map
/// leaves to the exact aim (a narrower wavelength range needs fewer Chebyshev terms).
const MAP_TAIL: f64 = 1e-5;

/// How the eye's colour channels are traced.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// Every channel at one wavelength, nm.
    Single(f64),
    /// Each channel at wavelengths drawn from its display primary.
    Primaries(Box<[SpectrumSampler; 3]>),
}

/// The thin lens's ray of eq. (1a), (1b) (as `transfer::eye_ray`): the one arithmetic of
/// [`EyeOptics::rays`] for the thin lens and of the batched paths that inline it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLensRay {
    /// Pupil to retina, mm.
    pub v0: f64,
    /// The lens's power, 1/mm.
    pub d1: f64,
}

impl ThinLensRay {
    /// The object-space ray (at the pupil plane, eye coordinates) of retina tangent `tangent`
    /// through pupil point `pupil`.
    #[inline(always)]
    pub fn ray(self, tangent: DVec2, pupil: DVec2) -> PlaneRay {
        let x0 = -self.v0 * tangent;
        let w0 = (pupil - x0) / self.v0;
        PlaneRay { position: pupil, slope: w0 }.refract(DVec2::ZERO, self.d1)
    }
}

/// The lens the rays go through.
#[derive(Clone, Debug)]
enum Lens {
    /// The paper's thin lens: v0 and d1 (eq. (1b)).
    ThinLens { v0: f64, d1: f64 },
    /// A schematic eye, solved for this eye case's focus.
    Schematic(Box<SchematicEye>),
}

/// The settings of an eye beyond the thin lens, as the experiment's `[eye]` states them.
#[derive(Clone, Debug, PartialEq)]
pub struct EyeOpticsSpec {
    /// The model.
    pub model: EyeModel,
    /// How the focus is judged when the accommodation is solved.
    pub criterion: FocusCriterion,
    /// The reference wavelength of the focus and of the retina's map, nm.
    pub reference_nm: f64,
    /// Trace each channel at its primary's wavelengths (else all at `reference_nm`).
    pub primaries: bool,
    /// Wavelengths per channel of the grid estimator (the converged one samples them).
    pub wavelength_samples: usize,
    /// Stiles-Crawford: rho (1/mm^2) and peak (mm), if applied.
    pub stiles_crawford: Option<(f64, DVec2)>,
    /// `[optics] diffraction` (`optics::diffraction`).
    pub diffraction: Diffraction,
}

impl EyeOpticsSpec {
    /// These settings with `[optics] diffraction = d`. With diffraction a thin-lens eye traces
    /// each channel at its primary's sampled wavelengths unless `eye.spectrum` was stated
    /// (`spectrum_stated`): diffraction's angle is proportional to the wavelength.
    pub fn with_diffraction(mut self, d: Diffraction, spectrum_stated: bool) -> Self {
        self.diffraction = d;
        if d.is_on() && !spectrum_stated {
            self.primaries = true;
        }
        self
    }
}

/// An eye's optics beyond the thin lens's fast paths, solved for one eye case.
#[derive(Clone, Debug)]
pub struct EyeOptics {
    lens: Lens,
    /// The schematic eye's fitted ray map over the measurement's field, when it is within its
    /// tolerances of the exact aim (else every ray is aimed).
    map: Option<RayMap>,
    /// The model.
    pub model: EyeModel,
    /// The solved accommodation, D (schematic eyes).
    pub accommodation: Option<f64>,
    /// The entrance pupil's diameter, mm (0: a pinhole).
    pub pupil_diameter: f64,
    /// The iris diameter that gives it, mm.
    pub iris_diameter: f64,
    /// The colour channels' wavelengths.
    pub spectrum: Spectrum,
    /// Grid estimator: wavelengths per channel (their quantiles).
    pub wavelength_samples: usize,
    /// The apodization, if applied.
    pub stiles_crawford: Option<StilesCrawford>,
    /// The focus criterion the accommodation was solved with.
    pub criterion: FocusCriterion,
    /// The reference wavelength, nm.
    pub reference_nm: f64,
    /// Which apertures diffract (`optics::diffraction`): the pupil here, the lenslets in the
    /// perceived images' transfer.
    pub diffraction: Diffraction,
}

impl PartialEq for EyeOptics {
    fn eq(&self, o: &Self) -> bool {
        self.model == o.model
            && self.accommodation == o.accommodation
            && self.pupil_diameter == o.pupil_diameter
            && self.spectrum == o.spectrum
            && self.stiles_crawford == o.stiles_crawford
            && self.criterion == o.criterion
            && self.reference_nm == o.reference_nm
            && self.wavelength_samples == o.wavelength_samples
            && self.diffraction == o.diffraction
    }
}

/// Up to three object-space rays of one sample (one per channel) and its weight.
#[derive(Clone, Copy, Debug)]
pub struct SampleRays {
    /// Channel c's ray at the eye's plane z = 0 (eye coordinates), `None` when blocked inside the
    /// eye (it then carries black for every image).
    pub rays: [Option<PlaneRay>; 3],
    /// True when one ray serves all three channels (`rays[0]`).
    pub single: bool,
    /// The sample's weight (1 unless a Stiles-Crawford peak is off centre).
    pub weight: f64,
}

impl EyeOptics {
    /// The optics of an eye case with aperture `aperture`, or `None` when the eye is the paper's
    /// thin lens without Stiles-Crawford (the fast paths). `field` names the case for errors.
    /// `max_tangent` is the largest retina tangent |t| the measurement asks for: a schematic
    /// eye's fitted ray map ([`RayMap`]) covers it (0: every ray is aimed exactly).
    pub fn build(
        spec: &EyeOpticsSpec,
        aperture: &Aperture,
        retina_distance: f64,
        primaries: &Primaries,
        max_tangent: f64,
        source: &str,
        field: &str,
    ) -> Result<Option<Arc<EyeOptics>>> {
        let (pupil_diameter, vergence) = match *aperture {
            Aperture::Pinhole => (0.0, None),
            Aperture::ThinLens { pupil_diameter, focus } => (pupil_diameter, Some(1000.0 * focus.vergence())),
        };
        let thin = spec.model == EyeModel::ThinLens;
        if thin && spec.stiles_crawford.is_none() && !spec.diffraction.is_on() {
            return Ok(None);
        }
        let (lens, accommodation, iris_diameter) = if thin {
            let d1 = 1.0 / retina_distance + vergence.unwrap_or(0.0) / 1000.0;
            (Lens::ThinLens { v0: retina_distance, d1 }, None, pupil_diameter)
        } else {
            let (eye, a) = match vergence {
                Some(v) => SchematicEye::focused(
                    &spec.model,
                    v,
                    spec.reference_nm,
                    spec.criterion,
                    pupil_diameter,
                    source,
                    field,
                )?,
                None => {
                    let a = spec.model.accommodation_range().0;
                    (SchematicEye::new(&spec.model, a, source)?, a)
                }
            };
            let iris = eye.iris_diameter(pupil_diameter);
            // An eye that blocks its own axial rays would give black images and a PSNR of inf.
            // Checked: the axis, the pupil's edge (at least 0.5 mm out) and a chief ray 0.1 off it.
            let axis = eye.retina_point(DVec2::ZERO);
            let edge = DVec2::new((0.5 * iris * (1.0 - 1e-9)).max(0.5), 0.0);
            let field = eye.retina_point(DVec2::new(0.1, 0.0));
            let nm = spec.reference_nm;
            if eye.ray_out(axis, DVec2::ZERO, nm).is_none()
                || eye.ray_out(axis, edge, nm).is_none()
                || eye.ray_out(field, DVec2::ZERO, nm).is_none()
            {
                return Err(Error::invalid(
                    source,
                    "eye.model",
                    format!(
                        "the {} eye blocks its own axial rays (or the chief ray 0.1 off the axis) \
                         through a {pupil_diameter} mm pupil (check the iris position and the \
                         surfaces' semi-diameters)",
                        spec.model.name()
                    ),
                ));
            }
            eye.check_field(max_tangent, source)?;
            (Lens::Schematic(Box::new(eye)), Some(a), iris)
        };
        let spectrum = if spec.primaries && (!thin || spec.diffraction.is_on()) {
            Spectrum::Primaries(Box::new(primaries.samplers(source)?))
        } else {
            Spectrum::Single(spec.reference_nm)
        };
        let map = match &lens {
            Lens::Schematic(eye) if max_tangent > 0.0 && max_tangent.is_finite() => {
                let range = match &spectrum {
                    Spectrum::Single(nm) => (*nm, *nm),
                    // All but the primaries' outermost 1e-5 of their power: the rare
                    // wavelength beyond is aimed exactly (`RayMap::ray` declines it).
                    Spectrum::Primaries(s) => s.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                        (lo.min(s.wavelength(MAP_TAIL)), hi.max(s.wavelength(1.0 - MAP_TAIL)))
                    }),
                };
                let scale = if pupil_diameter > 0.0 { iris_diameter / pupil_diameter } else { 0.0 };
                RayMap::fit(eye, max_tangent, 0.5 * pupil_diameter, scale, range)
            }
            _ => None,
        };
        if spec.wavelength_samples == 0 || spec.wavelength_samples > 64 {
            return Err(Error::invalid(
                source,
                "eye.wavelength_samples",
                format!("must be between 1 and 64, got {}", spec.wavelength_samples),
            ));
        }
        let stiles_crawford =
            spec.stiles_crawford.map(|(rho, peak)| StilesCrawford::new(rho, peak, 0.5 * pupil_diameter));
        Ok(Some(Arc::new(EyeOptics {
            lens,
            map,
            model: spec.model.clone(),
            accommodation,
            pupil_diameter,
            iris_diameter,
            spectrum,
            wavelength_samples: spec.wavelength_samples,
            stiles_crawford,
            criterion: spec.criterion,
            reference_nm: spec.reference_nm,
            diffraction: spec.diffraction,
        })))
    }

    /// The paper's thin-lens eye (eq. (1b) with d1, no Stiles-Crawford) as an `EyeOptics`: the
    /// eye a display with real lenslets is simulated through, so that each colour channel finds
    /// its own LCD pixel (the thin lens's fast paths read one pixel for all three).
    pub fn thin_lens(eye: &super::Eye) -> EyeOptics {
        let pupil_diameter = match eye.aperture {
            Aperture::Pinhole => 0.0,
            Aperture::ThinLens { pupil_diameter, .. } => pupil_diameter,
        };
        EyeOptics {
            lens: Lens::ThinLens { v0: eye.retina_distance, d1: eye.power() },
            map: None,
            model: EyeModel::ThinLens,
            accommodation: None,
            pupil_diameter,
            iris_diameter: pupil_diameter,
            spectrum: Spectrum::Single(crate::optics::lenslet::D_LINE_NM),
            wavelength_samples: 1,
            stiles_crawford: None,
            criterion: FocusCriterion::default(),
            reference_nm: crate::optics::lenslet::D_LINE_NM,
            diffraction: Diffraction::None,
        }
    }

    /// Whether the fitted ray map serves this eye's rays (else a schematic eye aims each ray
    /// exactly, an iterative solve about ten times the map's cost).
    pub fn has_ray_map(&self) -> bool {
        self.map.is_some()
    }

    /// The schematic eye, if this is one.
    pub fn schematic(&self) -> Option<&SchematicEye> {
        match &self.lens {
            Lens::Schematic(e) => Some(e),
            Lens::ThinLens { .. } => None,
        }
    }

    /// The paper's thin lens (its [`ThinLensRay`]), or `None` for a schematic eye.
    pub fn thin_lens_ray(&self) -> Option<ThinLensRay> {
        match &self.lens {
            Lens::ThinLens { v0, d1 } => Some(ThinLensRay { v0: *v0, d1: *d1 }),
            Lens::Schematic(_) => None,
        }
    }

    /// True when every channel is traced at one wavelength (one ray per sample).
    pub fn is_single_wavelength(&self) -> bool {
        matches!(self.spectrum, Spectrum::Single(_)) || (self.schematic().is_none() && !self.diffraction.is_on())
    }

    /// The pupil's diffraction deviation of channel `c`'s ray (a retina-side angle, added to
    /// the retina tangent) for the uniform pair `xi` and spectral number `u`: the Airy pattern of
    /// the entrance pupil at the channel's wavelength (zero without pupil diffraction or with a
    /// pinhole, whose geometric idealisation has no width).
    #[inline]
    pub fn pupil_deviation(&self, c: usize, u: f64, xi: [f64; 2]) -> DVec2 {
        if !self.diffraction.is_on() {
            return DVec2::ZERO;
        }
        disk_deviation(xi, self.pupil_diameter, self.wavelength(c, u))
    }

    /// [`Self::rays`] with the pupil's diffraction (`xi`: the sample's two uniform numbers of
    /// the pupil's deviation): each channel's ray leaves the retina point moved by its channel's
    /// deviation ([`Self::pupil_deviation`]); without diffraction, `rays` itself.
    pub fn rays_diffracted(&self, tangent: DVec2, pupil: DVec2, u: f64, xi: [f64; 2]) -> SampleRays {
        if !self.diffraction.is_on() || self.pupil_diameter <= 0.0 {
            return self.rays(tangent, pupil, u);
        }
        if self.is_single_wavelength() {
            return self.rays(tangent + self.pupil_deviation(0, u, xi), pupil, u);
        }
        // One Airy draw for the three channels, scaled by each one's wavelength: the same
        // deviations as `pupil_deviation` per channel, bit for bit.
        let draw = disk_draw(xi);
        let mut out = SampleRays { rays: [None; 3], single: false, weight: 1.0 };
        for c in 0..3 {
            let r = self.rays(tangent + draw.disk(self.pupil_diameter, self.wavelength(c, u)), pupil, u);
            out.rays[c] = if r.single { r.rays[0] } else { r.rays[c] };
            out.weight = r.weight;
        }
        out
    }

    /// Channel `c`'s wavelength for the uniform number `u`, nm.
    #[inline]
    pub fn wavelength(&self, c: usize, u: f64) -> f64 {
        match &self.spectrum {
            Spectrum::Single(nm) => *nm,
            Spectrum::Primaries(s) => s[c].wavelength(u),
        }
    }

    /// The grid estimator's uniform numbers for the wavelengths (one, 0.5, when single).
    pub fn grid_spectral(&self) -> Vec<f64> {
        if self.is_single_wavelength() {
            return vec![0.5];
        }
        let k = self.wavelength_samples;
        (0..k).map(|j| (j as f64 + 0.5) / k as f64).collect()
    }

    /// The rays of the sample with retina tangent `tangent`, entrance-pupil point `pupil` (a
    /// uniform point of the pupil disk, mm from its centre) and spectral number `u`.
    #[inline]
    pub fn rays(&self, tangent: DVec2, pupil: DVec2, u: f64) -> SampleRays {
        let (pupil, weight) = match &self.stiles_crawford {
            Some(sc) => {
                let p = sc.warp(pupil, 0.5 * self.pupil_diameter);
                (p, sc.weight(p))
            }
            None => (pupil, 1.0),
        };
        match &self.lens {
            Lens::ThinLens { v0, d1 } => {
                let ray = ThinLensRay { v0: *v0, d1: *d1 }.ray(tangent, pupil);
                SampleRays { rays: [Some(ray); 3], single: true, weight }
            }
            Lens::Schematic(eye) => {
                if let Some(map) = &self.map {
                    let fitted = match &self.spectrum {
                        Spectrum::Single(nm) => map.ray(tangent, pupil, [*nm; 1]).map(|[r]| (r, r, r, true)),
                        Spectrum::Primaries(s) => map
                            .ray(tangent, pupil, [s[0].wavelength(u), s[1].wavelength(u), s[2].wavelength(u)])
                            .map(|[r, g, b]| (r, g, b, false)),
                    };
                    if let Some((r, g, b, single)) = fitted {
                        return SampleRays { rays: [Some(r), Some(g), Some(b)], single, weight };
                    }
                }
                let retina = eye.retina_point(tangent);
                let scale = if self.pupil_diameter > 0.0 { self.iris_diameter / self.pupil_diameter } else { 0.0 };
                let iris = pupil * scale;
                match &self.spectrum {
                    Spectrum::Single(nm) => {
                        let ray = eye.ray_out(retina, iris, *nm);
                        SampleRays { rays: [ray; 3], single: true, weight }
                    }
                    Spectrum::Primaries(s) => SampleRays {
                        rays: std::array::from_fn(|c| eye.ray_out(retina, iris, s[c].wavelength(u))),
                        single: false,
                        weight,
                    },
                }
            }
        }
    }

    /// [`Self::rays`] of two samples `(tangent, pupil, u)` at once, bit for bit the same: a
    /// schematic eye's ray map evaluates them in lockstep ([`RayMap::rays`]), sharing its
    /// coefficients. `rays` stays the slow twin (and serves what the map does not cover).
    #[inline]
    pub fn rays2(&self, a: (DVec2, DVec2, f64), b: (DVec2, DVec2, f64)) -> [SampleRays; 2] {
        let (Lens::Schematic(_), Some(map)) = (&self.lens, &self.map) else {
            return [self.rays(a.0, a.1, a.2), self.rays(b.0, b.1, b.2)];
        };
        let warp = |(t, p, u): (DVec2, DVec2, f64)| match &self.stiles_crawford {
            Some(sc) => {
                let p = sc.warp(p, 0.5 * self.pupil_diameter);
                (t, p, u, sc.weight(p))
            }
            None => (t, p, u, 1.0),
        };
        let (wa, wb) = (warp(a), warp(b));
        let (t, p) = ([wa.0, wb.0], [wa.1, wb.1]);
        let fitted: [Option<([PlaneRay; 3], bool)>; 2] = match &self.spectrum {
            Spectrum::Single(nm) => map.rays(t, p, [[*nm]; 2]).map(|o| o.map(|[r]| ([r; 3], true))),
            Spectrum::Primaries(s) => {
                let nm = |u: f64| [s[0].wavelength(u), s[1].wavelength(u), s[2].wavelength(u)];
                map.rays(t, p, [nm(wa.2), nm(wb.2)]).map(|o| o.map(|r| (r, false)))
            }
        };
        let [fa, fb] = fitted;
        let one = |f: Option<([PlaneRay; 3], bool)>, weight: f64, input: (DVec2, DVec2, f64)| match f {
            Some((r, single)) => SampleRays { rays: r.map(Some), single, weight },
            None => self.rays(input.0, input.1, input.2),
        };
        [one(fa, wa.3, a), one(fb, wb.3, b)]
    }

    /// One line for reports: the model, its accommodation, the pupils and the colour.
    pub fn describe(&self) -> String {
        let mut s = self.model.name().to_string();
        if let Some(a) = self.accommodation {
            s += &format!(", accommodation {a:.3} D ({})", criterion_name(self.criterion));
        }
        if self.pupil_diameter > 0.0 {
            s += &format!(", entrance pupil {:.3} mm (iris {:.3} mm)", self.pupil_diameter, self.iris_diameter);
        }
        s += &match self.spectrum {
            Spectrum::Single(nm) => format!(", {nm} nm"),
            Spectrum::Primaries(_) => ", display primaries".to_string(),
        };
        if let Some(sc) = &self.stiles_crawford {
            s += &format!(", Stiles-Crawford rho {} /mm^2", sc.rho);
        }
        if self.diffraction.is_on() {
            s += &format!(
                ", diffraction at the {}",
                match self.diffraction {
                    Diffraction::Apertures => "pupil and the lenslets",
                    _ => "pupil",
                }
            );
        }
        s
    }
}

/// The file name of a focus criterion.
pub fn criterion_name(c: FocusCriterion) -> &'static str {
    match c {
        FocusCriterion::Paraxial => "paraxial",
        FocusCriterion::MinRmsSpot => "min-rms-spot",
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let (x, w) = super::super::accommodation::gauss_legendre(64);
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13);
        let i: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(10)).sum();
        assert!((i - 2.0 / 11.0).abs() < 1e-13, "{i}");
    }
}
