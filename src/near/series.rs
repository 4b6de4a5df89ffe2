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

/// [`far`] of all eight functions at once (in [`Func::ALL`] order), bit for bit: at each
/// power the four functions of its parity advance side by side, so their Horner chains
/// overlap instead of waiting on each other's latency (about 3x faster).
pub fn far_all(l: f64, x: f64) -> [f64; 8] {
    let odd = Func::ALL.map(Func::odd);
    let group = |want: bool| {
        let mut g = [0usize; 4];
        let mut n = 0;
        for (i, &o) in odd.iter().enumerate() {
            if o == want && n < 4 {
                g[n] = i;
                n += 1;
            }
        }
        g
    };
    let (even, odd_g) = (group(false), group(true));
    let w = x / (1.0 + l);
    let mut sum = [0.0; 8];
    let mut wk = 1.0;
    for k in 0..=K_FAR {
        let g = if k % 2 == 1 { odd_g } else { even };
        let mut p = [0.0; 4];
        for j in (row(k)..row(k) + k + 2).rev() {
            for (p, &f) in p.iter_mut().zip(&g) {
                *p = *p * l + FAR[f][j];
            }
        }
        for (p, &f) in p.iter().zip(&g) {
            sum[f] += p * wk;
        }
        wk *= w;
    }
    core::array::from_fn(|f| Func::ALL[f].prefactor(l) * sum[f])
}
