//! Running a study: for each content depth, the chart on its plane, each method's
//! display image rendered once (paper Sec. 3), and for each eye focus the ground truth and every
//! perceived image measured over the chart's windows by the converged estimator (Sec. 2.3, 4.1),
//! then each window's grating contrast ([`super::grating`]) and slanted-edge MTF
//! ([`super::edge`]) with their 95% intervals. Every stage is timed.
//!
//! Display images cover only the part of the LCD that the measured eye rays can reach
//! ([`crop_display`]): the same pixels as the full panel's (same pitch and grid), so every value
//! read is the full display image's; pixels no measured ray can reach are not rendered.

use std::time::Instant;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::chart::{Chart, ChartField, EyeFrame, Pattern};
use super::study::Study;
use super::window::{measure_windows_as, progress_steps, Grey, WindowSamples};
use super::{edge, grating};
use crate::error::Result;
use crate::measure::estimator::DisplaySource;
use crate::measure::sampler::Sampler;
use crate::optics::display::Lcd;
use crate::optics::eye::EyeOptics;
use crate::optics::{Display, Eye, Focus};
use crate::optimize::Optimization;
use crate::progress::Progress;
use crate::raster::RgbImage;
use crate::render::retina::DisplayStack;
use crate::render::{DisplayRenderSettings, Method};

/// The smallest centred part of `display`'s LCD, on the full panel's pixel grid, that holds
/// every LCD point an eye ray can reach for retina tangents within `half_tangent` (per axis),
/// pupil points within `pupil_radius` and eye focus vergences up to `max_vergence` (1/mm), with
/// the eye at the origin. The bound (triangle inequality through eq. (1), with the farthest a
/// lenslet centre can be from a point it is nearest to) errs on the side of a larger crop.
pub fn crop_display(display: &Display, half_tangent: DVec2, pupil_radius: f64, max_vergence: f64) -> Display {
    let slope = half_tangent + DVec2::splat(pupil_radius * max_vergence.abs());
    let x2 = DVec2::splat(pupil_radius) + slope * display.eye_to_lenslets;
    crop_reaching(display, x2, slope)
}

/// [`crop_display`] for an eye turned or moved to `frame` (its tangents, pupil and vergences in
/// its own frame): the eye's ray slopes in the display's frame are bounded by the images of the
/// corners of its tangent rectangle (the gnomonic map keeps straight lines straight), its pupil
/// points lie within `pupil_radius` of the pupil centre (a turned pupil also up to that much
/// nearer the lenslets).
pub fn crop_display_seen(
    display: &Display,
    half_tangent: DVec2,
    pupil_radius: f64,
    max_vergence: f64,
    frame: &EyeFrame,
) -> Display {
    let h = half_tangent + DVec2::splat(pupil_radius * max_vergence.abs());
    let mut slope = DVec2::ZERO;
    for c in [h, -h, DVec2::new(h.x, -h.y), DVec2::new(-h.x, h.y)] {
        let d = frame.direction(DVec3::new(c.x, c.y, 1.0));
        // A direction at or beyond 90 degrees from the axis never reaches the display: the whole
        // panel.
        slope = slope.max(if d.z > 0.0 { (d.truncate() / d.z).abs() } else { DVec2::splat(f64::INFINITY) });
    }
    let depth = display.eye_to_lenslets - frame.pupil.z + pupil_radius;
    let x2 = frame.pupil.truncate().abs() + DVec2::splat(pupil_radius) + slope * depth;
    crop_reaching(display, x2, slope)
}

