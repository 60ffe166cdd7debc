//! The page of an `assess` run (the paper's Sec. 4 experiment, Table 1 and Fig. 3), from its
//! `results.json` and the images it lists: what was simulated, the table of scores with their
//! intervals (every score the run measured, PSNR, SSIM and whatever `[measurement] scores`
//! added), the figure and each perceived image beside its ground truth, the plots, and the
//! provenance.

use std::path::Path;

use maud::{html, Markup};
use serde_json::Value;

use super::page::{self, facts, number, text};
use crate::error::Result;

/// The page of the run in `dir` whose `results.json` is `r`.
pub fn page(dir: &Path, r: &Value) -> Result<String> {
    let s = &r["simulated"];
    let name = text(&r["experiment"]);
    let title =
        if s.is_object() { format!("{name}: {} eye, {}", text(&s["eye"]), text(&s["lenslets"])) } else { name.clone() };
    let body = html! {
        @if let Some(d) = r["settings"]["description"].as_str() { p { (d) } }
        (simulated(r))
        (cases(r))
        (scores(r))
        (images(dir, r)?)
        (plots(dir, r)?)
        (stages(r))
        (page::provenance(r, &command(dir, r)))
    };
    Ok(page::document(&title, body))
}

fn simulated(r: &Value) -> Markup {
    let (s, d, st) = (&r["simulated"], &r["display"], &r["settings"]);
    let p = &r["provenance"];
    let m = &st["measurement"];
    let display = format!(
        "{}: v1 {} mm, v2 {} mm, f {} mm; lenslet pitch matrix {} mm; elemental-image pitch matrix {} mm; LCD {} mm, {} pixels; central depth plane {}",
        text(&d["name"]),
        text(&d["eye_to_lenslets_mm"]),
        text(&d["lenslets_to_lcd_mm"]),
        text(&d["focal_length_mm"]),
        text(&d["lenslets"]["pitch_matrix_mm"]),
        text(&d["elemental_images"]["pitch_matrix_mm"]),
        text(&d["lcd_size_mm"]),
        text(&d["lcd_resolution"]),
        match d["central_depth_plane_mm"].as_f64() {
            Some(z) => format!("{z:.1} mm ({:.3} D)", 1000.0 / z),
            None => "at infinity or real".into(),
        }
    );
    let ph = &d["photometry"];
    let photometry = if ph.is_object() {
        format!(
            "peak white {} cd/m², black {} cd/m², ambient {} lx on reflectance {}",
            text(&ph["peak_luminance"]),
            text(&ph["black_level"]),
            text(&ph["ambient_illuminance"]),
            text(&ph["reflectance"])
        )
    } else {
        String::new()
    };
    let mut citations: Vec<String> = Vec::new();
    for e in r["eyes"].as_array().into_iter().flatten() {
        let c = format!("{} ({})", text(&e["model"]), text(&e["citation"]));
        if !citations.contains(&c) {
            citations.push(c);
        }
    }
    let pupil = match &r["pupil"] {
        Value::Object(_) => format!("auto: {} mm (Watson & Yellott)", number(&r["pupil"]["diameter_mm"], 2)),
        _ => format!("{} mm", text(&st["eye"]["pupil_diameter"])),
    };
    let estimator = if m.is_object() { json_pairs(m) } else { "grid".into() };
    html! {
        h2 id="simulated" { "What was simulated" }
        (facts(&[
            ("Scene", format!("{} ({})", text(&p["scene_name"]), text(&p["scene_path"]))),
            ("Display", display),
            ("Lenslets", text(&s["lenslets"])),
            ("Photometry", photometry),
            ("Eye", text(&s["eye"])),
            ("Eye models", citations.join("; ")),
            ("Pupil", pupil),
            ("Spectrum", text(&s["spectrum"])),
            ("Diffraction", text(&s["diffraction"])),
            ("Gaze", st["eye"].get("gaze").map(json_pairs).unwrap_or_default()),
            ("Retina", format!("{} x {} pixels, half tangent {}", text(&st["eye"]["retina_resolution"]),
                text(&st["eye"]["retina_resolution"]), text(&st["eye"]["retina_half_tangent"]))),
            ("Methods", st["methods"].as_array().map(|a| a.iter().map(text).collect::<Vec<_>>().join(", ")).unwrap_or_default()),
            ("Estimator and targets", estimator),
            ("SSIM constants", text(&r["ssim_constants"])),
            ("Backend", format!("{}, {} threads", text(&r["backend"]), text(&r["threads"]))),
        ]))
    }
}

