//! Scene description.
pub mod mesh;
