//! The bench's Markdown reports: `summary.md` (the run's settings, methods x backends, the
//! builds, the convergence summaries and Table 1 convergence) and `bench.md` (the summary, then
//! every measured point), with the text helpers the plots share.

use std::fmt::{Display, Write as _};

use super::options::{BenchRow, MethodLabel, Parameter, Quantity, Series};
use super::summary::{max_abs_diff, MethodSet, Table1Sweep, Table1Within, CONVERGED_TOLERANCE_DB};
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

fn join<T: Display>(items: &[T], separator: &str) -> String {
    items.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(separator)
}

/// A setting of a convergence series ("k = 3", "n = 8 (52)", "2x2").
pub fn series_setting(series: Series, parameter: usize, samples: usize) -> String {
    match series {
        Series::LaGrid => format!("k = {parameter}"),
        Series::PupilGrid => format!("n = {parameter} ({samples})"),
        Series::Method | Series::RetinaSamples | Series::Table1 => format!("{parameter}x{parameter}"),
    }
}

/// What a Table 1 sweep varies, for tables and plots.
pub fn sweep_name(sweep: Parameter) -> &'static str {
    match sweep {
        Parameter::RetinaSamples => "samples per retina pixel, k x k",
        Parameter::DisplaySamples => "samples per display pixel, k x k",
        Parameter::PupilGrid => "pupil grid n x n",
        Parameter::LaGrid => "LA lenslet grid k x k",
    }
}

/// A setting of a Table 1 sweep, in words.
fn table1_setting(sweep: Parameter, parameter: usize, samples: usize) -> String {
    match sweep {
        Parameter::RetinaSamples => format!("{parameter}x{parameter} per retina pixel"),
        Parameter::DisplaySamples => format!("{parameter}x{parameter} per display pixel"),
        Parameter::PupilGrid => format!("pupil n = {parameter} ({samples})"),
        Parameter::LaGrid => format!("LA k = {parameter}"),
    }
}

/// (summary.md, bench.md).
pub fn markdown(rep: &BenchReport) -> (String, String) {
    let mut s = String::new();
    settings_paragraph(rep, &mut s);
    methods_table(rep, &mut s);
    builds_table(rep, &mut s);
    convergence_table(rep, &mut s);
    table1_summary(rep, &mut s);
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
         ![Table 1 convergence](table1.png)\n"
    );
    method_points(rep, &mut full);
    let _ = writeln!(full, "\n## Other stages\n\n| stage | s |\n|---|---:|");
    for st in &rep.stages {
        let _ = writeln!(full, "| {} | {} |", st.stage, secs(st.seconds));
    }
    convergence_points(rep, &mut full);
    table1_points(rep, &mut full);
    (s, full)
}

/// The run: scene, sizes, the paper's settings, the machine.
fn settings_paragraph(rep: &BenchReport, s: &mut String) {
    let sz = &rep.sizes;
    let _ = writeln!(
        s,
        "Scene `{}`, paper display at {} x {} LCD pixels, retina {} x {}; paper settings: LA {}x{}, {} mm pupil with \
         an {}x{} grid, {} sample(s) per retina pixel. {} worker thread(s) on {} logical core(s), git revision `{}`, \
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
        rep.retina_samples,
        rep.threads,
        rep.cores,
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
         highest setting; which settings are enough for the numbers users report is the Table 1 convergence \
         below.\n\n| series | against | rate p (error ~ N^p) | highest setting: PSNR, s |\n|---|---|---:|---:|",
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

fn table1_samples(rep: &BenchReport, sweep: Parameter, parameter: usize) -> usize {
    rep.table1_rows(sweep).find(|r| r.parameter == parameter).map(|r| r.samples).unwrap_or(0)
}

fn table1_within_text(t: &Table1Sweep, w: Option<&Table1Within>, diff: bool) -> String {
    match w {
        Some(w) => format!(
            "{}, {} s{}{}",
            table1_setting(t.sweep, w.parameter, w.samples),
            secs(w.seconds),
            if diff { format!(" ({:.2})", w.max_diff_db) } else { String::new() },
            if w.stays_within { "" } else { " *" }
        ),
        None => "-".into(),
    }
}

/// The eye cases of some rows, in first-seen order.
fn eye_cases<'a>(rows: impl Iterator<Item = &'a BenchRow>) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for r in rows {
        if !v.contains(&r.eye_case) {
            v.push(r.eye_case.clone());
        }
    }
    v
}

