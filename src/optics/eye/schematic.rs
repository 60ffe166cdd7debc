//! `SchematicEye`: a schematic eye model built for one accommodation, in the eye's frame.
//!
//! The frame: origin at the centre of the entrance pupil at the reference wavelength (the
//! paraxial image of the iris centre through the cornea, Smith, "Modern Optical Engineering",
//! Ch. 6), +z toward the object (the display), x and y as in the scene. Internally the surfaces
//! live in the lens-design frame (t from the cornea's front vertex toward the retina, as in the
//! model papers: Navarro et al., JOSA A 2:1273, 1985, Table 1); `z = origin_t - t`.
//!
//! The retina map ([`SchematicEye::retina_point`]) is a radial table (rotational symmetry) of
//! the chief ray's landing radius against the object tangent, interpolated by cubic Hermite
//! splines (de Boor, "A Practical Guide to Splines", 1978, Ch. IV), whose node values and
//! slopes come from the exact solve [`SchematicEye::retina_point_exact`].

use glam::{DVec2, DVec3};

use super::conic::Conic;
use super::medium::Dispersion;
use super::model::{EyeDefinition, EyeModel};
use super::paraxial::{Paraxial, ParaxialInput};
use crate::error::{Error, Result};

/// At most this many refracting surfaces (user eyes are validated against it).
pub(crate) const MAX_SURFACES: usize = 64;
/// The retina table covers object tangents up to this (it ends earlier if chief rays fail).
const TABLE_MAX_TANGENT: f64 = 1.0;
/// Nodes of the retina table.
const TABLE_NODES: usize = 512;

/// A schematic eye at one accommodation (see the module documentation for its frame).
#[derive(Clone, Debug)]
pub struct SchematicEye {
    pub(crate) name: &'static str,
    pub(crate) accommodation: f64,
    pub(crate) reference_wavelength: f64,
    /// Refracting surfaces in the lens-design frame, cornea front first.
    pub(crate) surfaces: Vec<Conic>,
    /// `media[i]` follows surface i (air precedes surface 0).
    pub(crate) media: Vec<Dispersion>,
    /// The iris plane lies between surfaces `iris_after` and `iris_after + 1`, at t = `iris_t`.
    pub(crate) iris_after: usize,
    pub(crate) iris_t: f64,
    pub(crate) retina: Conic,
    /// t of the frame's origin.
    pub(crate) origin_t: f64,
    /// Radius of the iris opening, when one is set ([`SchematicEye::with_pupil`]).
    pub(crate) iris_radius: Option<f64>,
    pub(crate) table: RetinaTable,
}

/// The chief ray's landing radius against the object tangent (odd in the tangent).
#[derive(Clone, Debug, Default)]
pub(crate) struct RetinaTable {
    step: f64,
    rho: Vec<f64>,
    slope: Vec<f64>,
}

impl RetinaTable {
    fn max_tangent(&self) -> f64 {
        self.step * (self.rho.len().saturating_sub(1)) as f64
    }

    #[inline]
    fn eval(&self, tau: f64) -> Option<f64> {
        if self.rho.len() < 2 || tau > self.max_tangent() {
            return None;
        }
        let x = tau / self.step;
        let i = (x as usize).min(self.rho.len() - 2);
        let t = x - i as f64;
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
            t * (1.0 - t) * (1.0 - t),
            t * t * (3.0 - 2.0 * t),
            t * t * (t - 1.0),
        );
        Some(
            h00 * self.rho[i]
                + h10 * self.step * self.slope[i]
                + h01 * self.rho[i + 1]
                + h11 * self.step * self.slope[i + 1],
        )
    }
}

impl SchematicEye {
    /// The model at accommodation `a` (the model's own parameter, D), checked against its
    /// range; `source` names where it came from in errors (field `accommodation`).
    pub fn new(model: &EyeModel, accommodation: f64, source: &str) -> Result<Self> {
        let (lo, hi) = model.accommodation_range();
        if !(accommodation.is_finite() && accommodation >= lo && accommodation <= hi) {
            return Err(Error::invalid(
                source,
                "accommodation",
                format!(
                    "must be within {lo}..{hi} D for the {} eye ({}), got {accommodation}",
                    model.name(),
                    model.citation()
                ),
            ));
        }
        let mut eye = Self::geometry(model, accommodation, source)?;
        eye.build_table();
        Ok(eye)
    }

    /// The surfaces and frame without the retina table (for the focus solvers).
    pub(crate) fn geometry(model: &EyeModel, accommodation: f64, source: &str) -> Result<Self> {
        let Some(def) = model.definition(accommodation) else {
            return Err(Error::invalid(
                source,
                "eye.model",
                "the thin-lens eye is not a schematic eye (it is optics::Eye)",
            ));
        };
        Self::from_definition(model.name(), accommodation, def, source)
    }

