//! Inertial RATTLE with the drag implicit (backward Euler in the velocity): stable at
//! any `dt`, equal to the overdamped step as the masses go to zero; with rotation it
//! runs on the 6N grand mobility.
//!
//! At temperature (Langevin dynamics with hydrodynamic friction) the generalised force
//! gains the random force `g = sqrt(2 kT / dt) L^-T xi`, `L L^T = mu` (Cholesky of the
//! translational or grand mobility), `xi` standard normal: covariance `2 kT R / dt`
//! with `R = mu^-1` the drag, the fluctuation-dissipation theorem's, and `mu g =
//! sqrt(2 kT / dt) L xi` is the overdamped Brownian velocity. For the discretised scheme
//! `(M + R dt) v' = M v + g dt` this has two exact consequences, for any `dt`, `M` and
//! `R` (without forces and bonds):
//!
//! * the stationary velocities are normal with covariance `kT (M + R dt / 2)^-1` (it
//!   solves `V = A M V M A + A (2 kT R dt) A`, `A = (M + R dt)^-1`): equipartition with
//!   the mass `M + R dt / 2`, so `<m v^2> = kT / (1 + zeta dt / 2m)` for a lone sphere,
//!   `kT` as `dt -> 0`;
//! * the long-time diffusion is exactly `kT mu` (the displacements over many steps
//!   add up to `mu` times the summed impulses), and as `M -> 0` the step is the
//!   overdamped Brownian step (`Drift::Uncorrected`).
//!
//! The impulse covariance that would make `<m v^2> = kT` exact at every `dt`,
//! `kT dt (2 R + dt R M^-1 R)`, was not chosen: since the position moves by `v' dt`, it
//! diffuses at `kT mu + kT dt M^-1 / 2`, without bound as `M -> 0` at fixed `dt`; the
//! scheme would lose the overdamped limit that makes it stable at any `dt`. Bonds: the
//! velocities are projected onto the constraints' tangent space as without noise
//! (RATTLE), so a chain's kinetic energy tends to `(3N - B) kT / 2` as `dt -> 0`. No
//! drift term: the noise enters the momentum, and the position is differentiable.

use super::{
    Start, StepReport, add_constraint_forces, add_flow, assemble_tt, bond_vectors,
    displacement_tensions, project_positions, project_velocity, report, step_velocity,
};
use crate::bonds::Bond;
use crate::constraints::{self, Metric, Problem, SolverKind, apply_drag};
use crate::error::{Stage, StepError};
use crate::forces::{self, ExternalForce};
use crate::linalg::{self, MobMut, tri};
use crate::noise::Noise;
use crate::params::{Brownian, Params};
use crate::particles::sphere_volume;
use crate::real::Real;
use crate::workspace::Views;

