//! The pipeline's stages as Python functions (Sec. 3-4, Table 1): the display image, the
//! perceived image, the ground truth, a whole assessment, and the comparison of two images.
//! Each calls the same library functions as the CLI command of the same name, with the GIL
//! released, on the global thread pool or one of `threads` workers, reporting progress to an
//! optional Python callable.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use glam::DVec3;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use inimtrace::experiment::{assess_images, Assessment, RunOptions, Score};
use inimtrace::io::exr::ExrCompression;
use inimtrace::metrics::{self, SsimConstants};
use inimtrace::optimize::Optimization;
use inimtrace::progress::{with_sink, Progress, ProgressSink};
use inimtrace::render::retina::simulate as simulate_images;
use inimtrace::render::{ground_truth as ground_truth_image, with_fields};
use inimtrace::render::{BackendChoice, DisplayRenderSettings, Method};
use inimtrace::resolution::command::{execute, ResolutionCommand};

use crate::convert::{depth_to_numpy, image_to_numpy, numpy_to_image, overrides, to_py};
use crate::errors::{value_error, IntoPy};
use crate::objects::{PyDisplay, PyExperiment, PyEye, PyScene};

/// The progress sink of every call: reports progress to an optional Python callable
/// `callback(stage, done, total)`, taking the GIL only for the call (at most every 0.1 s per
/// stage, see `inimtrace::progress`), and cancels the run once the caller's thread saw Ctrl-C.
/// The first exception the callable raises is kept, later reports are dropped, and the exception
/// is raised when the work ends.
struct PySink {
    callback: Option<Py<PyAny>>,
    error: Mutex<Option<PyErr>>,
    cancelled: AtomicBool,
}

impl ProgressSink for PySink {
    fn update(&self, stage: &str, done: u64, total: u64) {
        let Some(callback) = &self.callback else { return };
        let Ok(mut error) = self.error.lock() else { return };
        if error.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = callback.call1(py, (stage, done, total)) {
                *error = Some(e);
            }
        });
    }

    fn cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }
}

/// How often the calling thread looks for Ctrl-C (Python's signal handlers) while a call works.
const SIGNAL_INTERVAL: Duration = Duration::from_millis(50);

/// The stack of the thread that runs a call's work: the size of a main thread's (the work ran
/// on the caller's thread before, and deep inputs such as nested YAML recurse there).
const WORK_STACK: usize = 8 << 20;

/// Wakes the calling thread when the work's thread ends (normally or by a panic).
struct WakeOnDrop(std::thread::Thread);

impl Drop for WakeOnDrop {
    fn drop(&mut self) {
        self.0.unpark();
    }
}

