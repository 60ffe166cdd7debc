//! The `inimtrace` command line: runs the paper's assessment (`assess`) or one stage of it.
#![deny(unsafe_code)]

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use glam::DVec3;

use inimtrace::io::exr::ExrCompression;
use inimtrace::metrics::SsimConstants;
use inimtrace::overrides::Override;
use inimtrace::render::{BackendChoice, Method};

/// `print!` that returns write errors (a closed pipe) instead of panicking.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($t)*)?
    }};
}

/// `println!` that returns write errors (a closed pipe) instead of panicking.
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($t)*)?
    }};
}

mod cli;
use cli::{assess::assess, bench::bench, bench::bench_backends, compare::compare, info::eye_info, info::info};
use cli::{error_line, exr_path, parse_vec3, EyeArgs, Setup};
use cli::{render::ground_truth_command, render::render_display, render::simulate_command, resolution::resolution};

#[derive(Parser)]
#[command(
    name = "inimtrace",
    version,
    about = "How a near-eye integral-imaging display looks to a human eye, and how good each way of rendering its display image is."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// No progress bars.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Print the wall time of every stage.
    #[arg(long, global = true)]
    timings: bool,
    /// Compression of the EXR files written (every choice but pxr24 is lossless).
    #[arg(long, global = true, value_parser = cli::values::exr_compression(), default_value_t = ExrCompression::Zip)]
    exr_compression: ExrCompression,
    /// Memory limit (e.g. 4G, 512M): settings or input files that would need more are refused
    /// before anything is allocated. The system's limits still apply (the smallest wins):
    /// MemAvailable, RLIMIT_AS / RLIMIT_DATA and the process's cgroup memory limit.
    #[arg(long, global = true, value_parser = inimtrace::budget::parse_bytes)]
    max_memory: Option<u64>,
    /// Change one setting of the experiment, scene or display (repeatable): a dotted path into
    /// the resolved experiment, the value in TOML syntax: eye.pupil_diameter=3,
    /// eye_cases[1].focus_diopters=2.5, display.lenslets.pitch=1.0, scene.objects[0].center=[0,0,350].
    #[arg(long = "set", global = true, value_name = "KEY=VALUE")]
    set: Vec<Override>,
}

