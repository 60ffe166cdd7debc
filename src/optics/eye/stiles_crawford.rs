//! The Stiles-Crawford effect of the first kind (W. S. Stiles & B. H. Crawford, Proc. R. Soc.
//! B 112:428, 1933) in the Gaussian form of R. A. Applegate & V. Lakshminarayanan (JOSA A
//! 10:1611, 1993): light through entrance-pupil point p counts with the relative efficiency
//! `eta(p) = 10^(-rho |p - p0|^2)`, peaked at p0. A retina pixel's value is the eta-weighted
//! mean over the pupil, so a uniform scene keeps its value.
//!
//! The estimators draw uniform points of the pupil disk (radius a). Each becomes a sample of
//! that weighted mean:
//!
//! - **Centred peak** (p0 = 0): the point is moved radially so that uniform points become
//!   points of density proportional to eta (the inverse of the radial distribution, exact), and
//!   every sample counts once: a uniform scene stays exactly uniform.
//! - **Off-centre peak**: the point stays uniform and carries the weight `eta(p) / mean(eta)`,
//!   the mean over the disk. Uniform points cover the whole pupil, so the weight is bounded by
//!   `pi a^2 / N` (N the integral of eta over the disk) wherever the peak lies, up to the pupil's
//!   edge; it is computed as `exp(-k |p - p0|^2 + ln(pi a^2 / N))` (k = rho ln 10), which never
//!   overflows. `N = 2 pi Int_0^a r exp(-k (r - d)^2) i0e(2 k r d) dr` (d = |p0|; the angular
//!   integral of the offset Gaussian is a modified Bessel function, Abramowitz & Stegun 9.6.16,
//!   written with the exponentially scaled `i0e(x) = exp(-x) I0(x)`), by composite
//!   Gauss-Legendre panels a quarter of the peak's width wide.

use glam::DVec2;

/// The Stiles-Crawford apodization over the entrance pupil.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StilesCrawford {
    /// rho, 1/mm^2 (0.05 by default).
    pub rho: f64,
    /// The peak's position in the entrance pupil, mm from its centre.
    pub peak: DVec2,
    /// `ln(pi a^2 / N)`: the log of one over the mean of eta over the disk (0 for a centred
    /// peak, whose points are warped instead of weighted).
    log_norm: f64,
    /// Whether samples carry weights: an off-centre peak, rho > 0 and a pupil (a pinhole's one
    /// ray counts as it is).
    weighted: bool,
}

impl StilesCrawford {
    /// The apodization with `rho` (1/mm^2) peaked at `peak` (mm) over a pupil of `radius` mm.
    pub fn new(rho: f64, peak: DVec2, radius: f64) -> Self {
        let weighted = peak != DVec2::ZERO && rho > 0.0 && radius > 0.0;
        let mut s = Self { rho, peak, log_norm: 0.0, weighted };
        if weighted {
            let area = std::f64::consts::PI * radius * radius;
            s.log_norm = area.ln() - offset_gaussian_over_disk(s.k(), peak.length(), radius).ln();
        }
        s
    }

    /// `k = rho ln 10`: eta is `exp(-k |p - p0|^2)`.
    fn k(&self) -> f64 {
        self.rho * std::f64::consts::LN_10
    }

    /// The uniform disk point `p` (radius `radius`) as the sample's pupil point: for a centred
    /// peak moved radially so that uniform points become points of density proportional to
    /// `10^(-rho r^2)`; for an off-centre peak unchanged (its weight carries eta).
    #[inline]
    pub fn warp(&self, p: DVec2, radius: f64) -> DVec2 {
        let r2 = p.length_squared();
        if self.peak != DVec2::ZERO || r2 == 0.0 || radius == 0.0 || self.rho == 0.0 {
            return p;
        }
        let s = r2 / (radius * radius);
        let k = self.k();
        // F(r) = (1 - e^{-k r^2}) / (1 - e^{-k a^2}) = s  =>  r^2 = -ln(1 - s (1 - e^{-k a^2})) / k.
        let new_r2 = -(-s * (-(-k * radius * radius).exp_m1())).ln_1p() / k;
        p * (new_r2 / r2).sqrt()
    }

    /// The weight of the sample at pupil point `p` (as [`StilesCrawford::warp`] returned it): 1
    /// for a centred peak, else `eta(p) / mean(eta)`, finite and at most `pi a^2 / N`.
    #[inline]
    pub fn weight(&self, p: DVec2) -> f64 {
        if self.weighted {
            (self.log_norm - self.k() * (p - self.peak).length_squared()).exp()
        } else {
            1.0
        }
    }

    /// The largest weight a sample can carry (1 for a centred peak).
    pub fn max_weight(&self) -> f64 {
        if self.weighted {
            self.log_norm.exp()
        } else {
            1.0
        }
    }
}

/// `N(k, d, a)`: the integral of `exp(-k |p - p0|^2)` over the disk of radius `a`, `|p0| = d`
/// (see the module comment), relative error about 1e-13.
fn offset_gaussian_over_disk(k: f64, d: f64, a: f64) -> f64 {
    let (nodes, weights) = super::accommodation::gauss_legendre(8);
    // Panels a quarter of the peak's width (1 / sqrt(2k)) wide, at least 16, at most 20,000.
    let width = (2.0 * k).sqrt().recip();
    let panels = ((a / (0.25 * width)).ceil() as usize).clamp(16, 20_000);
    let h = a / panels as f64;
    let mut total = 0.0;
    for i in 0..panels {
        let mid = (i as f64 + 0.5) * h;
        for (x, w) in nodes.iter().zip(&weights) {
            let r = mid + 0.5 * h * x;
            total += 0.5 * h * w * r * (-k * (r - d) * (r - d)).exp() * i0e(2.0 * k * r * d);
        }
    }
    std::f64::consts::TAU * total
}