/// Runs `work` with the GIL released: on a pool of `threads` workers (`None`: the global pool,
/// all cores), with `progress` receiving the progress of every stage. The work runs on a thread
/// of its own while the calling thread, when it is Python's main thread (the only one that runs
/// signal handlers), runs them every [`SIGNAL_INTERVAL`]:
/// Ctrl-C (or any handler that raises) cancels the work through its progress sink, which the
/// library's loops ask at each row, band or tile, and the handler's exception
/// (`KeyboardInterrupt`) is raised as soon as the work has stopped; its partial results are
/// dropped.
fn detached<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
    work: impl FnOnce() -> inimtrace::Result<T> + Send,
) -> PyResult<T> {
    let pool = match threads {
        None => None,
        Some(n) => {
            let n = inimtrace::budget::check_threads("threads", n).map_err(value_error)?;
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| value_error(format!("cannot start {n} threads: {e}")))?,
            )
        }
    };
    if let Some(cb) = progress.as_ref() {
        if !cb.bind(py).is_callable() {
            return Err(value_error("progress must be a callable progress(stage, done, total) or None"));
        }
    }
    let sink = Arc::new(PySink { callback: progress, error: Mutex::new(None), cancelled: AtomicBool::new(false) });
    let installed: Arc<dyn ProgressSink> = sink.clone();
    // Python runs signal handlers on its main thread only: elsewhere the caller just waits.
    let threading = py.import("threading")?;
    let main = threading.call_method0("current_thread")?.is(&threading.call_method0("main_thread")?);
    let caller = std::thread::current();
    let mut interrupt = None;
    let joined = std::thread::scope(|scope| -> PyResult<_> {
        let worker = std::thread::Builder::new()
            .name("inimtrace".into())
            .stack_size(WORK_STACK)
            .spawn_scoped(scope, move || {
                let _wake = WakeOnDrop(caller);
                let run = move || with_sink(installed, work);
                match pool {
                    Some(pool) => pool.install(run),
                    None => run(),
                }
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start a thread for the work: {e}")))?;
        while !worker.is_finished() {
            if !main {
                // Parked with a timeout: the wake-up may come just before the thread counts as
                // finished. The GIL stays released throughout.
                py.detach(|| {
                    while !worker.is_finished() {
                        std::thread::park_timeout(SIGNAL_INTERVAL);
                    }
                });
                continue;
            }
            py.detach(|| std::thread::park_timeout(SIGNAL_INTERVAL));
            if interrupt.is_none() {
                if let Err(e) = py.check_signals() {
                    sink.cancelled.store(true, Ordering::Relaxed);
                    interrupt = Some(e);
                }
            }
        }
        Ok(worker.join())
    })?;
    let result = joined.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
    if let Some(e) = interrupt {
        return Err(e);
    }
    if let Some(e) = sink.error.lock().ok().and_then(|mut e| e.take()) {
        return Err(e);
    }
    result.py_err()
}

fn parse_backend(backend: &str) -> PyResult<BackendChoice> {
    backend.parse().map_err(value_error)
}

fn parse_compression(name: &str) -> PyResult<ExrCompression> {
    use ExrCompression::*;
    [None, Rle, Zips, Zip, Piz, Pxr24].into_iter().find(|c| c.name().eq_ignore_ascii_case(name.trim())).ok_or_else(
        || value_error(format!("unknown exr_compression `{name}`: expected none, rle, zips, zip, piz or pxr24")),
    )
}

/// Refuses an image that would not fit in memory before anything is allocated (the CLI's check).
fn check_memory(what: &str, setting: &str, pixels: usize, bytes_each: u64, source: &str) -> PyResult<()> {
    inimtrace::budget::check_buffer(what, setting, pixels, bytes_each, source).py_err()
}

/// The display image of `scene` on `display` by `method` ("LC", "PC", "LA", "LA<k>"), as
/// `inimtrace render-display`: a `(rows, columns, 3)` float32 array, and with `depth=True` also
/// the `(rows, columns)` hit distances (mm; None when the backend knows no depths).
#[pyfunction]
#[pyo3(signature = (scene, display, method="LA", backend="auto", *, samples_per_pixel=1, reference_plane=0.0,
    eye_position=(0.0, 0.0, 0.0), depth=false, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn render_display<'py>(
    py: Python<'py>,
    scene: &PyScene,
    display: &PyDisplay,
    method: &str,
    backend: &str,
    samples_per_pixel: usize,
    reference_plane: f64,
    eye_position: (f64, f64, f64),
    depth: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let method: Method = method.parse().map_err(value_error)?;
    let backend = parse_backend(backend)?;
    let (scene, display) = (&scene.inner, &display.inner);
    inimtrace::optics::limits::REFERENCE_PLANE_Z
        .check("render_display()", "reference_plane", reference_plane)
        .py_err()?;
    let eye_position = DVec3::new(eye_position.0, eye_position.1, eye_position.2);
    if !eye_position.is_finite() {
        return Err(value_error("eye_position must be three finite numbers (mm)"));
    }
    check_memory(
        "the display image and its depth plane",
        &format!("lcd.resolution = {:?} of the display", display.lcd.resolution),
        display.lcd.pixel_count(),
        28,
        "render_display()",
    )?;
    let settings = DisplayRenderSettings { samples_per_pixel, reference_plane_z: reference_plane, eye_position };
    let (img, z) = detached(py, threads, progress, || {
        // Without an experiment, OPT trains on the paper's eye states around the eye position.
        let training = (method == Method::Optimized).then(|| Optimization::paper_default(eye_position));
        with_fields(scene, backend, |fields| {
            let p = inimtrace::methods::progress(display, method, training.as_ref(), true);
            let (img, z, _) =
                inimtrace::methods::render(display, method, &settings, training.as_ref(), fields.with_depth, &p)?;
            p.finish();
            Ok((img, z))
        })
    })?;
    let (rows, columns) = (img.height, img.width);
    let img = image_to_numpy(py, img)?.into_any();
    if !depth {
        return Ok(img);
    }
    let z = match z {
        Some(z) => depth_to_numpy(py, z, rows, columns)?.into_any(),
        None => py.None().into_bound(py),
    };
    Ok((img, z).into_pyobject(py)?.into_any())
}

