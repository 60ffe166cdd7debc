//! A real lenslet's traces run several at a time: the camera ray of
//! [`ThickLenslet::camera_ray_in`] (the reverse trace from one LCD point through the pixel's
//! extended lenslet, `optics::lenslet`) for `K` lenslet points and indices at once, and the second
//! half of the eye -> LCD trace, [`ThickLenslet::trace_from_front`] through a plane back, for `K`
//! indices at once. Each step of a trace is a pass over the lanes without a branch (a blocked
//! lane carries a flag, not an early return), so that the square roots and divisions of
//! independent rays run side by side in the vector units.
//!
//! Every lane does the arithmetic of the one-ray trace in the same order (the closed-form conic
//! intersection, its normal and sag of `optics::eye::conic`, Snell's law of
//! `optics::eye::refract`, glam's normalisation), so each lane's ray is bit for bit the one the
//! one-ray trace returns, and `None` exactly where it returns `None` (tested in
//! `tests/thick_lenslet.rs`, which holds the two together). The display-image renderer traces
//! PupilCenter's Newton steps (the three colour channels' solves in lockstep) and
//! LensletCenter's and LensletAverage's rays through it (`render/display_thick.rs`); the eye's
//! rays reach the LCD in the three colour channels through it
//! ([`ThickLenslet::trace_to_lcd_each`]).

// Each pass indexes several lane arrays by the lane; the negated comparisons keep the one-ray
// trace's NaN semantics (a NaN passes its `x < 0` tests).
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use glam::{DMat2, DVec2, DVec3};

use super::eye::conic::Conic;
use super::lattice::Lattice;
use super::lenslet::{FrontHit, ThickLenslet, ThickTrace};
use crate::ray::Ray;

/// Three coordinates per lane.
#[derive(Clone, Copy)]
struct V<const K: usize> {
    x: [f64; K],
    y: [f64; K],
    z: [f64; K],
}

impl<const K: usize> V<K> {
    #[inline(always)]
    fn zero() -> Self {
        Self { x: [0.0; K], y: [0.0; K], z: [0.0; K] }
    }

    /// `v` in every lane.
    #[inline(always)]
    fn splat(v: DVec3) -> Self {
        Self { x: [v.x; K], y: [v.y; K], z: [v.z; K] }
    }
}

/// [`Conic::intersect`] in every lane (`ok` cleared where it returns `None`): the hit point.
#[inline(always)]
fn intersect<const K: usize>(s: &Conic, p: &V<K>, d: &V<K>, ok: &mut [bool; K]) -> V<K> {
    let c = s.curvature;
    let k1 = 1.0 + s.conic;
    let semi2 = s.semi_diameter * s.semi_diameter;
    let mut out = V::zero();
    for i in 0..K {
        let (px, py, pz) = (p.x[i], p.y[i], p.z[i] - s.vertex);
        let (dx, dy, dz) = (d.x[i], d.y[i], d.z[i]);
        let a = c * (dx * dx + dy * dy + k1 * dz * dz);
        let b = c * (px * dx + py * dy + k1 * pz * dz) - dz;
        let cc = c * (px * px + py * py + k1 * pz * pz) - 2.0 * pz;
        let disc = b * b - a * cc;
        let real = !(disc.is_nan() || disc < 0.0);
        let q = -(b + disc.sqrt().copysign(b));
        let r1 = if q != 0.0 { cc / q } else { f64::NAN };
        let r2 = if a != 0.0 { q / a } else { f64::NAN };
        let swap = !(r1 <= r2 || r2.is_nan());
        let (lo, hi) = if swap { (r2, r1) } else { (r1, r2) };
        // The first root in front of the start on the vertex sheet, as the one-ray loop takes it.
        let (lx, ly, lz) = (p.x[i] + lo * dx, p.y[i] + lo * dy, p.z[i] + lo * dz);
        let lo_ok = !(lo.is_nan() || lo <= 0.0 || (1.0 - k1 * c * (lz - s.vertex) < 0.0));
        let (hx, hy, hz) = (p.x[i] + hi * dx, p.y[i] + hi * dy, p.z[i] + hi * dz);
        let hi_ok = !(hi.is_nan() || hi <= 0.0 || (1.0 - k1 * c * (hz - s.vertex) < 0.0));
        let (x, y, z) = if lo_ok { (lx, ly, lz) } else { (hx, hy, hz) };
        let inside = !(x * x + y * y > semi2);
        ok[i] &= real && (lo_ok || hi_ok) && inside;
        out.x[i] = x;
        out.y[i] = y;
        out.z[i] = z;
    }
    out
}

