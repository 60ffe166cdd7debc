//! Raw Embree C API: by default generated at build time by bindgen from `wrapper.h` (see
//! `build.rs`); with the `embree4` feature, taken from the `embree4-sys` crate, whose bindings
//! (over the Embree 4.2 headers it ships) spell enums as Rust enums and bit-flag structs. Under
//! that feature the names the rest of the module uses (`RTC_ERROR_NONE`, `RTC_FORMAT_FLOAT3`, ...)
//! are defined here over the crate's, so one set of names serves both. Nothing here is safe to
//! call directly; `super` wraps what inimtrace needs.

#![allow(
    non_upper_case_globals,
    non_camel_case_types,
    non_snake_case,
    dead_code,
    unsafe_op_in_unsafe_fn,
    clippy::all,
    clippy::pedantic,
    rustdoc::all
)]

#[cfg(not(feature = "embree4"))]
include!(concat!(env!("OUT_DIR"), "/embree_bindings.rs"));

/// `RTC_INVALID_GEOMETRY_ID` is `((unsigned int)-1)` in the header; bindgen skips cast macros.
#[cfg(not(feature = "embree4"))]
pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

#[cfg(feature = "embree4")]
pub use embree4_sys::{
    rtcAttachGeometry, rtcCommitGeometry, rtcCommitScene, rtcGetDeviceError, rtcGetDeviceProperty, rtcIntersect1,
    rtcIntersect16, rtcIntersect8, rtcNewDevice, rtcNewGeometry, rtcNewScene, rtcOccluded1, rtcReleaseDevice,
    rtcReleaseGeometry, rtcReleaseScene, rtcSetDeviceErrorFunction, rtcSetGeometryBuildQuality,
    rtcSetNewGeometryBuffer, rtcSetSceneBuildQuality, rtcSetSceneFlags, RTCBufferType, RTCBuildQuality, RTCDevice,
    RTCDeviceProperty, RTCError, RTCFeatureFlags, RTCFormat, RTCGeometry, RTCGeometryType, RTCHit,
    RTCIntersectArguments, RTCRay, RTCRayHit, RTCRayHit16, RTCRayHit8, RTCRayQueryFlags, RTCScene, RTCSceneFlags,
    RTC_INVALID_GEOMETRY_ID,
};

// Error codes as plain numbers, as `error.rs` matches them (the crate's `RTCError` enum is
// converted by `compat::error_code`).
#[cfg(feature = "embree4")]
pub const RTC_ERROR_NONE: u32 = RTCError::NONE as u32;
#[cfg(feature = "embree4")]
pub const RTC_ERROR_UNKNOWN: u32 = RTCError::UNKNOWN as u32;
#[cfg(feature = "embree4")]
pub const RTC_ERROR_INVALID_ARGUMENT: u32 = RTCError::INVALID_ARGUMENT as u32;
#[cfg(feature = "embree4")]
pub const RTC_ERROR_INVALID_OPERATION: u32 = RTCError::INVALID_OPERATION as u32;
#[cfg(feature = "embree4")]
pub const RTC_ERROR_OUT_OF_MEMORY: u32 = RTCError::OUT_OF_MEMORY as u32;
#[cfg(feature = "embree4")]
pub const RTC_ERROR_UNSUPPORTED_CPU: u32 = RTCError::UNSUPPORTED_CPU as u32;
#[cfg(feature = "embree4")]
pub const RTC_ERROR_CANCELLED: u32 = RTCError::CANCELLED as u32;

#[cfg(feature = "embree4")]
pub const RTC_BUFFER_TYPE_INDEX: RTCBufferType = RTCBufferType::INDEX;
#[cfg(feature = "embree4")]
pub const RTC_BUFFER_TYPE_VERTEX: RTCBufferType = RTCBufferType::VERTEX;
#[cfg(feature = "embree4")]
pub const RTC_BUILD_QUALITY_LOW: RTCBuildQuality = RTCBuildQuality::LOW;
#[cfg(feature = "embree4")]
pub const RTC_BUILD_QUALITY_MEDIUM: RTCBuildQuality = RTCBuildQuality::MEDIUM;
#[cfg(feature = "embree4")]
pub const RTC_BUILD_QUALITY_HIGH: RTCBuildQuality = RTCBuildQuality::HIGH;
#[cfg(feature = "embree4")]
pub const RTC_FORMAT_FLOAT3: RTCFormat = RTCFormat::FLOAT3;
#[cfg(feature = "embree4")]
pub const RTC_FORMAT_UINT3: RTCFormat = RTCFormat::UINT3;
#[cfg(feature = "embree4")]
pub const RTC_GEOMETRY_TYPE_TRIANGLE: RTCGeometryType = RTCGeometryType::TRIANGLE;
#[cfg(feature = "embree4")]
pub const RTC_SCENE_FLAG_ROBUST: RTCSceneFlags = RTCSceneFlags::ROBUST;
#[cfg(feature = "embree4")]
pub const RTC_DEVICE_PROPERTY_VERSION: RTCDeviceProperty = RTCDeviceProperty::VERSION;
#[cfg(feature = "embree4")]
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED: RTCDeviceProperty = RTCDeviceProperty::NATIVE_RAY16_SUPPORTED;
#[cfg(feature = "embree4")]
pub const RTC_RAY_QUERY_FLAG_COHERENT: RTCRayQueryFlags = RTCRayQueryFlags::COHERENT;
#[cfg(feature = "embree4")]
pub const RTC_RAY_QUERY_FLAG_INCOHERENT: RTCRayQueryFlags = RTCRayQueryFlags::INCOHERENT;
#[cfg(feature = "embree4")]
pub const RTC_FEATURE_FLAG_ALL: RTCFeatureFlags = RTCFeatureFlags::RTC_FEATURE_FLAG_ALL;
