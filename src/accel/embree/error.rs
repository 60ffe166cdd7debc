//! Embree's errors as [`Error::Embree`]: the names of its error codes, and the error callback
//! that collects its messages for the device that raised them.

use std::ffi::{c_char, c_void, CStr};
use std::sync::Mutex;

use super::sys;
use crate::error::Error;

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
pub(super) type ErrorSink = Mutex<Vec<(u32, String)>>;

/// Embree's error callback. `user_ptr` is the device's [`ErrorSink`]. It must not unwind into
/// C, so it only records and never panics (a poisoned lock is still usable).
pub(super) unsafe extern "C" fn error_callback(user_ptr: *mut c_void, code: sys::RTCError, message: *const c_char) {
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
    guard.push((super::compat::error_code(code), text));
}
