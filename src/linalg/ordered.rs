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
    // factorisation of the whole would give it. The sums of `W` entries at a time run
    // side by side (a single running sum waits on each addition in turn).
    let mut j = 0;
    while j < m {
        j += match m - j {
            8.. => forward::<T, 8>(done, n, row, j),
            4.. => forward::<T, 4>(done, n, row, j),
            2.. => forward::<T, 2>(done, n, row, j),
            _ => forward::<T, 1>(done, n, row, j),
        };
    }
    row[m] = diagonal;
    Ok(pivot(row, m, floor)? == T::ZERO)
}

/// Entries `j..j + W` of an appended row (`row[..j]` final, `row[j..j + W]` its
/// entries against those positions): `L_kj = (A_kj - sum_i L_ki L_ji) / L_jj`, each sum
/// from zero in `i` order, the `W` of them in registers over the final entries and then
/// finished one by one within the block. Returns `W`.
#[inline(always)]
fn forward<T: Real, const W: usize>(done: &[T], n: usize, row: &mut [T], j: usize) -> usize {
    let mut s = [T::ZERO; W];
    for (i, &y) in row[..j].iter().enumerate() {
        for (q, s) in s.iter_mut().enumerate() {
            *s += y * done[(j + q) * n + i];
        }
    }
    for q in 0..W {
        let k = j + q;
        let inv = done[k * n + k];
        let l_k = &done[k * n..k * n + k];
        let s = (j..k).fold(s[q], |s, i| s + row[i] * l_k[i]);
        row[k] = match inv == T::ZERO {
            true => T::ZERO,
            false => (row[k] - s) * inv,
        };
    }
    W
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
    // `W` rows at a time, their sums side by side as in [`ordered_append`].
    let mut i = 0;
    while i < m {
        i += match m - i {
            8.. => lower::<T, 8>(a, n, order, x, i),
            4.. => lower::<T, 4>(a, n, order, x, i),
            2.. => lower::<T, 2>(a, n, order, x, i),
            _ => lower::<T, 1>(a, n, order, x, i),
        };
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

/// Positions `i..i + W` of the forward substitution `L y = x` (the positions before
/// final): `y_k = (x_k - sum_j L_kj y_j) / L_kk`, each running from `x_k` in `j` order.
/// Returns `W`.
#[inline(always)]
fn lower<T: Real, const W: usize>(
    a: &[T],
    n: usize,
    order: &[usize],
    x: &mut [T],
    i: usize,
) -> usize {
    let mut s: [T; W] = core::array::from_fn(|q| x[order[i + q]]);
    for (j, &o) in order[..i].iter().enumerate() {
        let y = x[o];
        for (q, s) in s.iter_mut().enumerate() {
            *s -= a[(i + q) * n + j] * y;
        }
    }
    for (q, &s) in s.iter().enumerate() {
        let k = i + q;
        let row = &a[k * n..k * n + k + 1];
        let s = (i..k).fold(s, |s, j| s - row[j] * x[order[j]]);
        x[order[k]] = s * row[k];
    }
    W
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
