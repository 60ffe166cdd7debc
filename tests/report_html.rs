//! `report.html`: every run folder (assess, resolution, sweep) gets one, `inimtrace report DIR`
//! rebuilds it byte for byte, every text from the user is escaped, and a real browser (headless
//! Chromium, driven by scripts/browse-report.py over the DevTools protocol) opens it with no
//! console error and no request leaving the page, every image loaded, the table's numbers those
//! of the run's own files, and a screenshot with content. Without Chromium the browser checks
//! skip, unless INIMTRACE_REQUIRE_CHROMIUM is set (CI sets it: there they must run).

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace")).current_dir(root()).args(args).output().unwrap();
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// A small converged assess whose scene is named with markup and whose description holds some:
/// the page must show it as text.
fn assess_run(dir: &Path) -> PathBuf {
    let scene = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap().replacen(
        "name = \"paper\"",
        "name = \"<script>alert('scene')</script> & <b>\"",
        1,
    );
    let scene_path = dir.join("hostile-scene.toml");
    std::fs::write(&scene_path, scene).unwrap();
    let out = dir.join("assess");
    inimtrace(&[
        "--quiet",
        "assess",
        "experiments/paper-converged.toml",
        "--scene",
        scene_path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "display.lcd.resolution=[270, 270]",
        "--set",
        "eye.retina_resolution=24",
        "--set",
        "measurement.max_samples_per_pixel=48",
        "--set",
        "measurement.psnr_ci95_db=0.0001",
        "--set",
        "eye_cases=[{ name = \"Near\", focus_mm = 300.0 }, { name = \"Pin\", pinhole = true }]",
        "--set",
        "description=\"<script>alert('description')</script>\"",
        "--set",
        "measurement.scores=[\"psnr\", \"ssim\", \"psnr-luminance\"]",
    ]);
    out
}

fn resolution_run(dir: &Path) -> PathBuf {
    let out = dir.join("resolution");
    inimtrace(&["--quiet", "resolution", "studies/tiny.toml", "--out", out.to_str().unwrap()]);
    out
}

fn sweep_run(dir: &Path) -> PathBuf {
    let out = dir.join("sweep");
    inimtrace(&["--quiet", "sweep", "sweeps/tiny.toml", "--out", out.to_str().unwrap()]);
    out
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The page is rebuilt byte for byte by `inimtrace report`, from any spelling of the folder.
fn assert_rebuilds(out: &Path) {
    let page = std::fs::read(out.join("report.html")).unwrap();
    std::fs::remove_file(out.join("report.html")).unwrap();
    inimtrace(&["--quiet", "report", out.to_str().unwrap()]);
    assert!(std::fs::read(out.join("report.html")).unwrap() == page, "{}: rebuilt page differs", out.display());
    let parent = out.parent().unwrap();
    let relative = format!("./{}/", out.strip_prefix(parent).unwrap().display());
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace")).current_dir(parent).args(["report", &relative]).output();
    let o = o.unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(out.join("report.html")).unwrap() == page, "{}: rebuilt page differs", out.display());
}

#[test]
fn every_run_writes_a_page_that_report_rebuilds_byte_for_byte_with_user_text_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let runs = [assess_run(dir.path()), resolution_run(dir.path()), sweep_run(dir.path())];
    for out in &runs {
        let page = std::fs::read_to_string(out.join("report.html")).unwrap();
        assert!(page.starts_with("<!DOCTYPE html>"), "{}", out.display());
        assert!(
            !page.to_ascii_lowercase().contains("<script"),
            "{}: markup from the inputs or a script",
            out.display()
        );
        assert!(!page.contains("http://") && !page.contains("https://"), "{}: a network address", out.display());
        assert_rebuilds(out);
    }
    let page = std::fs::read_to_string(runs[0].join("report.html")).unwrap();
    assert!(page.contains("&lt;script&gt;alert('scene')&lt;/script&gt; &amp; &lt;b&gt;"), "the scene's name, escaped");
    assert!(page.contains("&lt;script&gt;alert('description')&lt;/script&gt;"), "the description, escaped");
    // What was simulated, in words, and the reproduction command with the overrides quoted.
    for words in ["thin-lens", "thin lenslets", "none (rays only", "peak white", "inimtrace assess", "--set"] {
        assert!(page.contains(words), "missing {words:?}");
    }
    // A folder that holds no run is refused with one line naming it.
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(["report", dir.path().to_str().unwrap()]).output();
    let o = o.unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a finished assess, resolution or sweep run"));
}

