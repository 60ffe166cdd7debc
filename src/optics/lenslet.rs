//! The lenslets' optics: the paper's ideal thin lens (eq. (1b), [`LensletOptics::Paraxial`]) or a
//! real thick lenslet ([`ThickLenslet`]) traced exactly in f64 through both of its surfaces.
//!
//! A thick lenslet has a front surface (facing the eye) and a back surface (facing the LCD), each
//! a conic of revolution about the lenslet's axis (radius, conic constant; a plane allowed), a
//! centre thickness and a dispersive material. Its placement follows the display's conventions:
//! `v1` (`eye_to_lenslets`) runs from the pupil plane to the **front vertex plane**, `v2`
//! (`lenslets_to_lcd`) from the **back vertex plane** to the LCD, so the LCD is at
//! `v1 + thickness + v2`. Radii are signed as in lens-design programs: positive when the centre of
//! curvature lies toward the LCD (+z), so a plano-convex lenslet with its curved side toward the
//! eye has `front.radius > 0` and a plane back.
//!
//! The array is one monolithic sheet: lenslet (i, j)'s surfaces cover its Voronoi cell of the
//! lenslet lattice (the points whose nearest centre is its centre), so neighbouring caps meet
//! along the cell boundaries, where their sags are equal. The exact trace:
//!
//! - intersects a surface by the closed form of [`Conic::intersect`] (Spencer & Murty 1962), in
//!   the frame of the lenslet whose cell the ray is expected in (first: the cell of its crossing
//!   of the vertex plane); if the hit lies in another cell, it intersects that cell's surface
//!   instead, up to [`MAX_CELL_STEPS`] times; a ray that does not settle is blocked;
//! - refracts by Snell's law in vector form ([`refract`]) with the material's index at the ray's
//!   wavelength ([`Dispersion`]; PMMA and N-BK7 built in, [`Material`]);
//! - blocks (carries black): total internal reflection at either surface, a ray that misses a
//!   surface (a conic with no point at that distance from the axis, e.g. a sphere narrower than
//!   the cell), a ray that leaves the back surface away from the LCD. A ray that crosses into a
//!   neighbour's cell inside the material leaves through the neighbour's back surface, as light in
//!   a monolithic array does (crosstalk). The array has no side walls.
//!
//! Camera rays of display rendering (LC, PC, LA) start from an LCD point toward a point `p` of the
//! back vertex plane and refract through the lenslet of the pixel's elemental image, which they
//! treat as extended beyond its cell (as eq. (1b) does): [`ThickLenslet::camera_ray`].
//!
//! Paraxial properties ([`ThickLenslet::paraxial`]): the system matrix of two refractions and a
//! transfer in reduced angles (W. J. Smith, "Modern Optical Engineering", 4th ed., Sec. 3.4;
//! E. Hecht, "Optics", 5th ed., Sec. 6.2): `phi = phi1 + phi2 - phi1 phi2 t / n` with
//! `phi1 = (n - 1) c1`, `phi2 = (1 - n) c2` (the lensmaker's formula of a thick lens), effective
//! focal length `1/phi`, back focal distance `(1 - phi1 t / n) / phi` from the back vertex.

use glam::{DMat2, DVec2, DVec3, IVec2};

use super::eye::conic::{Conic, Hit};
use super::eye::medium::Dispersion;
use super::eye::refract::refract;
use super::lattice::Lattice;
use crate::error::{Error, Result};
use crate::ray::Ray;

/// How many times a trace moves to the neighbouring cell before it blocks the ray.
pub const MAX_CELL_STEPS: usize = 4;

/// The d line (He, 587.56 nm): the wavelength `info` reports focal properties at.
pub const D_LINE_NM: f64 = 587.56;

/// The lenslets' optics.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum LensletOptics {
    /// The paper's ideal thin lens of power `1 / focal_length` (eq. (1b)).
    #[default]
    Paraxial,
    /// A real lenslet, traced exactly.
    Thick(Box<ThickLenslet>),
}

