//! Resolution targets (the paper's Sec. 4 comparison "in terms of perceived spatial
//! resolution", and the Fourier-domain analysis its conclusion calls for): a sinusoidal
//! [`Grating`] and a [`SlantedEdge`] (ISO 12233), both defined in the **tangent coordinates**
//! of the hit point seen from the origin (the eye's pupil centre by convention):
//! `t = (x / z, y / z)`.
//!
//! Tangent coordinates make a target mean the same at every depth (a frequency in cycles per
//! degree is an angular frequency), and they are what the thin-lens eye maps linearly onto the
//! retina (`optics::eye`: the retina is uniform in tangents, and a defocused eye spreads each
//! tangent over a disk of tangent diameter `pupil * |1/z - 1/z_focus|`). So the perceived
//! image of a grating is an exact sinusoid of the same tangent frequency, which the analytic
//! MTF tests rely on. Frequencies are converted with one radian = one tangent unit
//! (`cycles per radian = cpd * 180 / pi`), exact on the axis and the convention everywhere.

use glam::{DVec2, DVec3};

use crate::ray::Ray;

/// Tangent coordinates `(x / z, y / z)` of a point seen from the origin; `None` for points
/// not in front of it (`z <= 0` or not finite).
#[inline]
pub fn tangent_of(p: DVec3) -> Option<DVec2> {
    let t = DVec2::new(p.x / p.z, p.y / p.z);
    (p.z > 0.0 && t.is_finite()).then_some(t)
}

/// Tangent coordinates of the hit at ray parameter `t`: the point `ray.origin + t * ray.dir`
/// (the one formula every renderer uses, so that fast paths agree with the generic path bit
/// for bit).
#[inline]
pub fn hit_tangent(ray: &Ray, t: f64) -> Option<DVec2> {
    tangent_of(ray.origin + t * ray.dir)
}

/// Unit vector at `deg` degrees counter-clockwise from +x (in the tangent plane, +y up).
#[inline]
fn unit_at(deg: f64) -> DVec2 {
    let (s, c) = deg.to_radians().sin_cos();
    DVec2::new(c, s)
}

/// A sinusoidal grating: `mean * (1 + contrast * cos(2 pi f t.n + phase))`, with `f` in cycles
/// per radian and `n` the unit normal to the bars (the direction of modulation). Grey: the
/// same value in R, G and B.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grating {
    /// Angular frequency seen from the pupil centre, cycles per degree.
    pub frequency_cpd: f64,
    /// Direction of modulation, degrees counter-clockwise from +x: 0 = vertical bars
    /// (modulation along x), 90 = horizontal bars.
    pub orientation_deg: f64,
    /// Mean value (albedo).
    pub mean: f64,
    /// Michelson contrast, 0..=1.
    pub contrast: f64,
    /// Phase at the origin's line of sight (t = 0), degrees.
    pub phase_deg: f64,
}

impl Grating {
    /// Frequency in cycles per radian (per tangent unit).
    pub fn cycles_per_radian(&self) -> f64 {
        self.frequency_cpd * 180.0 / std::f64::consts::PI
    }

    /// The unit normal to the bars.
    pub fn normal(&self) -> DVec2 {
        unit_at(self.orientation_deg)
    }

    /// The value at tangent coordinates `t`.
    #[inline]
    pub fn value(&self, t: DVec2) -> f64 {
        let arg = std::f64::consts::TAU * self.cycles_per_radian() * t.dot(self.normal()) + self.phase_deg.to_radians();
        self.mean * (1.0 + self.contrast * arg.cos())
    }

    /// What a point without tangent coordinates (behind the eye) sees: the mean.
    #[inline]
    pub fn at(&self, t: Option<DVec2>) -> DVec3 {
        DVec3::splat(t.map_or(self.mean, |t| self.value(t)))
    }

    /// Checks the parameters; `Err` holds the name of the offending field and why.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let f = self.frequency_cpd;
        if !(f.is_finite() && f > 0.0 && f <= 1e4) {
            return Err(("frequency_cpd", format!("must be positive and at most 1e4 cycles per degree, got {f}")));
        }
        if !self.orientation_deg.is_finite() {
            return Err(("orientation_deg", format!("must be finite, got {}", self.orientation_deg)));
        }
        if !(self.mean.is_finite() && self.mean >= 0.0 && self.mean <= 1e15) {
            return Err(("mean", format!("must be between 0 and 1e15, got {}", self.mean)));
        }
        if !(0.0..=1.0).contains(&self.contrast) {
            return Err(("contrast", format!("must be between 0 and 1 (Michelson), got {}", self.contrast)));
        }
        if !self.phase_deg.is_finite() {
            return Err(("phase_deg", format!("must be finite, got {}", self.phase_deg)));
        }
        Ok(())
    }
}