/// [`Conic::normal`] in every lane.
#[inline(always)]
fn normal<const K: usize>(s: &Conic, p: &V<K>) -> V<K> {
    let c = s.curvature;
    let mut out = V::zero();
    for i in 0..K {
        let g = 1.0 - (1.0 + s.conic) * c * (p.z[i] - s.vertex);
        let (x, y) = (-c * p.x[i], -c * p.y[i]);
        let r = 1.0 / (x * x + y * y + g * g).sqrt();
        out.x[i] = x * r;
        out.y[i] = y * r;
        out.z[i] = g * r;
    }
    out
}

/// [`refract`](super::eye::refract::refract) in every lane from index `n1[i]` into `n2[i]`
/// (`ok` cleared on total internal reflection).
#[inline(always)]
fn refract<const K: usize>(d: &V<K>, nrm: &V<K>, n1: &[f64; K], n2: &[f64; K], ok: &mut [bool; K]) -> V<K> {
    let mut out = V::zero();
    for i in 0..K {
        let cos = -(nrm.x[i] * d.x[i] + nrm.y[i] * d.y[i] + nrm.z[i] * d.z[i]);
        let flip = cos < 0.0;
        let cos_i = if flip { -cos } else { cos };
        let (nx, ny, nz) = if flip { (-nrm.x[i], -nrm.y[i], -nrm.z[i]) } else { (nrm.x[i], nrm.y[i], nrm.z[i]) };
        let eta = n1[i] / n2[i];
        let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
        ok[i] &= !(k < 0.0);
        let t = eta * cos_i - k.sqrt();
        out.x[i] = eta * d.x[i] + t * nx;
        out.y[i] = eta * d.y[i] + t * ny;
        out.z[i] = eta * d.z[i] + t * nz;
    }
    out
}

impl ThickLenslet {
    /// [`ThickLenslet::trace_from_front`] (closed-form intersection) of one front hit at each of
    /// the indices `n[i]` side by side, for a lenslet whose back surface is a plane (the same
    /// plane in every cell, so no lane changes cell); bit for bit the `K` one-index traces (see
    /// the module's documentation). [`ThickLenslet::trace_to_lcd_each`] takes it for such
    /// lenslets.
    #[inline]
    pub fn traces_from_front<const K: usize>(
        &self,
        lattice: &Lattice,
        front_z: f64,
        lcd_z: f64,
        f: &FrontHit,
        n: &[f64; K],
    ) -> [Option<ThickTrace>; K] {
        debug_assert!(self.back.curvature() == 0.0, "traces_from_front needs a plane back");
        let (c, front) = (f.center, f.point);
        let mut ok = [true; K];
        let air = [1.0; K];
        let d1 = refract(&V::splat(f.dir), &V::splat(f.normal), &air, n, &mut ok);
        let back_conic = Conic::from_radius(self.thickness, self.back.radius, self.back.conic, f64::INFINITY);
        // The plane's hit is looked for in the front hit's cell (`settle` of a plane).
        let c2 = lattice.center(f.cell);
        let mut start = V::zero();
        for i in 0..K {
            ok[i] &= !(d1.z[i] <= 0.0);
            let s = (f.zs - front.z) / d1.z[i];
            let (x, y, z) = (front.x + d1.x[i] * s, front.y + d1.y[i] * s, front.z + d1.z[i] * s);
            start.x[i] = (x + c.x) - c2.x;
            start.y[i] = (y + c.y) - c2.y;
            start.z[i] = (z + front_z) - front_z;
        }
        let back = intersect(&back_conic, &start, &d1, &mut ok);
        let d2 = refract(&d1, &normal(&back_conic, &back), n, &air, &mut ok);
        let front_world = DVec3::new(front.x + c.x, front.y + c.y, front.z + front_z);
        std::array::from_fn(|i| {
            if !ok[i] || d2.z[i] <= 0.0 {
                return None;
            }
            let back_world = DVec3::new(back.x[i] + c2.x, back.y[i] + c2.y, back.z[i] + front_z);
            let dir = DVec3::new(d2.x[i], d2.y[i], d2.z[i]);
            let lcd = back_world.truncate() + dir.truncate() * ((lcd_z - back_world.z) / dir.z);
            Some(ThickTrace { cell: f.cell, front: front_world, back: back_world, dir, lcd })
        })
    }

