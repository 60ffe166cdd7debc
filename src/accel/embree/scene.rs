//! [`SceneBuilder`] and the committed [`Scene`]: the RAII handles of an Embree scene
//! (`RTCScene`) being assembled and built, and the ray queries (single rays and 16-wide packets)
//! on the committed, thread-shareable result.

use super::compat;
use super::device::Device;
use super::error::embree_error;
use super::geometry::TriangleGeometry;
use super::live::{live_dec, live_inc};
use super::ray::{RawHit, RawRay, Valid16};
use super::sys;
use crate::error::Result;

/// BVH build quality (Embree's `RTC_BUILD_QUALITY_*`): `Low` builds fastest, `High` (spatial
/// splits) traces fastest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BuildQuality {
    /// Fastest build (Embree's `RTC_BUILD_QUALITY_LOW`).
    Low,
    /// Embree's default (`RTC_BUILD_QUALITY_MEDIUM`).
    #[default]
    Medium,
    /// Spatial splits: slowest build, fastest tracing (`RTC_BUILD_QUALITY_HIGH`).
    High,
}

impl BuildQuality {
    pub(super) fn raw(self) -> sys::RTCBuildQuality {
        match self {
            BuildQuality::Low => sys::RTC_BUILD_QUALITY_LOW,
            BuildQuality::Medium => sys::RTC_BUILD_QUALITY_MEDIUM,
            BuildQuality::High => sys::RTC_BUILD_QUALITY_HIGH,
        }
    }
}

/// Owns one `RTCScene` reference; shared by [`SceneBuilder`] and [`Scene`].
struct SceneHandle {
    raw: sys::RTCScene,
    device: Device,
}

impl Drop for SceneHandle {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live scene owned by this handle; released exactly once. Embree
        // releases the geometries attached to it when its reference count reaches zero.
        unsafe { sys::rtcReleaseScene(self.raw) };
        live_dec();
    }
}

/// A scene being assembled: attach geometries, then [`commit`](SceneBuilder::commit).
pub struct SceneBuilder {
    handle: SceneHandle,
    geometries: u32,
    triangles: usize,
}

// SAFETY: the builder exclusively owns its scene handle; Embree allows a scene to be modified
// from any thread as long as only one thread does so at a time, which `&mut self` ensures (the
// builder is not `Sync`).
unsafe impl Send for SceneBuilder {}

impl SceneBuilder {
    /// An empty scene on `device` with the given BVH build quality. Scenes use Embree's robust
    /// mode (`RTC_SCENE_FLAG_ROBUST`): watertight triangle tests, so a ray through an edge or
    /// vertex shared by neighbouring triangles cannot slip through.
    pub fn new(device: &Device, quality: BuildQuality) -> Result<SceneBuilder> {
        // SAFETY: the device handle is live; the result is checked for NULL below.
        let raw = unsafe { sys::rtcNewScene(device.raw()) };
        if raw.is_null() {
            device.check("rtcNewScene")?;
            return Err(embree_error(sys::RTC_ERROR_UNKNOWN, None, "rtcNewScene returned NULL"));
        }
        live_inc();
        let builder = SceneBuilder { handle: SceneHandle { raw, device: device.clone() }, geometries: 0, triangles: 0 };
        device.check("rtcNewScene")?;
        // SAFETY: `raw` is a live, uncommitted scene owned by `builder`; the flag and quality are
        // valid enum values.
        unsafe {
            sys::rtcSetSceneFlags(raw, sys::RTC_SCENE_FLAG_ROBUST);
            sys::rtcSetSceneBuildQuality(raw, quality.raw());
        }
        device.check("rtcSetSceneBuildQuality")?;
        Ok(builder)
    }

    /// Attaches `geometry` (which must come from the same device) and returns its Embree
    /// geometry ID, the `geom_id` that hits report. The scene keeps the geometry alive.
    pub fn attach(&mut self, geometry: TriangleGeometry) -> Result<u32> {
        // A geometry from another device is refused by Embree itself (`rtcAttachGeometry` checks
        // this in every release and raises RTC_ERROR_INVALID_ARGUMENT "inputs are from
        // different devices"), which reaches us as `Error::Embree` through `check` below.
        // SAFETY: both handles are live; the scene is not committed yet and is exclusively
        // borrowed. On success Embree takes its own reference to the geometry, so dropping
        // `geometry` afterwards is fine; on failure nothing was retained.
        let id = unsafe { sys::rtcAttachGeometry(self.handle.raw, geometry.raw) };
        self.handle.device.check("rtcAttachGeometry")?;
        self.geometries += 1;
        self.triangles += geometry.triangles;
        Ok(id)
    }

