//! The optical system of one eye case, decided once: the eye (its pose, its model, pupil,
//! spectrum and Stiles-Crawford weight, diffraction at the pupil), the display's lenslets
//! (paraxial, paper eq. (1b), or real thick ones, `optics::lenslet`; diffraction at their
//! apertures, `optics::diffraction`) and the LCD. It owns the per-sample trace of paper Sec. 2.3:
//! a retina point, a pupil point, a spectral number and four diffraction numbers ([`EyeSample`])
//! -> the scene rays of the ground truth (one for every channel, or one per channel) and each
//! channel's LCD pixel, where every method's display image is read ([`OpticalSystem::trace`],
//! `system/trace.rs`), and the fixed grid of samples the grid estimator and the OPT operator sum
//! ([`OpticalSystem::trace_grid`], `system/grid.rs`).
//!
//! [`OpticalSystem::new`] picks the kernel that traces the samples ([`Kernel`]): the paper's
//! thin lens through paraxial lenslets in eq. (1)'s closed form, the thin lens through real
//! lenslets, an eye's own rays batched, the thin lens with diffraction batched with its Airy-core
//! shortcuts (`system/diffracted.rs`), the general path sample by sample, and the eye turned to a
//! gaze (`optics::eye::gaze`), whose rays at rest are moved by its pose into the scene's frame. Every kernel has a
//! slow twin, [`OpticalSystem::trace_each`], which traces one sample at a time by the same
//! arithmetic and gives the same bits (tested). The grid simulation, the converged estimator, the
//! OPT operator and the resolution study all trace through this type; none of them branches on
//! the eye model, the lenslet kind or diffraction.

use std::sync::Arc;

use glam::DVec2;

use super::diffraction::ApertureShape;
use super::eye::EyeOptics;
use super::transfer::FastTransfer;
use super::{Display, Eye, Retina};
use crate::ray::AffineRays;

mod diffracted;
mod grid;
mod trace;

pub use grid::GridBuffers;
pub use trace::{Hint, Traced, Traces, KNOWN, MISS};

/// One eye ray of a measurement: the tangent of a retina point and a pupil point (mm from the
/// pupil centre), with the numbers that pick its wavelengths and diffraction angles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EyeSample {
    /// Tangents (x, y) of the retina point's direction.
    pub tangent: DVec2,
    /// Pupil point, mm from the pupil centre.
    pub pupil: DVec2,
    /// The uniform number in [0, 1) that picks the sample's wavelengths from the display
    /// primaries' spectra (0 when the system does not ask for it,
    /// [`OpticalSystem::needs_spectral`]).
    pub spectral: f64,
    /// Four uniform numbers in [0, 1) for the diffraction angles: the pupil's deviation (0, 1)
    /// and the lenslet's (2, 3) (zeros when the system does not ask for them,
    /// [`OpticalSystem::needs_diffraction`]).
    pub diffraction: [f64; 4],
}

/// How an [`OpticalSystem`] traces its samples: decided once, in [`OpticalSystem::new`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// The paper's thin lens through paraxial lenslets: eq. (1) in closed form, one ray and one
    /// LCD pixel for the three channels.
    Paraxial,
    /// The thin lens through real lenslets: one ray, each channel its own LCD pixel at its
    /// primary's median wavelength (the front surface's hit found once for the three).
    ThinThick,
    /// An eye's own rays (a schematic eye, the primaries' wavelengths, Stiles-Crawford) through
    /// paraxial lenslets, without diffraction: in passes over the batch.
    EyeRays,
    /// The thin lens with diffraction through paraxial lenslets, without Stiles-Crawford: in
    /// passes over the batch, with the Airy-core shortcuts.
    ThinDiffracted,
    /// Everything else (a schematic eye through real lenslets, diffraction with a schematic eye
    /// or Stiles-Crawford, ...): sample by sample.
    General,
    /// The eye turned to a gaze ([`crate::optics::eye::EyePose`]), any eye model: each sample's
    /// rays of the eye at rest (the thin lens's through `EyeOptics::thin_lens`) moved by the
    /// pose into the scene's frame, then as [`Kernel::General`], sample by sample.
    Rotated,
}