#[derive(Subcommand)]
enum Command {
    /// Run an experiment (default: the paper's, measured converged) and write every image, the table and the figure.
    Assess {
        /// Experiment TOML (default: the paper's experiment measured converged, experiments/paper-converged.toml).
        experiment: Option<PathBuf>,
        /// Output directory (default: out/<experiment name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Scene TOML replacing the experiment's scene.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Use an output folder that holds another command's results (e.g. `resolution`'s),
        /// removing the files that command's report lists (and nothing else).
        #[arg(long)]
        force: bool,
        /// Exit with status 3 when a score's 95% interval missed its precision target (the
        /// results are still written; without it a miss is reported on stderr and exits 0).
        #[arg(long)]
        strict: bool,
        /// Also write each converged retinal image's replicates (`*.replicates.exr`, one part
        /// per replicate): `compare` on two of them gives the table's de-biased scores.
        #[arg(long)]
        keep_replicates: bool,
        /// Load and validate every input (files, settings, eyes, the memory estimate), print what
        /// would run, and exit without running or writing anything.
        #[arg(long)]
        check: bool,
        #[command(flatten)]
        backend: BackendArg,
    },
    /// Render one display image.
    RenderDisplay {
        /// The rendering method (case-insensitive).
        #[arg(long, default_value = "LC", value_parser = cli::values::MethodValueParser)]
        method: Method,
        #[command(flatten)]
        setup: Setup,
        /// k x k samples per display pixel.
        #[arg(long, default_value_t = 1)]
        samples_per_pixel: usize,
        /// z of the reference plane camera rays start on (mm).
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        reference_plane: f64,
        /// Pupil centre PupilCenter aims at, mm.
        #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,0")]
        eye_position: DVec3,
        /// Output EXR with R, G, B and Z (hit distance, mm) channels; a PNG preview is written beside it.
        #[arg(long, short, value_parser = exr_path)]
        out: PathBuf,
        #[command(flatten)]
        backend: BackendArg,
    },
    /// Simulate the perceived retinal image of a display image (any EXR of the LCD's resolution).
    Simulate {
        /// Display image (EXR).
        display_image: PathBuf,
        /// The part of a multipart EXR to read, by name (default: its only part with R, G and B).
        #[arg(long, value_name = "NAME")]
        part: Option<String>,
        #[command(flatten)]
        setup: Setup,
        #[command(flatten)]
        eye: EyeArgs,
        #[arg(long, short, value_parser = exr_path)]
        out: PathBuf,
    },
    /// Render the ground-truth retinal image of the scene.
    GroundTruth {
        #[command(flatten)]
        setup: Setup,
        #[command(flatten)]
        eye: EyeArgs,
        #[arg(long, short, value_parser = exr_path)]
        out: PathBuf,
        #[command(flatten)]
        backend: BackendArg,
    },
    /// PSNR and SSIM of two RGB EXR images of the same size; of two replicate sets (`assess
    /// --keep-replicates`), the table's de-biased scores with their 95% intervals.
    Compare {
        a: PathBuf,
        b: PathBuf,
        /// The part of multipart EXRs to read, by name, in both files (default: each file's only
        /// part with R, G and B).
        #[arg(long, value_name = "NAME")]
        part: Option<String>,
        /// SSIM constants.
        #[arg(long, value_parser = cli::values::ssim_constants(), default_value_t = SsimConstants::Wang2004)]
        ssim: SsimConstants,
        /// Print JSON (PSNR and SSIM per channel; an infinite PSNR, identical channels, is null).
        #[arg(long)]
        json: bool,
        /// Scores beyond PSNR and SSIM, comma-separated: psnr-luminance, cvvdp (JOD), flip
        /// (HDR-FLIP mean); the first image is the reference (the ground truth), the second the test.
        #[arg(long, value_delimiter = ',', value_name = "NAMES")]
        scores: Vec<String>,
        /// The display's white luminance for cvvdp and flip, cd/m^2.
        #[arg(long, value_name = "CD_M2", default_value_t = 100.0)]
        peak_white: f64,
        /// The display's black luminance for cvvdp and flip, cd/m^2.
        #[arg(long, value_name = "CD_M2", default_value_t = 0.1)]
        black: f64,
        /// Pixels per degree of the images for cvvdp and flip (default: from the retina attributes
        /// inimtrace writes into its retinal images).
        #[arg(long, value_name = "PPD")]
        ppd: Option<f64>,
    },
    /// Speed against error for every method and backend, the convergence of every sampling
    /// parameter, and the seconds each Table 1 estimator needs to come within 0.1 to 0.01 dB of the
    /// converged Table 1; writes
    /// bench.csv, builds.csv, bench.json, bench.md and plots (PNG, SVG).
    Bench {
        /// Small sizes (LCD 540 x 540, retina 128 x 128).
        #[arg(long)]
        quick: bool,
        /// Scene TOML (default: the paper's scene). Rectangle-only scenes run on the analytic
        /// backends and the mesh backends; scenes with meshes on the mesh backends only (slow at
        /// full size: the LA reference traces 1,024 camera rays per display pixel; try --quick).
        /// With --backends: repeatable (default: scenes/bunny.toml and scenes/spheres-2m.toml).
        #[arg(long)]
        scene: Vec<PathBuf>,
        /// Output directory (default: out/bench or out/bench-quick; out/bench-backends with --backends).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Compare the mesh backends instead (Embree, bvh, brute): build time, nearest-hit and
        /// occlusion rays/s, whole-process time of an LA display image (backends.md, .csv, .json).
        #[arg(long)]
        backends: bool,
        /// With --backends: also measure the Embree of this other inimtrace binary (e.g. the
        /// Embree 3 build beside an Embree 4 one), and score its LA image against this one's.
        #[arg(long, requires = "backends", value_name = "BINARY")]
        also: Option<PathBuf>,
        /// With --backends: Embree only (what --also asks of the other binary).
        #[arg(long, requires = "backends", hide = true)]
        embree_only: bool,
        /// With --backends: also write each scene's Embree input (triangles, rays) into this
        /// folder for the bare C loop of scripts/embree-bare.sh.
        #[arg(long, requires = "backends", value_name = "DIR")]
        embree_input: Option<PathBuf>,
    },
    /// Run an experiment over the points of a sweep file (axes of --set values) on all cores, or
    /// as a Slurm job array; resumable. Writes sweep.csv, sweep.json, plots and points/.
    Sweep(cli::sweep::SweepArgs),
    /// Perceived resolution and focus cues: grating and slanted-edge MTF in cycles per degree for
    /// the ground truth and every method, through focus, the predicted accommodation and the
    /// display's limits (see docs/RESOLUTION.md). Writes mtf.csv, mtf50.csv, accommodation.csv,
    /// display.md, display.json, plots and study.json.
    Resolution {
        /// Study TOML (default: the built-in studies/paper.toml).
        study: Option<PathBuf>,
        /// Output directory (default: out/resolution-<study name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Use an output folder that holds another command's results (e.g. `assess`'s), removing
        /// the files that command's report lists (and nothing else).
        #[arg(long)]
        force: bool,
        /// Load and validate every input (files, settings, eyes, the memory estimate), print what
        /// would run, and exit without running or writing anything.
        #[arg(long)]
        check: bool,
    },
    /// Rebuild report.html of a finished run folder (assess, resolution or sweep) from its own
    /// files: what was simulated, the scores, the images, the plots, the provenance. The same
    /// folder gives the same page, byte for byte.
    Report {
        /// The run folder (holding results.json, study.json or sweep.json).
        dir: PathBuf,
    },
    /// Describe a display design (central depth plane, eye box, field of view, pixels per
    /// degree, views through the pupil, pixel beams in it) or a scene (objects, sizes, depth range), and write the
    /// built-in files.
    Info {
        /// Display TOML or OpenCV YAML (default: the paper's).
        #[arg(long)]
        display: Option<PathBuf>,
        /// Describe this scene TOML instead of a display (with --pupil auto: the scene the
        /// display shows, for the adapting luminance).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Pupil diameter (mm) for the views through the pupil and the pixel beams in it, or
        /// `auto`: the light-adapted pupil (Watson & Yellott 2012) of the display's field of view
        /// over --scene (default: the paper's scene) at the display's photometry, for an observer
        /// of 30 years adapted with both eyes.
        #[arg(long, default_value = "5")]
        pupil: String,
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Print the built-in experiment, scene or display as a file.
        #[arg(long, value_enum)]
        print: Option<PrintTarget>,
        /// Describe this schematic eye instead (navarro, navarro-1999, arizona, le-grand): its
        /// accommodation range, and at --focus-diopters its accommodation, power and pupils
        /// (--pupil is the entrance pupil).
        #[arg(long, conflicts_with_all = ["display", "scene"])]
        eye: Option<String>,
        /// The focus of --eye, D (default: the relaxed eye's).
        #[arg(long, requires = "eye")]
        focus_diopters: Option<f64>,
        /// Field angles for --eye, degrees off the axis (e.g. 10,20,30): the sagittal and
        /// tangential foci there and the astigmatism.
        #[arg(long, requires = "eye", value_delimiter = ',', allow_negative_numbers = true)]
        field_deg: Vec<f64>,
        /// The surface table of `--eye user`: a TOML file with an [eye.user] table (such as an
        /// experiment or a study that holds one).
        #[arg(long, requires = "eye")]
        eye_file: Option<PathBuf>,
        /// Write the display as an explicit display TOML (v2, pitch matrices) to this file,
        /// atomically; e.g. a display stated by intent, a framework YAML, or one with --set.
        #[arg(long, value_name = "FILE", conflicts_with_all = ["scene", "eye", "print"])]
        write_display: Option<PathBuf>,
        /// Let --write-display replace an existing file.
        #[arg(long, requires = "write_display")]
        force: bool,
        /// The experiment's `[optics] diffraction` to report: none, pupil or apertures (the
        /// angles lambda / D of the pupil and lambda / w of the lenslet aperture are printed
        /// either way).
        #[arg(long, default_value = "none", value_parser = ["none", "pupil", "apertures"])]
        diffraction: String,
        /// Check the provenance of a run folder (an `assess` run's results.json, or a sweep's
        /// point records): hash every input file it read again and report what changed.
        #[arg(long, value_name = "RUN_DIR", conflicts_with_all = ["display", "scene", "eye", "print", "write_display"])]
        provenance: Option<PathBuf>,
    },
}