impl LensletOptics {
    /// The thick lenslet, if any.
    pub fn thick(&self) -> Option<&ThickLenslet> {
        match self {
            LensletOptics::Paraxial => None,
            LensletOptics::Thick(t) => Some(t),
        }
    }

    /// The centre thickness (0 for the thin lens): the front vertex to the back vertex, mm.
    pub fn thickness(&self) -> f64 {
        self.thick().map_or(0.0, |t| t.thickness)
    }
}

/// One refracting surface: a conic of revolution about the lenslet's axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Signed radius of curvature, mm (positive: centre toward the LCD); 0 or infinite: a plane.
    pub radius: f64,
    /// Conic constant (0 sphere, -1 paraboloid).
    pub conic: f64,
}

impl Surface {
    /// A plane.
    pub const PLANE: Surface = Surface { radius: 0.0, conic: 0.0 };

    /// Curvature 1/R (0 for a plane).
    pub fn curvature(&self) -> f64 {
        if self.radius == 0.0 || self.radius.is_infinite() {
            0.0
        } else {
            1.0 / self.radius
        }
    }

    fn conic_at(&self, vertex: f64) -> Conic {
        Conic::from_radius(vertex, self.radius, self.conic, f64::INFINITY)
    }
}

/// A lenslet material: its name and dispersion formula.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// "PMMA", "N-BK7" or "user".
    pub name: String,
    /// n(lambda).
    pub dispersion: Dispersion,
}

impl Material {
    /// PMMA: the one-term Sellmeier fit `n^2 - 1 = 1.1819 lambda^2 / (lambda^2 - 0.011313)`
    /// (lambda in um) of N. Sultanova, S. Kasarova & I. Nikolov, "Dispersion properties of optical
    /// polymers", Acta Physica Polonica A 116:585 (2009); n_d = 1.4906.
    pub fn pmma() -> Self {
        Self { name: "PMMA".into(), dispersion: Dispersion::Sellmeier { b: vec![1.1819], c: vec![0.011313] } }
    }

    /// Schott N-BK7: the three-term Sellmeier coefficients of the Schott optical glass data sheet
    /// (B1 1.03961212, B2 0.231792344, B3 1.01046945; C1 0.00600069867, C2 0.0200179144,
    /// C3 103.560653 um^2); n_d = 1.5168.
    pub fn n_bk7() -> Self {
        Self {
            name: "N-BK7".into(),
            dispersion: Dispersion::Sellmeier {
                b: vec![1.039_612_12, 0.231_792_344, 1.010_469_45],
                c: vec![0.006_000_698_67, 0.020_017_914_4, 103.560_653],
            },
        }
    }

    /// The index at `nm`.
    #[inline]
    pub fn index(&self, nm: f64) -> f64 {
        self.dispersion.index(nm)
    }
}

/// First-order (paraxial) properties of a thick lenslet at one wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paraxial {
    /// The material's index.
    pub index: f64,
    /// Effective focal length, mm.
    pub efl: f64,
    /// Back focal distance: back vertex to the LCD-side focal point, mm.
    pub bfd: f64,
    /// Front focal distance: front vertex to the eye-side focal point (negative: toward the eye), mm.
    pub ffd: f64,
}

/// A real lenslet (the module's documentation gives its frame and conventions).
#[derive(Clone, Debug, PartialEq)]
pub struct ThickLenslet {
    /// The surface facing the eye.
    pub front: Surface,
    /// The surface facing the LCD.
    pub back: Surface,
    /// Centre thickness, mm.
    pub thickness: f64,
    /// The material.
    pub material: Material,
    /// The central depth plane the display was designed for, mm from the pupil (`info` warns when
    /// the lenslet images the LCD elsewhere); `None`: eq. (1)'s, from `focal_length` and `v2`.
    pub design_cdp_mm: Option<f64>,
}

/// A ray leaving the lenslet array on the eye side: a point on the front surface and a unit
/// direction toward the eye (-z), world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeSide {
    /// Where it leaves the front surface.
    pub point: DVec3,
    /// Its unit direction (z < 0).
    pub dir: DVec3,
}

