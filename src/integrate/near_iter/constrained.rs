//! `Overdamped` with constraints (bonds, pins) on the iterative near field: the
//! constraint move goes along the Stokesian dynamics mobility, `r' = r* + dt M_SD,tt
//! G^T lambda`, as the dense near step's does, with `M_SD` known only through products.
//!
//! The close pairs are found and factored once, at the start; every mobility the step
//! needs is then one product of that factored near field ([`Sd`]): the unconstrained
//! velocity, each product of the Krylov constraint solve (its metric's product,
//! [`crate::constraints::Products`]), and with [`Params::rotation`] the spins of the
//! total force at the end. The solve's entries (its band preconditioner, its curvature
//! bound) are read from the far field's translational blocks, the first `n` block rows
//! of the packed grand mobility assembled for the products: an approximation that
//! changes how fast the solve converges, never where it ends, since every move it makes
//! is a product of `M_SD`.
//!
//! Only the Krylov solver runs here: the sweep and Newton read `D_l(p)` for every bond
//! at every iteration (a table of `n x B` entries, `B` products of `M_SD` to form), and
//! are refused by `near::check`, typed, as are `Overdamped2`, contacts, the wall and
//! noise. A product that does not converge ends the step with
//! [`StepError::NoConvergence`] at [`Stage::Mobility`](crate::Stage::Mobility), the
//! caller's state unchanged.

use super::solve::{self, At};
use super::{Counts, Store, spins};
use crate::bonds::Bond;
use crate::constraints::{Metric, Problem, Products, krylov_with};
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::integrate::{
    Start, StepReport, add_constraint_forces, add_flow, bond_vectors, cell, check_resolved, report,
    step_velocity,
};
use crate::linalg::{Mob, tri};
use crate::params::Params;
use crate::real::Real;
use crate::workspace::Views;

/// The constraint solve's products: `M_SD` at the start ([`solve::at`]), counted.
struct Sd<'a, 's, T: Real> {
    at: &'a mut At<'s, T>,
    p: &'a Params<T>,
    counts: Counts,
}

impl<T: Real> Products<T> for Sd<'_, '_, T> {
    /// `out = dt M_SD,tt G^T c`: the metric's forces, one product.
    fn apply(
        &mut self,
        metric: &Metric<'_, T>,
        bonds: &[Bond<T>],
        c: &[T],
        out: &mut [T::V3],
        _: &mut [T::V3],
    ) -> Result<(), StepError> {
        let fill = |f: &mut [T::V3]| match metric.forces(bonds, c, f) {
            true => Ok(()),
            false => Err(StepError::Unsupported(
                "the iterative near field's constraint products along a metric without forces",
            )),
        };
        self.at
            .velocities_of(self.p, fill, out, None, &mut self.counts)
    }
}

/// `Overdamped` with bonds (and pins) on the iterative near field: `r* = r + dt U(r)`,
/// `U = U_inf + M_SD,tt F`, projected onto the constraints along `dt M_SD,tt G^T`
/// by the Krylov solve; the spins `Omega_inf + M_SD,rt (F + G^T lambda)`.
pub(in crate::integrate) fn overdamped<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        force,
        work_a: u,
        new_pos,
        new_vel,
        new_omega,
        grad,
        lambda,
        mut scratch,
        near,
        near_iter,
        ..
    } = v;
    let mut store = Store::new(near, near_iter);
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    // The far field at the start, and the close pairs factored once.
    solve::at(p, s.ewald, (s.pos, s.radius), &mut store, |at| {
        let packed = at.packed();
        let mut sd = Sd {
            at,
            p,
            counts: Counts::default(),
        };
        sd.at.velocities(p, force, u, None, &mut sd.counts)?;
        add_flow(p, s.pos, u);
        check_resolved(s.pos, u, dt)?;
        for i in 0..n {
            new_pos[i] = s.pos[i] + u[i] * dt;
        }
        // The projection: entries from the far field's `mu_tt` (the grand mobility's first
        // `n` block rows), moves from `M_SD`.
        bond_vectors(bonds, s.pos, cell(p), grad);
        let grad = &*grad;
        let metric = Metric::Mobility {
            mu: Mob::Full(&packed[..tri(n)]),
            grad,
            scale: dt,
            par: scratch.par,
            compact: None,
        };
        let problem = Problem::Positions {
            cell: cell(p),
            one_sided: usize::MAX,
            #[cfg(feature = "pins")]
            anchor: s.pos,
        };
        lambda.fill(T::ZERO);
        let (solver, ops) = (&p.solver, (&metric, &mut sd));
        let stats = krylov_with(problem, ops, bonds, solver, new_pos, lambda, &mut scratch)?;
        step_velocity(s.pos, new_pos, dt, new_vel);
        add_constraint_forces(bonds, grad, lambda, force);
        if p.rotation {
            sd.at
                .velocities(p, force, u, Some(&mut *new_omega), &mut sd.counts)?;
        }
        spins(p, new_omega);
        Ok(StepReport {
            near_pairs: sd.counts.pairs,
            near_products: sd.counts.products,
            near_iterations: sd.counts.iterations,
            ..report(stats, 0, bonds, lambda)
        })
    })
}