/// What `eye` perceives of `display_image` (a `(rows, columns, 3)` float32 array of the LCD's
/// resolution, rendered here or anywhere else), as `inimtrace simulate`: a `(n, n, 3)` array.
#[pyfunction]
#[pyo3(signature = (display_image, display, eye, *, threads=None, progress=None))]
pub fn simulate<'py>(
    py: Python<'py>,
    display_image: &Bound<'py, PyAny>,
    display: &PyDisplay,
    eye: &PyEye,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let display = &display.inner;
    let img = numpy_to_image(
        display_image,
        "display_image",
        Some((display.lcd.rows(), display.lcd.columns())),
        "simulate()",
    )?;
    let n = eye.retina.resolution;
    check_memory("the retinal image", "retina", n * n, 24, "simulate()")?;
    let e = &eye.for_display(Some(display))?;
    let retina = &eye.retina;
    let mut sims = detached(py, threads, progress, || {
        let p = Progress::new(n as u64, "simulate", true);
        let sims = simulate_images(display, e, retina, &[&img], &p)?;
        p.finish();
        Ok(sims)
    })?;
    Ok(image_to_numpy(py, sims.remove(0))?.into_any())
}

/// The ground-truth retinal image of `scene` seen by `eye`, as `inimtrace ground-truth`: a
/// `(n, n, 3)` float32 array. A polychromatic schematic eye takes `display`'s primaries when it
/// is given (else the default primaries).
#[pyfunction]
#[pyo3(signature = (scene, eye, backend="auto", *, display=None, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn ground_truth<'py>(
    py: Python<'py>,
    scene: &PyScene,
    eye: &PyEye,
    backend: &str,
    display: Option<&PyDisplay>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let backend = parse_backend(backend)?;
    let n = eye.retina.resolution;
    check_memory("the retinal image", "retina", n * n, 24, "ground_truth()")?;
    let e = &eye.for_display(display.map(|d| &d.inner))?;
    let (scene, retina) = (&scene.inner, &eye.retina);
    let img = detached(py, threads, progress, || {
        with_fields(scene, backend, |fields| {
            let p = Progress::new(n as u64, "ground truth", true);
            let img = ground_truth_image(e, retina, fields.shade, &p);
            p.finish();
            Ok(img)
        })
    })?;
    Ok(image_to_numpy(py, img)?.into_any())
}

