//! The few places where Embree 3 and Embree 4 differ, behind one set of functions.
//!
//! Embree 3 passes an `RTCIntersectContext` (initialised by the header-only
//! `rtcInitIntersectContext`, which bindgen cannot emit) to every ray query; Embree 4 drops the
//! context argument in favour of an optional `RTCIntersectArguments` (initialised by the
//! header-only `rtcInitIntersectArguments`). The Rust equivalents of both initialisers live here.
//! Embree 4 also gives occlusion queries their own `RTCOccludedArguments`.
//! `build.rs` sets `cfg(embree4)` when it bound against Embree 4.

use super::sys;

/// Per-query state: Embree 3's intersection context or Embree 4's intersect arguments.
#[cfg(not(embree4))]
type QueryArgs = sys::RTCIntersectContext;
#[cfg(embree4)]
type QueryArgs = sys::RTCIntersectArguments;

/// Which Embree major version the crate was bound against.
pub const EMBREE_MAJOR: u32 = if cfg!(embree4) { 4 } else { 3 };

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

/// Rust equivalent of `rtcInitIntersectArguments` (Embree 4): all traversal features, no
/// ray-query context, no filter or user-geometry callbacks (the zeroed default), plus the
/// coherence hint.
#[cfg(embree4)]
#[allow(clippy::field_reassign_with_default)] // the struct's fields depend on Embree's build options
fn query_args(coherent: bool) -> QueryArgs {
    let mut args = sys::RTCIntersectArguments::default();
    args.flags = if coherent { sys::RTC_RAY_QUERY_FLAG_COHERENT } else { sys::RTC_RAY_QUERY_FLAG_INCOHERENT };
    args.feature_mask = sys::RTC_FEATURE_FLAG_ALL;
    args.context = std::ptr::null_mut();
    args.filter = None;
    args
}

/// `rtcIntersect1` for either version (incoherent-ray hint).
///
/// # Safety
/// `scene` must be a live, committed scene, and `rayhit` must point to a valid, 16-byte aligned
/// `RTCRayHit` that nothing else accesses during the call.
#[inline]
pub(super) unsafe fn intersect1(scene: sys::RTCScene, rayhit: *mut sys::RTCRayHit) {
    let mut args = query_args(false);
    // SAFETY: forwarded from this function's contract; `args` is a fully initialised local
    // that outlives the call.
    unsafe {
        #[cfg(not(embree4))]
        sys::rtcIntersect1(scene, &mut args, rayhit);
        #[cfg(embree4)]
        sys::rtcIntersect1(scene, rayhit, &mut args);
    }
}

/// `rtcOccluded1` for either version (incoherent-ray hint).
///
/// # Safety
/// As for [`intersect1`], with a 16-byte aligned `RTCRay`.
#[inline]
pub(super) unsafe fn occluded1(scene: sys::RTCScene, ray: *mut sys::RTCRay) {
    #[cfg(not(embree4))]
    {
        let mut ctx = query_args(false);
        // SAFETY: forwarded from this function's contract; `ctx` is valid for the whole call.
        unsafe { sys::rtcOccluded1(scene, &mut ctx, ray) };
    }
    // Embree 4 takes a separate, optional `RTCOccludedArguments`; NULL means the defaults
    // (incoherent hint, all features, no filter), which is what we want.
    #[cfg(embree4)]
    {
        // SAFETY: forwarded from this function's contract; the arguments pointer may be NULL.
        unsafe { sys::rtcOccluded1(scene, ray, std::ptr::null_mut()) };
    }
}

/// `rtcIntersect16` for either version, with the coherent-ray hint when `coherent`.
///
/// # Safety
/// `scene` must be a live, committed scene; `valid` must point to 16 `int`s aligned to 64 bytes
/// (0 = inactive lane, -1 = active); `rayhit` must point to a valid, 64-byte aligned
/// `RTCRayHit16` that nothing else accesses during the call.
#[inline]
pub(super) unsafe fn intersect16(
    valid: *const i32,
    scene: sys::RTCScene,
    rayhit: *mut sys::RTCRayHit16,
    coherent: bool,
) {
    let mut args = query_args(coherent);
    // SAFETY: forwarded from this function's contract; `args` is valid for the whole call.
    unsafe {
        #[cfg(not(embree4))]
        sys::rtcIntersect16(valid, scene, &mut args, rayhit);
        #[cfg(embree4)]
        sys::rtcIntersect16(valid, scene, rayhit, &mut args);
    }
}
