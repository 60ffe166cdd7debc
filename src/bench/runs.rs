//! The bench's runs: every backend that can render the scene (with the acceleration-structure
//! builds of the mesh backends), every rendering method on each of them scored against a
//! high-sample reference (speed against error), and the convergence series of LA's lenslet
//! grid, the eye's pupil grid and samples per retina pixel. Every image comes from `assess`'s
//! stage functions through [`super::pipeline`].

use std::time::Instant;

use super::options::{
    la_grid_of, Backend, BenchRow, BuildRecord, MethodLabel, Parameter, Quantity, RowContext, Series, Sizes,
};
use super::pipeline::{
    display_images, focus_mm, focused_cases, ground_truth_image, perceived_images, with_methods, Sampling,
};
use super::summary::capped_psnr;
use super::StageTime;
use crate::accel::analytic::AnalyticRects;
use crate::accel::bvh::BvhIntersector;
#[cfg(feature = "embree")]
use crate::accel::embree::{BuildQuality, EmbreeIntersector};
use crate::error::Result;
use crate::experiment::Experiment;
use crate::metrics::{self, SsimConstants};
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::backend::scene_meshes;
use crate::render::{planar_kernel, FacingPlanes, Method, RadianceField, SceneTracer};
use crate::scene::{Mesh, Scene};

/// A backend that can render the scene, and its radiance field.
#[derive(Clone, Copy)]
pub struct Field<'a> {
    /// Which backend.
    pub backend: Backend,
    /// Its radiance field.
    pub field: &'a dyn RadianceField,
}

/// The intersection backends of a scene: the analytic one for rectangle-only scenes, and the
/// mesh backends on the tessellated scene, with their builds.
pub struct Backends {
    analytic: Option<AnalyticRects>,
    #[cfg(feature = "embree")]
    embree: EmbreeIntersector,
    bvh: BvhIntersector,
    /// Build time and triangle count of each mesh backend.
    pub builds: Vec<BuildRecord>,
    /// Triangles of the tessellated scene.
    pub triangles: usize,
}

impl Backends {
    /// Builds every backend that can intersect `scene`, timing the mesh backends' builds.
    pub fn build(scene: &Scene, ctx: &RowContext) -> Result<Self> {
        let analytic = if scene.is_analytic() { Some(AnalyticRects::new(scene)?) } else { None };
        let meshes = scene_meshes(scene);
        let refs: Vec<(u32, &Mesh)> = meshes.iter().map(|(i, m)| (*i, m.as_ref())).collect();
        let triangles: usize = refs.iter().map(|(_, m)| m.triangle_count()).sum();
        let mut builds = Vec::new();
        #[cfg(feature = "embree")]
        let embree = {
            let t = Instant::now();
            let e = EmbreeIntersector::new(&refs, BuildQuality::High)?;
            builds.push(ctx.build(Backend::Embree, triangles, e.build_seconds(), t.elapsed().as_secs_f64()));
            e
        };
        let t = Instant::now();
        let bvh = BvhIntersector::new(&refs)?;
        builds.push(ctx.build(Backend::Bvh, triangles, bvh.build_seconds(), t.elapsed().as_secs_f64()));
        Ok(Self {
            analytic,
            #[cfg(feature = "embree")]
            embree,
            bvh,
            builds,
            triangles,
        })
    }

    /// The radiance fields of `scene` on these backends; the fused kernel when the scene gets
    /// it everywhere else ([`planar_kernel`], as [`crate::render::with_scene_fields`] decides).
    pub fn fields<'a>(&'a self, scene: &'a Scene) -> Fields<'a> {
        Fields {
            fused: self.analytic.as_ref().and_then(|a| planar_kernel(scene, a)),
            analytic: self.analytic.as_ref().map(|a| SceneTracer { scene, backend: a }),
            #[cfg(feature = "embree")]
            embree: SceneTracer { scene, backend: &self.embree },
            bvh: SceneTracer { scene, backend: &self.bvh },
        }
    }
}

