//! Intel Embree as a scene intersection backend (paper Sec. 3.1: each ray is traversed until it
//! hits an object; Embree does this for triangle meshes).
//!
//! This module owns the crate's only `unsafe` code. Layers:
//! - `sys`: raw bindings that `build.rs` generates with bindgen from `wrapper.h`;
//! - `compat`: the few differences between Embree 3 and Embree 4;
//! - this file: a small safe API ([`Device`], [`TriangleGeometry`], [`SceneBuilder`], committed
//!   [`Scene`]) with RAII release, Embree errors turned into [`Error::Embree`], and a process-wide
//!   count of live Embree objects ([`live_objects`]);
//! - `intersector`: [`EmbreeIntersector`], the [`crate::accel::Intersector`] over inimtrace
//!   meshes, where `f64` optics meets Embree's `f32`.
//!
//! The safe API keeps Embree from ever reading out of bounds: vertex positions must be finite,
//! triangle indices must be in range, and rays with non-finite fields are answered "no hit"
//! without calling Embree.

mod compat;
mod intersector;
mod sys;

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

pub use compat::EMBREE_MAJOR;
pub use intersector::EmbreeIntersector;

// Embree requires 16-byte aligned single rays and 64-byte aligned 16-wide packets; bindgen
// carries the C `RTC_ALIGN` over as `repr(align)`, and these checks keep it that way.
const _: () = assert!(std::mem::align_of::<sys::RTCRayHit>() >= 16);
const _: () = assert!(std::mem::align_of::<sys::RTCRay>() >= 16);
const _: () = assert!(std::mem::align_of::<sys::RTCRayHit16>() >= 64);
const _: () = assert!(std::mem::align_of::<Valid16>() >= 64);

/// Number of Embree devices, scenes and geometries currently alive in this process (created by
/// this module and not yet dropped).
static LIVE: AtomicUsize = AtomicUsize::new(0);

/// How many Embree objects (devices, scenes, geometries) are alive right now, process-wide.
/// Returns to its earlier value once everything created since has been dropped.
pub fn live_objects() -> usize {
    LIVE.load(Ordering::SeqCst)
}

fn live_inc() {
    LIVE.fetch_add(1, Ordering::SeqCst);
}

fn live_dec() {
    LIVE.fetch_sub(1, Ordering::SeqCst);
}

/// BVH build quality (Embree's `RTC_BUILD_QUALITY_*`): `Low` builds fastest, `High` (spatial
/// splits) traces fastest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BuildQuality {
    Low,
    #[default]
    Medium,
    High,
}

impl BuildQuality {
    fn raw(self) -> sys::RTCBuildQuality {
        match self {
            BuildQuality::Low => sys::RTC_BUILD_QUALITY_LOW,
            BuildQuality::Medium => sys::RTC_BUILD_QUALITY_MEDIUM,
            BuildQuality::High => sys::RTC_BUILD_QUALITY_HIGH,
        }
    }
}

/// Embree's name for an `RTCError` code (`"RTC_ERROR_INVALID_ARGUMENT"`, ...).
pub fn error_code_name(code: u32) -> &'static str {
    match code {
        sys::RTC_ERROR_NONE => "RTC_ERROR_NONE",
        sys::RTC_ERROR_UNKNOWN => "RTC_ERROR_UNKNOWN",
        sys::RTC_ERROR_INVALID_ARGUMENT => "RTC_ERROR_INVALID_ARGUMENT",
        sys::RTC_ERROR_INVALID_OPERATION => "RTC_ERROR_INVALID_OPERATION",
        sys::RTC_ERROR_OUT_OF_MEMORY => "RTC_ERROR_OUT_OF_MEMORY",
        sys::RTC_ERROR_UNSUPPORTED_CPU => "RTC_ERROR_UNSUPPORTED_CPU",
        sys::RTC_ERROR_CANCELLED => "RTC_ERROR_CANCELLED",
        // Embree 4.3+ adds this one (SYCL device creation); same value in every release.
        7 => "RTC_ERROR_LEVEL_ZERO_RAYTRACING_SUPPORT_MISSING",
        _ => "RTC_ERROR_UNRECOGNISED",
    }
}

/// Turns an Embree error code and the message its error callback gave (if any) into
/// [`Error::Embree`]; `during` names the API call that failed.
pub fn embree_error(code: u32, message: Option<&str>, during: &str) -> Error {
    let name = error_code_name(code);
    let code = if name == "RTC_ERROR_UNRECOGNISED" { format!("{name}({code})") } else { name.to_string() };
    let message = match message {
        Some(m) if !m.is_empty() => format!("{during}: {m}"),
        _ => format!("{during}: (Embree gave no message)"),
    };
    Error::Embree { code, message }
}

