//! The one pipeline every bench image goes through: the paper's experiment (Sec. 4.1) at the
//! bench's sizes on the bench's scene, copies of it with sampling settings changed
//! ([`Sampling`]), and timed calls of the stage functions `assess` runs
//! ([`crate::experiment::render_display_images`], `pack_display_images`, `ground_truth_image`,
//! `perceived_images`), whose own stage timings are what the bench reports.

use std::path::Path;

use super::options::{Parameter, Sizes};
use crate::error::{Error, Result};
use crate::experiment::{self, Experiment, ExperimentSpec, EyeCase, StageTime};
use crate::optics::{Aperture, Display};
use crate::raster::RgbImage;
use crate::render::{Method, RadianceField};
use crate::scene::Scene;

/// The paper's experiment on `scene`, with the paper's display at `sizes.lcd_resolution` and the
/// retina at `sizes.retina_resolution`; every other setting is the paper's.
pub fn base_experiment(sizes: &Sizes, scene: &Scene) -> Result<Experiment> {
    let mut exp = Experiment::from_spec(ExperimentSpec::paper(), "built-in paper experiment", Path::new("."))?;
    exp.name = "bench".into();
    exp.scene = scene.clone();
    let mut display = Display::paper();
    display.lcd.resolution = [sizes.lcd_resolution, sizes.lcd_resolution];
    exp.display = display;
    exp.retina.resolution = sizes.retina_resolution;
    exp.spec.eye.retina_resolution = sizes.retina_resolution;
    Ok(exp)
}

/// The four sampling settings the bench varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampling {
    /// Samples per retina pixel, per axis.
    pub retina: usize,
    /// Samples per display pixel, per axis.
    pub display: usize,
    /// Pupil grid n.
    pub pupil: usize,
    /// LA's k.
    pub la: usize,
}

impl Sampling {
    /// The settings of `exp` (LA's k: that of its LA method, 1 without one).
    pub fn of(exp: &Experiment) -> Self {
        Self {
            retina: exp.retina.samples_per_pixel,
            display: exp.render.samples_per_pixel,
            pupil: exp.spec.eye.pupil_grid,
            la: exp
                .methods
                .iter()
                .find_map(|m| match m {
                    Method::LensletAverage { grid } => Some(*grid),
                    Method::LensletCenter | Method::PupilCenter | Method::Optimized => None,
                })
                .unwrap_or(1),
        }
    }

    /// These settings with `parameter` set to `value`.
    pub fn with(self, parameter: Parameter, value: usize) -> Self {
        match parameter {
            Parameter::RetinaSamples => Self { retina: value, ..self },
            Parameter::DisplaySamples => Self { display: value, ..self },
            Parameter::PupilGrid => Self { pupil: value, ..self },
            Parameter::LaGrid => Self { la: value, ..self },
        }
    }

    /// The value of `parameter`.
    #[cfg(test)]
    pub fn get(self, parameter: Parameter) -> usize {
        match parameter {
            Parameter::RetinaSamples => self.retina,
            Parameter::DisplaySamples => self.display,
            Parameter::PupilGrid => self.pupil,
            Parameter::LaGrid => self.la,
        }
    }

    /// A copy of `base` at these settings: samples per retina and display pixel, every eye
    /// case's pupil grid, and the grid of its LA method.
    pub fn apply(self, base: &Experiment) -> Experiment {
        let mut e = base.clone();
        e.retina.samples_per_pixel = self.retina;
        e.spec.eye.retina_samples = self.retina;
        e.render.samples_per_pixel = self.display;
        e.spec.display_render.samples_per_pixel = self.display;
        for c in &mut e.cases {
            c.eye.pupil_grid = self.pupil;
        }
        e.spec.eye.pupil_grid = self.pupil;
        for m in &mut e.methods {
            if let Method::LensletAverage { grid } = m {
                *grid = self.la;
            }
        }
        e.spec.display_render.la_grid = self.la;
        e
    }
}

/// `exp` rendering only `methods`.
pub fn with_methods(exp: &Experiment, methods: &[Method]) -> Experiment {
    Experiment { methods: methods.to_vec(), ..exp.clone() }
}

/// `exp` with only its focused (thin-lens) eye cases; an error when it has none.
pub fn focused_cases(exp: &Experiment) -> Result<Experiment> {
    let cases: Vec<EyeCase> =
        exp.cases.iter().filter(|c| matches!(c.eye.aperture, Aperture::ThinLens { .. })).cloned().collect();
    if cases.is_empty() {
        return Err(Error::Mismatch("the paper experiment has no focused eye case".into()));
    }
    Ok(Experiment { cases, ..exp.clone() })
}