/// The centred crop of `display` holding every LCD point of rays that meet the lenslet plane
/// within `x2` (per axis, mm) with slopes within `slope`.
fn crop_reaching(display: &Display, x2: DVec2, slope: DVec2) -> Display {
    let v2 = display.lenslets_to_lcd;
    let m = display.lenslets.reduced_matrix();
    // A point is at most half the two basis vectors' lengths from its nearest centre.
    let cell = 0.5 * (m.x_axis.abs() + m.y_axis.abs());
    let mut lcd = x2 + (slope + cell / display.focal_length) * v2;
    if let Some(t) = display.thick_lenslet() {
        // A real lenslet: the LCD is a thickness farther, and its shortest focal length over the
        // visible range and its aberrations bend rays more than 1/f; a quarter more is ample.
        let f = [400.0, 700.0].map(|nm| t.paraxial(nm).efl.abs()).into_iter().fold(display.focal_length, f64::min);
        lcd = 1.25 * (x2 + (slope + cell / f) * (v2 + t.thickness));
    }
    let pitch = display.lcd.pixel_pitch();
    let res = display.lcd.resolution;
    let pixels = |i: usize, half: f64| -> usize {
        let full = res[i];
        if !half.is_finite() {
            return full;
        }
        // Pixels either side of the centre, plus two; the parity of the full panel keeps the grid.
        let mut n = 2 * ((half / pitch[i]).ceil() as usize + 2);
        if full % 2 == 1 {
            n += 1;
        }
        n.min(full)
    };
    let (nx, ny) = (pixels(0, lcd.x), pixels(1, lcd.y));
    Display {
        lcd: Lcd { size: DVec2::new(nx as f64 * pitch.x, ny as f64 * pitch.y), resolution: [nx, ny] },
        ..display.clone()
    }
}

/// A measured value with the half-width of its 95% interval (NaN when not measured).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Value {
    /// The value.
    pub value: f64,
    /// Half-width of its 95% interval.
    pub ci95: f64,
}

impl Value {
    const NAN: Value = Value { value: f64::NAN, ci95: f64::NAN };
}

/// Source `k`'s grating contrast in window `w` at `frequency_cpd` (vertical bars, pixels of
/// `1 / ppd` degrees), over the target's `contrast`: 1 for a perfect eye and display (less the
/// retina pixel's own box response).
pub fn grating_value(w: &WindowSamples, k: usize, frequency_cpd: f64, ppd: f64, contrast: f64) -> Value {
    grating::modulation(w, k, frequency_cpd / ppd, 0.0)
        .map_or(Value::NAN, |m| Value { value: m.contrast / contrast, ci95: m.ci95 / contrast })
}

/// Source `k`'s slanted-edge MTF in window `w` at `frequencies_cpd`, and its MTF50 in cpd (NaN
/// when the MTF stays above 0.5 up to the retina's Nyquist frequency); NaN when the window
/// shows no edge.
pub fn edge_values(w: &WindowSamples, k: usize, frequencies_cpd: &[f64], ppd: f64) -> (Vec<Value>, Value) {
    let at: Vec<f64> = frequencies_cpd.iter().map(|f| f / ppd).collect();
    let Ok(m) = edge::edge_mtf(w, k, &at) else {
        return (vec![Value::NAN; at.len()], Value::NAN);
    };
    let values = m.at.iter().zip(&m.at_ci95).map(|(&value, &ci95)| Value { value, ci95 }).collect();
    let mtf50 = match m.curve.mtf50 {
        Some(f) if f <= 0.5 => Value { value: f * ppd, ci95: m.mtf50_ci95.map_or(f64::NAN, |h| h * ppd) },
        _ => Value::NAN,
    };
    (values, mtf50)
}

/// What one stage took.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Timing {
    /// The stage.
    pub stage: String,
    /// Its wall time, s.
    pub seconds: f64,
}

/// The gratings of one orientation other than 0 degrees.
#[derive(Clone, Debug)]
pub struct OrientedGratings {
    /// Degrees counter-clockwise from vertical bars.
    pub orientation_deg: f64,
    /// Contrast, `[source][depth][focus][frequency]`.
    pub grating: Vec<Vec<Vec<Vec<Value>>>>,
}

/// The measured numbers of a study, indexed `[source][depth][focus]` (then frequency); source 0
/// is the ground truth, source `1 + m` method `m`.
#[derive(Clone, Debug)]
pub struct StudyResults {
    /// The study measured.
    pub study: Study,
    /// "ground_truth", then each method's name ([`crate::render::Method::name`]).
    pub sources: Vec<String>,
    /// The chart measured.
    pub chart: Chart,
    /// The rendered part of the LCD, columns and rows.
    pub lcd_crop: [usize; 2],
    /// Grating contrast at 0 degrees (vertical bars), `[source][depth][focus][frequency]`.
    pub grating: Vec<Vec<Vec<Vec<Value>>>>,
    /// Grating contrast at each other orientation of the study, in its order.
    pub oriented: Vec<OrientedGratings>,
    /// Edge MTF, `[source][depth][focus][frequency]`.
    pub edge: Vec<Vec<Vec<Vec<Value>>>>,
    /// MTF50 in cpd, `[source][depth][focus]`.
    pub mtf50: Vec<Vec<Vec<Value>>>,
    /// Wall time of every stage.
    pub timings: Vec<Timing>,
    /// Eye rays traced (each serves every source).
    pub eye_rays: u64,
}