/// Every point of one exact eye -> LCD trace (world coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThickTrace {
    /// The lenslet whose front surface the ray entered.
    pub cell: IVec2,
    /// Where it meets the front surface.
    pub front: DVec3,
    /// Where it meets the back surface.
    pub back: DVec3,
    /// Its unit direction after the back surface.
    pub dir: DVec3,
    /// Where it meets the LCD plane.
    pub lcd: DVec2,
}

/// Where an eye -> LCD ray meets the front surface ([`ThickLenslet::front_hit`]): what the rest
/// of its trace needs at any wavelength ([`ThickLenslet::trace_from_front`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontHit {
    /// The lenslet whose front surface the ray entered.
    pub cell: IVec2,
    /// Its centre (world x, y).
    pub center: DVec2,
    /// The hit in that lenslet's frame (x, y from its centre, z from the front vertex plane).
    pub point: DVec3,
    /// The ray's unit direction before it.
    pub dir: DVec3,
    /// The front surface's unit normal there.
    pub normal: DVec3,
    /// The local z the trace inside the material starts from.
    pub(super) zs: f64,
}

/// How a surface is intersected: the closed form, or the slow twin's root finding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Intersection {
    /// [`Conic::intersect`].
    ClosedForm,
    /// [`Conic::intersect_by_root_finding`] (scan and bisection of the sag equation).
    RootFinding,
}

impl Intersection {
    #[inline(always)]
    fn hit(self, surface: &Conic, p: DVec3, d: DVec3) -> Option<Hit> {
        match self {
            Intersection::ClosedForm => surface.intersect(p, d),
            Intersection::RootFinding => {
                // The start lies within a few mm of the surface (the callers move it there).
                let reach = (p.z - surface.vertex).abs() / d.z.abs().max(1e-3) + 4.0;
                surface.intersect_by_root_finding(p, d, reach, 8_000)
            }
        }
    }
}

impl ThickLenslet {
    /// The paper's focal length as a plano-convex PMMA lenslet (curved side toward the eye) of
    /// `thickness` mm with that effective focal length at the d line.
    pub fn plano_convex(material: Material, efl: f64, thickness: f64) -> Self {
        let n = material.index(D_LINE_NM);
        Self {
            front: Surface { radius: (n - 1.0) * efl, conic: 0.0 },
            back: Surface::PLANE,
            thickness,
            material,
            design_cdp_mm: None,
        }
    }

    /// The paraxial properties at `nm`.
    pub fn paraxial(&self, nm: f64) -> Paraxial {
        let n = self.material.index(nm);
        let (p1, p2) = ((n - 1.0) * self.front.curvature(), (1.0 - n) * self.back.curvature());
        let t = self.thickness / n;
        let phi = p1 + p2 - p1 * p2 * t;
        Paraxial { index: n, efl: 1.0 / phi, bfd: (1.0 - p1 * t) / phi, ffd: -(1.0 - p2 * t) / phi }
    }