/// Every eye case: its focus as stated, and the accommodation and pupil a model solved for it.
fn cases(r: &Value) -> Markup {
    let eyes = r["eyes"].as_array().cloned().unwrap_or_default();
    let rows = r["settings"]["eye_cases"].as_array().cloned().unwrap_or_default();
    html! {
        h3 { "Eye cases" }
        div.scroll { table { thead { tr { th { "case" } th { "focus" } th { "accommodation (D)" } th { "entrance pupil (mm)" } th { "stated" } } }
        tbody { @for c in &rows {
            @let name = text(&c["name"]);
            @let eye = eyes.iter().find(|e| text(&e["eye_case"]) == name);
            tr {
                td { (name) }
                td { (focus(c)) }
                td.n { (eye.map(|e| number(&e["accommodation_d"], 3)).unwrap_or_default()) }
                td.n { (eye.map(|e| number(&e["entrance_pupil_mm"], 3)).unwrap_or_default()) }
                td { code { (json_pairs(c)) } }
            }
        } } } }
    }
}

fn focus(c: &Value) -> String {
    if c["pinhole"].as_bool() == Some(true) {
        "pinhole".into()
    } else if let Some(mm) = c["focus_mm"].as_f64() {
        format!("{mm} mm ({:.3} D)", 1000.0 / mm)
    } else if let Some(d) = c["focus_diopters"].as_f64() {
        format!("{d} D")
    } else {
        String::new()
    }
}

/// Table 1: one row per method and eye case, every score with its 95% half-width; rows whose
/// intervals missed the targets are marked.
fn scores(r: &Value) -> Markup {
    let rows = r["scores"].as_array().cloned().unwrap_or_default();
    let mut extra: Vec<String> = Vec::new();
    for s in &rows {
        for k in s["perceptual"].as_object().into_iter().flat_map(|m| m.keys()) {
            if !extra.contains(k) {
                extra.push(k.clone());
            }
        }
    }
    let missed = rows.iter().filter(|s| s["target_met"].as_bool() == Some(false)).count();
    html! {
        h2 id="scores" { "Scores" }
        p.note { "Each perceived retinal image against its ground truth: PSNR (dB, mean of the R, G, B channel PSNRs) and SSIM ("
            (text(&r["ssim_constants"])) "), then every further score the run measured, each ± its 95% half-width where the estimator knows it." }
        @if missed > 0 { p.missed-mark { (crate::count::count(missed, "row")) " missed the precision targets (marked)." } }
        div.scroll { table id="scores-table" { thead { tr {
            th { "eye case" } th { "method" } th { "PSNR (dB)" } th { "SSIM" }
            @for k in &extra { th { (k) } }
            th { "samples per pixel" } th { "replicates" } th { "targets" }
        } }
        tbody { @for (i, s) in rows.iter().enumerate() {
            tr class=[(s["target_met"].as_bool() == Some(false)).then_some("missed")] data-row=(i) {
                td { (text(&s["eye_case"])) }
                td { (text(&s["method"])) }
                (cell("psnr", &s["psnr"]["mean"], &s["psnr"]["ci95"], 3))
                (cell("ssim", &s["ssim"]["mean"], &s["ssim"]["ci95"], 4))
                @for k in &extra { (cell(k, &s["perceptual"][k]["value"], &s["perceptual"][k]["ci95"], 4)) }
                td.n { (text(&s["samples_per_pixel"])) }
                td.n { (text(&s["replicates"])) }
                td { @match s["target_met"].as_bool() { Some(true) => "met", Some(false) => span.missed-mark { "missed" }, None => "" } }
            }
        } } } }
        @if let Some(o) = r["optimization"].as_object() {
            h3 { "OPT" }
            p.note { "OPT's score bounds what LC, PC and LA could reach on its training states; its gain over them is a lower bound on the headroom, because the solve stops at its budget (table.md marks the trained and held-out rows)." }
            (facts(&o.iter().filter(|(_, v)| !v.is_array() && !v.is_object()).map(|(k, v)| (k.as_str(), text(v))).collect::<Vec<_>>()))
        }
    }
}

/// A score's cell: the value (and its half-width) as text, the exact values as data.
fn cell(score: &str, value: &Value, ci95: &Value, digits: usize) -> Markup {
    let v = number(value, digits);
    let h = number(ci95, digits);
    html! {
        td.n data-score=(score) data-value=(text(value)) data-ci95=(text(ci95)) {
            span.value { (v) } @if !h.is_empty() { " ± " span.ci95 { (h) } }
        }
    }
}