    fn from_definition(name: &'static str, accommodation: f64, def: EyeDefinition, source: &str) -> Result<Self> {
        if def.surfaces.is_empty() || def.surfaces.len() > MAX_SURFACES || def.iris_after >= def.surfaces.len() {
            return Err(Error::invalid(source, "eye.surfaces", "needs 1 to 64 surfaces and an iris among them"));
        }
        let mut t = 0.0;
        let mut surfaces = Vec::with_capacity(def.surfaces.len());
        for s in &def.surfaces {
            surfaces.push(Conic::from_radius(t, s.radius, s.conic, s.semi_diameter));
            t += s.thickness;
        }
        let retina_sd =
            if def.retina_radius == 0.0 || def.retina_radius.is_infinite() { 1e3 } else { def.retina_radius.abs() };
        let retina = Conic::from_radius(t, def.retina_radius, 0.0, retina_sd);
        let iris_t = surfaces[def.iris_after].vertex + def.iris_distance;
        let mut eye = SchematicEye {
            name,
            accommodation,
            reference_wavelength: def.reference_wavelength,
            surfaces,
            media: def.surfaces.into_iter().map(|s| s.medium).collect(),
            iris_after: def.iris_after,
            iris_t,
            retina,
            origin_t: 0.0,
            iris_radius: None,
            table: RetinaTable::default(),
        };
        let n = eye.indices(eye.reference_wavelength);
        // A medium without a real index at the reference wavelength is named here, before the
        // frame's paraxial solve (which would fail at the iris).
        if let Some(i) = n[1..].iter().position(|v| !(v.is_finite() && *v >= 1.0)) {
            return Err(Error::invalid(
                source,
                format!("eye.surfaces[{i}].medium"),
                format!(
                    "its index at the reference wavelength {} nm is {}: a medium needs a finite index >= 1",
                    eye.reference_wavelength,
                    n[i + 1]
                ),
            ));
        }
        let (ep_t, iris_over_ep) = eye.paraxial_input(&n, &mut Vec::new(), &mut Vec::new(), |p| p.entrance_pupil());
        if !(ep_t.is_finite() && iris_over_ep.is_finite() && iris_over_ep.abs() > 1e-9) {
            return Err(Error::invalid(
                source,
                "eye.iris",
                "the iris has no finite entrance pupil (its image through the cornea)",
            ));
        }
        eye.origin_t = ep_t;
        Ok(eye)
    }

    /// The indices `n[0] = 1 (air), n[i+1]` after surface i.
    pub(crate) fn indices(&self, wavelength_nm: f64) -> Vec<f64> {
        std::iter::once(1.0).chain(self.media.iter().map(|m| m.index(wavelength_nm))).collect()
    }

    fn paraxial_input<R>(
        &self,
        n: &[f64],
        vertices: &mut Vec<f64>,
        curvatures: &mut Vec<f64>,
        f: impl FnOnce(&ParaxialInput) -> R,
    ) -> R {
        vertices.extend(self.surfaces.iter().map(|s| s.vertex));
        curvatures.extend(self.surfaces.iter().map(|s| s.curvature));
        f(&ParaxialInput {
            vertices,
            curvatures,
            n,
            iris_after: self.iris_after,
            iris_t: self.iris_t,
            retina_t: self.retina.vertex,
        })
    }

    /// The matrix from the iris plane to the last surface's vertex (for ray aiming).
    pub(crate) fn iris_to_last(&self, n: &[f64]) -> super::paraxial::Abcd {
        let last = self.surfaces.len();
        self.paraxial_input(n, &mut Vec::new(), &mut Vec::new(), |p| {
            p.chain(self.iris_t, self.iris_after + 1, last, self.surfaces[last - 1].vertex)
        })
    }

