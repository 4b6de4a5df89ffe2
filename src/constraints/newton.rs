//! Newton on the dense `bonds x bonds` Jacobian, solved by LU: quadratic convergence,
//! `O(B^3)` per factorisation. The choice for small bond counts.

use super::{Metric, Problem, Scratch, SolveStats, Solver, active, dependent, onesided, worst};
use crate::bonds::Bond;
use crate::error::StepError;
use crate::linalg;
use crate::real::Real;

/// Newton iterations on the dense `bonds x bonds` Jacobian.
///
/// * Positions start on the symmetric chord Jacobian `J_kl = c g_k . (D_l(i_k) -
///   D_l(j_k))` along the start-of-step bond vectors `g` on both sides (`c G D G^T`,
///   positive definite for every metric here): its lower triangle, factorised by
///   Cholesky, half the entries and half the factorisation of the Jacobian at the
///   iterate, no pivoting. The chord converges linearly, by about the bonds' turn within
///   the step per iteration; while the residual falls at least tenfold per iteration it
///   is kept.
/// * Otherwise (velocities from the start, positions once the chord slows: a move of
///   many bond lengths) the Jacobian at the iterate `J_kl = dir_k . (D_l(i_k) -
///   D_l(j_k))`, solved by LU, refreshed whenever the residual falls less than tenfold.
///   Velocities are linear: one step.
/// * Dependent constraints (`docs/CONTACTS.md`): both factorisations take the rank
///   tolerance `sqrt(eps)` (`docs/CONTACTS.md`); a dependent row gets a zero multiplier update
///   (the basic solution) and positions move as the independent rows demand. A
///   rank-deficient iteration on the Jacobian at the iterate that fails to halve the
///   residual means the dependent rows ask what the others forbid:
///   [`StepError::Infeasible`], naming the dependent set (on the chord such a stall is
///   first taken for the chord's own slowness on a large move, and the Jacobian at the
///   iterate takes over as without dependent rows).
/// * One-sided rows (contacts, wall links: [`Problem::Positions`]) are inequalities:
///   each iteration decides which of them are equalities (`onesided.rs`, the
///   primal-dual active set); the others are left out of the chord's factor, which
///   is formed once per solve and then follows the set row by row (`active.rs`:
///   `O(rows^2)` a change instead of `O(rows^3)`). Without one-sided rows nothing of
///   this runs.
// Out of line on 32-bit Arm: inlined into a firmware's one caller, it ran more
// instructions a step (register pressure in the step's one large function) for less flash.
#[cfg_attr(target_arch = "arm", inline(never))]
pub fn newton<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    let nb = bonds.len();
    // One-sided rows from `from` on (`usize::MAX`: none, the equality solve as it
    // always was); their states after the pivots.
    let from = problem.one_sided(nb);
    let floor = dependent::rank_floor::<T>();
    // One-sided rows: the chord's factor of the active rows follows the set row by row
    // (`active.rs`); `piv` holds its rows by position, `held` of them (none before the
    // first build, or the last solve's brought to this one's rows where the caller
    // keeps it: `Carry`).
    let rows = active::Rows {
        metric,
        bonds,
        c: problem.chord_factor(),
        from,
        floor,
    };
    let carry = core::mem::take(&mut scratch.carry);
    let mut held = match carry.held.filter(|_| carry.keep && from < nb) {
        Some(h) => Some(rows.carried(h, carry.released, scratch.piv, scratch.jac)),
        None => None,
    };
    // A carried factor is brought to the first iteration's set whatever it is.
    let mut stale = held.is_some();
    #[cfg(feature = "contacts")]
    let (piv, state) = scratch.piv.split_at_mut(nb);
    #[cfg(not(feature = "contacts"))]
    let (piv, state): (_, &mut [usize]) = (&mut scratch.piv[..nb], &mut []);
    let (jac, rhs) = (&mut scratch.jac[..nb * nb], &mut scratch.rhs[..nb]);
    let one_sided = from < nb;
    if one_sided {
        onesided::reset(&mut state[..nb]);
    }
    // Positions start on the chord; every solve falls back to the Jacobian at the
    // iterate, refreshed whenever the residual falls less than tenfold.
    let mut chord = matches!(problem, Problem::Positions { .. });
    let mut previous: Option<T> = None;
    // Dependent rows found by the last factorisation.
    let mut deficient = 0;
    // `rhs` holds the update applied by the last iteration (none before the first).
    let mut applied = false;
    // `jac` holds the chord's factor of the current active set: the chord matrix does
    // not depend on the iterate, so a refresh that the set did not change would
    // recompute it bit for bit and keeps it instead.
    let mut fresh = false;
    let mut factorizations = 0;
    // Halvings of the update `rhs` taken back so far ([`backtrack`]).
    let mut halvings = 0;
    // The factor `apply` scales `rhs` by before adding it: 1 after a solve, -1/2 and
    // then 1/2 for the halvings (exact: powers of two).
    let mut scale = T::ONE;
    let mut next = 0;
    loop {
        let (mut changed, mut pushes) = (false, true);
        // The last iteration's update is applied at the start of the next, where its
        // residual is measured and, if it diverged, a part taken back and measured again
        // by another pass: one call site each of the update and of the residual, so
        // that firmware keeps them inline for its one metric (flash).
        if applied {
            apply(metric, bonds, (from, state), x, mult, rhs, scale);
        }
        // The residual at the iterate on the equations the last update solved (the
        // active set it was built for; one-sided rows measure it again below, after the
        // active set's update).
        let measured = match (one_sided, applied) {
            (false, _) => worst(&problem, bonds, x),
            (true, true) => onesided::residual(&problem, bonds, from, x, mult, state).0,
            (true, false) => T::ZERO,
        };
        let damped = halvings > 0;
        if applied {
            match backtrack(measured, halvings, previous, solver.tolerance) {
                Some(true) => {}
                Some(false) => {
                    // Half of what stands applied taken back by the next pass: `-rhs / 2`
                    // after the update, then half of the last halving (`rhs` holds what
                    // was last applied, the negative of what stands).
                    // (Scaled by `apply`, in the loop that adds it: one loop, not two.)
                    scale = match halvings {
                        0 => -T::HALF,
                        _ => T::HALF,
                    };
                    halvings += 1;
                    continue;
                }
                None => return Err(problem.no_convergence(next, measured)),
            }
        }
        (applied, halvings) = (false, 0);
        let it = next;
        next += 1;
        let residual = match one_sided {
            false => measured,
            true => {
                changed = onesided::update(&problem, metric, bonds, from, x, mult, state);
                fresh &= !changed;
                let (r, p) = onesided::residual(&problem, bonds, from, x, mult, state);
                pushes = p;
                r
            }
        };
        if !residual.is_finite() {
            return Err(problem.no_convergence(it, residual));
        }
        if residual <= solver.tolerance && pushes {
            // The factor (of the rows in `piv`, whatever the set now) for the next
            // solve on this chord matrix.
            scratch.carry.held = held.map(|m| (m, nb));
            return Ok(SolveStats {
                iterations: it,
                residual,
                factorizations,
            });
        }
        if it == solver.max_iterations {
            return Err(problem.no_convergence(it, residual));
        }
        let fast = previous.is_some_and(|p| residual <= p * T::from_f64(0.1));
        // One-sided rows never leave the chord: their stall is judged on it.
        // A damped step says nothing of the dependent rows (it stopped short).
        if deficient > 0
            && !damped
            && (!chord || one_sided)
            && !changed
            && previous.is_some_and(|p| residual > p * T::HALF)
        {
            if let Some(m) = held.filter(|_| one_sided) {
                // The factor follows the set (it is that of the current one). An active
                // contact that the contradiction asks to open is let go (`onesided.rs`).
                let v = linalg::ordered_null(jac, nb, m, piv, rhs);
                if onesided::let_go(&problem, metric, bonds, from, v, x, state) {
                    previous = None;
                    continue;
                }
                return Err(dependent::self_stress(metric, v));
            }
            // Named by the chord's self-stress (an LU factor shows only which columns
            // it skipped): refactorised here, on the way out.
            let c = problem.chord_factor();
            for k in 0..nb {
                let row = &mut jac[k * nb..k * nb + k + 1];
                metric.jacobian_row(bonds, k, metric.grad(k) * c, 0, row);
            }
            let _ = linalg::cholesky_dense(jac, nb, floor);
            return Err(dependent::infeasible(metric, bonds, jac, rhs));
        }
        // `rebuild`: the matrix is formed and factorised again (a refresh on the chord
        // whose set is unchanged keeps the factor it would recompute).
        let refresh = previous.is_none() || !fast || changed;
        if refresh && previous.is_some() && !changed && !one_sided {
            chord = false;
        }
        let rebuild = refresh && !(chord && fresh) && !one_sided;
        previous = Some(residual);
        for (k, b) in bonds.iter().enumerate() {
            // Without the magnitude (not read here) off 32-bit Arm; the firmware keeps
            // the one copy of `eval` it has (flash).
            let (value, dir, _) = match cfg!(target_arch = "arm") {
                true => problem.eval(b, k, x),
                false => problem.eval_with::<false>(b, k, x),
            };
            rhs[k] = -value;
            if rebuild {
                // The chord's lower triangle, or the whole row at the iterate (one call
                // site, so that firmware inlines it for its one metric).
                let (dir, len) = match chord {
                    true => (metric.grad(k) * problem.chord_factor(), k + 1),
                    false => (dir, nb),
                };
                metric.jacobian_row(bonds, k, dir, 0, &mut jac[k * nb..k * nb + len]);
            }
        }
        let fail = |error| StepError::Linalg {
            stage: problem.stage(),
            error,
        };
        if one_sided {
            // A carried factor that would cost more to bring to the set than to build
            // is built again.
            if stale && held.is_some_and(|m| rows.rebuild_cheaper(state, piv, m)) {
                held = None;
            }
            let m = match held {
                None => {
                    factorizations += 1;
                    let (m, d) = rows.build(state, piv, jac).map_err(fail)?;
                    deficient = d;
                    m
                }
                Some(mut m) => {
                    if changed || stale {
                        deficient = rows.sync(state, piv, &mut m, jac).map_err(fail)?;
                    }
                    m
                }
            };
            stale = false;
            held = Some(m);
            rows.solve(state, (piv, m), jac, mult, rhs);
            applied = true;
            continue;
        }
        if rebuild {
            factorizations += 1;
        }
        if chord {
            if rebuild {
                deficient = linalg::cholesky_dense(jac, nb, floor).map_err(fail)?;
                fresh = true;
            }
            linalg::cholesky_dense_solve(jac, nb, rhs);
        } else {
            fresh = false;
            if rebuild {
                deficient =
                    linalg::lu_ranked(jac, nb, piv, floor * max_diagonal(jac, nb)).map_err(fail)?;
            }
            linalg::lu_solve(jac, nb, piv, rhs);
        }
        // `rhs` is applied at the next iteration's start (the last one returns above).
        (applied, scale) = (true, T::ONE);
    }
}