/// One score as a flat record (a row of a `pandas.DataFrame`): the mean over R, G, B and each
/// channel, with the 95% half-widths (None for the grid estimator).
fn score_record<'py>(py: Python<'py>, experiment: &str, s: &Score) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("experiment", experiment)?;
    d.set_item("method", &s.method)?;
    d.set_item("eye_case", &s.eye_case)?;
    d.set_item("psnr_db", s.psnr.mean)?;
    d.set_item("psnr_ci95_db", s.psnr.ci95)?;
    d.set_item("ssim", s.ssim.mean)?;
    d.set_item("ssim_ci95", s.ssim.ci95)?;
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        d.set_item(format!("psnr_db_{name}"), s.psnr.channels[c])?;
        d.set_item(format!("psnr_ci95_db_{name}"), s.psnr.channels_ci95.map(|h| h[c]))?;
        d.set_item(format!("ssim_{name}"), s.ssim.channels[c])?;
        d.set_item(format!("ssim_ci95_{name}"), s.ssim.channels_ci95.map(|h| h[c]))?;
    }
    d.set_item("samples_per_pixel", s.samples_per_pixel)?;
    d.set_item("replicates", s.replicates)?;
    d.set_item("target_met", s.target_met)?;
    // The scores `[measurement] scores` names beyond PSNR and SSIM: `cvvdp`, `cvvdp_ci95`,
    // `cvvdp_noise_bias`, `flip`, ..., `psnr_luminance_db`, ... (absent when not named).
    perceptual_items(&d, &s.perceptual)?;
    Ok(d)
}

/// The extra scores as record items: `<name>` (`psnr_luminance_db` for the luminance PSNR),
/// `<name>_ci95` and `<name>_noise_bias` (None where unknown).
fn perceptual_items(d: &Bound<'_, PyDict>, p: &inimtrace::perception::PerceptualScores) -> PyResult<()> {
    for (n, e) in &p.0 {
        let key = match n {
            inimtrace::perception::ScoreName::PsnrLuminance => "psnr_luminance_db".to_string(),
            other => other.name().replace('-', "_"),
        };
        d.set_item(&key, e.value)?;
        d.set_item(format!("{key}_ci95"), e.ci95)?;
        d.set_item(format!("{key}_noise_bias"), e.noise_bias)?;
    }
    Ok(())
}

/// The scorer of `compare(scores=...)` for `size` images (`None` when no extra score is named).
fn compare_perception(
    scores: Option<Vec<String>>,
    peak_white: f64,
    black: f64,
    ppd: Option<f64>,
    size: (usize, usize),
) -> PyResult<Option<inimtrace::perception::Perception>> {
    use inimtrace::perception::{DisplayLuminance, ExtraScores, Perception, ScoreName, Viewing};
    let names: Vec<ScoreName> = scores
        .unwrap_or_default()
        .iter()
        .map(|n| n.parse::<ScoreName>().map_err(|e| value_error(format!("compare(): scores: {e}"))))
        .collect::<PyResult<_>>()?;
    let extra = ExtraScores::from_names(&names, "compare()", "scores").map_err(|e| value_error(e.to_string()))?;
    if extra.is_empty() {
        return Ok(None);
    }
    let ppd = match (ppd, extra.any_perceptual()) {
        (Some(p), _) => p,
        (None, false) => 1.0,
        (None, true) => return Err(value_error("compare(): ppd: cvvdp and flip need the images' pixels per degree")),
    };
    let viewing =
        Viewing { luminance: DisplayLuminance { peak_white, black, ..Default::default() }, pixels_per_degree: ppd };
    viewing.validate("compare()", "").map_err(|e| value_error(e.to_string()))?;
    Perception::new(&extra, &viewing, inimtrace::perception::BT709_LUMINANCE, size, None).map(Some).py_err()
}

/// Runs `experiment` as `inimtrace assess` does (the same code path), and with `out` writes the
/// same files there. Returns a dict: `scores` (records), `stages` (records), `images` and
/// `depths` (arrays by file stem: `display_LA`, `gt_Pin`, `sim_LA_Pin`), `report` (what
/// `results.json` holds).
#[pyfunction]
#[pyo3(name = "_assess", signature = (experiment, out=None, backend="auto", *, exr_compression="zip", threads=None,
    progress=None))]
