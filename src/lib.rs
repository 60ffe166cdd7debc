//! inimtrace: simulates how a near-eye integral-imaging (InIm) light-field display looks to a
//! human eye, and scores the ways of rendering its display image (LensletCenter, PupilCenter,
//! LensletAverage), after O. Doronin, E. Sahin, R. Bregovic and A. Gotchev, "A framework for
//! assessing rendering techniques for near-eye integral imaging displays", ICIP 2020.
//!
//! Conventions (see README): millimetres; the eye's pupil centre is the origin; +z points from
//! the eye toward the display and the scene, +x right, +y up; images are stored with row 0 at
//! the top. Optics is computed in `f64`.
//!
//! Layers, bottom up (a module imports only from layers below it): `error`, `raster`, `progress`
//! and `ray` (rays, hits, the intersector interface); `optics` (eq. (1)) and `scene`; `accel`
//! (intersection backends over the scene's data), `metrics` and `io` (file formats); `render`;
//! `experiment`, `resolution` (MTF measurements) and `bench`; `overrides` and `settings` (`--set` and the resolved settings of a
//! run); `sweep`.
//!
//! `unsafe` code is denied everywhere except in the Embree wrapper (`accel::embree`).

#![deny(unsafe_code)]

pub mod accel;
pub mod bench;
pub mod budget;
pub mod cpu;
pub mod error;
pub mod experiment;
#[doc(hidden)]
pub mod fixtures;
pub mod info;
pub mod io;
pub mod measure;
pub mod metrics;
pub mod optics;
pub mod overrides;
pub mod progress;
pub mod raster;
pub mod ray;
pub mod render;
pub mod resolution;
pub mod scene;
pub mod settings;
pub mod sweep;
pub mod version;

pub use error::{Error, Result};
