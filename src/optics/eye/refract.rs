//! Vector Snell refraction at a surface (Snell's law in vector form: e.g. A. S. Glassner, "An
//! Introduction to Ray Tracing", 1989, Ch. 6; M. Pharr, W. Jakob & G. Humphreys, "Physically
//! Based Rendering", 4th ed., Sec. 9.3). Total internal reflection loses the ray.

use glam::DVec3;

/// The unit direction after refraction of the unit direction `d` from index `n1` into `n2` at a
/// surface with unit normal `normal` (either orientation). None on total internal reflection.
#[inline]
pub fn refract(d: DVec3, normal: DVec3, n1: f64, n2: f64) -> Option<DVec3> {
    let mut cos_i = -normal.dot(d);
    let mut nrm = normal;
    if cos_i < 0.0 {
        cos_i = -cos_i;
        nrm = -normal;
    }
    let eta = n1 / n2;
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        return None;
    }
    Some(eta * d + (eta * cos_i - k.sqrt()) * nrm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snell_holds_and_total_internal_reflection_is_lost() {
        let d = DVec3::new(0.6, 0.0, 0.8);
        let out = refract(d, DVec3::Z, 1.0, 1.5).unwrap();
        assert!((out.length() - 1.0).abs() < 1e-15);
        assert!((1.0 * 0.6 - 1.5 * out.x).abs() < 1e-15, "n sin is conserved");
        // The normal's orientation does not matter.
        assert_eq!(refract(d, -DVec3::Z, 1.0, 1.5), Some(out));
        // From glass to air beyond the critical angle (sin > 1/1.5).
        assert!(refract(DVec3::new(0.8, 0.0, 0.6), DVec3::Z, 1.5, 1.0).is_none());
        // Normal incidence passes straight.
        assert_eq!(refract(DVec3::Z, DVec3::Z, 1.336, 1.42), Some(DVec3::Z));
    }
}
