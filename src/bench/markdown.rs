//! The bench's Markdown reports: `summary.md` (the run's settings, methods x backends, the
//! builds, the convergence summaries and the cost of precision) and `bench.md` (the summary, then
//! every measured point), with the text helpers the plots share.

use std::fmt::Write as _;

use super::options::{BenchRow, Estimator, MethodLabel, Quantity, Series};
use super::precision::{PRECISION_TARGETS_DB, SWEPT};
use super::BenchReport;

/// Two decimals (PSNR).
fn f2(v: f64) -> String {
    format!("{v:.2}")
}

/// Seconds: three decimals below 0.1 s, else two.
pub fn secs(v: f64) -> String {
    if v < 0.1 {
        format!("{v:.3}")
    } else {
        format!("{v:.2}")
    }
}

fn mrays(r: &BenchRow) -> String {
    format!("{:.1}", r.rays_per_second / 1e6)
}

fn load_text(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.2}")).unwrap_or_else(|| "unknown".into())
}

/// A setting of a convergence series ("k = 3", "n = 8 (52)", "2x2").
pub fn series_setting(series: Series, parameter: usize, samples: usize) -> String {
    match series {
        Series::LaGrid => format!("k = {parameter}"),
        Series::PupilGrid => format!("n = {parameter} ({samples})"),
        Series::Method | Series::RetinaSamples | Series::Precision => format!("{parameter}x{parameter}"),
    }
}

/// (summary.md, bench.md).
pub fn markdown(rep: &BenchReport) -> (String, String) {
    let mut s = String::new();
    settings_paragraph(rep, &mut s);
    methods_table(rep, &mut s);
    builds_table(rep, &mut s);
    convergence_table(rep, &mut s);
    precision_summary(rep, &mut s);
    let _ = writeln!(
        s,
        "\nCheck: LA with k = 1 renders {} display image as LC.",
        if rep.checks.la_k1_equals_lc { "bit for bit the same" } else { "**NOT** the same" }
    );

    // The full report: the summary, then every row.
    let mut full = format!("# inimtrace bench ({})\n\n{s}", rep.mode);
    let _ = writeln!(
        full,
        "\n## Plots\n\n![PSNR against wall time](speed_psnr.png)\n\n![SSIM against wall time](speed_ssim.png)\n\n\
         ![LA lenslet grid](la_grid.png)\n\n![pupil grid](pupil_grid.png)\n\n![samples per retina pixel](retina_samples.png)\n\n\
         ![The cost of precision](precision.png)\n"
    );
    method_points(rep, &mut full);
    let _ = writeln!(full, "\n## Other stages\n\n| stage | s |\n|---|---:|");
    for st in &rep.stages {
        let _ = writeln!(full, "| {} | {} |", st.stage, secs(st.seconds));
    }
    convergence_points(rep, &mut full);
    precision_points(rep, &mut full);
    (s, full)
}

/// The run: scene, sizes, the paper's settings, the machine.
fn settings_paragraph(rep: &BenchReport, s: &mut String) {
    let sz = &rep.sizes;
    let _ = writeln!(
        s,
        "Scene `{}`, paper display at {} x {} LCD pixels, retina {} x {}; paper settings: LA {}x{}, {} mm pupil with \
         an {}x{} grid, {} per retina pixel. {} on {}, git revision `{}`, \
         `inimtrace bench` ({} run, {:.0} s of measuring; 1-minute load average {} at the start, {} at the end).\n",
        rep.scene,
        sz.lcd_resolution,
        sz.lcd_resolution,
        sz.retina_resolution,
        sz.retina_resolution,
        rep.la_grid,
        rep.la_grid,
        rep.pupil_diameter_mm,
        rep.pupil_grid,
        rep.pupil_grid,
        crate::count::count(rep.retina_samples, "sample"),
        crate::count::count(rep.threads, "worker thread"),
        crate::count::count(rep.cores, "logical core"),
        rep.git_revision,
        rep.mode,
        rep.total_seconds,
        load_text(rep.load_average[0]),
        load_text(rep.load_average[1])
    );
}

