//! Lattice bases that are not reduced (issue #30, round two): any basis of the same lattice finds
//! the same nearest cell, and gives the same display image pixel for pixel.

use std::path::Path;
use std::process::Command;

use glam::{DMat2, DVec2, IVec2};
use inimtrace::optics::Lattice;

/// Deterministic pseudo-random numbers in [0, 1).
fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The nearest centre by exhaustive search over every user index `i` that can hold it: the
/// nearest centre is within `(|b1| + |b2|) / 2` of `p` for any basis, so its index is within
/// `|M^-1| (|b1| + |b2|) / 2` of the continuous coordinates `M^-1 (p - shift)`.
fn brute_nearest(l: &Lattice, p: DVec2) -> (IVec2, f64) {
    let m = l.matrix;
    let inv = m.inverse();
    let norm = (inv.x_axis.length_squared() + inv.y_axis.length_squared()).sqrt();
    let block = (norm * 0.5 * (m.x_axis.length() + m.y_axis.length())).ceil() as i32 + 1;
    let u = inv * (p - l.shift);
    let at = IVec2::new(u.x.round() as i32, u.y.round() as i32);
    let mut best = (IVec2::ZERO, f64::INFINITY);
    for j in -block..=block {
        for i in -block..=block {
            let c = at + IVec2::new(i, j);
            let d = (l.center(c) - p).length_squared();
            if d < best.1 {
                best = (c, d);
            }
        }
    }
    best
}

#[test]
fn the_nearest_cell_of_any_basis_is_the_nearest_by_brute_force() {
    let mut next = rng(0x5eed);
    let mut old_rule_wrong = 0usize;
    let mut checked = 0usize;
    for b in 0..40i32 {
        // A reduced basis (random lengths and angle), then sheared by a random unimodular matrix.
        let (a, r, angle) = (0.5 + next(), 0.6 + next(), 0.4 + 2.3 * next());
        let base = DMat2::from_cols(DVec2::new(a, 0.0), DVec2::new(r * angle.cos(), r * angle.sin()));
        let k = 1 + b % 7;
        let shear = if b % 2 == 0 {
            DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(k as f64, 1.0))
        } else {
            DMat2::from_cols(DVec2::new(1.0, -(k as f64)), DVec2::new(-1.0, 1.0 + k as f64))
        };
        let m = base * shear;
        let shift = DVec2::new(next() - 0.5, next() - 0.5);
        let lat = Lattice::new(shift, m).unwrap();
        let reduced = Lattice::new(shift, lat.reduced_matrix()).unwrap();
        for _ in 0..300 {
            let p = shift + DVec2::new((next() - 0.5) * 8.0, (next() - 0.5) * 8.0);
            let (want, d_want) = brute_nearest(&lat, p);
            let got = lat.nearest(p);
            let d_got = (lat.center(got) - p).length_squared();
            // Equal cells, or an exact tie (within 1e-9 mm of a boundary).
            assert!(
                got == want || (d_got.sqrt() - d_want.sqrt()).abs() < 1e-9,
                "basis {m:?} point {p}: {got} vs {want}"
            );
            // The reduced basis spans the same centres.
            let c = reduced.center(reduced.nearest(p));
            assert!((c - lat.center(got)).length() < 1e-9, "basis {m:?} point {p}");
            if lat.nearest_brute_force(p, 1) != want {
                old_rule_wrong += 1;
            }
            checked += 1;
        }
    }
    // The rule before reduction (the user's basis, neighbouring cells only) was wrong for many.
    eprintln!("neighbour search in the given basis: {old_rule_wrong} of {checked} points in the wrong cell");
    assert!(old_rule_wrong > checked / 10, "{old_rule_wrong} of {checked}");
}

#[test]
fn reduced_bases_are_kept_as_given() {
    let hex = DMat2::from_cols(DVec2::new(1.2, 0.0), DVec2::new(0.6, 1.2 * 3f64.sqrt() / 2.0));
    let rot = DMat2::from_angle(0.3) * DMat2::from_diagonal(DVec2::new(1.0, 1.3));
    for m in [DMat2::from_diagonal(DVec2::new(1.2, 1.58)), hex, rot, DMat2::from_cols(hex.y_axis, hex.x_axis)] {
        let l = Lattice::new(DVec2::new(0.1, 0.2), m).unwrap();
        assert_eq!(l.reduced_matrix(), m);
        assert_eq!(l.matrix, m);
    }
    // A sheared square basis reduces to the square one (up to sign and order) and keeps its own
    // pitch matrix and indices: cell (i, j) is still shift + M (i, j).
    let m = DMat2::from_cols(DVec2::new(1.2, 0.0), DVec2::new(12.0, 1.2));
    let l = Lattice::new(DVec2::ZERO, m).unwrap();
    let r = l.reduced_matrix();
    assert!((r.x_axis.length() - 1.2).abs() < 1e-12 && (r.y_axis.length() - 1.2).abs() < 1e-12, "{r:?}");
    assert_eq!(l.row_major(), [1.2, 12.0, 0.0, 1.2]);
    let p = DVec2::new(0.1, 2.4);
    let i = l.nearest(p);
    assert_eq!(i, IVec2::new(-20, 2));
    assert!((l.center(i) - DVec2::new(0.0, 2.4)).length() < 1e-12);
    // Absurdly skewed bases are refused, not looped on.
    assert!(Lattice::new(DVec2::ZERO, DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(1e12, 1.0))).is_none());
}

fn write_display(dir: &Path, name: &str, lenslet_pitch: &str, ei_pitch: &str) -> String {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(
        &p,
        format!(
            "name = \"{name}\"\neye_to_lenslets = 20.0\nlenslets_to_lcd = 6.316\n\
             [lenslets]\nfocal_length = 6.427\nshift = [0.0, 0.0]\npitch = {lenslet_pitch}\n\
             [elemental_images]\nshift = [0.0, 0.0]\npitch = {ei_pitch}\n\
             [lcd]\nsize = [21.6, 21.6]\nresolution = [360, 360]\n"
        ),
    )
    .unwrap();
    p.to_str().unwrap().to_string()
}

fn render(display: &str, method: &str, out: &Path) -> inimtrace::raster::RgbImage {
    let o = Command::new(env!("CARGO_BIN_EXE_inimtrace"))
        .args(["--quiet", "render-display", "--display", display, "--method", method, "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    inimtrace::io::exr::read_rgb(out).unwrap()
}

#[test]
fn a_sheared_basis_of_the_paper_display_gives_the_square_ones_display_image() {
    let dir = tempfile::tempdir().unwrap();
    let square = write_display(dir.path(), "square", "1.2", "1.58");
    // The same lattices through the bases (1.2, 0), (12, 1.2) and (1.58, 0), (15.8, 1.58).
    let sheared = write_display(dir.path(), "sheared", "[[1.2, 12.0], [0.0, 1.2]]", "[[1.58, 15.8], [0.0, 1.58]]");
    for method in ["LC", "LA3"] {
        let a = render(&square, method, &dir.path().join(format!("square_{method}.exr")));
        let b = render(&sheared, method, &dir.path().join(format!("sheared_{method}.exr")));
        assert_eq!((a.width, a.height), (b.width, b.height));
        let differ = a.pixels.iter().zip(&b.pixels).filter(|(x, y)| x != y).count();
        eprintln!("{method}: {differ} of {} pixels differ", a.pixels.len());
        assert_eq!(differ, 0, "{method}: {differ} of {} pixels differ", a.pixels.len());
    }
}
