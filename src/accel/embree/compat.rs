//! The few places where Embree 3 and Embree 4 differ, behind one set of functions: the ray-query
//! arguments, the argument order of the queries, the hit records' size, the version check at
//! device creation, and the spelling of enums in the two sources of bindings.
//!
//! Embree 3 passes an `RTCIntersectContext` (initialised by the header-only
//! `rtcInitIntersectContext`, which bindgen cannot emit) to every ray query, before the ray;
//! Embree 4 drops the context argument in favour of an optional `RTCIntersectArguments`
//! (initialised by the header-only `rtcInitIntersectArguments`) after the ray, and gives
//! occlusion queries their own optional `RTCOccludedArguments`. The Rust equivalents of both
//! initialisers live here. inimtrace registers no filter or user-geometry callbacks, so the
//! filter-function differences (`RTCFilterFunctionNArguments` gained a ray-query context in 4)
//! never arise: both versions get "no filter".
//!
//! Embree 4.3 and later write more of the hit record than the 4.2 headers of the `embree4-sys`
//! crate declare (`instPrimID`: 4 bytes past `RTCRayHit`, 64 past `RTCRayHit16`), so under
//! Embree 4 every hit record handed to a query is built and read in place inside a [`Padded`]
//! record with spare bytes after it.
//!
//! Both versions report whether the device traces 16-ray packets natively (`native_ray16`):
//! without AVX-512, Embree 4.4 answers `rtcIntersect16` one ray at a time, while its 8-ray
//! packets (`rtcIntersect8`, also here) stay fast, so the scene then traces 8 rays at a time.
//!
//! `build.rs` sets `cfg(embree4)` when it bound against Embree 4 (system headers through
//! `wrapper.h`, or the `embree4` feature, which takes the bindings from `embree4-sys`).

use super::sys;
use crate::error::{Error, Result};

/// Which Embree major version the crate was bound against.
pub const EMBREE_MAJOR: u32 = if cfg!(embree4) { 4 } else { 3 };

/// The variable that says where the library is, named by the version check's error.
const LIBRARY_VARIABLE: &str = if cfg!(feature = "embree4") { "EMBREE4_DIR" } else { "EMBREE_DIR" };

/// Spare bytes after every hit record handed to a query: a newer Embree than the headers may
/// write into them (none under Embree 3, whose records are as the headers say).
const SPARE: usize = if cfg!(embree4) { 128 } else { 0 };

/// A C struct followed by spare bytes that a newer Embree than the headers may write into. The
/// queries fill and read the record in place (`value`), so padding costs no copy.
#[repr(C, align(64))]
pub(super) struct Padded<T> {
    pub(super) value: T,
    spare: [u8; SPARE],
}

impl<T> Padded<T> {
    pub(super) fn new(value: T) -> Padded<T> {
        Padded { value, spare: [0; SPARE] }
    }
}

/// Per-query state: Embree 3's intersection context or Embree 4's intersect arguments.
#[cfg(not(embree4))]
type QueryArgs = sys::RTCIntersectContext;
#[cfg(embree4)]
type QueryArgs = Padded<sys::RTCIntersectArguments>;

/// Rust equivalent of `rtcInitIntersectContext` (Embree 3): no filter, no instance on the
/// stack, and the coherence hint. (Debian's build has `RTC_MAX_INSTANCE_LEVEL_COUNT == 1` and
/// `RTC_MIN_WIDTH == 0`; other builds may have more `instID` slots, all of which are set.)
#[cfg(not(embree4))]
#[allow(clippy::field_reassign_with_default)] // the struct's fields depend on Embree's build options
fn query_args(coherent: bool) -> QueryArgs {
    let mut ctx = sys::RTCIntersectContext::default();
    ctx.flags =
        if coherent { sys::RTC_INTERSECT_CONTEXT_FLAG_COHERENT } else { sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT };
    ctx.filter = None;
    for id in ctx.instID.iter_mut() {
        *id = sys::RTC_INVALID_GEOMETRY_ID;
    }
    ctx
}

/// Rust equivalent of `rtcInitIntersectArguments` (Embree 4, system headers): all traversal
/// features, no ray-query context, no filter or user-geometry callbacks (the zeroed default),
/// plus the coherence hint. Spare zero bytes follow, should the library's struct be longer.
#[cfg(all(embree4, not(feature = "embree4")))]
#[allow(clippy::field_reassign_with_default)] // the struct's fields depend on Embree's build options
fn query_args(coherent: bool) -> QueryArgs {
    let mut args = sys::RTCIntersectArguments::default();
    args.flags = if coherent { sys::RTC_RAY_QUERY_FLAG_COHERENT } else { sys::RTC_RAY_QUERY_FLAG_INCOHERENT };
    args.feature_mask = sys::RTC_FEATURE_FLAG_ALL;
    args.context = std::ptr::null_mut();
    args.filter = None;
    Padded::new(args)
}

