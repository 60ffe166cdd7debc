//! Le Grand's full theoretical eye: Y. Le Grand & S. G. El Hage, "Physiological Optics",
//! Springer Series in Optical Sciences 13 (1980), Table 5 (as tabulated by D. A. Atchison &
//! G. Smith, "Optics of the Human Eye", Butterworth-Heinemann 2000, Appendix 3): spherical
//! surfaces, unaccommodated, total power 59.94 D.
//!
//! | surface | R (mm) | thickness to next (mm) | n |
//! |---|---|---|---|
//! | cornea front | 7.8 | 0.55 | 1.3771 |
//! | cornea back | 6.5 | 3.05 | 1.3374 |
//! | lens front | 10.2 | 4.0 | 1.42 |
//! | lens back | -6.0 | 16.5966 | 1.336 |
//!
//! The model gives one index per medium. Its dispersion here is Navarro et al.'s (JOSA A 2:1273,
//! 1985, Table 3, see [`super::medium`]), shifted per medium so that it passes through Le Grand's
//! index at 589.3 nm. The retina, which the model does not specify, is a sphere of radius
//! -12 mm (Navarro 1999's); the iris lies in the plane of the lens front vertex (3.6 mm).

use super::medium::{navarro_media, Dispersion};
use super::model::{EyeDefinition, SurfaceDef, REFERENCE_WAVELENGTH};

/// Navarro's dispersion through `n589` at 589.3 nm.
fn shifted(n: [f64; 4], n589: f64) -> Dispersion {
    let base = Dispersion::Navarro { n, offset: 0.0 }.index(589.3);
    Dispersion::Navarro { n, offset: n589 - base }
}

/// The surface table.
pub(crate) fn definition() -> EyeDefinition {
    let s = |radius: f64, thickness: f64, medium: Dispersion, semi_diameter: f64| SurfaceDef {
        radius,
        conic: 0.0,
        thickness,
        medium,
        semi_diameter,
    };
    EyeDefinition {
        surfaces: vec![
            s(7.8, 0.55, shifted(navarro_media::CORNEA, 1.3771), 5.5),
            s(6.5, 3.05, shifted(navarro_media::AQUEOUS, 1.3374), 5.5),
            s(10.2, 4.0, shifted(navarro_media::LENS, 1.42), 4.5),
            s(-6.0, 16.5966, shifted(navarro_media::VITREOUS, 1.336), 4.5),
        ],
        iris_after: 1,
        iris_distance: 3.05,
        retina_radius: -12.0,
        reference_wavelength: REFERENCE_WAVELENGTH,
    }
}