/// The radiance fields of a scene on each of its [`Backends`].
pub struct Fields<'a> {
    fused: Option<FacingPlanes<'a>>,
    analytic: Option<SceneTracer<'a, AnalyticRects>>,
    #[cfg(feature = "embree")]
    embree: SceneTracer<'a, EmbreeIntersector>,
    bvh: SceneTracer<'a, BvhIntersector>,
}

impl Fields<'_> {
    /// Every backend that can render the scene, fastest first: the fused planar kernel when the
    /// scene allows it, the analytic backend for rectangle-only scenes, then the mesh backends.
    pub fn list(&self) -> Vec<Field<'_>> {
        let mut list = Vec::new();
        if let Some(f) = &self.fused {
            list.push(Field { backend: Backend::AnalyticFused, field: f });
        }
        if let Some(t) = &self.analytic {
            list.push(Field { backend: Backend::Analytic, field: t });
        }
        #[cfg(feature = "embree")]
        list.push(Field { backend: Backend::Embree, field: &self.embree });
        list.push(Field { backend: Backend::Bvh, field: &self.bvh });
        list
    }
}

/// PSNR (mean of channels, capped: see [`capped_psnr`]) and SSIM (Wang 2004) of `a` against
/// `reference`.
fn score(a: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
    let p = metrics::psnr(a, reference)?.mean;
    let s = metrics::ssim(a, reference, SsimConstants::Wang2004)?.mean;
    Ok((capped_psnr(p), s))
}

/// What the points of one method in the `method` series are scored against.
struct MethodReference<'r> {
    /// How the references were made (the rows' `reference`).
    name: String,
    /// The reference display image...
    display: &'r RgbImage,
    /// ... and what each focused eye case perceives of it.
    perceived: Vec<&'r RgbImage>,
}

/// The runs of one bench: their rows, and the time of the steps that are not measured points.
pub struct Runs<'a> {
    /// The paper's experiment at the bench's sizes (every eye case).
    base: &'a Experiment,
    /// Its sampling settings, at which every run measures what it does not sweep.
    paper: Sampling,
    sizes: &'a Sizes,
    ctx: &'a RowContext,
    progress: &'a Progress,
    pub rows: Vec<BenchRow>,
    pub stages: Vec<StageTime>,
    /// Scoring (PSNR + SSIM), timed apart from the renders it scores.
    pub score_seconds: f64,
}

impl<'a> Runs<'a> {
    /// The runs of the bench's experiment `base` at `sizes`, every row sharing `ctx`.
    pub fn new(base: &'a Experiment, sizes: &'a Sizes, ctx: &'a RowContext, progress: &'a Progress) -> Self {
        Self {
            base,
            paper: Sampling::of(base),
            sizes,
            ctx,
            progress,
            rows: Vec::new(),
            stages: Vec::new(),
            score_seconds: 0.0,
        }
    }

    fn stage(&mut self, name: &str, since: Instant) {
        self.stages.push(StageTime { stage: name.into(), seconds: since.elapsed().as_secs_f64() });
    }

    fn score(&mut self, a: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
        let t = Instant::now();
        let q = score(a, reference);
        self.score_seconds += t.elapsed().as_secs_f64();
        q
    }

    fn lcd_pixels(&self) -> u64 {
        (self.sizes.lcd_resolution * self.sizes.lcd_resolution) as u64
    }

    fn retina_pixels(&self) -> u64 {
        (self.sizes.retina_resolution * self.sizes.retina_resolution) as u64
    }

    /// The paper's experiment with only its first focused eye case.
    fn first_focused(&self) -> Result<Experiment> {
        let mut exp = focused_cases(self.base)?;
        exp.cases.truncate(1);
        Ok(exp)
    }

