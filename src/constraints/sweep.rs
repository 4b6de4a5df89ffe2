//! The SHAKE (positions) / RATTLE (velocities) sweep of the paper: one constraint at a
//! time, in bond order. One-sided rows (contacts, wall links) are swept by projected
//! Gauss-Seidel: each update clipped so that the multiplier stays non-negative
//! (`onesided.rs`).
//!
//! **Over-relaxation with one-sided rows** (`docs/CONTACTS.md`): where the solve holds
//! contacts or wall links, the sweeps from [`PLAIN_SWEEPS`] on scale every update by
//! the fixed factor [`OVER_RELAXATION`] before the clip (projected SOR). Plain
//! Gauss-Seidel's rate on a jammed pile (about 280 dependent rows) is so close to one
//! that 20 000 sweeps did not reach the tolerance; with 1.8 the pile runs to rest with at
//! most 1 772 sweeps in a solve. The first sweeps stay plain: a few contacts converge
//! in a few plain sweeps, and over-relaxed updates overshoot the large early moves
//! (1.9 and 1.95 from the first sweep stalled or diverged in the pile's second step).
//! Bonds alone are never over-relaxed (the paper's sweep, the same bits).
//!
//! Why it cannot cycle: on the linearised problem the sweep minimises the convex
//! quadratic `q(lambda) = lambda A lambda / 2 - lambda r` (`A = c G M G^T`, positive
//! semi-definite) one row at a time over `lambda_k >= 0` (one-sided rows). A row's
//! update `omega delta` with `0 < omega < 2`, clipped at zero, lands on the segment
//! between the old multiplier and its reflection through the row's minimiser, so `q`
//! does not increase (it falls by `omega (2 - omega) A_kk delta^2 / 2` unclipped):
//! projected SOR for a symmetric semi-definite complementarity problem (Cryer 1971,
//! Mangasarian 1977). The sweeps stay capped by [`Solver::max_iterations`].

use super::{Metric, Problem, SolveStats, Solver, dependent, onesided};
use crate::bonds::Bond;
use crate::error::{Row, StepError};
use crate::real::Real;

/// The over-relaxation factor of the sweeps with one-sided rows (module docs): chosen
/// on the 100-sphere pile among 1.5, 1.7, 1.8, 1.85 and 1.9 (fewest sweeps in all and
/// at rest; `docs/CONTACTS.md`).
pub const OVER_RELAXATION: f64 = 1.8;

/// Plain Gauss-Seidel sweeps before the over-relaxation starts (module docs).
pub const PLAIN_SWEEPS: u32 = 16;

/// The SHAKE (positions) / RATTLE (velocities) sweep: one constraint at a time, each
/// update the exact linearisation of that constraint alone (paper eqs. 3 and 4).
pub fn sweep<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
) -> Result<SolveStats<T>, StepError> {
    let from = problem.one_sided(bonds.len());
    let over = T::from_f64(OVER_RELAXATION);
    // Without one-sided rows `from` is `usize::MAX`: never over-relaxed. Turned off for
    // good where a relaxed sweep ends with a larger residual than the first sweep met
    // (`limit`, the violation of the move the solve started from): the safeguard
    // against overshoot on nonlinear or inconsistent rows (the squeezed sphere of
    // `tests/kernel/jam.rs`, where the relaxed sweeps stretched the bond by 68 %).
    let mut relaxing = from < bonds.len();
    let mut limit = T::ZERO;
    for it in 0..=solver.max_iterations {
        let relax = relaxing && it >= PLAIN_SWEEPS;
        let mut residual = T::ZERO;
        let mut moved = false;
        for (k, b) in bonds.iter().enumerate() {
            let (value, dir, r) = problem.eval(b, k, x);
            if k >= from && onesided::slack(true, mult[k], value) {
                continue;
            }
            residual = residual.max_sticky(r);
            if r <= solver.tolerance || it == solver.max_iterations {
                continue;
            }
            let w = metric.relative(bonds, k, k);
            let den = T::dot(dir, w);
            // A vanishing denominator means the bond turned ~90 degrees in one step.
            let floor = T::from_f64(1e-12) * T::norm(dir) * T::norm(w);
            if !(den.abs() > floor) {
                return Err(StepError::Degenerate {
                    bond: k,
                    row: Row::of(bonds, k, from),
                });
            }
            let mut delta = -value / den;
            if relax {
                delta *= over;
            }
            if k >= from {
                delta = onesided::clip(mult[k], delta);
            }
            mult[k] += delta;
            metric.apply_one(bonds, k, delta, x);
            moved = true;
        }
        if !residual.is_finite() {
            return Err(problem.no_convergence(it, residual));
        }
        if it == 0 {
            limit = residual;
        } else if relax && !(residual <= limit) {
            relaxing = false;
        }
        if !moved && residual <= solver.tolerance {
            return Ok(SolveStats {
                iterations: it,
                residual,
                factorizations: 0,
            });
        }
        if it == solver.max_iterations {
            // With one-sided rows: multipliers grown into a self-stress (net force on
            // every bead below 5 % of the largest constraint force) name an infeasible
            // dependent set (`docs/CONTACTS.md`, "The sweep's infeasibility
            // criterion": why 5 %, and where it can misname a slow solve).
            let share = T::from_f64(0.05);
            if from < bonds.len() && dependent::is_self_stress(metric, bonds, x.len(), mult, share)
            {
                return Err(dependent::self_stress(metric, mult));
            }
            return Err(problem.no_convergence(it, residual));
        }
    }
    // The loop returns on its last pass; this is the empty-range case (cap 0 handled above).
    Ok(SolveStats::default())
}
