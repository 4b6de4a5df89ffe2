//! Overdamped HydroSHAKE: inertia dropped; the constraint move goes through the full
//! mobility, `r' = r* + dt mu G^T lambda`. First order, and a second-order
//! predictor-corrector with the same projection.

use core::cell::Cell;

use super::near;
use super::{
    Projection, Start, StepReport, Sums, add_constraint_forces, add_flow, assemble_tt,
    bond_vectors, check_resolved, free_product, hydro, max_tension, mobility_metric,
    mobility_product, project_overdamped, report, spin, step_velocity,
};
use crate::bonds::Bond;
use crate::constraints::{self, Problem, Scratch, SolveStats};
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::linalg::{self, Mob, MobMut, with_blocks};
use crate::parallel::Parallel;
use crate::params::Params;
use crate::real::Real;
use crate::workspace::Views;

/// Overdamped HydroSHAKE, first order.
pub(super) fn overdamped<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        mut mu,
        fac: copy,
        force,
        work_a: u,
        new_pos,
        new_vel,
        new_omega,
        grad,
        disp,
        lambda,
        mut scratch,
        links,
        par,
        bands,
        near,
        ..
    } = v;
    let formed = Cell::new(0);
    let mut near = (near.0, near.1, &formed);
    // Forces and mobility at the start; unconstrained velocity U_inf + mu F.
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    // With `Params::compact_products` the assembly also writes each row of the compact
    // copy (in `fac`) while the row's blocks are in cache.
    let compact = p.compact_copy(n, bonds.len());
    if compact {
        let spheres = (s.pos, s.radius);
        compact_product(
            p,
            s.ewald,
            spheres,
            mu.reborrow(),
            (force, u),
            (par, bands),
            copy,
        )?;
    } else if p.near_on() {
        let at_start = mu.reborrow();
        near::assemble_apply(p, s.ewald, s.pos, s.radius, at_start, force, u, &mut near)?;
    } else {
        let at_start = mu.reborrow();
        mobility_product(p, s.ewald, s.pos, s.radius, at_start, force, u, par, bands)?;
    }
    let mu = mu.into_ref();
    add_flow(p, s.pos, u);
    check_resolved(s.pos, u, dt)?;
    // Unconstrained move r* = r + dt (U_inf + mu F), then the constraint move through
    // the full mobility: r' = r* + dt mu G^T lambda (bonds, and contacts if on).
    let free = |x: &mut [T::V3]| {
        for i in 0..n {
            x[i] = s.pos[i] + u[i] * dt;
        }
    };
    let views = Projection {
        links,
        grad: &mut *grad,
        disp,
        lambda: &mut *lambda,
        scratch: &mut scratch,
        ewald: s.ewald,
        compact: if compact { &*copy } else { &[] },
    };
    let r = project_overdamped(p, bonds, s.pos, s.radius, mu, views, new_pos, free)?;
    step_velocity(s.pos, new_pos, dt, new_vel);
    add_constraint_forces(r.held, grad, lambda, force);
    if p.near_on() {
        let at_start = (&mut near, near::Spins::Dense);
        near::spin(p, s.ewald, s.pos, s.radius, force, new_omega, at_start)?;
    } else {
        spin(p, s.ewald, s.pos, s.radius, force, new_omega)?;
    }
    Ok(StepReport {
        #[cfg(feature = "near")]
        near_formations: formed.get(),
        contacts: r.contacts,
        wall_contacts: r.wall_contacts,
        contact_rounds: r.rounds,
        ..report(r.stats, 0, bonds, lambda)
    })
}

/// `u = mu_tt f` as [`mobility_product`] gives it, the assembly's pass also writing
/// each row of the compact copy `copy` of `mu` ([`Params::compact_products`]) while the
/// row's blocks are in cache: fused with the product in free space, with the Ewald
/// assembly in a box (with the step's sums `ew`; PSE stores no blocks to copy).
fn compact_product<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    (pos, radius): (&[T::V3], &[T]),
    mu: MobMut<'_, T>,
    (f, u): (&[T::V3], &mut [T::V3]),
    (par, bands): (&dyn Parallel, &mut [T::V3]),
    copy: &mut [T::M3],
) -> Result<(), StepError> {
    hydro(p, ew).assemble_apply_copy(par, pos, radius, mu, (f, u), bands, copy)
}

