//! [`Device`]: the RAII handle of an Embree device (`RTCDevice`), the context every scene and
//! geometry is created in, with its error callback registered for its lifetime.

use std::ffi::{c_void, CString};
use std::sync::{Arc, Mutex};

use super::compat::{self, EMBREE_MAJOR};
use super::error::{embree_error, error_callback, ErrorSink};
use super::live::{live_dec, live_inc};
use super::sys;
use crate::error::{Error, Result};

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
            let code = unsafe { compat::device_error(std::ptr::null_mut()) };
            return Err(embree_error(code, None, &format!("rtcNewDevice(\"{config}\")")));
        }
        live_inc();
        let inner = DeviceInner { raw, sink: Box::new(Mutex::new(Vec::new())) };
        let sink_ptr = &*inner.sink as *const ErrorSink as *mut c_void;
        // SAFETY: `raw` is the live device just created; the sink pointer stays valid until
        // `DeviceInner::drop` unregisters the callback (the box is never moved out or replaced).
        unsafe { sys::rtcSetDeviceErrorFunction(raw, Some(error_callback), sink_ptr) };
        let device = Device { inner: Arc::new(inner) };
        // The library found at run time must be the major version the bindings were made for
        // (an LD_LIBRARY_PATH can swap it): else one error naming where the library comes from.
        compat::check_version(device.version(), EMBREE_MAJOR)?;
        Ok(device)
    }

    /// The loaded Embree library's version number (`rtcGetDeviceProperty`): `10000 major +
    /// 100 minor + patch`, e.g. 31305 for 3.13.5.
    pub fn version(&self) -> i64 {
        // SAFETY: `raw` is a live device.
        unsafe { compat::device_version(self.raw()) }
    }

    /// The loaded Embree library's version as text, e.g. `"4.4.0"`.
    pub fn version_text(&self) -> String {
        compat::version_text(self.version())
    }

    pub(super) fn raw(&self) -> sys::RTCDevice {
        self.inner.raw
    }

    /// Checks whether the last Embree call on this thread failed; if so, returns the error
    /// with the callback's message. `during` names the call.
    pub(super) fn check(&self, during: &str) -> Result<()> {
        // SAFETY: `raw` is a live device; `rtcGetDeviceError` only reads and clears this
        // thread's error code for it.
        let code = unsafe { compat::device_error(self.raw()) };
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
