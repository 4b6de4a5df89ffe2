//! Banded Cholesky of a symmetric scalar matrix: the Krylov solver's preconditioner.
//!
//! Row `k` of an `n x n` matrix of half-bandwidth `w` is stored as `w + 1` entries,
//! columns `k - w ..= k` (entries left of column 0 are unused zeros), so the storage is
//! `n (w + 1)` scalars and the factorisation costs `n w^2` flops.

use crate::fault::LinalgError;
use crate::real::Real;

/// Index of entry `(k, l)`, `k - w <= l <= k`, in band storage of half-bandwidth `w`.
#[inline(always)]
pub fn at(w: usize, k: usize, l: usize) -> usize {
    k * (w + 1) + (l + w - k)
}

/// In-place Cholesky `A = L L^T` of a banded symmetric matrix (lower band stored).
pub fn cholesky<T: Real>(a: &mut [T], n: usize, w: usize) -> Result<(), LinalgError> {
    regularised(a, n, w, T::ZERO).map(|_| ())
}

/// [`cholesky`] of a positive semi-definite matrix for a preconditioner: a pivot within
/// `floor` times its row's diagonal of zero (a row dependent on the ones before it) is
/// replaced by that diagonal, so the factor is that of `A` plus a positive diagonal
/// where `A` is singular: positive definite, and `A` itself elsewhere. A pivot below
/// that is an error: the band is indefinite (the band of a positive definite matrix
/// need not be), and replacing its pivots would make a factor far from `A`. Returns
/// how many pivots were replaced. With `floor = 0` it is [`cholesky`].
pub fn regularised<T: Real>(
    a: &mut [T],
    n: usize,
    w: usize,
    floor: T,
) -> Result<usize, LinalgError> {
    let mut replaced = 0;
    for k in 0..n {
        for l in k.saturating_sub(w)..=k {
            let diagonal = a[at(w, k, l)];
            let mut s = diagonal;
            for t in k.saturating_sub(w).max(l.saturating_sub(w))..l {
                s -= a[at(w, k, t)] * a[at(w, l, t)];
            }
            if l < k {
                a[at(w, k, l)] = s / a[at(w, l, l)];
            } else if s > floor * diagonal && s.is_finite() {
                a[at(w, k, k)] = s.sqrt();
            } else if floor > T::ZERO
                && diagonal > T::ZERO
                && s > -floor * diagonal
                && s.is_finite()
            {
                a[at(w, k, k)] = diagonal.sqrt();
                replaced += 1;
            } else {
                return Err(LinalgError::NotPositiveDefinite { row: k });
            }
        }
    }
    Ok(replaced)
}

/// Solves `L L^T x = b` in place with a factor from [`cholesky`].
pub fn solve<T: Real>(l: &[T], n: usize, w: usize, x: &mut [T]) {
    for k in 0..n {
        let mut acc = x[k];
        for t in k.saturating_sub(w)..k {
            acc -= l[at(w, k, t)] * x[t];
        }
        x[k] = acc / l[at(w, k, k)];
    }
    for k in (0..n).rev() {
        let mut acc = x[k];
        for t in k + 1..n.min(k + w + 1) {
            acc -= l[at(w, t, k)] * x[t];
        }
        x[k] = acc / l[at(w, k, k)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tridiagonal Laplacian plus identity, solved against a known vector.
    #[test]
    fn solves_a_banded_system() -> Result<(), LinalgError> {
        let (n, w): (usize, usize) = (6, 2);
        let mut a = [0.0f64; 18];
        let dense = |k: usize, l: usize| -> f64 {
            match k.abs_diff(l) {
                0 => 3.0,
                1 => -1.0,
                2 => 0.25,
                _ => 0.0,
            }
        };
        for k in 0..n {
            for l in k.saturating_sub(w)..=k {
                a[at(w, k, l)] = dense(k, l);
            }
        }
        let x_true = [1.0, -2.0, 0.5, 3.0, -1.0, 2.0];
        let mut b = [0.0; 6];
        for k in 0..n {
            b[k] = (0..n).map(|l| dense(k, l) * x_true[l]).sum();
        }
        cholesky(&mut a, n, w)?;
        solve(&a, n, w, &mut b);
        for k in 0..n {
            assert!((b[k] - x_true[k]).abs() < 1e-13, "{k}: {}", b[k]);
        }
        Ok(())
    }

    #[test]
    fn indefinite_is_an_error() {
        let mut a = [0.0f64, 1.0, 2.0, 1.0]; // [[1, 2], [2, 1]] with w = 1
        assert_eq!(
            cholesky(&mut a, 2, 1),
            Err(LinalgError::NotPositiveDefinite { row: 1 })
        );
    }
}