/// Messages from Embree's error callback, most recent last, waiting to be attached to the
/// error code that `rtcGetDeviceError` reports for the failing call.
type ErrorSink = Mutex<Vec<(u32, String)>>;

/// Embree's error callback. `user_ptr` is the device's [`ErrorSink`]. It must not unwind into
/// C, so it only records and never panics (a poisoned lock is still usable).
unsafe extern "C" fn error_callback(user_ptr: *mut c_void, code: sys::RTCError, message: *const c_char) {
    if user_ptr.is_null() {
        return;
    }
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated C string that is valid for the duration of the
        // callback; we copy it out before returning.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    // SAFETY: `user_ptr` is the address of the `ErrorSink` boxed inside `DeviceInner`, registered
    // by `Device::with_config` and unregistered in `DeviceInner::drop` before that box is
    // freed, so it points to a live `Mutex` here. Only shared access is taken.
    let sink = unsafe { &*(user_ptr as *const ErrorSink) };
    let mut guard = match sink.lock() {
        Ok(g) => g,
        Err(poisoned) => poisoned.into_inner(),
    };
    // Keep the sink bounded even if nobody ever collects (errors on rendering threads).
    if guard.len() >= 16 {
        guard.remove(0);
    }
    guard.push((code, text));
}

struct DeviceInner {
    raw: sys::RTCDevice,
    sink: Box<ErrorSink>,
}

