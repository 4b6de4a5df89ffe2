//! Overdamped HydroSHAKE with thermal noise (constrained Brownian dynamics).
//!
//! The unconstrained move gets a displacement with covariance `2 kT dt mu`, drawn as
//! `L xi` with `L L^T = mu` (block Cholesky of the packed mobility) and `xi` standard
//! normal; the constraint projection then runs as in the deterministic step. What the
//! constrained motion also needs is the Ito drift `kT div(P mu)`, `P mu` the mobility
//! projected onto the constraints (`P = I - mu G^T (G mu G^T)^-1 G`):
//!
//! * [`Drift::Midpoint`] gets it from a Fixman-type midpoint. With
//!   `x~ = x + sqrt(kT dt / 2) L xi`, the noise `sqrt(2 kT dt) P(x~) mu(x~) L^-T xi` has
//!   covariance `2 kT dt P mu` to leading order (`L^-T L^-1 = mu^-1`) and mean
//!   `kT dt d_k (P mu)_ik` (`E[(L xi)_k (L^-T xi)_j] = delta_kj`). `P(x~) mu(x~) v` is a
//!   linear constraint solve at `x~`: `v` through `mu(x~)`, minus the part that changes
//!   a bond length at `x~`.
//! * [`Drift::Uncorrected`] adds `sqrt(2 kT dt) L xi` and nothing else.
//!
//! The RPY mobility (and Oseen's, and free draining) has zero divergence in free space,
//! so the unconstrained drift `kT div mu` vanishes: no term for it here. The midpoint
//! would supply it anyway (it differentiates `P mu` as a whole).

use super::{
    Projection, Start, StepReport, add_constraint_forces, add_flow, assemble_tt, bond_vectors,
    mobility_metric, mobility_product, project_overdamped, report, spin, step_velocity,
};
use crate::bonds::Bond;
use crate::constraints::{self, Problem, Scratch};
use crate::error::{Stage, StepError};
use crate::forces::{self, ExternalForce};
use crate::linalg;
use crate::noise::Noise;
use crate::noise::lanczos::{self, LanczosError};
use crate::params::{Brownian, Drift, Params};
use crate::real::Real;
use crate::workspace::Views;

/// One overdamped step with thermal noise at `b.temperature > 0` (stored mobility).
pub(super) fn overdamped_thermal<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    b: Brownian<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
    noise: &mut Noise,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    // The normal deviates and the midpoint borrow the candidate velocities and spins,
    // which are written only at the end.
    let Views {
        mu,
        fac,
        force,
        work_a: u,
        work_b: dx,
        new_pos,
        new_vel: xi,
        new_omega: mid,
        grad,
        grad_new: grad_mid,
        disp,
        lambda,
        kappa,
        mut scratch,
        par,
        bands,
        basis,
        krylov_t,
        links,
        ..
    } = v;
    // Deterministic velocity at the start: U_inf + mu F.
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    mobility_product(p, s.pos, s.radius, mu, force, u, par, bands)?;
    add_flow(p, s.pos, u);
    let held = Held {
        bonds,
        grad_mid,
        disp,
        kappa,
        scratch: &mut scratch,
    };
    let krylov = (basis, krylov_t);
    let noise_iterations = kick(p, b, s, mu, fac, xi, mid, dx, noise, Some(held), krylov)?;
    // r* = r + dt (U_inf + mu F) + noise, projected as in the deterministic step (with
    // the wall's links when there is one).
    let free = |x: &mut [T::V3]| {
        for i in 0..n {
            x[i] = s.pos[i] + u[i] * dt + dx[i];
        }
    };
    let views = Projection {
        links,
        grad: &mut *grad,
        disp,
        lambda: &mut *lambda,
        scratch: &mut scratch,
    };
    let r = project_overdamped(p, bonds, s.pos, s.radius, mu, views, new_pos, free)?;
    step_velocity(s.pos, new_pos, dt, xi);
    add_constraint_forces(r.held, grad, lambda, force);
    spin(p, s.pos, s.radius, force, mid)?;
    Ok(StepReport {
        noise_iterations,
        contacts: r.contacts,
        wall_contacts: r.wall_contacts,
        contact_rounds: r.rounds,
        ..report(r.stats, 0, bonds, lambda)
    })
}

/// The bonds the midpoint's noise is projected onto (constraints), and its storage.
pub(super) struct Held<'a, 'b, T: Real> {
    pub(super) bonds: &'a [Bond<T>],
    pub(super) grad_mid: &'a mut [T::V3],
    pub(super) disp: &'a mut [T::V3],
    pub(super) kappa: &'a mut [T],
    pub(super) scratch: &'a mut Scratch<'b, T>,
}