    /// Speed against error: every method of the paper's experiment on every backend, at each of
    /// [`Sizes::display_samples`], the display image and what each focused eye case perceives of
    /// it, against references rendered once on the first (fastest) backend.
    pub fn method_series(&mut self, backends: &[Field<'_>]) -> Result<()> {
        let sz = self.sizes;
        let best = backends[0];
        let focused = focused_cases(self.base)?;
        // References: each method with many samples per display pixel (LA also with a finer
        // lenslet grid), and what a finer eye perceives of those.
        let t = Instant::now();
        let reference = Sampling {
            retina: sz.reference_retina_samples,
            display: sz.reference_display_samples,
            pupil: sz.reference_pupil_grid,
            la: sz.reference_la_grid,
        }
        .apply(&focused);
        let (ref_displays, _) = display_images(&reference, best.field)?;
        let ref_perceived = perceived_images(&reference, &ref_displays.iter().collect::<Vec<_>>())?.images;
        self.stage("references of the method series", t);
        self.progress.inc(1);
        for b in backends {
            for (mi, &method) in focused.methods.iter().enumerate() {
                let ref_m = reference.methods[mi];
                let against = MethodReference {
                    name: format!(
                        "{} ({}x{} per display pixel, {} best backend {})",
                        ref_m,
                        sz.reference_display_samples,
                        sz.reference_display_samples,
                        if ref_m == method { "same method," } else { "finer lenslet grid," },
                        best.backend
                    ),
                    display: &ref_displays[mi],
                    perceived: ref_perceived.iter().map(|p| &p[mi]).collect(),
                };
                for &k in &sz.display_samples {
                    let exp = with_methods(&self.paper.with(Parameter::DisplaySamples, k).apply(&focused), &[method]);
                    self.method_point(b, &exp, &against)?;
                }
            }
            self.progress.inc(1);
        }
        Ok(())
    }

    /// One point of the `method` series: the display image of `exp`'s one method, and what each
    /// of its eye cases perceives of it, each against its reference.
    fn method_point(&mut self, b: &Field<'_>, exp: &Experiment, against: &MethodReference<'_>) -> Result<()> {
        let method = exp.methods[0];
        let k = exp.render.samples_per_pixel;
        let (img, t_display) = display_images(exp, b.field)?;
        let display_rays = self.lcd_pixels() * (k * k * method.lenslet_samples()) as u64;
        let base = BenchRow {
            parameter: k,
            samples: k * k,
            display_samples: k,
            la_grid: la_grid_of(method),
            ..self.ctx.row(Series::Method, Parameter::DisplaySamples, Quantity::Display, b.backend, method.into())
        };
        let q = self.score(&img[0], against.display)?;
        let row = BenchRow { reference: against.name.clone(), ..base.clone() };
        self.rows.push(row.measured(t_display, display_rays, q));
        let sims = perceived_images(exp, &[&img[0]])?;
        let sz = self.sizes;
        for (ci, case) in exp.cases.iter().enumerate() {
            let pupil_samples = case.eye.pupil_samples().len();
            let eye_rays = self.retina_pixels() * (pupil_samples * exp.retina.samples_per_pixel.pow(2)) as u64;
            let row = BenchRow {
                quantity: Quantity::Perceived,
                eye_case: case.name.clone(),
                focus_mm: focus_mm(case),
                pupil_grid: case.eye.pupil_grid,
                pupil_samples,
                retina_samples: exp.retina.samples_per_pixel,
                reference: format!(
                    "{}, seen with pupil grid {} and {}x{} per retina pixel",
                    against.name, sz.reference_pupil_grid, sz.reference_retina_samples, sz.reference_retina_samples
                ),
                ..base.clone()
            };
            let q = self.score(&sims.images[ci][0], against.perceived[ci])?;
            self.rows.push(row.measured(t_display + sims.seconds(ci), display_rays + eye_rays, q));
        }
        Ok(())
    }

    /// LA's k x k lenslet grid: the LA display image for each of [`Sizes::la_grids`] against a
    /// much finer grid. Returns the LC display image (one sample per pixel) and whether LA with
    /// k = 1 rendered it bit for bit.
    pub fn la_grid_series(&mut self, best: &Field<'_>) -> Result<(RgbImage, bool)> {
        let sz = self.sizes;
        let one = self.paper.with(Parameter::DisplaySamples, 1).apply(self.base);
        let t = Instant::now();
        let la = |grid: usize| with_methods(&one, &[Method::LensletAverage { grid }]);
        let (mut reference, _) = display_images(&la(sz.la_grid_reference), best.field)?;
        let (mut lc, _) = display_images(&with_methods(&one, &[Method::LensletCenter]), best.field)?;
        let (reference, lc) = (reference.remove(0), lc.remove(0));
        self.stage("reference of la_grid (and the LC image)", t);
        let mut la_k1_equals_lc = false;
        for &k in &sz.la_grids {
            let (img, secs) = display_images(&la(k), best.field)?;
            if k == 1 {
                la_k1_equals_lc = img[0] == lc;
            }
            let r = BenchRow {
                parameter: k,
                samples: k * k,
                la_grid: k,
                reference: format!("LA {0}x{0}", sz.la_grid_reference),
                ..self.ctx.row(Series::LaGrid, Parameter::LaGrid, Quantity::Display, best.backend, MethodLabel::La)
            };
            let q = self.score(&img[0], &reference)?;
            self.rows.push(r.measured(secs, self.lcd_pixels() * (k * k) as u64, q));
        }
        self.progress.inc(1);
        Ok((lc, la_k1_equals_lc))
    }

    /// The eye's n x n pupil grid: what the first focused eye case perceives of the LC display
    /// image `lc`, for each of [`Sizes::pupil_grids`], against a much finer grid.
    pub fn pupil_grid_series(&mut self, best: &Field<'_>, lc: &RgbImage) -> Result<()> {
        let sz = self.sizes;
        let first = self.first_focused()?;
        let paper = self.paper;
        let at = |n: usize| paper.with(Parameter::PupilGrid, n).apply(&first);
        let t = Instant::now();
        let reference = perceived_images(&at(sz.pupil_grid_reference), &[lc])?.images.remove(0).remove(0);
        self.stage("reference of pupil_grid", t);
        for &n in &sz.pupil_grids {
            let exp = at(n);
            let sims = perceived_images(&exp, &[lc])?;
            let case = &exp.cases[0];
            let kept = case.eye.pupil_samples().len();
            let r = BenchRow {
                eye_case: case.name.clone(),
                focus_mm: focus_mm(case),
                parameter: n,
                samples: kept,
                pupil_grid: n,
                pupil_samples: kept,
                retina_samples: exp.retina.samples_per_pixel,
                reference: format!("pupil grid {}", sz.pupil_grid_reference),
                ..self.ctx.row(
                    Series::PupilGrid,
                    Parameter::PupilGrid,
                    Quantity::Perceived,
                    best.backend,
                    MethodLabel::Lc,
                )
            };
            let q = self.score(&sims.images[0][0], &reference)?;
            self.rows.push(r.measured(sims.seconds(0), self.retina_pixels() * kept as u64, q));
        }
        self.progress.inc(1);
        Ok(())
    }

    /// Samples per retina pixel: the ground truth of the first focused eye case for each of
    /// [`Sizes::retina_samples`], against many more samples.
    pub fn retina_samples_series(&mut self, best: &Field<'_>) -> Result<()> {
        let sz = self.sizes;
        let first = self.first_focused()?;
        let paper = self.paper;
        let at = |k: usize| paper.with(Parameter::RetinaSamples, k).apply(&first);
        let t = Instant::now();
        let exp = at(sz.retina_samples_reference);
        let (reference, _) = ground_truth_image(&exp, &exp.cases[0], best.field);
        self.stage("reference of retina_samples", t);
        for &k in &sz.retina_samples {
            let exp = at(k);
            let case = &exp.cases[0];
            let (gt, secs) = ground_truth_image(&exp, case, best.field);
            let pupil_samples = case.eye.pupil_samples().len();
            let row = BenchRow {
                eye_case: case.name.clone(),
                focus_mm: focus_mm(case),
                parameter: k,
                samples: k * k,
                pupil_grid: case.eye.pupil_grid,
                pupil_samples,
                retina_samples: k,
                reference: format!("{0}x{0} per retina pixel", sz.retina_samples_reference),
                ..self.ctx.row(
                    Series::RetinaSamples,
                    Parameter::RetinaSamples,
                    Quantity::GroundTruth,
                    best.backend,
                    MethodLabel::Gt,
                )
            };
            let q = self.score(&gt, &reference)?;
            self.rows.push(row.measured(secs, self.retina_pixels() * (k * k * pupil_samples) as u64, q));
        }
        self.progress.inc(1);
        Ok(())
    }
}
