//! The distortion map files of the perceptual scores (docs/PERCEPTION.md): one EXR (channel `Y`)
//! and one PNG heatmap per score, method and eye case, of the retina's size. Each EXR decodes to
//! the metric's own map of the run's images as written (its ground truth and perceived image
//! read back), under the thin-lens eye and with the Navarro eye's optics counted once (`neural`);
//! under the grid estimator its FLIP mean is the reported FLIP and ColorVideoVDP's JOD of those
//! images the reported JOD; under the converged estimator the maps are of the replicates' mean
//! images, whose FLIP is the reported value plus the noise bias removed from it. Each PNG
//! pixel is the Magma colour of its value.

use std::path::Path;

use inimtrace::experiment::{assess, Experiment, RunOptions, Score};
use inimtrace::io::exr::read_rgb;
use inimtrace::overrides::Override;
use inimtrace::perception::{cvvdp::Cvvdp, flip::flip, Compensation, ScoreName, Viewing};
use inimtrace::raster::RgbImage;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `file` small (a 48-pixel retina of about 7 pixels per degree, LC and LA) scoring ColorVideoVDP
/// and FLIP, with the extra `settings`.
fn experiment(file: &str, settings: &[&str]) -> Experiment {
    let mut set = vec![
        "display.lcd.resolution=[540, 540]",
        "eye.retina_resolution=48",
        "eye.retina_half_tangent=0.06",
        "methods=[\"LC\", \"LA\"]",
        "measurement.scores=[\"psnr\", \"ssim\", \"cvvdp\", \"flip\"]",
    ];
    set.extend_from_slice(settings);
    let set: Vec<Override> = set.iter().map(|s| s.parse().unwrap()).collect();
    inimtrace::settings::load_experiment(Some(&root().join(file)), None, &set).unwrap()
}

/// A map file's values and size, decoded by the `exr` crate (its one channel `Y`).
fn read_map(path: &Path) -> (Vec<f32>, (usize, usize)) {
    use exr::prelude::*;
    let image = read_first_flat_layer_from_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let layer = &image.layer_data;
    assert_eq!(layer.channel_data.list.len(), 1, "{}: one channel", path.display());
    let channel = &layer.channel_data.list[0];
    assert_eq!(channel.name, Text::from("Y"), "{}", path.display());
    let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
    (values, (layer.size.width(), layer.size.height()))
}

/// The PNG heatmap: its size and that every pixel is the Magma colour of its map value.
fn check_heatmap(path: &Path, values: &[f32], size: (usize, usize)) {
    let png = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    assert_eq!((png.width() as usize, png.height() as usize), size, "{}", path.display());
    for (p, v) in png.pixels().zip(values) {
        let want = flip_rs::MAGMA[(v.clamp(0.0, 1.0) * 255.0 + 0.5) as usize].map(|c| (c * 255.0 + 0.5) as u8);
        assert_eq!(p.0, want, "{}: value {v}", path.display());
    }
}

/// The largest difference of two maps, and that they have one value per pixel each.
fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

