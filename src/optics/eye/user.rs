//! A user-defined schematic eye: a table of rotationally symmetric conic surfaces (sag formula of
//! Welford, "Aberrations of Optical Systems", 1986, Sec. 2.4, see [`super::conic`]), media
//! given by a dispersion formula of [`super::medium`], an iris plane and a spherical retina.
//!
//! ```toml
//! [eye.user]
//! retina_radius = -12.0
//! iris = { after = "cornea-back", distance = 3.05 }   # or { before = "lens-front", distance = 0.0 }
//! [[eye.user.surfaces]]
//! name = "cornea-front"
//! radius = 7.72
//! conic = -0.26
//! thickness = 0.55
//! semi_diameter = 5.5
//! medium = { constant = 1.376 }
//! ```
//!
//! An optional `[eye.user.accommodation]` ([`super::user_accommodation`]) lets surface
//! parameters change with the accommodation; without it the eye has one fixed focus.
//!
//! The table is checked by the rules it shares with the thick lenslet
//! ([`crate::optics::clearance`]): consecutive surfaces, and the last one and the retina, may not
//! cross inside their common semi-diameter; the iris plane lies between the surface it follows
//! and the next one there; names are unique; the reference wavelength is visible (380-780 nm, the
//! range of `eye.wavelength_nm`).

use serde::{Deserialize, Serialize};

use super::conic::Conic;
use super::medium::Dispersion;
use super::model::{EyeDefinition, SurfaceDef, REFERENCE_WAVELENGTH};
use super::user_accommodation::{surface_index, LawParameter, UserAccommodation};
use crate::error::{Error, Result};

/// One surface of a user eye, in order from the cornea toward the retina.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserSurface {
    /// A name the iris can refer to (optional).
    #[serde(default)]
    pub name: Option<String>,
    /// Signed vertex radius of curvature, mm: positive when the centre of curvature lies toward
    /// the retina; 0 or infinite for a plane.
    pub radius: f64,
    /// Conic constant (0 sphere, -1 paraboloid, < -1 hyperboloid).
    #[serde(default)]
    pub conic: f64,
    /// Axial distance from this surface's vertex to the next one's (the last: to the retina
    /// vertex), mm.
    pub thickness: f64,
    /// The medium after this surface.
    pub medium: Dispersion,
    /// Semi-diameter, mm: rays farther from the axis are blocked.
    pub semi_diameter: f64,
}

/// Where the iris stop sits: `distance` mm behind the vertex of surface `after`, or `distance`
/// mm in front of the vertex of surface `before` (by name, or by index as a string such as "1"),
/// exactly one of the two. With `before`, the iris keeps its place relative to that surface when
/// an accommodation law changes the thickness in front of it (the schematic eyes' iris in the
/// lens front's vertex plane: `before = "lens-front", distance = 0`). Its diameter is set by the
/// run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserIris {
    /// The surface the iris follows: its `name`, or its index.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after: Option<String>,
    /// The surface the iris precedes: its `name`, or its index (not the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub before: Option<String>,
    /// Distance from that surface's vertex, mm (>= 0, at most the thickness between the two
    /// surfaces the iris lies between).
    pub distance: f64,
}

/// A user-defined eye.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserEye {
    /// The surfaces, cornea front first (the medium before the first one is air, n = 1).
    pub surfaces: Vec<UserSurface>,
    /// The iris stop.
    pub iris: UserIris,
    /// Radius of the spherical retina, mm (negative: concave toward the lens, as a real eye;
    /// 0 for a flat retina).
    pub retina_radius: f64,
    /// The wavelength at which the eye's frame and retina map are built, nm (555 by default).
    #[serde(default)]
    pub reference_wavelength: Option<f64>,
    /// The accommodation law (`None`: one fixed focus).
    #[serde(default)]
    pub accommodation: Option<UserAccommodation>,
}

impl UserEye {
    /// Index of the surface named `name` (its name, or its index as a string).
    fn surface_named(&self, name: &str) -> Option<usize> {
        self.surfaces
            .iter()
            .position(|s| s.name.as_deref() == Some(name))
            .or_else(|| name.parse::<usize>().ok().filter(|&i| i < self.surfaces.len()))
    }

    /// Index of the surface the iris follows.
    fn iris_surface(&self) -> Option<usize> {
        match (&self.iris.after, &self.iris.before) {
            (Some(a), None) => self.surface_named(a),
            (None, Some(b)) => self.surface_named(b).filter(|&j| j > 0).map(|j| j - 1),
            _ => None,
        }
    }

