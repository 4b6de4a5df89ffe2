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

/// Relative rank tolerance of a factorisation of `rows` rows: a pivot at or below
/// `64 rows eps` times its row's diagonal is rounding, not information (the pivot of
/// an exactly dependent row is the difference of two sums of `rows` rounded terms of
/// the diagonal's size). 1.4e-12 at 100 rows in f64, 7.6e-4 in f32.
pub(crate) fn rank_floor<T: Real>(rows: usize) -> T {
    T::EPSILON * T::from_f64(64.0 * rows.max(1) as f64)
}

/// The [`StepError::Infeasible`] of a rank-deficient factor of `bonds.len()` rows:
/// from a [`cholesky_dense`](crate::linalg::cholesky_dense) factor (`chord`), the
/// self-stress of its first dependent row, listed by the forces `|v_l| |g_l|` it puts
/// on the constraints (`work`: `bonds.len()` scalars); from an LU factor, its
/// dependent columns.
pub(super) fn infeasible<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    fac: &[T],
    work: &mut [T],
    chord: bool,
) -> StepError {
    let n = bonds.len();
    let dependent = |k: usize| fac[k * n + k] == T::ZERO;
    let first = (0..n).find(|&k| dependent(k)).unwrap_or(0);
    let v = &mut work[..n];
    v.fill(T::ZERO);
    if chord {
        // `L^T v = 0` above row `first`, by back substitution (a dependent row's
        // column of `L` is zero: its entry stays 0).
        v[first] = T::ONE;
        for j in (0..first).rev() {
            let mut s = fac[first * n + j];
            for i in j + 1..first {
                s += fac[i * n + j] * v[i];
            }
            v[j] = -s * fac[j * n + j];
        }
        return self_stress(metric, v);
    } else {
        for (k, x) in v.iter_mut().enumerate() {
            *x = if dependent(k) { T::ONE } else { T::ZERO };
        }
    }
    listed(v)
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
