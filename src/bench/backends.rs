//! `inimtrace bench --backends`: the mesh backends side by side on mesh scenes (by default
//! `scenes/bunny.toml` and `scenes/spheres-2m.toml`): the acceleration structure's build time,
//! nearest-hit and occlusion throughput (rays per second over all threads) on the pipeline's LC
//! camera rays through the middle rows of the paper display, and the whole-process wall time of
//! one LA display image (`inimtrace render-display --method LA`, run as a child process, so that
//! start-up, scene loading, build and writing count). `--also BINARY` runs the same measurement
//! of Embree in another inimtrace binary (an Embree 3 build beside an Embree 4 one) within the
//! same run, and scores its LA image against this binary's (PSNR; `inf` when equal).
//!
//! The brute-force twin traces a fixed, smaller number of rays (its rate is still rays per
//! second) and no LA image (hours at these sizes): such cells are left empty, and say so.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::accel::brute::BruteForce;
use crate::accel::bvh::BvhIntersector;
use crate::error::{Error, Result};
use crate::io::csv_table::CsvTable;
use crate::ray::{Hit, Intersector, Ray};
use crate::render::backend::scene_meshes;

/// What a `--backends` run measures.
#[derive(Clone, Debug)]
pub struct BackendsOptions {
    /// Scene files (mesh scenes).
    pub scenes: Vec<PathBuf>,
    /// Smaller sizes (fewer rays, a smaller LCD).
    pub quick: bool,
    /// Another inimtrace binary whose Embree is measured too.
    pub also: Option<PathBuf>,
    /// Measure Embree only (what `--also` asks of the other binary).
    pub embree_only: bool,
    /// Output folder.
    pub out: PathBuf,
    /// Also write each scene's Embree input (single-precision triangles, rays and packet plan)
    /// here, as `<scene>.embree-input`, for `scripts/embree-bare.c`.
    pub embree_input: Option<PathBuf>,
}

impl BackendsOptions {
    /// LCD pixels per side of the LA display image.
    pub fn lcd_resolution(&self) -> usize {
        if self.quick {
            270
        } else {
            540
        }
    }

    /// LCD rows of camera rays for the throughput (2,160 rays per row).
    fn rows(&self) -> usize {
        if self.quick {
            8
        } else {
            64
        }
    }
}

/// One backend on one scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BackendRow {
    /// The scene file.
    pub scene: String,
    /// `embree`, `bvh` or `brute`.
    pub backend: String,
    /// What does the work: `Embree 4.4.0` (as the loaded library reports it), `inimtrace`.
    pub library: String,
    /// The binary that measured it.
    pub binary: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Seconds to build the acceleration structure (the meshes already loaded).
    pub build_s: f64,
    /// Rays traced for each throughput.
    pub rays: usize,
    /// Of them, rays that hit something (nearest-hit query).
    pub hits: usize,
    /// Nearest-hit rays per second: the median pass after the first.
    pub nearest_rays_per_s: f64,
    /// Nearest-hit rays per second in the first pass, right after the build.
    #[serde(default)]
    pub nearest_cold_rays_per_s: f64,
    /// Nearest-hit passes timed (the first included).
    #[serde(default)]
    pub nearest_passes: usize,
    /// Of them, rays occluded within 10 m (occlusion query).
    pub occluded: usize,
    /// Occlusion rays per second: the median pass after the first.
    pub occluded_rays_per_s: f64,
    /// Occlusion rays per second in the first pass.
    #[serde(default)]
    pub occluded_cold_rays_per_s: f64,
    /// Occlusion passes timed (the first included).
    #[serde(default)]
    pub occluded_passes: usize,
    /// Whole-process seconds of `render-display --method LA` (none: not feasible).
    pub la_process_s: Option<f64>,
    /// The LA image written (EXR).
    pub la_image: Option<String>,
    /// PSNR (dB) of this row's LA image against this binary's Embree image (`--also` rows;
    /// none when identical).
    pub la_psnr_vs_this_embree_db: Option<f64>,
    /// Whether that LA image equals this binary's Embree image pixel for pixel (`--also` rows).
    pub la_identical_to_this_embree: Option<bool>,
}

/// Rays the brute-force twin traces per scene: at most this many.
const BRUTE_RAYS: usize = 2_048;