impl StudyResults {
    /// Grating contrast at the study's orientation `oi` (0: 0 degrees), `[source][depth][focus][frequency]`.
    pub fn grating_at(&self, oi: usize) -> &Vec<Vec<Vec<Vec<Value>>>> {
        if oi == 0 {
            &self.grating
        } else {
            &self.oriented[oi - 1].grating
        }
    }

    /// Index of source `name`.
    pub fn source_index(&self, name: &str) -> Option<usize> {
        self.sources.iter().position(|s| s == name)
    }
}

/// Source names of `study`.
pub fn source_names(study: &Study) -> Vec<String> {
    std::iter::once("ground_truth".to_string()).chain(study.methods.iter().map(|m| m.name())).collect()
}

/// The rays a study traces, for the long-run note: every method's display image of the LCD
/// crop at every depth (LA's grid of rays per pixel), and at every depth and focus each window
/// pixel's samples in every replicate. A sample is one eye ray that every source (the ground
/// truth and each method) reads, so it counts once: the chart's analytic field and the display
/// stack make the sources' reads far cheaper than the generic tracer the note assumes.
pub fn study_rays(study: &Study, display: &Display, chart: &Chart) -> u64 {
    let lcd = display.lcd.pixel_count() as u64;
    let nd = study.depths.len() as u64;
    let display_rays: u64 = study
        .methods
        .iter()
        .map(|m| match m {
            crate::render::Method::LensletAverage { grid } => (*grid as u64).pow(2),
            _ => 1,
        })
        .fold(0u64, |a, k| a.saturating_add(lcd.saturating_mul(k)));
    let pixels: u64 = chart.patches.iter().map(|p| (p.cols * p.rows) as u64).sum();
    let per_window = [
        nd,
        study.focus_diopters.len() as u64,
        pixels,
        study.measurement.replicates as u64,
        u64::from(study.measurement.samples_per_pixel),
    ]
    .iter()
    .fold(1u64, |a, &x| a.saturating_mul(x));
    nd.saturating_mul(display_rays).saturating_add(per_window)
}

/// The rays of the turned chart `chart` on its crop `display` (as [`study_rays`]), at `focuses`
/// focuses per depth.
fn turned_rays(study: &Study, display: &Display, chart: &Chart, focuses: usize) -> u64 {
    let all = study_rays(study, display, chart);
    let nf = study.focus_diopters.len().max(1) as u64;
    let pixels: u64 = chart.patches.iter().map(|p| (p.cols * p.rows) as u64).sum();
    let per_focus = [study.depths.len() as u64, pixels, study.measurement.replicates as u64]
        .iter()
        .fold(u64::from(study.measurement.samples_per_pixel), |a, &x| a.saturating_mul(x));
    all.saturating_sub(per_focus.saturating_mul(nf.saturating_sub(focuses as u64)))
}

/// The memory a depth of the study holds at once, on `display` (the LCD crop) with `chart`'s
/// windows: every method's display image (f32 RGB) and the simulation's stack of them (at most
/// as large), and the windows' samples (f32 per replicate, image and pixel; the bands and their
/// concatenation). The other orientations run one after another: the largest counts.
pub fn study_memory(study: &Study, display: &Display, chart: &Chart) -> crate::budget::Estimate {
    let mut e = crate::budget::Estimate::default();
    let methods = study.methods.len() as u64;
    let lcd = display.lcd.pixel_count() as u64;
    e.add(
        "the display images of one depth and their stack",
        format!("the display's lcd.resolution = {:?} (the crop the chart reaches)", display.lcd.resolution),
        lcd.saturating_mul(methods),
        24,
    );
    let pixels: u64 = chart.patches.iter().map(|p| (p.cols as u64).saturating_mul(p.rows as u64)).sum();
    let per_pixel = (study.measurement.replicates as u64).saturating_mul(1 + methods).saturating_mul(2 * 4);
    e.add(
        "the windows' samples",
        format!(
            "retina.pixels_per_degree = {} with retina.window_deg and measurement.replicates",
            study.retina.pixels_per_degree
        ),
        pixels,
        per_pixel,
    );
    e
}