    /// Builds the BVH (`rtcCommitScene`) and returns the read-only, thread-shareable scene.
    pub fn commit(self) -> Result<Scene> {
        // SAFETY: the scene is live and owned by `self`; all attached geometries are committed.
        unsafe { sys::rtcCommitScene(self.handle.raw) };
        self.handle.device.check("rtcCommitScene")?;
        // SAFETY: the device is live (the handle holds it).
        let native16 = unsafe { compat::native_ray16(self.handle.device.raw()) };
        Ok(Scene { handle: self.handle, geometries: self.geometries, triangles: self.triangles, native16 })
    }
}

/// Traces `$rays` (at most the packet's width) as one packet made by `$blank` and traced by
/// `$trace` (`rtcIntersect16` or `rtcIntersect8`, whose records have the same fields), writing
/// `$hits`.
macro_rules! trace_packet {
    ($scene:expr, $rays:expr, $hits:expr, $coherent:expr, $blank:path, $trace:path) => {{
        let mut valid = Valid16([0; 16]);
        let mut padded = $blank();
        let packet = &mut padded.value;
        for (lane, ray) in $rays.iter().enumerate() {
            packet.hit.geomID[lane] = sys::RTC_INVALID_GEOMETRY_ID;
            for level in packet.hit.instID.iter_mut() {
                level[lane] = sys::RTC_INVALID_GEOMETRY_ID;
            }
            if !ray.is_valid() {
                continue;
            }
            valid.0[lane] = -1;
            let r = &mut packet.ray;
            r.org_x[lane] = ray.org[0];
            r.org_y[lane] = ray.org[1];
            r.org_z[lane] = ray.org[2];
            r.dir_x[lane] = ray.dir[0];
            r.dir_y[lane] = ray.dir[1];
            r.dir_z[lane] = ray.dir[2];
            r.tnear[lane] = ray.tnear;
            r.tfar[lane] = ray.tfar;
            // Debian builds Embree with ray masks on: a zero mask would miss everything.
            r.mask[lane] = u32::MAX;
        }
        if valid.0.iter().any(|&v| v != 0) {
            // SAFETY: the scene is live and committed; `valid` and `padded` are 64-byte aligned
            // locals (checked at compile time), initialised for every lane (inactive lanes are
            // ignored by Embree), and only this call accesses them.
            unsafe { $trace(valid.0.as_ptr(), $scene.handle.raw, &mut padded, $coherent) };
        }
        let packet = &padded.value;
        for (lane, hit) in $hits.iter_mut().enumerate() {
            let h = &packet.hit;
            *hit = (valid.0[lane] != 0 && h.geomID[lane] != sys::RTC_INVALID_GEOMETRY_ID).then(|| RawHit {
                t: packet.ray.tfar[lane],
                u: h.u[lane],
                v: h.v[lane],
                ng: [h.Ng_x[lane], h.Ng_y[lane], h.Ng_z[lane]],
                geom_id: h.geomID[lane],
                prim_id: h.primID[lane],
            });
        }
    }};
}

/// A committed Embree scene: read-only and safe to query from many threads at once.
pub struct Scene {
    handle: SceneHandle,
    geometries: u32,
    triangles: usize,
    /// Whether the device has native 16-ray packet kernels (else packets go 8 rays at a time).
    native16: bool,
}

// SAFETY: after `rtcCommitScene` the scene is never modified (no method takes `&mut self` or
// calls a mutating Embree function), and Embree documents `rtcIntersect*`/`rtcOccluded*` on a
// committed scene as thread-safe: every query writes only to the caller's own ray/hit structs.
unsafe impl Send for Scene {}
// SAFETY: see `Send` above: shared access only issues thread-safe read-only queries.
unsafe impl Sync for Scene {}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("geometries", &self.geometries)
            .field("triangles", &self.triangles)
            .field("native16", &self.native16)
            .finish()
    }
}

