//! Focusing a schematic eye: the accommodation that puts an object in best focus.
//!
//! Best focus on axis by one of two criteria ([`FocusCriterion`]): the paraxial image on the
//! retina vertex (Smith, "Modern Optical Engineering", Ch. 3), or the least RMS radius of the
//! real-ray spot on the retina for rays filling the entrance pupil (W. J. Smith, op. cit.,
//! Sec. 11.6; the minimum-RMS focus of an eye with spherical aberration, cf. L. N. Thibos et
//! al., "Accuracy and precision of objective refraction from wavefront aberrations", J. Vision
//! 4:329, 2004). The RMS is a Gauss-Legendre quadrature over the pupil radius squared
//! (rotational symmetry: one meridian of rays, each standing for its ring), minimised over the
//! object vergence by a coarse scan and golden-section search (Kiefer, Proc. AMS 4:502, 1953).
//! The accommodation is then the root of `best focus(A) = target`, by the Illinois variant of
//! regula falsi (Dowell & Jarratt, BIT 11:168, 1971) on the model's range.

use glam::DVec2;

use super::model::{EyeModel, FocusCriterion};
use super::schematic::SchematicEye;
use crate::error::{Error, Result};
use crate::optics::PlaneRay;

/// Rays (rings) of the RMS-spot quadrature.
const RMS_RAYS: usize = 16;

/// How close (D) a stated focus must be to one the eye reaches beyond which it is refused: a fixed
/// eye's one focus, or an end of an accommodating eye's range. A thousandth of the eye's depth of
/// field at a 5 mm pupil (about 0.1 D), and far above a value printed to 4 decimals.
pub const FOCUS_MATCH_D: f64 = 1e-4;

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton's method on P_n).
pub(crate) fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

impl SchematicEye {
    /// Mean squared transverse radius (mm²) on the retina of the on-axis object at vergence
    /// `vergence_d` (D, from the origin) for an entrance pupil of `pupil_diameter` mm at
    /// `wavelength_nm`; None when no ray arrives.
    pub fn rms_spot_squared(&self, vergence_d: f64, wavelength_nm: f64, pupil_diameter: f64) -> Option<f64> {
        let at = self.at(wavelength_nm);
        let (x, w) = gauss_legendre(RMS_RAYS);
        let r2max = 0.25 * pupil_diameter * pupil_diameter;
        let (mut sum, mut weight) = (0.0, 0.0);
        for (xi, wi) in x.iter().zip(&w) {
            let rho = (0.5 * (xi + 1.0) * r2max).sqrt();
            // The line from the object point (0, 0, 1000/V) through (rho, 0, 0).
            let ray = PlaneRay { position: DVec2::new(rho, 0.0), slope: DVec2::new(-rho * vergence_d / 1000.0, 0.0) };
            if let Some((p, _)) = at.ray_in(ray) {
                sum += wi * (p.x * p.x + p.y * p.y);
                weight += wi;
            }
        }
        (weight > 0.0).then(|| sum / weight)
    }

    /// The object vergence (D) in best focus on axis by `criterion` at `wavelength_nm` for an
    /// entrance pupil of `pupil_diameter` mm.
    pub fn best_focus_vergence(
        &self,
        wavelength_nm: f64,
        criterion: FocusCriterion,
        pupil_diameter: f64,
    ) -> Option<f64> {
        let paraxial = self.paraxial(wavelength_nm).conjugate_vergence_d;
        if criterion == FocusCriterion::Paraxial || !paraxial.is_finite() {
            return paraxial.is_finite().then_some(paraxial);
        }
        let f = |v: f64| self.rms_spot_squared(v, wavelength_nm, pupil_diameter).unwrap_or(f64::INFINITY);
        // Coarse scan, then golden section on the best bracket.
        let (span, steps) = (6.0, 48);
        let mut best = (f64::INFINITY, paraxial);
        for i in 0..=steps {
            let v = paraxial - span + 2.0 * span * i as f64 / steps as f64;
            let fv = f(v);
            if fv < best.0 {
                best = (fv, v);
            }
        }
        if !best.0.is_finite() {
            return None;
        }
        let h = 2.0 * span / steps as f64;
        let (mut a, mut b) = (best.1 - h, best.1 + h);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
        let (mut fc, mut fd) = (f(c), f(d));
        while b - a > 1e-8 {
            if fc < fd {
                b = d;
                d = c;
                fd = fc;
                c = b - g * (b - a);
                fc = f(c);
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + g * (b - a);
                fd = f(d);
            }
        }
        Some(0.5 * (a + b))
    }