/// Projected overdamped velocity at `pos`: `U = U_inf + mu (F + G^T kappa)` with `kappa`
/// such that every bond's length rate vanishes. `mu` and `force` must hold the mobility
/// and external forces at `pos` (matrix-free `mu` is empty: the product is taken at
/// `pos`, summed in `bands`); the result is left in `u`. Inlined at both calls, so
/// that the solver choice folds where the parameters are constant ([`constraints::solve`]).
/// With `judge`, the unconstrained velocity `U_inf + mu F` is first checked to resolve
/// a step ([`check_resolved`]), as the first-order scheme checks it.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn projected_velocity<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    (pos, radius): (&[T::V3], &[T]),
    mu: Mob<'_, T>,
    force: &[T::V3],
    bonds: &[Bond<T>],
    grad: &mut [T::V3],
    disp: &mut [T::V3],
    kappa: &mut [T],
    scratch: &mut Scratch<'_, T>,
    (u, bands): (&mut [T::V3], &mut [T::V3]),
    judge: bool,
) -> Result<SolveStats<T>, StepError> {
    let n = pos.len();
    if p.matrix_free {
        free_product(p, ew, pos, radius, force, u, (scratch.par, bands))?;
    } else {
        with_blocks!(mu, a => linalg::sym_matvec::<T>(a, n, force, u));
    }
    add_flow(p, pos, u);
    if judge {
        check_resolved(pos, u, p.dt)?;
    }
    bond_vectors(bonds, pos, super::cell(p), grad);
    kappa.fill(T::ZERO);
    let problem = Problem::Velocities {
        bond: grad,
        dt: p.dt,
    };
    let par = scratch.par;
    let metric = mobility_metric(
        p,
        ew,
        bonds,
        pos,
        radius,
        mu,
        grad,
        T::ONE,
        disp,
        (par, &[]),
    );
    constraints::solve(problem, &metric, bonds, &p.solver, u, kappa, scratch)
}

/// Overdamped second order: Heun predictor-corrector on the projected velocity, then
/// the same position projection as the first-order scheme. Matrix-free
/// ([`Params::matrix_free`]) each mobility is a product where it is used (the pair
/// products, the fast free-space product, PSE or Ewald in a box), nothing stored.
pub(super) fn overdamped2<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        mu: mut mu0,
        mu2: mut mu1,
        force,
        work_a: f0,
        work_b: f1,
        work_c: x_p,
        new_pos,
        new_vel,
        new_omega,
        grad,
        grad_new,
        disp,
        lambda,
        kappa,
        scratch: mut sc,
        mut links,
        near,
        bands,
        ..
    } = v;
    let formed = Cell::new(0);
    let mut near = (near.0, near.1, &formed);
    // Predictor: projected velocity at r, one projected Euler step.
    if p.near_on() {
        near::assemble_tt(p, s.ewald, s.pos, s.radius, mu0.reborrow(), &mut near)?;
    } else if !p.matrix_free {
        assemble_tt(p, s.ewald, s.pos, s.radius, mu0.reborrow())?;
    }
    let mu0 = mu0.into_ref();
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    let (spheres, out) = ((s.pos, s.radius), (&mut *f0, &mut *bands));
    projected_velocity(
        p, s.ewald, spheres, mu0, force, bonds, grad, disp, kappa, &mut sc, out, true,
    )?;
    // Tension and spin at the start of the step: the velocity projection's multipliers
    // are the constraint forces (metric `mu G^T`, so `G^T kappa` is a force).
    let tension = max_tension(bonds, kappa);
    add_constraint_forces(bonds, grad, kappa, force);
    if p.near_on() {
        let at_start = (&mut near, near::Spins::Dense);
        near::spin(p, s.ewald, s.pos, s.radius, force, new_omega, at_start)?;
    } else {
        spin(p, s.ewald, s.pos, s.radius, force, new_omega)?;
    }
    let predict = |x: &mut [T::V3]| {
        for i in 0..n {
            x[i] = s.pos[i] + f0[i] * dt;
        }
    };
    let views = Projection {
        links: links.reborrow(),
        grad: &mut *grad,
        disp: &mut *disp,
        lambda: &mut *lambda,
        scratch: &mut sc,
        ewald: s.ewald,
        compact: &[],
    };
    project_overdamped(p, bonds, s.pos, s.radius, mu0, views, x_p, predict)?;
    // Corrector: projected velocity at the predicted point, trapezoidal average.
    if p.near_on() {
        near::assemble_tt(p, s.ewald, x_p, s.radius, mu1.reborrow(), &mut near)?;
    } else if !p.matrix_free {
        assemble_tt(p, s.ewald, x_p, s.radius, mu1.reborrow())?;
    }
    let mu1 = mu1.into_ref();
    forces::external(p, x_p, s.radius, s.density, ext, force)?;
    let (spheres, out) = ((&*x_p, s.radius), (&mut *f1, &mut *bands));
    projected_velocity(
        p, s.ewald, spheres, mu1, force, bonds, grad_new, disp, kappa, &mut sc, out, false,
    )?;
    // Projection as in the first-order scheme: r' = r* + dt mu(r) G(r)^T lambda.
    let trapezoid = |x: &mut [T::V3]| {
        for i in 0..n {
            x[i] = s.pos[i] + (f0[i] + f1[i]) * (dt * T::HALF);
        }
    };
    let views = Projection {
        links,
        grad,
        disp,
        lambda: &mut *lambda,
        scratch: &mut sc,
        ewald: s.ewald,
        compact: &[],
    };
    let r = project_overdamped(p, bonds, s.pos, s.radius, mu0, views, new_pos, trapezoid)?;
    step_velocity(s.pos, new_pos, dt, new_vel);
    Ok(StepReport {
        max_tension: tension,
        #[cfg(feature = "near")]
        near_formations: formed.get(),
        contacts: r.contacts,
        wall_contacts: r.wall_contacts,
        contact_rounds: r.rounds,
        ..report(r.stats, 0, bonds, lambda)
    })
}