pub fn assess<'py>(
    py: Python<'py>,
    experiment: &PyExperiment,
    out: Option<PathBuf>,
    backend: &str,
    exr_compression: &str,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let backend = parse_backend(backend)?;
    let exr_compression = parse_compression(exr_compression)?;
    let exp = &experiment.inner;
    let options = RunOptions { quiet: true, backend, exr_compression, force: false, keep_replicates: false };
    let Assessment { report, displays, depths, ground_truths, perceived } =
        detached(py, threads, progress, || assess_images(exp, out.as_deref(), options))?;

    let result = PyDict::new(py);
    let scores = PyList::empty(py);
    for s in &report.scores {
        scores.append(score_record(py, &report.experiment, s)?)?;
    }
    result.set_item("scores", scores)?;
    let stages = PyList::empty(py);
    for st in &report.stages {
        let d = PyDict::new(py);
        d.set_item("stage", &st.stage)?;
        d.set_item("method", &st.method)?;
        d.set_item("eye_case", &st.eye_case)?;
        d.set_item("seconds", st.seconds)?;
        stages.append(d)?;
    }
    result.set_item("stages", stages)?;
    let images = PyDict::new(py);
    let depth_planes = PyDict::new(py);
    for ((m, img), depth) in exp.methods.iter().zip(displays).zip(depths) {
        let stem = format!("display_{}", m.name());
        let (rows, columns) = (img.height, img.width);
        images.set_item(&stem, image_to_numpy(py, img)?)?;
        match depth {
            Some(z) => depth_planes.set_item(&stem, depth_to_numpy(py, z, rows, columns)?)?,
            None => depth_planes.set_item(&stem, py.None())?,
        }
    }
    for ((case, gt), sims) in exp.cases.iter().zip(ground_truths).zip(perceived) {
        images.set_item(format!("gt_{}", case.name), image_to_numpy(py, gt)?)?;
        for (m, sim) in exp.methods.iter().zip(sims) {
            images.set_item(format!("sim_{}_{}", m.name(), case.name), image_to_numpy(py, sim)?)?;
        }
    }
    result.set_item("images", images)?;
    result.set_item("depths", depth_planes)?;
    result.set_item("report", to_py(py, &report)?)?;
    result.set_item("out", out.map(|p| p.display().to_string()))?;
    Ok(result)
}

/// Whether `compare()` on plain images has said that sampling noise biases their scores.
static NOISE_NOTED: AtomicBool = AtomicBool::new(false);

/// PSNR and SSIM of two `(rows, columns, 3)` float32 arrays of the same shape, as
/// `inimtrace compare --json` (an infinite PSNR, identical channels, stays `inf`); of two
/// replicate sets `(replicates, rows, columns, 3)` (`read_replicates` of the files `assess
/// --keep-replicates` writes), the table's de-biased scores with their 95% intervals.
/// With `scores` (`psnr-luminance`, `cvvdp`, `flip`) also those, `a` the reference and `b`
/// the test, seen on a display of `peak_white` and `black` cd/m^2 at `ppd` pixels per degree.
#[pyfunction]
#[pyo3(signature = (a, b, ssim="wang2004", *, scores=None, peak_white=100.0, black=0.1, ppd=None))]
#[allow(clippy::too_many_arguments)]
pub fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    ssim: &str,
    scores: Option<Vec<String>>,
    peak_white: f64,
    black: f64,
    ppd: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let constants: SsimConstants = ssim.parse().map_err(|e: inimtrace::Error| value_error(e.to_string()))?;
    let ndim = |o: &Bound<'py, PyAny>| o.getattr("ndim").ok().and_then(|n| n.extract::<usize>().ok());
    let scorer = |size| compare_perception(scores.clone(), peak_white, black, ppd, size);
    if ndim(a) == Some(4) || ndim(b) == Some(4) {
        return compare_sets(py, a, b, constants, &scorer);
    }
    let ia = numpy_to_image(a, "a", None, "compare()")?;
    let ib = numpy_to_image(b, "b", Some((ia.height, ia.width)), "compare()")?;
    if !NOISE_NOTED.swap(true, Ordering::SeqCst) {
        let warning = py.get_type::<pyo3::exceptions::PyUserWarning>();
        PyErr::warn(
            py,
            &warning,
            c"compare() scores the images as they are: if they are estimates with sampling noise (inimtrace's \
              converged images are means of replicates), the noise biases PSNR and SSIM down. For the table's \
              de-biased scores, compare two replicate sets: read_replicates() of the files assess --keep-replicates \
              writes (said once per session)",
            1,
        )?;
    }
    let perception = scorer((ia.width, ia.height))?;
    let (p, s, extra) = detached(py, None, None, || {
        let extra = match &perception {
            Some(q) => q.score_images(&ib, &ia)?,
            None => Default::default(),
        };
        Ok((metrics::psnr(&ia, &ib)?, metrics::ssim(&ia, &ib, constants)?, extra))
    })?;
    let channels = |v: [f64; 3], mean: f64| -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, x) in ["R", "G", "B"].iter().zip(v) {
            d.set_item(*name, x)?;
        }
        d.set_item("mean", mean)?;
        // One schema with replicate sets': no interval for plain images.
        d.set_item("ci95", py.None())?;
        d.set_item("channels_ci95", py.None())?;
        Ok(d)
    };
    let out = PyDict::new(py);
    out.set_item("width", ia.width)?;
    out.set_item("height", ia.height)?;
    out.set_item("replicate_sets", false)?;
    out.set_item("replicates", py.None())?;
    out.set_item("psnr_db", channels(p.channels, p.mean)?)?;
    out.set_item("ssim", channels(s.channels, s.mean)?)?;
    out.set_item("ssim_constants", constants.name())?;
    perceptual_items(&out, &extra)?;
    Ok(out)
}