    /// The system matrix from the front vertex plane to the back vertex plane in reduced angles
    /// (`(y, n u)`), at `nm`.
    fn matrix(&self, nm: f64) -> DMat2 {
        let n = self.material.index(nm);
        let (p1, p2) = ((n - 1.0) * self.front.curvature(), (1.0 - n) * self.back.curvature());
        let r = |p: f64| DMat2::from_cols(DVec2::new(1.0, -p), DVec2::new(0.0, 1.0));
        let t = DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(self.thickness / n, 1.0));
        r(p2) * t * r(p1)
    }

    /// The paraxial image of the LCD (at `v2` behind the back vertex) on the eye side, mm from the
    /// front vertex toward the LCD (positive: a virtual image behind the lenslets, the display's
    /// central depth plane); `None` at infinity or when the image is real (on the eye's side).
    pub fn lcd_image_distance(&self, v2: f64, nm: f64) -> Option<f64> {
        // The ray from the LCD's axial point with height 1 at the back vertex, run backward.
        let m = self.matrix(nm).inverse();
        let front = m * DVec2::new(1.0, -1.0 / v2);
        // Its line (slope front.y, in air) meets the axis at z = -y / u from the front vertex.
        let z = -front.x / front.y;
        (z.is_finite() && z > 0.0).then_some(z)
    }

    /// The `v2` that puts the LCD's image at `distance` mm behind the front vertex, at `nm`.
    pub fn v2_for_image_distance(&self, distance: f64, nm: f64) -> f64 {
        // Forward: the ray from the axial image point through height 1 at the front vertex.
        let back = self.matrix(nm) * DVec2::new(1.0, -1.0 / distance);
        -back.x / back.y
    }

    /// Checks the lenslet for the lattice `lattice`: finite values, a positive thickness, both
    /// surfaces defined over the whole cell, a non-negative edge thickness across the cell, and an
    /// index above 1 over the visible range; `field` prefixes the fields named in errors.
    pub fn validate(&self, lattice: &Lattice, source: &str, field: &str) -> Result<()> {
        let bad = |f: &str, m: String| Err(Error::invalid(source, format!("{field}.{f}"), m));
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return bad("thickness", format!("must be positive and finite, got {}", self.thickness));
        }
        if self.thickness > 50.0 {
            return bad("thickness", format!("{} mm is beyond the supported 50 mm", self.thickness));
        }
        for (name, s) in [("front", &self.front), ("back", &self.back)] {
            if s.radius.is_nan() || !s.conic.is_finite() {
                return bad(name, format!("radius and conic must be numbers, got {} and {}", s.radius, s.conic));
            }
        }
        self.material.dispersion.validate(source, &format!("{field}.material"))?;
        for nm in [380.0, 780.0] {
            let n = self.material.index(nm);
            if !(n > 1.0 && n < 4.0) {
                return bad("material", format!("the index at {nm} nm is {n}: a lenslet needs 1 < n < 4"));
            }
        }
        // The rules the user eye shares (`optics::clearance`): both surfaces defined over the
        // cell, and not crossing inside it.
        let r = cell_radius(lattice);
        let (front, back) = (self.front.conic_at(0.0), self.back.conic_at(0.0));
        match crate::optics::clearance::narrowest_gap(&front, &back, self.thickness, r) {
            Err(at) => {
                let which = if front.sag(at * at).is_none() { "front" } else { "back" };
                return bad(
                    which,
                    format!(
                        "the conic has no point {at:.4} mm from the lenslet's axis, inside its cell (whose corners are \
                         {r:.4} mm from the centre): a larger radius or conic constant is needed"
                    ),
                );
            }
            Ok(g) if g.gap < 0.0 => {
                return bad(
                    "thickness",
                    format!(
                        "the surfaces cross {:.4} mm from the axis, inside the cell (edge thickness {:.4} mm): \
                         a thickness of at least {:.4} mm is needed",
                        g.r,
                        g.gap,
                        self.thickness - g.gap
                    ),
                );
            }
            Ok(_) => {}
        }
        if self.paraxial(D_LINE_NM).efl.is_nan() {
            return bad("front", "the lenslet's focal length is undefined".into());
        }
        Ok(())
    }

    /// The exact eye -> LCD trace of the ray through world point `origin` with slope `slope`
    /// (travelling toward +z), through the array of `lattice` whose front vertex plane is at
    /// `front_z`, to the LCD plane at `lcd_z`, at wavelength `nm`. `None`: blocked (see the
    /// module's documentation).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn trace_to_lcd(
        &self,
        lattice: &Lattice,
        front_z: f64,
        lcd_z: f64,
        origin: DVec3,
        slope: DVec2,
        nm: f64,
        how: Intersection,
    ) -> Option<ThickTrace> {
        self.trace_to_lcd_in(lattice, front_z, lcd_z, origin, slope, self.material.index(nm), how)
    }

    /// [`ThickLenslet::trace_to_lcd`] with the material's index `n` given: [`ThickLenslet::front_hit`]
    /// then [`ThickLenslet::trace_from_front`].
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn trace_to_lcd_in(
        &self,
        lattice: &Lattice,
        front_z: f64,
        lcd_z: f64,
        origin: DVec3,
        slope: DVec2,
        n: f64,
        how: Intersection,
    ) -> Option<ThickTrace> {
        let front = self.front_hit(lattice, front_z, origin, slope, how)?;
        self.trace_from_front(lattice, front_z, lcd_z, &front, n, how)
    }

    /// [`ThickLenslet::trace_to_lcd_in`] of one ray at each of the indices `ns` (the colour
    /// channels'): the front surface's hit, which no index changes, found once and refracted at
    /// each index (through a plane back, the three side by side:
    /// [`ThickLenslet::traces_from_front`]). The same traces bit for bit as three calls (the same
    /// arithmetic in the same order; tested).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn trace_to_lcd_each(
        &self,
        lattice: &Lattice,
        front_z: f64,
        lcd_z: f64,
        origin: DVec3,
        slope: DVec2,
        ns: [f64; 3],
        how: Intersection,
    ) -> [Option<ThickTrace>; 3] {
        match self.front_hit(lattice, front_z, origin, slope, how) {
            // A plane back (the same plane in every cell) in closed form: the three channels side
            // by side (`optics::lenslet_lanes`, the same traces bit for bit).
            Some(front) if how == Intersection::ClosedForm && self.back.curvature() == 0.0 => {
                self.traces_from_front(lattice, front_z, lcd_z, &front, &ns)
            }
            Some(front) => ns.map(|n| self.trace_from_front(lattice, front_z, lcd_z, &front, n, how)),
            None => [None; 3],
        }
    }

    /// The first half of the exact eye -> LCD trace, the same at every wavelength: where the ray
    /// through world point `origin` with slope `slope` meets the front surface of the array of
    /// `lattice` (front vertex plane at `front_z`), in which lenslet, and that surface's normal
    /// there. `None`: it misses the surface (blocked).
    #[inline]
    pub fn front_hit(
        &self,
        lattice: &Lattice,
        front_z: f64,
        origin: DVec3,
        slope: DVec2,
        how: Intersection,
    ) -> Option<FrontHit> {
        let d = slope.extend(1.0).normalize();
        // Start on the front vertex plane, moved back along the ray to clear the surface's sag.
        let at_plane = origin.truncate() + slope * (front_z - origin.z);
        let lead = self.front_lead();
        let start = (at_plane - slope * lead).extend(front_z - lead);
        let (cell, c, front) = settle(lattice, lattice.nearest(at_plane), self.front.curvature() == 0.0, |c| {
            how.hit(&self.front.conic_at(0.0), local(start, c, front_z), d)
        })?;
        let normal = self.front.conic_at(0.0).normal(front.point);
        // Inside the material the trace starts behind both the front hit and the back surface
        // there, so that a zero-thickness lens (whose surfaces touch) is traced as two
        // refractions at once.
        let back_conic = self.back.conic_at(self.thickness);
        let r2 = front.point.x * front.point.x + front.point.y * front.point.y;
        let back_z = self.thickness + back_conic.sag(r2).unwrap_or(-self.back.radius.abs());
        let zs = front.point.z.min(back_z) - 1e-3 * (1.0 + self.thickness);
        Some(FrontHit { cell, center: c, point: front.point, dir: d, normal, zs })
    }

    /// The rest of the exact eye -> LCD trace from its [`ThickLenslet::front_hit`]: refraction
    /// into the material of index `n`, the back surface (in whichever cell the ray reaches it),
    /// refraction out, on to the LCD plane at `lcd_z`. `None`: blocked.
    #[inline]
    pub fn trace_from_front(
        &self,
        lattice: &Lattice,
        front_z: f64,
        lcd_z: f64,
        f: &FrontHit,
        n: f64,
        how: Intersection,
    ) -> Option<ThickTrace> {
        let (cell, c, front) = (f.cell, f.center, f.point);
        let d1 = refract(f.dir, f.normal, 1.0, n)?;
        if d1.z <= 0.0 {
            return None;
        }
        let back_conic = self.back.conic_at(self.thickness);
        let inside = front + d1 * ((f.zs - front.z) / d1.z);
        let world_inside = DVec3::new(inside.x + c.x, inside.y + c.y, inside.z + front_z);
        let (_, c2, back) = settle(lattice, cell, self.back.curvature() == 0.0, |c2| {
            how.hit(&back_conic, local(world_inside, c2, front_z), d1)
        })?;
        let d2 = refract(d1, back_conic.normal(back.point), n, 1.0)?;
        if d2.z <= 0.0 {
            return None;
        }
        let back_world = DVec3::new(back.point.x + c2.x, back.point.y + c2.y, back.point.z + front_z);
        let lcd = back_world.truncate() + d2.truncate() * ((lcd_z - back_world.z) / d2.z);
        let front_world = DVec3::new(front.x + c.x, front.y + c.y, front.z + front_z);
        Some(ThickTrace { cell, front: front_world, back: back_world, dir: d2, lcd })
    }

    /// How far in front of the front vertex plane a trace starts: beyond the front surface's
    /// deepest point toward the eye over a cell (the sag of a concave front is negative).
    fn front_lead(&self) -> f64 {
        1.0 + self.front.radius.abs().min(10.0)
    }

    /// The reverse trace: light leaving LCD point `lcd` (world x, y, on the plane `lcd_z`)
    /// toward point `p` of the back vertex plane (`front_z + thickness`), through the lenslet
    /// centred at `center` treated as extended (no cell change), at `nm`. `None`: blocked.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn trace_from_lcd(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        p: DVec2,
        nm: f64,
        how: Intersection,
    ) -> Option<EyeSide> {
        self.trace_from_lcd_in(center, front_z, lcd_z, lcd, p, self.material.index(nm), how)
    }

    /// [`ThickLenslet::trace_from_lcd`] with the material's index `n` given.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn trace_from_lcd_in(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        p: DVec2,
        n: f64,
        how: Intersection,
    ) -> Option<EyeSide> {
        let back_plane = front_z + self.thickness;
        let d = (p - lcd).extend(back_plane - lcd_z).normalize();
        let back_conic = self.back.conic_at(self.thickness);
        // Start a little behind the back surface's farthest point toward the LCD.
        let lead = 1.0 + self.back.radius.abs().min(10.0);
        let s0 = (lcd_z - (back_plane + lead)).max(0.0) / -d.z;
        let start = local(lcd.extend(lcd_z) + d * s0, center, front_z);
        let back = how.hit(&back_conic, start, d)?;
        let d1 = refract(d, back_conic.normal(back.point), 1.0, n)?;
        if d1.z >= 0.0 {
            return None;
        }
        let front_conic = self.front.conic_at(0.0);
        let r2 = back.point.x * back.point.x + back.point.y * back.point.y;
        let front_z_local = front_conic.sag(r2).unwrap_or(self.front.radius.abs());
        let zs = back.point.z.max(front_z_local) + 1e-3 * (1.0 + self.thickness);
        let inside = back.point + d1 * ((zs - back.point.z) / d1.z);
        let front = how.hit(&front_conic, inside, d1)?;
        let d2 = refract(d1, front_conic.normal(front.point), n, 1.0)?;
        if d2.z >= 0.0 {
            return None;
        }
        Some(EyeSide {
            point: DVec3::new(front.point.x + center.x, front.point.y + center.y, front.point.z + front_z),
            dir: d2,
        })
    }

    /// The camera ray of [`ThickLenslet::trace_from_lcd`]: the eye-side line of that light,
    /// starting on the plane `z = reference_z` with unit z component, pointing toward +z.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn camera_ray(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        p: DVec2,
        reference_z: f64,
        nm: f64,
    ) -> Option<Ray> {
        self.camera_ray_in(center, front_z, lcd_z, lcd, p, reference_z, self.material.index(nm))
    }

    /// [`ThickLenslet::camera_ray`] with the material's index `n` given.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn camera_ray_in(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        p: DVec2,
        reference_z: f64,
        n: f64,
    ) -> Option<Ray> {
        let out = self.trace_from_lcd_in(center, front_z, lcd_z, lcd, p, n, Intersection::ClosedForm)?;
        let w = out.dir.truncate() / out.dir.z;
        let start = out.point.truncate() + w * (reference_z - out.point.z);
        Some(Ray { origin: start.extend(reference_z), dir: w.extend(1.0) })
    }

    /// PupilCenter's point for the real lenslet: the point `p` of the back vertex plane whose
    /// camera ray passes through the pupil centre `eye`, by Newton's method from `guess` (the thin
    /// lens's closed form) with a forward-difference Jacobian (step 1e-7 mm); `None` when it does
    /// not converge to 1e-9 mm in 20 steps or a ray on the way is blocked.
    #[allow(clippy::too_many_arguments)]
    pub fn pupil_center_point(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        eye: DVec3,
        guess: DVec2,
        nm: f64,
    ) -> Option<DVec2> {
        let n = self.material.index(nm);
        self.pupil_center_ray(center, front_z, lcd_z, lcd, eye, guess, n).map(|(p, _)| p)
    }

    /// [`ThickLenslet::pupil_center_point`] with the material's index `n` given, returning with
    /// the point its camera ray from the plane `z = eye.z` (the solve's last trace, the same ray
    /// bit for bit as [`ThickLenslet::camera_ray_in`] at that point).
    #[allow(clippy::too_many_arguments)]
    pub fn pupil_center_ray(
        &self,
        center: DVec2,
        front_z: f64,
        lcd_z: f64,
        lcd: DVec2,
        eye: DVec3,
        guess: DVec2,
        n: f64,
    ) -> Option<(DVec2, Ray)> {
        let miss = |p: DVec2| -> Option<(Ray, DVec2)> {
            let r = self.camera_ray_in(center, front_z, lcd_z, lcd, p, eye.z, n)?;
            Some((r, r.origin.truncate() - eye.truncate()))
        };
        let mut p = if guess.is_finite() { guess } else { center };
        let h = 1e-7;
        for _ in 0..20 {
            let (ray, f) = miss(p)?;
            if f.length() < 1e-9 {
                return Some((p, ray));
            }
            let dx = (miss(p + DVec2::new(h, 0.0))?.1 - f) / h;
            let dy = (miss(p + DVec2::new(0.0, h))?.1 - f) / h;
            let j = DMat2::from_cols(dx, dy);
            if j.determinant().abs() < 1e-300 {
                return None;
            }
            p -= j.inverse() * f;
        }
        miss(p).filter(|(_, f)| f.length() < 1e-9).map(|(ray, _)| (p, ray))
    }
}

