//! Inertial HydroRATTLE as the paper writes it: velocity-Verlet form (`r* = r + v dt +
//! a dt^2 / 2`), but the velocity takes the start acceleration only (`v* = v + a(t) dt +
//! a_C dt / 2`), so the scheme is first order. The drag `-R (v - U_inf)` is explicit;
//! SHAKE with the mass metric (eq. 3) fixes the positions and RATTLE (eq. 4) the
//! velocities. Stable only for `dt` below about `2 m / zeta`.

use super::{
    Start, StepReport, assemble_tt, bond_vectors, cell, displacement_tensions, project_velocity,
    report, spin,
};
use crate::bonds::Bond;
use crate::constraints::{self, Metric, Problem};
use crate::error::{Stage, StepError};
use crate::forces::{self, ExternalForce};
use crate::linalg::{self, MobMut};
use crate::params::Params;
use crate::particles::sphere_volume;
use crate::real::Real;
use crate::workspace::Views;

/// `1/m` per particle into `inv_mass`.
fn inverse_masses<T: Real>(radius: &[T], density: &[T], inv_mass: &mut [T]) {
    for ((w, &a), &rho) in inv_mass.iter_mut().zip(radius).zip(density) {
        *w = T::ONE / (sphere_volume(a) * rho);
    }
}

/// Inertial HydroRATTLE as the paper writes it (explicit drag).
pub(super) fn rattle_explicit<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        mu,
        fac,
        force,
        work_a: drag,
        work_b: acc,
        work_c: r_star,
        inv_mass,
        new_pos,
        new_vel,
        new_omega,
        grad,
        grad_new,
        lambda,
        kappa,
        scratch: mut sc,
        ..
    } = v;
    let mu = mu.general();
    inverse_masses(s.radius, s.density, inv_mass);
    // Resistance through the Cholesky factor of mu_tt: R dv = mu^-1 (v - U_inf).
    assemble_tt(p, s.ewald, s.pos, s.radius, MobMut::Full(&mut *mu))?;
    fac.copy_from_slice(mu);
    linalg::cholesky::<T>(fac, n).map_err(|error| StepError::Linalg {
        stage: Stage::Mobility,
        error,
    })?;
    if p.stability_guard {
        let limit = explicit_drag_limit(fac, n, inv_mass, r_star, acc);
        if p.dt > limit {
            return Err(StepError::Unstable {
                dt: dt.to_f64(),
                limit: limit.to_f64(),
            });
        }
    }
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    for i in 0..n {
        drag[i] = s.vel[i] - p.flow_at(s.pos[i]);
    }
    linalg::cholesky_solve::<T>(fac, n, drag);
    // a = (F_ext - R (v - U_inf)) / m;  r* = r + v dt + a dt^2 / 2.
    let half_dt2 = T::HALF * dt * dt;
    for i in 0..n {
        acc[i] = (force[i] - drag[i]) * inv_mass[i];
        r_star[i] = s.pos[i] + s.vel[i] * dt + acc[i] * half_dt2;
        new_pos[i] = r_star[i];
    }
    // SHAKE with the mass metric (eq. 3).
    bond_vectors(bonds, s.pos, cell(p), grad);
    lambda.fill(T::ZERO);
    let metric = Metric::Mass {
        inv_mass,
        grad,
        scale: half_dt2,
    };
    let stats = constraints::solve(
        Problem::Positions {
            cell: cell(p),
            one_sided: usize::MAX,
            // Pins are refused with this method (`integrate::checks`).
            #[cfg(feature = "pins")]
            anchor: &[],
            #[cfg(feature = "slit")]
            ceiling: T::ZERO,
        },
        &metric,
        bonds,
        &p.solver,
        new_pos,
        lambda,
        &mut sc,
    )?;
    // v* = v + a dt + a_C dt / 2, then RATTLE (eq. 4) for the velocity multipliers.
    for i in 0..n {
        new_vel[i] = s.vel[i] + acc[i] * dt + (new_pos[i] - r_star[i]) / dt;
    }
    bond_vectors(bonds, new_pos, cell(p), grad_new);
    kappa.fill(T::ZERO);
    let metric = Metric::Mass {
        inv_mass,
        grad: grad_new,
        scale: T::HALF * dt,
    };
    let problem = Problem::Velocities { bond: grad_new, dt };
    let vstats = constraints::solve(problem, &metric, bonds, &p.solver, new_vel, kappa, &mut sc)?;
    // Each sphere pushes on the fluid with R (v - U_inf).
    spin(p, s.ewald, s.pos, s.radius, drag, new_omega)?;
    // The tensions from the step's displacement `v dt + a dt^2 / 2` (r* - r without the
    // positions' rounding) along the position metric, with `v` tangent to the bonds;
    // `a` follows `v` through the drag (see `displacement_tensions`); only when asked.
    if p.resolve_tensions {
        let metric = Metric::Mass {
            inv_mass,
            grad,
            scale: half_dt2,
        };
        let (vel, x) = (r_star, acc);
        vel.copy_from_slice(s.vel);
        if project_velocity(p, bonds, grad, vel, inv_mass, kappa, &mut sc) {
            for i in 0..n {
                drag[i] = vel[i] - s.vel[i];
            }
            linalg::cholesky_solve::<T>(fac, n, drag);
            for i in 0..n {
                x[i] = vel[i] * dt + (x[i] - drag[i] * inv_mass[i]) * half_dt2;
            }
            if displacement_tensions(p, bonds, &metric, grad, grad_new, x, kappa, &mut sc) {
                lambda.copy_from_slice(kappa);
            }
        }
    }
    Ok(report(stats, vstats.iterations, bonds, lambda))
}

/// Linear stability limit of the explicit drag, `2 lambda_min(M^1/2 mu M^1/2)`, by
/// inverse iteration through the Cholesky factor of `mu`: 60 iterations from an
/// irregular (hashed, deterministic) start, so no mode is missed by symmetry. The
/// Rayleigh quotient converges from above; it costs 60 Cholesky solves per step.
fn explicit_drag_limit<T: Real>(
    fac: &[T::M3],
    n: usize,
    inv_mass: &[T],
    z: &mut [T::V3],
    y: &mut [T::V3],
) -> T {
    // xorshift64 of the component index: every component differs, none is zero.
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        T::from_f64((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    };
    for zi in z.iter_mut() {
        *zi = T::v3(next(), next(), next());
    }
    let mut rq = T::ZERO;
    for _ in 0..60 {
        let norm = z.iter().fold(T::ZERO, |a, &v| a + T::norm2(v)).sqrt();
        for (i, yi) in y.iter_mut().enumerate() {
            z[i] = z[i] / norm;
            *yi = z[i] * inv_mass[i].sqrt();
        }
        linalg::cholesky_solve::<T>(fac, n, y);
        rq = T::ZERO;
        for i in 0..n {
            y[i] *= inv_mass[i].sqrt();
            rq += T::dot(z[i], y[i]);
        }
        z.copy_from_slice(y);
    }
    T::TWO / rq
}
