//! Tests of the Table 1 metrics (src/metrics.rs): PSNR against analytic MSEs, SSIM against
//! analytic constant-image values, against scikit-image reference numbers, and fast (separable)
//! against the slow direct twin.
#![deny(unsafe_code)]

use inimtrace::metrics::{finite_db, format_db, psnr, psnr_channel, ssim, ssim_direct, SsimConstants, SSIM_WINDOW};
use inimtrace::raster::RgbImage;

/// Deterministic test image: an LCG (glibc constants) gives each sample a value k/255, computed
/// in f32, in row-major, channel-fastest order. Reproduced exactly by `lcg_image` in the Python
/// script quoted in `ssim_matches_scikit_image`.
fn lcg_image(seed: u64, height: usize, width: usize) -> RgbImage {
    let mut s = seed;
    let mut img = RgbImage::new(width, height);
    for r in 0..height {
        for c in 0..width {
            let mut p = [0.0f32; 3];
            for v in &mut p {
                s = (s * 1_103_515_245 + 12_345) % (1u64 << 31);
                *v = ((s >> 8) % 256) as f32 / 255.0;
            }
            img.set(r, c, p);
        }
    }
    img
}

/// `0.75 a + 0.25 n` in f32, as numpy's float32 arithmetic computes it.
fn mix(a: &RgbImage, n: &RgbImage) -> RgbImage {
    let mut out = a.clone();
    for (o, q) in out.pixels.iter_mut().zip(&n.pixels) {
        for ch in 0..3 {
            o[ch] = 0.75f32 * o[ch] + 0.25f32 * q[ch];
        }
    }
    out
}

fn assert_close(got: f64, want: f64, tol: f64, what: &str) {
    assert!((got - want).abs() <= tol, "{what}: got {got:.17}, want {want:.17} (tol {tol:e})");
}

#[test]
fn identical_images_give_ssim_one_and_infinite_psnr() {
    let a = lcg_image(7, 20, 23);
    let p = psnr(&a, &a).unwrap();
    assert_eq!(p.channels, [f64::INFINITY; 3]);
    assert_eq!(p.mean, f64::INFINITY);
    assert_eq!(p.mean_text(2), "inf");
    assert_eq!(finite_db(p.mean), None);
    for k in SsimConstants::ALL {
        let s = ssim(&a, &a, k).unwrap();
        assert_eq!(s.channels, [1.0; 3], "{k}");
        assert_eq!(s.mean, 1.0, "{k}");
    }
}

#[test]
fn psnr_of_known_mse() {
    // Offset 0.125 is exact in f32: MSE = 1/64, PSNR = 10 log10 64.
    let a = RgbImage::filled(12, 9, [0.25; 3]);
    let b = RgbImage::filled(12, 9, [0.375; 3]);
    let p = psnr(&a, &b).unwrap();
    assert_close(p.mean, 10.0 * 64f64.log10(), 1e-12, "offset 0.125");
    // Offset 0.1 (0.1f32 = 0.100000001490116...): 20 dB up to the f32 rounding of 0.1.
    let z = RgbImage::filled(12, 9, [0.0; 3]);
    let t = RgbImage::filled(12, 9, [0.1; 3]);
    let p = psnr(&z, &t).unwrap();
    for c in p.channels {
        assert_close(c, 20.0, 1e-6, "offset 0.1");
    }
    assert_eq!(format_db(p.mean, 2), "20.00");
    // The mean is over channel PSNRs, not the PSNR of the pooled MSE: one channel off by 0.1
    // (20 dB), one off by 0.01 (40 dB), one identical (inf) -> mean inf; with the third channel
    // off by 0.001 (60 dB) the mean is 40 dB.
    let mut u = RgbImage::filled(4, 4, [0.5, 0.5, 0.5]);
    let v = RgbImage::filled(4, 4, [0.5, 0.5, 0.5]);
    for p in &mut u.pixels {
        *p = [0.5 + 0.1, 0.5 + 0.01, 0.5 + 0.001];
    }
    let p = psnr(&u, &v).unwrap();
    assert_close(p.channels[0], 20.0, 1e-5, "R");
    assert_close(p.channels[1], 40.0, 1e-4, "G");
    assert_close(p.channels[2], 60.0, 1e-2, "B");
    assert_close(p.mean, 40.0, 1e-2, "mean");
}