/// Methods x backends at one sample per display pixel.
fn methods_table(rep: &BenchReport, s: &mut String) {
    let sz = &rep.sizes;
    let _ = writeln!(
        s,
        "**Methods x backends** (one sample per display pixel). Display image: render time, camera rays per second, \
         PSNR (dB) / SSIM against the same method with {r}x{r} samples per pixel (LA: {la}x{la} lenslet grid). \
         Perceived images: display render plus simulation (pupil grid {pg}, one sample per retina pixel), against \
         the reference display image seen with pupil grid {rp} and {rr}x{rr} samples per retina pixel.\n",
        r = sz.reference_display_samples,
        la = sz.reference_la_grid,
        pg = rep.pupil_grid,
        rp = sz.reference_pupil_grid,
        rr = sz.reference_retina_samples
    );
    let mut head = "| method | backend | display s | Mrays/s | PSNR / SSIM |".to_string();
    let mut rule = "|---|---|---:|---:|---:|".to_string();
    for (c, mm) in &rep.eye_cases {
        let _ = write!(head, " {c} ({mm:.0} mm) s | PSNR / SSIM |");
        rule.push_str("---:|---:|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
    for m in MethodLabel::METHODS {
        for b in &rep.backends {
            let find = |quantity: Quantity, eye: &str| {
                rep.rows.iter().find(|r| {
                    r.series == Series::Method
                        && r.quantity == quantity
                        && r.eye_case == eye
                        && r.parameter == 1
                        && r.method == m
                        && r.backend == *b
                })
            };
            let Some(d) = find(Quantity::Display, "") else { continue };
            let _ = write!(s, "| {m} | {b} | {} | {} | {} / {:.4} |", secs(d.seconds), mrays(d), f2(d.psnr_db), d.ssim);
            for (c, _) in &rep.eye_cases {
                match find(Quantity::Perceived, c) {
                    Some(p) => {
                        let _ = write!(s, " {} | {} / {:.4} |", secs(p.seconds), f2(p.psnr_db), p.ssim);
                    }
                    None => s.push_str(" | |"),
                }
            }
            s.push('\n');
        }
    }
}

/// The mesh backends' acceleration structures.
fn builds_table(rep: &BenchReport, s: &mut String) {
    let _ = writeln!(
        s,
        "\n**Acceleration structures** of the mesh backends on the tessellated scene (Embree at its high build \
         quality):\n\n| backend | triangles | build (ms) | whole constructor (ms) |\n|---|---:|---:|---:|"
    );
    for b in &rep.builds {
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {:.3} |",
            b.backend,
            b.triangles,
            1e3 * b.build_seconds,
            1e3 * b.constructor_seconds
        );
    }
}

/// One line per convergence series: its rate and highest setting.
fn convergence_table(rep: &BenchReport, s: &mut String) {
    let _ = writeln!(
        s,
        "\n**Convergence** on the {} backend, each quantity against its own high-sample reference. Rate p: \
         least-squares slope of ln(error) against ln(samples per pixel) over the whole sweep, error = 10^(-PSNR/20) \
         (the geometric mean of the R, G, B RMSEs). At these rates every series still gains several dB at its \
         highest setting; what the numbers users report (Table 1) cost at a given precision is the cost of \
         precision below.\n\n| series | against | rate p (error ~ N^p) | highest setting: PSNR, s |\n|---|---|---:|---:|",
        rep.backends.first().map(|b| b.as_str()).unwrap_or("?"),
    );
    for c in &rep.convergence {
        let highest = rep.rows.iter().rfind(|r| r.series == c.series).map(|r| r.samples).unwrap_or(0);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {}: {} dB, {} s |",
            c.quantity,
            c.reference,
            c.rate.map(|p| format!("{p:.2}")).unwrap_or_else(|| "-".into()),
            series_setting(c.series, c.highest_parameter, highest),
            f2(c.converged_psnr_db),
            secs(c.highest_seconds),
        );
    }
}

/// Every point of the `method` series, for bench.md.
fn method_points(rep: &BenchReport, full: &mut String) {
    let _ = writeln!(
        full,
        "## Every speed-against-error point\n\nSamples per display pixel: {}; perceived seconds include the display \
         render, perceived rays the eye rays of the simulation.\n\n| method | backend | samples/px | image | s | Mrays/s | PSNR | SSIM |\n|---|---|---:|---|---:|---:|---:|---:|",
        rep.sizes.display_samples.iter().map(|k| format!("{k}x{k}")).collect::<Vec<_>>().join(", ")
    );
    for r in rep.rows.iter().filter(|r| r.series == Series::Method) {
        let what =
            if r.eye_case.is_empty() { r.quantity.to_string() } else { format!("{} {}", r.quantity, r.eye_case) };
        let _ = writeln!(
            full,
            "| {} | {} | {}x{} | {} | {} | {} | {} | {:.4} |",
            r.method,
            r.backend,
            r.parameter,
            r.parameter,
            what,
            secs(r.seconds),
            mrays(r),
            f2(r.psnr_db),
            r.ssim
        );
    }
}