/// The eye, the lenslets, the LCD and diffraction of one eye case: see the module comment.
pub struct OpticalSystem<'a> {
    /// `None`: the eye alone ([`OpticalSystem::scene_only`]).
    display: Option<&'a Display>,
    eye: Eye,
    /// The eye's rays: its own optics, or the thin lens's (`EyeOptics::thin_lens`).
    optics: Arc<EyeOptics>,
    /// Eye -> LCD, with the pupil grid's constants (the grid's closed form); `None`: the eye
    /// alone, every LCD pixel [`MISS`].
    transfer: Option<FastTransfer<'a>>,
    /// The pupil grid.
    pupil: Vec<DVec2>,
    /// The lenslet aperture when it diffracts.
    lenslet: Option<ApertureShape>,
    /// Diffraction modelled (the eye's setting, unless the system is geometric).
    diffraction: bool,
    kernel: Kernel,
}

impl<'a> OpticalSystem<'a> {
    /// `eye` looking at `display`, with diffraction as the eye states it.
    pub fn new(display: &'a Display, eye: &Eye) -> Self {
        Self::build(display, eye, true)
    }

    /// `eye` looking at `display` in geometric optics: diffraction not modelled, whatever the eye
    /// states (the grid estimator's system).
    pub fn geometric(display: &'a Display, eye: &Eye) -> Self {
        Self::build(display, eye, false)
    }

    /// The eye alone, in geometric optics: the scene rays of the ground truth, no display (every
    /// LCD pixel [`MISS`]).
    pub fn scene_only(eye: &Eye) -> Self {
        Self::build_with(None, eye, false)
    }

    fn build(display: &'a Display, eye: &Eye, diffraction: bool) -> Self {
        Self::build_with(Some(display), eye, diffraction)
    }

    fn build_with(display: Option<&'a Display>, eye: &Eye, diffraction: bool) -> Self {
        let pupil = eye.pupil_samples();
        let transfer = display.map(|d| FastTransfer::new(d, eye, &pupil));
        let thick = transfer.as_ref().is_some_and(|t| t.is_thick());
        let own = eye.optics.clone();
        let diffraction = diffraction && own.as_ref().is_some_and(|o| o.diffraction.is_on());
        let lenslet = own
            .as_ref()
            .filter(|o| diffraction && o.diffraction.lenslets())
            .and(display)
            .map(|d| ApertureShape::of_lattice(&d.lenslets));
        let kernel = match &own {
            _ if eye.pose.is_some() => Kernel::Rotated,
            None if thick => Kernel::ThinThick,
            None => Kernel::Paraxial,
            Some(_) if thick => Kernel::General,
            Some(_) if !diffraction => Kernel::EyeRays,
            Some(o) if o.schematic().is_none() && o.stiles_crawford.is_none() => Kernel::ThinDiffracted,
            Some(_) => Kernel::General,
        };
        let optics = own.unwrap_or_else(|| Arc::new(EyeOptics::thin_lens(eye)));
        Self { display, eye: eye.clone(), optics, transfer, pupil, lenslet, diffraction, kernel }
    }

    /// The eye (its pose and aperture).
    pub fn eye(&self) -> &Eye {
        &self.eye
    }