/// As above, over `embree4-sys`'s struct (the 4.2 layout, no `minWidthDistanceFactor`).
#[cfg(feature = "embree4")]
fn query_args(coherent: bool) -> QueryArgs {
    Padded::new(sys::RTCIntersectArguments {
        flags: if coherent { sys::RTC_RAY_QUERY_FLAG_COHERENT } else { sys::RTC_RAY_QUERY_FLAG_INCOHERENT },
        feature_mask: sys::RTC_FEATURE_FLAG_ALL,
        context: std::ptr::null_mut(),
        filter: None,
        intersect: None,
    })
}

/// An `RTCError` as the number `error.rs` names.
#[cfg(not(feature = "embree4"))]
pub(super) fn error_code(code: sys::RTCError) -> u32 {
    code
}

/// An `RTCError` as the number `error.rs` names.
#[cfg(feature = "embree4")]
pub(super) fn error_code(code: sys::RTCError) -> u32 {
    code as u32
}

/// `rtcGetDeviceError` as a number (`sys::RTC_ERROR_NONE` when the last call succeeded).
///
/// # Safety
/// `device` must be a live device, or NULL for the error of a failed `rtcNewDevice`.
/// (Under `embree4-sys` the result is a Rust enum of the codes 0-6; Embree 4 adds code 7 only
/// for SYCL devices, which inimtrace never creates.)
pub(super) unsafe fn device_error(device: sys::RTCDevice) -> u32 {
    // SAFETY: forwarded from this function's contract.
    error_code(unsafe { sys::rtcGetDeviceError(device) })
}

/// `rtcGetDeviceProperty(RTC_DEVICE_PROPERTY_VERSION)`: the loaded library's version as
/// `10000 major + 100 minor + patch` (40400 for 4.4.0).
///
/// # Safety
/// `device` must be a live device.
pub(super) unsafe fn device_version(device: sys::RTCDevice) -> i64 {
    // SAFETY: forwarded from this function's contract; the property is valid in every release.
    let version = unsafe { sys::rtcGetDeviceProperty(device, sys::RTC_DEVICE_PROPERTY_VERSION) };
    version as i64
}