#[test]
fn a_new_run_into_the_folder_removes_the_old_page_with_the_old_report_but_never_a_users_page() {
    use inimtrace::io::output::{OutputDir, RunKind};
    let dir = tempfile::tempdir().unwrap();
    let out = resolution_run(dir.path());
    assert!(out.join("report.html").is_file());
    // The next run takes the folder: the old report goes, and the page built from it with it.
    drop(OutputDir::open(&out, RunKind::Resolution, false).unwrap());
    assert!(!out.join("study.json").exists() && !out.join("report.html").exists());
    // A page inimtrace did not write stays.
    let out = resolution_run(dir.path());
    std::fs::write(out.join("report.html"), "<!DOCTYPE html><p>my notes</p>").unwrap();
    drop(OutputDir::open(&out, RunKind::Resolution, false).unwrap());
    assert_eq!(std::fs::read_to_string(out.join("report.html")).unwrap(), "<!DOCTYPE html><p>my notes</p>");
}

/// What the browser saw (scripts/browse-report.py's answer), or why it could not look.
fn browse(page: &Path, screenshot: &Path) -> Result<serde_json::Value, String> {
    let chromium = ["chromium", "chromium-browser"]
        .into_iter()
        .find(|c| Command::new(c).arg("--version").output().is_ok_and(|o| o.status.success()))
        .ok_or("no chromium on PATH (Debian: apt-get install chromium; scripts/install-deps.sh does)")?;
    let o = Command::new("python3")
        .arg(root().join("scripts/browse-report.py"))
        .args([page, screenshot])
        .arg(chromium)
        .output()
        .map_err(|e| format!("python3: {e}"))?;
    assert!(o.status.success(), "browse-report.py: {}", String::from_utf8_lossy(&o.stderr));
    Ok(serde_json::from_slice(&o.stdout).unwrap())
}

/// A number shown with d decimals equals `exact` to within half a unit of its last digit.
fn shows(text: &str, exact: f64) -> bool {
    let decimals = text.split_once('.').map_or(0, |(_, f)| f.len()) as i32;
    text.parse::<f64>().is_ok_and(|v| (v - exact).abs() <= 0.5 * 10f64.powi(-decimals) + 1e-12)
}

fn number(v: &serde_json::Value) -> f64 {
    match v {
        serde_json::Value::String(s) if s == "inf" => f64::INFINITY,
        other => other.as_f64().unwrap(),
    }
}

