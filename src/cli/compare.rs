//! `inimtrace compare`: PSNR and SSIM of two images, or the de-biased scores and 95% intervals
//! of two replicate sets (what the table reports); with `--scores`, the luminance PSNR and the
//! perceptual scores too (`inimtrace::perception`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use inimtrace::metrics::{self, SsimConstants};
use inimtrace::perception::{DisplayLuminance, ExtraScores, Perception, PerceptualScores, ScoreName, Viewing};

use super::read_exr_input;
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
    fn scorer(&self, a: &Path, size: (usize, usize)) -> Result<Option<Perception>> {
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
            None if extra.any_perceptual() => retina_ppd(a)?.with_context(|| {
                format!("{} has no retina attributes: give the images' pixels per degree with --ppd", a.display())
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
fn retina_ppd(path: &Path) -> Result<Option<f64>> {
    let attrs = inimtrace::io::exr::read_attributes(path).unwrap_or_default();
    let get = |k: &str| attrs.iter().find(|(n, _)| n == k).and_then(|(_, v)| v.parse::<f64>().ok());
    let (Some(n), Some(t)) = (get("inimtrace:retina_resolution"), get("inimtrace:retina_half_tangent")) else {
        return Ok(None);
    };
    let retina = inimtrace::optics::Retina { resolution: n as usize, half_tangent: t, samples_per_pixel: 1 };
    Ok(Some(inimtrace::perception::viewing::retina_pixels_per_degree(&retina)))
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
    if part.is_none() {
        if let Some((p, s, extra)) = compare_replicate_sets(&a, &b, constants, perceptual)? {
            return print_replicate_scores(&a, &b, &p, &s, &extra, constants, json);
        }
    }
    let ia = read_exr_input(&a, part)?;
    let ib = read_exr_input(&b, part)?;
    let noisy = [&a, &b].iter().any(|p| {
        inimtrace::io::exr::read_attributes(p)
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
    let extra = match perceptual.scorer(&a, (ia.width, ia.height))? {
        Some(p) => {
            p.score_images(&ib, &ia).with_context(|| format!("comparing {} and {}", a.display(), b.display()))?
        }
        None => PerceptualScores::default(),
    };
    if json {
        let channels = |v: [f64; 3], m: f64, f: &dyn Fn(f64) -> serde_json::Value| serde_json::json!({"R": f(v[0]), "G": f(v[1]), "B": f(v[2]), "mean": f(m)});
        let db = |x: f64| serde_json::json!(metrics::finite_db(x));
        let mut out = serde_json::json!({
            "a": a.display().to_string(),
            "b": b.display().to_string(),
            "width": ia.width,
            "height": ia.height,
            "psnr_db": channels(p.channels, p.mean, &db),
            "ssim": channels(s.channels, s.mean, &|x| serde_json::json!(x)),
            "ssim_constants": constants.name(),
            "tool": inimtrace::version::TOOL,
        });
        if !extra.is_empty() {
            print_perceptual(&extra, &mut Some(&mut out))?;
        }
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(true);
    }
    use inimtrace::measure::stats::Estimate;
    print_scores(&Estimate::exact(p.channels, p.mean), &Estimate::exact(s.channels, s.mean), constants, "")?;
    print_perceptual(&extra, &mut None)?;
    Ok(false)
}

/// The table's scores of two replicate sets (`None` when neither file is one).
type SetScores = (inimtrace::measure::stats::Estimate, inimtrace::measure::stats::Estimate, PerceptualScores);

fn compare_replicate_sets(
    a: &Path,
    b: &Path,
    constants: SsimConstants,
    perceptual: &Perceptual,
) -> Result<Option<SetScores>> {
    use inimtrace::io::exr_replicates as sets;
    let (ca, cb) = (sets::count(a)?, sets::count(b)?);
    match (ca, cb) {
        (None, None) => Ok(None),
        (Some(ra), Some(rb)) => {
            let (sa, sb) = (sets::read(a, ra)?, sets::read(b, rb)?);
            let (na, nb) = (a.display().to_string(), b.display().to_string());
            // Image 0 of the pair is the reference (a), image 1 the test (b).
            let reps = sets::pair((&na, &sa), (&nb, &sb), 1)?;
            let n = reps.resolution();
            let extra = match perceptual.scorer(a, (n, n))? {
                Some(p) => p.score_replicates(&reps, 1)?,
                None => PerceptualScores::default(),
            };
            Ok(inimtrace::measure::adaptive::estimates(&reps, constants).pop().map(|(p, s)| (p, s, extra)))
        }
        (Some(_), None) | (None, Some(_)) => {
            let (set, plain) = if ca.is_some() { (a, b) } else { (b, a) };
            bail!(
                "{} is a replicate set and {} is one image: compare two replicate sets (the table's de-biased \
                 scores) or two images",
                set.display(),
                plain.display()
            )
        }
    }
}

fn print_replicate_scores(
    a: &Path,
    b: &Path,
    p: &inimtrace::measure::stats::Estimate,
    s: &inimtrace::measure::stats::Estimate,
    extra: &PerceptualScores,
    constants: SsimConstants,
    json: bool,
) -> Result<bool> {
    if json {
        let mut out = serde_json::json!({
            "a": a.display().to_string(),
            "b": b.display().to_string(),
            "replicate_sets": true,
            "psnr_db": p,
            "ssim": s,
            "ssim_constants": constants.name(),
            "tool": inimtrace::version::TOOL,
        });
        if !extra.is_empty() {
            print_perceptual(extra, &mut Some(&mut out))?;
        }
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(true);
    }
    print_scores(p, s, constants, "; de-biased over replicates, 95% interval")?;
    print_perceptual(extra, &mut None)?;
    Ok(false)
}

/// `compare`'s two lines: PSNR and SSIM, their channels, and the 95% half-widths when known.
fn print_scores(
    p: &inimtrace::measure::stats::Estimate,
    s: &inimtrace::measure::stats::Estimate,
    constants: SsimConstants,
    note: &str,
) -> Result<()> {
    let ci = |e: &inimtrace::measure::stats::Estimate, digits: usize| match e.ci95 {
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
