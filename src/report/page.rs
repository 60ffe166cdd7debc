//! The page's frame and its building blocks: the HTML document (one file, its style sheet inline,
//! print rules included, no script), sections, definition lists, tables of numbers, images
//! inlined as `data:` URIs, the files of the folder with their hashes, and the command that
//! reproduces the run. Every text is escaped by `maud`, which escapes `&`, `<`, `>` and `"` in
//! every `(expression)` it splices (its `Render` for strings), at compile time checked markup;
//! only the constant style sheet is spliced unescaped.

use std::path::Path;

use base64::Engine;
use maud::{html, Markup, PreEscaped, DOCTYPE};
use serde_json::Value;

use crate::error::{Error, Result};

/// The style sheet: a readable column on a laptop screen, tables that scroll sideways rather
/// than overflow, images scaled to the column, and print rules (no backgrounds, no breaks
/// inside figures and table rows, URLs not expanded).
const CSS: &str = "\
body{font:15px/1.45 system-ui,-apple-system,'DejaVu Sans',sans-serif;color:#1b1b1b;background:#fff;\
max-width:1180px;margin:0 auto;padding:1.2em 1.6em}\
h1{font-size:1.5em;margin:.2em 0 .4em}h2{font-size:1.2em;border-bottom:1px solid #ccc;margin-top:1.6em}\
h3{font-size:1.02em;margin:1em 0 .3em}\
dl{display:grid;grid-template-columns:max-content 1fr;gap:.2em 1em;margin:.4em 0}dt{font-weight:600}dd{margin:0}\
.scroll{overflow-x:auto}table{border-collapse:collapse;font-size:.9em;margin:.5em 0}\
th,td{border:1px solid #ccc;padding:.2em .45em;text-align:left;vertical-align:top}\
td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}\
tr.missed td{background:#fde8e8}.missed-mark{color:#a00;font-weight:600}\
figure{margin:.6em 0;break-inside:avoid}figcaption{font-size:.85em;color:#444}\
img{max-width:100%;height:auto;image-rendering:auto}\
.pair{display:flex;flex-wrap:wrap;gap:.6em}.pair figure{flex:0 1 260px}.pair img{width:100%}\
code,pre{font-family:'DejaVu Sans Mono',monospace;font-size:.85em}\
pre{background:#f5f5f5;padding:.5em;white-space:pre-wrap;word-break:break-all}\
.note{color:#444;font-size:.9em}\
@media print{body{max-width:none;padding:0;font-size:10pt}h2{break-after:avoid}\
tr,figure,img{break-inside:avoid}.scroll{overflow:visible}pre{background:none;border:1px solid #ccc}\
tr.missed td{background:none}a{color:inherit;text-decoration:none}table{font-size:7pt}td.n{white-space:normal}}";

/// The whole document: `title` as its heading, then `body`.
pub fn document(title: &str, body: Markup) -> String {
    html! {
        (DOCTYPE)
        html lang="en" {
            head {
                meta charset="utf-8";
                meta name="generator" content="inimtrace";
                meta name="viewport" content="width=device-width, initial-scale=1";
                // Nothing may be fetched: images are data: URIs, the style is inline.
                meta http-equiv="Content-Security-Policy"
                    content="default-src 'none'; img-src data:; style-src 'unsafe-inline'";
                title { (title) }
                style { (PreEscaped(CSS)) }
            }
            body {
                h1 { (title) }
                (body)
            }
        }
    }
    .into_string()
}

/// A definition list of (term, description) pairs; empty descriptions are left out.
pub fn facts(rows: &[(&str, String)]) -> Markup {
    html! {
        dl {
            @for (k, v) in rows.iter().filter(|(_, v)| !v.is_empty()) {
                dt { (k) } dd { (v) }
            }
        }
    }
}