/// [`compare`] of two replicate sets: the same statistics as the table (`src/measure/`).
fn compare_sets<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    constants: SsimConstants,
    scorer: &dyn Fn((usize, usize)) -> PyResult<Option<inimtrace::perception::Perception>>,
) -> PyResult<Bound<'py, PyDict>> {
    let set = |o: &Bound<'py, PyAny>, name: &str, other: &str| -> PyResult<Vec<inimtrace::raster::RgbImage>> {
        if o.getattr("ndim").ok().and_then(|n| n.extract::<usize>().ok()) != Some(4) {
            return Err(value_error(format!(
                "{other} is a replicate set (replicates, rows, columns, 3) but {name} is not: compare two replicate \
                 sets or two images"
            )));
        }
        let n = o.len()?;
        let first = o.get_item(0).ok();
        let shape = first
            .as_ref()
            .and_then(|f| f.getattr("shape").ok())
            .and_then(|s| s.extract::<(usize, usize, usize)>().ok());
        if let Some((rows, columns, _)) = shape {
            inimtrace::budget::check_buffer(
                &format!("the copy of `{name}`"),
                name,
                n.saturating_mul(rows).saturating_mul(columns),
                std::mem::size_of::<[f32; 3]>() as u64,
                "compare()",
            )
            .py_err()?;
        }
        (0..n).map(|r| numpy_to_image(&o.get_item(r)?, &format!("{name}[{r}]"), None, "compare()")).collect()
    };
    let sa = set(a, "a", "b")?;
    let sb = set(b, "b", "a")?;
    let perception = scorer((sa[0].width, sa[0].height))?;
    let (p, s, extra) = detached(py, None, None, || {
        let reps = inimtrace::io::exr_replicates::pair(("a", &sa), ("b", &sb), 1)?;
        let extra = match &perception {
            Some(q) => q.score_replicates(&reps, 1)?,
            None => Default::default(),
        };
        let (p, s) = inimtrace::measure::adaptive::estimates(&reps, constants).pop().expect("one scored image");
        Ok((p, s, extra))
    })?;
    let estimate = |e: &inimtrace::measure::stats::Estimate| -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, x) in ["R", "G", "B"].iter().zip(e.channels) {
            d.set_item(*name, x)?;
        }
        d.set_item("mean", e.mean)?;
        d.set_item("ci95", e.ci95)?;
        match e.channels_ci95 {
            Some(h) => {
                let c = PyDict::new(py);
                for (name, x) in ["R", "G", "B"].iter().zip(h) {
                    c.set_item(*name, x)?;
                }
                d.set_item("channels_ci95", c)?;
            }
            None => d.set_item("channels_ci95", py.None())?,
        }
        Ok(d)
    };
    let out = PyDict::new(py);
    out.set_item("width", sa[0].width)?;
    out.set_item("height", sa[0].height)?;
    out.set_item("replicates", sa.len())?;
    out.set_item("replicate_sets", true)?;
    out.set_item("psnr_db", estimate(&p)?)?;
    out.set_item("ssim", estimate(&s)?)?;
    out.set_item("ssim_constants", constants.name())?;
    perceptual_items(&out, &extra)?;
    Ok(out)
}