// SAFETY: an `RTCDevice` is a handle to a reference-counted, internally synchronised Embree
// device. The only device-level calls made through `DeviceInner` are object creation
// (`rtcNewScene`, `rtcNewGeometry`), which Embree allows from any thread, and
// `rtcGetDeviceError`, whose state is per thread by specification. The error sink is a `Mutex`.
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send` above; no method mutates the handle itself.
unsafe impl Sync for DeviceInner {}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live device owned by this struct (all scenes and geometries hold an
        // `Arc` to it, so none is left). Unregistering the callback first guarantees Embree never
        // calls it with the sink pointer after the sink is freed; then our reference is released.
        unsafe {
            sys::rtcSetDeviceErrorFunction(self.raw, None, std::ptr::null_mut());
            sys::rtcReleaseDevice(self.raw);
        }
        live_dec();
    }
}

/// An Embree device (`RTCDevice`): the context that scenes and geometries are created in.
/// Cheap to clone (shared handle); released when the last clone and everything created from it
/// are dropped.
#[derive(Clone)]
pub struct Device {
    inner: Arc<DeviceInner>,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Device").field("embree_major", &EMBREE_MAJOR).finish_non_exhaustive()
    }
}

impl Device {
    /// A device with Embree's default configuration.
    pub fn new() -> Result<Device> {
        Device::with_config("")
    }

    /// A device with an Embree configuration string (e.g. `"threads=1,verbose=0"`).
    pub fn with_config(config: &str) -> Result<Device> {
        let c_config = CString::new(config)
            .map_err(|_| Error::invalid("Embree device", "config", "configuration string contains a NUL byte"))?;
        // SAFETY: `c_config` is a valid NUL-terminated string that lives across the call.
        let raw = unsafe { sys::rtcNewDevice(c_config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: passing NULL asks for the error of the failed device construction, which
            // the Embree API documents as the way to query it.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(embree_error(code, None, &format!("rtcNewDevice(\"{config}\")")));
        }
        live_inc();
        let inner = DeviceInner { raw, sink: Box::new(Mutex::new(Vec::new())) };
        let sink_ptr = &*inner.sink as *const ErrorSink as *mut c_void;
        // SAFETY: `raw` is the live device just created; the sink pointer stays valid until
        // `DeviceInner::drop` unregisters the callback (the box is never moved out or replaced).
        unsafe { sys::rtcSetDeviceErrorFunction(raw, Some(error_callback), sink_ptr) };
        Ok(Device { inner: Arc::new(inner) })
    }

    fn raw(&self) -> sys::RTCDevice {
        self.inner.raw
    }

    /// Checks whether the last Embree call on this thread failed; if so, returns the error
    /// with the callback's message. `during` names the call.
    fn check(&self, during: &str) -> Result<()> {
        // SAFETY: `raw` is a live device; `rtcGetDeviceError` only reads and clears this
        // thread's error code for it.
        let code = unsafe { sys::rtcGetDeviceError(self.raw()) };
        if code == sys::RTC_ERROR_NONE {
            return Ok(());
        }
        let mut sink = match self.inner.sink.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        let message = sink.iter().rposition(|(c, _)| *c == code).map(|i| sink.remove(i).1);
        sink.clear();
        Err(embree_error(code, message.as_deref(), during))
    }
}

/// A committed triangle mesh (`RTC_GEOMETRY_TYPE_TRIANGLE`) with its own copy of the vertex and
/// index data, ready to attach to a scene. Released on drop (a scene it was attached to keeps
/// Embree's own reference).
pub struct TriangleGeometry {
    raw: sys::RTCGeometry,
    device: Device,
    triangles: usize,
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
        Ok(Scene { handle: self.handle, geometries: self.geometries, triangles: self.triangles })
    }
}

/// A ray in Embree's single precision: `org + t dir` for `tnear <= t <= tfar`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawRay {
    pub org: [f32; 3],
    pub dir: [f32; 3],
    pub tnear: f32,
    pub tfar: f32,
}

impl RawRay {
    /// Whether Embree may be asked about this ray: finite origin and direction, finite
    /// `tnear >= 0`, and `tfar >= tnear` (`tfar` may be `+inf`).
    pub fn is_valid(&self) -> bool {
        self.org.iter().chain(self.dir.iter()).all(|c| c.is_finite())
            && self.tnear.is_finite()
            && self.tnear >= 0.0
            && self.tfar >= self.tnear
    }

    fn to_sys(self) -> sys::RTCRay {
        sys::RTCRay {
            org_x: self.org[0],
            org_y: self.org[1],
            org_z: self.org[2],
            tnear: self.tnear,
            dir_x: self.dir[0],
            dir_y: self.dir[1],
            dir_z: self.dir[2],
            time: 0.0,
            tfar: self.tfar,
            // Debian builds Embree with ray masks on: a zero mask would miss everything.
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }
}

/// The nearest hit Embree found, in its own terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawHit {
    /// Ray parameter (in units of the ray's `dir`).
    pub t: f32,
    /// Barycentrics: point = (1 - u - v) p0 + u p1 + v p2.
    pub u: f32,
    pub v: f32,
    /// Unnormalised geometric normal, (p1 - p0) x (p2 - p0) up to Embree's sign convention.
    pub ng: [f32; 3],
    pub geom_id: u32,
    pub prim_id: u32,
}

/// The 16-lane activity mask of `rtcIntersect16`, which Embree wants 64-byte aligned.
#[repr(C, align(64))]
struct Valid16([i32; 16]);

/// A committed Embree scene: read-only and safe to query from many threads at once.
pub struct Scene {
    handle: SceneHandle,
    geometries: u32,
    triangles: usize,
}

// SAFETY: after `rtcCommitScene` the scene is never modified (no method takes `&mut self` or
// calls a mutating Embree function), and Embree documents `rtcIntersect*`/`rtcOccluded*` on a
// committed scene as thread-safe: every query writes only to the caller's own ray/hit structs.
unsafe impl Send for Scene {}
// SAFETY: see `Send` above: shared access only issues thread-safe read-only queries.
unsafe impl Sync for Scene {}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene").field("geometries", &self.geometries).field("triangles", &self.triangles).finish()
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
        let mut rayhit = sys::RTCRayHit { ray: ray.to_sys(), hit: sys::RTCHit::default() };
        rayhit.hit.geomID = sys::RTC_INVALID_GEOMETRY_ID;
        rayhit.hit.instID.fill(sys::RTC_INVALID_GEOMETRY_ID);
        // SAFETY: the scene is live and committed; `rayhit` is a properly aligned (checked at
        // compile time), fully initialised local that only this call accesses.
        unsafe { compat::intersect1(self.handle.raw, &mut rayhit) };
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

    /// Nearest hits for up to 16 rays in one packet (`rtcIntersect16`). `coherent` hints that
    /// the rays start close together and point in similar directions. Invalid rays get `None`.
    ///
    /// # Panics
    /// If `rays.len() > 16` or `hits.len() != rays.len()` (caller bugs, not data errors).
    pub fn intersect16(&self, rays: &[RawRay], hits: &mut [Option<RawHit>], coherent: bool) {
        assert!(rays.len() <= 16, "intersect16: {} rays given, at most 16 fit a packet", rays.len());
        assert_eq!(rays.len(), hits.len(), "intersect16: rays and hits differ in length");
        let mut valid = Valid16([0; 16]);
        let mut packet = sys::RTCRayHit16::default();
        for (lane, ray) in rays.iter().enumerate() {
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
            // SAFETY: the scene is live and committed; `valid` and `packet` are 64-byte aligned
            // locals (checked at compile time), initialised for every lane (inactive lanes are
            // ignored by Embree), and only this call accesses them.
            unsafe { compat::intersect16(valid.0.as_ptr(), self.handle.raw, &mut packet, coherent) };
        }
        for (lane, hit) in hits.iter_mut().enumerate() {
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
