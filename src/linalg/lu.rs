//! Small dense scalar matrices of the dense Newton solve: Cholesky of the symmetric
//! chord Jacobian (positions), LU with partial pivoting of the Jacobian at the iterate
//! (velocities, and positions when the chord slows).
//!
//! **Dependent rows.** Constraints that are linearly dependent (a pile of spheres on a
//! wall, a square with both diagonals) make these matrices exactly singular, though the
//! projection's positions stay unique. Both factorisations take a relative rank
//! tolerance `floor`: a pivot at or below `floor` times its row's scale marks the row
//! (column) dependent instead of failing. Its factor column is set to zero and the
//! solves give its unknown zero: the *basic* solution, which keeps the independent
//! rows' equations exactly and drops the dependent row's, which for a consistent
//! right-hand side (one that the others imply) holds as well. `floor = 0` keeps the
//! strict behaviour (every pivot must be positive).

use crate::error::LinalgError;
use crate::real::Real;

/// In-place LU factorisation with partial pivoting of the `n x n` row-major `a`.
///
/// `piv[k]` records the row swapped into row `k`. A zero or non-finite pivot is
/// [`LinalgError::Singular`].
pub fn lu<T: Real>(a: &mut [T], n: usize, piv: &mut [usize]) -> Result<(), LinalgError> {
    lu_ranked(a, n, piv, T::ZERO).map(|_| ())
}

/// [`lu`] with the absolute rank tolerance `floor`: a column whose largest remaining
/// entry is at most `floor` (and finite) is dependent: it is not eliminated, its
/// diagonal is stored as exactly zero and [`lu_solve`] gives its unknown zero. Returns
/// the number of dependent columns. With `floor = 0` a zero pivot is still
/// [`LinalgError::Singular`].
pub fn lu_ranked<T: Real>(
    a: &mut [T],
    n: usize,
    piv: &mut [usize],
    floor: T,
) -> Result<usize, LinalgError> {
    let a = &mut a[..n * n];
    let mut dependent = 0;
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
        if !(best > floor && best.is_finite()) {
            if !(floor > T::ZERO && best.is_finite()) {
                return Err(LinalgError::Singular { row: k });
            }
            // Dependent column: nothing to eliminate; the solve skips its unknown.
            piv[k] = k;
            for row in a[k * n..].chunks_exact_mut(n) {
                row[k] = T::ZERO;
            }
            dependent += 1;
            continue;
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
    Ok(dependent)
}

/// Solves `A x = b` in place with the factors from [`lu`] (a dependent column's unknown,
/// a zero diagonal from [`lu_ranked`], is zero).
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
        let u = a[r * n + r];
        x[r] = if u == T::ZERO { T::ZERO } else { acc / u };
    }
}

/// In-place Cholesky factorisation `A = L L^T` of the symmetric positive definite
/// `n x n` row-major `a`, reading and writing only the lower triangle (the upper one is
/// never touched, so the caller fills only `l <= k`). Row by row, each entry one
/// contiguous dot product, two rows at a time: their entries are independent up to the
/// first row's diagonal, so the two dot products' addition chains overlap (each entry's
/// arithmetic is that of one row at a time: the same bits). The diagonal holds
/// `1 / L_kk`, so solves only multiply. A pivot that is not positive and finite is
/// [`LinalgError::NotPositiveDefinite`]. Cost: about `n^3 / 6` multiply-adds, half of
/// [`lu`]'s, and no pivot search.
///
/// Semi-definite matrices: a pivot `d <= floor A_kk` (negative ones included: a
/// Gram matrix has none but by rounding) marks row `k` dependent (a Gram matrix `G M G^T` whose row `k` of `G` lies in the span of the rows
/// before it: its Schur complement vanishes, up to rounding, in its whole row). Its
/// stored `1 / L_kk` is zero, so column `k` of `L` is zero and [`cholesky_dense_solve`]
/// gives its unknown zero. Returns the number of dependent rows. Rows are taken in
/// order (no pivoting), so which of a dependent set is dropped is the last one listed:
/// deterministic. A non-finite pivot, or a diagonal entry that is not positive, is
/// still not positive definite.
pub fn cholesky_dense<T: Real>(a: &mut [T], n: usize, floor: T) -> Result<usize, LinalgError> {
    let a = &mut a[..n * n];
    let mut k = 0;
    while k + 1 < n {
        let (done, rest) = a.split_at_mut(k * n);
        let (row_k, row_m) = rest.split_at_mut(n);
        let (row_k, row_m) = (&mut row_k[..=k], &mut row_m[..=k + 1]);
        // L_kj and L_(k+1)j for j < k, both from row j.
        for (j, row_j) in done.chunks_exact(n).enumerate() {
            let (s, t) = dot2(&row_k[..j], &row_m[..j], &row_j[..j]);
            row_k[j] = (row_k[j] - s) * row_j[j];
            row_m[j] = (row_m[j] - t) * row_j[j];
        }
        let inv = pivot(row_k, k, floor)?;
        row_m[k] = (row_m[k] - dot(&row_m[..k], &row_k[..k])) * inv;
        pivot(row_m, k + 1, floor)?;
        k += 2;
    }
    if k < n {
        let (done, rest) = a.split_at_mut(k * n);
        let row_k = &mut rest[..=k];
        for (j, row_j) in done.chunks_exact(n).enumerate() {
            let (head, tail) = row_k.split_at_mut(j);
            tail[0] = (tail[0] - dot(head, &row_j[..j])) * row_j[j];
        }
        pivot(row_k, k, floor)?;
    }
    // The dependent rows' stored `1 / L_kk` is exactly zero (a regular one is > 0).
    Ok((0..n).filter(|&k| a[k * n + k] == T::ZERO).count())
}