#[test]
fn psnr_channel_direct() {
    assert_eq!(psnr_channel(&[0.5, 0.5], &[0.5, 0.5]), f64::INFINITY);
    // MSE = (0.5^2 + 0)/2 = 0.125 -> 10 log10 8
    assert_close(psnr_channel(&[0.5, 0.0], &[0.0, 0.0]), 10.0 * 8f64.log10(), 1e-12, "mse 1/8");
}

#[test]
fn ssim_of_constant_images_is_analytic() {
    // Uniform images: all variances vanish, so SSIM = (2pq + C1) / (p^2 + q^2 + C1).
    let (p, q) = (0.25f64, 0.5f64);
    let a = RgbImage::filled(15, 12, [p as f32; 3]);
    let b = RgbImage::filled(15, 12, [q as f32; 3]);
    for k in SsimConstants::ALL {
        let (c1, _) = k.c1_c2();
        let want = (2.0 * p * q + c1) / (p * p + q * q + c1);
        let s = ssim(&a, &b, k).unwrap();
        assert_close(s.mean, want, 1e-14, k.name());
    }
    assert_eq!(SsimConstants::Wang2004.c1_c2(), (1e-4, 9e-4));
    let (c1, c2) = SsimConstants::Framework8Bit.c1_c2();
    assert_close(c1, 6.5025, 1e-12, "C1");
    assert_close(c2, 58.5225, 1e-12, "C2");
}

/// Reference values from scikit-image 0.26.0 (numpy 2.4.6), produced by:
///
/// ```python
/// from skimage.metrics import structural_similarity
/// def lcg_image(seed, h, w):           # same generator as lcg_image() above
///     s = seed; out = np.zeros((h, w, 3), dtype=np.float32)
///     for r in range(h):
///         for c in range(w):
///             for ch in range(3):
///                 s = (s * 1103515245 + 12345) % (1 << 31)
///                 out[r, c, ch] = np.float32(((s >> 8) % 256) / 255.0)
///     return out
/// a = lcg_image(1, 13, 17); n = lcg_image(2, 13, 17)
/// b = (np.float32(0.75) * a + np.float32(0.25) * n).astype(np.float32)
/// [structural_similarity(a64[..., c], b64[..., c], gaussian_weights=True, sigma=1.5,
///      use_sample_covariance=False, data_range=1.0) for c in range(3)]   # a64 = a as float64
/// ```
///
/// scikit-image filters the whole image (mode 'reflect', 11 taps since truncate = 3.5) and
/// then crops (11-1)/2 = 5 pixels from every side before averaging the SSIM map, so the
/// averaged positions are exactly the windows fully inside the image: the same set as
/// ssim_index.m's 'valid' filtering. A direct numpy/scipy `correlate2d(..., 'valid')`
/// implementation agreed with these numbers to 5e-16.
#[test]
fn ssim_matches_scikit_image() {
    let a = lcg_image(1, 13, 17);
    let n = lcg_image(2, 13, 17);
    let b = mix(&a, &n);
    let want_ab = [0.9160862763632832, 0.9281172262733702, 0.9240597480241406];
    let want_an = [-0.0802944551248405, 0.07510907092850032, -0.08828134024912122];
    for (y, want) in [(&b, want_ab), (&n, want_an)] {
        for s in [ssim(&a, y, SsimConstants::Wang2004).unwrap(), ssim_direct(&a, y, SsimConstants::Wang2004).unwrap()] {
            for (got, want) in s.channels.iter().zip(want) {
                assert_close(*got, want, 1e-12, "channel SSIM vs scikit-image");
            }
            assert_close(s.mean, want.iter().sum::<f64>() / 3.0, 1e-12, "mean SSIM");
        }
    }
    // Framework constants on the same pair, from the same numpy 'valid' implementation with
    // C1 = 6.5025, C2 = 58.5225.
    let want_fw = [0.9997761980060974, 0.999824381717742, 0.9997701477319089];
    let s = ssim(&a, &b, SsimConstants::Framework8Bit).unwrap();
    for (got, want) in s.channels.iter().zip(want_fw) {
        assert_close(*got, want, 1e-12, "framework-8bit SSIM");
    }
}