    /// The model's canonical name.
    pub fn model_name(&self) -> &'static str {
        self.name
    }

    /// The accommodation parameter it was built at, D.
    pub fn accommodation(&self) -> f64 {
        self.accommodation
    }

    /// The wavelength its origin and retina map are built at, nm (555 by default).
    pub fn reference_wavelength(&self) -> f64 {
        self.reference_wavelength
    }

    /// Paraxial data at a wavelength (total power, focal and cardinal points, entrance pupil,
    /// iris, cornea and retina positions in this frame, the vergence conjugate to the retina).
    pub fn paraxial(&self, wavelength_nm: f64) -> Paraxial {
        let n = self.indices(wavelength_nm);
        self.paraxial_input(&n, &mut Vec::new(), &mut Vec::new(), |p| p.paraxial(wavelength_nm, self.origin_t))
    }

    /// The iris diameter that gives an entrance pupil of `pupil_diameter` mm (paraxial
    /// magnification at the reference wavelength).
    pub fn iris_diameter(&self, pupil_diameter: f64) -> f64 {
        pupil_diameter / self.paraxial(self.reference_wavelength).iris_to_entrance_pupil_magnification
    }

    /// The same eye with an iris opening that gives an entrance pupil of `pupil_diameter` mm:
    /// rays through the iris plane farther from the axis than half of
    /// [`SchematicEye::iris_diameter`] are then blocked (by `ray_in` and `ray_out`).
    pub fn with_pupil(mut self, pupil_diameter: f64) -> Self {
        self.iris_radius = Some(0.5 * self.iris_diameter(pupil_diameter));
        self
    }

    /// The iris opening's radius, mm, if one is set.
    pub fn iris_radius(&self) -> Option<f64> {
        self.iris_radius
    }

    /// A lens-design-frame point from a frame point (and back: the map is its own inverse).
    #[inline]
    pub(crate) fn flip(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.x, p.y, self.origin_t - p.z)
    }

    /// The retina point (3-D, this frame, on the spherical retina) where the chief ray (through
    /// the iris centre) of object-space direction with tangents `tangent` = (dx/dz, dy/dz) lands
    /// at the reference wavelength: the analogue of the thin-lens eye's `-v0 * tangent`. From
    /// the radial table within its range (tangents up to 1.0 for the built-in models), beyond it
    /// the exact solve, and where that fails the table's last slope carried on.
    pub fn retina_point(&self, tangent: DVec2) -> DVec3 {
        let tau = tangent.length();
        if tau == 0.0 {
            return self.flip(DVec3::new(0.0, 0.0, self.retina.vertex));
        }
        let rho = match self.table.eval(tau) {
            Some(r) => r,
            None => match self.retina_point_exact(tangent) {
                Some(p) => return p,
                None => {
                    let m = self.table.max_tangent();
                    let last = self.table.rho.last().copied().unwrap_or(0.0);
                    let slope = self.table.slope.last().copied().unwrap_or(0.0);
                    last + slope * (tau - m)
                }
            },
        };
        self.retina_at(tangent / tau * rho)
    }

    /// The retina point at transverse position `xy` (this frame).
    #[inline]
    pub(crate) fn retina_at(&self, xy: DVec2) -> DVec3 {
        let r2 = xy.length_squared().min(self.retina.semi_diameter * self.retina.semi_diameter);
        let sag = self.retina.sag(r2).unwrap_or(-self.retina.curvature.recip().abs());
        DVec3::new(xy.x, xy.y, self.origin_t - (self.retina.vertex + sag))
    }

    /// Refuses a field the retina cannot hold: the chief ray of the field's corner (object
    /// tangent `max_tangent`, at the reference wavelength) must land on the retina. A user eye
    /// whose chief rays run off its retina's rim before then names `eye.retina_radius`; otherwise
    /// the field, `eye.retina_half_tangent`.
    pub fn check_field(&self, max_tangent: f64, source: &str) -> Result<()> {
        if !(max_tangent > 0.0 && max_tangent.is_finite())
            || self.retina_point_exact(DVec2::new(max_tangent, 0.0)).is_some()
        {
            return Ok(());
        }
        // The largest tangent that lands, by bisection (the axis lands: checked by the caller).
        let (mut lo, mut hi) = (0.0, max_tangent);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if self.retina_point_exact(DVec2::new(mid, 0.0)).is_some() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let rim = self.retina.curvature.abs().recip();
        let landed = self.retina_point_exact(DVec2::new(lo, 0.0)).map_or(0.0, |p| p.truncate().length());
        let (field, why) = if self.name == "user" && rim.is_finite() && landed >= 0.9 * rim {
            ("eye.retina_radius", format!("the retina's radius of {rim} mm is too small to hold"))
        } else {
            ("eye.retina_half_tangent", format!("the {} eye's retina cannot hold", self.name))
        };
        Err(Error::invalid(
            source,
            field,
            format!(
                "{why} the field: the chief ray of the field's corner (tangent {max_tangent:.4}) misses it; chief \
                 rays land only up to tangent {lo:.4} ({landed:.3} mm from the axis)"
            ),
        ))
    }

    /// The exact chief-ray solve behind [`SchematicEye::retina_point`]; None where the chief ray
    /// is blocked or the aim does not converge.
    pub fn retina_point_exact(&self, tangent: DVec2) -> Option<DVec3> {
        self.at(self.reference_wavelength).chief_ray(tangent).map(|(p, _)| p)
    }

    fn build_table(&mut self) {
        let step = TABLE_MAX_TANGENT / (TABLE_NODES - 1) as f64;
        let at = self.at(self.reference_wavelength);
        let radial = |tau: f64| at.chief_ray(DVec2::new(tau, 0.0)).map(|(p, _)| p.x);
        let delta = 1e-5;
        let (mut rho, mut slope) = (Vec::with_capacity(TABLE_NODES), Vec::with_capacity(TABLE_NODES));
        for i in 0..TABLE_NODES {
            let tau = i as f64 * step;
            let (Some(r), Some(rp), Some(rm)) = (radial(tau), radial(tau + delta), radial(tau - delta)) else {
                break;
            };
            rho.push(r);
            slope.push((rp - rm) / (2.0 * delta));
        }
        self.table = RetinaTable { step, rho, slope };
    }
}