    /// The iris plane's distance behind the vertex of the surface it follows, mm.
    fn iris_distance(&self) -> f64 {
        match (&self.iris.before, self.iris_surface()) {
            (Some(_), Some(k)) => self.surfaces[k].thickness - self.iris.distance,
            _ => self.iris.distance,
        }
    }

    /// The accommodation range, D: the law's, or `(0, 0)` for a fixed eye.
    pub fn accommodation_range(&self) -> (f64, f64) {
        self.accommodation.as_ref().map_or((0.0, 0.0), |l| (l.range[0], l.range[1]))
    }

    /// The eye with its accommodation law applied at `a` (the law itself then dropped).
    pub fn at(&self, a: f64) -> UserEye {
        let mut eye = self.clone();
        let Some(law) = eye.accommodation.take() else { return eye };
        let names: Vec<Option<String>> = self.surfaces.iter().map(|s| s.name.clone()).collect();
        for l in &law.laws {
            let Some(k) = surface_index(&names, &l.surface) else { continue };
            let (v, s) = (l.value(a), &mut eye.surfaces[k]);
            match l.parameter {
                LawParameter::Radius => s.radius = v,
                LawParameter::Conic => s.conic = v,
                LawParameter::Thickness => s.thickness = v,
                LawParameter::Index => match &mut s.medium {
                    Dispersion::Constant(n) => *n = v,
                    Dispersion::Abbe { nd, .. } => *nd = v,
                    _ => {}
                },
            }
        }
        eye
    }

    /// Checks the table, and with an accommodation law the law and the table it makes at every
    /// accommodation in steps of at most 0.25 D (errors then say at which `A`); errors name the
    /// field (`eye.surfaces[2].radius`).
    pub fn validate(&self, source: &str) -> Result<()> {
        self.validate_table(source)?;
        let Some(law) = &self.accommodation else { return Ok(()) };
        let names: Vec<Option<String>> = self.surfaces.iter().map(|s| s.name.clone()).collect();
        let media: Vec<Dispersion> = self.surfaces.iter().map(|s| s.medium.clone()).collect();
        law.validate(&names, &media, source)?;
        for a in law.checkpoints() {
            self.at(a).validate_table(source).map_err(|e| match e {
                Error::Invalid { source_name, field, message } => {
                    Error::Invalid { source_name, field: format!("{field} (eye.accommodation at A = {a} D)"), message }
                }
                other => other,
            })?;
        }
        Ok(())
    }

    /// The checks of one surface table (no accommodation law).
    fn validate_table(&self, source: &str) -> Result<()> {
        let err = |f: String, m: String| Err(Error::invalid(source, f, m));
        if self.surfaces.is_empty() || self.surfaces.len() > 64 {
            return err("eye.surfaces".into(), format!("needs 1 to 64 surfaces, got {}", self.surfaces.len()));
        }
        for (i, s) in self.surfaces.iter().enumerate() {
            let f = |name: &str| format!("eye.surfaces[{i}].{name}");
            if s.radius.is_nan() || (s.radius.is_finite() && s.radius != 0.0 && s.radius.abs() < 0.1) {
                return err(
                    f("radius"),
                    format!("must be 0 (plane), infinite or at least 0.1 mm in size, got {}", s.radius),
                );
            }
            if !(s.conic.is_finite() && s.conic.abs() <= 1e3) {
                return err(f("conic"), format!("must be finite (|Q| <= 1000), got {}", s.conic));
            }
            if !(s.thickness.is_finite() && s.thickness > 0.0 && s.thickness <= 100.0) {
                return err(f("thickness"), format!("must be positive and at most 100 mm, got {}", s.thickness));
            }
            if !(s.semi_diameter.is_finite() && s.semi_diameter > 0.0 && s.semi_diameter <= 50.0) {
                return err(f("semi_diameter"), format!("must be positive and at most 50 mm, got {}", s.semi_diameter));
            }
            if s.radius.is_finite() && s.radius != 0.0 {
                let c = 1.0 / s.radius;
                if (1.0 + s.conic) * c * c * s.semi_diameter * s.semi_diameter > 1.0 {
                    return err(
                        f("semi_diameter"),
                        format!(
                            "{} mm is beyond the edge of the conic (R = {}, Q = {})",
                            s.semi_diameter, s.radius, s.conic
                        ),
                    );
                }
            }
            s.medium.validate(source, &f("medium"))?;
        }
        for (i, s) in self.surfaces.iter().enumerate() {
            let Some(name) = &s.name else { continue };
            if let Some(j) = self.surfaces[..i].iter().position(|t| t.name.as_ref() == Some(name)) {
                return err(
                    format!("eye.surfaces[{i}].name"),
                    format!("`{name}` is also the name of eye.surfaces[{j}]; surface names must be unique"),
                );
            }
        }
        let Some(k) = self.iris_surface() else {
            return match (&self.iris.after, &self.iris.before) {
                (Some(a), None) => err("eye.iris.after".into(), format!("names no surface: `{a}`")),
                (None, Some(b)) => err(
                    "eye.iris.before".into(),
                    format!("names no surface after the first: `{b}` (the iris lies between two surfaces)"),
                ),
                _ => err("eye.iris".into(), "give exactly one of `after` and `before`".into()),
            };
        };
        let d = self.iris.distance;
        if !(d.is_finite() && d >= 0.0 && d <= self.surfaces[k].thickness) {
            return err(
                "eye.iris.distance".into(),
                format!("must be between 0 and the surface's thickness {} mm, got {d}", self.surfaces[k].thickness),
            );
        }
        let r = self.retina_radius;
        if r.is_nan() || (r.is_finite() && r != 0.0 && r.abs() < 1.0) {
            return err("eye.retina_radius".into(), format!("must be 0 (flat) or at least 1 mm in size, got {r}"));
        }
        if let Some(w) = self.reference_wavelength {
            let (lo, hi) = crate::optics::spectrum::VISIBLE_NM;
            if !(w.is_finite() && (lo..=hi).contains(&w)) {
                return err(
                    "eye.reference_wavelength".into(),
                    format!("must be a visible wavelength in nm ({lo} to {hi}, as eye.wavelength_nm), got {w}"),
                );
            }
        }
        self.validate_clearances(source)
    }