/// What a study runs on, before any ray is traced: the chart, the eye of every focus (its
/// accommodation solved once), the LCD crop the chart's rays reach, and each other orientation's
/// turned chart on its own crop. Building it validates the study's optics.
pub struct StudySetup {
    /// The gratings and edges at orientation 0.
    pub chart: Chart,
    /// The eye of each focus.
    pub eyes: Vec<Eye>,
    /// The display cropped to what the chart's rays reach.
    pub display: Display,
    /// The other orientations' charts, each with its crop.
    pub turned: Vec<(Chart, Display)>,
}

impl StudySetup {
    /// The setup of `study` (see the type).
    pub fn new(study: &Study) -> Result<Self> {
        let chart = Chart::of_study(study);
        let half = chart.eye_reach_tangent();
        let max_vergence = study.focus_diopters.iter().map(|d| d / 1000.0).fold(0.0, f64::max);
        let radius = 0.5 * study.pupil_diameter_mm;
        let primaries = study.display.primaries.clone().unwrap_or_default();
        let eyes: Vec<Eye> = study
            .focus_diopters
            .iter()
            .enumerate()
            .map(|(i, &focus)| {
                let mut eye = Eye::thin_lens(study.pupil_diameter_mm, Focus::Diopters(focus), 8);
                eye.retina_distance = study.retina_distance_mm;
                eye.position = study.eye_place.position;
                eye.pose = study.eye_place.pose;
                eye.optics = EyeOptics::build(
                    &study.eye_optics,
                    &eye.aperture,
                    eye.retina_distance,
                    &primaries,
                    half.length() * 1.02,
                    &study.source,
                    &format!("focus_diopters[{i}]"),
                )?;
                Ok(eye)
            })
            .collect::<Result<_>>()?;
        // A schematic eye's rays leave the thin lens's bound by its aberrations: a wide margin
        // (the crop only saves display-image pixels). Diffraction bends rays by angles of a few
        // lambda / aperture, with a thin tail: the crop keeps 200 lambda / aperture at the
        // reddest visible wavelength (the Airy and sinc^2 tails beyond hold under 0.1% of the
        // light).
        let diffraction = if study.eye_optics.diffraction.is_on() {
            let cell = crate::optics::diffraction::ApertureShape::of_lattice(&study.display.lenslets);
            let pupil = if radius > 0.0 { 780e-6 / (2.0 * radius) } else { 0.0 };
            let lenslet = if study.eye_optics.diffraction.lenslets() { cell.angle(780.0) } else { 0.0 };
            DVec2::splat(200.0 * pupil.max(lenslet))
        } else {
            DVec2::ZERO
        };
        let schematic = eyes.iter().any(|e| e.optics.as_ref().is_some_and(|o| o.schematic().is_some()));
        let frame = study.eye_place.frame();
        let crop = |half: DVec2| {
            let (half, radius, vergence) = if schematic {
                (half * 1.25 + 0.02 + diffraction, radius * 1.3, max_vergence + 0.003)
            } else {
                (half + diffraction, radius, max_vergence)
            };
            match &frame {
                None => crop_display(&study.display, half, radius, vergence),
                Some(f) => crop_display_seen(&study.display, half, radius, vergence, f),
            }
        };
        let display = crop(half);
        // The other orientations: the gratings turned about the axis, each on its own display
        // images.
        let turned: Vec<(Chart, Display)> = study.orientations_deg[1..]
            .iter()
            .map(|&o| {
                let c = chart.turned(o);
                let d = crop(c.eye_reach_tangent());
                (c, d)
            })
            .collect();
        Ok(Self { chart, eyes, display, turned })
    }

