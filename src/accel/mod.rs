//! Scene intersection backends behind one trait, [`crate::ray::Intersector`] (paper Sec. 3.1:
//! "each ray is traversed until it hits an object"). The analytic backend intersects the paper's
//! planar rectangles exactly in `f64`; the mesh backends (brute force, the pure-Rust BVH,
//! Embree) intersect triangle meshes with one watertight triangle test and one nearest-hit rule
//! ([`triangle`]; Embree has its own robust test in `f32`). Backends read the scene's data
//! (`crate::scene`) and nothing above it.

pub mod analytic;
pub mod brute;
pub mod bvh;
pub mod bvh4;
// The crate's only `unsafe` code: the safe wrapper over Embree's C API.
#[cfg(feature = "embree")]
#[allow(unsafe_code)]
pub mod embree;
pub mod triangle;
