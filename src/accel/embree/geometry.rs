//! [`TriangleGeometry`]: the RAII handle of one committed Embree triangle mesh
//! (`RTC_GEOMETRY_TYPE_TRIANGLE`), checked before Embree sees it so that Embree never reads out
//! of bounds.

use std::ffi::c_void;

use super::device::Device;
use super::error::embree_error;
use super::live::{live_dec, live_inc};
use super::scene::BuildQuality;
use super::sys;
use crate::error::{Error, Result};

/// A committed triangle mesh (`RTC_GEOMETRY_TYPE_TRIANGLE`) with its own copy of the vertex and
/// index data, ready to attach to a scene. Released on drop (a scene it was attached to keeps
/// Embree's own reference).
pub struct TriangleGeometry {
    pub(super) raw: sys::RTCGeometry,
    device: Device,
    pub(super) triangles: usize,
}

// SAFETY: the geometry is fully built and committed in `new` and never mutated afterwards; Embree
// objects may be released or attached from any thread as long as no two threads modify the same
// object at once, which `&mut`/ownership rules ensure (the type is not `Sync`).
unsafe impl Send for TriangleGeometry {}

impl Drop for TriangleGeometry {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live geometry owned by this wrapper; we release our reference once.
        unsafe { sys::rtcReleaseGeometry(self.raw) };
        live_dec();
    }
}

impl TriangleGeometry {
    /// Copies `positions` and `triangles` into a new Embree triangle geometry and commits it.
    ///
    /// Errors ([`Error::Invalid`] with `source_name`, naming the element) when a position is not
    /// finite, a triangle index is not below `positions.len()`, or a count exceeds Embree's
    /// 32-bit limits; [`Error::Embree`] when Embree refuses.
    pub fn new(
        device: &Device,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        quality: BuildQuality,
        source_name: &str,
    ) -> Result<TriangleGeometry> {
        if positions.len() > u32::MAX as usize || triangles.len() >= u32::MAX as usize {
            return Err(Error::invalid(
                source_name,
                "triangles",
                format!(
                    "{} vertices / {} triangles exceed Embree's 32-bit element count",
                    positions.len(),
                    triangles.len()
                ),
            ));
        }
        if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::invalid(
                source_name,
                format!("positions[{i}]"),
                format!("vertex ({}, {}, {}) is not finite in single precision", p[0], p[1], p[2]),
            ));
        }
        let n = positions.len();
        if let Some((i, t)) = triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&k| k as usize >= n)) {
            return Err(Error::invalid(
                source_name,
                format!("triangles[{i}]"),
                format!("vertex index in {t:?} is out of range (the mesh has {n} vertices)"),
            ));
        }

        // SAFETY: the device handle is live; the result is checked for NULL below.
        let raw = unsafe { sys::rtcNewGeometry(device.raw(), sys::RTC_GEOMETRY_TYPE_TRIANGLE) };
        if raw.is_null() {
            device.check("rtcNewGeometry")?;
            return Err(embree_error(sys::RTC_ERROR_UNKNOWN, None, "rtcNewGeometry returned NULL"));
        }
        live_inc();
        // From here on, `geometry`'s Drop releases `raw` on every early return.
        let geometry = TriangleGeometry { raw, device: device.clone(), triangles: triangles.len() };
        device.check("rtcNewGeometry")?;

        let vertex_ptr = geometry.new_buffer(sys::RTC_BUFFER_TYPE_VERTEX, sys::RTC_FORMAT_FLOAT3, n)?;
        let index_ptr = geometry.new_buffer(sys::RTC_BUFFER_TYPE_INDEX, sys::RTC_FORMAT_UINT3, triangles.len())?;
        // SAFETY: Embree returned buffers of exactly `n` (resp. `triangles.len()`) items of 12
        // bytes (`FLOAT3` / `UINT3`, byte stride 12), 4-byte aligned (Embree aligns buffers to at
        // least 16 bytes), owned by the geometry and not accessed by Embree until commit. The
        // source slices have the same element size and count and cannot overlap Embree's fresh
        // allocation. Zero-length copies are skipped, so a NULL pointer is never written.
        unsafe {
            if n > 0 {
                std::ptr::copy_nonoverlapping(positions.as_ptr(), vertex_ptr.cast::<[f32; 3]>(), n);
            }
            if !triangles.is_empty() {
                std::ptr::copy_nonoverlapping(triangles.as_ptr(), index_ptr.cast::<[u32; 3]>(), triangles.len());
            }
        }
        // SAFETY: `raw` is a live geometry; quality is one of Embree's valid enum values.
        unsafe { sys::rtcSetGeometryBuildQuality(raw, quality.raw()) };
        geometry.device.check("rtcSetGeometryBuildQuality")?;
        // SAFETY: `raw` is a live geometry whose buffers are fully written and whose indices were
        // checked to be in range above.
        unsafe { sys::rtcCommitGeometry(raw) };
        geometry.device.check("rtcCommitGeometry")?;
        Ok(geometry)
    }

    /// Allocates an Embree-owned buffer of `count` 12-byte items; returns its address.
    fn new_buffer(&self, kind: sys::RTCBufferType, format: sys::RTCFormat, count: usize) -> Result<*mut c_void> {
        // SAFETY: `raw` is a live geometry; stride 12 matches FLOAT3/UINT3; Embree allocates the
        // buffer (with its own padding for vector loads) and keeps it alive with the geometry.
        let ptr = unsafe { sys::rtcSetNewGeometryBuffer(self.raw, kind, 0, format, 12, count) };
        self.device.check("rtcSetNewGeometryBuffer")?;
        if ptr.is_null() && count > 0 {
            return Err(embree_error(sys::RTC_ERROR_OUT_OF_MEMORY, None, "rtcSetNewGeometryBuffer returned NULL"));
        }
        Ok(ptr)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }
}