    /// The display (`None`: the eye alone).
    pub fn display(&self) -> Option<&'a Display> {
        self.display
    }

    /// The kernel that traces the samples.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// The eye's rays (its own optics, or the thin lens's).
    pub fn optics(&self) -> &EyeOptics {
        &self.optics
    }

    /// True when the samples need their spectral number ([`EyeSample::spectral`]).
    pub fn needs_spectral(&self) -> bool {
        self.eye.optics.is_some() && !self.optics.is_single_wavelength()
    }

    /// True when the samples need their diffraction numbers ([`EyeSample::diffraction`]).
    pub fn needs_diffraction(&self) -> bool {
        self.diffraction
    }

    /// The pupil grid (the eye's fixed pupil samples).
    pub fn pupil_grid(&self) -> &[DVec2] {
        &self.pupil
    }

    /// The fixed grid's spectral numbers (one, 0.5, unless the channels have their own
    /// wavelengths).
    pub fn grid_spectral(&self) -> Vec<f64> {
        self.optics.grid_spectral()
    }

    /// The number of grid samples per retina pixel: sub-pixel points x pupil points x spectral
    /// numbers.
    pub fn grid_samples_per_pixel(&self, retina: &Retina) -> usize {
        retina.subpixel_offsets().len() * self.pupil.len() * self.grid_spectral().len()
    }

    /// The scene rays of every sample of a retina pixel with tangents in the box `tangents` and
    /// pupil points in the box `pupil`, as one affine family that also holds the rays of the
    /// samples whose diffraction deviations lie in the system's core (so a field that proves the
    /// family one colour gives that colour to those samples, [`Hint::reference`]); `None` when
    /// the eye's rays are not such a family (a schematic eye) or when the system has no such
    /// shortcut.
    pub fn ray_family(&self, tangents: (DVec2, DVec2), pupil: (DVec2, DVec2)) -> Option<AffineRays> {
        let core = match self.kernel {
            Kernel::Paraxial | Kernel::ThinThick => 0.0,
            Kernel::ThinDiffracted => self.pupil_core(),
            Kernel::EyeRays | Kernel::General | Kernel::Rotated => return None,
        };
        let core = DVec2::splat(core);
        let (t_lo, t_hi) = (tangents.0.min(tangents.1) - core, tangents.0.max(tangents.1) + core);
        Some(AffineRays {
            origin: self.eye.position,
            dir: t_lo,
            q_lo: pupil.0.min(pupil.1),
            q_hi: pupil.0.max(pupil.1),
            alpha: 1.0,
            beta: 1.0 / self.eye.retina_distance - self.eye.power(),
            e_lo: DVec2::ZERO,
            e_hi: t_hi - t_lo,
        })
    }

    /// The LCD pixels every perceived ray of a retina pixel (tangents in the box `tangents`,
    /// pupil points within `pupil_radius` mm of its centre) can meet with its diffraction
    /// deviations in the system's cores: `each(columns, rows)` (inclusive ranges) for rectangles
    /// that together hold them, as `FastTransfer::deviated_family_pixels`. `Some(true)`: every
    /// call said true, so a sample whose deviations lie in the cores reads one of those pixels
    /// ([`Hint::images`]); `Some(false)`: not proven; `None`: the system has no such shortcut.
    pub fn family_lcd_pixels(
        &self,
        tangents: (DVec2, DVec2),
        pupil_radius: f64,
        each: impl FnMut([usize; 2], [usize; 2]) -> bool,
    ) -> Option<bool> {
        if self.kernel != Kernel::ThinDiffracted {
            return None;
        }
        let lens = self.optics.thin_lens_ray()?;
        let core = DVec2::splat(self.pupil_core());
        let widened = (tangents.0.min(tangents.1) - core, tangents.0.max(tangents.1) + core);
        Some(self.transfer.as_ref()?.deviated_family_pixels(
            (lens.v0, lens.d1),
            widened,
            pupil_radius,
            self.lenslet_core(),
            diffracted::MAX_LENSLETS,
            each,
        ))
    }

    /// True when every sample carries one ray for the three channels, weight 1 and one LCD pixel
    /// (the thin lens's closed form).
    pub fn samples_are_plain(&self) -> bool {
        self.kernel == Kernel::Paraxial
    }

    /// The LCD's pixels per row.
    pub fn lcd_columns(&self) -> usize {
        self.transfer.as_ref().map_or(0, |t| t.lcd_columns())
    }
}

#[cfg(test)]
mod tests;