    /// The study's peak memory: its largest orientation's ([`study_memory`]).
    pub fn memory(&self, study: &Study) -> crate::budget::Estimate {
        let mut estimate = study_memory(study, &self.display, &self.chart);
        for (c, d) in &self.turned {
            let e = study_memory(study, d, c);
            if e.bytes() > estimate.bytes() {
                estimate = e;
            }
        }
        estimate
    }

    /// The rays the whole study traces.
    pub fn rays(&self, study: &Study) -> u64 {
        let turned_focuses = if study.orientations_through_focus { study.focus_diopters.len() } else { 1 };
        self.turned.iter().fold(study_rays(study, &self.display, &self.chart), |a, (c, d)| {
            a.saturating_add(turned_rays(study, d, c, turned_focuses))
        })
    }
}

/// Runs `study`; progress bars on stderr unless `quiet`. Its memory is estimated from the
/// settings ([`study_memory`]) and refused over the budget before anything large is allocated.
pub fn run_study(study: &Study, quiet: bool) -> Result<StudyResults> {
    let t = Instant::now();
    let setup = StudySetup::new(study)?;
    setup.memory(study).check_memory(&crate::budget::memory_budget(), &study.source)?;
    crate::long_run::announce(setup.rays(study));
    let StudySetup { chart, eyes, display, turned } = setup;
    let radius = 0.5 * study.pupil_diameter_mm;
    let sources = source_names(study);
    let (nd, nf, nq) = (study.depths.len(), study.focus_diopters.len(), study.frequencies_cpd.len());
    let ns = sources.len();
    // Turned gratings are measured with the eye on the content, or at every focus.
    let turned_focuses = if study.orientations_through_focus { nf } else { 1 };
    let mut timings = vec![Timing { stage: "chart and LCD crop".into(), seconds: t.elapsed().as_secs_f64() }];

    // PupilCenter renders for the pupil the study's tracking says (the origin by default).
    let settings = DisplayRenderSettings { eye_position: study.eye_place.pupil_center, ..Default::default() };
    // A study states no [optimize]: OPT trains on the paper's eye states.
    let training =
        study.methods.contains(&Method::Optimized).then(|| Optimization::paper_default(settings.eye_position));
    let display_rows = display.lcd.rows() + turned.iter().map(|(_, d)| d.lcd.rows()).sum::<usize>();
    let display_bar = Progress::new((nd * study.methods.len() * display_rows) as u64, "display images", quiet);
    let turned_steps: u64 = turned.iter().map(|(c, _)| progress_steps(c)).sum::<u64>() * turned_focuses as u64;
    let measure_bar = Progress::new(nd as u64 * (nf as u64 * progress_steps(&chart) + turned_steps), "eye rays", quiet);
    let (mut t_display, mut t_measure, mut t_analysis) = (0.0, 0.0, 0.0);
    let (mut t_turned_display, mut t_turned_measure) = (0.0, 0.0);
    let empty = vec![vec![vec![Value::NAN; nq]; nf]; nd];
    let mut grating = vec![empty.clone(); ns];
    let mut oriented: Vec<OrientedGratings> = turned
        .iter()
        .map(|(c, _)| OrientedGratings { orientation_deg: c.orientation_deg, grating: vec![empty.clone(); ns] })
        .collect();
    let mut edge = vec![empty; ns];
    let mut mtf50 = vec![vec![vec![Value::NAN; nf]; nd]; ns];
    let reps = study.measurement.replicates;
    let spp = study.measurement.samples_per_pixel;
    let (mut eye_rays, mut turned_eye_rays) = (0u64, 0u64);
    let rays_of = |windows: &[WindowSamples]| -> u64 {
        windows.iter().map(|w| (w.cols * w.rows * reps) as u64 * u64::from(spp)).sum::<u64>()
    };
    let grey = Grey::of_display(study.measurement.channels, &display);
    for (di, depth) in study.depths.iter().enumerate() {
        let field = ChartField { chart: &chart, depth: depth.mm };
        let t = Instant::now();
        let stack = render_stack(study, &display, (&settings, training.as_ref()), &field, &display_bar)?;
        t_display += t.elapsed().as_secs_f64();
        for (fi, eye) in eyes.iter().enumerate() {
            let t = Instant::now();
            let source = DisplaySource::new(&display, eye, &field, &stack);
            let sampler = Sampler::new(study.measurement.seed, (di * nf + fi) as u64, Some(radius));
            let windows = measure_windows_as(&source, &sampler, &chart, (reps, spp), grey, &measure_bar);
            measure_bar.check()?;
            eye_rays += rays_of(&windows);
            t_measure += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let per_source = analyse_windows(study, &chart, &windows, ns);
            for (k, (g, e, m50)) in per_source.into_iter().enumerate() {
                grating[k][di][fi] = g;
                edge[k][di][fi] = e;
                mtf50[k][di][fi] = m50;
            }
            t_analysis += t.elapsed().as_secs_f64();
        }
        drop(stack);
        // The turned charts at this depth: their own display images, the eye on the content (or
        // at every focus); sample streams after every 0-degree one.
        let content_focus = study.focus_index(depth.diopters).expect("content depths are measured focuses");
        for (ti, (tchart, tdisplay)) in turned.iter().enumerate() {
            let field = ChartField { chart: tchart, depth: depth.mm };
            let t = Instant::now();
            let stack = render_stack(study, tdisplay, (&settings, training.as_ref()), &field, &display_bar)?;
            t_turned_display += t.elapsed().as_secs_f64();
            for (fi, eye) in eyes.iter().enumerate() {
                if !study.orientations_through_focus && fi != content_focus {
                    continue;
                }
                let t = Instant::now();
                let source = DisplaySource::new(tdisplay, eye, &field, &stack);
                let stream = ((1 + ti) * nd * nf + di * nf + fi) as u64;
                let sampler = Sampler::new(study.measurement.seed, stream, Some(radius));
                let windows = measure_windows_as(&source, &sampler, tchart, (reps, spp), grey, &measure_bar);
                measure_bar.check()?;
                turned_eye_rays += rays_of(&windows);
                t_turned_measure += t.elapsed().as_secs_f64();
                let t = Instant::now();
                for (k, (g, _, _)) in analyse_windows(study, tchart, &windows, ns).into_iter().enumerate() {
                    oriented[ti].grating[k][di][fi] = g;
                }
                t_analysis += t.elapsed().as_secs_f64();
            }
        }
    }
    display_bar.finish();
    measure_bar.finish();
    let seconds = StageSeconds {
        display: t_display,
        measure: t_measure,
        turned_display: t_turned_display,
        turned_measure: t_turned_measure,
        analysis: t_analysis,
    };
    stage_timings(study, &display, &turned, (eye_rays, turned_eye_rays), &seconds, &mut timings);
    let eye_rays = eye_rays + turned_eye_rays;
    Ok(StudyResults {
        study: study.clone(),
        sources,
        chart,
        lcd_crop: display.lcd.resolution,
        grating,
        oriented,
        edge,
        mtf50,
        timings,
        eye_rays,
    })
}

