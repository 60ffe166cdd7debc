//! `inimtrace compare`: PSNR and SSIM of two images, or the de-biased scores and 95% intervals
//! of two replicate sets (what the table reports). Each file is read once, through the input
//! gate; two replicate sets must come from one measurement's sample pattern (the same seed and
//! samples per pixel: the de-biasing pairs replicate r of one with replicate r of the other), and
//! sets from different experiments are compared with a warning. `--json` has one schema for both
//! kinds: every score with its channels, mean and 95% half-widths (`null` where unknown or
//! infinite). With `--scores`, the luminance PSNR and the perceptual scores too
//! (`inimtrace::perception`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use inimtrace::io::exr::ExrFile;
use inimtrace::measure::stats::Estimate;
use inimtrace::metrics::{self, SsimConstants};
use inimtrace::perception::{DisplayLuminance, ExtraScores, Perception, PerceptualScores, ScoreName, Viewing};

use crate::Globals;

/// `compare --scores`: the scores beyond PSNR and SSIM and how the images are seen.
pub(crate) struct Perceptual {
    /// The names given to `--scores`.
    pub scores: Vec<String>,
    /// `--peak-white`, `--black`.
    pub luminance: DisplayLuminance,
    /// `--ppd`.
    pub ppd: Option<f64>,
}

impl Perceptual {
    /// The scorer for `size` images (`None` without `--scores`); the pixels per degree from
    /// `--ppd` or the retina attributes of `a`.
    fn scorer(&self, a: &ExrFile, size: (usize, usize)) -> Result<Option<Perception>> {
        let names: Vec<ScoreName> =
            self.scores.iter().map(|n| n.trim().parse()).collect::<inimtrace::Result<_>>().map_err(|e| {
                anyhow::anyhow!(
                    "command line: field `--scores`: {}",
                    e.to_string().replace("scores: field `name`: ", "")
                )
            })?;
        let extra = ExtraScores::from_names(&names, "command line", "--scores")?;
        if extra.is_empty() {
            return Ok(None);
        }
        let ppd = match self.ppd {
            Some(p) => p,
            None if extra.any_perceptual() => retina_ppd(a).with_context(|| {
                format!(
                    "{} has no retina attributes: give the images' pixels per degree with --ppd",
                    a.path().display()
                )
            })?,
            None => 1.0,
        };
        let viewing = Viewing { luminance: self.luminance, pixels_per_degree: ppd };
        if extra.any_perceptual() {
            viewing.luminance.validate("command line", "").map_err(|e| {
                anyhow::anyhow!(e.to_string().replace("`peak_white`", "`--peak-white`").replace("`black`", "`--black`"))
            })?;
            if !(ppd.is_finite() && ppd > 0.0) {
                bail!("command line: field `--ppd`: must be a positive number of pixels per degree, got {ppd}");
            }
        }
        let weights = inimtrace::perception::BT709_LUMINANCE;
        Ok(Some(Perception::new(&extra, &viewing, weights, size, None)?))
    }
}

/// Pixels per degree at the centre of the retina an inimtrace retinal image's attributes describe.
fn retina_ppd(file: &ExrFile) -> Option<f64> {
    let attrs = file.attributes().unwrap_or_default();
    let get = |k: &str| attrs.iter().find(|(n, _)| n == k).and_then(|(_, v)| v.parse::<f64>().ok());
    let (Some(n), Some(t)) = (get("inimtrace:retina_resolution"), get("inimtrace:retina_half_tangent")) else {
        return None;
    };
    let retina = inimtrace::optics::Retina { resolution: n as usize, half_tangent: t, samples_per_pixel: 1 };
    Some(inimtrace::perception::viewing::retina_pixels_per_degree(&retina))
}

/// The extra scores as two-line text or JSON.
fn print_perceptual(p: &PerceptualScores, json: &mut Option<&mut serde_json::Value>) -> Result<()> {
    if let Some(out) = json {
        out["perceptual"] = serde_json::to_value(p)?;
        return Ok(());
    }
    for (n, e) in &p.0 {
        let d = if *n == ScoreName::Flip { 5 } else { 3 };
        let ci = e.ci95.map(|h| format!(" ± {h:.d$}")).unwrap_or_default();
        let bias = e.noise_bias.map(|b| format!("  (noise bias {b:+.d$})")).unwrap_or_default();
        let label = match n {
            ScoreName::Cvvdp => "JOD ",
            ScoreName::Flip => "FLIP",
            _ => "PSNR-Y",
        };
        let unit = if *n == ScoreName::PsnrLuminance { " dB" } else { "" };
        outln!("{label}  {}{unit}{ci}{bias}", metrics::format_db(e.value, d));
    }
    Ok(())
}