/// Seconds of the first (cold) pass and the median of the passes after it, and how many passes
/// were timed in all. A pass over 138,240 rays lasts 15-50 ms on Embree: the first one right
/// after a build also pays for the build's threads winding down and the structure's first
/// touch, so one timed pass measures those as much as the traversal. After the cold pass the
/// passes repeat until at least [`MIN_PASSES`] and [`MIN_STEADY_S`] of them are timed; a cold
/// pass over [`SLOW_PASS_S`] (the brute-force twin) is the only one.
fn timed_passes(mut pass: impl FnMut() -> usize) -> (usize, f64, f64, usize) {
    let start = Instant::now();
    let count = pass();
    let cold = start.elapsed().as_secs_f64();
    if cold > SLOW_PASS_S {
        return (count, cold, cold, 1);
    }
    let mut steady: Vec<f64> = Vec::new();
    while steady.len() < MIN_PASSES || steady.iter().sum::<f64>() < MIN_STEADY_S {
        let start = Instant::now();
        let again = pass();
        steady.push(start.elapsed().as_secs_f64());
        debug_assert_eq!(again, count, "a backend answered the same rays differently in two passes");
    }
    steady.sort_by(f64::total_cmp);
    (count, cold, steady[steady.len() / 2], steady.len() + 1)
}

/// Steady passes timed after the cold one: at least this many...
const MIN_PASSES: usize = 5;
/// ...and at least this many seconds of them.
const MIN_STEADY_S: f64 = 0.5;
/// A cold pass longer than this is timed alone.
const SLOW_PASS_S: f64 = 1.0;

/// One query's throughput: what it found, and the cold and steady (median) pass seconds.
struct Timed {
    found: usize,
    cold_s: f64,
    steady_s: f64,
    passes: usize,
}

/// Traces `rays` with `backend` on all threads, in timed passes ([`timed_passes`]), for nearest
/// hits (hits found) and occlusion (rays occluded).
fn throughput<I: Intersector + Sync>(backend: &I, rays: &[Ray]) -> (Timed, Timed) {
    let nearest = timed_passes(|| {
        rays.par_chunks(2_160)
            .map(|chunk| {
                let mut found: Vec<Option<Hit>> = vec![None; chunk.len()];
                backend.intersect_many(chunk, &mut found);
                found.iter().filter(|h| h.is_some()).count()
            })
            .sum()
    });
    let occluded = timed_passes(|| rays.par_iter().filter(|r| backend.occluded(r, 1e4)).count());
    let timed = |(found, cold_s, steady_s, passes)| Timed { found, cold_s, steady_s, passes };
    (timed(nearest), timed(occluded))
}

/// The Embree library this binary loads (`Embree 4.4.0`).
fn embree_library() -> String {
    crate::version::embree_loaded()
}

/// Runs `render-display --method LA` of `scene` on `backend` with `binary`; whole-process seconds.
fn la_image(binary: &Path, scene: &Path, backend: &str, lcd: usize, out: &Path) -> Result<f64> {
    let start = Instant::now();
    let output = Command::new(binary)
        .args(["render-display", "--quiet", "--method", "LA", "--backend", backend, "--scene"])
        .arg(scene)
        .arg("--set")
        .arg(format!("display.lcd.resolution=[{lcd},{lcd}]"))
        .arg("--out")
        .arg(out)
        .output()
        .map_err(|e| Error::invalid(binary.display().to_string(), "--also", format!("cannot run it: {e}")))?;
    let seconds = start.elapsed().as_secs_f64();
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        return Err(Error::invalid(
            binary.display().to_string(),
            "render-display",
            format!("failed on {}: {}", scene.display(), stderr.trim()),
        ));
    }
    Ok(seconds)
}

