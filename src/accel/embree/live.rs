//! The process-wide count of live Embree objects (devices, scenes, geometries): every RAII
//! handle of this module counts itself in on creation and out on drop, so tests can check that
//! nothing leaks.

use std::sync::atomic::{AtomicUsize, Ordering};

/// Number of Embree devices, scenes and geometries currently alive in this process (created by
/// this module and not yet dropped).
static LIVE: AtomicUsize = AtomicUsize::new(0);

/// How many Embree objects (devices, scenes, geometries) are alive right now, process-wide.
/// Returns to its earlier value once everything created since has been dropped.
pub fn live_objects() -> usize {
    LIVE.load(Ordering::SeqCst)
}

pub(super) fn live_inc() {
    LIVE.fetch_add(1, Ordering::SeqCst);
}

pub(super) fn live_dec() {
    LIVE.fetch_sub(1, Ordering::SeqCst);
}
