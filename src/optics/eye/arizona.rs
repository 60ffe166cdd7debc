//! The Arizona eye: J. Schwiegerling, "Field Guide to Visual and Ophthalmic Optics", SPIE Field
//! Guides FG04 (2004), pp. 16-17 (the model after Schwiegerling's Arizona eye of
//! Schwiegerling & Greivenkamp; Zemax's notes and the optrace preset list the same numbers).
//!
//! | surface | R (mm) | Q | thickness to next (mm) | nd | Vd |
//! |---|---|---|---|---|---|
//! | cornea front | 7.8 | -0.25 | 0.55 | 1.377 | 57.1 |
//! | cornea back | 6.5 | -0.25 | 2.97 - 0.04 A | 1.337 | 61.3 |
//! | lens front | 12.0 - 0.4 A | -7.518749 + 1.285720 A | 3.767 + 0.04 A | 1.42 + 0.00256 A - 0.00022 A² | 51.9 |
//! | lens back | -5.224557 + 0.2 A | -1.353971 - 0.431762 A | 16.713 | 1.336 | 61.1 |
//! | retina | -13.4 | 0 | | | |
//!
//! Dispersion: the linear Abbe form of [`super::medium::Dispersion::Abbe`]. The iris is in the
//! plane of the lens front vertex; semi-diameters (not in the model) cornea 5.5 mm, lens 4.5 mm.

use super::medium::Dispersion;
use super::model::{EyeDefinition, SurfaceDef, REFERENCE_WAVELENGTH};

/// The surface table at accommodation `a` (D).
pub(crate) fn definition(a: f64) -> EyeDefinition {
    let aqueous = 2.97 - 0.04 * a;
    let abbe = |nd: f64, vd: f64| Dispersion::Abbe { nd, vd };
    let surfaces = vec![
        SurfaceDef { radius: 7.8, conic: -0.25, thickness: 0.55, medium: abbe(1.377, 57.1), semi_diameter: 5.5 },
        SurfaceDef { radius: 6.5, conic: -0.25, thickness: aqueous, medium: abbe(1.337, 61.3), semi_diameter: 5.5 },
        SurfaceDef {
            radius: 12.0 - 0.4 * a,
            conic: -7.518749 + 1.285720 * a,
            thickness: 3.767 + 0.04 * a,
            medium: abbe(1.42 + 0.00256 * a - 0.00022 * a * a, 51.9),
            semi_diameter: 4.5,
        },
        SurfaceDef {
            radius: -5.224557 + 0.2 * a,
            conic: -1.353971 - 0.431762 * a,
            thickness: 16.713,
            medium: abbe(1.336, 61.1),
            semi_diameter: 4.5,
        },
    ];
    EyeDefinition {
        surfaces,
        iris_after: 1,
        iris_distance: aqueous,
        retina_radius: -13.4,
        reference_wavelength: REFERENCE_WAVELENGTH,
    }
}
