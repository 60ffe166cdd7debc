//! What a run simulated, in words: the eye model of every eye case (the paper's thin lens,
//! Sec. 2.3, or a schematic eye of docs/EYE.md), the wavelengths traced, diffraction
//! (docs/OPTICS.md) and the lenslets (the paper's thin lens of eq. (1b) or a real thick lenslet).
//! `table.md`'s title and caption, `figure.png`'s title, `results.json` (`simulated`) and
//! `report.html` all say it with these words, so no output names the experiment alone.

use serde::Serialize;

use super::Experiment;
use crate::optics::diffraction::Diffraction;
use crate::optics::lenslet::{LensletOptics, Surface};
use crate::optics::Display;

/// The four things a reader must know to read a run's scores, each as a short phrase.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Simulated {
    /// The eye model(s) of the eye cases, in case order, without repeats (`thin-lens`,
    /// `navarro-1985`, ...).
    pub eye: String,
    /// The wavelengths each colour channel is traced at.
    pub spectrum: String,
    /// Which apertures diffract.
    pub diffraction: String,
    /// The lenslets' kind and parameters.
    pub lenslets: String,
    /// The spectrum and diffraction in a few words, for the figure's title.
    #[serde(skip)]
    short: [String; 2],
}

impl Simulated {
    /// The phrases of an experiment as resolved (its cases' eyes, its display, `[optics]`).
    pub fn of(exp: &Experiment) -> Self {
        let mut models: Vec<&str> = Vec::new();
        for c in &exp.cases {
            let m = c.eye.optics.as_ref().map_or("thin-lens", |o| o.model.name());
            if !models.contains(&m) {
                models.push(m);
            }
        }
        let optics: Vec<_> = exp.cases.iter().filter_map(|c| c.eye.optics.as_ref()).collect();
        let (spectrum, short) = if optics.iter().any(|o| !o.is_single_wavelength()) {
            ("each colour channel at its display primary's wavelengths".to_string(), "primaries' spectra".to_string())
        } else if let Some(o) = optics.first() {
            (format!("one wavelength, {} nm", o.reference_nm), format!("{} nm", o.reference_nm))
        } else {
            (
                "one ray per sample for all three channels (the thin lens has no dispersion)".to_string(),
                "no dispersion".to_string(),
            )
        };
        let diffraction = exp.spec.optics.as_ref().map(|o| o.diffraction).unwrap_or_default();
        // A turned eye names its gazes (straight ahead names none, as before gaze existed).
        let mut gazes: Vec<String> = Vec::new();
        for g in exp.cases.iter().filter_map(|c| c.eye.pose.as_ref()).map(|p| p.gaze) {
            let g = format!("[{}, {}] degrees", g.horizontal_deg, g.vertical_deg);
            if !gazes.contains(&g) {
                gazes.push(g);
            }
        }
        let gaze = if gazes.is_empty() { String::new() } else { format!(", gaze {}", gazes.join(", ")) };
        Self {
            eye: models.join(", ") + &gaze,
            spectrum,
            diffraction: diffraction_words(diffraction).to_string(),
            lenslets: lenslet_words(&exp.display),
            short: [short, format!("diffraction {}", diffraction.name())],
        }
    }

    /// The eye and the lenslets, for a title: "navarro-1985 eye, thick PMMA lenslets".
    pub fn title_part(&self) -> String {
        let kind = self.lenslets.split(" (").next().unwrap_or(&self.lenslets);
        let diffraction = if self.diffraction.starts_with("none") { "" } else { ", diffraction" };
        format!("{} eye, {kind}{diffraction}", self.eye)
    }

    /// All four in a few words, for the figure's title: "navarro-1985 eye, thin lenslets,
    /// primaries' spectra, diffraction none".
    pub fn figure_part(&self) -> String {
        let kind = self.lenslets.split(" (").next().unwrap_or(&self.lenslets);
        format!("{} eye, {kind}, {}, {}", self.eye, self.short[0], self.short[1])
    }