#[test]
fn framework_constants_pin_ssim_near_one() {
    let a = lcg_image(11, 32, 32);
    let n = lcg_image(12, 32, 32);
    let b = mix(&a, &n);
    let wang = ssim(&a, &b, SsimConstants::Wang2004).unwrap().mean;
    let fw = ssim(&a, &b, SsimConstants::Framework8Bit).unwrap().mean;
    assert!(fw > 0.99, "framework-8bit SSIM {fw}");
    assert!(wang < 0.95, "wang2004 SSIM {wang}");
    assert!(fw > wang);
}

#[test]
fn fast_ssim_equals_direct_twin() {
    // Heights above 74 give more than one 64-row band in the fast path.
    let sizes = [(11, 11), (11, 19), (24, 13), (31, 40), (90, 15), (139, 12)];
    for (i, &(h, w)) in sizes.iter().enumerate() {
        let a = lcg_image(100 + i as u64, h, w);
        // A mix of a similar image (a blurred-like blend) and an unrelated one.
        let b = mix(&a, &lcg_image(200 + i as u64, h, w));
        let c = lcg_image(300 + i as u64, h, w);
        for y in [&b, &c] {
            for k in SsimConstants::ALL {
                let fast = ssim(&a, y, k).unwrap();
                let slow = ssim_direct(&a, y, k).unwrap();
                for ch in 0..3 {
                    assert_close(fast.channels[ch], slow.channels[ch], 1e-12, "fast vs direct");
                }
                assert_close(fast.mean, slow.mean, 1e-12, "fast vs direct mean");
            }
        }
    }
}

#[test]
fn ssim_is_symmetric_and_at_most_one() {
    let a = lcg_image(5, 16, 21);
    let b = mix(&a, &lcg_image(6, 16, 21));
    let ab = ssim(&a, &b, SsimConstants::Wang2004).unwrap();
    let ba = ssim(&b, &a, SsimConstants::Wang2004).unwrap();
    assert_close(ab.mean, ba.mean, 1e-14, "symmetry");
    assert!(ab.mean < 1.0);
}

#[test]
fn bad_inputs_are_errors() {
    let a = RgbImage::new(12, 12);
    let b = RgbImage::new(12, 13);
    let e = psnr(&a, &b).unwrap_err().to_string();
    assert!(e.contains("12x12") && e.contains("12x13"), "{e}");
    assert!(ssim(&a, &b, SsimConstants::Wang2004).is_err());
    let small = RgbImage::new(SSIM_WINDOW - 1, 20);
    let e = ssim(&small, &small, SsimConstants::Wang2004).unwrap_err().to_string();
    assert!(e.contains("smaller than the 11x11"), "{e}");
    assert!(ssim_direct(&small, &small, SsimConstants::Wang2004).is_err());
    let mut nan = RgbImage::new(12, 12);
    nan.set(3, 4, [0.0, f32::NAN, 0.0]);
    let e = psnr(&a, &nan).unwrap_err().to_string();
    assert!(e.contains("row 3") && e.contains("col 4"), "{e}");
    assert!(ssim(&nan, &a, SsimConstants::Wang2004).is_err());
    assert!(psnr(&RgbImage::new(0, 0), &RgbImage::new(0, 0)).is_err());
}

#[test]
fn ssim_constants_names() {
    assert_eq!(SsimConstants::default(), SsimConstants::Wang2004);
    for k in SsimConstants::ALL {
        assert_eq!(k.name().parse::<SsimConstants>().unwrap(), k);
        let json = serde_json::to_string(&k).unwrap();
        assert_eq!(json, format!("\"{}\"", k.name()));
        assert_eq!(serde_json::from_str::<SsimConstants>(&json).unwrap(), k);
    }
    assert_eq!(SsimConstants::Framework8Bit.name(), "framework-8bit");
    assert_eq!(SsimConstants::Wang2004.to_string(), "wang2004");
    let e = "wang".parse::<SsimConstants>().unwrap_err().to_string();
    assert!(e.contains("wang2004") && e.contains("framework-8bit"), "{e}");
}
