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

use crate::fault::LinalgError;
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
/// `n x n` row-major `a`, reading only the lower triangle (the caller fills only
/// `l <= k`). `L` is written into the lower triangle and, transposed, into the strict
/// upper one (`a[j n + k] = L_kj`, `k > j`), where [`cholesky_dense_solve`] reads it.
/// The diagonal holds `1 / L_kk`, so solves only multiply. A pivot that is not positive
/// and finite is [`LinalgError::NotPositiveDefinite`]. Cost: about `n^3 / 6`
/// multiply-adds, half of [`lu`]'s, and no pivot search.
///
/// Column by column: `L_kj = (A_kj - sum_m L_km L_jm) * (1 / L_jj)`, the sum from zero
/// in `m` order, and `L_kk^2 = A_kk - L_k0^2 - L_k1^2 - ...` in that order, as a row at a
/// time would form them (the same bits); but the entries of one column are independent,
/// so their sums run side by side, over contiguous rows of the transposed copy, which
/// the compiler vectorises (the sums of one row were one latency-bound chain after
/// another).
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
    for j in 0..n {
        let (done, rest) = a.split_at_mut(j * n);
        let (row_j, below) = rest.split_at_mut(n);
        let inv = pivot(&mut row_j[..=j], j, floor)?;
        // The column's sums `s_k = sum_m L_km L_jm` for 8 rows `k` at a time (then 4, 2,
        // 1), held in registers over `m`, then `L_kj` into both triangles.
        let (head, upper) = row_j.split_at_mut(j + 1);
        let mut k0 = j + 1;
        while k0 < n {
            let at = (&*done, &head[..j], k0, j, inv);
            // Four rows at a time and one by one on 32-bit Arm: the Cortex-M4F has no
            // vector lanes, and each width is its own copy of the loop (flash).
            let arm = cfg!(target_arch = "arm");
            k0 += match n - k0 {
                4.. if arm => column_rows::<T, 4>(at, below, upper),
                _ if arm => column_rows::<T, 1>(at, below, upper),
                8.. => column_rows::<T, 8>(at, below, upper),
                4.. => column_rows::<T, 4>(at, below, upper),
                2.. => column_rows::<T, 2>(at, below, upper),
                _ => column_rows::<T, 1>(at, below, upper),
            };
        }
    }
    // The dependent rows' stored `1 / L_kk` is exactly zero (a regular one is > 0).
    Ok((0..n).filter(|&k| a[k * n + k] == T::ZERO).count())
}

/// `L_kj` for the `W` rows `k0..k0 + W` of column `j` (`(done, l_j, k0, j, 1 / L_jj)`:
/// the rows above `j`, row `j`'s `L_jm`); `below` holds the rows from `j + 1` on,
/// `upper` row `j`'s strict upper part. Each sum runs from zero in `m` order, the `W`
/// of them side by side in registers (fixed `W`: no masked lanes). Returns `W`.
#[inline(always)]
fn column_rows<T: Real, const W: usize>(
    (done, l_j, k0, j, inv): (&[T], &[T], usize, usize, T),
    below: &mut [T],
    upper: &mut [T],
) -> usize {
    let n = upper.len() + j + 1;
    let mut s = [T::ZERO; W];
    for (row_m, &l_jm) in done.chunks_exact(n).zip(l_j) {
        let l_k = &row_m[k0..k0 + W];
        for (s, &l_km) in s.iter_mut().zip(l_k) {
            *s += l_km * l_jm;
        }
    }
    for (q, &s) in s.iter().enumerate() {
        let (k, row_k) = (k0 + q, &mut below[(k0 + q - j - 1) * n..]);
        let l = (row_k[j] - s) * inv;
        row_k[j] = l;
        upper[k - j - 1] = l;
    }
    W
}