/// Every method's display image of `field` on `display`, packed for the simulation (the images
/// themselves are dropped once packed). `opt` is the render settings and OPT's training states.
fn render_stack(
    study: &Study,
    display: &Display,
    opt: (&DisplayRenderSettings, Option<&Optimization>),
    field: &ChartField,
    bar: &Progress,
) -> Result<DisplayStack> {
    let images: Vec<RgbImage> = study
        .methods
        .iter()
        .map(|&m| crate::methods::render(display, m, opt.0, opt.1, field, bar).map(|r| r.0))
        .collect::<Result<_>>()?;
    let refs: Vec<&RgbImage> = images.iter().collect();
    DisplayStack::new(display, &refs)
}

/// Each source's measurements in `chart`'s windows: the grating modulations (per study
/// frequency; in its own frame every grating is vertical bars), the edge's MTF at those
/// frequencies and its MTF50 (NaN where the chart has no edge).
fn analyse_windows(
    study: &Study,
    chart: &Chart,
    windows: &[WindowSamples],
    sources: usize,
) -> Vec<(Vec<Value>, Vec<Value>, Value)> {
    let (nq, ppd) = (study.frequencies_cpd.len(), study.retina.pixels_per_degree);
    (0..sources)
        .into_par_iter()
        .map(|k| {
            let mut g = vec![Value::NAN; nq];
            let mut e = (g.clone(), Value::NAN);
            for (p, w) in chart.patches.iter().zip(windows) {
                match p.pattern {
                    Pattern::Grating { frequency_cpd } => {
                        let qi = study.frequency_index(frequency_cpd).expect("chart frequencies are the study's");
                        g[qi] = grating_value(w, k, frequency_cpd, ppd, chart.contrast);
                    }
                    Pattern::Edge { .. } => e = edge_values(w, k, &study.frequencies_cpd, ppd),
                }
            }
            (g, e.0, e.1)
        })
        .collect()
}