/// The exponentially scaled modified Bessel function `i0e(x) = exp(-x) I0(x)`, x >= 0: its power
/// series (Abramowitz & Stegun 9.6.10) up to 15, its asymptotic series (A&S 9.7.1) beyond, where
/// the smallest term is below 1e-13.
fn i0e(x: f64) -> f64 {
    if x <= 15.0 {
        let q = 0.25 * x * x;
        let (mut term, mut sum) = (1.0, 1.0);
        for m in 1..200 {
            term *= q / (m * m) as f64;
            sum += term;
            if term < 1e-17 * sum {
                break;
            }
        }
        sum * (-x).exp()
    } else {
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..60 {
            let next = term * ((2 * k - 1) as f64).powi(2) / (8.0 * k as f64 * x);
            if next.abs() >= term.abs() {
                break;
            }
            term = next;
            sum += term;
            if term < 1e-17 {
                break;
            }
        }
        sum / (std::f64::consts::TAU * x).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polar(s: f64, angle: f64, radius: f64) -> DVec2 {
        DVec2::from_angle(angle) * radius * s.sqrt()
    }

    #[test]
    fn i0e_matches_its_tabulated_values_on_both_sides_of_the_switch() {
        // I0(1) = 1.2660658777520082, I0(10) = 2815.716628466254, I0(20) = 4.355828255955353e7
        // (Abramowitz & Stegun Table 9.8 and its scaled columns).
        for (x, i0) in [(1.0, 1.2660658777520082), (10.0, 2815.716628466254), (20.0, 4.355828255955353e7)] {
            let want = i0 * f64::exp(-x);
            assert!((i0e(x) - want).abs() < 1e-12 * want, "{x}: {} vs {want}", i0e(x));
        }
        // Continuity at the switch, and the large-x limit 1 / sqrt(2 pi x).
        assert!((i0e(15.0) - i0e(15.0 + 1e-12)).abs() < 1e-12);
        let big = 1e6;
        assert!((i0e(big) * (std::f64::consts::TAU * big).sqrt() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_disk_integral_of_an_offset_gaussian_matches_the_closed_forms() {
        // Centred: pi (1 - e^{-k a^2}) / k.
        let (k, a): (f64, f64) = (0.7, 3.0);
        let want = std::f64::consts::PI * -(-k * a * a).exp_m1() / k;
        assert!((offset_gaussian_over_disk(k, 0.0, a) - want).abs() < 1e-12 * want);
        // A narrow peak far inside: the whole Gaussian, pi / k.
        let k = 50.0;
        let want = std::f64::consts::PI / k;
        assert!((offset_gaussian_over_disk(k, 5.0, 10.0) - want).abs() < 1e-10 * want);
        // A narrow peak on the rim: half of it (the rim is straight on the peak's scale).
        let got = offset_gaussian_over_disk(k, 10.0, 10.0);
        assert!((got / want - 0.5).abs() < 1e-2, "{}", got / want);
    }

    #[test]
    fn the_warp_draws_the_stiles_crawford_density() {
        // Uniform disk points (by area fraction s) warped: the fraction of points within radius
        // r must be the density's CDF (1 - 10^(-rho r^2)) / (1 - 10^(-rho a^2)).
        let (rho, a) = (0.05, 3.0);
        let sc = StilesCrawford::new(rho, DVec2::ZERO, a);
        for s in [0.1, 0.3, 0.5, 0.8, 0.99] {
            let p = sc.warp(DVec2::new(a * f64::sqrt(s), 0.0), a);
            let r2 = p.length_squared();
            let cdf = (1.0 - 10f64.powf(-rho * r2)) / (1.0 - 10f64.powf(-rho * a * a));
            assert!((cdf - s).abs() < 1e-12, "{s}: {cdf}");
        }
        assert_eq!(sc.weight(DVec2::new(1.0, 1.0)), 1.0);
        // The edge stays the edge, the centre the centre.
        assert!((sc.warp(DVec2::new(0.0, a), a).y - a).abs() < 1e-12);
    }

    #[test]
    fn an_off_centre_peaks_weights_are_eta_over_its_mean() {
        // Uniform points keep their place; the weight is eta(p) / mean(eta), which averages to
        // 1 over the disk (a fine polar grid, independent of the Bessel quadrature) and whose
        // ratio between two points is eta's.
        let a = 2.5;
        let sc = StilesCrawford::new(0.05, DVec2::new(0.5, -0.3), a);
        let p = DVec2::new(1.0, 0.7);
        assert_eq!(sc.warp(p, a), p);
        let eta = |p: DVec2| 10f64.powf(-0.05 * (p - DVec2::new(0.5, -0.3)).length_squared());
        let q = DVec2::new(-2.0, 0.1);
        assert!((sc.weight(p) / sc.weight(q) - eta(p) / eta(q)).abs() < 1e-12);
        let n = 400;
        let mut total = 0.0;
        for i in 0..n {
            for j in 0..n {
                let p = polar((i as f64 + 0.5) / n as f64, std::f64::consts::TAU * (j as f64 + 0.5) / n as f64, a);
                total += sc.weight(sc.warp(p, a));
            }
        }
        let mean = total / (n * n) as f64;
        assert!((mean - 1.0).abs() < 1e-5, "{mean}");
        assert!(sc.max_weight() >= sc.weight(DVec2::new(0.5, -0.3)) * (1.0 - 1e-12));
    }
}
