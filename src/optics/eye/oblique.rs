//! Off-axis (oblique) astigmatism of a schematic eye: the sagittal and tangential foci at a
//! field angle, by Coddington's equations along the exact chief ray.
//!
//! The chief ray (through the iris centre) of the field angle is found and traced surface by
//! surface by the exact tracer ([`super::trace`]). Along it, the thin astigmatic pencil around
//! the chief ray is followed in its two principal sections, the tangential (the plane of the
//! chief ray and the axis) and the sagittal (across it), by Coddington's equations (H.
//! Coddington, "A Treatise on the Reflexion and Refraction of Light", 1829; here in vergence
//! form, e.g. W. T. Welford, "Aberrations of Optical Systems", Hilger 1986):
//!
//! - sagittal: `V' = V + (n' cos I' - n cos I) κs`,
//! - tangential: `V' cos² I' = V cos² I + (n' cos I' - n cos I) κt`,
//!
//! with `V = n / l` the pencil's reduced vergence (l the signed distance along the ray to its
//! focus, positive downstream), I and I' the chief ray's angles of incidence and refraction, and
//! κt and κs the surface's principal curvatures where the chief ray meets it, signed positive
//! when the centre of curvature lies downstream. Between surfaces `V ← V / (1 - d V / n)` over
//! the distance d along the chief ray. For a conic of revolution (vertex curvature c, conic
//! constant Q) at distance r from the axis, the meridional and sagittal curvatures are
//! `κt = c / (1 - Q c² r²)^(3/2)` and `κs = c / (1 - Q c² r²)^(1/2)` (from the sag of
//! [`super::conic`]; e.g. Y.-Z. Wang & L. N. Thibos, "Oblique (off-axis) astigmatism of the
//! reduced schematic eye with elliptical refracting surface", Optom. Vis. Sci. 74:557, 1997,
//! who apply Coddington's equations to aspheric eyes the same way). A meridional chief ray meets
//! every surface of revolution in one of its principal sections, so the ordinary (not the
//! generalised) equations are exact for the infinitesimal pencil.
//!
//! The **refraction** at the field angle is found by running the equations backward from a point
//! source on the retina where the chief ray lands: the object vergence (D, `1000 / distance`
//! along the object-space chief ray from its crossing of the entrance-pupil plane z = 0;
//! positive for a point in front of the eye, as [`super::Paraxial::conjugate_vergence_d`])
//! whose sagittal, and whose tangential, focal line lies on the retina. The **image side** is
//! the forward run from an object at a given vergence: where its two focal lines lie along the
//! chief ray, relative to the retina.

use glam::{DVec2, DVec3};
use serde::Serialize;

use super::trace::{EyeAtWavelength, Refraction};
use super::SchematicEye;
use crate::optics::PlaneRay;

/// The astigmatic foci of a schematic eye at one field angle (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ObliqueFoci {
    /// The field angle: the object-space chief ray's angle with the optical axis, degrees.
    pub field_deg: f64,
    /// The wavelength, nm.
    pub wavelength_nm: f64,
    /// The object vergence whose sagittal focal line lies on the retina, D (from the entrance
    /// pupil along the chief ray; positive in front of the eye, i.e. myopic).
    pub sagittal_d: f64,
    /// The object vergence whose tangential focal line lies on the retina, D.
    pub tangential_d: f64,
    /// `tangential_d - sagittal_d`, D: positive when the tangential line is the nearer focus,
    /// as in human eyes.
    pub astigmatism_d: f64,
    /// The mean of the two (the vergence that puts the circle of least confusion on the
    /// retina, to first order), D.
    pub mean_d: f64,
    /// The object vergence the image-side positions below are for, D.
    pub object_d: f64,
    /// Where that object's sagittal focal line lies: mm along the chief ray in front of the
    /// retina (toward the lens; negative behind the retina).
    pub sagittal_before_retina_mm: f64,
    /// The same for the tangential focal line, mm.
    pub tangential_before_retina_mm: f64,
    /// The chief ray's landing point's distance from the axis, mm.
    pub retina_height_mm: f64,
}

/// One surface as the chief ray meets it: indices before and after, cosines of the angles of
/// incidence and refraction, and the oblique powers `(n' cos I' - n cos I) κ` of the two
/// sections (1/mm).
#[derive(Clone, Copy, Debug)]
struct Crossing {
    cos_i: f64,
    cos_o: f64,
    sagittal_power: f64,
    tangential_power: f64,
}