/// `inimtrace compare`; returns whether it printed its own total time.
pub(crate) fn compare(
    g: &Globals,
    a: PathBuf,
    b: PathBuf,
    part: Option<&str>,
    constants: SsimConstants,
    json: bool,
    perceptual: &Perceptual,
) -> Result<bool> {
    let set = &g.set[..];
    if !set.is_empty() {
        bail!("--set does not apply to compare (it reads no experiment, scene or display)");
    }
    let (fa, fb) = (ExrFile::open(&a)?, ExrFile::open(&b)?);
    if part.is_none() {
        if let Some((p, s, n, extra)) = compare_replicate_sets(&fa, &fb, constants, perceptual)? {
            return print(&a, &b, (n.0, n.0, Some(n.1)), &p, &s, &extra, constants, json);
        }
    }
    let ia = read(&fa, part)?;
    let ib = read(&fb, part)?;
    let noisy = [&fa, &fb].iter().any(|f| {
        f.attributes()
            .is_ok_and(|attrs| attrs.iter().any(|(k, v)| k == "inimtrace:estimator" && v.starts_with("converged")))
    });
    if noisy {
        eprintln!(
            "note: these images are means of a converged measurement's replicates and keep its sampling noise, which \
             biases PSNR and SSIM down; the table's scores remove it: run `assess --keep-replicates` and compare the \
             `*.replicates.exr` files for them (docs/TABLE1.md)"
        );
    }
    let p = metrics::psnr(&ia, &ib).with_context(|| format!("comparing {} and {}", a.display(), b.display()))?;
    let s =
        metrics::ssim(&ia, &ib, constants).with_context(|| format!("comparing {} and {}", a.display(), b.display()))?;
    let extra = match perceptual.scorer(&fa, (ia.width, ia.height))? {
        Some(p) => {
            p.score_images(&ib, &ia).with_context(|| format!("comparing {} and {}", a.display(), b.display()))?
        }
        None => PerceptualScores::default(),
    };
    let (p, s) = (Estimate::exact(p.channels, p.mean), Estimate::exact(s.channels, s.mean));
    print(&a, &b, (ia.width, ia.height, None), &p, &s, &extra, constants, json)
}

/// The RGB image of part `part` of an input file, printing the reader's note on a multipart file.
fn read(file: &ExrFile, part: Option<&str>) -> Result<inimtrace::raster::RgbImage> {
    let input = file.input(part)?;
    if let Some(note) = input.note {
        eprintln!("{note}");
    }
    Ok(input.image)
}

/// PSNR and SSIM of two replicate sets with their images' size and their replicate count, and
/// the scores `--scores` names.
type SetScores = (Estimate, Estimate, (usize, usize), PerceptualScores);

/// The table's scores of two replicate sets, with their size and replicate count (`None` when
/// neither file is one).
fn compare_replicate_sets(
    a: &ExrFile,
    b: &ExrFile,
    constants: SsimConstants,
    perceptual: &Perceptual,
) -> Result<Option<SetScores>> {
    use inimtrace::io::exr_replicates as sets;
    let (ca, cb) = (sets::count_of(a)?, sets::count_of(b)?);
    match (ca, cb) {
        (None, None) => Ok(None),
        (Some(ra), Some(rb)) => {
            check_one_measurement(a, b)?;
            let (sa, sb) = (sets::read_of(a, ra)?, sets::read_of(b, rb)?);
            let (na, nb) = (a.path().display().to_string(), b.path().display().to_string());
            // Image 0 of the pair is the reference (a), image 1 the test (b).
            let reps = sets::pair((&na, &sa), (&nb, &sb), 1)?;
            let n = reps.resolution();
            let extra = match perceptual.scorer(a, (n, n))? {
                Some(p) => p.score_replicates(&reps, 1)?,
                None => PerceptualScores::default(),
            };
            let (p, s) = inimtrace::measure::adaptive::estimates(&reps, constants).pop().context("no image scored")?;
            Ok(Some((p, s, (sa[0].width, ra), extra)))
        }
        (Some(_), None) | (None, Some(_)) => {
            let (set, plain) = if ca.is_some() { (a, b) } else { (b, a) };
            bail!(
                "{} is a replicate set and {} is one image: compare two replicate sets (the table's de-biased \
                 scores) or two images",
                set.path().display(),
                plain.path().display()
            )
        }
    }
}