/// `point` (world) in the frame of the lenslet centred at `c` with its front vertex at `front_z`.
#[inline(always)]
fn local(point: DVec3, c: DVec2, front_z: f64) -> DVec3 {
    DVec3::new(point.x - c.x, point.y - c.y, point.z - front_z)
}

/// Intersects in cell `cell`'s frame; moves to the cell the hit lies in until they agree. A
/// plane is the same plane in every cell: its hit needs no owner.
#[inline(always)]
fn settle(
    lattice: &Lattice,
    mut cell: IVec2,
    plane: bool,
    hit: impl Fn(DVec2) -> Option<Hit>,
) -> Option<(IVec2, DVec2, Hit)> {
    if plane {
        let c = lattice.center(cell);
        return hit(c).map(|h| (cell, c, h));
    }
    for _ in 0..MAX_CELL_STEPS {
        let c = lattice.center(cell);
        let h = hit(c)?;
        let owner = lattice.nearest(h.point.truncate() + c);
        if owner == cell {
            return Some((cell, c, h));
        }
        cell = owner;
    }
    None
}

/// The largest distance from a lenslet's centre to a point of its (Voronoi) cell, mm: the
/// boundary's distance in 3,600 directions, against the 24 nearest lattice vectors.
pub fn cell_radius(lattice: &Lattice) -> f64 {
    let m = lattice.reduced_matrix();
    let mut neighbours = Vec::new();
    for i in -2..=2 {
        for j in -2..=2 {
            if (i, j) != (0, 0) {
                neighbours.push(m * DVec2::new(f64::from(i), f64::from(j)));
            }
        }
    }
    (0..3600)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 3600.0;
            let u = DVec2::new(a.cos(), a.sin());
            neighbours
                .iter()
                .filter(|v| v.dot(u) > 0.0)
                .map(|v| 0.5 * v.length_squared() / v.dot(u))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}