/// `info --print`.
#[derive(Clone, Copy, ValueEnum)]
enum PrintTarget {
    /// The paper's experiment measured converged (what `assess` runs with no file).
    PaperExperiment,
    /// The paper's experiment as its text states it, with the grid estimator.
    PaperGridExperiment,
    /// What the published framework ran.
    #[value(name = "framework-2020-experiment")]
    Framework2020Experiment,
    /// The paper's scene.
    PaperScene,
    /// The paper's display.
    PaperDisplay,
}

/// Scene intersection backend.
#[derive(Args)]
struct BackendArg {
    /// Scene intersection backend.
    #[arg(long = "backend", value_parser = cli::values::backend(), ignore_case = true, default_value_t = BackendChoice::Auto)]
    backend: BackendChoice,
}

impl BackendArg {
    fn choice(&self) -> Result<BackendChoice> {
        Ok(self.backend)
    }
}

fn main() {
    // Before anything else: a CPU without the instructions this build assumes would otherwise
    // stop with "illegal instruction" somewhere later.
    inimtrace::cpu::exit_if_unsupported();
    if let Err(e) = run() {
        // A reader that went away (`inimtrace compare a b | head -1`) ends the program quietly,
        // with the exit status of a process killed by SIGPIPE.
        if e.chain()
            .any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
        {
            std::process::exit(141);
        }
        eprintln!("error: {}", error_line(&e));
        std::process::exit(if e.downcast_ref::<TargetsMissed>().is_some() { 3 } else { 1 });
    }
}

