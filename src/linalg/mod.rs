//! Dense and banded linear algebra in caller-owned storage.
//!
//! * Symmetric block matrices (the mobility `mu_tt`, the grand mobility, the implicit
//!   drag operator) are stored **packed**: the lower triangle of 3x3 blocks, row by
//!   row, block `(i, j)`, `j <= i`, at [`tri`]`(i) + j` — `n (n + 1) / 2` blocks, half
//!   of a full matrix. The blocks themselves are symmetric on the diagonal.
//! * Block Cholesky of such a matrix; resistance products `R x = mu^-1 x` go through
//!   the factor, never an explicit inverse.
//! * LU with partial pivoting of a small scalar matrix ([`lu()`]), and a banded Cholesky
//!   ([`band`]) for the Krylov solver's preconditioner.
//!
//! Loops run in a fixed order and use plain multiply-add (no `mul_add`), so results are
//! bit-identical across runs and platforms.
//!
//! Slice lengths are the caller's contract (`tri(n)` blocks for a matrix, `n` for a
//! vector); a shorter slice panics on indexing, like any slice API. `step()` always
//! passes views carved from a checked [`Layout`](crate::workspace::Layout), so no user
//! input reaches these with a wrong length.

pub mod band;
pub(crate) mod block;
mod lu;
mod ordered;
pub(crate) mod packed;

pub(crate) use block::with_blocks;
pub use block::{Block, Mob, MobMut, Sym};

pub use lu::{cholesky_dense, cholesky_dense_solve, lu, lu_ranked, lu_solve, spd_inverse};
pub use ordered::{ordered_append, ordered_build, ordered_null, ordered_remove, ordered_solve};

use crate::fault::LinalgError;
use crate::real::Real;

/// Offset of packed row `i`: `i (i + 1) / 2`; `tri(n)` is the size of an `n x n` matrix.
#[inline(always)]
pub const fn tri(i: usize) -> usize {
    i * (i + 1) / 2
}

/// Block `(i, j)` of a packed symmetric matrix, either triangle (`A_ji = A_ij^T`).
#[inline(always)]
pub fn sym_get<T: Real>(a: &[T::M3], i: usize, j: usize) -> T::M3 {
    if j <= i {
        a[tri(i) + j]
    } else {
        T::transpose(a[tri(j) + i])
    }
}

/// `b x` for a symmetric 3x3 block from its lower triangle: the bits of both `b * x` and
/// `b^T x` (the same products summed in glam's order, the upper entries equal to the
/// lower), with 6 entries live instead of 9.
#[inline(always)]
pub fn sym3_mul<T: Real>(b: T::M3, x: T::V3) -> T::V3 {
    let e = |r, c| T::m3_get(b, r, c);
    let (b00, b10, b20, b11, b21, b22) = (e(0, 0), e(1, 0), e(2, 0), e(1, 1), e(2, 1), e(2, 2));
    let [x, y, z] = T::xyz(x);
    T::v3(
        b00 * x + b10 * y + b20 * z,
        b10 * x + b11 * y + b21 * z,
        b20 * x + b21 * y + b22 * z,
    )
}

/// `y = A x` for a packed symmetric block matrix.
///
/// Row `i` starts `y_i` from its diagonal term and adds its lower blocks' products in
/// order; the transposed products reach `y_j` from the rows below, in row order. In one
/// pass on one thread at any size; [`crate::parallel::product`] is the same arithmetic
/// cut into bands (the same bits below [`crate::parallel::BANDED_MIN`] rows).
pub fn sym_matvec<T: Real>(a: &[impl Block<T>], n: usize, x: &[T::V3], y: &mut [T::V3]) {
    packed::band::<T, _>(a, 0, x, &mut y[..n], &mut []);
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

/// In-place block Cholesky `A = L L^T` of a packed symmetric matrix (left-looking).
///
/// On success the strictly lower blocks hold `L` and each diagonal block holds
/// `L_jj^-1` (so solves only multiply). Cost: about `(3n)^3 / 3` flops.
pub fn cholesky<T: Real>(a: &mut [T::M3], n: usize) -> Result<(), LinalgError> {
    for j in 0..n {
        let (rj, dj) = (tri(j), tri(j) + j);
        let mut s = a[dj];
        for k in 0..j {
            let l = a[rj + k];
            s -= l * T::transpose(l);
        }
        let linv = inv_lower3::<T>(chol3::<T>(s, 3 * j)?);
        a[dj] = linv;
        let linv_t = T::transpose(linv);
        for i in j + 1..n {
            let ri = tri(i);
            let mut c = a[ri + j];
            for k in 0..j {
                c -= a[ri + k] * T::transpose(a[rj + k]);
            }
            a[ri + j] = c * linv_t;
        }
    }
    Ok(())
}

/// Solves `L L^T x = b` in place with a factor from [`cholesky`].
pub fn cholesky_solve<T: Real>(l: &[T::M3], n: usize, x: &mut [T::V3]) {
    solve_lower::<T>(l, n, x);
    solve_upper::<T>(l, n, x);
}

/// Solves `L y = b` in place with a factor from [`cholesky`] (forward substitution).
pub fn solve_lower<T: Real>(l: &[T::M3], n: usize, x: &mut [T::V3]) {
    for i in 0..n {
        let ri = tri(i);
        let mut acc = x[i];
        for k in 0..i {
            acc -= l[ri + k] * x[k];
        }
        x[i] = l[ri + i] * acc;
    }
}

/// Solves `L^T x = y` in place with a factor from [`cholesky`] (back substitution):
/// with `y` standard normal, `x = L^-T y` has covariance `A^-1`.
pub fn solve_upper<T: Real>(l: &[T::M3], n: usize, x: &mut [T::V3]) {
    for i in (0..n).rev() {
        let mut acc = x[i];
        for k in i + 1..n {
            acc -= T::m3_tmul(l[tri(k) + i], x[k]);
        }
        x[i] = T::m3_tmul(l[tri(i) + i], acc);
    }
}

/// `y = L x` with a factor from [`cholesky`] (whose diagonal blocks hold `L_ii^-1`):
/// with `x` standard normal, `y` has covariance `A = L L^T`.
pub fn lower_mul<T: Real>(l: &[T::M3], n: usize, x: &[T::V3], y: &mut [T::V3]) {
    for i in 0..n {
        let ri = tri(i);
        let mut acc = inv_lower3::<T>(l[ri + i]) * x[i];
        for k in 0..i {
            acc += l[ri + k] * x[k];
        }
        y[i] = acc;
    }
}
