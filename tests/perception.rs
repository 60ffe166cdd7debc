//! The perceptual scores' invariants (docs/PERCEPTION.md): identical images score JOD 10 and FLIP
//! 0 exactly; JOD falls and FLIP rises as noise or blur is added; a common luminance scale moves
//! JOD as ColorVideoVDP's luminance model predicts (sensitivity rising with luminance toward
//! Weber's law) and leaves HDR-FLIP unchanged; the replicate estimator's interval and bias; bad
//! input gives one error naming the field.

use inimtrace::measure::estimator::Replicates;
use inimtrace::perception::{
    cvvdp::Cvvdp, flip::flip, luminance, DisplayLuminance, ExtraScores, Perception, ScalarEstimate, ScoreName, Viewing,
    BT709_LUMINANCE,
};
use inimtrace::raster::RgbImage;

const N: usize = 64;

fn viewing(peak: f64) -> Viewing {
    Viewing { luminance: DisplayLuminance::default().with_peak(peak), pixels_per_degree: 15.0 }
}

/// A test scene: bars of three periods over a colour gradient, values within 0.05..0.95.
fn scene() -> RgbImage {
    let mut img = RgbImage::new(N, N);
    for r in 0..N {
        for c in 0..N {
            let period = [4, 8, 16][r * 3 / N];
            let bar = if (c / (period / 2)) % 2 == 0 { 0.3 } else { -0.3 };
            let g = c as f32 / N as f32;
            img.set(r, c, [0.5 + bar * 0.8 + 0.1 * g, 0.5 + bar, 0.5 + bar * 0.6 - 0.1 * g]);
        }
    }
    img
}

/// A fixed pseudo-random field in -0.5..0.5.
fn noise_field(seed: u64) -> Vec<f32> {
    let mut s = seed;
    (0..N * N * 3)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) as f32
        })
        .collect()
}

fn with_noise(img: &RgbImage, amplitude: f32, field: &[f32]) -> RgbImage {
    let mut out = img.clone();
    for (i, p) in out.pixels.iter_mut().enumerate() {
        for c in 0..3 {
            p[c] = (p[c] + amplitude * field[i * 3 + c]).clamp(0.0, 1.0);
        }
    }
    out
}