    /// The surface `i` as a conic about its own vertex.
    fn conic(&self, i: usize) -> Conic {
        let s = &self.surfaces[i];
        Conic::from_radius(0.0, s.radius, s.conic, s.semi_diameter)
    }

    /// `eye.surfaces[i]` with its name, for messages.
    fn label(&self, i: usize) -> String {
        match &self.surfaces[i].name {
            Some(n) => format!("eye.surfaces[{i}] (`{n}`)"),
            None => format!("eye.surfaces[{i}]"),
        }
    }

    /// The shared geometric rules ([`crate::optics::clearance`]): no two consecutive surfaces
    /// (nor the last one and the retina) cross inside their common semi-diameter, and the iris
    /// plane lies between its neighbours there. The surfaces themselves are checked first.
    fn validate_clearances(&self, source: &str) -> Result<()> {
        use crate::optics::clearance::{narrowest_gap, plane_between};
        let n = self.surfaces.len();
        let cross = |i: usize, next: String, r: f64, gap: f64| {
            let t = self.surfaces[i].thickness;
            Err(Error::invalid(
                source,
                format!("eye.surfaces[{i}].thickness"),
                format!(
                    "{} and {next} cross {r:.4} mm from the axis, inside their semi-diameters (the gap there is \
                     {gap:.4} mm): a thickness of at least {:.4} mm is needed",
                    self.label(i),
                    t - gap
                ),
            ))
        };
        for i in 0..n.saturating_sub(1) {
            let reach = self.surfaces[i].semi_diameter.min(self.surfaces[i + 1].semi_diameter);
            if let Ok(g) = narrowest_gap(&self.conic(i), &self.conic(i + 1), self.surfaces[i].thickness, reach) {
                if g.gap < 0.0 {
                    return cross(i, self.label(i + 1), g.r, g.gap);
                }
            }
        }
        let retina = Conic::from_radius(0.0, self.retina_radius, 0.0, f64::INFINITY);
        let last = n - 1;
        let reach = match self.retina_radius {
            r if r == 0.0 || r.is_infinite() => self.surfaces[last].semi_diameter,
            r => self.surfaces[last].semi_diameter.min(r.abs()),
        };
        if let Ok(g) = narrowest_gap(&self.conic(last), &retina, self.surfaces[last].thickness, reach) {
            if g.gap < 0.0 {
                return cross(last, "the retina".into(), g.r, g.gap);
            }
        }
        let k = self.iris_surface().unwrap_or(0);
        let next = (k + 1 < n).then(|| self.conic(k + 1));
        let reach = match &next {
            Some(_) => self.surfaces[k].semi_diameter.min(self.surfaces[k + 1].semi_diameter),
            None => self.surfaces[k].semi_diameter,
        };
        let thickness = self.surfaces[k].thickness;
        if let Some((behind, g)) = plane_between(&self.conic(k), next.as_ref(), thickness, self.iris_distance(), reach)
        {
            let which = if behind { self.label(k + 1) } else { self.label(k) };
            return Err(Error::invalid(
                source,
                "eye.iris.distance",
                format!(
                    "the iris plane, {} mm behind the vertex of {}, crosses {which} {:.4} mm from the axis, \
                     inside the surfaces' semi-diameters: the iris would lie inside a surface",
                    self.iris_distance(),
                    self.label(k),
                    g.r
                ),
            ));
        }
        Ok(())
    }

