//! A semi-definite Cholesky factor whose rows change one at a time: rows are appended
//! at the end (`O(m^2)`: the new row's entries by forward substitution) and removed
//! from anywhere (`O((m - p)^2)`: the rows below are moved up and the block below
//! the removed row takes its column back by a rank-one update, Givens rotations, which
//! never lose precision as a downdate can). The rows are the caller's in the order
//! they entered ("positions"); a factorisation from scratch is `O(m^3)`.
//!
//! Storage: row-major with stride `n`, position `i`'s row `L_ij` (`j < i`) at
//! `a[i n + j]` and `1 / L_ii` on the diagonal, zero for a dependent row (its pivot
//! `d <= floor A_ii`, as in [`cholesky_dense`](super::cholesky_dense)): its column is
//! zero and the solve gives it a zero value (the basic solution).

use super::lu::pivot;
use crate::fault::LinalgError;
use crate::real::Real;

/// Factorises the `m` rows whose lower triangle `entry(i, j)` (`j <= i`) gives, into
/// `a` (stride `n >= m`), by [`cholesky_dense`](super::cholesky_dense). Returns the
/// dependent rows counted.
pub fn ordered_build<T: Real>(
    a: &mut [T],
    n: usize,
    m: usize,
    floor: T,
    entry: impl Fn(usize, usize) -> T,
) -> Result<usize, LinalgError> {
    // Gathered with stride `m`, factorised, then spread to stride `n` from the last row
    // up (a row's place at stride `n` lies past every earlier row's at stride `m`).
    for i in 0..m {
        for j in 0..=i {
            a[i * m + j] = entry(i, j);
        }
    }
    let deficient = super::cholesky_dense(a, m, floor)?;
    for i in (1..m).rev() {
        a.copy_within(i * m..i * m + i + 1, i * n);
    }
    Ok(deficient)
}

/// Appends row `m` (`entry(j)`: its entry against position `j < m`; `diagonal`: its
/// own). Returns whether it is dependent on the rows before it.
pub fn ordered_append<T: Real>(
    a: &mut [T],
    n: usize,
    m: usize,
    floor: T,
    diagonal: T,
    entry: impl Fn(usize) -> T,
) -> Result<bool, LinalgError> {
    let (done, rest) = a.split_at_mut(m * n);
    let row = &mut rest[..=m];
    for (j, r) in row[..m].iter_mut().enumerate() {
        *r = entry(j);
    }
    // Each sum from zero in column order, as `cholesky_dense` forms it: a row appended
    // after rows that are all before it in the caller's list has the bits a
    // factorisation of the whole would give it.
    for j in 0..m {
        let inv = done[j * n + j];
        row[j] = match inv == T::ZERO {
            true => T::ZERO,
            false => {
                let l_j = &done[j * n..j * n + j];
                let s = row[..j]
                    .iter()
                    .zip(l_j)
                    .fold(T::ZERO, |s, (&a, &b)| s + a * b);
                (row[j] - s) * inv
            }
        };
    }
    row[m] = diagonal;
    Ok(pivot(row, m, floor)? == T::ZERO)
}

/// Removes position `p` of `m`: the rows below move up one, and the block from `p` on
/// takes the removed column `w` back (`L' L'^T = L L^T + w w^T` there) by Givens
/// rotations. A dependent row that `w` reaches by `w_j^2 <= floor diagonal(j)` (the
/// diagonal entry of the row now at `j`) stays dependent, as a factorisation from
/// scratch would leave it.
pub fn ordered_remove<T: Real>(
    a: &mut [T],
    n: usize,
    m: usize,
    p: usize,
    floor: T,
    diagonal: impl Fn(usize) -> T,
) {
    // `w` (for the new position `q`) kept in row `p`'s unused upper part, column `q + 1`.
    for i in p + 1..m {
        a[p * n + i] = a[i * n + p];
    }
    for i in p + 1..m {
        a.copy_within(i * n..i * n + p, (i - 1) * n);
        a.copy_within(i * n + p + 1..i * n + i + 1, (i - 1) * n + p);
    }
    let m = m - 1;
    for j in p..m {
        let wj = a[p * n + j + 1];
        let inv = a[j * n + j];
        if wj == T::ZERO || (inv == T::ZERO && wj * wj <= floor * diagonal(j)) {
            continue;
        }
        let l = match inv == T::ZERO {
            true => T::ZERO,
            false => T::ONE / inv,
        };
        let r = (l * l + wj * wj).sqrt();
        let (c, s) = (l / r, wj / r);
        a[j * n + j] = T::ONE / r;
        for i in j + 1..m {
            let (f, w) = (a[i * n + j], a[p * n + i + 1]);
            a[i * n + j] = c * f + s * w;
            a[p * n + i + 1] = c * w - s * f;
        }
    }
}

/// Solves `A y = x` for the `m` positions, position `i` reading and writing
/// `x[order[i]]` (other entries untouched).
pub fn ordered_solve<T: Real>(a: &[T], n: usize, m: usize, order: &[usize], x: &mut [T]) {
    for i in 0..m {
        let row = &a[i * n..i * n + i + 1];
        let s = (0..i).fold(x[order[i]], |s, j| s - row[j] * x[order[j]]);
        x[order[i]] = s * row[i];
    }
    for i in (0..m).rev() {
        let row = &a[i * n..i * n + i + 1];
        let v = x[order[i]] * row[i];
        x[order[i]] = v;
        for j in 0..i {
            x[order[j]] -= row[j] * v;
        }
    }
}

/// The self-stress of the first dependent position `q` (`L^T v = 0` above it, `v_q =
/// 1`), written to `v[order[i]]`, every other entry of `v` zero. All zero where no row
/// is dependent.
pub fn ordered_null<'v, T: Real>(
    a: &[T],
    n: usize,
    m: usize,
    order: &[usize],
    v: &'v mut [T],
) -> &'v mut [T] {
    v.fill(T::ZERO);
    let Some(q) = (0..m).find(|&k| a[k * n + k] == T::ZERO) else {
        return v;
    };
    v[order[q]] = T::ONE;
    for j in (0..q).rev() {
        let s = (j + 1..q).fold(a[q * n + j], |s, i| s + a[i * n + j] * v[order[i]]);
        v[order[j]] = -s * a[j * n + j];
    }
    v
}
