//! The tensions of an inertial step, solved again where the position multipliers are
//! rounding noise ([`Params::resolve_tensions`]): from the step's displacements
//! ([`displacement_tensions`]), and from the start velocities projected with the mass
//! metric ([`project_velocity`]). Apart from the shared stages because only the two
//! inertial steps (`rattle.rs`, `stable.rs`) call them, and the trajectory never reads
//! them: they change what a step reports, not where it goes.

use crate::bonds::Bond;
use crate::constraints::{self, Metric, Problem, Scratch};
use crate::params::Params;
use crate::real::Real;

/// The step's bond tensions (force units, as the position multipliers) solved again
/// from the step's displacements, into `spare`; `false` if the solve fails (then the
/// position multipliers stay). The inertial steps call it after [`project_velocity`].
///
/// Why: an inertial step's constraint displacement is `O(dt^2 F / m)`, below the
/// rounding of an f32 position (`eps |x|`) once `dt` is small, so the position
/// multipliers are rounding noise there (a settling dimer's tension read `-0` at
/// `dt = 0.001`), and no solve on positions can do better. The same condition written
/// in the displacements, which are never added to a position, keeps them: with
/// `r_new - r_start = x_i - x_j` exactly, `|r_new|^2 - |r_start|^2 = 2 r_mid . (x_i -
/// x_j)`, `r_mid = (r_start + r_new) / 2`, so SHAKE's multipliers are those of the
/// linear condition `r_mid . (x_i - x_j) = 0`, less the correction of the start's
/// length error (rounding, not a force). `x` holds the unconstrained displacement
/// (scratch out), `mid` the new bond vectors (their midpoints with `start` out),
/// `metric` the step's position metric. In f64 the result equals the position
/// multipliers to rounding; the trajectory never reads it.
#[allow(clippy::too_many_arguments)]
pub(super) fn displacement_tensions<T: Real>(
    p: &Params<T>,
    bonds: &[Bond<T>],
    metric: &Metric<'_, T>,
    start: &[T::V3],
    mid: &mut [T::V3],
    x: &mut [T::V3],
    spare: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> bool {
    for (m, &g) in mid.iter_mut().zip(start) {
        *m = (*m + g) * T::HALF;
    }
    let problem = Problem::Velocities {
        bond: mid,
        dt: tolerance_scale(bonds, x),
    };
    spare.fill(T::ZERO);
    let solver = tension_solver(p);
    let solved = constraints::solve(problem, metric, bonds, &solver, x, spare, scratch);
    solved.is_ok() && spare.iter().all(|l| l.is_finite())
}

/// Projects `vel` (the start velocities) onto the bonds' tangent space at the start
/// (`start`) with the mass metric (`1/m` in `inv_mass`), its multipliers into `mult`;
/// `false` if the solve fails. The velocity stage stops at its tolerance,
/// `dt |b . v| / d^2`, which in f32 leaves far more along the bonds than a tension's
/// `dt F / m`; the next step's multipliers absorb that, so the tensions are taken
/// without it (like the start's length error in [`displacement_tensions`]).
pub(super) fn project_velocity<T: Real>(
    p: &Params<T>,
    bonds: &[Bond<T>],
    start: &[T::V3],
    vel: &mut [T::V3],
    inv_mass: &[T],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> bool {
    let mass = Metric::Mass {
        inv_mass,
        grad: start,
        scale: T::ONE,
    };
    let problem = Problem::Velocities {
        bond: start,
        dt: tolerance_scale(bonds, vel),
    };
    mult.fill(T::ZERO);
    let solver = tension_solver(p);
    let solved = constraints::solve(problem, &mass, bonds, &solver, vel, mult, scratch);
    solved.is_ok() && mult.iter().all(|l| l.is_finite())
}

/// The step's solver at the tightest tolerance: the tension is a small part of the
/// displacement (`dt F / m` of the velocity), so the step's tolerance would leave it
/// unresolved in f32; where that cannot converge, the position multipliers stay.
fn tension_solver<T: Real>(p: &Params<T>) -> constraints::Solver<T> {
    constraints::Solver {
        tolerance: constraints::Solver::<T>::min_tolerance(),
        ..p.solver
    }
}

/// The `dt` of a velocity problem on `x` that states its tolerance as a fraction of
/// `d_max max |x|` (the rounding of its residual is `eps` of that) instead of a
/// length change per step: the residual is normalised as `|c| dt / d^2`.
fn tolerance_scale<T: Real>(bonds: &[Bond<T>], x: &[T::V3]) -> T {
    let reach = x.iter().fold(T::ZERO, |a, &v| a.max_sticky(T::norm(v)));
    let longest = bonds.iter().fold(T::ZERO, |a, b| a.max_sticky(b.length));
    if reach > T::ZERO && longest > T::ZERO {
        longest / reach
    } else {
        T::ONE
    }
}