/// The chief ray's path as the pencil sees it.
struct ChiefPath {
    crossings: Vec<Crossing>,
    /// `gaps[i]`: distance along the chief ray from surface i to surface i + 1 (the last: to
    /// the retina), in the medium of index `index[i + 1]`.
    gaps: Vec<f64>,
    /// `index[0]` air, `index[i + 1]` after surface i.
    index: Vec<f64>,
    /// Signed distance from the chief ray's crossing of z = 0 to the cornea, downstream
    /// (negative: the entrance pupil lies inside the eye, after the cornea).
    to_cornea: f64,
    retina_height: f64,
}

/// The sagittal and tangential foci of `eye` at `field_deg` degrees off axis, at `wavelength_nm`;
/// the image side for an object at `object_d` dioptres. None when the chief ray is blocked (a
/// semi-diameter, total internal reflection, a missed surface) or its aim does not converge.
pub fn oblique_foci(eye: &SchematicEye, field_deg: f64, object_d: f64, wavelength_nm: f64) -> Option<ObliqueFoci> {
    if !(field_deg.is_finite() && field_deg.abs() < 90.0 && object_d.is_finite() && wavelength_nm > 0.0) {
        return None;
    }
    let at = eye.at(wavelength_nm);
    let tangent = DVec2::new(field_deg.abs().to_radians().tan(), 0.0);
    let (_, position) = at.chief_ray(tangent)?;
    let (refractions, retina) = at.recorded_in(PlaneRay { position, slope: tangent })?;
    let path = chief_path(eye, &at, position, &refractions, retina)?;
    let [sagittal_d, tangential_d] = [false, true].map(|t| 1000.0 * path.retina_conjugate(t));
    let [sagittal_before_retina_mm, tangential_before_retina_mm] =
        [false, true].map(|t| path.focus_before_retina(object_d / 1000.0, t));
    let out = ObliqueFoci {
        field_deg,
        wavelength_nm,
        sagittal_d,
        tangential_d,
        astigmatism_d: tangential_d - sagittal_d,
        mean_d: 0.5 * (sagittal_d + tangential_d),
        object_d,
        sagittal_before_retina_mm,
        tangential_before_retina_mm,
        retina_height_mm: path.retina_height,
    };
    (out.sagittal_d.is_finite() && out.tangential_d.is_finite()).then_some(out)
}

/// The crossings, gaps and indices of the recorded chief ray (lens-design frame).
fn chief_path(
    eye: &SchematicEye,
    at: &EyeAtWavelength<'_>,
    position: DVec2,
    refractions: &[Refraction],
    retina: DVec3,
) -> Option<ChiefPath> {
    let n = refractions.len();
    let index: Vec<f64> = (0..=n).map(|i| at.index(i)).collect();
    let mut crossings = Vec::with_capacity(n);
    for (i, r) in refractions.iter().enumerate() {
        let s = &eye.surfaces[i];
        let normal = s.normal(r.point);
        let (c, q) = (s.curvature, s.conic);
        let r2 = r.point.x * r.point.x + r.point.y * r.point.y;
        let u = 1.0 - q * c * c * r2;
        if u <= 0.0 {
            return None;
        }
        // Curvatures are positive when the centre of curvature lies along `normal` (toward the
        // retina): signed for the direction of travel.
        let sign = r.before.dot(normal).signum();
        let (kappa_s, kappa_t) = (sign * c / u.sqrt(), sign * c / (u * u.sqrt()));
        let (cos_i, cos_o) = (r.before.dot(normal).abs(), r.after.dot(normal).abs());
        let oblique = index[i + 1] * cos_o - index[i] * cos_i;
        crossings.push(Crossing {
            cos_i,
            cos_o,
            sagittal_power: oblique * kappa_s,
            tangential_power: oblique * kappa_t,
        });
    }
    let mut gaps: Vec<f64> = refractions.windows(2).map(|w| (w[1].point - w[0].point).length()).collect();
    gaps.push((retina - refractions.last()?.point).length());
    let entrance = DVec3::new(position.x, position.y, eye.origin_t);
    let to_cornea = (refractions[0].point - entrance).dot(refractions[0].before);
    Some(ChiefPath { crossings, gaps, index, to_cornea, retina_height: retina.truncate().length() })
}

