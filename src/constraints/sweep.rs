//! The SHAKE (positions) / RATTLE (velocities) sweep of the paper: one constraint at a
//! time, in bond order. One-sided rows (contacts, wall links) are swept by projected
//! Gauss-Seidel: each update clipped so that the multiplier stays non-negative
//! (`onesided.rs`).

use super::{Metric, Problem, SolveStats, Solver, dependent, onesided};
use crate::bonds::Bond;
use crate::error::StepError;
use crate::real::Real;

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
    for it in 0..=solver.max_iterations {
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
                return Err(StepError::Degenerate { bond: k });
            }
            let mut delta = -value / den;
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
        if !moved && residual <= solver.tolerance {
            return Ok(SolveStats {
                iterations: it,
                residual,
            });
        }
        if it == solver.max_iterations {
            // With one-sided rows: multipliers grown into a self-stress (net force on
            // every bead below 5 % of the largest constraint force) name an infeasible
            // dependent set (`docs/CONTACTS.md`).
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
