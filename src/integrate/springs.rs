//! Hookean springs instead of constraints (the paper's costly alternative): overdamped
//! explicit Euler, stable only for `dt` below about `1 / (k mu)`.

use super::{Start, StepReport, add_flow, mobility_product, spin};
use crate::bonds::{Bond, max_residual};
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::params::Params;
use crate::real::Real;
use crate::workspace::Views;

/// Hookean springs, overdamped explicit Euler.
pub(super) fn springs<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        mu,
        force,
        work_a: u,
        new_pos,
        new_vel,
        new_omega,
        par,
        bands,
        ..
    } = v;
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    forces::springs(bonds, p.spring_stiffness, s.pos, force);
    mobility_product(p, s.pos, s.radius, mu, force, u, par, bands)?;
    add_flow(p, s.pos, u);
    for i in 0..n {
        new_pos[i] = s.pos[i] + u[i] * dt;
        new_vel[i] = u[i];
    }
    spin(p, s.pos, s.radius, force, new_omega)?;
    let (_, worst) = max_residual(bonds, new_pos);
    let tension = bonds.iter().fold(T::ZERO, |a, b| a.max(b.length)) * worst * p.spring_stiffness;
    Ok(StepReport {
        iterations: 0,
        velocity_iterations: 0,
        residual: worst,
        max_tension: tension,
        ..StepReport::default()
    })
}