/// A slanted edge: `high` on the side of the line through `through` that its normal points
/// to, `low` on the other side. The normal is at `angle_deg` counter-clockwise from +x, so 0
/// is a vertical edge with `high` on the right, 5 (the ISO 12233 kind of slant) the same edge
/// turned 5 degrees counter-clockwise, 95 a nearly horizontal edge with `high` above. Points
/// on the line are `high`. Grey.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlantedEdge {
    /// A point of the edge, tangent coordinates.
    pub through: DVec2,
    /// Normal direction, degrees counter-clockwise from +x (toward `high`).
    pub angle_deg: f64,
    /// Value on the dark side.
    pub low: f64,
    /// Value on the light side.
    pub high: f64,
}

impl SlantedEdge {
    /// The unit normal of the edge, pointing to the `high` side.
    pub fn normal(&self) -> DVec2 {
        unit_at(self.angle_deg)
    }

    /// The value at tangent coordinates `t`.
    #[inline]
    pub fn value(&self, t: DVec2) -> f64 {
        if (t - self.through).dot(self.normal()) >= 0.0 {
            self.high
        } else {
            self.low
        }
    }

    /// What a point without tangent coordinates (behind the eye) sees: the mean of both sides.
    #[inline]
    pub fn at(&self, t: Option<DVec2>) -> DVec3 {
        DVec3::splat(t.map_or(0.5 * (self.low + self.high), |t| self.value(t)))
    }

    /// Checks the parameters; `Err` holds the name of the offending field and why.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        if !self.through.is_finite() {
            return Err(("through", format!("must be finite, got {:?}", self.through.to_array())));
        }
        if !self.angle_deg.is_finite() {
            return Err(("angle_deg", format!("must be finite, got {}", self.angle_deg)));
        }
        for (name, v) in [("low", self.low), ("high", self.high)] {
            if !(v.is_finite() && (0.0..=1e15).contains(&v)) {
                return Err((name, format!("must be between 0 and 1e15, got {v}")));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grating_has_its_frequency_contrast_and_orientation_in_tangent_space() {
        let g = Grating { frequency_cpd: 3.0, orientation_deg: 0.0, mean: 0.5, contrast: 0.8, phase_deg: 0.0 };
        // Peak at t = 0, trough half a period further along x; nothing changes along y.
        let period = 1.0 / g.cycles_per_radian();
        assert!((g.value(DVec2::ZERO) - 0.9).abs() < 1e-15);
        assert!((g.value(DVec2::new(0.5 * period, 0.0)) - 0.1).abs() < 1e-12);
        assert!((g.value(DVec2::new(0.0, 0.37)) - 0.9).abs() < 1e-15);
        // 3 cpd: one period is a third of a degree (in tangent units).
        assert!((period - (1.0f64 / 3.0).to_radians()).abs() < 1e-15);
        // Horizontal bars: modulation along y; phase shifts the pattern.
        let h = Grating { orientation_deg: 90.0, phase_deg: 180.0, ..g };
        assert!((h.value(DVec2::ZERO) - 0.1).abs() < 1e-12);
        assert!((h.value(DVec2::new(0.3, 0.0)) - 0.1).abs() < 1e-12);
        // The same grating on planes at two depths: the same tangent, the same value.
        let p = DVec3::new(1.3, -0.4, 250.0);
        let (a, b) = (g.value(tangent_of(p).unwrap()), g.value(tangent_of(p * 3.0).unwrap()));
        assert!((a - b).abs() < 1e-14, "{a} {b}");
        assert_eq!(tangent_of(DVec3::new(1.0, 1.0, -2.0)), None);
    }

    #[test]
    fn edge_is_high_on_the_side_of_its_normal() {
        let e = SlantedEdge { through: DVec2::new(0.01, 0.0), angle_deg: 5.0, low: 0.1, high: 0.9 };
        assert_eq!(e.value(DVec2::new(0.02, 0.0)), 0.9);
        assert_eq!(e.value(DVec2::new(0.0, 0.0)), 0.1);
        // Along the edge line (direction (-sin 5, cos 5)) the side flips exactly at the line.
        let d = DVec2::new(-(5.0f64.to_radians().sin()), 5.0f64.to_radians().cos());
        let on = e.through + 0.05 * d;
        assert_eq!(e.value(on + 1e-9 * e.normal()), 0.9);
        assert_eq!(e.value(on - 1e-9 * e.normal()), 0.1);
        let bad = SlantedEdge { low: -1.0, ..e };
        assert_eq!(bad.check().unwrap_err().0, "low");
    }
}
