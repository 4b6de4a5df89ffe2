//! Series of the eight resistance functions from the recurrences, and their remainders
//! once the lubrication singular part's own series is subtracted term by term (the way
//! Jeffrey and Onishi 1984 obtain their O(1) constants). `x = 2 / s`.

use crate::recur::{Arrays, Family};
use hydrorattle::near::lubrication::{Func, basis_coeff};

/// How the recurrences give one function's series: `f_k = scale 2^k sum_q c lambda^j`.
pub struct Spec {
    /// Which recurrence.
    pub family: Family,
    /// The series reads `Q_1pq` (else `P_1pq`).
    pub use_q: bool,
    /// `j = q + (k mod 2)` (`Y^C`), else `j = q`.
    pub shift: bool,
    /// Extra factor (2 for `Y^B`).
    pub scale: f64,
}

/// The recipe for `f`.
pub fn spec(f: Func) -> Spec {
    let (family, use_q) = match f {
        Func::X11A | Func::X12A => (Family::Xa, false),
        Func::Y11A | Func::Y12A => (Family::Ya, false),
        Func::Y11B | Func::Y12B => (Family::Ya, true),
        Func::Y11C | Func::Y12C => (Family::Yc, true),
    };
    let shift = family == Family::Yc;
    let scale = if use_q && !shift { 2.0 } else { 1.0 };
    Spec {
        family,
        use_q,
        shift,
        scale,
    }
}

/// `c[k][j]`: `f_k(lambda) / 2^k = sum_j c[k][j] lambda^j`; rows off parity are zero.
pub fn poly(f: Func, a: &Arrays, k_max: usize) -> Vec<Vec<f64>> {
    let sp = spec(f);
    (0..=k_max)
        .map(|k| {
            let mut c = vec![0.0; k + 2];
            if (k % 2 == 1) == f.odd() {
                for q in 0..=k {
                    let (p, qi) = ((k - q) as i64, q as i64);
                    let v = if sp.use_q {
                        a.q(1, p, qi)
                    } else {
                        a.p(1, p, qi)
                    };
                    c[q + if sp.shift { k % 2 } else { 0 }] += sp.scale * v;
                }
            }
            c
        })
        .collect()
}

/// Coefficient of `x^k` in the series of `f` at size ratio `l`.
pub fn coeff(f: Func, c: &[Vec<f64>], l: f64, k: usize) -> f64 {
    let mut p = 0.0;
    for &cj in c[k].iter().rev() {
        p = p * l + cj;
    }
    f.prefactor(l) * p / (1.0 + l).powi(k as i32)
}

/// Remainder coefficients `r_k` (series minus the singular part's series).
pub fn remainder_coeffs(f: Func, c: &[Vec<f64>], l: f64) -> Vec<f64> {
    let g = f.singular(l);
    (0..c.len())
        .map(|k| {
            coeff(f, c, l, k)
                - (0..3)
                    .map(|i| g[i] * basis_coeff(f.odd(), i, k))
                    .sum::<f64>()
        })
        .collect()
}

/// The remainder at `xi` summed to the end, and an estimate of the neglected tail: the
/// coefficients fall as `k^-3` (an `xi^2 ln xi` leftover), so the tail past `K` is about
/// `K / 2` times the last term's size (the last two, as half the rows are zero).
pub fn remainder(r: &[f64], xi: f64) -> (f64, f64) {
    let x = 2.0 / (2.0 + xi);
    let mut sum = 0.0;
    for &rk in r.iter().rev() {
        sum = sum * x + rk;
    }
    let k = r.len() - 1;
    let tail = (r[k].abs() + r[k - 1].abs()) * k as f64 / 4.0 * x.powi(k as i32 - 1);
    (sum, tail)
}