/// The reduced vergence `v` carried `d` downstream through a medium of index `n`.
#[inline]
fn transfer(v: f64, d: f64, n: f64) -> f64 {
    v / (1.0 - d * v / n)
}

impl ChiefPath {
    /// The object vergence (1/mm, from the entrance-pupil plane) conjugate to the retina point
    /// in the tangential (`tangential`) or sagittal section: the pencil of a point source on the
    /// retina, traced back out of the eye.
    fn retina_conjugate(&self, tangential: bool) -> f64 {
        let last = self.crossings.len();
        let mut v = self.index[last] / -self.gaps[last - 1];
        for i in (0..last).rev() {
            let c = &self.crossings[i];
            v = if tangential {
                (v * c.cos_o * c.cos_o + c.tangential_power) / (c.cos_i * c.cos_i)
            } else {
                v + c.sagittal_power
            };
            if i > 0 {
                v = transfer(v, self.gaps[i - 1], self.index[i]);
            }
        }
        // Out of the cornea to the entrance-pupil plane (behind it, so upstream of the
        // outgoing light): `to_cornea` downstream of the forward light is the same distance.
        transfer(v, self.to_cornea, 1.0)
    }

    /// Where the focal line of the section of an object at vergence `object` (1/mm) lies: mm
    /// along the chief ray in front of the retina.
    fn focus_before_retina(&self, object: f64, tangential: bool) -> f64 {
        let mut v = transfer(-object, self.to_cornea, 1.0);
        for (i, c) in self.crossings.iter().enumerate() {
            v = if tangential {
                (v * c.cos_i * c.cos_i + c.tangential_power) / (c.cos_o * c.cos_o)
            } else {
                v + c.sagittal_power
            };
            if i + 1 < self.crossings.len() {
                v = transfer(v, self.gaps[i], self.index[i + 1]);
            }
        }
        let last = self.crossings.len();
        self.gaps[last - 1] - self.index[last] / v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::eye::EyeModel;

    #[test]
    fn on_the_axis_both_sections_are_the_paraxial_conjugate() {
        for model in [EyeModel::Navarro1985, EyeModel::Navarro1999, EyeModel::Arizona, EyeModel::LeGrand] {
            let eye = SchematicEye::new(&model, 0.0, "t").unwrap();
            for nm in [450.0, 555.0, 650.0] {
                let f = oblique_foci(&eye, 0.0, 0.0, nm).unwrap();
                let p = eye.paraxial(nm).conjugate_vergence_d;
                assert!((f.sagittal_d - p).abs() < 1e-9 && (f.tangential_d - p).abs() < 1e-9, "{f:?} vs {p}");
                assert_eq!(f.retina_height_mm, 0.0);
            }
        }
    }

    #[test]
    fn an_object_at_the_conjugate_vergence_focuses_on_the_retina() {
        let eye = SchematicEye::new(&EyeModel::Navarro1999, 1.0, "t").unwrap();
        for field in [5.0, 20.0, 40.0, -30.0] {
            let f = oblique_foci(&eye, field, 0.0, 555.0).unwrap();
            let s = oblique_foci(&eye, field, f.sagittal_d, 555.0).unwrap();
            let t = oblique_foci(&eye, field, f.tangential_d, 555.0).unwrap();
            assert!(s.sagittal_before_retina_mm.abs() < 1e-9, "{s:?}");
            assert!(t.tangential_before_retina_mm.abs() < 1e-9, "{t:?}");
            // The tangential line (the more myopic) focuses in front of the sagittal one.
            assert!(f.astigmatism_d > 0.0 && s.tangential_before_retina_mm > 0.0, "{f:?} {s:?}");
            // One field angle mirrors the other.
            assert_eq!(f.sagittal_d, oblique_foci(&eye, -field, 0.0, 555.0).unwrap().sagittal_d);
        }
    }

    #[test]
    fn a_blocked_chief_ray_or_a_bad_angle_gives_none() {
        let eye = SchematicEye::new(&EyeModel::Navarro1985, 0.0, "t").unwrap();
        for field in [f64::NAN, 90.0, 89.0] {
            assert!(oblique_foci(&eye, field, 0.0, 555.0).is_none(), "{field}");
        }
    }
}
