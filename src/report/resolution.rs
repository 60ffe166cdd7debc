//! The page of a `resolution` study (the paper's Sec. 4 perceived resolution, and its
//! conclusion's Fourier analysis: docs/RESOLUTION.md), from its `study.json` and the files it
//! lists: the study as resolved, the accommodation table (focus-grid floors and ceilings
//! marked) and MTF50s, the display's limits, every plot (MTF, through-focus, accommodation,
//! orientations), and the provenance.

use std::path::Path;

use maud::html;
use serde_json::Value;

use super::assess::{folder_name, json_pairs};
use super::page::{self, facts, text};
use crate::error::Result;

/// The page of the study in `dir` whose `study.json` is `r`.
pub fn page(dir: &Path, r: &Value) -> Result<String> {
    let st = &r["study"];
    let title = format!("Resolution study {}", text(&st["name"]));
    let names: Vec<String> = r["files"].as_array().into_iter().flatten().map(|f| text(&f["name"])).collect();
    let has = |n: &str| names.iter().any(|f| f == n);
    let mut plots = Vec::new();
    for n in names.iter().filter(|n| n.ends_with(".png")) {
        plots.push(page::image(dir, n, n.trim_end_matches(".png"))?);
    }
    let display_md = if has("display.md") {
        String::from_utf8_lossy(&crate::io::input::read_regular(&dir.join("display.md"))?).into_owned()
    } else {
        String::new()
    };
    let study_facts: Vec<(&str, String)> = st
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(k, _)| k.as_str() != "name")
        .map(|(k, v)| (k.as_str(), if v.is_object() { json_pairs(v) } else { text(v) }))
        .collect();
    let body = html! {
        @if let Some(d) = st["description"].as_str().filter(|d| !d.is_empty()) { p { (d) } }
        h2 id="simulated" { "What was simulated" }
        (facts(&study_facts))
        (facts(&[
            ("Central depth plane", match r["central_depth_plane_mm"].as_f64() {
                Some(z) => format!("{z:.1} mm ({:.3} D)", 1000.0 / z), None => "at infinity or real".into() }),
            ("Sources", r["sources"].as_array().map(|a| a.iter().map(text).collect::<Vec<_>>().join(", ")).unwrap_or_default()),
            ("Eye rays", text(&r["eye_rays"])),
        ]))
        @if has("accommodation.csv") {
            h2 id="accommodation" { "Accommodation" }
            p.note { "The focus each source drives the eye to, with its 95% interval; a row at the focus grid's floor or ceiling (grid_edge) is marked: the true focus may lie beyond the grid." }
            (page::csv_table(dir, "accommodation.csv")?)
        }
        @if has("mtf50.csv") {
            h2 id="mtf50" { "MTF50" }
            (page::csv_table(dir, "mtf50.csv")?)
        }
        @if !display_md.is_empty() {
            h2 id="display" { "The display's limits" }
            pre { (display_md) }
        }
        @if !plots.is_empty() {
            h2 id="plots" { "Plots" }
            @for p in &plots { (p) }
        }
        (page::provenance(r, &command(dir, r)))
    };
    Ok(page::document(&title, body))
}

fn command(dir: &Path, r: &Value) -> String {
    let p = &r["provenance"];
    let study = p["study_path"].as_str().map(str::to_string).unwrap_or_else(|| text(&r["study"]["source"]));
    let mut words = vec!["inimtrace".to_string(), "resolution".to_string(), study, "--out".into(), folder_name(dir)];
    for s in p["set"].as_array().into_iter().flatten() {
        words.push("--set".into());
        words.push(text(s));
    }
    page::command_line(&words)
}
