//! Loading triangle meshes from files: [`load_mesh`] picks the format by extension (Wavefront
//! OBJ in `obj.rs`, Stanford PLY in `ply.rs`, STL in `stl.rs`, glTF 2.0 / GLB in `gltf.rs`) and
//! applies the rules every format shares. Place the loaded mesh in the world with a
//! [`crate::scene::Transform`].
//!
//! The paper's scenes (Sec. 3.1) are planar rectangles; meshes extend the scene so that the
//! display simulation can be run on real 3-D objects through the mesh backends (Embree, BVH,
//! brute force). Everything here is input handling: every malformed file gives an [`Error`]
//! that names the file and the line or element, never a panic.
//!
//! Attribute conventions:
//! * Coordinates are taken as millimetres in every format (glTF's metres are not converted: a
//!   scene file scales with `transform` or `fit`).
//! * Per-vertex normals, uvs and colours are kept when the file gives them for every vertex
//!   (for merged OBJ objects: for every object; for glTF primitives without colours the colour
//!   is white, glTF's neutral value); otherwise the attribute is `None`.
//! * UVs follow the OBJ/PLY convention, `v = 0` at the bottom of the image; glTF's `v` (0 at
//!   the top) is flipped on load (`v' = 1 - v`).
//! * OBJ and PLY colours are taken to be sRGB-encoded (what MeshLab and scanners write) and are
//!   linearised with the sRGB transfer function. PLY integer colours are first divided by their
//!   type's maximum (`uchar` by 255); PLY float and OBJ (`v x y z r g b`) colours are used as
//!   given in `[0, 1]`. So the same 8-bit colour written to a PLY file and, as `c / 255`, to an
//!   OBJ file loads to the same linear value. glTF colours (`COLOR_0`) and base colour factors
//!   are linear by the glTF specification and are used as they are; MTL `Kd` is taken as linear.
//! * Zero-area triangles are removed and counted in [`MeshLoad::dropped_degenerate`]; the caller
//!   warns with the count.
//! * The file's own materials come back as [`MeshPart`]s: consecutive runs of triangles that
//!   share a [`FileMaterial`] (an OBJ `usemtl`, a glTF primitive's material). A scene object
//!   without a `material` uses them.
//! * Files as exporters write them: a `\` in an OBJ/MTL file name is a path separator
//!   (`file_name_path`); a texture that is missing or cannot be read, and vertex colours that
//!   cannot be used, are warnings (the material's base colour is used instead), as in Assimp and
//!   Blender. Geometry that cannot be read is still an error.

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::gltf::load_gltf;
use super::input::Reach;
use super::obj::load_obj;
use super::ply::load_ply;
use super::stl::load_stl;
use crate::error::{Error, Result};
use crate::scene::image_texture::{Filter, Wrap};
use crate::scene::mesh::Mesh;

/// The extensions [`load_mesh`] reads (lower case, without the dot).
pub const MESH_EXTENSIONS: [&str; 5] = ["obj", "ply", "stl", "gltf", "glb"];

/// Where a file's texture image is.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureSource {
    /// An image file, resolved relative to the mesh file (not checked for existence: the caller
    /// opens it and reports a missing file).
    File(PathBuf),
    /// Image bytes held in the mesh file (a glTF buffer view or `data:` URI); `name` says which
    /// image of the file, for messages.
    Embedded {
        /// Which image of the file, for messages.
        name: String,
        /// The encoded image (PNG or JPEG).
        bytes: Vec<u8>,
    },
}

/// A texture named by the mesh file's own material.
#[derive(Clone, Debug, PartialEq)]
pub struct FileTexture {
    /// Where the image comes from.
    pub source: TextureSource,
    /// The file's sampler, when it names one (glTF).
    pub filter: Option<Filter>,
    /// What UVs outside [0, 1] do, when the file says.
    pub wrap: Option<Wrap>,
}

/// A material as the mesh file describes it. Colours are linear RGB.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileMaterial {
    /// The material's name in the file, if any.
    pub name: Option<String>,
    /// Base colour (MTL `Kd`, glTF `baseColorFactor`); multiplies the texture and the vertex
    /// colours when those are present.
    pub base_color: Option<DVec3>,
    /// Base colour texture (MTL `map_Kd`, glTF `baseColorTexture`).
    pub texture: Option<FileTexture>,
    /// The colour the material shows when its texture cannot be read, where that differs from
    /// `base_color`: an MTL `Kd` given beside `map_Kd` (which `base_color` leaves out, since
    /// the texture alone gives the colour). `None`: `base_color` is used.
    pub untextured_color: Option<DVec3>,
    /// The part's vertices carry colours from the file ([`Mesh::colors`]).
    pub vertex_colors: bool,
}

/// A run of triangles of the loaded mesh that share one file material.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPart {
    /// Indices into [`Mesh::triangles`] of [`MeshLoad::mesh`].
    pub triangles: Range<usize>,
    /// The file's material of these triangles.
    pub material: FileMaterial,
}

