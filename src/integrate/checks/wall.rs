//! The wall's part of a step's checks: its height, the kernel's features and the
//! method that holds it, and no sphere below it (at the start, [`check_wall`], and in
//! a candidate, [`below_wall`] for the acceptance).

use crate::error::{ParticleError, StepError};
use crate::params::{Method, Params};
use crate::particles::State;
use crate::real::Real;

/// Checks the wall: a finite height; the kernel built with its `wall` feature (the
/// wall's mobility, `mobility::wall`) and its `contacts` feature (the wall is held as
/// a one-sided constraint); a method whose position projection holds it (Overdamped,
/// Overdamped2); and no sphere below its contact height `height + a_i` (beyond the
/// contacts' tolerance: the last step's wall contacts end within it).
pub(super) fn check_wall<T: Real>(p: &Params<T>, state: &State<'_, T>) -> Result<(), StepError> {
    let Some(height) = p.place().wall() else {
        return Ok(());
    };
    if !height.is_finite() {
        return Err(StepError::BadParameter("wall.height (finite)"));
    }
    if !cfg!(feature = "wall") {
        return Err(StepError::Unsupported(
            "a wall: the kernel was built without its `wall` feature",
        ));
    }
    if !cfg!(feature = "contacts") {
        return Err(StepError::Unsupported(
            "a wall: the kernel was built without its `contacts` feature",
        ));
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "a wall with a method other than Overdamped or Overdamped2",
        ));
    }
    match below_wall(state.pos, state.radius, height, p.solver.tolerance) {
        Some(particle) => Err(ParticleError::BelowWall { particle }.into()),
        None => Ok(()),
    }
}

/// The first sphere whose centre is below `height + a_i (1 - 2 tol)`, less the
/// rounding of the numbers compared (4 epsilons of `|z| + |height| + a_i`): far from
/// the origin a sphere put or held at contact is off by an ulp of its coordinates,
/// which can exceed `2 tol a_i`. A centre that is not strictly above the plane in the
/// step's precision (`z - height <= 0`: the coordinates' spacing there exceeds the
/// radius, f32 far from the origin) is below it whatever that rounding: the wall's
/// mobility has no value there (`mobility::wall`), and a scene checked with this test
/// at parse time is not refused at its first step by that one.
pub(super) fn below_wall<T: Real>(pos: &[T::V3], radius: &[T], height: T, tol: T) -> Option<usize> {
    let reach = T::ONE - tol * T::TWO;
    let ulps = T::EPSILON * T::from_f64(4.0);
    pos.iter().zip(radius).position(|(&r, &a)| {
        let z = T::xyz(r)[2];
        let rounding = (z.abs() + height.abs() + a) * ulps;
        !(z - height > T::ZERO && z - height + rounding >= a * reach)
    })
}