/// Reads a replicate set (`*.replicates.exr`, written by `assess --keep-replicates`) as a
/// `(replicates, rows, columns, 3)` float32 array, for [`compare`].
#[pyfunction]
pub fn read_replicates<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let images = detached(py, None, None, || {
        let n = inimtrace::io::exr_replicates::count(&path)?.ok_or_else(|| {
            inimtrace::Error::parse(&path, "is not a replicate set (parts named `replicate 0`, `replicate 1`, ...)")
        })?;
        inimtrace::io::exr_replicates::read(&path, n)
    })?;
    let (r, rows, columns) = (images.len(), images[0].height, images[0].width);
    let mut flat: Vec<f32> = Vec::with_capacity(r * rows * columns * 3);
    for img in images {
        flat.extend(img.pixels.iter().flatten());
    }
    let array = numpy::ndarray::Array4::from_shape_vec((r, rows, columns, 3), flat)
        .map_err(|e| value_error(format!("replicate set of {r} x {columns} x {rows}: {e}")))?;
    Ok(numpy::PyArray4::from_owned_array(py, array).into_any())
}

/// Reads an RGB EXR (e.g. a display image the CLI wrote) as a `(rows, columns, 3)` float32
/// array and its `Z` channel as `(rows, columns)` (None without one).
#[pyfunction]
pub fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let (img, z) = detached(py, None, None, || inimtrace::io::exr::read_rgb_depth(&path))?;
    let (rows, columns) = (img.height, img.width);
    let img = image_to_numpy(py, img)?.into_any();
    let z = match z {
        Some(z) => depth_to_numpy(py, z, rows, columns)?.into_any(),
        None => py.None().into_bound(py),
    };
    Ok((img, z).into_pyobject(py)?.into_any())
}

/// Runs a resolution study as `inimtrace resolution` does (the same code path) and writes its
/// files into `out` (default `out/resolution-<study name>`). `study`: a study TOML (`None`: the
/// built-in `studies/paper.toml`); `set`: the same overrides as `--set`. Returns a dict: `out`
/// (the folder) and `timings` (records of `stage`, `seconds`).
#[pyfunction]
#[pyo3(name = "_resolution", signature = (study=None, out=None, set=None, *, threads=None, progress=None))]
pub fn resolution<'py>(
    py: Python<'py>,
    study: Option<PathBuf>,
    out: Option<PathBuf>,
    set: Option<&Bound<'py, PyAny>>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let cmd = ResolutionCommand { study, out, overrides: overrides(set)?, quiet: true, force: false };
    // Likely unit mistakes before the run (minutes), as the CLI gives them.
    let loaded = inimtrace::resolution::command::load_study(&cmd).py_err()?;
    crate::errors::warn_all(py, &inimtrace::resolution::command::plausibility_warnings(&loaded))?;
    let run = detached(py, threads, progress, || execute(&cmd))?;
    let result = PyDict::new(py);
    result.set_item("out", run.out.display().to_string())?;
    let timings = PyList::empty(py);
    for t in &run.timings {
        let d = PyDict::new(py);
        d.set_item("stage", &t.stage)?;
        d.set_item("seconds", t.seconds)?;
        timings.append(d)?;
    }
    result.set_item("timings", timings)?;
    Ok(result)
}
