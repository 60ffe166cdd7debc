//! A sweep whose experiment names perceptual scores (`[measurement] scores`, docs/PERCEPTION.md)
//! carries them as `sweep.csv` columns with their 95% half-widths, removed noise bias and bias
//! flag, equal to what `assess` gives the same point by hand; plots them against the swept axis;
//! its point records read back complete (a rerun runs nothing), and a record whose perceptual
//! score was edited to a non-number does not count.
#![deny(unsafe_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .current_dir(root())
        .args(args)
        .arg("--quiet")
        .output()
        .expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A CSV file as its header and its rows of fields (no field of these files is quoted).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let split = |l: &str| l.split(',').map(String::from).collect::<Vec<_>>();
    let header = split(lines.next().unwrap());
    let rows: Vec<Vec<String>> = lines.map(split).collect();
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
    }
    (header, rows)
}

/// Rows as maps from column to field.
fn named(header: &[String], rows: &[Vec<String>]) -> Vec<BTreeMap<String, String>> {
    rows.iter().map(|r| header.iter().cloned().zip(r.iter().cloned()).collect()).collect()
}

const SCORES: [&str; 2] = ["cvvdp", "flip"];

#[test]
fn a_sweep_carries_the_perceptual_scores_with_their_intervals_as_assess_gives_them() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("perceptual.toml");
    let exp = root().join("experiments/paper-converged.toml");
    // The paper's converged experiment, small: a 48-pixel retina, LC and LA, one eye case, loose
    // PSNR and SSIM targets (one round of four replicates), two pupils.
    std::fs::write(
        &file,
        format!(
            "experiment = \"{}\"\n[set]\n\"display.lcd.resolution\" = [540, 540]\n\"eye.retina_resolution\" = 48\n\
             \"eye.retina_half_tangent\" = 0.06\n\
             \"eye_cases\" = [{{ name = \"Eye\", focus_diopters = 2.5 }}]\n\"methods\" = [\"LC\", \"LA\"]\n\
             \"measurement.psnr_ci95_db\" = 5.0\n\"measurement.ssim_ci95\" = 0.5\n\"measurement.replicates\" = 4\n\
             \"measurement.scores\" = [\"psnr\", \"ssim\", \"cvvdp\", \"flip\"]\n\
             [[axes]]\n\"eye.pupil_diameter\" = [2.0, 4.0]\n",
            exp.display()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let (ok, _, e) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", o]);
    assert!(ok, "{e}");
    let (header, fields) = read_csv(&out.join("sweep.csv"));
    for n in SCORES {
        for c in [n.to_string(), format!("{n}_ci95"), format!("{n}_noise_bias"), format!("{n}_bias_above_ci95")] {
            assert!(header.contains(&c), "sweep.csv has no column {c}: {header:?}");
        }
    }
    assert!(!header.iter().any(|h| h.starts_with("psnr-luminance")), "only the scores named: {header:?}");
    assert_eq!(header.last().map(String::as_str), Some("seconds"), "the point's time stays last");
    let rows = named(&header, &fields);
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let num = |c: &str| r[c].parse::<f64>().unwrap_or_else(|_| panic!("{c} of {r:?}"));
        let (jod, flip) = (num("cvvdp"), num("flip"));
        assert!(jod > 0.0 && jod <= 10.0, "JOD in (0, 10]: {r:?}");
        assert!((0.0..=1.0).contains(&flip), "FLIP in [0, 1]: {r:?}");
        for n in SCORES {
            let (h, b) = (num(&format!("{n}_ci95")), num(&format!("{n}_noise_bias")));
            assert!(h > 0.0 && h.is_finite() && b.is_finite(), "{n}: {r:?}");
            assert_eq!(r[&format!("{n}_bias_above_ci95")], (b.abs() > h).to_string(), "{n}'s flag: {r:?}");
        }
    }
    // The two pupils' scores of one method differ: each row holds its own point's score.
    let la: Vec<&BTreeMap<String, String>> = rows.iter().filter(|r| r["method"] == "LA").collect();
    assert_ne!(la[0]["cvvdp"], la[1]["cvvdp"], "{la:?}");

    // Point 1 by hand: the same perceptual scores, half-widths, biases and flags, digit for digit.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["complete"], 2);
    assert!(json["points"][1]["scores"][0]["perceptual"]["cvvdp"]["value"].is_string(), "{}", json["points"][1]);
    let by_hand = dir.path().join("by-hand");
    let mut args = vec!["assess".to_string(), exp.display().to_string(), "--out".into(), by_hand.display().to_string()];
    args.extend(json["points"][1]["assess_args"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()));
    let (ok, _, e) = inimtrace(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{e}");
    let (rh, rf) = read_csv(&by_hand.join("results.csv"));
    let mut compared = 0;
    for f in named(&rh, &rf).iter().filter(|f| f["record"] == "score" && f["channel"] == "mean") {
        let row = rows.iter().find(|r| r["point"] == "1" && r["method"] == f["method"]).unwrap();
        for n in SCORES {
            for c in [n.to_string(), format!("{n}_ci95"), format!("{n}_noise_bias"), format!("{n}_bias_above_ci95")] {
                assert_eq!(row[&c], f[&c], "{c} of {}", row["method"]);
            }
        }
        compared += 1;
    }
    assert_eq!(compared, 2);

    // Each perceptual score against the pupil, as PSNR and SSIM are.
    for n in ["psnr", "ssim", "cvvdp", "flip"] {
        for ext in ["png", "svg"] {
            let plot = out.join("plots").join(format!("{n}_vs_eye.pupil_diameter.{ext}"));
            assert!(std::fs::metadata(&plot).map(|m| m.len() > 1000).unwrap_or(false), "{}", plot.display());
        }
    }

    // The records read back whole: a rerun runs nothing and the table is the same.
    let csv = std::fs::read(out.join("sweep.csv")).unwrap();
    let (ok, _, e) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", o]);
    assert!(ok, "{e}");
    assert!(e.contains("2 already complete, 0 run"), "{e}");
    assert_eq!(std::fs::read(out.join("sweep.csv")).unwrap(), csv);

    // A record whose JOD was edited to a non-number does not count; collecting names why.
    let id = json["points"][0]["id"].as_str().unwrap();
    let record = out.join("points").join(format!("{id}.json"));
    let text = std::fs::read_to_string(&record).unwrap();
    let value = json["points"][0]["scores"][0]["perceptual"]["cvvdp"]["value"].as_str().unwrap();
    let edited = text.replacen(&format!("\"value\": \"{value}\""), "\"value\": \"NaN\"", 1);
    assert_ne!(edited, text);
    std::fs::write(&record, edited).unwrap();
    let (ok, _, e) = inimtrace(&["sweep", file.to_str().unwrap(), "--out", o, "--collect"]);
    assert!(ok, "{e}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["complete"], 1);
    let why = json["points"][0]["invalid_record"].as_str().unwrap_or_default();
    assert!(why.contains("cvvdp"), "{why}");
}
