//! Outputs say what was simulated: under `--set eye.model=...` and on a display with real
//! lenslets, `table.md`'s title and caption, `results.json` and the EXR headers name the eye model,
//! the spectrum, diffraction and the lenslets actually used, in one vocabulary (a schematic eye
//! carries no thin-lens field), while the paper's thin-lens images keep theirs.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A small converged `assess` of `experiments/EXPERIMENT.toml` into `dir/run` with `sets`: a
/// 270 x 270 LCD, a 16 x 16 retina, one eye case focused at 2.5 D, LC only, few samples.
fn small_assess(dir: &Path, experiment: &str, sets: &[&str]) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = dir.join(experiment);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_inimtrace"));
    cmd.current_dir(root).args(["--quiet", "assess", &format!("experiments/{experiment}.toml"), "--out"]);
    cmd.arg(&out);
    for s in [
        "display.lcd.resolution=[270, 270]",
        "eye.retina_resolution=16",
        "eye_cases=[{ name = \"Eye\", focus_diopters = 2.5 }]",
        "methods=[\"LC\"]",
        "measurement.max_samples_per_pixel=64",
    ]
    .iter()
    .chain(sets)
    {
        cmd.args(["--set", s]);
    }
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn attributes(path: &Path) -> HashMap<String, String> {
    inimtrace::io::exr::read_attributes(path).unwrap().into_iter().collect()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn a_schematic_eye_is_named_in_the_table_results_and_exr_headers_without_thin_lens_fields() {
    let dir = tempfile::tempdir().unwrap();
    let out = small_assess(dir.path(), "paper-converged", &["eye.model=\"arizona\""]);
    let table = std::fs::read_to_string(out.join("table.md")).unwrap();
    let title = table.lines().next().unwrap();
    assert!(title.starts_with("# paper-converged (arizona eye, thin lenslets)"), "{title}");
    assert!(
        table.contains(
            "Eye: arizona; spectrum: each colour channel at its display primary's wavelengths; diffraction: none"
        ),
        "{table}"
    );
    let r = json(&out.join("results.json"));
    assert_eq!(r["simulated"]["eye"], "arizona");
    assert_eq!(r["display"]["lenslet"]["kind"], "thin");
    assert_eq!(r["display"]["diffraction"], "none");
    assert!(r["display"]["photometry"]["peak_luminance"].as_f64().unwrap() > 0.0, "{}", r["display"]);
    for name in ["gt_Eye.exr", "sim_LC_Eye.exr"] {
        let a = attributes(&out.join(name));
        assert_eq!(a["inimtrace:eye"], "schematic eye", "{name}");
        assert_eq!(a["inimtrace:eye_model"], "arizona", "{name}");
        assert_eq!(a["inimtrace:diffraction"], "none", "{name}");
        assert_eq!(a["inimtrace:spectrum"], "primaries", "{name}");
        assert!(!a.contains_key("inimtrace:retina_distance_mm"), "{name}: a thin-lens field on a schematic eye");
    }
}

#[test]
fn the_papers_thin_lens_keeps_its_fields_and_real_lenslets_and_diffraction_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let thin = small_assess(dir.path(), "paper-converged", &[]);
    let a = attributes(&thin.join("gt_Eye.exr"));
    assert_eq!(a["inimtrace:eye"], "thin lens");
    assert!(a.contains_key("inimtrace:retina_distance_mm"));
    assert!(!a.contains_key("inimtrace:lenslet"), "the paper's thin lenslets add no attribute");
    let table = std::fs::read_to_string(thin.join("table.md")).unwrap();
    assert!(table.starts_with("# paper-converged (thin-lens eye, thin lenslets):"), "{table}");

    let pmma = small_assess(dir.path(), "paper-pmma", &["optics.diffraction=\"pupil\""]);
    let r = json(&pmma.join("results.json"));
    let lenslet = &r["display"]["lenslet"];
    assert_eq!(lenslet["kind"], "thick");
    assert_eq!(lenslet["material"], "PMMA");
    assert!(lenslet["thickness_mm"].as_f64().unwrap() > 0.0 && lenslet["efl_d_mm"].as_f64().unwrap() > 0.0);
    assert_eq!(r["display"]["diffraction"], "pupil");
    let table = std::fs::read_to_string(pmma.join("table.md")).unwrap();
    assert!(table.starts_with("# paper-pmma (thin-lens eye, thick PMMA lenslets, diffraction):"), "{table}");
    assert!(table.contains("diffraction: at the eye's pupil;"), "{table}");
    let sim = attributes(&pmma.join("sim_LC_Eye.exr"));
    assert_eq!(sim["inimtrace:lenslet"], "thick lenslet");
    assert_eq!(sim["inimtrace:lenslet_material"], "PMMA");
    assert_eq!(sim["inimtrace:diffraction"], "pupil");
    assert_eq!(sim["inimtrace:eye"], "thin lens");
    let display = attributes(&pmma.join("display_LC.exr"));
    assert!(display.contains_key("inimtrace:lenslet_thickness_mm"));
}

#[test]
fn the_figures_title_names_eye_lenslets_spectrum_and_diffraction() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper-pmma.toml");
    let set: Vec<inimtrace::overrides::Override> =
        ["eye.model=\"navarro\"", "optics.diffraction=\"pupil\""].iter().map(|s| s.parse().unwrap()).collect();
    let exp = inimtrace::settings::load_experiment(Some(&path), None, &set).unwrap();
    let s = inimtrace::experiment::simulated::Simulated::of(&exp);
    assert_eq!(s.figure_part(), "navarro-1985 eye, thick PMMA lenslets, primaries' spectra, diffraction pupil");
    let paper = inimtrace::settings::load_experiment(None, None, &[]).unwrap();
    let s = inimtrace::experiment::simulated::Simulated::of(&paper);
    assert_eq!(s.figure_part(), "thin-lens eye, thin lenslets, no dispersion, diffraction none");
}
