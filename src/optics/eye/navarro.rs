//! The Navarro accommodating schematic eye: R. Navarro, J. Santamaria & J. Bescos,
//! "Accommodation-dependent model of the human eye with aspherics", JOSA A 2:1273-1281 (1985),
//! Tables 1 and 2 (surfaces, ln(A+1) laws of accommodation) and Table 3 (dispersion, see
//! [`super::medium`]); and its wide-angle variant, I. Escudero-Sanz & R. Navarro, "Off-axis
//! aberrations of a wide-angle schematic eye model", JOSA A 16:1881-1891 (1999), Table 1:
//! the same optics with a spherical retina of radius -12 mm and a vitreous of 16.3203 mm.
//!
//! | surface | R (mm) | Q | thickness to next (mm) | medium (n at 589.3 nm) |
//! |---|---|---|---|---|
//! | cornea front | 7.72 | -0.26 | 0.55 | cornea 1.376 |
//! | cornea back | 6.50 | 0 | 3.05 - 0.05 L | aqueous 1.3374 |
//! | lens front | 10.2 - 1.75 L | -3.1316 - 0.34 L | 4.0 + 0.1 L | lens 1.42 + 9e-5 (10A + A²) |
//! | lens back | -6.0 + 0.2294 L | -1.0 - 0.125 L | vitreous (24.0 or 23.9203 mm axial length) | vitreous 1.336 |
//! | retina | -12 | 0 | | |
//!
//! L = ln(A + 1), A the accommodation in dioptres. Each medium's dispersion (Table 3, Eq. 4)
//! is shifted by a constant so that it passes through the Table 1 index at 589.3 nm exactly. The axial length is held fixed as the lens
//! accommodates (the vitreous takes up the lens's backward growth of 0.05 L); the iris is in the
//! plane of the lens front vertex. Semi-diameters (not in the papers): cornea 5.5 mm, lens
//! 4.5 mm, retina its full hemisphere. Both variants use the 1985 accommodation laws.

use super::medium::{navarro_media, Dispersion};
use super::model::{EyeDefinition, SurfaceDef, REFERENCE_WAVELENGTH};

/// The surface table at accommodation `a` (D); `wide_angle` selects the 1999 variant.
pub(crate) fn definition(a: f64, wide_angle: bool) -> EyeDefinition {
    let l = (a + 1.0).ln();
    let axial = if wide_angle { 0.55 + 3.05 + 4.0 + 16.3203 } else { 0.55 + 3.05 + 4.0 + 16.40 };
    let aqueous = 3.05 - 0.05 * l;
    let lens = 4.0 + 0.1 * l;
    let vitreous = axial - 0.55 - aqueous - lens;
    // Eq. (4) through the Table 1 index at 589.3 nm (the interpolation misses it by up to
    // 6e-5, 0.01 D of the model's 60.416 D).
    let medium = |n: [f64; 4], offset: f64| {
        let n589 = match n {
            x if x == navarro_media::CORNEA => 1.376,
            x if x == navarro_media::AQUEOUS => 1.3374,
            x if x == navarro_media::LENS => 1.42,
            _ => 1.336,
        };
        let shift = n589 - Dispersion::Navarro { n, offset: 0.0 }.index(589.3);
        Dispersion::Navarro { n, offset: offset + shift }
    };
    let surfaces = vec![
        SurfaceDef {
            radius: 7.72,
            conic: -0.26,
            thickness: 0.55,
            medium: medium(navarro_media::CORNEA, 0.0),
            semi_diameter: 5.5,
        },
        SurfaceDef {
            radius: 6.50,
            conic: 0.0,
            thickness: aqueous,
            medium: medium(navarro_media::AQUEOUS, 0.0),
            semi_diameter: 5.5,
        },
        SurfaceDef {
            radius: 10.2 - 1.75 * l,
            conic: -3.1316 - 0.34 * l,
            thickness: lens,
            medium: medium(navarro_media::LENS, 9e-5 * (10.0 * a + a * a)),
            semi_diameter: 4.5,
        },
        SurfaceDef {
            radius: -6.0 + 0.2294 * l,
            conic: -1.0 - 0.125 * l,
            thickness: vitreous,
            medium: medium(navarro_media::VITREOUS, 0.0),
            semi_diameter: 4.5,
        },
    ];
    EyeDefinition {
        surfaces,
        iris_after: 1,
        iris_distance: aqueous,
        retina_radius: -12.0,
        reference_wavelength: REFERENCE_WAVELENGTH,
    }
}