/// Two replicate sets pair replicate r with replicate r: they must share the measurement's
/// sample pattern (`inimtrace:seed`, `inimtrace:retina_samples_per_pixel`), or the de-biasing
/// is meaningless; another experiment (`inimtrace:experiment`) is allowed, with a warning.
fn check_one_measurement(a: &ExrFile, b: &ExrFile) -> Result<()> {
    let (ta, tb) = (a.attributes()?, b.attributes()?);
    let get = |t: &[(String, String)], k: &str| t.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
    for (key, what) in [("inimtrace:seed", "seed"), ("inimtrace:retina_samples_per_pixel", "samples per pixel")] {
        match (get(&ta, key), get(&tb, key)) {
            (Some(x), Some(y)) if x != y => bail!(
                "{} ({what} {x}) and {} ({what} {y}) are replicate sets of different measurements: their replicates \
                 do not pair, so their scores cannot be de-biased; compare sets written by one run (or runs with \
                 one measurement.seed and sample count)",
                a.path().display(),
                b.path().display()
            ),
            (Some(_), Some(_)) => {}
            _ => eprintln!(
                "warning: {} or {} does not say its {what} ({key}): whether their replicates pair cannot be \
                 checked",
                a.path().display(),
                b.path().display()
            ),
        }
    }
    if let (Some(x), Some(y)) = (get(&ta, "inimtrace:experiment"), get(&tb, "inimtrace:experiment")) {
        if x != y {
            eprintln!(
                "warning: {} is from experiment `{x}` and {} from `{y}`: their replicates pair only if both \
                 experiments sampled the same retina and pupil points",
                a.path().display(),
                b.path().display()
            );
        }
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
/// Prints the scores (two lines, or `--json`). `size` is (width, height, replicates).
fn print(
    a: &Path,
    b: &Path,
    size: (usize, usize, Option<usize>),
    p: &Estimate,
    s: &Estimate,
    extra: &PerceptualScores,
    constants: SsimConstants,
    json: bool,
) -> Result<bool> {
    if json {
        let mut out = serde_json::json!({
            "a": a.display().to_string(),
            "b": b.display().to_string(),
            "width": size.0,
            "height": size.1,
            "replicate_sets": size.2.is_some(),
            "replicates": size.2,
            "psnr_db": score_json(p),
            "ssim": score_json(s),
            "ssim_constants": constants.name(),
            "tool": inimtrace::version::TOOL,
        });
        if !extra.is_empty() {
            print_perceptual(extra, &mut Some(&mut out))?;
        }
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(true);
    }
    let note = if size.2.is_some() { "; de-biased over replicates, 95% interval" } else { "" };
    print_scores(p, s, constants, note)?;
    print_perceptual(extra, &mut None)?;
    Ok(false)
}

/// A score in `compare --json`'s one schema: `R`, `G`, `B`, `mean`, `ci95` and `channels_ci95`
/// (`{R, G, B}`), `null` for an infinite value (identical channels) and for an unknown interval.
fn score_json(e: &Estimate) -> serde_json::Value {
    let num = |x: f64| serde_json::json!(metrics::finite_db(x));
    let channels = |v: [f64; 3]| serde_json::json!({"R": num(v[0]), "G": num(v[1]), "B": num(v[2])});
    serde_json::json!({
        "R": num(e.channels[0]),
        "G": num(e.channels[1]),
        "B": num(e.channels[2]),
        "mean": num(e.mean),
        "ci95": e.ci95.map(num),
        "channels_ci95": e.channels_ci95.map(channels),
    })
}

/// `compare`'s two lines: PSNR and SSIM, their channels, and the 95% half-widths when known.
fn print_scores(p: &Estimate, s: &Estimate, constants: SsimConstants, note: &str) -> Result<()> {
    let ci = |e: &Estimate, digits: usize| match e.ci95 {
        Some(h) => format!(" ± {h:.digits$}"),
        None => String::new(),
    };
    outln!(
        "PSNR  {} dB{}  (R {}, G {}, B {}{note})",
        metrics::format_db(p.mean, 3),
        ci(p, 3),
        metrics::format_db(p.channels[0], 3),
        metrics::format_db(p.channels[1], 3),
        metrics::format_db(p.channels[2], 3)
    );
    outln!(
        "SSIM  {:.5}{}  (R {:.5}, G {:.5}, B {:.5}; constants {})",
        s.mean,
        ci(s, 5),
        s.channels[0],
        s.channels[1],
        s.channels[2],
        constants
    );
    Ok(())
}