    /// The accommodation that puts an object at vergence `object_vergence_d` (D, 1000 /
    /// distance in mm from the origin; 0 = infinity) in best focus on axis at `wavelength_nm`
    /// by `criterion`, for an entrance pupil of `pupil_diameter` mm; the eye built at it and the
    /// accommodation (D). A focus the model cannot reach is an error naming `field` with the
    /// model's reachable range in dioptres.
    pub fn focused(
        model: &EyeModel,
        object_vergence_d: f64,
        wavelength_nm: f64,
        criterion: FocusCriterion,
        pupil_diameter: f64,
        source: &str,
        field: &str,
    ) -> Result<(Self, f64)> {
        if !object_vergence_d.is_finite() {
            return Err(Error::invalid(
                source,
                field,
                format!("must be a finite vergence in D, got {object_vergence_d}"),
            ));
        }
        if !(wavelength_nm.is_finite() && (350.0..=1100.0).contains(&wavelength_nm)) {
            return Err(Error::invalid(
                source,
                "wavelength",
                format!("must be within 350..1100 nm, got {wavelength_nm}"),
            ));
        }
        if !(pupil_diameter.is_finite() && pupil_diameter > 0.0 && pupil_diameter <= 10.0) {
            return Err(Error::invalid(
                source,
                "pupil_diameter",
                format!("must be within (0, 10] mm, got {pupil_diameter}"),
            ));
        }
        let (lo, hi) = model.accommodation_range();
        let best = |a: f64| -> Result<f64> {
            let eye = SchematicEye::geometry(model, a, source)?;
            eye.best_focus_vergence(wavelength_nm, criterion, pupil_diameter).ok_or_else(|| {
                Error::invalid(source, field, format!("no ray of the {} eye reaches the retina at {a} D", model.name()))
            })
        };
        let (f_lo, f_hi) =
            (best(lo)? - object_vergence_d, if hi > lo { best(hi)? } else { f64::NAN } - object_vergence_d);
        let tol = 1e-9;
        // A stated focus this close to one the eye reaches (its fixed focus, or an end of its
        // range) is taken as that focus: a value typed back from a message rounded to 4 decimals.
        let near = FOCUS_MATCH_D;
        let unreachable = || {
            let (v_lo, v_hi) =
                (f_lo + object_vergence_d, if hi > lo { f_hi + object_vergence_d } else { f_lo + object_vergence_d });
            Error::invalid(
                source,
                field,
                // Shortest round-trip forms: the values typed back are accepted.
                if hi > lo {
                    format!(
                        "{object_vergence_d} D is out of reach of the {} eye at {wavelength_nm} nm ({criterion:?} focus, \
                         {pupil_diameter} mm pupil): its accommodation {lo}..{hi} D focuses {}..{} D",
                        model.name(),
                        v_lo.min(v_hi),
                        v_lo.max(v_hi)
                    )
                } else {
                    format!(
                        "{object_vergence_d} D is out of reach of the {} eye at {wavelength_nm} nm ({criterion:?} focus, \
                         {pupil_diameter} mm pupil): it does not accommodate and focuses {v_lo} D (a focus within \
                         {near} D of it is taken as it; an accommodation law gives a user eye a range, docs/EYE.md)",
                        model.name(),
                    )
                },
            )
        };
        let a = if hi <= lo {
            if f_lo.abs() > near {
                return Err(unreachable());
            }
            lo
        } else if f_lo.abs() <= tol {
            lo
        } else if f_hi.abs() <= tol {
            hi
        } else if (f_lo < 0.0) == (f_hi < 0.0) {
            // Beyond the range: within `near` of its nearer end is that end.
            match (f_lo.abs() <= near, f_hi.abs() <= near) {
                (true, _) if f_lo.abs() <= f_hi.abs() => lo,
                (_, true) => hi,
                (true, false) => lo,
                (false, false) => return Err(unreachable()),
            }
        } else {
            // Illinois regula falsi.
            let (mut a0, mut fa, mut b0, mut fb) = (lo, f_lo, hi, f_hi);
            let mut side = 0;
            let mut x = lo;
            for _ in 0..100 {
                x = (a0 * fb - b0 * fa) / (fb - fa);
                let fx = best(x)? - object_vergence_d;
                if fx.abs() <= tol || (b0 - a0).abs() < 1e-13 {
                    break;
                }
                if (fx < 0.0) == (fb < 0.0) {
                    b0 = x;
                    fb = fx;
                    if side == -1 {
                        fa *= 0.5;
                    }
                    side = -1;
                } else {
                    a0 = x;
                    fa = fx;
                    if side == 1 {
                        fb *= 0.5;
                    }
                    side = 1;
                }
            }
            x
        };
        Ok((SchematicEye::new(model, a, source)?, a))
    }
}