    /// One sentence naming all four: "Eye: ...; spectrum: ...; diffraction: ...; lenslets: ...".
    pub fn sentence(&self) -> String {
        format!(
            "Eye: {}; spectrum: {}; diffraction: {}; lenslets: {}.",
            self.eye, self.spectrum, self.diffraction, self.lenslets
        )
    }
}

/// `[optics] diffraction` in words.
pub fn diffraction_words(d: Diffraction) -> &'static str {
    match d {
        Diffraction::None => "none (rays only, the paper's model)",
        Diffraction::Pupil => "at the eye's pupil",
        Diffraction::Apertures => "at the eye's pupil and at each lenslet's aperture",
    }
}

/// The lenslets in words: "thin lenslets (f = 6.427 mm)" or "thick PMMA lenslets (front R 3 mm,
/// conic -0.5; back plane; centre thickness 1 mm)".
pub fn lenslet_words(d: &Display) -> String {
    match &d.lenslet {
        LensletOptics::Paraxial => format!("thin lenslets (f = {} mm, the paper's eq. (1b))", d.focal_length),
        LensletOptics::Thick(t) => {
            let surface = |s: &Surface| {
                if s.curvature() == 0.0 {
                    "plane".to_string()
                } else {
                    format!("R {} mm, conic {}", s.radius, s.conic)
                }
            };
            format!(
                "thick {} lenslets (front {}; back {}; centre thickness {} mm)",
                t.material.name,
                surface(&t.front),
                surface(&t.back),
                t.thickness
            )
        }
    }
}

/// `results.json`'s `display`: the display's parameters, its lenslets (a thick lenslet's
/// surfaces, thickness, material and first-order properties at the d line), the diffraction at its
/// apertures and its photometry.
#[derive(Clone, Debug, Serialize)]
pub struct DisplayReport {
    /// v1, v2, f, the lattices, the LCD and the central depth plane.
    #[serde(flatten)]
    pub parameters: crate::info::DisplayParameters,
    /// The lenslets' optics.
    pub lenslet: LensletReport,
    /// `[optics] diffraction`: "none", "pupil" or "apertures".
    pub diffraction: &'static str,
    /// The panel's photometry (stated, or the documented default).
    pub photometry: crate::optics::photometry::Photometry,
}

/// The lenslets of `results.json`'s `display`.
#[derive(Clone, Debug, Serialize)]
pub struct LensletReport {
    /// "thin" (the paper's eq. (1b)) or "thick" (a real lenslet traced exactly).
    pub kind: &'static str,
    /// Thick: the material ("PMMA", "N-BK7", "user").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Thick: front and back surfaces' signed radii, mm (0: a plane).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radii_mm: Option<[f64; 2]>,
    /// Thick: front and back surfaces' conic constants.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub conics: Option<[f64; 2]>,
    /// Thick: centre thickness, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thickness_mm: Option<f64>,
    /// Thick: the material's index at the d line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index_d: Option<f64>,
    /// Thick: effective focal length at the d line, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub efl_d_mm: Option<f64>,
    /// Thick: back focal distance at the d line (back vertex to focus), mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bfd_d_mm: Option<f64>,
}

impl DisplayReport {
    /// The report of display `d` under `[optics] diffraction = diffraction`.
    pub fn of(d: &Display, diffraction: Diffraction) -> Self {
        let lenslet = match d.lenslet.thick() {
            None => LensletReport {
                kind: "thin",
                material: None,
                radii_mm: None,
                conics: None,
                thickness_mm: None,
                index_d: None,
                efl_d_mm: None,
                bfd_d_mm: None,
            },
            Some(t) => {
                let p = t.paraxial(crate::optics::lenslet::D_LINE_NM);
                LensletReport {
                    kind: "thick",
                    material: Some(t.material.name.clone()),
                    radii_mm: Some([t.front.radius, t.back.radius]),
                    conics: Some([t.front.conic, t.back.conic]),
                    thickness_mm: Some(t.thickness),
                    index_d: Some(p.index),
                    efl_d_mm: Some(p.efl),
                    bfd_d_mm: Some(p.bfd),
                }
            }
        };
        Self { parameters: d.into(), lenslet, diffraction: diffraction.name(), photometry: d.photometry() }
    }
}
