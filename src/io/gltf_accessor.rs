//! glTF 2.0 accessors: typed, bounds-checked reads of a buffer view's elements as `f64`
//! components (glTF 2.0 specification, sec. 3.6.2 "Accessors": component types, normalised
//! integers, byte strides), each failure naming the file, the element and the accessor.

use std::path::Path;

use gltf::accessor::{DataType, Dimensions};

use crate::error::{Error, Result};

/// Most elements an accessor without a buffer view (all zeros) may declare.
const MAX_ZERO_ELEMENTS: usize = 1 << 24;

/// An accessor's elements as `f64` components, `comps` per element.
pub(super) struct Elements {
    comps: usize,
    data: Vec<f64>,
}

impl Elements {
    pub(super) fn len(&self) -> usize {
        self.data.len() / self.comps
    }

    pub(super) fn iter(&self) -> std::slice::ChunksExact<'_, f64> {
        self.data.chunks_exact(self.comps)
    }
}

/// Typed, bounds-checked reads of accessors.
pub(super) struct Reader<'a> {
    pub(super) path: &'a Path,
    pub(super) buffers: &'a [Vec<u8>],
    /// Where the files the glTF names may be.
    pub(super) reach: &'a super::input::Reach,
}

impl Reader<'_> {
    /// The components of every element as `f64` (normalised integers mapped to `[0, 1]` or
    /// `[-1, 1]`), after checking the accessor's type against `dims` and `types`.
    pub(super) fn read(
        &self,
        at: &str,
        accessor: &gltf::Accessor,
        dims: &[Dimensions],
        types: &[(DataType, bool)],
        want: &str,
    ) -> Result<Elements> {
        let err = |msg: String| Error::parse(self.path, format!("{at}: accessor {}: {msg}", accessor.index()));
        let (dt, dim, norm) = (accessor.data_type(), accessor.dimensions(), accessor.normalized());
        if !dims.contains(&dim) || !types.contains(&(dt, norm)) {
            let n = if norm { " normalized" } else { "" };
            return Err(err(format!("is {} of{n} {}, expected {want}", dims_name(dim), type_name(dt))));
        }
        if accessor.sparse().is_some() {
            return Err(err("sparse accessors are not supported".into()));
        }
        let count = accessor.count();
        let comps = dim.multiplicity();
        let size = dt.size();
        let elem = comps * size;
        let Some(view) = accessor.view() else {
            // No buffer view: zeros (the specification's initial value of sparse accessors).
            if count > MAX_ZERO_ELEMENTS {
                return Err(err(format!("{count} elements without a buffer view (over {MAX_ZERO_ELEMENTS})")));
            }
            return Ok(Elements { comps, data: vec![0.0; comps * count] });
        };
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(err(format!("byteStride {stride} is smaller than one element ({elem} bytes)")));
        }
        let buffer = &self.buffers[view.buffer().index()];
        let start = view.offset() as u128 + accessor.offset() as u128;
        let view_end = view.offset() as u128 + view.length() as u128;
        let end = if count == 0 { start } else { start + stride as u128 * (count as u128 - 1) + elem as u128 };
        if end > view_end || view_end > buffer.len() as u128 {
            return Err(err(format!(
                "{count} elements of {elem} bytes (stride {stride}) at byte {start} run past the end of bufferViews[{}] \
                 (bytes {}..{view_end}) or of its buffer ({} bytes)",
                view.index(),
                view.offset(),
                buffer.len()
            )));
        }
        let start = start as usize;
        let mut data = Vec::with_capacity(count * comps);
        for k in 0..count {
            let e = &buffer[start + k * stride..start + k * stride + elem];
            data.extend((0..comps).map(|c| component(&e[c * size..(c + 1) * size], dt, norm)));
        }
        Ok(Elements { comps, data })
    }
}

/// The glTF name of an accessor type.
fn dims_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// The glTF name of a component type.
fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

/// One component of type `dt` (normalised to `[0, 1]` or `[-1, 1]` when `norm`).
fn component(b: &[u8], dt: DataType, norm: bool) -> f64 {
    let (v, max) = match dt {
        DataType::I8 => (f64::from(b[0] as i8), 127.0),
        DataType::U8 => (f64::from(b[0]), 255.0),
        DataType::I16 => (f64::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
        DataType::U16 => (f64::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
        DataType::U32 => (f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])), 4294967295.0),
        DataType::F32 => return f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    };
    if norm {
        (v / max).max(-1.0)
    } else {
        v
    }
}

/// Float components.
pub(super) const FLOAT: (DataType, bool) = (DataType::F32, false);
/// Normalised unsigned bytes.
pub(super) const UNORM8: (DataType, bool) = (DataType::U8, true);
/// Normalised unsigned shorts.
pub(super) const UNORM16: (DataType, bool) = (DataType::U16, true);