/// Every point of each convergence series, for bench.md.
fn convergence_points(rep: &BenchReport, full: &mut String) {
    for c in &rep.convergence {
        let _ = writeln!(
            full,
            "\n## Convergence: {}\n\nAgainst {} ({} backend). Observed rate p = {}.\n\n| setting | samples | s | Mrays/s | PSNR | SSIM |\n|---|---:|---:|---:|---:|---:|",
            c.quantity,
            c.reference,
            c.backend,
            c.rate.map(|p| format!("{p:.2}")).unwrap_or_else(|| "-".into())
        );
        for r in rep.rows.iter().filter(|r| r.series == c.series) {
            let _ = writeln!(
                full,
                "| {} | {} | {} | {} | {} | {:.4} |",
                series_setting(c.series, r.parameter, r.samples),
                r.samples,
                secs(r.seconds),
                mrays(r),
                f2(r.psnr_db),
                r.ssim
            );
        }
    }
}

/// What an estimator is, in words.
pub fn estimator_name(e: Estimator) -> &'static str {
    match e {
        Estimator::Grid => "grid (paper: pupil grid n x n, s x s per retina pixel)",
        Estimator::Random => "random (independent points, PSNR of the mean image)",
        Estimator::RqmcNaive => "RQMC naive (PSNR of the replicates' mean image)",
        Estimator::Rqmc => "RQMC de-biased (cross-replicate)",
        Estimator::Reference => "converged reference",
    }
}

/// The cost-of-precision section of summary.md: the reference and the seconds each estimator
/// needs per target.
fn precision_summary(rep: &BenchReport, s: &mut String) {
    let p = &rep.precision;
    if p.points.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n**The cost of precision** on the {} backend: Table 1 (PSNR of the perceived image against the ground truth, \
         every method and eye case) by each estimator, against the converged Table 1 (a reference run of the \
         de-biased RQMC estimator with its own seed, to a 95% half-width of {} dB; reached {:.4} dB with {} samples \
         per pixel in {} s, stopped by: {}). Error: the largest |PSNR - converged PSNR| over Table 1's cells. Seconds: eye rays and \
         scoring of the whole Table 1 (the display images, common to all, not counted); RQMC and random use {} \
         replicates. Seconds to stay within each target from then on to the sweep's top (\"not reached\": the top \
         is not within it):\n",
        rep.backends.first().map(|b| b.as_str()).unwrap_or("?"),
        p.reference_target_db,
        p.reference_ci95_db,
        p.reference_samples_per_pixel,
        secs(p.reference_seconds),
        p.reference_stopped_by,
        p.replicates,
    );
    let _ = write!(s, "| estimator |");
    for t in PRECISION_TARGETS_DB {
        let _ = write!(s, " +-{t} dB |");
    }
    let _ = writeln!(s, "\n|---|{}", "---:|".repeat(PRECISION_TARGETS_DB.len()));
    for e in SWEPT {
        let _ = write!(s, "| {} |", estimator_name(e));
        for r in p.reached.iter().filter(|r| r.estimator == e) {
            let _ = match (r.seconds, r.samples_per_pixel) {
                (Some(t), Some(n)) => write!(s, " {} s ({n}) |", secs(t)),
                _ => write!(s, " not reached |"),
            };
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "\n(In parentheses: samples per retina pixel.)");
}

/// Every point of the cost-of-precision sweep, for bench.md.
fn precision_points(rep: &BenchReport, full: &mut String) {
    let p = &rep.precision;
    if p.points.is_empty() {
        return;
    }
    let _ = writeln!(
        full,
        "\n## The cost of precision\n\nLargest |error| over Table 1's cells against the converged Table 1.\n\n\
         | estimator | setting | samples per pixel | s | max PSNR error (dB) | max SSIM error |\n|---|---|---:|---:|---:|---:|"
    );
    for pt in &p.points {
        let _ = writeln!(
            full,
            "| {} | {} | {} | {} | {:.4} | {:.5} |",
            pt.estimator,
            pt.setting,
            pt.samples_per_pixel,
            secs(pt.seconds),
            pt.max_psnr_error_db,
            pt.max_ssim_error
        );
    }
}