/// Measures every backend (or Embree only) on one scene.
fn measure_scene(opts: &BackendsOptions, path: &Path, me: &Path) -> Result<Vec<BackendRow>> {
    let scene = crate::io::scene_file::load_scene(&path.to_string_lossy(), Path::new(""))?;
    let owned = scene_meshes(&scene);
    let meshes: Vec<(u32, &crate::scene::mesh::Mesh)> = owned.iter().map(|(i, m)| (*i, m.as_ref())).collect();
    let rays = crate::fixtures::bunny_display_rays(opts.rows());
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut rows = Vec::new();
    let mut push = |backend: &str, library: String, triangles: usize, build_s: f64, traced: &[Ray], t| {
        let (nearest, occlusion): (Timed, Timed) = t;
        let rate = |s: f64| traced.len() as f64 / s.max(1e-12);
        let feasible = backend != "brute";
        let image = opts.out.join(format!("la_{stem}_{backend}.exr"));
        let la = if feasible { Some(la_image(me, path, backend, opts.lcd_resolution(), &image)?) } else { None };
        rows.push(BackendRow {
            scene: path.display().to_string(),
            backend: backend.to_string(),
            library,
            binary: me.display().to_string(),
            triangles,
            build_s,
            rays: traced.len(),
            hits: nearest.found,
            nearest_rays_per_s: rate(nearest.steady_s),
            nearest_cold_rays_per_s: rate(nearest.cold_s),
            nearest_passes: nearest.passes,
            occluded: occlusion.found,
            occluded_rays_per_s: rate(occlusion.steady_s),
            occluded_cold_rays_per_s: rate(occlusion.cold_s),
            occluded_passes: occlusion.passes,
            la_process_s: la,
            la_image: la.map(|_| image.display().to_string()),
            la_psnr_vs_this_embree_db: None,
            la_identical_to_this_embree: None,
        });
        Ok::<(), Error>(())
    };
    #[cfg(feature = "embree")]
    {
        let start = Instant::now();
        let embree = crate::accel::embree::EmbreeIntersector::new(&meshes, Default::default())?;
        let build = start.elapsed().as_secs_f64();
        if let Some(dir) = &opts.embree_input {
            write_embree_input(&dir.join(format!("{stem}.embree-input")), &meshes, &rays, &embree.packet_plan(&rays))?;
        }
        let t = throughput(&embree, &rays);
        push("embree", embree_library(), embree.triangle_count(), build, &rays, t)?;
    }
    if opts.embree_only {
        return Ok(rows);
    }
    let start = Instant::now();
    let bvh = BvhIntersector::new(&meshes)?;
    let build = start.elapsed().as_secs_f64();
    let t = throughput(&bvh, &rays);
    push("bvh", "inimtrace".into(), bvh.triangle_count(), build, &rays, t)?;
    drop(bvh);
    // Every `step`-th ray, so that the twin traces at most BRUTE_RAYS.
    let step = rays.len().div_ceil(BRUTE_RAYS).max(1);
    let few: Vec<Ray> = rays.iter().step_by(step).copied().collect();
    let start = Instant::now();
    let brute = BruteForce::new(&meshes)?;
    let build = start.elapsed().as_secs_f64();
    let t = throughput(&brute, &few);
    push("brute", "inimtrace".into(), brute.triangle_count(), build, &few, t)?;
    Ok(rows)
}

