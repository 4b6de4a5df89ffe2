//! The first and third stages of a step: checking the inputs (parameters, particles,
//! bonds, thermal noise, contacts) before anything is touched, and accepting the
//! candidate state before it is committed.
//!
//! This file holds the input checks that read the parameters and the spheres one by
//! one; the periodic box's checks, which also derive the step's Ewald or PSE sums, are
//! in `checks/periodic_box.rs`, the wall's in `checks/wall.rs`, the slit's in `checks/slit.rs`, and the acceptance of a candidate (a pair search, in
//! bands through the host's threads) in `checks/acceptance.rs`. The seam is what each
//! costs and what it hands on: `O(N + B)` checks that return nothing, the box's sums
//! that every product of the step reads, and the `O(N^2)` (or cell-list) pair search.

mod acceptance;
mod periodic_box;
mod slit;
mod wall;

pub(super) use acceptance::accept;
pub(super) use periodic_box::check_box;
use periodic_box::check_periodic;
use slit::check_slit;
pub(super) use slit::check_slit_place;
use wall::check_wall;

use crate::bonds::Bond;
use crate::constraints::Solver;
use crate::error::{ParticleError, StepError};
use crate::params::{Method, Params};
use crate::particles::{State, sphere_volume};
use crate::real::Real;

use super::stages::HeldSums;

/// The thermal settings when this step has noise (`brownian` with `kT > 0`), after
/// checking that the temperature is valid and the combination is implemented.
pub(super) fn check_thermal<T: Real>(
    p: &Params<T>,
    has_generator: bool,
) -> Result<Option<crate::params::Brownian<T>>, StepError> {
    let Some(b) = p.brownian else {
        return Ok(None);
    };
    if !(b.temperature >= T::ZERO && b.temperature.is_finite()) {
        return Err(StepError::BadParameter(
            "brownian.temperature (finite, >= 0)",
        ));
    }
    if b.temperature == T::ZERO {
        return Ok(None);
    }
    if !matches!(
        p.method,
        Method::Overdamped | Method::Springs | Method::RattleStable
    ) {
        return Err(StepError::Unsupported(
            "thermal noise with Rattle or Overdamped2 (Overdamped, Springs and RattleStable take it)",
        ));
    }
    if p.method == Method::RattleStable && p.noise_sqrt == crate::params::NoiseSqrt::Lanczos {
        return Err(StepError::Unsupported(
            "noise_sqrt = Lanczos with RattleStable (it factors its drag densely: Cholesky only)",
        ));
    }
    if p.matrix_free && p.noise_sqrt == crate::params::NoiseSqrt::Cholesky {
        return Err(StepError::Unsupported(
            "a Cholesky factor of the noise without a stored mobility (matrix_free: use Lanczos or Auto)",
        ));
    }
    let l = p.lanczos;
    if p.noise_sqrt != crate::params::NoiseSqrt::Cholesky
        && (l.max_iterations == 0 || !(l.tolerance > T::ZERO && l.tolerance.is_finite()))
    {
        return Err(StepError::BadParameter(
            "lanczos (tolerance finite and > 0, max_iterations > 0)",
        ));
    }
    if !has_generator {
        return Err(StepError::Unsupported(
            "thermal noise without a generator (State::noise / ParticleSet::noise)",
        ));
    }
    Ok(Some(b))
}

/// Stage 1 of a step: every check of its inputs, in order; the thermal settings when
/// the step has noise, and the step's Ewald parameters in a box.
pub(super) fn check_all<T: Real>(
    state: &State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    has_generator: bool,
) -> Result<(Option<crate::params::Brownian<T>>, HeldSums<T>), StepError> {
    check_inputs(state, bonds, p)?;
    let thermal = check_thermal(p, has_generator)?;
    super::pins::check(p, bonds, state.pos, state.radius, thermal.is_some())?;
    check_contacts(p)?;
    // The box first: a box with a wall is refused as such, not by the wall's check.
    let sums = check_periodic(p, state, bonds)?;
    check_wall(p, state)?;
    check_slit(p, state)?;
    super::near::check(p, state.len(), thermal.is_some())?;
    Ok((thermal, sums))
}

