//! File input and output, one format per file: display files (our TOML and the framework's
//! OpenCV YAML), scene files (TOML), triangle meshes (OBJ, PLY), OpenEXR images, PNG previews
//! and figures. The loaders most callers need are re-exported here.

pub mod display_file;
pub mod exr;
pub mod figure;
pub mod input;
pub mod mesh;
mod obj;
pub mod output;
mod ply;
pub mod png;
pub mod scene_file;
pub mod text;

pub use display_file::load_display;
pub use mesh::{load_mesh, MeshLoad};
pub use scene_file::load_scene;
