//! Tests of the parent module: its fast paths against their slow twins and exact answers.
use super::pass::{accumulate, accumulate_each};
use super::*;

#[test]
fn mean_images_row_by_row_equal_the_pixel_by_pixel_means_bit_for_bit() {
    // Values with many significant bits, zeros of both signs, and 1 to 8 replicates.
    for replicates in [1, 2, 3, 8] {
        let reps = Replicates::from_fn(13, replicates, 3, 4, |p, r, k, c| {
            let h = super::super::sampler::mix64((p * 97 + r * 13 + k * 5 + c) as u64);
            match h % 7 {
                0 => 0.0,
                1 => -0.0,
                _ => (h >> 40) as f32 / (1u32 << 20) as f32 * 0.37,
            }
        });
        for k in 0..3 {
            let (fast, slow) = (reps.mean_image(k), reps.mean_image_by_pixel(k));
            let bits = |img: &RgbImage| img.pixels.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&slow), "{replicates} replicates, image {k}");
            assert!(fast.pixels.iter().flatten().any(|&v| v > 0.0));
        }
    }
}

#[test]
fn run_sums_in_registers_equal_sample_by_sample_sums_bit_for_bit() {
    // Owners in runs of uneven length, a pixel coming back after others (as when a batch
    // boundary splits a pixel's samples), and sums that start non-zero.
    let owners: Vec<u32> = [0u32, 0, 0, 3, 3, 1, 0, 0, 5, 5, 5, 5, 5, 2, 2, 3].to_vec();
    for k in [2, 3, 4] {
        let mut h = 11u64;
        let vals: Vec<[f64; 3]> = (0..owners.len() * k)
            .map(|_| {
                std::array::from_fn(|_| {
                    h = super::super::sampler::mix64(h);
                    (h >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.0
                })
            })
            .collect();
        let start: Vec<f64> = (0..6 * k * 3).map(|i| 0.1 * i as f64 + 1e-17).collect();
        let (mut fast, mut slow) = (start.clone(), start);
        match k {
            2 => accumulate::<2>(&vals, &owners, &mut fast),
            3 => accumulate::<3>(&vals, &owners, &mut fast),
            _ => accumulate::<4>(&vals, &owners, &mut fast),
        }
        accumulate_each(&vals, k, &owners, &mut slow);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&slow), "k = {k}");
        assert_ne!(bits(&fast), bits(&(0..6 * k * 3).map(|i| 0.1 * i as f64 + 1e-17).collect::<Vec<_>>()));
    }
}
