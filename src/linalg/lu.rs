//! LU with partial pivoting of a small dense scalar matrix: the constraint Jacobian of
//! the dense Newton solve.

use crate::error::LinalgError;
use crate::real::Real;

/// In-place LU factorisation with partial pivoting of the `n x n` row-major `a`.
///
/// `piv[k]` records the row swapped into row `k`. A zero or non-finite pivot is
/// [`LinalgError::Singular`].
pub fn lu<T: Real>(a: &mut [T], n: usize, piv: &mut [usize]) -> Result<(), LinalgError> {
    let a = &mut a[..n * n];
    for k in 0..n {
        let mut p = k;
        let mut best = a[k * n + k].abs();
        for r in k + 1..n {
            let v = a[r * n + k].abs();
            if v > best {
                best = v;
                p = r;
            }
        }
        if !(best > T::ZERO && best.is_finite()) {
            return Err(LinalgError::Singular { row: k });
        }
        piv[k] = p;
        if p != k {
            let (top, bottom) = a.split_at_mut(p * n);
            top[k * n..k * n + n].swap_with_slice(&mut bottom[..n]);
        }
        // Eliminate below the pivot row, one row slice at a time (no bounds checks inside).
        let (upper, lower) = a.split_at_mut((k + 1) * n);
        let pivot_row = &upper[k * n + k..k * n + n];
        let inv = T::ONE / pivot_row[0];
        for row in lower.chunks_exact_mut(n) {
            let f = row[k] * inv;
            row[k] = f;
            for (x, &u) in row[k + 1..].iter_mut().zip(&pivot_row[1..]) {
                *x -= f * u;
            }
        }
    }
    Ok(())
}

/// Solves `A x = b` in place with the factors from [`lu`].
pub fn lu_solve<T: Real>(a: &[T], n: usize, piv: &[usize], x: &mut [T]) {
    let x = &mut x[..n];
    for k in 0..n {
        x.swap(k, piv[k]);
    }
    for r in 0..n {
        let row = &a[r * n..r * n + r];
        let acc = row
            .iter()
            .zip(&x[..r])
            .fold(x[r], |acc, (&l, &y)| acc - l * y);
        x[r] = acc;
    }
    for r in (0..n).rev() {
        let row = &a[r * n + r + 1..r * n + n];
        let acc = row
            .iter()
            .zip(&x[r + 1..])
            .fold(x[r], |acc, (&u, &y)| acc - u * y);
        x[r] = acc / a[r * n + r];
    }
}
