//! Intel Embree as a scene intersection backend (paper Sec. 3.1: each ray is traversed until it
//! hits an object; Embree does this for triangle meshes).
//!
//! This module owns the crate's only `unsafe` code (the crate root denies it everywhere else).
//! One RAII handle per file:
//! - `sys`: raw bindings that `build.rs` generates with bindgen from `wrapper.h`, or those of
//!   the `embree4-sys` crate (feature `embree4`);
//! - `compat`: the few differences between Embree 3 and Embree 4 (query arguments, padded hit
//!   records, the loaded library's version check);
//! - `device`: [`Device`], the Embree device, with its error callback (`error`: Embree errors
//!   as [`crate::Error::Embree`]);
//! - `geometry`: [`TriangleGeometry`], one committed triangle mesh;
//! - `scene`: [`SceneBuilder`] and the committed, thread-shareable [`Scene`] with its ray
//!   queries on [`RawRay`]s (`ray`);
//! - `live`: the process-wide count of live Embree objects ([`live_objects`]);
//! - `intersector`: [`EmbreeIntersector`], the [`crate::ray::Intersector`] over inimtrace
//!   meshes, where `f64` optics meets Embree's `f32`.
//!
//! The safe API keeps Embree from ever reading out of bounds: vertex positions must be finite,
//! triangle indices must be in range, and rays with non-finite fields are answered "no hit"
//! without calling Embree.

mod compat;
mod device;
mod error;
mod geometry;
mod intersector;
mod live;
mod ray;
mod scene;
mod sys;

pub use compat::{check_version, version_text, EMBREE_MAJOR};
pub use device::Device;
pub use error::{embree_error, error_code_name};
pub use geometry::TriangleGeometry;
pub use intersector::{raw_ray, EmbreeIntersector};
pub use live::live_objects;
pub use ray::{RawHit, RawRay};
pub use scene::{BuildQuality, Scene, SceneBuilder};
