//! Loading triangle meshes from files: [`load_mesh`] picks the format by extension (Wavefront
//! OBJ in `obj.rs`, Stanford PLY in `ply.rs`) and applies the rules every format shares. Place
//! the loaded mesh in the world with a [`crate::scene::Transform`].
//!
//! The paper's scenes (Sec. 3.1) are planar rectangles; meshes extend the scene so that the
//! display simulation can be run on real 3-D objects through the mesh backends (Embree, BVH,
//! brute force). Everything here is input handling: every malformed file gives an [`Error`]
//! that names the file and the line or element, never a panic.
//!
//! Attribute conventions:
//! * Per-vertex normals, uvs and colours are kept when the file gives them for every vertex
//!   (for merged OBJ objects: for every object); otherwise the attribute is `None`.
//! * UVs are as stored in the file (OBJ/PLY convention: `v = 0` is the bottom of the image).
//! * Colours are taken to be sRGB-encoded (what MeshLab and scanners write) and are linearised
//!   with the sRGB transfer function. PLY integer colours are first divided by their type's
//!   maximum (`uchar` by 255); PLY float and OBJ (`v x y z r g b`) colours are used as given in
//!   `[0, 1]`. So the same 8-bit colour written to a PLY file and, as `c / 255`, to an OBJ file
//!   loads to the same linear value.
//! * Zero-area triangles are removed and counted in [`MeshLoad::dropped_degenerate`]; the caller
//!   warns with the count.

use std::path::{Path, PathBuf};

use super::obj::load_obj;
use super::ply::load_ply;
use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

/// A mesh read from a file.
#[derive(Clone, Debug)]
pub struct MeshLoad {
    /// The mesh in file coordinates (apply a [`crate::scene::Transform`] to place it), degenerate triangles
    /// already removed.
    pub mesh: Mesh,
    /// How many zero-area triangles were removed.
    pub dropped_degenerate: usize,
    /// The OBJ material's diffuse texture, resolved relative to the OBJ file (not checked for
    /// existence: the caller opens it and reports a missing file).
    pub texture: Option<PathBuf>,
}

/// Loads a triangle mesh, choosing the format from the extension (`.obj`, `.ply`, any case).
///
/// Errors (all name the file): missing file or directory ([`Error::Io`]); unknown extension
/// ([`Error::Unsupported`]); malformed content, index out of range, non-finite vertex, or no
/// triangles left ([`Error::Parse`], with the line or element).
pub fn load_mesh(path: &Path) -> Result<MeshLoad> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::io(path, std::io::Error::other("is a directory, expected a mesh file (.obj or .ply)")));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = crate::io::input::read_regular(path)?;
    let (mut mesh, texture) = match ext.as_deref() {
        Some("obj") => load_obj(path, &bytes)?,
        Some("ply") => (load_ply(path, &bytes)?, None),
        _ => {
            return Err(Error::Unsupported(format!(
                "{}: unknown mesh format (expected extension .obj or .ply)",
                path.display()
            )))
        }
    };
    let dropped_degenerate = mesh.remove_degenerate();
    if mesh.triangles.is_empty() {
        let why = if dropped_degenerate > 0 {
            format!("contains no triangles (all {dropped_degenerate} have zero area)")
        } else {
            "contains no triangles (empty mesh)".to_string()
        };
        return Err(Error::parse(path, why));
    }
    // The readers already checked everything; this is a cheap guard that they did.
    mesh.validate(&path.display().to_string())?;
    Ok(MeshLoad { mesh, dropped_degenerate, texture })
}

pub(super) use crate::raster::srgb_to_linear;
