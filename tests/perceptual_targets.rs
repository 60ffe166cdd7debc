//! A perceptual score's `[measurement]` target drives the converged estimator's sampling as
//! PSNR's and SSIM's do (docs/PERCEPTION.md): with loose PSNR and SSIM targets a run stops at its
//! first round; a ColorVideoVDP or FLIP target a third of that round's half-width makes it sample
//! on until every cell's half-width meets the target, and the cell says the target was met.

use std::path::Path;

use inimtrace::experiment::{assess_images, RunOptions, Score};
use inimtrace::overrides::Override;
use inimtrace::perception::ScoreName;

/// The paper's converged experiment, small (a 48-pixel retina of about 14 pixels per degree, LA
/// through the eye focused at 300 mm), PSNR and SSIM targets met by any first round, scoring
/// `score` with the extra `settings`.
fn run(score: ScoreName, settings: &[String]) -> Score {
    let mut set: Vec<String> = [
        "display.lcd.resolution=[540, 540]",
        "eye.retina_resolution=48",
        "eye.retina_half_tangent=0.06",
        "methods=[\"LA\"]",
        r#"eye_cases=[{ name = "Near", focus_mm = 300.0 }]"#,
        "measurement.psnr_ci95_db=5.0",
        "measurement.ssim_ci95=0.5",
        "measurement.max_samples_per_pixel=8192",
    ]
    .map(String::from)
    .to_vec();
    set.push(format!("measurement.scores=[\"psnr\", \"ssim\", \"{}\"]", score.name()));
    set.extend_from_slice(settings);
    let set: Vec<Override> = set.iter().map(|s| s.parse().unwrap()).collect();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper-converged.toml");
    let exp = inimtrace::settings::load_experiment(Some(&path), None, &set).unwrap();
    let mut report = assess_images(&exp, None, RunOptions { quiet: true, ..Default::default() }).unwrap().report;
    assert_eq!(report.scores.len(), 1);
    report.scores.remove(0)
}

#[test]
fn a_perceptual_target_samples_on_until_its_half_width_meets_it() {
    for (score, key) in [(ScoreName::Cvvdp, "cvvdp_ci95"), (ScoreName::Flip, "flip_ci95")] {
        let first = run(score, &[]);
        let h0 = first.perceptual.get(score).unwrap().ci95.unwrap();
        assert!(h0 > 0.0 && first.target_met != Some(false), "{score}: {first:?}");
        let target = h0 / 3.0;
        let driven = run(score, &[format!("measurement.{key}={target}")]);
        let h = driven.perceptual.get(score).unwrap().ci95.unwrap();
        let (n0, n) = (first.samples_per_pixel.unwrap(), driven.samples_per_pixel.unwrap());
        eprintln!("{score}: half-width {h0:.2e} at {n0} samples per pixel; target {target:.2e}: {h:.2e} at {n}");
        assert!(h <= target, "{score}: half-width {h} above its target {target} at {n} samples per pixel");
        assert_eq!(driven.target_met, Some(true), "{score}: {driven:?}");
        assert!(n > n0, "{score}: {n} samples per pixel against {n0} without the target");
    }
}
