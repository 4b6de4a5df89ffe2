//! Contacts and wall links as inequalities inside the solve (`docs/CONTACTS.md`):
//! `sigma_k(x) >= 0`, `lambda_k >= 0`, `lambda_k sigma_k(x) = 0` for the rows from
//! [`Problem::Positions::one_sided`] on; the bonds before them stay equalities.
//!
//! * **Newton and Krylov: a primal-dual active set inside the iteration** (the
//!   semismooth Newton method on `min(lambda_k A_kk, sigma_k) = 0`, Hintermüller, Ito
//!   and Kunisch 2002). Each iteration every inactive row that overlaps is taken in as
//!   an equality, and of the active rows whose `lambda_k A_kk - sigma_k <= 0` (they
//!   pull) the one that pulls hardest is released. A released row's multiplier goes to
//!   zero in the next linear solve (`delta_k = -lambda_k`, the active rows'
//!   right-hand side corrected by `A_:k lambda_k`); its row and column are otherwise
//!   decoupled (Newton: left out of the factor; Krylov: masked out of the conjugate
//!   gradients). `A_kk` is the chord matrix's diagonal (the scale that turns a
//!   multiplier into a residual). Where the active equalities contradict each other
//!   along a self-stress, [`let_go`] releases the contact that can open (Farkas).
//! * **Anti-cycling**: the active set of this method can cycle where `A` is not an
//!   M-matrix. Each row counts its switches; after [`SWITCHES`] it is *held* active
//!   (an equality for the rest of the solve, whatever its multiplier: the rule the
//!   active-set rounds apply between solves, `integrate/contacts.rs`). So the set
//!   changes at most `SWITCHES x rows` times, and between changes the iteration is
//!   the equality solve's (bounded by [`Solver::max_iterations`](super::Solver)).
//! * **Sweep: projected Gauss-Seidel**: each one-sided update is clipped so that the
//!   multiplier stays non-negative.
//!
//! Converged: bonds and active rows within the tolerance, inactive rows overlapping
//! by at most the tolerance, every active row that is not held pushing
//! (`lambda >= 0`).

use super::{Metric, Problem};
use crate::bonds::Bond;
use crate::real::Real;

/// Switches between active and inactive after which a row is held active.
pub(super) const SWITCHES: usize = 4;

/// A row's state word: bit 0 set when active, bit 1 when let go by [`let_go`] (kept
/// inactive by the next [`update`]), the switches counted above them.
const ACTIVE: usize = 1;
const LET_GO: usize = 2;
const SHIFT: u32 = 2;

/// Whether a row is held active (switched [`SWITCHES`] times).
#[inline]
fn held(state: usize) -> bool {
    state >> SHIFT >= SWITCHES
}

/// `state` switched to `on`.
#[inline]
fn switched(state: usize, on: bool) -> usize {
    ((state >> SHIFT) + 1) << SHIFT | on as usize
}

/// Index scratch per row (the state words) that the one-sided solve needs, where
/// contacts are compiled in.
pub(super) const STATE_PER_ROW: usize = if cfg!(feature = "contacts") { 1 } else { 0 };

/// Whether a state word is active.
#[inline]
pub(super) fn active(state: usize) -> bool {
    state & ACTIVE != 0
}

/// The chord matrix's diagonal `A_kk = c g_k . (D_k(i_k) - D_k(j_k))`.
pub(super) fn diagonal<T: Real>(metric: &Metric<'_, T>, bonds: &[Bond<T>], c: T, k: usize) -> T {
    T::dot(metric.grad(k), metric.relative(bonds, k, k)) * c
}

/// The start of a solve: every one-sided row inactive, no switch counted.
pub(super) fn reset(state: &mut [usize]) {
    state.fill(0);
}

