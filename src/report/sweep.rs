//! The page of a sweep (the paper's Sec. 4 experiment over ranges of its settings:
//! docs/SWEEPS.md), from its `sweep.json`, `sweep.csv`, plots and point records: the base
//! experiment and the axes, the table of every point's scores (rows that missed their precision
//! target marked), the plots and heatmaps, and the provenance (the inputs' SHA-256 from the
//! point records, each file of the folder's SHA-256).

use std::path::Path;

use maud::html;
use serde_json::Value;

use super::assess::{folder_name, json_pairs};
use super::page::{self, facts, text};
use crate::error::Result;

/// The page of the sweep in `dir` whose `sweep.json` is `r`.
pub fn page(dir: &Path, r: &Value) -> Result<String> {
    let title = format!("Sweep {}", text(&r["name"]));
    let base = &r["base"];
    let plots_dir = dir.join("plots");
    let plot_names = sorted_files(&plots_dir, ".png")?;
    let mut plots = Vec::new();
    for n in &plot_names {
        plots.push(page::image(&plots_dir, n, n.trim_end_matches(".png"))?);
    }
    let point_names = sorted_files(&dir.join("points"), ".json")?;
    // The inputs every point read (the first complete record's provenance).
    let mut provenance = Value::Null;
    if let Some(first) = point_names.first() {
        let bytes = crate::io::input::read_regular(&dir.join("points").join(first))?;
        if let Ok(v) = serde_json::from_slice::<Value>(&bytes) {
            provenance = v["provenance"].clone();
        }
    }
    let mut files = Vec::new();
    let listed = ["sweep.csv".to_string(), "sweep.json".to_string()]
        .into_iter()
        .chain(plot_names.iter().map(|n| format!("plots/{n}")))
        .chain(sorted_files(&plots_dir, ".svg")?.into_iter().map(|n| format!("plots/{n}")))
        .chain(point_names.iter().map(|n| format!("points/{n}")));
    for name in listed {
        let bytes = crate::io::input::read_regular(&dir.join(&name))?;
        files.push(serde_json::json!({
            "path": name, "bytes": bytes.len(), "sha256": crate::provenance::sha256_hex(&bytes)
        }));
    }
    let axes: Vec<String> = r["axes"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|axis| {
            axis.as_array()
                .into_iter()
                .flatten()
                .map(|k| format!("{} = {}", text(&k["key"]), k["values"]))
                .collect::<Vec<_>>()
                .join(" with ")
        })
        .collect();
    let body = html! {
        @if let Some(d) = r["description"].as_str() { p { (d) } }
        h2 id="simulated" { "What was simulated" }
        (facts(&[
            ("Base experiment", format!("{} ({})", text(&base["name"]), text(&r["experiment"]))),
            ("Scene", text(&base["scene"]["name"])),
            ("Display", text(&base["display"]["name"])),
            ("Eye", json_pairs(&base["eye"])),
            ("Optics", json_pairs(&base["optics"])),
            ("Methods", base["methods"].as_array().map(|a| a.iter().map(text).collect::<Vec<_>>().join(", ")).unwrap_or_default()),
            ("Estimator and targets", json_pairs(&base["measurement"])),
            ("Settings of every point", r["set"].as_array().map(|a| a.iter().map(text).collect::<Vec<_>>().join("; ")).unwrap_or_default()),
            ("Points", format!("{} of {} complete; {} rows missed their precision target", text(&r["complete"]), text(&r["point_count"]), text(&r["rows_missing_target"]))),
        ]))
        h3 { "Axes (declared together: zipped)" }
        ul { @for a in &axes { li { code { (a) } } } }
        h2 id="scores" { "Scores" }
        (page::csv_table(dir, "sweep.csv")?)
        @if !plots.is_empty() {
            h2 id="plots" { "Plots and heatmaps" }
            @for p in &plots { (p) }
        }
        h2 id="provenance" { "Provenance" }
        p { "To reproduce the sweep, from " code { (text(&provenance["working_directory"])) } ":" }
        pre.command { (page::command_line(&["inimtrace".into(), "sweep".into(), text(&r["sweep"]), "--out".into(), folder_name(dir)])) }
        h3 { "Inputs read (SHA-256)" }
        (hash_table(provenance["files"].as_array().map(Vec::as_slice).unwrap_or_default()))
        h3 { "Files of this folder (SHA-256)" }
        (hash_table(&files))
    };
    Ok(page::document(&title, body))
}

fn hash_table(files: &[Value]) -> maud::Markup {
    html! {
        div.scroll { table { thead { tr { th { "file" } th { "bytes" } th { "SHA-256" } } }
            tbody { @for f in files { tr { td { code { (text(&f["path"])) } } td.n { (text(&f["bytes"])) } td { code { (text(&f["sha256"])) } } } } }
        } }
    }
}

/// The names of the regular files in `dir` ending with `ext`, sorted; none when `dir` is absent.
fn sorted_files(dir: &Path, ext: &str) -> Result<Vec<String>> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Ok(Vec::new()) };
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(ext) && !n.starts_with('.'))
        .collect();
    names.sort();
    Ok(names)
}
