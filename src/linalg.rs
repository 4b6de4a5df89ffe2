//! Dense linear algebra in caller-owned storage.
//!
//! * Block Cholesky of a symmetric positive definite matrix stored as `n x n` 3x3
//!   blocks (row-major slice): the mobility `mu_tt` (`n` blocks) or the grand mobility
//!   (`2n` blocks). Resistance products `R x = mu^-1 x` go through the factor, never an
//!   explicit inverse.
//! * LU with partial pivoting of a small scalar matrix (the constraint Jacobian).
//!
//! Loops run in a fixed order and use plain multiply-add (no `mul_add`), so results are
//! bit-identical across runs and platforms.
//!
//! Slice lengths are the caller's contract (`n * n` blocks for a matrix, `n` for a
//! vector); a shorter slice panics on indexing, like any slice API. `step()` always
//! passes views sized from its own capacity, so no user input reaches these with a
//! wrong length.

use crate::error::LinalgError;
use crate::real::Real;

/// `y = A x` for a symmetric block matrix, reading only its lower triangle.
pub fn sym_matvec<T: Real>(a: &[T::M3], n: usize, x: &[T::V3], y: &mut [T::V3]) {
    for i in 0..n {
        y[i] = a[i * n + i] * x[i];
    }
    for i in 0..n {
        let row = &a[i * n..i * n + i];
        let mut acc = T::V3_ZERO;
        for (j, &aij) in row.iter().enumerate() {
            acc += aij * x[j];
            y[j] += T::m3_tmul(aij, x[i]);
        }
        y[i] += acc;
    }
}

/// Lower Cholesky factor of a symmetric 3x3 block; `row0` names the block's first row
/// in errors.
fn chol3<T: Real>(s: T::M3, row0: usize) -> Result<T::M3, LinalgError> {
    let g = |r, c| T::m3_get(s, r, c);
    let root = |x: T, row: usize| {
        if x > T::ZERO && x.is_finite() {
            Ok(x.sqrt())
        } else {
            Err(LinalgError::NotPositiveDefinite { row })
        }
    };
    let l00 = root(g(0, 0), row0)?;
    let l10 = g(1, 0) / l00;
    let l20 = g(2, 0) / l00;
    let l11 = root(g(1, 1) - l10 * l10, row0 + 1)?;
    let l21 = (g(2, 1) - l20 * l10) / l11;
    let l22 = root(g(2, 2) - l20 * l20 - l21 * l21, row0 + 2)?;
    let o = T::ZERO;
    Ok(T::m3_cols(
        T::v3(l00, l10, l20),
        T::v3(o, l11, l21),
        T::v3(o, o, l22),
    ))
}

/// Inverse of a lower-triangular 3x3 matrix with a positive diagonal.
fn inv_lower3<T: Real>(l: T::M3) -> T::M3 {
    let g = |r, c| T::m3_get(l, r, c);
    let i00 = T::ONE / g(0, 0);
    let i11 = T::ONE / g(1, 1);
    let i22 = T::ONE / g(2, 2);
    let i10 = -g(1, 0) * i00 * i11;
    let i21 = -g(2, 1) * i11 * i22;
    let i20 = -(g(2, 0) * i00 + g(2, 1) * i10) * i22;
    let o = T::ZERO;
    T::m3_cols(T::v3(i00, i10, i20), T::v3(o, i11, i21), T::v3(o, o, i22))
}

/// In-place block Cholesky `A = L L^T` (left-looking, by block columns).
///
/// Reads the lower triangle of `a` (`n x n` blocks). On success the strictly lower
/// blocks hold `L` and each diagonal block holds `L_jj^-1` (so solves only multiply).
/// The upper triangle is left as it was. Cost: about `(3n)^3 / 3` flops.
pub fn cholesky<T: Real>(a: &mut [T::M3], n: usize) -> Result<(), LinalgError> {
    for j in 0..n {
        let mut s = a[j * n + j];
        for k in 0..j {
            let l = a[j * n + k];
            s -= l * T::transpose(l);
        }
        let linv = inv_lower3::<T>(chol3::<T>(s, 3 * j)?);
        a[j * n + j] = linv;
        let linv_t = T::transpose(linv);
        for i in j + 1..n {
            let mut c = a[i * n + j];
            for k in 0..j {
                c -= a[i * n + k] * T::transpose(a[j * n + k]);
            }
            a[i * n + j] = c * linv_t;
        }
    }
    Ok(())
}

/// Solves `L L^T x = b` in place with a factor from [`cholesky`].
pub fn cholesky_solve<T: Real>(l: &[T::M3], n: usize, x: &mut [T::V3]) {
    for i in 0..n {
        let mut acc = x[i];
        for k in 0..i {
            acc -= l[i * n + k] * x[k];
        }
        x[i] = l[i * n + i] * acc;
    }
    for i in (0..n).rev() {
        let mut acc = x[i];
        for k in i + 1..n {
            acc -= T::m3_tmul(l[k * n + i], x[k]);
        }
        x[i] = T::m3_tmul(l[i * n + i], acc);
    }
}

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