/// One active-set update of the one-sided rows (`from..`): decides each row's state
/// from its multiplier and residual at `x`. A row that turns inactive keeps its
/// multiplier until the next linear solve takes it to zero (`delta_k = -lambda_k`,
/// the active rows' right-hand side corrected by `A_:k lambda_k`): applied alone, the
/// release of a large multiplier of nearly dependent rows is a large move that the
/// others would have to undo. Returns whether the set changed.
pub(super) fn update<T: Real>(
    problem: &Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    from: usize,
    x: &[T::V3],
    mult: &[T],
    state: &mut [usize],
) -> bool {
    let c = problem.chord_factor();
    // The active row that pulls hardest (`lambda_k A_kk - sigma_k` most negative) is
    // the only one released per update: releasing every puller at once made the set
    // oscillate on the pile (`docs/CONTACTS.md`).
    let mut worst: Option<(usize, T)> = None;
    for k in from..bonds.len() {
        let s = state[k];
        if !active(s) || held(s) || s & LET_GO != 0 {
            continue;
        }
        let (value, _, _) = problem.eval(&bonds[k], k, x);
        // A matrix-free metric that forms no blocks (the spectral Ewald sum, PSE) has
        // no diagonal to read (zero): the test is then the multiplier's sign alone (the
        // limit of a large scale). With the zero diagonal read as is, the test was
        // `sigma_k >= 0`, which a pushing row that the chord left open by its
        // residual (1e-8) meets: the suspension released and re-took loaded contacts
        // until they were held (13 contacts: 75 products instead of 5).
        let a = diagonal(metric, bonds, c, k);
        let slack = match a > T::ZERO && a.is_finite() {
            true => mult[k] * a - value,
            false => mult[k],
        };
        if !(slack > T::ZERO) && worst.is_none_or(|(_, w)| slack < w) {
            worst = Some((k, slack));
        }
    }
    let mut changed = false;
    for k in from..bonds.len() {
        let s = state[k];
        let on = match () {
            _ if s & LET_GO != 0 => false,
            _ if active(s) => worst.is_none_or(|(w, _)| w != k),
            _ => !(problem.eval(&bonds[k], k, x).0 >= T::ZERO),
        };
        state[k] = s & !LET_GO;
        // A row let go changed the set since the last update.
        changed |= s & LET_GO != 0;
        if on != active(s) {
            state[k] = switched(s, on);
            changed = true;
        }
    }
    changed
}

/// The largest normalised residual under complementarity: the equality rows' (bonds
/// and active rows) error, the inactive rows' overlap; and whether every active row
/// that is not held pushes (otherwise the set must change: not converged).
pub(super) fn residual<T: Real>(
    problem: &Problem<'_, T>,
    bonds: &[Bond<T>],
    from: usize,
    x: &[T::V3],
    mult: &[T],
    state: &[usize],
) -> (T, bool) {
    let mut worst = T::ZERO;
    let mut pushes = true;
    for (k, b) in bonds.iter().enumerate() {
        let (value, _, norm) = problem.eval(b, k, x);
        if k < from || active(state[k]) {
            if k >= from && mult[k] < T::ZERO && !held(state[k]) {
                pushes = false;
            }
            worst = worst.max_sticky(norm);
        } else {
            pushes &= mult[k] == T::ZERO;
            if !(value >= T::ZERO) {
                worst = worst.max_sticky(norm);
            }
        }
    }
    (worst, pushes)
}

/// Where the active rows' equalities contradict each other along the self-stress `v`
/// (`G^T v = 0`, so `v . sigma` is the same after any move: the equalities need it
/// zero) and some active one-sided row `k` not held has `v_k (v . sigma) > 0`, that
/// row can open (`sigma_k = (v . sigma) / v_k > 0`) while the others close: it is let
/// go (inactive through the next update, counted as a switch; its multiplier goes in
/// the next linear solve),
/// the one of largest force `|v_k| |g_k|`. `false` where there is none: no first-order
/// move meets the constraints (Farkas), the geometry is infeasible.
#[allow(clippy::too_many_arguments)]
pub(super) fn let_go<T: Real>(
    problem: &Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    from: usize,
    v: &[T],
    x: &[T::V3],
    state: &mut [usize],
) -> bool {
    let s = (0..bonds.len()).fold(T::ZERO, |s, k| s + v[k] * problem.eval(&bonds[k], k, x).0);
    let mut best: Option<(usize, T)> = None;
    for k in from..bonds.len() {
        let force = v[k].abs() * T::norm(metric.grad(k));
        let opens = v[k] * s > T::ZERO && active(state[k]) && !held(state[k]);
        if opens && best.is_none_or(|(_, f)| force > f) {
            best = Some((k, force));
        }
    }
    let Some((k, _)) = best else {
        return false;
    };
    state[k] = switched(state[k], false) | LET_GO;
    true
}

/// The projected Gauss-Seidel clip of a one-sided row's update: `lambda + delta`
/// kept non-negative.
#[inline]
pub(super) fn clip<T: Real>(lambda: T, delta: T) -> T {
    (lambda + delta).max(T::ZERO) - lambda
}

/// Whether a row's residual needs no update under complementarity (the sweep's test):
/// a one-sided row that does not push and does not overlap is satisfied whatever its
/// gap.
#[inline]
pub(super) fn slack<T: Real>(one_sided: bool, lambda: T, value: T) -> bool {
    one_sided && lambda <= T::ZERO && value >= T::ZERO
}
