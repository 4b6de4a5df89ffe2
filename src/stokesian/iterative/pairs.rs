//! The pairs' blocks of the iterative product: `L` and `L^T` over the sphere vectors,
//! the block-Jacobi preconditioner, and their set-up (a sphere near the wall is an
//! entry `[i, i]` beside the pairs, its 6x6 correction in half of a pair's 12x12).

use super::super::{Far, NearField, SdError, pair_far, wall_correction};
use super::{B, K};
use crate::linalg::{cholesky_dense, spd_inverse};
use crate::real::Real;

/// The `V3` slot (in the grand layout) of entry `b` (0..4) of pair `(i, j)`.
#[inline(always)]
pub(super) fn slot(n: usize, [i, j]: [usize; 2], b: usize) -> usize {
    [i, j, n + i, n + j][b]
}

/// `(n, pairs, factors)`.
pub(super) type Ctx<'c, T> = (usize, &'c [[usize; 2]], &'c [T]);

/// `a . b`, in order.
pub(super) fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    a.iter().zip(b).fold(T::ZERO, |s, (&a, &b)| s + a * b)
}

/// `y += a x`.
pub(super) fn axpy<T: Real>(a: T, x: &[T], y: &mut [T]) {
    for (y, &x) in y.iter_mut().zip(x) {
        *y += a * x;
    }
}

/// Pair `p`'s `L_p` and preconditioner `B_p^-1` as fixed-size blocks (always there:
/// the storage holds `2 B` reals a pair).
#[inline(always)]
fn blocks<T: Real>(fac: &[T], p: usize) -> Option<(&[T; B], &[T; B])> {
    let (l, rest) = fac.get(p * 2 * B..)?.split_first_chunk::<B>()?;
    Some((l, rest.first_chunk::<B>()?))
}

/// `x = L v` over the sphere vectors (`2n`).
pub(super) fn scatter<T: Real>((n, pairs, fac): Ctx<'_, T>, v: &[T], x: &mut [T::V3]) {
    x.fill(T::V3_ZERO);
    for (p, (&pair, v)) in pairs.iter().zip(v.chunks_exact(K)).enumerate() {
        let Some((l, _)) = blocks(fac, p) else {
            continue;
        };
        let mut w = [T::ZERO; K];
        for k in 0..K {
            let mut s = T::ZERO;
            for m in 0..=k {
                s += l[k * K + m] * v[m];
            }
            w[k] = s;
        }
        for b in 0..4 {
            x[slot(n, pair, b)] += T::v3(w[3 * b], w[3 * b + 1], w[3 * b + 2]);
        }
    }
}

/// `g = L^T u`, pair by pair.
pub(super) fn gather<T: Real>((n, pairs, fac): Ctx<'_, T>, u: &[T::V3], g: &mut [T]) {
    for (p, (&pair, g)) in pairs.iter().zip(g.chunks_exact_mut(K)).enumerate() {
        let Some((l, _)) = blocks(fac, p) else {
            continue;
        };
        let mut loc = [T::ZERO; K];
        for b in 0..4 {
            loc[3 * b..3 * b + 3].copy_from_slice(&T::xyz(u[slot(n, pair, b)]));
        }
        let mut out = [T::ZERO; K];
        for k in 0..K {
            for m in 0..=k {
                out[m] += l[k * K + m] * loc[k];
            }
        }
        g.copy_from_slice(&out);
    }
}

/// `s = B^-1 r`, pair by pair (the stored inverse).
pub(super) fn precond<T: Real>((_, _, fac): Ctx<'_, T>, r: &[T], s: &mut [T]) {
    for (p, (r, s)) in r.chunks_exact(K).zip(s.chunks_exact_mut(K)).enumerate() {
        let Some((_, b)) = blocks(fac, p) else {
            continue;
        };
        for k in 0..K {
            let mut t = T::ZERO;
            for m in 0..K {
                t += b[k * K + m] * r[m];
            }
            s[k] = t;
        }
    }
}

/// `l` (a semi-definite `k x k`, row-major) into its lower Cholesky factor, strict
/// upper part zero; a dependent row's column is zero.
pub(super) fn factor_semidefinite<T: Real>(l: &mut [T], k: usize) -> Result<(), SdError> {
    let floor = T::EPSILON * T::from_f64(64.0);
    cholesky_dense(l, k, floor).map_err(SdError::NotPositiveDefinite)?;
    for r in 0..k {
        let d = l[r * k + r];
        l[r * k + r] = if d == T::ZERO { T::ZERO } else { T::ONE / d };
        l[r * k + r + 1..(r + 1) * k].fill(T::ZERO);
    }
    Ok(())
}