/// Halvings of a Newton update that made the residual diverge ([`backtrack`]).
const HALVINGS: u32 = 10;

/// Scales the update `rhs` by `scale` (1 after a solve: exact, the update as solved; a
/// halving's power of two) and adds it to `mult` (`mult` holds a multiplier a row of
/// `rhs`), and its moves to `x`. After a solve's update (not a halving's) the released
/// one-sided rows' multipliers are set to exactly zero (the solve gives `-lambda_k` to
/// rounding).
#[inline(always)]
fn apply<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    (from, state): (usize, &[usize]),
    x: &mut [T::V3],
    mult: &mut [T],
    rhs: &mut [T],
    scale: T,
) {
    for (m, r) in mult.iter_mut().zip(rhs.iter_mut()) {
        *r *= scale;
        *m += *r;
    }
    metric.apply_each(bonds, rhs, x);
    if scale == T::ONE {
        for k in from..bonds.len() {
            if !onesided::active(state[k]) {
                mult[k] = T::ZERO;
            }
        }
    }
}

/// The safeguard of a diverging update, a backtracking line search on the residual
/// (the largest normalised one, as the tolerance is stated), judged after the update
/// and each halving of it: `Some(true)` where the residual `r` stands, `Some(false)`
/// where half of what stands applied is to be taken back and `r` measured again, `None`
/// where [`HALVINGS`] halvings found no decrease (the step is too long for the
/// linearisation: a shorter one can pass).
///
/// Only a residual that is no longer finite after the update counts as divergence (far
/// outside the region where the linearisation holds: a jammed pile's step overshoots
/// by many sphere radii and the next one diverges): the solve could never come back
/// from it, so damping there changes no run that converged undamped (a finite growth,
/// even a large one, is left to the iteration: the chord and the active set
/// legitimately raise the residual for an iteration or two). The halvings stop once
/// the residual is below `previous` or within `tolerance`. A line search rather than a
/// trust region: the direction is already the solver's (chord or Newton, a zero update
/// on dependent rows) and only its length is in doubt; the updates are linear in
/// `rhs`, so the halvings retrace one line at one residual each.
fn backtrack<T: Real>(r: T, halvings: u32, previous: Option<T>, tolerance: T) -> Option<bool> {
    if halvings == 0 {
        return Some(r.is_finite());
    }
    if previous.is_some_and(|p| r < p) || r <= tolerance {
        return Some(true);
    }
    (halvings < HALVINGS).then_some(false)
}

/// Largest `|A_kk|`: the scale of the LU rank tolerance (the rows of one problem share
/// their units).
fn max_diagonal<T: Real>(a: &[T], n: usize) -> T {
    (0..n).fold(T::ZERO, |m, k| m.max(a[k * n + k].abs()))
}