/// The Table 1 convergence section of summary.md.
fn table1_summary(rep: &BenchReport, s: &mut String) {
    let Some(first) = rep.table1.first() else { return };
    let methods: Vec<MethodSet> = first.per_method.iter().map(|w| w.methods).collect();
    let cases = eye_cases(rep.table1_rows(first.sweep));
    let paper_display =
        rep.table1.iter().find(|t| t.sweep == Parameter::DisplaySamples).map(|t| t.paper_parameter).unwrap_or(1);
    let _ = writeln!(
        s,
        "\n**Table 1 convergence** on the {} backend: the paper's Table 1 as `inimtrace assess` computes it (PSNR of \
         the perceived image against the ground-truth retinal image, mean of R, G, B; {} x {}), with one sampling \
         parameter swept and the others at the paper's settings ({}x{} per retina pixel, {}x{} per display pixel, \
         pupil n = {}, LA k = {}). Converged: the Table 1 of the sweep's highest setting. Seconds: computing the \
         whole Table 1 at that setting ({} display images, {} ground truths and simulations, the scores; no files); \
         images a sweep does not change are computed once and their time counted at each setting. \"Within {} \
         dB\": the cheapest setting (fewest samples) whose Table-1 PSNRs are all within {} dB of their converged \
         values, for every method and eye case at once (\"all\") and for each method's {} eye cases{}.\n",
        first.backend,
        join(&methods, ", "),
        cases.join(", "),
        rep.retina_samples,
        rep.retina_samples,
        paper_display,
        paper_display,
        rep.pupil_grid,
        rep.la_grid,
        methods.len(),
        cases.len(),
        CONVERGED_TOLERANCE_DB,
        CONVERGED_TOLERANCE_DB,
        cases.len(),
        if rep.table1.iter().flat_map(|t| t.all_methods.iter().chain(&t.per_method)).any(|w| !w.stays_within) {
            format!("; `*`: a higher setting of the sweep is again more than {CONVERGED_TOLERANCE_DB} dB away")
        } else {
            String::new()
        }
    );
    let mut head = format!(
        "| parameter swept | settings | paper's setting: largest diff. to converged (dB) | converged: highest \
         setting, s | last step (dB) | within {CONVERGED_TOLERANCE_DB} dB, all: setting, s (largest diff., dB) |"
    );
    let mut rule = "|---|---|---:|---:|---:|---:|".to_string();
    for m in &methods {
        let _ = write!(head, " {m} |");
        rule.push_str("---:|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
    for t in &rep.table1 {
        let paper = match t.paper_max_diff_db {
            Some(d) => format!(
                "{}: {:.2}",
                table1_setting(t.sweep, t.paper_parameter, table1_samples(rep, t.sweep, t.paper_parameter)),
                d
            ),
            None => "-".into(),
        };
        let _ = write!(
            s,
            "| {} | {} | {} | {}, {} s | {} | {} |",
            sweep_name(t.sweep),
            join(&t.parameters, ", "),
            paper,
            table1_setting(t.sweep, t.converged_parameter, table1_samples(rep, t.sweep, t.converged_parameter)),
            t.seconds.last().map(|v| secs(*v)).unwrap_or_default(),
            t.last_step_db.map(|d| format!("{d:.2}")).unwrap_or_else(|| "-".into()),
            table1_within_text(t, t.all_methods.as_ref(), true)
        );
        for m in &methods {
            let w = t.per_method.iter().find(|w| &w.methods == m);
            let _ = write!(s, " {} |", table1_within_text(t, w, false));
        }
        s.push('\n');
    }
    table1_answer(rep, s);
}

/// The answer of the Table 1 series in words.
fn table1_answer(rep: &BenchReport, s: &mut String) {
    let answers: Vec<String> = rep
        .table1
        .iter()
        .filter_map(|t| {
            t.all_methods.as_ref().map(|w| {
                let open = t.last_step_db.is_some_and(|d| d > CONVERGED_TOLERANCE_DB);
                format!(
                    "{} ({} s{})",
                    table1_setting(t.sweep, w.parameter, w.samples),
                    secs(w.seconds),
                    if open {
                        format!(
                            "; the sweep's highest setting, not levelled off: its last step still moves Table 1 by \
                             {:.2} dB",
                            t.last_step_db.unwrap_or(f64::NAN)
                        )
                    } else {
                        String::new()
                    }
                )
            })
        })
        .collect();
    let paper_off: Vec<String> = rep
        .table1
        .iter()
        .filter_map(|t| t.paper_max_diff_db.map(|d| format!("{d:.2} dB ({})", sweep_name(t.sweep))))
        .collect();
    let _ = writeln!(
        s,
        "\nOne parameter at a time, every method and eye case of Table 1 is within {} dB of its converged value \
         from: {}. At the paper's settings Table 1 is off its converged value by up to {}.",
        CONVERGED_TOLERANCE_DB,
        answers.join("; "),
        paper_off.join(", ")
    );
}

/// Every point of every Table 1 sweep, for bench.md: PSNR then SSIM, one table each.
fn table1_points(rep: &BenchReport, full: &mut String) {
    for t in &rep.table1 {
        for ssim in [false, true] {
            table1_sweep_table(rep, t, ssim, full);
        }
    }
}

/// The PSNR (or SSIM) table of one Table 1 sweep.
fn table1_sweep_table(rep: &BenchReport, t: &Table1Sweep, ssim: bool, full: &mut String) {
    let rows: Vec<&BenchRow> = rep.table1_rows(t.sweep).collect();
    let cases = eye_cases(rows.iter().copied());
    let mut methods: Vec<MethodLabel> = Vec::new();
    for r in &rows {
        if !methods.contains(&r.method) {
            methods.push(r.method);
        }
    }
    let value = |p: usize, c: &str, m: MethodLabel| {
        rows.iter()
            .find(|r| r.parameter == p && r.eye_case == c && r.method == m)
            .map(|r| if ssim { format!("{:.4}", r.ssim) } else { f2(r.psnr_db) })
            .unwrap_or_else(|| "-".into())
    };
    let converged: Vec<f64> = rows.iter().filter(|r| r.parameter == t.converged_parameter).map(|r| r.psnr_db).collect();
    let _ = writeln!(
        full,
        "\n## Table 1 convergence: {}{}\n\n{} of the perceived image against the ground truth ({} backend), \
         the other parameters at the paper's settings; s: computing the whole Table 1 at that setting{}.\n",
        sweep_name(t.sweep),
        if ssim { " (SSIM)" } else { "" },
        if ssim { "SSIM (Wang 2004)" } else { "PSNR (dB)" },
        t.backend,
        if ssim { "" } else { "; largest diff.: largest |PSNR - converged PSNR| over every method and eye case" }
    );
    let mut head = "| setting | s | Mrays/s |".to_string();
    let mut rule = "|---|---:|---:|".to_string();
    for c in &cases {
        let _ = write!(head, " {c} {} |", join(&methods, " / "));
        rule.push_str("---:|");
    }
    if !ssim {
        head.push_str(" largest diff. (dB) |");
        rule.push_str("---:|");
    }
    let _ = writeln!(full, "{head}\n{rule}");
    for (i, &p) in t.parameters.iter().enumerate() {
        let Some(first) = rows.iter().find(|r| r.parameter == p) else { continue };
        let _ = write!(
            full,
            "| {}{} | {} | {} |",
            table1_setting(t.sweep, p, first.samples),
            if p == t.paper_parameter { " (paper)" } else { "" },
            secs(t.seconds[i]),
            mrays(first)
        );
        for c in &cases {
            let v: Vec<String> = methods.iter().map(|m| value(p, c, *m)).collect();
            let _ = write!(full, " {} |", v.join(" / "));
        }
        if !ssim {
            let here: Vec<f64> = rows.iter().filter(|r| r.parameter == p).map(|r| r.psnr_db).collect();
            let _ = write!(full, " {:.3} |", max_abs_diff(&here, &converged));
        }
        full.push('\n');
    }
}
