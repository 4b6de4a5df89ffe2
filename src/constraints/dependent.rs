//! Linearly dependent constraints: the rank tolerance of the dense factorisations, and
//! the self-stress that names an infeasible dependent set.
//!
//! Rows `k` of the constraint gradient `G` that lie in the span of the rows before
//! them (a sphere resting on the wall and on two others whose contacts already fix its
//! height; a square with both diagonals) make `A = c G M G^T` singular. The projection
//! still has unique positions, so the solves drop such rows (the basic solution:
//! their multipliers stay where they were) and keep the others' equations exactly. A
//! dependent row `k` comes with a *self-stress* `v`, `G^T v = 0`, `v_k = 1`: multipliers
//! whose forces cancel on every sphere. When the dependent equations cannot be met
//! (their right-hand side is not the one the others imply: the geometry is
//! infeasible), the constraints where `v` is not zero are the ones that fight.

use super::Metric;
use crate::bonds::Bond;
use crate::error::{INFEASIBLE_SHOWN, StepError};
use crate::real::Real;

/// Relative rank tolerance of a factorisation: a pivot at or below `sqrt(eps)` times
/// its row's diagonal (1.5e-8 in f64, 3.5e-4 in f32) is taken for a dependent row. An
/// exactly dependent row's pivot is the difference of sums of rounded terms of the
/// diagonal's size, a few hundred `eps` at a few hundred rows (measured: the pile of
/// `host/scenes/pile.toml` went below `-64 rows eps` at 280 rows); a row that
/// independent has a condition number of `1 / eps` against the others, and its
/// multiplier would carry no digit the step can use.
pub(crate) fn rank_floor<T: Real>() -> T {
    T::EPSILON.sqrt()
}

/// The [`StepError::Infeasible`] of a rank-deficient
/// [`cholesky_dense`](crate::linalg::cholesky_dense) factor of `bonds.len()` rows: the
/// self-stress of its first dependent row, listed by the forces `|v_l| |g_l|` it puts
/// on the constraints (`work`: `bonds.len()` scalars).
pub(super) fn infeasible<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    fac: &[T],
    work: &mut [T],
) -> StepError {
    self_stress(metric, null_vector(fac, bonds.len(), work))
}

/// The self-stress `v` (signed, `v_first = 1`) of the first dependent row of a
/// rank-deficient [`cholesky_dense`](crate::linalg::cholesky_dense) factor of `n`
/// rows, in `work` (`n` scalars).
pub(super) fn null_vector<'w, T: Real>(fac: &[T], n: usize, work: &'w mut [T]) -> &'w mut [T] {
    let first = (0..n).find(|&k| fac[k * n + k] == T::ZERO).unwrap_or(0);
    let v = &mut work[..n];
    v.fill(T::ZERO);
    // `L^T v = 0` above row `first`, by back substitution (a dependent row's column of
    // `L` is zero: its entry stays 0).
    v[first] = T::ONE;
    for j in (0..first).rev() {
        let mut s = fac[first * n + j];
        for i in j + 1..first {
            s += fac[i * n + j] * v[i];
        }
        v[j] = -s * fac[j * n + j];
    }
    v
}

/// The [`StepError::Infeasible`] of the self-stress `v` (multipliers with no net
/// force): the constraints where `|v_l| |g_l|` is not negligible, the largest listed.
pub(super) fn self_stress<T: Real>(metric: &Metric<'_, T>, v: &mut [T]) -> StepError {
    for (l, x) in v.iter_mut().enumerate() {
        *x = x.abs() * T::norm(metric.grad(l));
    }
    listed(v)
}

/// [`StepError::Infeasible`] listing the constraints of weight `v` (non-negative;
/// overwritten).
fn listed<T: Real>(v: &mut [T]) -> StepError {
    let biggest = v.iter().fold(T::ZERO, |m, &x| m.max(x));
    let cut = biggest * T::from_f64(1e-6);
    let count = v.iter().filter(|&&x| x > cut).count();
    // The largest forces, then in index order.
    let mut constraints = [usize::MAX; INFEASIBLE_SHOWN];
    let mut shown = 0;
    while shown < INFEASIBLE_SHOWN.min(count) {
        let mut best: Option<usize> = None;
        for (l, &x) in v.iter().enumerate() {
            if x > cut && best.is_none_or(|b| x > v[b]) {
                best = Some(l);
            }
        }
        let Some(b) = best else { break };
        constraints[shown] = b;
        v[b] = T::ZERO;
        shown += 1;
    }
    constraints[..shown].sort_unstable();
    StepError::Infeasible {
        constraints,
        shown,
        count,
    }
}

/// Whether the multipliers `v` are a self-stress to `share`: their net force on every
/// bead at most `share` times the largest force of one constraint `|v_l| |g_l|`. The
/// sweep's multipliers on an inconsistent dependent set grow along its self-stress by
/// the same amount each sweep while their net force stays bounded (`sweep.rs`).
pub(super) fn is_self_stress<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    beads: usize,
    v: &[T],
    share: T,
) -> bool {
    let largest =
        (0..bonds.len()).fold(T::ZERO, |m, l| m.max(v[l].abs() * T::norm(metric.grad(l))));
    if !(largest > T::ZERO) {
        return false;
    }
    (0..beads).all(|p| {
        let mut f = T::V3_ZERO;
        for (l, b) in bonds.iter().enumerate() {
            if b.i == p {
                f += metric.grad(l) * v[l];
            } else if b.j == p && !b.one_sphere() {
                f -= metric.grad(l) * v[l];
            }
        }
        T::norm(f) <= share * largest
    })
}
