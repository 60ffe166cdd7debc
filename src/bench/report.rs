//! Writing a bench run: `bench.csv` (one line per measured point), `builds.csv`, the Markdown
//! reports and plots, `bench.json` (everything, written last), and the table `inimtrace bench`
//! prints on stdout.

use std::fmt::Write as _;
use std::path::Path;

use super::markdown::markdown;
use super::options::{BenchRow, BuildRecord};
use super::plots::write_plots;
use super::BenchReport;
use crate::error::{Error, Result};
use crate::io::csv_table::CsvTable;

/// `bench.csv`: one line per row, the columns of [`BenchRow`] in order.
pub fn rows_csv(rows: &[BenchRow]) -> String {
    let mut csv = CsvTable::new();
    csv.row([
        "series",
        "sweep",
        "estimator",
        "quantity",
        "eye_case",
        "focus_mm",
        "backend",
        "method",
        "parameter",
        "samples",
        "seconds",
        "rays",
        "rays_per_second",
        "psnr_db",
        "ssim",
        "scene",
        "lcd_resolution",
        "retina_resolution",
        "display_samples",
        "la_grid",
        "pupil_grid",
        "pupil_samples",
        "retina_samples",
        "reference",
        "threads",
        "cores",
        "git_revision",
    ]);
    for r in rows {
        let fields = [
            r.series.as_str().to_string(),
            r.sweep.as_str().to_string(),
            r.estimator.map(|e| e.as_str()).unwrap_or_default().to_string(),
            r.quantity.as_str().to_string(),
            r.eye_case.clone(),
            r.focus_mm.map(|f| f.to_string()).unwrap_or_default(),
            r.backend.as_str().to_string(),
            r.method.as_str().to_string(),
            r.parameter.to_string(),
            r.samples.to_string(),
            r.seconds.to_string(),
            r.rays.to_string(),
            r.rays_per_second.to_string(),
            r.psnr_db.to_string(),
            r.ssim.to_string(),
            r.scene.clone(),
            r.lcd_resolution.to_string(),
            r.retina_resolution.to_string(),
            r.display_samples.to_string(),
            r.la_grid.to_string(),
            r.pupil_grid.to_string(),
            r.pupil_samples.to_string(),
            r.retina_samples.to_string(),
            r.reference.clone(),
            r.threads.to_string(),
            r.cores.to_string(),
            r.git_revision.clone(),
        ];
        csv.row(fields);
    }
    csv.finish()
}

/// `builds.csv`: one line per mesh backend.
fn builds_csv(builds: &[BuildRecord]) -> String {
    let mut csv = CsvTable::new();
    csv.row(["backend", "triangles", "build_seconds", "constructor_seconds", "threads", "cores", "git_revision"]);
    for b in builds {
        csv.row([
            b.backend.as_str().to_string(),
            b.triangles.to_string(),
            b.build_seconds.to_string(),
            b.constructor_seconds.to_string(),
            b.threads.to_string(),
            b.cores.to_string(),
            b.git_revision.clone(),
        ]);
    }
    csv.finish()
}

/// Every report but `bench.json`: the CSVs, `summary.md`, `bench.md` and the plots.
pub fn write_reports(report: &BenchReport, out: &Path) -> Result<()> {
    let write = |name: &str, text: String| -> Result<()> {
        let p = out.join(name);
        crate::io::output::write_atomic(&p, |tmp| std::fs::write(tmp, &text).map_err(|e| Error::io(tmp, e)))
    };
    write("bench.csv", rows_csv(&report.rows))?;
    write("builds.csv", builds_csv(&report.builds))?;
    let (summary, full) = markdown(report);
    write("summary.md", summary)?;
    write("bench.md", full)?;
    write_plots(report, out)
}

/// `bench.json`, written last: its presence marks a complete run.
pub fn write_json(report: &BenchReport, out: &Path) -> Result<()> {
    let p = out.join("bench.json");
    let text = serde_json::to_string_pretty(report).map_err(|e| Error::serialize("serialise the bench report", e))?;
    crate::io::output::write_atomic(&p, |tmp| std::fs::write(tmp, &text).map_err(|e| Error::io(tmp, e)))
}

/// What `inimtrace bench` prints on stdout: every row as a Markdown table, the rate of each
/// convergence series, and the seconds each Table 1 estimator needs per precision target.
pub fn console_table(report: &BenchReport) -> String {
    let mut s = String::new();
    s.push_str("| series | image | backend | method | parameter | seconds | Mrays/s | PSNR (dB) | SSIM |\n");
    s.push_str("|---|---|---|---|---:|---:|---:|---:|---:|\n");
    for r in &report.rows {
        let _ = writeln!(
            s,
            "| {} | {} {} | {} | {} | {} | {:.3} | {:.1} | {:.2} | {:.4} |",
            r.series,
            r.quantity,
            r.eye_case,
            r.backend,
            r.method,
            r.parameter,
            r.seconds,
            r.rays_per_second / 1e6,
            r.psnr_db,
            r.ssim
        );
    }
    for c in &report.convergence {
        let _ = writeln!(
            s,
            "{}: error ~ samples^{}",
            c.series,
            c.rate.map(|p| format!("{p:.2}")).unwrap_or_else(|| "?".into())
        );
    }
    for r in &report.precision.reached {
        let _ = writeln!(
            s,
            "precision {}: +-{} dB {}",
            r.estimator,
            r.target_db,
            match (r.seconds, r.samples_per_pixel) {
                (Some(t), Some(n)) => format!("in {t:.3} s ({n} samples per pixel)"),
                _ => "not reached".into(),
            }
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_csv_quotes_only_fields_that_need_it() {
        let b = BuildRecord {
            backend: super::super::options::Backend::Bvh,
            triangles: 4,
            build_seconds: 0.5,
            constructor_seconds: 0.75,
            threads: 2,
            cores: 2,
            git_revision: "abc, \"dirty\"".into(),
        };
        assert_eq!(
            builds_csv(&[b]),
            "backend,triangles,build_seconds,constructor_seconds,threads,cores,git_revision\nbvh,4,0.5,0.75,2,2,\"abc, \"\"dirty\"\"\"\n"
        );
    }
}