/// A mesh read from a file.
#[derive(Clone, Debug)]
pub struct MeshLoad {
    /// The mesh in file coordinates (apply a [`crate::scene::Transform`] to place it), degenerate triangles
    /// already removed; all parts of the file merged.
    pub mesh: Mesh,
    /// How many zero-area triangles were removed.
    pub dropped_degenerate: usize,
    /// The OBJ material's diffuse texture (`map_Kd` of the first material that has one),
    /// resolved relative to the OBJ file (not checked for existence).
    pub texture: Option<PathBuf>,
    /// The file's materials: consecutive, non-empty runs of triangles covering
    /// [`Mesh::triangles`] in order (at least one).
    pub parts: Vec<MeshPart>,
    /// Things the reader skipped or could not honour (unknown PLY header lines, glTF extensions
    /// and primitive modes), each naming the file; the caller shows them.
    pub warnings: Vec<String>,
}

/// What a format reader returns before the shared checks.
pub(super) struct Loaded {
    /// The mesh as read.
    pub mesh: Mesh,
    /// As [`MeshLoad::parts`], before degenerate triangles are removed (may be empty: one part
    /// with no file material).
    pub parts: Vec<MeshPart>,
    pub texture: Option<PathBuf>,
    pub warnings: Vec<String>,
}

impl Loaded {
    /// A mesh with no file materials.
    pub fn plain(mesh: Mesh) -> Self {
        Loaded { mesh, parts: Vec::new(), texture: None, warnings: Vec::new() }
    }
}

/// Loads a triangle mesh, choosing the format from the extension (`.obj`, `.ply`, `.stl`,
/// `.gltf`, `.glb`, any case).
///
/// Errors (all name the file): missing file or directory ([`Error::Io`]); unknown extension
/// ([`Error::UnknownFormat`]); malformed content, index out of range, non-finite vertex, or no
/// triangles left ([`Error::Parse`], with the line or element).
pub fn load_mesh(path: &Path) -> Result<MeshLoad> {
    let folder = path.parent().unwrap_or(Path::new(""));
    load_mesh_within(path, &Reach::within(folder))
}

/// [`load_mesh`], with the files the mesh names (glTF buffers and images, OBJ `mtllib` and
/// `map_Kd`) kept to `reach` (a scene's folder, see [`Reach`]): a reference outside it is an
/// error saying so.
pub(crate) fn load_mesh_within(path: &Path, reach: &Reach) -> Result<MeshLoad> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::io(
            path,
            std::io::Error::other("is a directory, expected a mesh file (.obj, .ply, .stl, .gltf or .glb)"),
        ));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = crate::io::input::read_regular(path)?;
    let loaded = match ext.as_deref() {
        Some("obj") => load_obj(path, &bytes, reach)?,
        Some("ply") => load_ply(path, &bytes)?,
        Some("stl") => Loaded::plain(load_stl(path, &bytes)?),
        Some("gltf") | Some("glb") => load_gltf(path, &bytes, reach)?,
        _ => {
            return Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                kind: "mesh",
                expected: "extension .obj, .ply, .stl, .gltf or .glb",
            })
        }
    };
    let Loaded { mut mesh, parts, texture, warnings } = loaded;
    let mut parts = if parts.is_empty() {
        vec![MeshPart { triangles: 0..mesh.triangles.len(), material: FileMaterial::default() }]
    } else {
        parts
    };
    let dropped_degenerate = remove_degenerate_in_parts(&mut mesh, &mut parts);
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
    Ok(MeshLoad { mesh, dropped_degenerate, texture, parts, warnings })
}

/// Removes zero-area triangles (see [`Mesh::is_degenerate`]) and shrinks the parts' triangle
/// ranges to match, dropping parts left empty. Returns how many triangles were removed.
pub(super) fn remove_degenerate_in_parts(mesh: &mut Mesh, parts: &mut Vec<MeshPart>) -> usize {
    let keep: Vec<bool> = (0..mesh.triangles.len()).map(|t| !mesh.is_degenerate(t)).collect();
    let mut kept_before = Vec::with_capacity(keep.len() + 1);
    let mut n = 0;
    kept_before.push(0);
    for &k in &keep {
        n += usize::from(k);
        kept_before.push(n);
    }
    for part in parts.iter_mut() {
        let (a, b) = (part.triangles.start.min(keep.len()), part.triangles.end.min(keep.len()));
        part.triangles = kept_before[a]..kept_before[b];
    }
    parts.retain(|p| !p.triangles.is_empty());
    let before = mesh.triangles.len();
    let mut k = keep.iter();
    mesh.triangles.retain(|_| *k.next().unwrap_or(&true));
    before - mesh.triangles.len()
}

pub(super) use crate::raster::srgb_to_linear;

/// The file a mesh file names (an MTL library, a texture), resolved relative to the folder
/// `base` of the mesh file: surrounding blanks trimmed, and `\` read as a path separator, as
/// Assimp and Blender read it (Windows exporters write `map_Kd .\textures\skin.jpg`).
pub(super) fn file_name_path(base: &Path, name: &str) -> PathBuf {
    base.join(name.trim().replace('\\', "/"))
}