/// The seconds of each stage of a study.
struct StageSeconds {
    display: f64,
    measure: f64,
    turned_display: f64,
    turned_measure: f64,
    analysis: f64,
}

/// The study's stage timings after the chart's: display images, eye rays (their count in
/// millions), the turned charts' if any, and the analysis.
fn stage_timings(
    study: &Study,
    display: &Display,
    turned: &[(Chart, Display)],
    (eye_rays, turned_eye_rays): (u64, u64),
    seconds: &StageSeconds,
    timings: &mut Vec<Timing>,
) {
    let (t_display, t_measure, t_turned_display, t_turned_measure, t_analysis) =
        (seconds.display, seconds.measure, seconds.turned_display, seconds.turned_measure, seconds.analysis);
    timings.push(Timing {
        stage: format!(
            "display images ({} x {} LCD pixels, {} per depth)",
            display.lcd.columns(),
            display.lcd.rows(),
            study.methods.len()
        ),
        seconds: t_display,
    });
    timings.push(Timing { stage: format!("eye rays ({:.0} M)", eye_rays as f64 / 1e6), seconds: t_measure });
    if let Some((_, d)) = turned.iter().max_by_key(|(_, d)| d.lcd.pixel_count()) {
        timings.push(Timing {
            stage: format!(
                "display images of the turned charts ({} per depth, up to {} x {} LCD pixels)",
                turned.len() * study.methods.len(),
                d.lcd.columns(),
                d.lcd.rows()
            ),
            seconds: t_turned_display,
        });
        timings.push(Timing {
            stage: format!("eye rays of the turned charts ({:.0} M)", turned_eye_rays as f64 / 1e6),
            seconds: t_turned_measure,
        });
    }
    timings.push(Timing { stage: "grating and edge analysis".into(), seconds: t_analysis });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::Rng;
    use crate::measure::estimator::EyeToLcd;

    #[test]
    fn the_crop_holds_every_lcd_point_the_eye_rays_reach_on_the_full_grid() {
        let full = Display::paper();
        let half = DVec2::new(0.08, 0.05);
        let crop = crop_display(&full, half, 2.5, 0.004);
        // Half-width 2.5 + 0.09 x 20 mm at the lenslets, plus (0.09 + 0.6 / 6.427) x 6.316 mm: 5.46 mm.
        assert!(crop.lcd.columns() == 1096 && crop.lcd.columns().is_multiple_of(2), "{:?}", crop.lcd);
        assert_eq!(crop.lcd.pixel_pitch(), full.lcd.pixel_pitch());
        // Pixel centres coincide with the full panel's.
        let (oc, or) = ((full.lcd.columns() - crop.lcd.columns()) / 2, (full.lcd.rows() - crop.lcd.rows()) / 2);
        assert!((crop.lcd.pixel_center(0, 0) - full.lcd.pixel_center(or, oc)).length() < 1e-12);
        let mut rng = Rng(7);
        for _ in 0..100_000 {
            let focus = rng.range(0.0, 4.0);
            let eye = Eye::thin_lens(5.0, Focus::Diopters(focus), 8);
            let to = EyeToLcd::new(&crop, &eye);
            let t = DVec2::new(rng.range(-half.x, half.x), rng.range(-half.y, half.y));
            let p = loop {
                let p = DVec2::new(rng.range(-2.5, 2.5), rng.range(-2.5, 2.5));
                if p.length() <= 2.5 {
                    break p;
                }
            };
            assert!(to.pixel_index(t, p).is_some(), "tangent {t} pupil {p} focus {focus}");
        }
    }
}