/// `L_kk = sqrt(A_kk - sum_j L_kj^2)` for `row = [L_k0, .., L_k(k-1), A_kk]`; stores and
/// returns `1 / L_kk`, or zero for a dependent row (`d <= floor A_kk`).
#[inline(always)]
pub(super) fn pivot<T: Real>(row: &mut [T], k: usize, floor: T) -> Result<T, LinalgError> {
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

/// Solves `A x = b` in place with the factor from [`cholesky_dense`] (both triangles).
pub fn cholesky_dense_solve<T: Real>(a: &[T], n: usize, x: &mut [T]) {
    let x = &mut x[..n];
    // L y = b, column by column of L (rows of the transposed copy): y_m final, then
    // taken off the rows below, each of which subtracts its terms in `m` order, as a
    // row at a time would.
    // The loop over the rows below starts at the next multiple of 4 (those before it one
    // by one), so that its vector loads of `y` meet the previous column's vector stores
    // at the same addresses (a load that straddles two stores waits for both to retire).
    for m in 0..n {
        let row = &a[m * n..m * n + n];
        let (done, rest) = x.split_at_mut(m + 1);
        let v = done[m] * row[m];
        done[m] = v;
        let head = (3 - m % 4).min(rest.len());
        let (rest_head, rest_body) = rest.split_at_mut(head);
        let (row_head, row_body) = row[m + 1..].split_at(head);
        for (y, &l) in rest_head.iter_mut().zip(row_head) {
            *y -= l * v;
        }
        for (y, &l) in rest_body.iter_mut().zip(row_body) {
            *y -= l * v;
        }
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

/// Inverts the symmetric positive definite `m x m` row-major `a` in place: Cholesky
/// `A = U^T U` ([`cholesky_dense`], upper triangle `U`, diagonal `1 / U_kk`), `V = U^-1`
/// row by row from the bottom, then `A^-1 = V V^T`. About `2/3 m^3` flops.
pub fn spd_inverse<T: Real>(a: &mut [T], m: usize) -> Result<(), LinalgError> {
    cholesky_dense(a, m, T::ZERO)?;
    for j in (0..m).rev() {
        // Row j of V: V_jk = -V_jj sum_{j < l <= k} U_jl V_lk, taking l from the right so
        // that each U_jl is read before the sums overwrite it.
        let (head, tail) = a.split_at_mut((j + 1) * m);
        let row = &mut head[j * m..];
        for l in (j + 1..m).rev() {
            let u = row[l];
            let vl = &tail[(l - j - 1) * m..(l - j) * m];
            row[l] = u * vl[l];
            for k in l + 1..m {
                row[k] += u * vl[k];
            }
        }
        let vjj = row[j];
        for v in &mut row[j + 1..] {
            *v = -*v * vjj;
        }
    }
    // (V V^T)_ik = sum_{l >= k} V_il V_kl for k >= i: row i from the left, each entry
    // needing only row i's entries to its right and the rows below (not yet touched).
    for i in 0..m {
        let (head, tail) = a.split_at_mut((i + 1) * m);
        let row = &mut head[i * m..];
        row[i] = row[i..].iter().fold(T::ZERO, |s, &v| s + v * v);
        for k in i + 1..m {
            let vk = &tail[(k - i - 1) * m..(k - i) * m];
            row[k] = (k..m).fold(T::ZERO, |s, l| s + row[l] * vk[l]);
        }
    }
    for i in 0..m {
        for k in 0..i {
            a[i * m + k] = a[k * m + i];
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MAX: usize = 30;

    /// The row-at-a-time factorisation, written plainly: each `L_kj` a dot product from
    /// zero in index order, each pivot `A_kk` minus the squares in order.
    fn rows(a: &mut [f64], n: usize, floor: f64) -> Result<usize, LinalgError> {
        for k in 0..n {
            for j in 0..k {
                let mut s = 0.0;
                for m in 0..j {
                    s += a[k * n + m] * a[j * n + m];
                }
                a[k * n + j] = (a[k * n + j] - s) * a[j * n + j];
            }
            pivot(&mut a[k * n..=k * n + k], k, floor)?;
        }
        Ok((0..n).filter(|&k| a[k * n + k] == 0.0).count())
    }

    /// Forward substitution row by row, then the back substitution.
    fn solve_rows(a: &[f64], n: usize, x: &mut [f64]) {
        for r in 0..n {
            let mut s = x[r];
            for m in 0..r {
                s -= a[r * n + m] * x[m];
            }
            x[r] = s * a[r * n + r];
        }
        for r in (0..n).rev() {
            let v = x[r] * a[r * n + r];
            x[r] = v;
            for y in 0..r {
                x[y] -= v * a[r * n + y];
            }
        }
    }

    /// Gram matrices `G G^T` (regular, with dependent rows, or made indefinite), every
    /// size up to `MAX`: the column-wise factor and solve give the row-wise bits and the
    /// same error.
    #[test]
    fn columns_give_the_bits_of_rows() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut v = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for n in 0..MAX {
            for case in 0..3 {
                let mut g = [[0.0; MAX]; MAX];
                for row in g.iter_mut().take(n) {
                    row.iter_mut().take(n).for_each(|x| *x = v());
                }
                if case == 1 && n > 3 {
                    // Row 2 a combination of rows 0 and 1: dependent.
                    for c in 0..n {
                        g[2][c] = 0.5 * g[0][c] - 2.0 * g[1][c];
                    }
                }
                let mut a = [0.0; MAX * MAX];
                for i in 0..n {
                    for j in 0..=i {
                        a[i * n + j] = (0..n).map(|c| g[i][c] * g[j][c]).sum::<f64>();
                    }
                    a[i * n + i] += if case == 2 && i == n / 2 { -50.0 } else { 0.0 };
                }
                let floor = if case == 1 { 1e-8 } else { 0.0 };
                let (mut a0, mut a1) = (a, a);
                let (r0, r1) = (rows(&mut a0, n, floor), cholesky_dense(&mut a1, n, floor));
                assert_eq!(r0, r1, "n = {n}, case {case}");
                if r0.is_err() {
                    continue;
                }
                for i in 0..n {
                    for j in 0..=i {
                        let (l, t) = (a1[i * n + j], a1[j * n + i]);
                        assert_eq!(a0[i * n + j].to_bits(), l.to_bits(), "{n}: {i} {j}");
                        // The transposed copy.
                        assert_eq!(l.to_bits(), t.to_bits(), "{n}: {i} {j}");
                    }
                }
                let mut b = [0.0; MAX];
                b.iter_mut().take(n).for_each(|x| *x = v());
                let (mut x0, mut x1) = (b, b);
                solve_rows(&a0, n, &mut x0);
                cholesky_dense_solve(&a1, n, &mut x1);
                assert_eq!(x0.map(f64::to_bits), x1.map(f64::to_bits), "solve, n = {n}");
            }
        }
    }
}