/// Whether the device traces 16-ray packets natively (`RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED`:
/// the AVX-512 kernels are in use). Where they are not (AVX2 CPUs), Embree 4.4 answers
/// `rtcIntersect16` one ray at a time, while its 8-ray packets stay fast.
///
/// # Safety
/// `device` must be a live device.
pub(super) unsafe fn native_ray16(device: sys::RTCDevice) -> bool {
    // SAFETY: forwarded from this function's contract; the property is valid in every release.
    unsafe { sys::rtcGetDeviceProperty(device, sys::RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0 }
}

/// `"4.4.0"` from Embree's version number `40400`.
pub fn version_text(version: i64) -> String {
    format!("{}.{}.{}", version / 10000, version / 100 % 100, version % 100)
}

/// Checks that the loaded library's `version` has the major version the bindings were made for
/// (`expected_major`); else one error naming the variable that chooses the library.
pub fn check_version(version: i64, expected_major: u32) -> Result<()> {
    if version / 10000 == i64::from(expected_major) {
        return Ok(());
    }
    Err(Error::Embree {
        code: "RTC_ERROR_UNKNOWN".into(),
        message: format!(
            "the Embree library loaded reports version {}, but inimtrace was built for Embree {expected_major}.x: \
             point {LIBRARY_VARIABLE} at an Embree {expected_major} library and rebuild (or remove the \
             LD_LIBRARY_PATH / LD_PRELOAD that loads another one)",
            version_text(version)
        ),
    })
}

/// `rtcIntersect1` for either version (incoherent-ray hint).
///
/// # Safety
/// `scene` must be a live, committed scene.
#[inline]
pub(super) unsafe fn intersect1(scene: sys::RTCScene, rayhit: &mut Padded<sys::RTCRayHit>) {
    let mut args = query_args(false);
    // SAFETY: forwarded from this function's contract; `args` and the ray-hit record are fully
    // initialised locals, aligned as Embree requires (`Padded` is 64-byte aligned), that outlive
    // the call; under Embree 4 the record has spare bytes after it for a library that writes a
    // longer hit.
    unsafe {
        #[cfg(not(embree4))]
        sys::rtcIntersect1(scene, &mut args, &mut rayhit.value);
        #[cfg(embree4)]
        sys::rtcIntersect1(scene, &mut rayhit.value, &mut args.value);
    }
}

/// `rtcOccluded1` for either version (incoherent-ray hint).
///
/// # Safety
/// `scene` must be a live, committed scene; `ray` must be 16-byte aligned.
#[inline]
pub(super) unsafe fn occluded1(scene: sys::RTCScene, ray: *mut sys::RTCRay) {
    #[cfg(not(embree4))]
    {
        let mut ctx = query_args(false);
        // SAFETY: forwarded from this function's contract; `ctx` is valid for the whole call.
        unsafe { sys::rtcOccluded1(scene, &mut ctx, ray) };
    }
    // Embree 4 takes a separate, optional `RTCOccludedArguments`; NULL means the defaults
    // (incoherent hint, all features, no filter), which is what we want. An occlusion query
    // writes only the ray's `tfar`, whose layout is the same in every Embree 4.
    #[cfg(embree4)]
    {
        // SAFETY: forwarded from this function's contract; the arguments pointer may be NULL.
        unsafe { sys::rtcOccluded1(scene, ray, std::ptr::null_mut()) };
    }
}

/// A 16-ray packet with every field zero (rays and hits), ready to fill, with spare bytes after
/// it under Embree 4.
pub(super) fn blank_packet() -> Padded<sys::RTCRayHit16> {
    // Zeroed where it lies: building the 1.3 KB packet and moving it into `Padded` cost two
    // copies per query.
    // SAFETY: `RTCRayHit16` is C arrays of `f32` and `u32` (and the spare bytes `u8`), for which
    // all-zero bytes are a valid value: the same value as every field's `Default`.
    unsafe { std::mem::zeroed() }
}

/// `rtcIntersect16` for either version, with the coherent-ray hint when `coherent`.
///
/// # Safety
/// `scene` must be a live, committed scene; `valid` must point to 16 `int`s aligned to 64 bytes
/// (0 = inactive lane, -1 = active).
#[inline]
pub(super) unsafe fn intersect16(
    valid: *const i32,
    scene: sys::RTCScene,
    rayhit: &mut Padded<sys::RTCRayHit16>,
    coherent: bool,
) {
    let mut args = query_args(coherent);
    // SAFETY: forwarded from this function's contract; `args` and the packet are fully
    // initialised, 64-byte aligned records valid for the whole call; under Embree 4 the packet
    // has spare bytes after it for a library that writes a longer hit.
    unsafe {
        #[cfg(not(embree4))]
        sys::rtcIntersect16(valid, scene, &mut args, &mut rayhit.value);
        #[cfg(embree4)]
        sys::rtcIntersect16(valid, scene, &mut rayhit.value, &mut args.value);
    }
}

/// An 8-ray packet with every field zero (rays and hits), ready to fill, with spare bytes after
/// it under Embree 4.
pub(super) fn blank_packet8() -> Padded<sys::RTCRayHit8> {
    // SAFETY: `RTCRayHit8` is C arrays of `f32` and `u32` (and the spare bytes `u8`), for which
    // all-zero bytes are a valid value.
    unsafe { std::mem::zeroed() }
}

/// `rtcIntersect8` for either version, with the coherent-ray hint when `coherent`.
///
/// # Safety
/// `scene` must be a live, committed scene; `valid` must point to 8 `int`s aligned to 32 bytes
/// (0 = inactive lane, -1 = active).
#[inline]
pub(super) unsafe fn intersect8(
    valid: *const i32,
    scene: sys::RTCScene,
    rayhit: &mut Padded<sys::RTCRayHit8>,
    coherent: bool,
) {
    let mut args = query_args(coherent);
    // SAFETY: forwarded from this function's contract; `args` and the packet are fully
    // initialised, 64-byte aligned records valid for the whole call; under Embree 4 the packet
    // has spare bytes after it for a library that writes a longer hit.
    unsafe {
        #[cfg(not(embree4))]
        sys::rtcIntersect8(valid, scene, &mut args, &mut rayhit.value);
        #[cfg(embree4)]
        sys::rtcIntersect8(valid, scene, &mut rayhit.value, &mut args.value);
    }
}
