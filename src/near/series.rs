//! Far field: Jeffrey and Onishi's (1984) power series in `x = 2 / s`, to
//! [`K_FAR`] terms, from the generated coefficient polynomials.

use super::lubrication::Func;
use super::tables::{FAR, K_FAR};

/// Offset of row `k` in a flat coefficient array (row `k` holds `k + 2` entries).
pub const fn row(k: usize) -> usize {
    k * (k + 3) / 2
}

/// Length of a flat coefficient array of rows `0..=k_max`.
pub const fn far_len(k_max: usize) -> usize {
    row(k_max + 1)
}

/// The series of `f` at size ratio `l` and `x = 2 / s`, summed to `K_FAR`.
pub fn far(f: Func, l: f64, x: f64) -> f64 {
    let c = FAR[f as usize];
    let w = x / (1.0 + l);
    let mut sum = 0.0;
    let mut wk = 1.0;
    for k in 0..=K_FAR {
        if (k % 2 == 1) == f.odd() {
            let mut p = 0.0;
            for &cj in c[row(k)..row(k) + k + 2].iter().rev() {
                p = p * l + cj;
            }
            sum += p * wk;
        }
        wk *= w;
    }
    f.prefactor(l) * sum
}