/// A Gaussian blur of standard deviation `sigma` pixels (edges clamped).
fn blurred(img: &RgbImage, sigma: f64) -> RgbImage {
    let k = (3.0 * sigma).ceil() as isize;
    let w: Vec<f64> = (-k..=k).map(|d| (-(d * d) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let sum: f64 = w.iter().sum();
    let pass = |src: &RgbImage, horizontal: bool| {
        let mut out = RgbImage::new(N, N);
        for r in 0..N {
            for c in 0..N {
                let mut acc = [0.0f64; 3];
                for (i, d) in (-k..=k).enumerate() {
                    let (rr, cc) = if horizontal { (r as isize, c as isize + d) } else { (r as isize + d, c as isize) };
                    let p = src.get(rr.clamp(0, N as isize - 1) as usize, cc.clamp(0, N as isize - 1) as usize);
                    for ch in 0..3 {
                        acc[ch] += w[i] / sum * f64::from(p[ch]);
                    }
                }
                out.set(r, c, acc.map(|v| v as f32));
            }
        }
        out
    };
    pass(&pass(img, true), false)
}

fn jod(test: &RgbImage, reference: &RgbImage, v: &Viewing) -> f64 {
    Cvvdp::new(v, N, N, false).unwrap().score(test, reference).unwrap().jod
}

#[test]
fn identical_images_score_jod_10_and_flip_0_exactly() {
    let img = scene();
    for peak in [10.0, 100.0, 1000.0] {
        let v = viewing(peak);
        assert_eq!(jod(&img, &img, &v), 10.0, "{peak} cd/m^2");
        assert_eq!(flip(&img, &img, &v).unwrap().mean, 0.0, "{peak} cd/m^2");
        assert!(flip(&img, &img, &v).unwrap().map.iter().all(|&x| x == 0.0));
    }
}

#[test]
fn jod_falls_and_flip_rises_monotonically_with_noise_and_blur() {
    let img = scene();
    let v = viewing(100.0);
    let field = noise_field(7);
    let noisy: Vec<RgbImage> = [0.01, 0.03, 0.1, 0.3].iter().map(|a| with_noise(&img, *a, &field)).collect();
    let blurs: Vec<RgbImage> = [0.5, 1.0, 2.0, 4.0].iter().map(|s| blurred(&img, *s)).collect();
    for (what, series) in [("noise", &noisy), ("blur", &blurs)] {
        let jods: Vec<f64> = series.iter().map(|t| jod(t, &img, &v)).collect();
        let flips: Vec<f64> = series.iter().map(|t| flip(t, &img, &v).unwrap().mean).collect();
        assert!(jods[0] < 10.0, "{what}: {jods:?}");
        assert!(jods.windows(2).all(|w| w[1] < w[0]), "{what}: JOD {jods:?}");
        assert!(flips[0] > 0.0 && flips.windows(2).all(|w| w[1] > w[0]), "{what}: FLIP {flips:?}");
    }
}

#[test]
fn a_common_luminance_scale_moves_jod_as_the_csf_predicts_and_leaves_hdr_flip() {
    // castleCSF's sensitivity rises with the adapting luminance toward Weber's law: the same
    // relative distortion is more visible at 100 than at 10 cd/m^2 and at 1000 than at 100, and
    // the step from 100 to 1000 is the smaller one (docs/PERCEPTION.md).
    let img = scene();
    let test = blurred(&with_noise(&img, 0.05, &noise_field(3)), 0.7);
    let jods: Vec<f64> = [10.0, 100.0, 1000.0].iter().map(|p| jod(&test, &img, &viewing(*p))).collect();
    assert!(jods.windows(2).all(|w| w[1] < w[0]), "JOD by decade of luminance: {jods:?}");
    assert!(jods[1] - jods[2] < jods[0] - jods[1], "toward Weber's law: {jods:?}");
    // HDR-FLIP's exposures follow the reference's luminance: a common scale changes nothing but
    // rounding.
    let f: Vec<f64> = [10.0, 100.0, 1000.0].iter().map(|p| flip(&test, &img, &viewing(*p)).unwrap().mean).collect();
    assert!((f[0] - f[1]).abs() < 1e-4 && (f[1] - f[2]).abs() < 1e-4, "{f:?}");
}

#[test]
fn bad_input_names_the_field() {
    let img = scene();
    for peak in [0.0, -10.0, f64::NAN, f64::INFINITY] {
        let v =
            Viewing { luminance: DisplayLuminance { peak_white: peak, ..Default::default() }, pixels_per_degree: 15.0 };
        let e = Cvvdp::new(&v, N, N, false).err().expect("refused").to_string();
        assert!(e.contains("peak_white"), "{e}");
        let e = flip(&img, &img, &v).unwrap_err().to_string();
        assert!(e.contains("peak_white"), "{e}");
    }
    let small = RgbImage::filled(N, N - 1, [0.5; 3]);
    let v = viewing(100.0);
    let e = Cvvdp::new(&v, N, N, false).unwrap().score(&small, &img).unwrap_err().to_string();
    assert!(e.contains("image size") && e.contains("64x63"), "{e}");
    let e = flip(&small, &img, &v).unwrap_err().to_string();
    assert!(e.contains("image size"), "{e}");
    let e = luminance::psnr_luminance(&small, &img, BT709_LUMINANCE).unwrap_err().to_string();
    assert!(e.contains("image size"), "{e}");
    let mut nan = img.clone();
    nan.pixels[5][1] = f32::NAN;
    let e = flip(&nan, &img, &v).unwrap_err().to_string();
    assert!(e.contains("pixels") && e.contains("col 5"), "{e}");
    let e = "lpips".parse::<ScoreName>().unwrap_err().to_string();
    assert!(e.contains("lpips") && e.contains("flip"), "{e}");
}

#[test]
fn luminance_psnr_is_the_psnr_of_the_weighted_sum() {
    let img = scene();
    let test = with_noise(&img, 0.1, &noise_field(11));
    let y = |p: &[f32; 3]| (0..3).map(|c| BT709_LUMINANCE[c] * f64::from(p[c])).sum::<f64>();
    let mse = img.pixels.iter().zip(&test.pixels).map(|(a, b)| (y(a) - y(b)).powi(2)).sum::<f64>() / (N * N) as f64;
    let p = luminance::psnr_luminance(&test, &img, BT709_LUMINANCE).unwrap();
    assert!((p + 10.0 * mse.log10()).abs() < 1e-9, "{p}");
    assert_eq!(luminance::psnr_luminance(&img, &img, BT709_LUMINANCE).unwrap(), f64::INFINITY);
}

/// Replicates of the scene (image 0) and a blurred version (image 1), each replicate with its
/// own noise of `amplitude` (0: identical replicates).
fn replicates(amplitude: f32, count: usize) -> (Replicates, RgbImage, RgbImage) {
    let (gt, sim) = (scene(), blurred(&scene(), 0.8));
    let fields: Vec<Vec<f32>> = (0..2 * count).map(|i| noise_field(100 + i as u64)).collect();
    let reps = Replicates::from_fn(N, count, 2, 16, |p, r, k, c| {
        let base = if k == 0 { gt.pixels[p][c] } else { sim.pixels[p][c] };
        (base + amplitude * fields[2 * r + k][p * 3 + c]).max(0.0)
    });
    (reps, gt, sim)
}

#[test]
fn noise_free_replicates_give_the_plain_scores_with_zero_interval_and_bias() {
    let (reps, gt, sim) = replicates(0.0, 4);
    let names = [ScoreName::PsnrLuminance, ScoreName::Cvvdp, ScoreName::Flip];
    let extra = ExtraScores::from_names(&names, "test", "scores").unwrap();
    let p = Perception::new(&extra, &viewing(100.0), BT709_LUMINANCE, (N, N), None).unwrap();
    let plain = p.score_images(&sim, &gt).unwrap();
    let reps = p.score_replicates(&reps, 1).unwrap();
    for name in names {
        let (a, b) = (plain.get(name).unwrap(), reps.get(name).unwrap());
        assert!((a.value - b.value).abs() < 1e-6 * a.value.abs().max(1.0), "{name}: {a:?} {b:?}");
        assert!(b.ci95.unwrap().abs() < 1e-6, "{name}: {b:?}");
        assert!(b.noise_bias.is_none_or(|x| x.abs() < 1e-6), "{name}: {b:?}");
    }
}

/// Replicates as [`replicates`], with the noise of trial `trial` (never clamped: every value
/// stays within 0.1..1.0, so the noise-free images are the replicates' expectation).
fn trial_replicates(amplitude: f32, count: usize, trial: u64) -> Replicates {
    let (gt, sim) = (scene(), blurred(&scene(), 0.8));
    let fields: Vec<Vec<f32>> = (0..2 * count).map(|i| noise_field(1_000 * (trial + 1) + i as u64)).collect();
    Replicates::from_fn(N, count, 2, 16, |p, r, k, c| {
        let base = if k == 0 { gt.pixels[p][c] } else { sim.pixels[p][c] };
        base + amplitude * fields[2 * r + k][p * 3 + c]
    })
}

#[test]
fn the_corrected_scores_intervals_cover_the_noise_free_scores() {
    // The noise-free score is the exact answer; each trial's 8 replicates carry independent
    // noise, at three levels (uniform, amplitude 0.04, 0.08 and 0.16: the replicate mean's
    // standard deviation 0.004 to 0.016 per sample). The score of the mean images is biased (JOD
    // down) by more than its plain jackknife interval at the higher levels; the corrected value's
    // 95% interval must cover the exact answer in about 95% of trials: at least 88 of 100
    // (fewer has probability 0.001 at a true 95%).
    let extra = ExtraScores::from_names(&[ScoreName::Cvvdp, ScoreName::Flip], "test", "scores").unwrap();
    let p = Perception::new(&extra, &viewing(100.0), BT709_LUMINANCE, (N, N), None).unwrap();
    let clean = p.score_images(&blurred(&scene(), 0.8), &scene()).unwrap();
    let trials = 100;
    for amplitude in [0.04f32, 0.08, 0.16] {
        let estimates: Vec<_> =
            (0..trials).map(|t| p.score_replicates(&trial_replicates(amplitude, 8, t), 1).unwrap()).collect();
        for name in [ScoreName::Cvvdp, ScoreName::Flip] {
            let truth = clean.get(name).unwrap().value;
            let es: Vec<_> = estimates.iter().map(|s| *s.get(name).unwrap()).collect();
            let hits = es.iter().filter(|e| (e.value - truth).abs() <= e.ci95.unwrap()).count();
            let flagged = es.iter().filter(|e| e.bias_above_ci95()).count();
            // Mean and standard error of the mean over the trials.
            let stats = |f: &dyn Fn(&ScalarEstimate) -> f64| {
                let m = es.iter().map(f).sum::<f64>() / trials as f64;
                let var = es.iter().map(|e| (f(e) - m).powi(2)).sum::<f64>() / (trials - 1) as f64;
                (m, (var / trials as f64).sqrt())
            };
            let (error, se) = stats(&|e| e.value - truth);
            let (raw_error, raw_se) = stats(&|e| e.value + e.noise_bias.unwrap() - truth);
            let (half, _) = stats(&|e| e.ci95.unwrap());
            eprintln!(
                "{name} amplitude {amplitude}: {hits} of {trials} cover {truth:.5}; mean error {error:.2e} \
                 (standard error {se:.2e}), uncorrected {raw_error:.2e}; mean half-width {half:.2e}; bias above it \
                 in {flagged}"
            );
            assert!(hits >= 88, "{name} amplitude {amplitude}: {hits} of {trials} intervals cover {truth}");
            if amplitude >= 0.08 {
                // The noise's bias is clear here, and the correction removes most of it.
                assert!(raw_error.abs() > 3.0 * raw_se, "{name} amplitude {amplitude}: bias {raw_error}");
                assert!(
                    error.abs() < 0.3 * raw_error.abs(),
                    "{name} amplitude {amplitude}: mean error {error} against {raw_error} uncorrected"
                );
            }
            if name == ScoreName::Cvvdp {
                // A smooth score: its bias falls as 1/N and the jackknife removes all of it.
                assert!(error.abs() < 3.0 * se, "mean error {error} against its standard error {se}");
                assert!(raw_error < 0.0, "the noise is seen as distortion: {raw_error}");
            }
        }
    }
}
