//! The analytic MTF of the eye's view of a target (the paper's thin-lens eye of
//! Sec. 2.3 and 4.1): the geometric defocus blur of a circular pupil, `|2 J1(pi b v) / (pi b v)|`
//! for a blur disk of angular diameter `b` (radians) and a frequency `v` (cycles per radian),
//! times the box response of a square retina pixel. In tangent coordinates both are exact for
//! inimtrace's eye (a defocused point spreads uniformly over a disk of tangent diameter
//! `pupil * |1/z - 1/z_focus|`, and a retina pixel averages a tangent square), so the ground
//! truth's contrast must equal their product.

use std::f64::consts::PI;

/// The first zero of `J1`: the defocus MTF first vanishes at `pi b v = J1_FIRST_ZERO`.
pub const J1_FIRST_ZERO: f64 = 3.831_705_970_207_512_3;

/// Bessel function of the first kind, order 1 (`libm`'s implementation).
pub fn bessel_j1(x: f64) -> f64 {
    libm::j1(x)
}

/// `2 J1(x) / x` (1 at `x = 0`): the Fourier transform of a uniform disk, signed.
pub fn jinc(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0 - x * x / 8.0
    } else {
        2.0 * bessel_j1(x) / x
    }
}

/// `sin(x) / x` (1 at `x = 0`).
pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// Angular diameter (radians, tangent units) of the geometric blur disk of an eye with a
/// `pupil_mm` pupil focused at `focus_diopters` looking at content at `target_diopters`:
/// `pupil (m) * |D_target - D_focus|`.
pub fn blur_diameter_rad(pupil_mm: f64, target_diopters: f64, focus_diopters: f64) -> f64 {
    pupil_mm * 1e-3 * (target_diopters - focus_diopters).abs()
}

/// The modulation that defocus leaves at `freq_cycles_per_rad`: `|2 J1(pi b v) / (pi b v)|`
/// (the absolute value: past the first zero the contrast returns with its phase reversed).
pub fn defocus_mtf(blur_diameter_rad: f64, freq_cycles_per_rad: f64) -> f64 {
    jinc(PI * blur_diameter_rad * freq_cycles_per_rad).abs()
}

/// The frequency (cycles per radian) of the defocus MTF's first zero; infinite in focus.
pub fn defocus_first_zero(blur_diameter_rad: f64) -> f64 {
    J1_FIRST_ZERO / (PI * blur_diameter_rad)
}

/// The box response of a square retina pixel of angular size `pixel_rad` to a grating of
/// `freq_cycles_per_rad` whose modulation runs at `orientation_deg` from the pixel's x axis:
/// the product of the two axis sincs, `|sinc(pi v cos(theta) p) sinc(pi v sin(theta) p)|`.
pub fn pixel_mtf(pixel_rad: f64, freq_cycles_per_rad: f64, orientation_deg: f64) -> f64 {
    let (s, c) = orientation_deg.to_radians().sin_cos();
    let x = PI * freq_cycles_per_rad * pixel_rad;
    (sinc(x * c) * sinc(x * s)).abs()
}

/// The whole analytic curve: defocus times the retina pixel's box.
pub fn eye_mtf(blur_diameter_rad: f64, pixel_rad: f64, freq_cycles_per_rad: f64, orientation_deg: f64) -> f64 {
    defocus_mtf(blur_diameter_rad, freq_cycles_per_rad) * pixel_mtf(pixel_rad, freq_cycles_per_rad, orientation_deg)
}

/// Cycles per degree to cycles per radian.
pub fn cpd_to_cycles_per_rad(cpd: f64) -> f64 {
    cpd * 180.0 / PI
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn j1_matches_tabulated_values() {
        // Abramowitz and Stegun, Table 9.1, and the first zero j_{1,1}.
        for (x, j) in [
            (0.0, 0.0),
            (0.5, 0.242_268_457_674_873_9),
            (1.0, 0.440_050_585_744_933_5),
            (2.0, 0.576_724_807_756_873_4),
            (5.0, -0.327_579_137_591_465_2),
            (10.0, 0.043_472_746_168_861_44),
        ] {
            assert!((bessel_j1(x) - j).abs() < 1e-14, "J1({x}) = {}", bessel_j1(x));
        }
        assert!(bessel_j1(J1_FIRST_ZERO).abs() < 1e-15);
        assert!(bessel_j1(-1.0) == -bessel_j1(1.0));
    }

    #[test]
    fn defocus_mtf_is_one_in_focus_and_zero_at_the_first_zero() {
        assert_eq!(defocus_mtf(0.0, 1e4), 1.0);
        // 5 mm pupil, 1 D of defocus: b = 5 mrad; first zero at 3.8317 / (pi 0.005) = 243.9 c/rad.
        let b = blur_diameter_rad(5.0, 2.0, 1.0);
        assert!((b - 0.005).abs() < 1e-18);
        let z = defocus_first_zero(b);
        assert!((z - 243.94).abs() < 0.01, "{z}");
        assert!(defocus_mtf(b, z) < 1e-15);
        // Small argument: 1 - x^2 / 8 + x^4 / 192.
        let x = PI * b;
        assert!((defocus_mtf(b, 1.0) - (1.0 - x * x / 8.0 + x.powi(4) / 192.0)).abs() < 1e-13);
        // 2 J1(x) / x = sum_k (-1)^k (x/2)^(2k) / (k! (k+1)!), for moderate x.
        for x in [0.3, 1.7, 2.2, 4.5] {
            let (mut term, mut sum) = (1.0f64, 1.0f64);
            for k in 1..40 {
                term *= -(x * x / 4.0) / (k as f64 * (k + 1) as f64);
                sum += term;
            }
            assert!((jinc(x) - sum).abs() < 1e-14, "{x}: {} vs {sum}", jinc(x));
        }
    }

    #[test]
    fn pixel_response_is_the_product_of_axis_sincs() {
        let p = 1e-3;
        // Along x: zero at one cycle per pixel, 2/pi at Nyquist.
        assert!(pixel_mtf(p, 1.0 / p, 0.0) < 1e-15);
        assert!((pixel_mtf(p, 0.5 / p, 0.0) - 2.0 / PI).abs() < 1e-15);
        assert!((pixel_mtf(p, 0.5 / p, 90.0) - 2.0 / PI).abs() < 1e-15);
        // At 45 degrees both axes see v / sqrt(2).
        let x = PI * 0.5 / 2f64.sqrt();
        assert!((pixel_mtf(p, 0.5 / p, 45.0) - (x.sin() / x).powi(2)).abs() < 1e-15);
        assert!((cpd_to_cycles_per_rad(1.0) - 57.295_779_513_082_32).abs() < 1e-12);
    }
}