/// Runs `exp` into a temporary folder and checks every map against the metric's own map of the
/// run's images (with the typical eye's optics divided out when `compensated`); calls `check`
/// with each score, its map's mean (f32 sum, as FLIP's own mean) and the metric's JOD or mean FLIP
/// of the images written. Returns how many maps were checked.
fn check_maps(exp: &Experiment, compensated: bool, check: &dyn Fn(&Score, ScoreName, f64, f64)) -> usize {
    let dir = tempfile::tempdir().unwrap();
    let report = assess(exp, dir.path(), RunOptions { quiet: true, ..Default::default() }).unwrap();
    // The display's luminance and the retina's pixels per degree (docs/PERCEPTION.md).
    let viewing = Viewing::of_retina(&exp.retina, exp.luminance);
    let n = exp.retina.resolution;
    let mut checked = 0;
    for (c, case) in exp.cases.iter().enumerate() {
        let gt = read_rgb(&dir.path().join(format!("gt_{}.exr", case.name))).unwrap();
        let seen = |img: &RgbImage| -> RgbImage {
            match compensated {
                true => Compensation::new(pupil(exp, c), viewing.pixels_per_degree).apply(img),
                false => img.clone(),
            }
        };
        for m in &exp.methods {
            let sim = read_rgb(&dir.path().join(format!("sim_{}_{}.exr", m.name(), case.name))).unwrap();
            let (t, r) = (seen(&sim), seen(&gt));
            let score = report.scores.iter().find(|s| s.method == m.name() && s.eye_case == case.name).unwrap();
            for name in [ScoreName::Cvvdp, ScoreName::Flip] {
                let stem = format!("map_{}_{}_{}", name.name(), m.name(), case.name);
                let (values, size) = read_map(&dir.path().join(format!("{stem}.exr")));
                assert_eq!(size, (n, n), "{stem}: the retina's size");
                // FLIP's error is within [0, 1]; ColorVideoVDP's `1 - JOD_pixel / 10` is at least 0
                // (JOD at most 10) and passes 1 where a pixel's JOD extrapolates below 0.
                let top = if name == ScoreName::Flip { 1.0 } else { f32::INFINITY };
                assert!(
                    values.iter().all(|v| v.is_finite() && (0.0..=top).contains(v)),
                    "{stem}: values in [0, {top}]"
                );
                let (own, metric) = match name {
                    ScoreName::Cvvdp => {
                        let j = Cvvdp::new(&viewing, n, n, true).unwrap().score(&t, &r).unwrap();
                        (j.map.unwrap(), j.jod)
                    }
                    _ => {
                        let f = flip(&t, &r, &viewing).unwrap();
                        (f.map, f.mean)
                    }
                };
                let d = max_diff(&values, &own);
                assert!(d <= 1e-6, "{stem}: {d} from the metric's own map of the images written");
                let mean = values.iter().sum::<f32>() / values.len() as f32;
                check(score, name, f64::from(mean), metric);
                check_heatmap(&dir.path().join(format!("{stem}.png")), &values, size);
                checked += 1;
            }
        }
    }
    checked
}

fn pupil(exp: &Experiment, c: usize) -> f64 {
    match exp.cases[c].eye.aperture {
        inimtrace::optics::Aperture::ThinLens { pupil_diameter, .. } => pupil_diameter,
        inimtrace::optics::Aperture::Pinhole => 0.0,
    }
}

#[test]
fn grid_maps_are_the_metrics_maps_and_their_flip_mean_is_the_reported_flip() {
    let exp = experiment("experiments/paper.toml", &[]);
    let checked = check_maps(&exp, false, &|s, name, mean, metric| {
        let reported = s.perceptual.get(name).unwrap();
        assert_eq!(reported.ci95, None);
        // The images written are the images scored: the metric gives the reported score.
        assert!(
            (metric - reported.value).abs() <= 1e-6,
            "{name} of {} {}: {metric} {reported:?}",
            s.method,
            s.eye_case
        );
        if name == ScoreName::Flip {
            assert!(
                (mean - reported.value).abs() <= 1e-6,
                "{} {}: map mean {mean}, FLIP {reported:?}",
                s.method,
                s.eye_case
            );
        }
    });
    assert_eq!(checked, 2 * 2 * exp.cases.len());
}

#[test]
fn navarro_maps_count_the_optics_once_and_converged_maps_are_of_the_mean_images() {
    // The Navarro eye focused at 300 mm, its optics counted once (the typical eye's optics
    // divided out of both images before the metrics), one round of four replicates.
    let exp = experiment(
        "experiments/navarro.toml",
        &[
            r#"eye_cases=[{ name = "Near", focus_mm = 300.0 }]"#,
            "measurement.optics=\"neural\"",
            "measurement.psnr_ci95_db=5.0",
            "measurement.ssim_ci95=0.5",
            "measurement.replicates=4",
        ],
    );
    let checked = check_maps(&exp, true, &|s, name, mean, metric| {
        let reported = s.perceptual.get(name).unwrap();
        let theta = reported.value + reported.noise_bias.unwrap();
        assert!(reported.ci95.unwrap() > 0.0, "{reported:?}");
        // The score of the mean images is the reported value with its removed bias added back.
        assert!((metric - theta).abs() <= 1e-5, "{name} of {}: {metric} against {theta} ({reported:?})", s.method);
        if name == ScoreName::Flip {
            assert!((mean - theta).abs() <= 1e-5, "{}: map mean {mean} against {theta}", s.method);
        }
    });
    assert_eq!(checked, 2 * 2);
}