    /// The surface table at accommodation `a` (the eye must have been validated; a fixed eye
    /// ignores `a`).
    pub(crate) fn definition(&self, a: f64) -> EyeDefinition {
        if self.accommodation.is_some() {
            return self.at(a).definition(a);
        }
        EyeDefinition {
            surfaces: self
                .surfaces
                .iter()
                .map(|s| SurfaceDef {
                    radius: s.radius,
                    conic: s.conic,
                    thickness: s.thickness,
                    medium: s.medium.clone(),
                    semi_diameter: s.semi_diameter,
                })
                .collect(),
            iris_after: self.iris_surface().unwrap_or(0),
            iris_distance: self.iris_distance(),
            retina_radius: self.retina_radius,
            reference_wavelength: self.reference_wavelength.unwrap_or(REFERENCE_WAVELENGTH),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The user-eye fixture every medium form appears in (tests/data/eyes/navarro-like.toml).
    const NAVARRO_LIKE: &str = include_str!("../../../tests/data/eyes/navarro-like.toml");

    #[test]
    fn a_user_eye_reads_from_toml_and_validates() {
        let u: UserEye = toml::from_str(NAVARRO_LIKE).unwrap();
        u.validate("e.toml").unwrap();
        assert_eq!(u.definition(0.0).iris_after, 1);
        // The same plane stated from the surface the iris precedes.
        let mut before = u.clone();
        let gap = u.surfaces[1].thickness - u.iris.distance;
        before.iris = UserIris { after: None, before: Some("2".into()), distance: gap };
        before.validate("e.toml").unwrap();
        let (a, b) = (u.definition(0.0), before.definition(0.0));
        assert_eq!((a.iris_after, b.iris_after), (1, 1));
        assert!((a.iris_distance - b.iris_distance).abs() < 1e-12);
        assert_eq!(u.surfaces[1].medium, Dispersion::Cauchy { a: 1.3247, b: 0.0044, c: 0.0 });
    }

    #[test]
    fn bad_user_eyes_name_the_field() {
        let mut u: UserEye = toml::from_str(NAVARRO_LIKE).unwrap();
        u.surfaces[2].radius = f64::NAN;
        let e = u.validate("e.toml").unwrap_err().to_string();
        assert!(e.contains("eye.surfaces[2].radius"), "{e}");
        let mut u: UserEye = toml::from_str(NAVARRO_LIKE).unwrap();
        u.iris.after = Some("lens".into());
        assert!(u.validate("e").unwrap_err().to_string().contains("eye.iris.after"));
        let mut u: UserEye = toml::from_str(NAVARRO_LIKE).unwrap();
        u.iris.before = Some("2".into());
        assert!(u.validate("e").unwrap_err().to_string().contains("exactly one of `after` and `before`"));
        u.iris.after = None;
        u.iris.before = Some("0".into());
        assert!(u.validate("e").unwrap_err().to_string().contains("eye.iris.before"));
        let mut u: UserEye = toml::from_str(NAVARRO_LIKE).unwrap();
        u.surfaces[0].semi_diameter = 9.0;
        assert!(u.validate("e").unwrap_err().to_string().contains("eye.surfaces[0].semi_diameter"));
        let unknown = NAVARRO_LIKE.replace("retina_radius = -12.0", "retina_radius = -12.0\ncolour = 1");
        assert!(toml::from_str::<UserEye>(&unknown).is_err());
        let unknown = NAVARRO_LIKE.replace("b = 0.0044", "b = 0.0044, d = 1.0");
        assert!(toml::from_str::<UserEye>(&unknown).is_err(), "unknown fields in a medium are refused");
    }
}
