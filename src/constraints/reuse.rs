//! The dense Newton solve's chord system after a change of the active set, solved by
//! conjugate gradients preconditioned with the chord's factor of an earlier set instead
//! of a new factorisation (`docs/CONTACTS.md`, "Large piles").
//!
//! The chord matrix `A = c G D` does not change within a solve; an active-set change
//! only decouples other rows. The factor of the last set differs from the new set's
//! matrix in the rows that switched (a low-rank change), so conjugate gradients
//! converge in about as many iterations as rows switched, each costing one product
//! with the metric (`O(rows x beads)`) and two triangular solves (`O(rows^2)`),
//! against `O(rows^3)` for a factorisation. Where they do not converge within
//! [`cap`] iterations (many rows switched, or a newly active row dependent on the
//! others) the caller factorises as before, so the result is a converged chord step
//! either way.

use super::{Metric, onesided};
use crate::bonds::{Bond, component};
use crate::linalg;
use crate::real::Real;

/// Constraint rows from which a solve tries the factor it has before refactorising on
/// an active-set change. Below, a factorisation costs little and the solve keeps the
/// bits it always had (the small piles' and chains' golden digests).
pub const ROWS_MIN: usize = 128;

/// Scalars of scratch per row: a copy of the right-hand side and the four vectors of
/// conjugate gradients.
pub const SCALARS_PER_ROW: usize = 5;

/// Iterations allowed before the caller factorises instead: a sixteenth of the rows, about
/// where their products and solves cost what a factorisation does.
pub fn cap(rows: usize) -> usize {
    (rows / 16).max(4)
}

/// Conjugate gradients on the chord system of the set `state`, preconditioned by `fac`.
///
/// `rhs` holds `-sigma` (every row); on success it holds the update (the inactive rows'
/// `-lambda_k`, releasing them) and `true` is returned; otherwise `rhs` is left as it
/// came and `false` returned. `c`: the chord factor; `work`: [`SCALARS_PER_ROW`] x
/// rows; `beads`: one vector a bead.
#[allow(clippy::too_many_arguments)]
pub(super) fn solve<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    c: T,
    (from, state): (usize, &[usize]),
    mult: &[T],
    fac: &[T],
    rhs: &mut [T],
    (work, beads): (&mut [T], &mut [T::V3]),
) -> bool {
    let nb = bonds.len();
    let on = |k: usize| k < from || onesided::active(state[k]);
    let (b, rest) = work.split_at_mut(nb);
    let (r, rest) = rest.split_at_mut(nb);
    let (z, rest) = rest.split_at_mut(nb);
    let (p, q) = rest.split_at_mut(nb);
    let q = &mut q[..nb];
    b.copy_from_slice(&rhs[..nb]);
    // The released rows' fixed update `-lambda_k`, and its push on the active rows.
    let mut release = false;
    for k in 0..nb {
        p[k] = match on(k) {
            true => T::ZERO,
            false => -mult[k],
        };
        release |= p[k] != T::ZERO;
    }
    if release {
        product(metric, bonds, c, p, q, beads);
    }
    for k in 0..nb {
        r[k] = match (on(k), release) {
            (false, _) => T::ZERO,
            (true, true) => b[k] - q[k],
            (true, false) => b[k],
        };
        rhs[k] = T::ZERO;
    }
    let norm = |v: &[T]| v.iter().fold(T::ZERO, |s, &x| s + x * x).sqrt();
    let target = norm(r) * T::from_f64(1e-8).max(T::EPSILON * T::from_f64(1e3));
    DBG[0].fetch_add(1, core::sync::atomic::Ordering::Relaxed);
    let converged = cg(metric, bonds, c, &on, fac, (rhs, r, z, p, q), beads, target);
    if !converged {
        rhs[..nb].copy_from_slice(b);
        return false;
    }
    for k in 0..nb {
        if !on(k) {
            rhs[k] = -mult[k];
        }
    }
    true
}

/// Preconditioned conjugate gradients from `x = 0` on the active rows until `|r| <=
/// target`, within [`cap`] iterations; `false` where they do not get there (or meet a
/// direction without curvature: a row the factor does not hold).
#[allow(clippy::too_many_arguments)]
fn cg<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    c: T,
    on: &dyn Fn(usize) -> bool,
    fac: &[T],
    (x, r, z, p, q): (&mut [T], &mut [T], &mut [T], &mut [T], &mut [T]),
    beads: &mut [T::V3],
    target: T,
) -> bool {
    let nb = bonds.len();
    let dot = |a: &[T], b: &[T]| a.iter().zip(b).fold(T::ZERO, |s, (&x, &y)| s + x * y);
    let norm = |v: &[T]| dot(v, v).sqrt();
    if !target.is_finite() {
        return false;
    }
    if norm(r) <= target {
        return true;
    }
    let precondition = |r: &[T], z: &mut [T]| {
        z.copy_from_slice(r);
        linalg::cholesky_dense_solve(fac, nb, z);
        for (k, v) in z.iter_mut().enumerate() {
            if !on(k) {
                *v = T::ZERO;
            }
        }
    };
    precondition(r, z);
    p.copy_from_slice(z);
    let mut rz = dot(r, z);
    for _ in 0..cap(nb) {
        DBG[2].fetch_add(1, core::sync::atomic::Ordering::Relaxed);
        product(metric, bonds, c, p, q, beads);
        for (k, v) in q.iter_mut().enumerate() {
            if !on(k) {
                *v = T::ZERO;
            }
        }
        let pq = dot(p, q);
        if !(pq > T::ZERO && rz > T::ZERO) {
            return false;
        }
        let alpha = rz / pq;
        for k in 0..nb {
            x[k] += alpha * p[k];
            r[k] -= alpha * q[k];
        }
        if norm(r) <= target {
            DBG[1].fetch_add(1, core::sync::atomic::Ordering::Relaxed);
            return true;
        }
        precondition(r, z);
        let next = dot(r, z);
        let beta = next / rz;
        rz = next;
        for (pk, &zk) in p.iter_mut().zip(z.iter()) {
            *pk = zk + beta * *pk;
        }
    }
    false
}

/// `q = A v`, `A_kl = c g_k . (D_l(i_k) - D_l(j_k))` (the chord matrix the dense solve
/// forms row by row): the moves `sum_l v_l D_l` of the beads, then each row's relative
/// change along its `c g_k`.
fn product<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    c: T,
    v: &[T],
    q: &mut [T],
    beads: &mut [T::V3],
) {
    beads.fill(T::V3_ZERO);
    metric.apply_each(bonds, v, beads);
    for (k, (b, out)) in bonds.iter().zip(q.iter_mut()).enumerate() {
        let rel = match b.one_sphere() {
            true => component::<T>(beads[b.i], b.axis()),
            false => beads[b.i] - beads[b.j],
        };
        *out = T::dot(metric.grad(k) * c, rel);
    }
}

/// TEMP
pub static DBG: [core::sync::atomic::AtomicU32; 3] =
    [const { core::sync::atomic::AtomicU32::new(0) }; 3];