    /// [`ThickLenslet::camera_ray_in`] from the LCD point `lcd` toward each lane's back-vertex
    /// point `p[i]` at index `n[i]`, through the lenslet centred at `center`: bit for bit the
    /// `K` one-ray traces (see the module's documentation).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn camera_rays_in<const K: usize>(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        p: &[DVec2; K],
        n: &[f64; K],
        reference_z: f64,
    ) -> [Option<Ray>; K] {
        let back_plane = front_z + self.thickness;
        let back_conic = Conic::from_radius(self.thickness, self.back.radius, self.back.conic, f64::INFINITY);
        let front_conic = Conic::from_radius(0.0, self.front.radius, self.front.conic, f64::INFINITY);
        let lead = 1.0 + self.back.radius.abs().min(10.0);
        let gap = (lcd_z - (back_plane + lead)).max(0.0);
        let dz0 = back_plane - lcd_z;
        let mut ok = [true; K];
        // The unit direction from the LCD point to p and the start behind the back surface.
        let mut d = V::zero();
        let mut start = V::zero();
        for i in 0..K {
            let (x, y) = (p[i].x - lcd.x, p[i].y - lcd.y);
            let r = 1.0 / (x * x + y * y + dz0 * dz0).sqrt();
            d.x[i] = x * r;
            d.y[i] = y * r;
            d.z[i] = dz0 * r;
            let s0 = gap / -d.z[i];
            start.x[i] = (lcd.x + d.x[i] * s0) - center.x;
            start.y[i] = (lcd.y + d.y[i] * s0) - center.y;
            start.z[i] = (lcd_z + d.z[i] * s0) - front_z;
        }
        let back = intersect(&back_conic, &start, &d, &mut ok);
        let air = [1.0; K];
        let d1 = refract(&d, &normal(&back_conic, &back), &air, n, &mut ok);
        // Inside the material: start in front of both the back hit and the front surface there.
        let mut inside = V::zero();
        for i in 0..K {
            ok[i] &= !(d1.z[i] >= 0.0);
            let r2 = back.x[i] * back.x[i] + back.y[i] * back.y[i];
            let c = front_conic.curvature;
            let u = 1.0 - (1.0 + front_conic.conic) * c * c * r2;
            let sag = if u < 0.0 { self.front.radius.abs() } else { c * r2 / (1.0 + u.sqrt()) };
            let zs = back.z[i].max(sag) + 1e-3 * (1.0 + self.thickness);
            let s = (zs - back.z[i]) / d1.z[i];
            inside.x[i] = back.x[i] + d1.x[i] * s;
            inside.y[i] = back.y[i] + d1.y[i] * s;
            inside.z[i] = back.z[i] + d1.z[i] * s;
        }
        let front = intersect(&front_conic, &inside, &d1, &mut ok);
        let d2 = refract(&d1, &normal(&front_conic, &front), n, &air, &mut ok);
        std::array::from_fn(|i| {
            if !ok[i] || d2.z[i] >= 0.0 {
                return None;
            }
            let point = DVec3::new(front.x[i] + center.x, front.y[i] + center.y, front.z[i] + front_z);
            let w = DVec2::new(d2.x[i], d2.y[i]) / d2.z[i];
            let start = point.truncate() + w * (reference_z - point.z);
            Some(Ray { origin: start.extend(reference_z), dir: w.extend(1.0) })
        })
    }

    /// [`ThickLenslet::camera_rays_in`] for any number of lanes: `out[i]` is the camera ray from
    /// `lcd` toward `p[i]` at index `n[i]` (eight lanes at a time, the rest four, two, one).
    #[allow(clippy::too_many_arguments)]
    pub fn camera_rays_into(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        p: &[DVec2],
        n: &[f64],
        reference_z: f64,
        out: &mut [Option<Ray>],
    ) {
        debug_assert!(p.len() == n.len() && p.len() == out.len());
        let mut i = 0;
        macro_rules! lanes {
            ($k:literal) => {
                while p.len() - i >= $k {
                    let ps: &[DVec2; $k] = p[i..i + $k].try_into().expect("lanes");
                    let ns: &[f64; $k] = n[i..i + $k].try_into().expect("lanes");
                    out[i..i + $k].copy_from_slice(&self.camera_rays_in(
                        center,
                        front_z,
                        lcd_z,
                        lcd,
                        ps,
                        ns,
                        reference_z,
                    ));
                    i += $k;
                }
            };
        }
        lanes!(8);
        lanes!(4);
        lanes!(2);
        lanes!(1);
    }

    /// [`ThickLenslet::pupil_center_ray`] at each of the three indices `ns` (the colour
    /// channels'), the three Newton solves in lockstep: each round traces every unfinished
    /// channel's point and its two Jacobian neighbours together ([`ThickLenslet::camera_rays_into`];
    /// a channel that converges or is blocked at its point leaves its neighbours' traces unused).
    /// Bit for bit the three one-channel solves (the same traces, the same steps; tested).
    #[allow(clippy::too_many_arguments)]
    pub fn pupil_center_rays(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        eye: DVec3,
        guess: DVec2,
        ns: [f64; 3],
    ) -> [Option<(DVec2, Ray)>; 3] {
        let h = 1e-7;
        let miss = |r: &Ray| r.origin.truncate() - eye.truncate();
        let mut p = [if guess.is_finite() { guess } else { center }; 3];
        let mut out = [None; 3];
        let mut active = [true; 3];
        let (mut ps, mut nl) = ([DVec2::ZERO; 9], [0.0; 9]);
        let mut rays = [None; 9];
        for step in 0..=20 {
            // The last round only checks the point the twentieth step reached.
            let last = step == 20;
            let per = if last { 1 } else { 3 };
            let mut live = [0usize; 3];
            let mut m = 0;
            for c in 0..3 {
                if active[c] {
                    live[m] = c;
                    let lanes = [p[c], p[c] + DVec2::new(h, 0.0), p[c] + DVec2::new(0.0, h)];
                    ps[m * per..(m + 1) * per].copy_from_slice(&lanes[..per]);
                    nl[m * per..(m + 1) * per].fill(ns[c]);
                    m += 1;
                }
            }
            if m == 0 {
                break;
            }
            let k = m * per;
            self.camera_rays_into(center, front_z, lcd_z, lcd, &ps[..k], &nl[..k], eye.z, &mut rays[..k]);
            for (j, &c) in live[..m].iter().enumerate() {
                let Some(ray) = rays[j * per] else {
                    active[c] = false;
                    continue;
                };
                let f = miss(&ray);
                if f.length() < 1e-9 {
                    out[c] = Some((p[c], ray));
                    active[c] = false;
                    continue;
                }
                if last {
                    active[c] = false;
                    continue;
                }
                let (Some(rx), Some(ry)) = (rays[j * per + 1], rays[j * per + 2]) else {
                    active[c] = false;
                    continue;
                };
                let dx = (miss(&rx) - f) / h;
                let dy = (miss(&ry) - f) / h;
                let jac = DMat2::from_cols(dx, dy);
                if jac.determinant().abs() < 1e-300 {
                    active[c] = false;
                    continue;
                }
                p[c] -= jac.inverse() * f;
            }
        }
        out
    }
}
