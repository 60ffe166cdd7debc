//! First-order (paraxial) optics of a schematic eye: a y-nu trace with 2x2 transfer and
//! refraction matrices in reduced angles (y, n u), after W. J. Smith, "Modern Optical
//! Engineering", 4th ed. (2008), Ch. 3, and A. Gerrard & J. M. Burch, "Introduction to Matrix
//! Methods in Optics" (1975). Surface power `(n' - n) c`; cardinal points from the system matrix
//! `[[A, B], [C, D]]` between the first and last vertices: power `-C`, front focal point
//! `-D/φ`, principal points `(1 - D)/φ` and `t_last + n'(A - 1)/φ`, nodal points shifted from
//! them by `(n' - n)/φ`. The entrance pupil is the paraxial image of the iris centre through
//! the surfaces before it, seen from the air.

/// A 2x2 ray-transfer matrix acting on (y, n u).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Abcd {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
}

impl Abcd {
    pub const IDENTITY: Abcd = Abcd { a: 1.0, b: 0.0, c: 0.0, d: 1.0 };
    /// Transfer by `distance` mm in a medium of index `n`.
    pub fn transfer(distance: f64, n: f64) -> Abcd {
        Abcd { a: 1.0, b: distance / n, c: 0.0, d: 1.0 }
    }
    /// Refraction by a surface of power `power` (1/mm).
    pub fn refraction(power: f64) -> Abcd {
        Abcd { a: 1.0, b: 0.0, c: -power, d: 1.0 }
    }
    /// `next` applied after `self`.
    pub fn then(self, next: Abcd) -> Abcd {
        Abcd {
            a: next.a * self.a + next.b * self.c,
            b: next.a * self.b + next.b * self.d,
            c: next.c * self.a + next.d * self.c,
            d: next.c * self.b + next.d * self.d,
        }
    }
}

/// Paraxial data of a schematic eye at one wavelength; every z in the eye's frame (origin at
/// the entrance pupil centre at the reference wavelength, +z toward the object).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paraxial {
    /// The wavelength, nm.
    pub wavelength_nm: f64,
    /// Total power, dioptres.
    pub power_d: f64,
    /// Front (object-side, in air) focal length 1/φ, mm.
    pub front_focal_length: f64,
    /// Back (image-side) focal length n'/φ, mm.
    pub back_focal_length: f64,
    /// z of the front focal point.
    pub front_focal_z: f64,
    /// z of the back focal point.
    pub back_focal_z: f64,
    /// z of the front and back principal points.
    pub principal_z: (f64, f64),
    /// z of the front and back nodal points.
    pub nodal_z: (f64, f64),
    /// z of the entrance pupil (about 0 at the reference wavelength).
    pub entrance_pupil_z: f64,
    /// Entrance-pupil size over iris size (the iris's paraxial magnification through the cornea).
    pub iris_to_entrance_pupil_magnification: f64,
    /// z of the iris plane.
    pub iris_z: f64,
    /// z of the cornea's front vertex.
    pub cornea_z: f64,
    /// z of the retina's vertex.
    pub retina_z: f64,
    /// Object vergence conjugate to the retina vertex, dioptres: 1000 / (object z), 0 for
    /// infinity, negative for a virtual object behind the eye (hyperopia).
    pub conjugate_vergence_d: f64,
}

/// The lens-design data a paraxial trace needs: vertices t (mm from the cornea vertex toward the
/// retina), curvatures, the indices `n[0] = air, n[i+1]` after surface i.
pub(crate) struct ParaxialInput<'a> {
    pub vertices: &'a [f64],
    pub curvatures: &'a [f64],
    pub n: &'a [f64],
    pub iris_after: usize,
    pub iris_t: f64,
    pub retina_t: f64,
}

impl ParaxialInput<'_> {
    /// The matrix from the plane `t0` (in front of surface `i0`) through surfaces `i0..i1` to
    /// the plane `t1` (behind surface `i1 - 1`).
    pub fn chain(&self, t0: f64, i0: usize, i1: usize, t1: f64) -> Abcd {
        let mut m = Abcd::IDENTITY;
        let mut t = t0;
        for i in i0..i1 {
            m = m.then(Abcd::transfer(self.vertices[i] - t, self.n[i]));
            m = m.then(Abcd::refraction((self.n[i + 1] - self.n[i]) * self.curvatures[i]));
            t = self.vertices[i];
        }
        m.then(Abcd::transfer(t1 - t, self.n[i1]))
    }

    /// Entrance pupil t and the iris's y over the entrance pupil's y.
    pub fn entrance_pupil(&self) -> (f64, f64) {
        let m = self.chain(0.0, 0, self.iris_after + 1, self.iris_t);
        (m.b / m.a, m.a)
    }

    /// The paraxial data in the frame whose origin is at `origin_t` (z = origin_t - t).
    pub fn paraxial(&self, wavelength_nm: f64, origin_t: f64) -> Paraxial {
        let last = self.vertices.len();
        let s = self.chain(0.0, 0, last, self.vertices[last - 1]);
        let phi = -s.c;
        let n1 = self.n[last];
        let tl = self.vertices[last - 1];
        let z = |t: f64| origin_t - t;
        let (ep_t, iris_over_ep) = self.entrance_pupil();
        let h = ((1.0 - s.d) / phi, tl + n1 * (s.a - 1.0) / phi);
        let full = self.chain(0.0, 0, last, self.retina_t);
        let denom = origin_t * full.a - full.b;
        Paraxial {
            wavelength_nm,
            power_d: 1000.0 * phi,
            front_focal_length: 1.0 / phi,
            back_focal_length: n1 / phi,
            front_focal_z: z(-s.d / phi),
            back_focal_z: z(tl + n1 * s.a / phi),
            principal_z: (z(h.0), z(h.1)),
            nodal_z: (z(h.0 + (n1 - 1.0) / phi), z(h.1 + (n1 - 1.0) / phi)),
            entrance_pupil_z: z(ep_t),
            iris_to_entrance_pupil_magnification: 1.0 / iris_over_ep,
            iris_z: z(self.iris_t),
            cornea_z: z(0.0),
            retina_z: z(self.retina_t),
            conjugate_vergence_d: if denom == 0.0 { f64::INFINITY } else { 1000.0 * full.a / denom },
        }
    }
}