/// The global flags every command reads.
struct Globals {
    /// `--set` overrides.
    set: Vec<Override>,
    /// `--quiet`.
    quiet: bool,
    /// `--timings`.
    timings: bool,
    /// `--exr-compression`.
    exr_compression: ExrCompression,
}

/// The parsed command line (clap prints help, the version or a usage error and exits), with the
/// process-wide flags applied: `--threads` sizes the thread pool, `--max-memory` sets the budget.
fn parse_command_line() -> Result<Cli> {
    let mut command = Cli::command();
    // Only `--version` starts Embree to ask the loaded library's version (after `main`'s CPU check).
    if std::env::args_os().skip(1).any(|a| a == "--version" || a == "-V") {
        command = command.version(&*Box::leak(inimtrace::version::long().into_boxed_str()));
    }
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    if let Some(n) = cli.threads {
        inimtrace::budget::check_threads("--threads", n).map_err(anyhow::Error::msg)?;
        rayon::ThreadPoolBuilder::new().num_threads(n).build_global().context("cannot start the thread pool")?;
    }
    if let Some(bytes) = cli.max_memory {
        inimtrace::budget::set_memory_limit(bytes);
    }
    Ok(cli)
}

/// Runs the command given; with `--timings`, the total time of a command that does not print its own.
fn run() -> Result<()> {
    let cli = parse_command_line()?;
    let quiet = cli.quiet;
    let set = cli.set;
    let g = Globals { set: set.clone(), quiet, timings: cli.timings, exr_compression: cli.exr_compression };
    let start = Instant::now();
    // `assess` and `bench` print their own total with --timings.
    let mut printed_total = false;
    match cli.command {
        Command::Assess { experiment, scene, check: true, .. } => {
            let exp = inimtrace::settings::load_experiment(experiment.as_deref(), scene.as_deref(), &set)?;
            for w in exp.plausibility_warnings() {
                eprintln!("warning: {w}");
            }
            outln!("{}", inimtrace::experiment::check_text(&exp)?);
        }
        Command::Assess { experiment, out, scene, force, strict, keep_replicates, backend, .. } => {
            printed_total = assess(&g, experiment, out, scene, force, strict, keep_replicates, backend)?;
        }
        Command::RenderDisplay { method, setup, samples_per_pixel, reference_plane, eye_position, out, backend } => {
            printed_total =
                render_display(&g, method, setup, samples_per_pixel, reference_plane, eye_position, out, backend)?;
        }
        Command::Simulate { display_image, part, setup, eye, out } => {
            printed_total = simulate_command(&g, display_image, part.as_deref(), setup, eye, out)?;
        }
        Command::GroundTruth { setup, eye, out, backend } => {
            printed_total = ground_truth_command(&g, setup, eye, out, backend)?;
        }
        Command::Compare { a, b, part, ssim: constants, json, scores, peak_white, black, ppd } => {
            let luminance = inimtrace::perception::DisplayLuminance { peak_white, black, ..Default::default() };
            let perceptual = cli::compare::Perceptual { scores, luminance, ppd };
            printed_total = compare(&g, a, b, part.as_deref(), constants, json, &perceptual)?;
        }
        Command::Bench { quick, scene, out, backends: true, also, embree_only, embree_input } => {
            bench_backends(&g, quick, scene, out, also, embree_only, embree_input)?;
        }
        Command::Bench { quick, scene, out, .. } => {
            if scene.len() > 1 {
                bail!("--scene is given {} times; bench takes one scene (several only with --backends)", scene.len());
            }
            printed_total = bench(&g, quick, scene.into_iter().next(), out)?;
        }
        Command::Sweep(args) => {
            // `--check` prints no total.
            printed_total = cli::sweep::sweep(&g, cli.threads, cli.max_memory, args)?;
        }
        Command::Resolution { study, out, force, check } => {
            resolution(&g, study, out, force, check)?;
            printed_total = true;
        }
        Command::Report { dir } => {
            let path = inimtrace::report::write(&dir)?;
            if !quiet {
                eprintln!("wrote {}", path.display());
            }
        }
        Command::Info { provenance: Some(dir), .. } => {
            let (text, _) = inimtrace::provenance::report(&dir)?;
            out!("{text}");
            printed_total = true;
        }
        Command::Info { eye: Some(model), focus_diopters, field_deg, eye_file, pupil, json, .. } => {
            eye_info(&model, eye_file.as_deref(), focus_diopters, &field_deg, &pupil, json)?;
            printed_total = true;
        }
        Command::Info { display, scene, pupil, json, print, write_display, force, diffraction, .. } => {
            let write = write_display.map(|path| (path, force));
            let diffraction = match diffraction.as_str() {
                "pupil" => inimtrace::optics::diffraction::Diffraction::Pupil,
                "apertures" => inimtrace::optics::diffraction::Diffraction::Apertures,
                _ => inimtrace::optics::diffraction::Diffraction::None,
            };
            printed_total = info(&g, display, scene, (pupil, diffraction), json, print, write)?;
        }
    }
    if cli.timings && !printed_total {
        eprintln!("total {:.3} s", start.elapsed().as_secs_f64());
    }
    std::io::Write::flush(&mut std::io::stdout())?;
    Ok(())
}

/// `--strict` and a score whose interval missed its target: exit status 3 (the results are
/// written; the note said where).
#[derive(Debug)]
struct TargetsMissed(usize);

impl std::fmt::Display for TargetsMissed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "--strict: {} missed their precision target", inimtrace::count::count(self.0, "score"))
    }
}

impl std::error::Error for TargetsMissed {}