/// A PNG of the folder as an `<img>` with a `data:` URI, captioned; nothing when the file is
/// absent (a run that did not write it) or `name` is not a plain name inside the folder (a
/// report's names never reach outside it).
pub fn image(dir: &Path, name: &str, caption: &str) -> Result<Markup> {
    let path = dir.join(name);
    if !crate::io::output::is_plain_name(name) || !path.is_file() {
        return Ok(html! {});
    }
    let bytes = crate::io::input::read_regular(&path)?;
    let uri = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes));
    Ok(html! {
        figure {
            img src=(uri) alt=(caption);
            figcaption { (caption) " (" code { (name) } ")" }
        }
    })
}

/// A CSV file of the folder as a table: every cell as written (full precision); a row whose
/// `target_met` is `false`, or whose `grid_edge` names the focus grid's floor or ceiling, is marked.
pub fn csv_table(dir: &Path, name: &str) -> Result<Markup> {
    let path = dir.join(name);
    let bytes = crate::io::input::read_regular(&path)?;
    let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(bytes.as_slice());
    let bad = |e: csv::Error| Error::invalid(path.display().to_string(), "CSV", e.to_string());
    let header: Vec<String> = reader.headers().map_err(bad)?.iter().map(str::to_string).collect();
    let mut rows = Vec::new();
    for r in reader.records() {
        rows.push(r.map_err(bad)?.iter().map(str::to_string).collect::<Vec<_>>());
    }
    let met = header.iter().position(|h| h == "target_met");
    let flag = header.iter().position(|h| h == "grid_edge");
    let missed = |r: &[String]| {
        met.is_some_and(|i| r.get(i).is_some_and(|v| v == "false"))
            || flag.is_some_and(|i| r.get(i).is_some_and(|v| !v.is_empty()))
    };
    Ok(html! {
        div.scroll {
            table data-file=(name) {
                thead { tr { @for h in &header { th { (h) } } } }
                tbody {
                    @for r in &rows {
                        tr class=[missed(r).then_some("missed")] {
                            @for (i, v) in r.iter().enumerate() {
                                td.n[v.parse::<f64>().is_ok()] data-column=(header.get(i).map_or("", |s| s.as_str())) { (v) }
                            }
                        }
                    }
                }
            }
        }
    })
}

/// The folder's files as the report's manifest lists them (`files`: name, bytes, CRC-32) and the
/// inputs the run read with their SHA-256 (`provenance.files`).
pub fn provenance(report: &Value, command: &str) -> Markup {
    let inputs = report["provenance"]["files"].as_array().cloned().unwrap_or_default();
    let outputs = report["files"].as_array().cloned().unwrap_or_default();
    let wd = text(&report["provenance"]["working_directory"]);
    html! {
        h2 id="provenance" { "Provenance" }
        p { "To reproduce the run, from " code { (if wd.is_empty() { "the folder it was started in" } else { wd.as_str() }) } ":" }
        pre.command { (command) }
        h3 { "Inputs read (SHA-256)" }
        div.scroll { table { thead { tr { th { "file" } th { "bytes" } th { "SHA-256" } } }
            tbody { @for f in &inputs { tr { td { code { (text(&f["path"])) } } td.n { (text(&f["bytes"])) } td { code { (text(&f["sha256"])) } } } } }
        } }
        h3 { "Files of this folder (the run's manifest: size and CRC-32)" }
        div.scroll { table { thead { tr { th { "file" } th { "bytes" } th { "CRC-32" } } }
            tbody { @for f in &outputs { tr { td { code { (text(&f["name"])) } } td.n { (text(&f["bytes"])) } td { code { (text(&f["crc32"])) } } } } }
        } }
    }
}

/// The command line `program args...`, each word quoted for a POSIX shell where it needs it.
pub fn command_line(words: &[String]) -> String {
    shell_words::join(words)
}

/// A JSON value as text: strings as they are, numbers and the rest as JSON writes them, null
/// as nothing.
pub fn text(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A number with `digits` decimals, "inf" or "-inf" for JSON's strings of them; nothing when
/// absent.
pub fn number(v: &Value, digits: usize) -> String {
    match v {
        Value::Number(n) => n.as_f64().map(|x| format!("{x:.digits$}")).unwrap_or_default(),
        Value::String(s) => s.clone(),
        _ => String::new(),
    }
}
