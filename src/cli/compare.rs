//! `inimtrace compare`: PSNR and SSIM of two images, or the de-biased scores and 95% intervals
//! of two replicate sets (what the table reports).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use inimtrace::metrics::{self, SsimConstants};

use super::read_exr_input;
use crate::Globals;

/// `inimtrace compare`; returns whether it printed its own total time.
pub(crate) fn compare(
    g: &Globals,
    a: PathBuf,
    b: PathBuf,
    part: Option<&str>,
    constants: SsimConstants,
    json: bool,
) -> Result<bool> {
    let set = &g.set[..];
    if !set.is_empty() {
        bail!("--set does not apply to compare (it reads no experiment, scene or display)");
    }
    if part.is_none() {
        if let Some((p, s)) = compare_replicate_sets(&a, &b, constants)? {
            return print_replicate_scores(&a, &b, &p, &s, constants, json);
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
    if json {
        let channels = |v: [f64; 3], m: f64, f: &dyn Fn(f64) -> serde_json::Value| serde_json::json!({"R": f(v[0]), "G": f(v[1]), "B": f(v[2]), "mean": f(m)});
        let db = |x: f64| serde_json::json!(metrics::finite_db(x));
        let out = serde_json::json!({
            "a": a.display().to_string(),
            "b": b.display().to_string(),
            "width": ia.width,
            "height": ia.height,
            "psnr_db": channels(p.channels, p.mean, &db),
            "ssim": channels(s.channels, s.mean, &|x| serde_json::json!(x)),
            "ssim_constants": constants.name(),
            "tool": inimtrace::version::TOOL,
        });
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(true);
    }
    use inimtrace::measure::stats::Estimate;
    print_scores(&Estimate::exact(p.channels, p.mean), &Estimate::exact(s.channels, s.mean), constants, "")?;
    Ok(false)
}

/// The table's scores of two replicate sets (`None` when neither file is one).
fn compare_replicate_sets(
    a: &Path,
    b: &Path,
    constants: SsimConstants,
) -> Result<Option<(inimtrace::measure::stats::Estimate, inimtrace::measure::stats::Estimate)>> {
    use inimtrace::io::exr_replicates as sets;
    let (ca, cb) = (sets::count(a)?, sets::count(b)?);
    match (ca, cb) {
        (None, None) => Ok(None),
        (Some(ra), Some(rb)) => {
            let (sa, sb) = (sets::read(a, ra)?, sets::read(b, rb)?);
            let (na, nb) = (a.display().to_string(), b.display().to_string());
            let reps = sets::pair((&na, &sa), (&nb, &sb), 1)?;
            Ok(inimtrace::measure::adaptive::estimates(&reps, constants).pop())
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
    constants: SsimConstants,
    json: bool,
) -> Result<bool> {
    if json {
        let out = serde_json::json!({
            "a": a.display().to_string(),
            "b": b.display().to_string(),
            "replicate_sets": true,
            "psnr_db": p,
            "ssim": s,
            "ssim_constants": constants.name(),
            "tool": inimtrace::version::TOOL,
        });
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(true);
    }
    print_scores(p, s, constants, "; de-biased over replicates, 95% interval")?;
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