/// One entry's 12x12 far-field block, `(1, 2, rotation 1, rotation 2)`.
pub(super) type Far12<T> = [[<T as Real>::M3; 4]; 4];

/// The pair `(i, j)`'s own free-space RPY 12x12 mobility, the preconditioner's far
/// block, at the clamped gap as the correction is (apart, so positive definite).
pub(super) fn pair_block<T: Real>(
    eta: T,
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    [i, j]: [usize; 2],
) -> Far12<T> {
    let (a1, a2) = (radius[i], radius[j]);
    let r = far.separation(pos[i], pos[j]);
    let len = T::norm2(r).sqrt();
    let (mean, floor) = ((a1 + a2) * T::HALF, near.min_gap + T::TWO);
    let d = match len > T::ZERO {
        true => r * ((len.max(mean * floor)) / len),
        false => T::v3(mean * floor, T::ZERO, T::ZERO),
    };
    pair_far(eta, a1, a2, d)
}

/// Sphere `i`'s wall correction ([`wall_correction`]) factored into the 12x12 `l` of
/// an entry `[i, i]`: its translation rows and columns at the pair's first slot, its
/// rotation at the third (both [`slot`]s of those are sphere `i`'s), the second and
/// fourth zero. Returns the far field's 6x6 self block in the same places, the
/// preconditioner's.
pub(super) fn wall_factor<T: Real>(
    eta: T,
    height: T,
    spheres: (&[T::V3], &[T]),
    near: NearField<T>,
    i: usize,
    l: &mut [T],
) -> Result<Far12<T>, SdError> {
    let z = T::M3_ZERO;
    let mut m = [[z; 4]; 4];
    l.fill(T::ZERO);
    let Some((c, far)) = wall_correction(eta, height, spheres, near, i)? else {
        return Ok(m);
    };
    // The entry's row of local row `q` (translation 0..3, rotation 3..6).
    let slot_of = |q: usize| if q < 3 { q } else { q + 3 };
    let entry = |k: usize, c6: usize| T::m3_get(c[k / 3][c6 / 3], k % 3, c6 % 3);
    // A mode whose correction is zero to rounding (far from the wall, where the far
    // self block is all but exact) may round below zero in f32: left out, as the
    // semi-definite factor leaves out a dependent row (its own scale, the far field's
    // resistance `1 / M_kk`); one further below zero is refused, not hidden.
    let floor = T::EPSILON * T::from_f64(64.0);
    let (mut kept, mut nk) = ([0usize; 6], 0);
    for k in 0..6 {
        let scale = T::ONE / T::m3_get(far[k / 3][k / 3], k % 3, k % 3);
        let d = entry(k, k);
        if d > floor * scale {
            kept[nk] = k;
            nk += 1;
        } else if !(d >= -floor * scale) {
            let error = crate::error::LinalgError::NotPositiveDefinite { row: slot_of(k) };
            return Err(SdError::NotPositiveDefinite(error));
        }
    }
    let mut l6 = [T::ZERO; 36];
    for (q, x) in l6[..nk * nk].iter_mut().enumerate() {
        *x = entry(kept[q / nk], kept[q % nk]);
    }
    factor_semidefinite(&mut l6[..nk * nk], nk)?;
    for (q, &x) in l6[..nk * nk].iter().enumerate() {
        l[slot_of(kept[q / nk]) * K + slot_of(kept[q % nk])] = x;
    }
    for (r, row) in far.iter().enumerate() {
        for (c, &b) in row.iter().enumerate() {
            m[2 * r][2 * c] = b;
        }
    }
    Ok(m)
}

/// The preconditioner's block `(I + L^T M L)^-1` of one entry into `b`, `m` its far
/// block ([`pair_block`], [`wall_factor`]).
pub(super) fn precondition<T: Real>(m: &Far12<T>, l: &[T], b: &mut [T]) -> Result<(), SdError> {
    let mp = |k: usize, c: usize| T::m3_get(m[k / 3][c / 3], k % 3, c % 3);
    // t = M L, then b = I + L^T t.
    let mut t = [T::ZERO; B];
    for k in 0..K {
        for c in 0..K {
            t[k * K + c] = (c..K).fold(T::ZERO, |s, q| s + mp(k, q) * l[q * K + c]);
        }
    }
    for k in 0..K {
        for c in 0..K {
            let v = (k..K).fold(T::ZERO, |s, q| s + l[q * K + k] * t[q * K + c]);
            b[k * K + c] = v + if k == c { T::ONE } else { T::ZERO };
        }
    }
    // Symmetric in exact arithmetic; its inverse, by the kernel's Cholesky.
    spd_inverse(b, K).map_err(SdError::NotPositiveDefinite)
}
