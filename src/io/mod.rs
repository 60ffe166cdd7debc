//! File input and output, one format per file: display files (our TOML and the framework's
//! OpenCV YAML), scene files (TOML), triangle meshes (OBJ, PLY, STL, glTF 2.0 / GLB), OpenEXR
//! images and their typed header attributes, PNG previews and figures. The loaders most callers
//! need are re-exported here.

pub mod csv_table;
pub mod display_file;
pub mod display_intent;
pub mod display_lenslet;
pub mod exr;
mod exr_attributes;
mod exr_file;
pub mod exr_map;
mod exr_read;
pub mod exr_replicates;
mod exr_zip;
pub mod eye_file;
pub mod figure;
mod gltf;
mod gltf_accessor;
mod gltf_material;
mod gltf_nodes;
mod gltf_primitive;
pub(crate) mod input;
pub mod input_log;
pub mod manifest;
pub mod mesh;
mod obj;
pub mod output;
pub(crate) mod plot;
mod ply;
pub mod png;
pub mod scene_file;
mod scene_mesh;
pub(crate) mod scene_target;
mod stl;
pub(crate) mod text;

pub use display_file::load_display;
pub use mesh::{load_mesh, FileMaterial, FileTexture, MeshLoad, MeshPart, TextureSource};
pub use scene_file::load_scene;
