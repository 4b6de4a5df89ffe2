//! `Overdamped2` with constraints (bonds, pins, hard contacts, the wall's links) on the
//! iterative near field: the dense near step's predictor-corrector
//! (`integrate/overdamped.rs`) with every mobility one of `M_SD`'s iterative products
//! in place of its stored blocks (`constrained.rs` for the solves along them).
//!
//! * At the start: the projected velocity `U0` (`U_inf + M_SD,tt (F + G^T kappa)`,
//!   the bonds' length rates zero), the spins of `F + G^T kappa`, and the predictor
//!   `r + dt U0` projected onto the constraints along `dt M_SD,tt(r) G^T` (the
//!   contacts' active-set rounds).
//! * At the predicted point `r_p`: the projected velocity `U1` along `M_SD,tt(r_p)`.
//! * The trapezoid `r + dt (U0 + U1) / 2` projected along `dt M_SD,tt(r) G^T`, as the
//!   first-order step projects.
//!
//! The near field's storage holds one configuration's factors, so the start's is
//! assembled and factored again for the last projection (the same bits as the first
//! time): three assemblies of the far field a step, against the dense step's two
//! formations of `M_SD`, and no storage beyond the first-order constrained step's.
//! A product that does not converge ends the step with [`StepError::NoConvergence`]
//! at [`Stage::Mobility`](crate::Stage::Mobility), the caller's state unchanged.

use super::constrained::{Iterative, held, held_report};
use super::{Counts, Store, solve, spins};
use crate::bonds::Bond;
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::integrate::contacts::project_along;
use crate::integrate::{Start, StepReport, add_constraint_forces, max_tension, step_velocity};
use crate::params::Params;
use crate::real::Real;
use crate::workspace::Views;

/// `Overdamped2` with bonds, pins and contacts on the iterative near field (see the
/// module): Heun's predictor-corrector on the projected velocity, then the first-order
/// step's position projection along `M_SD` at the start.
pub(in crate::integrate) fn overdamped2<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        force,
        work_a: u0,
        work_b: u1,
        work_c: x_p,
        new_pos,
        new_vel,
        new_omega,
        grad,
        grad_new,
        disp,
        lambda,
        kappa,
        mut scratch,
        mut links,
        near,
        near_iter,
        ..
    } = v;
    // Room for every row the step may solve: the bonds and the contacts' capacity.
    let rows = p.constraints(n, bonds.len());
    let (reals, stiff) = near.1.split_at_mut(near.1.len().saturating_sub(rows));
    let mut store = Store::new((near.0, reals), near_iter);
    let mut counts = Counts::default();
    let start = (s.pos, s.radius);
    // One configuration's products: entries from its far field's `mu_tt`, moves and
    // squeeze resistances from its `M_SD`.
    macro_rules! along {
        ($at:expr, $spheres:expr) => {
            Iterative::new(
                $at,
                p,
                &mut counts,
                &mut *stiff,
                $spheres,
                s.ewald,
                &mut *disp,
            )
        };
    }
    // Predictor: the projected velocity at the start, its constraint forces' spins,
    // one projected Euler step.
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    let tension = solve::at(p, s.ewald, start, &mut store, |at| {
        let mut along = along!(at, start);
        let views = (&mut *grad, &mut *kappa);
        along.velocities(p, bonds, force, views, &mut scratch, u0, true)?;
        let tension = max_tension(bonds, kappa);
        add_constraint_forces(bonds, grad, kappa, force);
        if p.rotation {
            let sd = &mut along.sd;
            sd.at
                .velocities(p, force, u1, Some(&mut *new_omega), sd.counts)?;
        }
        let predict = |x: &mut [T::V3]| {
            for i in 0..n {
                x[i] = s.pos[i] + u0[i] * dt;
            }
        };
        let views = (links.reborrow(), &mut *grad, &mut *lambda, &mut scratch);
        project_along(p, bonds, start, views, x_p, predict, &mut along)?;
        Ok(tension)
    })?;
    spins(p, new_omega);
    // Corrector: the projected velocity at the predicted point.
    forces::external(p, x_p, s.radius, s.density, ext, force)?;
    let predicted = (&*x_p, s.radius);
    solve::at(p, s.ewald, predicted, &mut store, |at| {
        let mut along = along!(at, predicted);
        let views = (&mut *grad_new, &mut *kappa);
        along
            .velocities(p, bonds, force, views, &mut scratch, u1, false)
            .map(|_| ())
    })?;
    // The trapezoid, projected along `M_SD` at the start (factored again).
    let r = solve::at(p, s.ewald, start, &mut store, |at| {
        let mut along = along!(at, start);
        let trapezoid = |x: &mut [T::V3]| {
            for i in 0..n {
                x[i] = s.pos[i] + (u0[i] + u1[i]) * (dt * T::HALF);
            }
        };
        let views = (links, &mut *grad, &mut *lambda, &mut scratch);
        let r = project_along(p, bonds, start, views, new_pos, trapezoid, &mut along)?;
        Ok(held(&r))
    })?;
    step_velocity(s.pos, new_pos, dt, new_vel);
    Ok(StepReport {
        max_tension: tension,
        ..held_report(&counts, r, 0, bonds, lambda)
    })
}
