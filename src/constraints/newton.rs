//! Newton on the dense `bonds x bonds` Jacobian, solved by LU: quadratic convergence,
//! `O(B^3)` per factorisation. The choice for small bond counts.

use super::{Metric, Problem, Scratch, SolveStats, Solver, worst};
use crate::bonds::Bond;
use crate::error::StepError;
use crate::linalg;
use crate::real::Real;

/// Newton iterations on the dense Jacobian `J_kl = dir_k . (D_l(i_k) - D_l(j_k))`,
/// solved by LU. The factorisation is reused while the residual falls at least
/// tenfold per iteration (a chord / quasi-Newton step: the Jacobian barely changes
/// within one time step) and refreshed otherwise. Velocities are linear: one step.
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
    let (jac, rhs, piv) = (
        &mut scratch.jac[..nb * nb],
        &mut scratch.rhs[..nb],
        &mut scratch.piv[..nb],
    );
    let mut previous: Option<T> = None;
    for it in 0..=solver.max_iterations {
        let residual = worst(&problem, bonds, x);
        if !residual.is_finite() {
            return Err(problem.no_convergence(it, residual));
        }
        if residual <= solver.tolerance {
            return Ok(SolveStats {
                iterations: it,
                residual,
            });
        }
        if it == solver.max_iterations {
            return Err(problem.no_convergence(it, residual));
        }
        let refresh = match previous {
            None => true,
            Some(p) => !(residual <= p * T::from_f64(0.1)),
        };
        previous = Some(residual);
        for (k, b) in bonds.iter().enumerate() {
            let (value, dir, _) = problem.eval(b, k, x);
            rhs[k] = -value;
            if refresh {
                metric.jacobian_row(bonds, k, dir, 0, &mut jac[k * nb..k * nb + nb]);
            }
        }
        if refresh {
            linalg::lu(jac, nb, piv).map_err(|error| StepError::Linalg {
                stage: problem.stage(),
                error,
            })?;
        }
        linalg::lu_solve(jac, nb, piv, rhs);
        for l in 0..nb {
            mult[l] += rhs[l];
            metric.apply_one(bonds, l, rhs[l], x);
        }
    }
    // The loop returns on its last pass (it == max_iterations).
    Err(StepError::NoConvergence {
        stage: problem.stage(),
        iterations: solver.max_iterations,
        residual: f64::NAN,
    })
}