/// The Lanczos basis and its scalars ([`Views::basis`], [`Views::krylov_t`]); empty
/// with the Cholesky factor.
pub(super) type Krylov<'a, T> = (&'a mut [<T as Real>::V3], &'a mut [T]);

/// The thermal displacement `dx` of one step from the packed mobility `mu` at the
/// start (see the module): `fac` takes its Cholesky factor (then, with the midpoint,
/// the mobility at the midpoint), `xi` the deviates, `mid` the midpoint. With `held`
/// the midpoint's noise is projected onto its bonds; without (springs), it is
/// `sqrt(2 kT dt) mu(x~) L^-T xi`, whose mean is `kT dt div mu` (zero for RPY).
/// With the Lanczos square root ([`Params::noise_sqrt`]) `L` is the symmetric
/// `mu^(1/2)`, drawn from products with `mu` in the basis `krylov`, and the returned
/// count is its iterations (0 with Cholesky).
#[allow(clippy::too_many_arguments)]
pub(super) fn kick<T: Real>(
    p: &Params<T>,
    b: Brownian<T>,
    s: &Start<'_, T>,
    mu: &[T::M3],
    fac: &mut [T::M3],
    xi: &mut [T::V3],
    mid: &mut [T::V3],
    dx: &mut [T::V3],
    noise: &mut Noise,
    held: Option<Held<'_, '_, T>>,
    krylov: Krylov<'_, T>,
) -> Result<u32, StepError> {
    let (n, dt, kt) = (s.pos.len(), p.dt, b.temperature);
    let lanczos = p.noise_sqrt.lanczos(n);
    if !lanczos {
        // L L^T = mu.
        fac.copy_from_slice(mu);
        linalg::cholesky::<T>(fac, n).map_err(|error| StepError::Linalg {
            stage: Stage::Mobility,
            error,
        })?;
    }
    noise.fill::<T>(xi);
    let amplitude = (T::TWO * kt * dt).sqrt();
    let (basis, work) = krylov;
    let product = |v: &[T::V3], w: &mut [T::V3]| linalg::sym_matvec::<T>(mu, n, v, w);
    let mut iterations = 0;
    match b.drift {
        Drift::Uncorrected => {
            if lanczos {
                iterations = lanczos::sqrt(p.lanczos, product, xi, basis, work, dx, None)
                    .map_err(refused)?;
            } else {
                linalg::lower_mul::<T>(fac, n, xi, dx);
            }
            for d in dx.iter_mut() {
                *d *= amplitude;
            }
        }
        Drift::Midpoint => {
            // x~ = x + sqrt(kT dt / 2) L xi; then xi <- sqrt(2 kT dt) L^-T xi.
            if lanczos {
                iterations =
                    lanczos::sqrt(p.lanczos, product, xi, basis, work, mid, Some(&mut *dx))
                        .map_err(refused)?;
                xi.copy_from_slice(dx);
            } else {
                linalg::lower_mul::<T>(fac, n, xi, mid);
                linalg::solve_upper::<T>(fac, n, xi);
            }
            let half = (kt * dt * T::HALF).sqrt();
            for (m, &r) in mid.iter_mut().zip(s.pos) {
                *m = r + *m * half;
            }
            for z in xi.iter_mut() {
                *z *= amplitude;
            }
            // dx = P(x~) mu(x~) xi: the factor's storage takes mu(x~).
            assemble_tt(p, mid, s.radius, fac)?;
            linalg::sym_matvec::<T>(fac, n, xi, dx);
            if let Some(h) = held {
                bond_vectors(h.bonds, mid, h.grad_mid);
                h.kappa.fill(T::ZERO);
                let par = h.scratch.par;
                let metric = mobility_metric(
                    p,
                    h.bonds,
                    mid,
                    s.radius,
                    fac,
                    h.grad_mid,
                    T::ONE,
                    h.disp,
                    par,
                );
                let problem = Problem::Velocities {
                    bond: h.grad_mid,
                    dt: T::ONE,
                };
                constraints::solve(problem, &metric, h.bonds, &p.solver, dx, h.kappa, h.scratch)?;
            }
        }
    }
    Ok(iterations)
}

/// A failed Lanczos square root as the step's error (at the mobility stage).
fn refused(e: LanczosError) -> StepError {
    match e {
        LanczosError::NoConvergence { iterations, change } => StepError::NoConvergence {
            stage: Stage::Mobility,
            iterations,
            residual: change,
        },
        LanczosError::NotPositiveDefinite { .. } => StepError::Linalg {
            stage: Stage::Mobility,
            error: crate::error::LinalgError::NotPositiveDefinite { row: 0 },
        },
        LanczosError::Storage => StepError::BadParameter("lanczos.max_iterations (> 0)"),
    }
}
