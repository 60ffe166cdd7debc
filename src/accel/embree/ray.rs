//! Rays and hits in Embree's own single-precision terms ([`RawRay`], [`RawHit`]), and the
//! alignment Embree requires of the C structs they are copied into.

use super::sys;

// Embree requires 16-byte aligned single rays, 32-byte aligned 8-wide and 64-byte aligned 16-wide
// packets; bindgen carries the C `RTC_ALIGN` over as `repr(align)`, and these checks keep it that
// way.
const _: () = assert!(std::mem::align_of::<sys::RTCRayHit>() >= 16);
const _: () = assert!(std::mem::align_of::<sys::RTCRay>() >= 16);
const _: () = assert!(std::mem::align_of::<sys::RTCRayHit16>() >= 64);
const _: () = assert!(std::mem::align_of::<sys::RTCRayHit8>() >= 32);
const _: () = assert!(std::mem::align_of::<Valid16>() >= 64);

/// A ray in Embree's single precision: `org + t dir` for `tnear <= t <= tfar`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawRay {
    /// Origin, world mm.
    pub org: [f32; 3],
    /// Direction (any length).
    pub dir: [f32; 3],
    /// Smallest `t` accepted.
    pub tnear: f32,
    /// Largest `t` accepted.
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

    pub(super) fn to_sys(self) -> sys::RTCRay {
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
    /// Second barycentric.
    pub v: f32,
    /// Unnormalised geometric normal, (p1 - p0) x (p2 - p0) up to Embree's sign convention.
    pub ng: [f32; 3],
    /// Embree's id of the geometry hit (the scene object).
    pub geom_id: u32,
    /// Embree's id of the triangle hit within it.
    pub prim_id: u32,
}

/// The 16-lane activity mask of `rtcIntersect16`, which Embree wants 64-byte aligned (its first 8
/// lanes serve `rtcIntersect8`, which wants 32).
#[repr(C, align(64))]
pub(super) struct Valid16(pub(super) [i32; 16]);
