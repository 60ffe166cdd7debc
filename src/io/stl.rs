//! STL meshes (stereolithography), ASCII and binary, read through the `stl_io` crate. STL is what
//! 3-D scanners and CAD tools most often export: triangles with a facet normal each and nothing
//! else (no colours, no texture coordinates), so the loaded [`Mesh`] has positions and
//! triangles only; shading uses the geometric normal. Vertices shared by triangles (equal bit
//! patterns) are merged in order of first use.
//!
//! The format is told apart here rather than by the first word alone: many binary exporters
//! begin their free-text 80-byte header with `solid`, so a file whose size is exactly
//! `84 + 50 n` for the triangle count `n` of its header is binary, whatever its first word.
//! Otherwise a plain-text file starting with `solid` is ASCII, and anything else is binary whose
//! size does not match its count: an error that gives both numbers. ASCII errors name the facet.
//! Shared conventions (degenerate triangles): [`super::mesh`].

use std::io::Cursor;
use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

const HEADER: usize = 80;
const RECORD: usize = 50;

pub(super) fn load_stl(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let binary_count =
        (bytes.len() >= HEADER + 4).then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize);
    let sized_binary = binary_count.is_some_and(|n| (bytes.len() - HEADER - 4) as u128 == n as u128 * RECORD as u128);
    let text = bytes.iter().all(|&b| matches!(b, b'\t' | b'\n' | b'\r' | 0x20..=0x7e));
    let ascii = !sized_binary && text && bytes.trim_ascii_start().starts_with(b"solid");
    if ascii {
        return read_ascii(path, bytes);
    }
    let Some(n) = binary_count else {
        return Err(Error::parse(
            path,
            format!(
                "not an STL file: {} bytes, neither ASCII (`solid ...`) nor binary (80-byte header and a triangle count)",
                bytes.len()
            ),
        ));
    };
    if !sized_binary {
        let body = bytes.len() - HEADER - 4;
        return Err(Error::parse(
            path,
            format!(
                "binary STL header announces {n} triangles ({} bytes) but the file holds {body} bytes after the header \
                 ({} whole triangles{})",
                n as u128 * RECORD as u128,
                body / RECORD,
                if !body.is_multiple_of(RECORD) { ", the last one truncated" } else { "" }
            ),
        ));
    }
    // The size matches the count: read as binary even when the header starts with "solid"
    // (stl_io would take that for ASCII), by blanking the header's free text.
    let mut patched = bytes.to_vec();
    patched[..HEADER].fill(b' ');
    collect(path, stl_io::create_stl_reader(&mut Cursor::new(patched)), "binary")
}

fn read_ascii(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    // stl_io wants "solid " with a space; an unnamed solid ("solid\n") is valid STL too.
    let start = bytes.len() - bytes.trim_ascii_start().len();
    let mut text = bytes[start..].to_vec();
    let first_line_end = text.iter().position(|&b| b == b'\n').unwrap_or(text.len());
    if text[..first_line_end].trim_ascii_end() == b"solid" {
        text.splice(5..5, *b" unnamed");
    }
    collect(path, stl_io::create_stl_reader(&mut Cursor::new(text)), "ASCII")
}

type Triangles<'a> = std::io::Result<Box<dyn stl_io::TriangleIterator<Item = std::io::Result<stl_io::Triangle>> + 'a>>;

/// Reads every triangle, merging vertices by bit pattern; errors name the facet.
fn collect(path: &Path, reader: Triangles<'_>, kind: &str) -> Result<Mesh> {
    let reader = reader.map_err(|e| Error::parse(path, format!("{kind} STL: {e}")))?;
    let mut mesh = Mesh::default();
    let mut index = std::collections::HashMap::new();
    for (facet, triangle) in reader.enumerate() {
        let triangle = triangle.map_err(|e| {
            let what = if e.kind() == std::io::ErrorKind::UnexpectedEof { "file ends early: " } else { "" };
            Error::parse(path, format!("{kind} STL, facet {facet}: {what}{e}"))
        })?;
        let mut corners = [0u32; 3];
        for (k, v) in triangle.vertices.iter().enumerate() {
            let p = DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
            if !p.is_finite() {
                return Err(Error::parse(
                    path,
                    format!(
                        "{kind} STL, facet {facet}: vertex {k} has a non-finite coordinate ({}, {}, {})",
                        p.x, p.y, p.z
                    ),
                ));
            }
            let key = [v[0].to_bits(), v[1].to_bits(), v[2].to_bits()];
            let next = mesh.positions.len();
            let i = *index.entry(key).or_insert(next);
            if i == next {
                mesh.positions.push(p);
            }
            corners[k] =
                u32::try_from(i).map_err(|_| Error::parse(path, "more than 2^32 vertices are not supported"))?;
        }
        mesh.triangles.push(corners);
    }
    Ok(mesh)
}
