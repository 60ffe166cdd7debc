//! Scene description.
pub mod mesh;
pub mod mesh_io;