impl Scene {
    /// Number of attached geometries.
    pub fn geometry_count(&self) -> u32 {
        self.geometries
    }

    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Nearest hit along `ray` (`rtcIntersect1`); `None` on a miss or an invalid ray.
    pub fn intersect1(&self, ray: &RawRay) -> Option<RawHit> {
        if !ray.is_valid() {
            return None;
        }
        let mut padded = compat::Padded::new(sys::RTCRayHit { ray: ray.to_sys(), hit: sys::RTCHit::default() });
        let rayhit = &mut padded.value;
        rayhit.hit.geomID = sys::RTC_INVALID_GEOMETRY_ID;
        rayhit.hit.instID.fill(sys::RTC_INVALID_GEOMETRY_ID);
        // SAFETY: the scene is live and committed; `padded` is a properly aligned (checked at
        // compile time), fully initialised local that only this call accesses.
        unsafe { compat::intersect1(self.handle.raw, &mut padded) };
        let rayhit = &padded.value;
        (rayhit.hit.geomID != sys::RTC_INVALID_GEOMETRY_ID).then_some(RawHit {
            t: rayhit.ray.tfar,
            u: rayhit.hit.u,
            v: rayhit.hit.v,
            ng: [rayhit.hit.Ng_x, rayhit.hit.Ng_y, rayhit.hit.Ng_z],
            geom_id: rayhit.hit.geomID,
            prim_id: rayhit.hit.primID,
        })
    }

    /// Whether anything lies on `ray` within `[tnear, tfar]` (`rtcOccluded1`); `false` for an
    /// invalid ray.
    pub fn occluded1(&self, ray: &RawRay) -> bool {
        if !ray.is_valid() {
            return false;
        }
        let mut raw = ray.to_sys();
        // SAFETY: the scene is live and committed; `raw` is an aligned, initialised local.
        unsafe { compat::occluded1(self.handle.raw, &mut raw) };
        // Embree marks an occluded ray by setting tfar to -inf.
        raw.tfar < 0.0
    }

    /// Rays per packet that Embree traces natively on this device: 16 with AVX-512, else 8.
    pub fn packet_width(&self) -> usize {
        if self.native16 {
            16
        } else {
            8
        }
    }

    /// Nearest hits for up to 16 rays in one packet (`rtcIntersect16`; as two 8-ray packets,
    /// `rtcIntersect8`, where the device has no native 16-ray kernels, e.g. on AVX2 CPUs, where
    /// Embree 4.4 would answer a 16-ray packet one ray at a time). `coherent` hints that the rays
    /// start close together and point in similar directions. Invalid rays get `None`.
    ///
    /// # Panics
    /// If `rays.len() > 16` or `hits.len() != rays.len()` (caller bugs, not data errors).
    pub fn intersect16(&self, rays: &[RawRay], hits: &mut [Option<RawHit>], coherent: bool) {
        assert!(rays.len() <= 16, "intersect16: {} rays given, at most 16 fit a packet", rays.len());
        assert_eq!(rays.len(), hits.len(), "intersect16: rays and hits differ in length");
        if self.native16 {
            trace_packet!(self, rays, hits, coherent, compat::blank_packet, compat::intersect16);
        } else {
            for (rays, hits) in rays.chunks(8).zip(hits.chunks_mut(8)) {
                trace_packet!(self, rays, hits, coherent, compat::blank_packet8, compat::intersect8);
            }
        }
    }

    /// Nearest hits for any number of rays, traced as 16-wide packets of consecutive rays
    /// (fast when neighbouring rays are coherent, e.g. adjacent pixels).
    ///
    /// # Panics
    /// If `hits.len() != rays.len()`.
    pub fn intersect_packets(&self, rays: &[RawRay], hits: &mut [Option<RawHit>]) {
        assert_eq!(rays.len(), hits.len(), "intersect_packets: rays and hits differ in length");
        for (r, h) in rays.chunks(16).zip(hits.chunks_mut(16)) {
            self.intersect16(r, h, true);
        }
    }
}
