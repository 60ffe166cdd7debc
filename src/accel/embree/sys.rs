//! Raw Embree C API, generated at build time by bindgen from `wrapper.h` (see `build.rs`).
//! Nothing here is safe to call directly; `super` wraps what inimtrace needs.

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

include!(concat!(env!("OUT_DIR"), "/embree_bindings.rs"));

/// `RTC_INVALID_GEOMETRY_ID` is `((unsigned int)-1)` in the header; bindgen skips cast macros.
pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
