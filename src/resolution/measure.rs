//! The retinal images of a resolution target through the converged estimator (the
//! paper's Sec. 4.1 eye looking at the scene, or at the display's rendering of it): a narrow,
//! finely sampled retina ([`narrow_retina`]), the ground truth alone ([`SceneSource`]) or with
//! the perceived images of display images ([`crate::measure::estimator::DisplaySource`]), and
//! the sampling loop ([`measure_image`], [`measure_until`]) that returns the R replicates the
//! modulation ([`super::grating`]) and edge ([`super::edge`]) measurements need (as one window:
//! [`super::window::WindowSamples::from_replicates`]).

use glam::{DVec2, DVec3};

use crate::measure::estimator::{EyeSample, PairedSource, Replicates};
use crate::measure::sampler::{Sampler, MAX_SAMPLES_PER_REPLICATE};
use crate::optics::transfer::eye_scene_ray;
use crate::optics::{Aperture, Eye, Retina};
use crate::progress::Progress;
use crate::render::{RadianceField, Sample};
use crate::scene::{Material, Object, Rect, Scene, Shape};

/// A square retina of `2 half_field_deg * pixels_per_degree` pixels (rounded) with pixels of
/// exactly `1 / pixels_per_degree` degrees (in tangent units: one degree = pi/180), centred on
/// the axis. E.g. +-1 degree at 64 pixels per degree: 128 x 128.
pub fn narrow_retina(half_field_deg: f64, pixels_per_degree: f64) -> Retina {
    let resolution = (2.0 * half_field_deg * pixels_per_degree).round().max(1.0) as usize;
    let pixel = (1.0 / pixels_per_degree).to_radians();
    Retina { resolution, half_tangent: 0.5 * resolution as f64 * pixel, samples_per_pixel: 1 }
}

/// Angular size (radians, tangent units) of one pixel of `retina`.
pub fn pixel_rad(retina: &Retina) -> f64 {
    2.0 * retina.half_tangent / retina.resolution as f64
}

/// Converts cycles per degree to cycles per pixel of `retina`.
pub fn cycles_per_pixel(retina: &Retina, cpd: f64) -> f64 {
    cpd * 180.0 / std::f64::consts::PI * pixel_rad(retina)
}

/// A scene of one target: an eye-facing square at `depth_mm` spanning +-63 degrees (4 z wide,
/// so that every camera ray of a near-eye display meets it), with `material` (a grating or an
/// edge, whose tangent coordinates make it the same at every depth); the background is the
/// target's mean grey.
pub fn target_scene(name: &str, depth_mm: f64, material: Material) -> Scene {
    let background = match &material {
        Material::Grating(g) => DVec3::splat(g.mean),
        Material::Edge(e) => DVec3::splat(0.5 * (e.low + e.high)),
        Material::Albedo(a) => *a,
        _ => DVec3::ZERO,
    };
    Scene {
        name: name.into(),
        objects: vec![Object {
            name: "target".into(),
            shape: Shape::Rect(Rect::facing_eye(DVec3::new(0.0, 0.0, depth_mm), 4.0 * depth_mm, 4.0 * depth_mm)),
            material,
        }],
        background,
        light: None,
        warnings: Vec::new(),
    }
}

/// The ground truth alone: one image, the eye ray's radiance into the scene (what
/// [`crate::measure::estimator::DisplaySource`] gives as its image 0, without a display).
pub struct SceneSource<'a, F: RadianceField + ?Sized> {
    /// The eye.
    pub eye: &'a Eye,
    /// The scene's radiance field.
    pub field: &'a F,
}

impl<F: RadianceField + ?Sized> PairedSource for SceneSource<'_, F> {
    fn images(&self) -> usize {
        1
    }

    fn eval(&self, samples: &[EyeSample], out: &mut [[f64; 3]]) {
        if self.field.prefers_batches() {
            let rays: Vec<_> = samples.iter().map(|s| eye_scene_ray(self.eye, s.tangent, s.pupil)).collect();
            let mut hits = vec![Sample::default(); rays.len()];
            self.field.sample_many(&rays, &mut hits);
            for (o, h) in out.iter_mut().zip(&hits) {
                *o = h.radiance.to_array();
            }
        } else {
            for (o, s) in out.iter_mut().zip(samples) {
                *o = self.field.radiance(&eye_scene_ray(self.eye, s.tangent, s.pupil)).to_array();
            }
        }
    }
}

/// How the images are sampled: Owen-scrambled Sobol points over each retina pixel and the
/// eye's pupil disk (`measure::sampler`), `replicates` independent scrambles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Seed of the scrambles.
    pub seed: u64,
    /// Independent scrambles for different images measured with one seed (e.g. the index of
    /// the content depth and focus).
    pub stream: u64,
    /// At least 3 for intervals.
    pub replicates: usize,
    /// Samples per pixel and replicate of the first round.
    pub initial_samples: u32,
    /// Samples per pixel and replicate, at most (up to 2^16).
    pub max_samples: u32,
}

impl Default for Sampling {
    fn default() -> Self {
        Self { seed: 1, stream: 0, replicates: 8, initial_samples: 8, max_samples: 1024 }
    }
}

/// The sampler of `sampling` for `eye` (its pupil disk; one point for a pinhole).
pub fn sampler(sampling: &Sampling, eye: &Eye) -> Sampler {
    let radius = match eye.aperture {
        Aperture::Pinhole => None,
        Aperture::ThinLens { pupil_diameter, .. } => Some(0.5 * pupil_diameter),
    };
    Sampler::new(sampling.seed, sampling.stream, radius)
}

/// Every image of `source` on `retina` with `samples` samples per pixel in each replicate.
pub fn measure_image<S: PairedSource + ?Sized>(
    source: &S,
    eye: &Eye,
    retina: &Retina,
    sampling: &Sampling,
    samples: u32,
) -> Replicates {
    let mut reps = Replicates::new(retina.resolution, sampling.replicates.max(1), source.images());
    let samples = samples.clamp(1, MAX_SAMPLES_PER_REPLICATE as u32);
    reps.extend(source, &sampler(sampling, eye), retina, samples, &Progress::hidden());
    reps
}

/// Samples until `half_width(&replicates)` (e.g. the widest 95% half-width of the contrasts
/// that matter) is at most `target`, doubling the samples per replicate from
/// `sampling.initial_samples` up to `sampling.max_samples`; earlier samples are kept (nested
/// sequences). Returns the replicates and whether the target was met.
pub fn measure_until<S: PairedSource + ?Sized>(
    source: &S,
    eye: &Eye,
    retina: &Retina,
    sampling: &Sampling,
    target: f64,
    half_width: impl Fn(&Replicates) -> f64,
) -> (Replicates, bool) {
    let sampler = sampler(sampling, eye);
    let max = sampling.max_samples.clamp(1, MAX_SAMPLES_PER_REPLICATE as u32);
    let mut reps = Replicates::new(retina.resolution, sampling.replicates.max(1), source.images());
    let mut n = sampling.initial_samples.clamp(1, max);
    loop {
        reps.extend(source, &sampler, retina, n, &Progress::hidden());
        let h = half_width(&reps);
        if h <= target {
            return (reps, true);
        }
        if n >= max {
            return (reps, false);
        }
        n = n.saturating_mul(2).min(max);
    }
}

/// The tangent of the centre of pixel (row, col) of `retina` (for placing targets).
pub fn pixel_tangent(retina: &Retina, row: usize, col: usize) -> DVec2 {
    retina.tangent(row, col, DVec2::splat(0.5))
}
