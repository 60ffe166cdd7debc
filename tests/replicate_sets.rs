//! Scores anyone can recompute: `assess --keep-replicates` writes each converged retinal image's
//! replicates, and `compare` on the ground truth's and a method's replicate sets gives the
//! table's de-biased PSNR and SSIM and their 95% intervals for every cell (the same numbers, to
//! 1e-9), while `compare` on the plain mean images says once that their noise biases the score.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn inimtrace(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_inimtrace")).args(args).output().unwrap()
}

fn close(a: &serde_json::Value, b: &serde_json::Value, what: &str) {
    let (x, y) = (a.as_f64().unwrap(), b.as_f64().unwrap());
    assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{what}: compare gives {x}, the table {y}");
}

fn same_estimate(from_compare: &serde_json::Value, from_table: &serde_json::Value, what: &str) {
    close(&from_compare["mean"], &from_table["mean"], &format!("{what} mean"));
    close(&from_compare["ci95"], &from_table["ci95"], &format!("{what} ci95"));
    // compare --json names the channels (`R`, `G`, `B`, and `channels_ci95: {R, G, B}`); the
    // table lists them in that order.
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        close(&from_compare[name], &from_table["channels"][c], &format!("{what} channel {name}"));
        close(
            &from_compare["channels_ci95"][name],
            &from_table["channels_ci95"][c],
            &format!("{what} channel {name} ci95"),
        );
    }
}

#[test]
fn compare_on_two_replicate_sets_reproduces_every_cell_of_the_converged_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let exp = root().join("experiments/paper-converged.toml");
    let o = inimtrace(&[
        "--quiet",
        "assess",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--keep-replicates",
        "--set",
        "display.lcd.resolution=[540, 540]",
        "--set",
        "eye.retina_resolution=48",
        "--set",
        "measurement.max_samples_per_pixel=256",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let results: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("results.json")).unwrap()).unwrap();
    let listed: Vec<&str> = results["files"].as_array().unwrap().iter().map(|f| f["name"].as_str().unwrap()).collect();
    let scores = results["scores"].as_array().unwrap();
    assert_eq!(scores.len(), 12, "3 methods x 4 eye cases");
    for cell in scores {
        let (method, case) = (cell["method"].as_str().unwrap(), cell["eye_case"].as_str().unwrap());
        let gt = format!("gt_{case}.replicates.exr");
        let sim = format!("sim_{method}_{case}.replicates.exr");
        assert!(listed.contains(&gt.as_str()) && listed.contains(&sim.as_str()), "not in the manifest: {listed:?}");
        let p = |name: &str| out.join(name).to_str().unwrap().to_string();
        let o = inimtrace(&["compare", "--json", &p(&gt), &p(&sim)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(c["replicate_sets"], true);
        same_estimate(&c["psnr_db"], &cell["psnr"], &format!("PSNR {method} {case}"));
        same_estimate(&c["ssim"], &cell["ssim"], &format!("SSIM {method} {case}"));
    }

    // The plain mean images: the naive, noise-biased scores, and a note saying so, once.
    let o = inimtrace(&["compare", &path(&out, "gt_Near.exr"), &path(&out, "sim_LA_Near.exr")]);
    assert!(o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(stderr.matches("biases PSNR and SSIM").count(), 1, "{stderr}");
    assert!(stderr.contains("--keep-replicates"), "{stderr}");

    // A replicate set against a plain image is refused, naming both.
    let o = inimtrace(&["compare", &path(&out, "gt_Near.replicates.exr"), &path(&out, "sim_LA_Near.exr")]);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("gt_Near.replicates.exr is a replicate set") && stderr.contains("sim_LA_Near.exr"),
        "{stderr}"
    );
}

#[test]
fn without_the_flag_no_replicate_sets_are_written_and_a_grid_run_says_it_has_none() {
    let dir = tempfile::tempdir().unwrap();
    for (exp, flag) in [("paper-converged.toml", false), ("paper.toml", true)] {
        let out = dir.path().join(exp);
        let exp = root().join("experiments").join(exp);
        let mut args = vec!["--quiet", "assess", exp.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(["--set", "display.lcd.resolution=[540, 540]", "--set", "eye.retina_resolution=32"]);
        if flag {
            args.push("--keep-replicates");
        }
        let o = inimtrace(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(flag, stderr.contains("--keep-replicates has nothing to keep"), "{stderr}");
        let sets = std::fs::read_dir(&out)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().contains("replicates"))
            .count();
        assert_eq!(sets, 0, "{}", out.display());
    }
}

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_str().unwrap().to_string()
}