/// Inertial with implicit drag: `(R + M/dt) v' = F + F_C + M v/dt + R U_inf`, solved as
/// `v' = S^-1 dt K^-1 S (mu (F + F_C + M v/dt) + U_inf)`, `S = M^1/2`, `K = dt I + S mu S`.
/// With rotation the same on the 6N grand mobility (`M` holds masses and moments).
/// At temperature (`thermal`: the settings and the generator) `F` includes the random
/// force of the module's documentation.
pub(super) fn rattle_stable<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
    thermal: Option<(Brownian<T>, &mut Noise)>,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let m = if p.rotation { 2 * n } else { n };
    let noisy = thermal.is_some();
    let Views {
        mu,
        fac,
        force: rhs6,
        work_a: u,
        work_b: t,
        sqrt_m: sq,
        new_pos,
        new_vel,
        new_omega,
        grad,
        grad_new,
        disp,
        lambda,
        kappa,
        scratch: mut sc,
        ..
    } = v;
    let mu = mu.general();
    // Mobility (translation or grand) and the drag operator K = dt I + S mu S.
    if p.rotation {
        super::geometry::grand(p, s.ewald, s.pos, s.radius, mu)?;
    } else {
        assemble_tt(p, s.ewald, s.pos, s.radius, MobMut::Full(&mut *mu))?;
    }
    for i in 0..n {
        let mass = sphere_volume(s.radius[i]) * s.density[i];
        sq[i] = mass.sqrt();
        if p.rotation {
            sq[n + i] = (T::from_f64(0.4) * mass * s.radius[i] * s.radius[i]).sqrt();
        }
    }
    // The random force sqrt(2 kT / dt) L^-T xi (`t` holds it until the forces are
    // known); `fac` holds L until it takes the drag operator.
    if let Some((b, noise)) = thermal {
        fac.copy_from_slice(mu);
        linalg::cholesky::<T>(fac, m).map_err(|error| StepError::Linalg {
            stage: Stage::Mobility,
            error,
        })?;
        noise.fill::<T>(t);
        linalg::solve_upper::<T>(fac, m, t);
        let amplitude = (T::TWO * b.temperature / dt).sqrt();
        for g in t.iter_mut() {
            *g *= amplitude;
        }
    }
    for i in 0..m {
        for j in 0..=i {
            fac[tri(i) + j] = mu[tri(i) + j] * (sq[i] * sq[j]);
        }
        fac[tri(i) + i] += T::m3_diag(dt);
    }
    linalg::cholesky::<T>(fac, m).map_err(|error| StepError::Linalg {
        stage: Stage::Drag,
        error,
    })?;
    // Unconstrained generalised velocity from F + M v / dt.
    forces::external(p, s.pos, s.radius, s.density, ext, &mut rhs6[..n])?;
    rhs6[n..].fill(T::V3_ZERO);
    for i in 0..m {
        let w = if i < n { s.vel[i] } else { s.omega[i - n] };
        rhs6[i] += w * (sq[i] * sq[i] / dt);
    }
    if noisy {
        for (f, &g) in rhs6.iter_mut().zip(t.iter()) {
            *f += g;
        }
    }
    drag_velocity(p, s.pos, mu, fac, sq, rhs6, u);
    for i in 0..n {
        new_pos[i] = s.pos[i] + u[i] * dt;
    }
    // Constraint displacements D_l = dt S^-1 dt K^-1 S mu g_l (every bead moves):
    // for the dense solves one drag solve per bond, for Krylov one per iteration.
    bond_vectors(bonds, s.pos, super::cell(p), grad);
    let metric = if p.solver.kind.resolve(bonds.len()) == SolverKind::Krylov {
        Metric::Drag {
            mu,
            fac,
            sq,
            dt,
            grad,
        }
    } else {
        for (l, b) in bonds.iter().enumerate() {
            for q in 0..m {
                // Block (q, i): the tt blocks are symmetric, rotation rows lie below.
                let block = |i: usize| {
                    if i <= q {
                        mu[tri(q) + i]
                    } else {
                        mu[tri(i) + q]
                    }
                };
                t[q] = (block(b.i) - block(b.j)) * grad[l];
            }
            apply_drag(fac, sq, dt, t);
            for (d, &tq) in disp[l * n..(l + 1) * n].iter_mut().zip(t.iter()) {
                *d = tq * dt;
            }
        }
        let disp = &disp[..n * bonds.len()];
        Metric::Dense { disp, n, grad }
    };
    let stats = project_positions(p, bonds, &metric, new_pos, lambda, &mut sc, usize::MAX, &[])?;
    step_velocity(s.pos, new_pos, dt, new_vel);
    // The unconstrained displacement `u dt` for the tensions (`u` is the spin's next).
    for (d, &w) in t[..n].iter_mut().zip(u[..n].iter()) {
        *d = w * dt;
    }
    // Angular velocities: the same solve with the constraint forces included.
    if p.rotation {
        add_constraint_forces(bonds, grad, lambda, &mut rhs6[..n]);
        drag_velocity(p, s.pos, mu, fac, sq, rhs6, u);
        new_omega.copy_from_slice(&u[n..]);
    } else {
        new_omega.fill(p.vorticity);
    }
    // RATTLE: make the velocities tangent to the bonds at the new positions.
    bond_vectors(bonds, new_pos, super::cell(p), grad_new);
    kappa.fill(T::ZERO);
    let problem = Problem::Velocities { bond: grad_new, dt };
    let vstats = constraints::solve(problem, &metric, bonds, &p.solver, new_vel, kappa, &mut sc)?;
    // The tensions from the displacement `u dt`, never added to a position: f32 keeps
    // them (see `displacement_tensions`); only when asked.
    let x = &mut t[..n];
    if p.resolve_tensions
        && displacement_tensions(p, bonds, &metric, grad, grad_new, x, kappa, &mut sc)
    {
        // `sq` is done with once the step's metric is: it takes the inverse masses.
        for w in &mut sq[..n] {
            *w = T::ONE / (*w * *w);
        }
        u[..n].copy_from_slice(s.vel);
        let vel = &mut u[..n];
        if project_velocity(p, bonds, grad, vel, &sq[..n], lambda, &mut sc) {
            // `v + M^-1 G kappa_0` moves `u dt` by `Q G kappa_0`, the step's metric's
            // move of `kappa_0 / dt`: the tensions are the displacements' less that.
            for (l, &k) in lambda.iter_mut().zip(kappa.iter()) {
                *l = k - *l / dt;
            }
        } else {
            lambda.copy_from_slice(kappa);
        }
    }
    Ok(report(stats, vstats.iterations, bonds, lambda))
}

/// `u = S^-1 dt K^-1 S (mu f + U_inf)` for a generalised force `f` (length `m`).
fn drag_velocity<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    mu: &[T::M3],
    fac: &[T::M3],
    sq: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
) {
    let (m, n) = (f.len(), pos.len());
    linalg::sym_matvec::<T>(mu, m, f, u);
    add_flow(p, pos, &mut u[..n]);
    for w in &mut u[n..] {
        *w += p.vorticity;
    }
    apply_drag(fac, sq, p.dt, u);
}