/// Refuses contacts where they are not implemented.
pub(super) fn check_contacts<T: Real>(p: &Params<T>) -> Result<(), StepError> {
    let Some(c) = p.contacts else {
        return Ok(());
    };
    if !cfg!(feature = "contacts") {
        return Err(StepError::Unsupported(
            "contacts: the kernel was built without its `contacts` feature",
        ));
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "contacts with a method other than Overdamped or Overdamped2",
        ));
    }
    if c.max_rounds == 0 {
        return Err(StepError::BadParameter("contacts.max_rounds (> 0)"));
    }
    Ok(())
}

/// Cheap checks (O(N + B)); pair checks happen in assembly and in [`accept`].
pub(super) fn check_inputs<T: Real>(
    state: &State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
) -> Result<(), StepError> {
    let n = state.len();
    let lengths = [
        state.vel.len(),
        state.omega.len(),
        state.radius.len(),
        state.density.len(),
    ];
    if lengths.iter().any(|&l| l != n) {
        return Err(StepError::StateLength);
    }
    if !(p.dt > T::ZERO && p.dt.is_finite()) {
        return Err(StepError::BadTimeStep);
    }
    let bad = |ok: bool, name| {
        if ok {
            Ok(())
        } else {
            Err(StepError::BadParameter(name))
        }
    };
    bad(
        p.viscosity > T::ZERO && p.viscosity.is_finite(),
        "viscosity",
    )?;
    bad(p.fluid_density.is_finite(), "fluid_density")?;
    bad(T::v3_is_finite(p.gravity), "gravity")?;
    bad(T::v3_is_finite(p.flow_velocity), "flow_velocity")?;
    bad(T::v3_is_finite(p.vorticity), "vorticity")?;
    bad(
        p.solver.tolerance >= Solver::min_tolerance() && p.solver.tolerance.is_finite(),
        "tolerance (at least 16 machine epsilons, finite)",
    )?;
    // Time must stay finite and advance (a huge time would swallow dt).
    bad(
        state.time.is_finite()
            && *state.time + p.dt > *state.time
            && (*state.time + p.dt).is_finite(),
        "time (finite, and advanced by dt)",
    )?;
    bad(p.solver.max_iterations > 0, "max_iterations")?;
    bad(
        !p.matrix_free
            || matches!(
                p.method,
                Method::Overdamped | Method::Overdamped2 | Method::Springs
            ),
        "matrix_free (Overdamped, Overdamped2 and Springs only)",
    )?;
    if p.method == Method::Springs {
        bad(
            p.spring_stiffness > T::ZERO && p.spring_stiffness.is_finite(),
            "spring_stiffness",
        )?;
        bad(
            p.fene.is_none_or(|q| q > T::ZERO && (q * q).is_finite()),
            "fene (maximum extension > 0, its square finite)",
        )?;
    }
    let inertial = matches!(p.method, Method::Rattle | Method::RattleStable);
    for i in 0..n {
        let finite = T::v3_is_finite(state.pos[i])
            && T::v3_is_finite(state.vel[i])
            && T::v3_is_finite(state.omega[i])
            && state.radius[i].is_finite()
            && state.density[i].is_finite();
        if !finite {
            return Err(ParticleError::NonFinite { particle: i }.into());
        }
        if !(state.radius[i] >= T::MIN_POSITIVE) {
            return Err(ParticleError::BadRadius { particle: i }.into());
        }
        if state.density[i] < T::ZERO {
            return Err(ParticleError::BadDensity { particle: i }.into());
        }
        if inertial && sphere_volume(state.radius[i]) * state.density[i] <= T::ZERO {
            return Err(ParticleError::Massless { particle: i }.into());
        }
    }
    let springs = p.method == Method::Springs;
    for (bond, b) in bonds.iter().enumerate() {
        crate::bonds::check_one(bond, b, n)?;
        // A constraint of length zero has no direction to hold.
        if b.length == T::ZERO && !springs {
            return Err(crate::error::BondError::BadLength { bond }.into());
        }
    }
    Ok(())
}
