//! Optics: the display, the eye and the paraxial ray transfer between them (paper Sec. 2.3).

pub mod clearance;
pub mod crosstalk;
pub mod diffraction;
pub mod display;
pub mod eye;
pub mod intent;
pub mod lattice;
pub mod lenslet;
pub mod lenslet_lanes;
pub mod lenslet_paraxial;
pub mod limits;
pub mod photometry;
pub mod plausibility;
pub mod spectrum;
pub mod system;
pub mod transfer;

pub use display::{Display, Lcd};
pub use eye::{Aperture, Eye, Focus, Retina};
pub use lattice::Lattice;
pub use transfer::{EyeTrace, PlaneRay};
