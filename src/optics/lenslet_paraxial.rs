//! A real lenslet's paraxial equivalent (Gaussian optics: W. J. Smith, "Modern Optical
//! Engineering", 4th ed., Sec. 2.3-2.4): its principal planes, which hold its nodal points in
//! air, and the thin lens they make of it, as eq. (1b)'s extended thin lens (paper Sec. 2.3).
//! `info` reads a thick lenslet's angular quantities through them, and PupilCenter takes this
//! lens's ray where the real lens sends no light from a pixel to the pupil centre.

use glam::{DVec2, DVec3};

use super::lenslet::{Paraxial, ThickLenslet};
use crate::ray::Ray;

impl Paraxial {
    /// The principal planes `(h1, h2)`: the front one `h1` mm beyond the front vertex (the front
    /// focal point lies `ffd` from the front vertex, the principal plane `efl` beyond it), the back
    /// one `h2` mm beyond the back vertex (`efl` before the back focal point); both toward the LCD
    /// when positive. In air on both sides they hold the nodal points.
    pub fn principal_planes(&self) -> (f64, f64) {
        (self.ffd + self.efl, self.bfd - self.efl)
    }
}

impl ThickLenslet {
    /// PupilCenter's camera ray where the real lenslet sends no light from the LCD point `lcd` to
    /// the pupil centre `eye` (the point would lie beyond the lens's edge: from the pupil centre
    /// a lenslet shows only the middle of its elemental image): the ray of the optically
    /// equivalent thin lens at index `n`, whose principal planes (`h1` beyond the front vertex at
    /// `front_z`, `h2` beyond the back vertex) stand for the lens as eq. (1b)'s extended thin lens
    /// does. With `L` from the pupil to the front principal plane and `s` from the back one to
    /// the LCD, the lens point `p (1/L + 1/s - 1/f) = e/L + x/s - c/f` (as
    /// `transfer::pupil_center_point`), and the ray is the line from the pupil centre through `p`
    /// on the front principal plane, from the plane `z = reference_z`. `None` when the lens
    /// images the pupil centre onto the LCD (no such ray).
    #[allow(clippy::too_many_arguments)]
    pub fn paraxial_pupil_center_ray(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        eye: DVec3,
        reference_z: f64,
        n: f64,
    ) -> Option<Ray> {
        let (p1, p2) = ((n - 1.0) * self.front.curvature(), (1.0 - n) * self.back.curvature());
        let t = self.thickness / n;
        let phi = p1 + p2 - p1 * p2 * t;
        let p = Paraxial { index: n, efl: 1.0 / phi, bfd: (1.0 - p1 * t) / phi, ffd: -(1.0 - p2 * t) / phi };
        let (h1, h2) = p.principal_planes();
        let z1 = front_z + h1;
        let (l, s) = (z1 - eye.z, lcd_z - (front_z + self.thickness + h2));
        let denom = 1.0 / l + 1.0 / s - phi;
        let regular = denom.abs() > 1e-9 * (1.0 / l + 1.0 / s + phi.abs());
        if !regular || l <= 0.0 || s <= 0.0 || l.is_nan() || s.is_nan() {
            return None;
        }
        let point = (eye.truncate() / l + lcd / s - center * phi) / denom;
        let w = (point - eye.truncate()) / l;
        let start = eye.truncate() + w * (reference_z - eye.z);
        Some(Ray { origin: start.extend(reference_z), dir: w.extend(1.0) })
    }
}