/// Writes what Embree is given for one scene, so that a bare C loop (`scripts/embree-bare.c`)
/// can make the same calls: the bytes `INIMEMB1`, then little-endian: the geometry count (u32);
/// per geometry its vertex and triangle counts (u32 each), vertices (3 f32 each) and triangles
/// (3 u32 each); the ray count (u32) and per ray origin, direction, tnear, tfar (8 f32); then one
/// byte per run of 16 rays, 1 when `intersect_many` traces it as a packet.
#[cfg(feature = "embree")]
fn write_embree_input(
    path: &Path,
    meshes: &[(u32, &crate::scene::mesh::Mesh)],
    rays: &[Ray],
    plan: &[bool],
) -> Result<()> {
    let count = |n: usize, what: &str| {
        u32::try_from(n).map_err(|_| Error::invalid(path.display().to_string(), what, "more than 2^32 - 1"))
    };
    let mut bytes: Vec<u8> = b"INIMEMB1".to_vec();
    let put_u32 = |bytes: &mut Vec<u8>, x: u32| bytes.extend_from_slice(&x.to_le_bytes());
    put_u32(&mut bytes, count(meshes.len(), "meshes")?);
    for (_, mesh) in meshes {
        put_u32(&mut bytes, count(mesh.positions.len(), "positions")?);
        put_u32(&mut bytes, count(mesh.triangles.len(), "triangles")?);
        for p in &mesh.positions {
            // The same f64 -> f32 rounding as `EmbreeIntersector`.
            for c in p.as_vec3().to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in &mesh.triangles {
            t.iter().for_each(|&k| put_u32(&mut bytes, k));
        }
    }
    put_u32(&mut bytes, count(rays.len(), "rays")?);
    for ray in rays {
        let r = crate::accel::embree::raw_ray(ray, f64::INFINITY);
        for c in r.org.iter().chain(&r.dir).chain(&[r.tnear, r.tfar]) {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    bytes.extend(plan.iter().map(|&p| u8::from(p)));
    crate::io::output::write_atomic(path, |temp| std::fs::write(temp, &bytes).map_err(|e| Error::io(temp, e)))
}

/// Runs the comparison; writes `backends.csv`, `backends.json` and `backends.md` into
/// `opts.out` and returns the rows.
pub fn run(opts: &BackendsOptions) -> Result<Vec<BackendRow>> {
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    if let Some(dir) = &opts.embree_input {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let me = std::env::current_exe().map_err(|e| Error::io(Path::new("current_exe"), e))?;
    let mut rows = Vec::new();
    for scene in &opts.scenes {
        rows.extend(measure_scene(opts, scene, &me)?);
    }
    if let Some(other) = &opts.also {
        let other_out = opts.out.join("also");
        let mut command = Command::new(other);
        command.args(["--quiet", "bench", "--backends", "--embree-only", "--out"]).arg(&other_out);
        if opts.quick {
            command.arg("--quick");
        }
        for scene in &opts.scenes {
            command.arg("--scene").arg(scene);
        }
        let output = command
            .output()
            .map_err(|e| Error::invalid(other.display().to_string(), "--also", format!("cannot run it: {e}")))?;
        if !output.status.success() {
            return Err(Error::invalid(
                other.display().to_string(),
                "--also",
                format!("its bench --backends failed: {}", String::from_utf8_lossy(&output.stderr).trim()),
            ));
        }
        let json = other_out.join("backends.json");
        let text = std::fs::read_to_string(&json).map_err(|e| Error::io(&json, e))?;
        let theirs: Vec<BackendRow> = serde_json::from_str(&text)
            .map_err(|e| Error::invalid(json.display().to_string(), "rows", e.to_string()))?;
        for mut row in theirs {
            let mine = rows.iter().find(|r| r.scene == row.scene && r.backend == "embree");
            if let (Some(a), Some(b)) = (mine.and_then(|r| r.la_image.as_ref()), row.la_image.as_ref()) {
                let a = crate::io::exr::read_rgb(Path::new(a))?;
                let b = crate::io::exr::read_rgb(Path::new(b))?;
                let psnr = crate::metrics::psnr(&a, &b)?.mean;
                row.la_psnr_vs_this_embree_db = psnr.is_finite().then_some(psnr);
                row.la_identical_to_this_embree = Some(a.pixels == b.pixels);
            }
            rows.push(row);
        }
    }
    write_reports(opts, &rows)?;
    Ok(rows)
}

fn cell(x: Option<f64>, digits: usize) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.digits$}"))
}

/// The comparison as a Markdown table.
pub fn markdown(rows: &[BackendRow]) -> String {
    let mut s = String::from(
        "| scene | backend | library | triangles | build s | nearest Mrays/s | first pass | occlusion Mrays/s | first pass | rays | hits | LA image s (process) | LA image vs this Embree (PSNR dB) |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let scene = Path::new(&r.scene).file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
        s.push_str(&format!(
            "| {scene} | {} | {} | {} | {:.3} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} |\n",
            r.backend,
            r.library,
            r.triangles,
            r.build_s,
            r.nearest_rays_per_s / 1e6,
            r.nearest_cold_rays_per_s / 1e6,
            r.occluded_rays_per_s / 1e6,
            r.occluded_cold_rays_per_s / 1e6,
            r.rays,
            r.hits,
            cell(r.la_process_s, 2),
            match r.la_identical_to_this_embree {
                Some(true) => "identical".to_string(),
                _ => cell(r.la_psnr_vs_this_embree_db, 1),
            },
        ));
    }
    s.push_str("\n`-`: not measured (the brute-force twin renders no LA image: hours at these sizes).\n");
    s
}

fn write_reports(opts: &BackendsOptions, rows: &[BackendRow]) -> Result<()> {
    let mut csv = CsvTable::new();
    csv.row([
        "scene",
        "backend",
        "library",
        "binary",
        "triangles",
        "build_s",
        "rays",
        "hits",
        "nearest_rays_per_s",
        "nearest_cold_rays_per_s",
        "nearest_passes",
        "occluded",
        "occluded_rays_per_s",
        "occluded_cold_rays_per_s",
        "occluded_passes",
        "la_process_s",
        "la_psnr_vs_this_embree_db",
        "la_identical_to_this_embree",
        "threads",
        "git_revision",
    ]);
    for r in rows {
        csv.row([
            r.scene.clone(),
            r.backend.clone(),
            r.library.clone(),
            r.binary.clone(),
            r.triangles.to_string(),
            r.build_s.to_string(),
            r.rays.to_string(),
            r.hits.to_string(),
            r.nearest_rays_per_s.to_string(),
            r.nearest_cold_rays_per_s.to_string(),
            r.nearest_passes.to_string(),
            r.occluded.to_string(),
            r.occluded_rays_per_s.to_string(),
            r.occluded_cold_rays_per_s.to_string(),
            r.occluded_passes.to_string(),
            r.la_process_s.map(|v| v.to_string()).unwrap_or_default(),
            r.la_psnr_vs_this_embree_db.map(|v| v.to_string()).unwrap_or_default(),
            r.la_identical_to_this_embree.map(|v| v.to_string()).unwrap_or_default(),
            rayon::current_num_threads().to_string(),
            crate::version::GIT_REVISION.to_string(),
        ]);
    }
    let write = |name: &str, text: String| {
        let path = opts.out.join(name);
        std::fs::write(&path, text).map_err(|e| Error::io(&path, e))
    };
    write("backends.csv", csv.finish())?;
    let json =
        serde_json::to_string_pretty(rows).map_err(|e| Error::invalid("backends.json", "rows", e.to_string()))?;
    write("backends.json", json)?;
    write("backends.md", markdown(rows))
}