/// `L_kk = sqrt(A_kk - sum_j L_kj^2)` for `row = [L_k0, .., L_k(k-1), A_kk]`; stores and
/// returns `1 / L_kk`, or zero for a dependent row (`d <= floor A_kk`).
#[inline(always)]
fn pivot<T: Real>(row: &mut [T], k: usize, floor: T) -> Result<T, LinalgError> {
    let (head, last) = row.split_at_mut(k);
    let d = head.iter().fold(last[0], |s, &x| s - x * x);
    if !(d > T::ZERO && d.is_finite()) || d <= floor * last[0] {
        if floor > T::ZERO && last[0] > T::ZERO && d.is_finite() {
            last[0] = T::ZERO;
            return Ok(T::ZERO);
        }
        return Err(LinalgError::NotPositiveDefinite { row: k });
    }
    last[0] = T::ONE / d.sqrt();
    Ok(last[0])
}

/// Solves `A x = b` in place with the factor from [`cholesky_dense`].
pub fn cholesky_dense_solve<T: Real>(a: &[T], n: usize, x: &mut [T]) {
    let x = &mut x[..n];
    // L y = b, row by row.
    for r in 0..n {
        let row = &a[r * n..r * n + r + 1];
        x[r] = sub_dot(x[r], &row[..r], &x[..r]) * row[r];
    }
    // L^T x = y, column by column of L^T (rows of L): x_r final, then taken off the rest.
    for r in (0..n).rev() {
        let row = &a[r * n..r * n + r + 1];
        let (rest, done) = x.split_at_mut(r);
        let v = done[0] * row[r];
        done[0] = v;
        for (y, &l) in rest.iter_mut().zip(&row[..r]) {
            *y -= v * l;
        }
    }
}

/// `sum a_i b_i` from zero in index order, four terms per loop pass (the same bits as
/// the plain loop; fewer loop instructions on cores without SIMD floats).
#[inline(always)]
fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (a4.remainder(), b4.remainder());
    let mut s = T::ZERO;
    for (x, y) in a4.zip(b4) {
        s += x[0] * y[0];
        s += x[1] * y[1];
        s += x[2] * y[2];
        s += x[3] * y[3];
    }
    ra.iter().zip(rb).fold(s, |s, (&x, &y)| s + x * y)
}

/// `s - a_0 b_0 - a_1 b_1 - ...` in index order, four terms per loop pass (the bits of
/// the plain loop).
#[inline(always)]
fn sub_dot<T: Real>(mut s: T, a: &[T], b: &[T]) -> T {
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (a4.remainder(), b4.remainder());
    for (x, y) in a4.zip(b4) {
        s -= x[0] * y[0];
        s -= x[1] * y[1];
        s -= x[2] * y[2];
        s -= x[3] * y[3];
    }
    ra.iter().zip(rb).fold(s, |s, (&x, &y)| s - x * y)
}

/// `(sum a_i c_i, sum b_i c_i)`, each from zero in index order (the bits of [`dot`]).
#[inline(always)]
fn dot2<T: Real>(a: &[T], b: &[T], c: &[T]) -> (T, T) {
    let (mut s, mut t) = (T::ZERO, T::ZERO);
    for ((&x, &y), &z) in a.iter().zip(b).zip(c) {
        s += x * z;
        t += y * z;
    }
    (s, t)
}
