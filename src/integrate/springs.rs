//! Hookean springs instead of constraints (the paper's costly alternative): overdamped
//! explicit Euler, stable only for `dt` below about `1 / (k mu)`; at temperature the
//! Ermak–McCammon step, `r' = r + dt (U_inf + mu F) + dx` with the thermal
//! displacement `dx` of covariance `2 kT dt mu` (`brownian.rs`, without constraints).

use super::brownian::{Krylov, kick};
use super::{Start, StepReport, add_flow, check_resolved, mobility_product, spin, step_velocity};
use crate::bonds::{Bond, max_residual_in};
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::noise::Noise;
use crate::params::{Brownian, Params};
use crate::real::Real;
use crate::workspace::Views;

/// Hookean springs, overdamped explicit Euler; at temperature (`thermal`: the
/// settings and the generator) with the thermal displacement added.
pub(super) fn springs<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
    thermal: Option<(Brownian<T>, &mut Noise)>,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    // `fac` and `dx` are empty without noise; the deviates and the midpoint borrow the
    // candidate velocities and spins, written at the end.
    let Views {
        mut mu,
        mu2,
        fac,
        force,
        work_a: u,
        work_b: dx,
        new_pos,
        new_vel,
        new_omega,
        par,
        bands,
        basis,
        krylov_t,
        ..
    } = v;
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    forces::springs_in(
        bonds,
        p.spring_stiffness,
        p.fene,
        s.pos,
        super::cell(p),
        force,
    )?;
    let at_start = mu.reborrow();
    mobility_product(p, s.ewald, s.pos, s.radius, at_start, force, u, par, bands)?;
    let mu = mu.into_ref();
    add_flow(p, s.pos, u);
    let mut noise_iterations = 0;
    match thermal {
        None => {
            // The velocities are `u` itself, but positions that round back would
            // freeze the trajectory: judged as the overdamped step judges it.
            check_resolved(s.pos, u, dt)?;
            for i in 0..n {
                new_pos[i] = s.pos[i] + u[i] * dt;
                new_vel[i] = u[i];
            }
        }
        Some((b, noise)) => {
            let krylov = Krylov {
                basis,
                work: krylov_t,
                par,
                bands,
                copied: false,
                at_mid: mu2,
                near: (&mut [], &mut [], &core::cell::Cell::new(0)),
            };
            (noise_iterations, _) = kick(
                p, b, s, mu, fac, new_vel, new_omega, dx, noise, None, krylov,
            )?;
            for i in 0..n {
                new_pos[i] = s.pos[i] + u[i] * dt + dx[i];
            }
            step_velocity(s.pos, new_pos, dt, new_vel);
        }
    }
    if let Some(q0) = p.fene {
        for (k, b) in bonds.iter().enumerate() {
            forces::overstretched(k, T::norm2(new_pos[b.i] - new_pos[b.j]) / (q0 * q0))?;
        }
    }
    spin(p, s.ewald, s.pos, s.radius, force, new_omega)?;
    Ok(StepReport {
        noise_iterations,
        ..spring_report(p, bonds, new_pos)
    })
}

/// The report of a spring step: the largest relative length error (over the bonds of
/// nonzero rest length) and the largest spring force, Hookean `k | |r_ij| - d |` or
/// FENE `k |r_ij| / (1 - |r_ij|^2 / Q0^2)`.
fn spring_report<T: Real>(p: &Params<T>, bonds: &[Bond<T>], new_pos: &[T::V3]) -> StepReport<T> {
    let (_, worst) = max_residual_in(bonds, new_pos, super::cell(p).as_ref());
    let k = p.spring_stiffness;
    let tension = bonds.iter().fold(T::ZERO, |a, b| {
        let r2 = T::norm2(new_pos[b.i] - new_pos[b.j]);
        let f = match p.fene {
            None => k * (r2.sqrt() - b.length).abs(),
            Some(q0) => k * r2.sqrt() / (T::ONE - r2 / (q0 * q0)),
        };
        a.max(f)
    });
    StepReport {
        iterations: 0,
        velocity_iterations: 0,
        residual: worst,
        max_tension: tension,
        ..StepReport::default()
    }
}