/// Focus distance (mm) of an eye case; `None` for a pinhole.
pub fn focus_mm(case: &EyeCase) -> Option<f64> {
    match case.eye.aperture {
        Aperture::ThinLens { focus, .. } => Some(focus.distance_mm()),
        Aperture::Pinhole => None,
    }
}

/// Total seconds of some stages.
pub fn stage_seconds(stages: &[StageTime]) -> f64 {
    stages.iter().map(|s| s.seconds).sum()
}

/// Stage 1 of `assess`: the display image of every method of `exp` on `field`, and the seconds
/// that took.
pub fn display_images(exp: &Experiment, field: &dyn RadianceField) -> Result<(Vec<RgbImage>, f64)> {
    let mut stages = Vec::new();
    let (images, _depths) = experiment::render_display_images(exp, field, true, &mut stages)?;
    Ok((images, stage_seconds(&stages)))
}

/// What every eye case of `exp` perceives of `displays`.
pub struct Perceived {
    /// `images[case][display]`.
    pub images: Vec<Vec<RgbImage>>,
    /// Packing the display images for the simulation (done once for every eye case).
    pub pack_seconds: f64,
    /// Simulating each eye case.
    pub case_seconds: Vec<f64>,
}

impl Perceived {
    /// Getting eye case `case`'s images from the display images: packing plus its simulation.
    pub fn seconds(&self, case: usize) -> f64 {
        self.pack_seconds + self.case_seconds[case]
    }
}

/// Stage 2b of `assess` for every eye case of `exp`: the display images packed once, then
/// simulated per eye case.
pub fn perceived_images(exp: &Experiment, displays: &[&RgbImage]) -> Result<Perceived> {
    let mut stages = Vec::new();
    let stack = experiment::pack_display_images(exp, displays, &mut stages)?;
    let pack_seconds = stage_seconds(&stages);
    let mut images = Vec::new();
    let mut case_seconds = Vec::new();
    for case in &exp.cases {
        let mut stages = Vec::new();
        images.push(experiment::perceived_images(exp, case, &stack, true, &mut stages)?);
        case_seconds.push(stage_seconds(&stages));
    }
    Ok(Perceived { images, pack_seconds, case_seconds })
}

/// Stage 2a of `assess`: the ground truth of eye case `case` of `exp` on `field`, and the seconds
/// that took.
pub fn ground_truth_image(exp: &Experiment, case: &EyeCase, field: &dyn RadianceField) -> (RgbImage, f64) {
    let mut stages = Vec::new();
    let image = experiment::ground_truth_image(exp, case, field, true, &mut stages);
    (image, stage_seconds(&stages))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_sets_exactly_the_parameter_it_names() {
        let s = Sampling { retina: 1, display: 2, pupil: 8, la: 5 };
        for (i, p) in Parameter::ALL.iter().enumerate() {
            let v = 40 + i;
            let t = s.with(*p, v);
            assert_eq!(t.get(*p), v);
            for q in Parameter::ALL.iter().filter(|q| *q != p) {
                assert_eq!(t.get(*q), s.get(*q), "{p} changed {q}");
            }
        }
    }

    #[test]
    fn sampling_applies_to_every_eye_case_and_the_la_method_only() {
        let sizes = Sizes { lcd_resolution: 54, retina_resolution: 16, ..Sizes::quick() };
        let base = base_experiment(&sizes, &Scene::paper()).unwrap();
        assert_eq!(base.display.lcd.resolution, [54, 54]);
        assert_eq!(base.retina.resolution, 16);
        let paper = Sampling::of(&base);
        assert_eq!(paper, Sampling { retina: 1, display: 1, pupil: 8, la: 5 });
        let s = Sampling { retina: 3, display: 2, pupil: 6, la: 4 };
        let e = s.apply(&base);
        assert_eq!(Sampling::of(&e), s);
        assert_eq!(e.methods, [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 4 }]);
        assert!(e.cases.iter().all(|c| c.eye.pupil_grid == 6));
        let focused = focused_cases(&e).unwrap();
        let names: Vec<&str> = focused.cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["Near", "Cen", "Far"]);
        assert_eq!(focused.cases.iter().map(focus_mm).collect::<Vec<_>>(), [Some(300.0), Some(400.0), Some(600.0)]);
        assert_eq!(focus_mm(&e.cases[0]), None);
        let pin_only = Experiment { cases: vec![e.cases[0].clone()], ..e };
        assert!(focused_cases(&pin_only).is_err());
    }
}
