//! The monomials `a^i b^j c^k` of total degree <= 5 in the three rotation invariants of the
//! fitted ray map (`ray_map.rs`: `|t|^2`, `t . p`, `|p|^2`; G. W. Schwarz, Topology 14:63, 1975),
//! each one multiply from a lower one: written out for speed, with the table-driven chain as its
//! slow twin (bit for bit, tested).

#[cfg(test)]
use super::ray_map::DEGREE;
use super::ray_map::TERMS;

/// The exponents `(i, j, k)` of the monomials `a^i b^j c^k` (i + j + k <= DEGREE), in order
/// of total degree.
#[cfg(test)]
pub(super) const EXPONENTS: [[usize; 3]; TERMS] = {
    let mut e = [[0; 3]; TERMS];
    let (mut n, mut g) = (0, 0);
    while g <= DEGREE {
        let mut i = 0;
        while i <= g {
            let mut j = 0;
            while j <= g - i {
                e[n] = [i, j, g - i - j];
                n += 1;
                j += 1;
            }
            i += 1;
        }
        g += 1;
    }
    e
};

/// For each monomial of [`EXPONENTS`] after the first, the earlier monomial it is one factor
/// away from and that factor's variable (0: a, 1: b, 2: c): the first nonzero exponent is
/// lowered by one.
#[cfg(test)]
const PARENTS: [(usize, usize); TERMS] = {
    let mut p = [(0, 0); TERMS];
    let mut n = 1;
    while n < TERMS {
        let [i, j, k] = EXPONENTS[n];
        let (var, lower) = if i > 0 {
            (0, [i - 1, j, k])
        } else if j > 0 {
            (1, [i, j - 1, k])
        } else {
            (2, [i, j, k - 1])
        };
        let mut m = 0;
        while !(EXPONENTS[m][0] == lower[0] && EXPONENTS[m][1] == lower[1] && EXPONENTS[m][2] == lower[2]) {
            m += 1;
        }
        p[n] = (m, var);
        n += 1;
    }
    p
};

/// The monomials `a^i b^j c^k` of [`EXPONENTS`], written into `m`: each one multiply from its
/// parent ([`PARENTS`]), in place, written out one by one (a loop over the table is not
/// unrolled by the compiler, and its indexed stores and loads cost more than the multiplies).
/// Its slow twin is [`monomials_by_table`], bit for bit (tested).
#[inline(always)]
pub(super) fn monomials_into(m: &mut [f64; TERMS], a: f64, b: f64, c: f64) {
    const { assert!(TERMS == 56, "the unrolled chain is written for degree 5") };
    m[0] = 1.0;
    m[1] = m[0] * c;
    m[2] = m[0] * b;
    m[3] = m[0] * a;
    m[4] = m[1] * c;
    m[5] = m[1] * b;
    m[6] = m[2] * b;
    m[7] = m[1] * a;
    m[8] = m[2] * a;
    m[9] = m[3] * a;
    m[10] = m[4] * c;
    m[11] = m[4] * b;
    m[12] = m[5] * b;
    m[13] = m[6] * b;
    m[14] = m[4] * a;
    m[15] = m[5] * a;
    m[16] = m[6] * a;
    m[17] = m[7] * a;
    m[18] = m[8] * a;
    m[19] = m[9] * a;
    m[20] = m[10] * c;
    m[21] = m[10] * b;
    m[22] = m[11] * b;
    m[23] = m[12] * b;
    m[24] = m[13] * b;
    m[25] = m[10] * a;
    m[26] = m[11] * a;
    m[27] = m[12] * a;
    m[28] = m[13] * a;
    m[29] = m[14] * a;
    m[30] = m[15] * a;
    m[31] = m[16] * a;
    m[32] = m[17] * a;
    m[33] = m[18] * a;
    m[34] = m[19] * a;
    m[35] = m[20] * c;
    m[36] = m[20] * b;
    m[37] = m[21] * b;
    m[38] = m[22] * b;
    m[39] = m[23] * b;
    m[40] = m[24] * b;
    m[41] = m[20] * a;
    m[42] = m[21] * a;
    m[43] = m[22] * a;
    m[44] = m[23] * a;
    m[45] = m[24] * a;
    m[46] = m[25] * a;
    m[47] = m[26] * a;
    m[48] = m[27] * a;
    m[49] = m[28] * a;
    m[50] = m[29] * a;
    m[51] = m[30] * a;
    m[52] = m[31] * a;
    m[53] = m[32] * a;
    m[54] = m[33] * a;
    m[55] = m[34] * a;
}

/// The slow twin of [`monomials_into`]: the same chain, read from [`PARENTS`].
#[cfg(test)]
fn monomials_by_table(m: &mut [f64; TERMS], a: f64, b: f64, c: f64) {
    let v = [a, b, c];
    m[0] = 1.0;
    for (n, &(parent, var)) in PARENTS.iter().enumerate().skip(1) {
        m[n] = m[parent] * v[var];
    }
}

/// The monomials `a^i b^j c^k` of [`EXPONENTS`] ([`monomials_into`]).
#[inline(always)]
pub(super) fn monomials(a: f64, b: f64, c: f64) -> [f64; TERMS] {
    let mut m = [0.0; TERMS];
    monomials_into(&mut m, a, b, c);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_written_out_monomials_equal_the_table_chain_bit_for_bit() {
        for i in 0..200 {
            let u = [
                (0.5 + 0.7548776662 * i as f64).fract(),
                (0.5 + 0.5698402909 * i as f64).fract(),
                (0.5 + 0.6180339887 * i as f64).fract(),
            ];
            let (a, b, c) = (u[0] * 1.3, 2.0 * u[1] - 1.0, u[2] + 1e-3);
            let (mut fast, mut slow) = ([0.0; TERMS], [0.0; TERMS]);
            monomials_into(&mut fast, a, b, c);
            monomials_by_table(&mut slow, a, b, c);
            assert_eq!(fast.map(f64::to_bits), slow.map(f64::to_bits), "{a} {b} {c}");
            // Each is its monomial.
            for (n, &[i, j, k]) in EXPONENTS.iter().enumerate() {
                let direct = a.powi(i as i32) * b.powi(j as i32) * c.powi(k as i32);
                assert!((fast[n] - direct).abs() <= 1e-14 * direct.abs().max(1e-300), "{n}");
            }
        }
    }
}