/// The checks every page passes in the browser; returns what it saw.
fn check_in_browser(out: &Path) -> Option<serde_json::Value> {
    let shot = out.with_extension("screenshot.png");
    let seen = match browse(&out.join("report.html"), &shot) {
        Ok(s) => s,
        Err(why) => {
            assert!(
                std::env::var_os("INIMTRACE_REQUIRE_CHROMIUM").is_none(),
                "INIMTRACE_REQUIRE_CHROMIUM is set: {why}"
            );
            eprintln!("SKIPPED the browser checks of {}: {why}", out.display());
            return None;
        }
    };
    let name = out.display();
    assert_eq!(seen["console_errors"], serde_json::json!([]), "{name}");
    assert_eq!(seen["requests"], serde_json::json!([]), "{name}: a request left the page");
    assert_eq!(seen["blocked_requests"], serde_json::json!([]), "{name}: a request left the page");
    assert_eq!(seen["scriptCount"], 0, "{name}");
    assert!(
        seen["scrollWidth"].as_u64().unwrap() <= 1366,
        "{name}: wider than a laptop screen: {}",
        seen["scrollWidth"]
    );
    let images = seen["images"].as_array().unwrap();
    assert!(!images.is_empty(), "{name}: no image");
    for i in images {
        assert!(
            i["complete"] == true && i["naturalWidth"].as_u64().unwrap() > 0 && i["scheme"] == "data",
            "{name}: {i}"
        );
    }
    // The screenshot shows content: taller than the viewport, and far from one colour.
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples();
    let pixels = &buf[..info.buffer_size()];
    let inked = pixels.chunks(px).filter(|p| p[..3].iter().any(|&c| c < 200)).count();
    assert!(info.height > 768 && info.width >= 1000, "{name}: screenshot {} x {}", info.width, info.height);
    assert!(inked * 50 > pixels.len() / px, "{name}: the screenshot is nearly blank ({inked} inked pixels)");
    Some(seen)
}

/// The cells of the table from CSV file `file`, in order, against the file's own fields.
fn assert_csv_cells(seen: &serde_json::Value, out: &Path, file: &str) {
    let cells: Vec<&serde_json::Value> =
        seen["cells"].as_array().unwrap().iter().filter(|c| c["table"] == file).collect();
    let mut reader = csv::Reader::from_path(out.join(file)).unwrap();
    let fields: Vec<String> =
        reader.records().flat_map(|r| r.unwrap().iter().map(str::to_string).collect::<Vec<_>>()).collect();
    assert_eq!(cells.len(), fields.len(), "{file}: cells");
    for (c, f) in cells.iter().zip(&fields) {
        assert_eq!(c["text"].as_str().unwrap().trim(), f, "{file}");
    }
}

#[test]
fn a_real_browser_opens_every_kind_of_page_offline_with_the_runs_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let assess = assess_run(dir.path());
    let Some(seen) = check_in_browser(&assess) else { return };
    let results = json(&assess.join("results.json"));
    let scores = results["scores"].as_array().unwrap();
    let cells: Vec<&serde_json::Value> =
        seen["cells"].as_array().unwrap().iter().filter(|c| c["table"] == "scores-table").collect();
    let mut checked = 0;
    for c in cells.iter().filter(|c| c["score"].is_string()) {
        let s = &scores[c["row"].as_str().unwrap().parse::<usize>().unwrap()];
        let (value, ci) = match c["score"].as_str().unwrap() {
            "psnr" | "ssim" => (&s[c["score"].as_str().unwrap()]["mean"], &s[c["score"].as_str().unwrap()]["ci95"]),
            other => (&s["perceptual"][other]["value"], &s["perceptual"][other]["ci95"]),
        };
        let text = c["text"].as_str().unwrap();
        let (shown, shown_ci) = text.split_once(" ± ").unwrap_or((text, ""));
        assert!(shows(shown.trim(), number(value)), "{text} against {value}");
        if !ci.is_null() {
            assert!(shows(shown_ci.trim(), number(ci)), "{text} against ± {ci}");
        }
        checked += 1;
    }
    assert_eq!(checked, 3 * scores.len(), "every score's PSNR, SSIM and luminance PSNR cell");
    // The precision target 0.0001 dB cannot be met in 48 samples: every row is marked missed.
    let missed = cells.iter().filter(|c| c["missed"] == true).count();
    assert!(missed > 0 && scores.iter().all(|s| s["target_met"] == false), "{missed}");

    let resolution = resolution_run(dir.path());
    let seen = check_in_browser(&resolution).unwrap();
    assert_csv_cells(&seen, &resolution, "accommodation.csv");
    let sweep = sweep_run(dir.path());
    let seen = check_in_browser(&sweep).unwrap();
    assert_csv_cells(&seen, &sweep, "sweep.csv");
}