/// The figure, then each eye case's ground truth beside every method's perceived image.
fn images(dir: &Path, r: &Value) -> Result<Markup> {
    let methods: Vec<String> =
        r["settings"]["methods"].as_array().into_iter().flatten().map(text).map(|m| method_name(&m, r)).collect();
    let cases: Vec<String> =
        r["settings"]["eye_cases"].as_array().into_iter().flatten().map(|c| text(&c["name"])).collect();
    let score = |m: &str, c: &str| {
        r["scores"].as_array().into_iter().flatten().find(|s| text(&s["method"]) == m && text(&s["eye_case"]) == c).map(
            |s| format!("{}: PSNR {} dB, SSIM {}", m, number(&s["psnr"]["mean"], 2), number(&s["ssim"]["mean"], 3)),
        )
    };
    let mut rows = Vec::new();
    for c in &cases {
        let mut cells = vec![page::image(dir, &format!("gt_{c}.png"), &format!("{c}: ground truth"))?];
        for m in &methods {
            let caption = score(m, c).unwrap_or_else(|| format!("{m}: perceived"));
            cells.push(page::image(dir, &format!("sim_{m}_{c}.png"), &format!("{c}, {caption}"))?);
        }
        rows.push((c.clone(), cells));
    }
    Ok(html! {
        h2 id="figure" { "Figure" }
        (page::image(dir, "figure.png", "The figure: perceived retinal images with their scores, the ground truth (GT) first")?)
        @for (c, cells) in &rows {
            h3 { "Eye case " (c) ": each perceived image beside its ground truth" }
            div.pair { @for m in cells { (m) } }
        }
    })
}

/// A method as the run names its files: `LA` is named by its grid (`LA` for 5 x 5, else `LA<k>`).
fn method_name(m: &str, r: &Value) -> String {
    if m.eq_ignore_ascii_case("LA") {
        match r["settings"]["display_render"]["la_grid"].as_u64() {
            Some(5) | None => "LA".into(),
            Some(k) => format!("LA{k}"),
        }
    } else {
        m.to_string()
    }
}

/// Every other PNG the run wrote (OPT's convergence, the perceptual scores' maps), inlined, and
/// the display images linked (they are the LCD's size).
fn plots(dir: &Path, r: &Value) -> Result<Markup> {
    let names: Vec<String> = r["files"].as_array().into_iter().flatten().map(|f| text(&f["name"])).collect();
    let is_png = |n: &&String| n.ends_with(".png");
    let other: Vec<&String> = names
        .iter()
        .filter(is_png)
        .filter(|n| !n.starts_with("gt_") && !n.starts_with("sim_") && !n.starts_with("display_") && *n != "figure.png")
        .collect();
    let displays: Vec<&String> = names.iter().filter(is_png).filter(|n| n.starts_with("display_")).collect();
    let mut figures = Vec::new();
    for n in &other {
        figures.push(page::image(dir, n, n.trim_end_matches(".png"))?);
    }
    Ok(html! {
        @if !figures.is_empty() {
            h2 id="plots" { "Plots and maps" }
            @for f in &figures { (f) }
        }
        @if !displays.is_empty() {
            h3 { "Display images (LCD size, linked)" }
            ul { @for n in &displays { li { a href=(n) { (n) } } } }
        }
    })
}

fn stages(r: &Value) -> Markup {
    let rows = r["stages"].as_array().cloned().unwrap_or_default();
    html! {
        h2 id="time" { "Time" }
        p { "The run took " (number(&r["total_seconds"], 1)) " s." }
        details { summary { "Stages" }
            div.scroll { table { thead { tr { th { "stage" } th { "method" } th { "eye case" } th { "seconds" } } }
            tbody { @for s in &rows { tr { td { (text(&s["stage"])) } td { (text(&s["method"])) } td { (text(&s["eye_case"])) } td.n { (number(&s["seconds"], 3)) } } } } } }
        }
    }
}

/// `inimtrace assess EXPERIMENT --out FOLDER --set ...` as the run was asked.
fn command(dir: &Path, r: &Value) -> String {
    let p = &r["provenance"];
    let mut words = vec!["inimtrace".to_string(), "assess".to_string()];
    match p["experiment_path"].as_str() {
        Some(e) => words.push(e.to_string()),
        None => words.push(format!("builtin:{}", text(&r["experiment"]))),
    }
    words.push("--out".into());
    words.push(folder_name(dir));
    for s in p["set"].as_array().into_iter().flatten() {
        words.push("--set".into());
        words.push(text(s));
    }
    page::command_line(&words)
}

/// The folder's own name (the page does not depend on how the folder was reached).
pub fn folder_name(dir: &Path) -> String {
    let abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    abs.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| ".".into())
}

/// A JSON object as `key = value` pairs.
pub fn json_pairs(v: &Value) -> String {
    match v.as_object() {
        Some(m) => m.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", "),
        None => text(v),
    }
}
