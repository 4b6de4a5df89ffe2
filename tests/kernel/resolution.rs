//! What the precision resolves, checked against closed forms:
//!
//! * a step so short that no sphere moves by the spacing of its coordinates computes
//!   nothing (the positions round back, the velocities come out zero or wrong): it is
//!   refused with a typed error and the state kept, in f32 and f64; a short step that
//!   does resolve the move gives Stokes' settling speed `F / (6 pi eta a)` of a lone
//!   sphere (RPY self-mobility, no wall);
//! * a sphere touching a wall far from the origin in f32, where the coordinates'
//!   spacing (2 at 3e7) exceeds its radius: the input check and the step agree (both
//!   refuse it as below the wall; before, the check passed it and the step refused).

use crate::common;

use std::f64::consts::PI;

use common::*;
use hydrorattle::{
    Layout, Method, NoForce, ParticleError, Real, SolverKind, StepError, Wall, check_step, step,
};
use hydrorattle_heap::Buffers;

/// Stokes' speed of a sphere of radius 1 and density `RHO` in unit viscosity and
/// gravity: `(4/3 pi a^3 rho g) / (6 pi eta a)`.
fn stokes() -> f64 {
    4.0 / 3.0 * PI * RHO / (6.0 * PI)
}

/// The schemes whose step moves the positions by the unconstrained velocity times `dt`
/// (overdamped, both orders, and springs): each is judged on that move.
const JUDGED: [Method; 3] = [Method::Overdamped, Method::Overdamped2, Method::Springs];

/// Two spheres far apart near `(x0, 0, 5)` (a loose pair: the pair's coupling is below
/// 1e-3 of the speed), one step of `dt` by `method`.
fn one_step<T: Real>(
    method: Method,
    dt: f64,
    x0: f64,
) -> (Result<(), StepError>, Vec<u64>, Vec<u64>, f64) {
    let s = |x: f64| Sphere {
        pos: [x, 0.0, 5.0],
        radius: 1.0,
        density: RHO,
    };
    let mut ps = particles::<T, 2>(&[s(x0), s(x0 + 2000.0)]);
    let mut p = params::<T>(dt, method, SolverKind::Newton);
    p.gravity = v3::<T>(0.0, 0.0, -1.0);
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
    let bonds = hydrorattle::BondSet::<T, 1>::new();
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut store.workspace(), &mut NoForce).map(|_| ());
    let speed = -f64s::<T>(ps.vel[0])[2];
    (r, before, snapshot(&ps), speed)
}

fn tiny_steps_are_refused<T: Real>(method: Method) {
    // Coordinates about 1 (spacing eps): the move `dt U` must reach about eps.
    for dt in [1e-20, 1e-30, f64::from_bits(1), pick::<T>(1e-9, 1e-18)] {
        let dt = T::from_f64(dt).to_f64();
        if dt == 0.0 {
            continue; // Rounds to zero in f32: the zero-step check's case.
        }
        let (r, before, after, _) = one_step::<T>(method, dt, 1.0);
        assert!(
            matches!(r, Err(StepError::BadParameter(name)) if name.starts_with("dt")),
            "{method:?} dt {dt:e}: {r:?}"
        );
        assert_eq!(before, after, "{method:?} dt {dt:e}: state kept");
    }
    // Far from the origin the spacing is larger: a step that resolves the move at 1
    // does not at 1e6 (f64: 1e-13 moves by 2e-14, the spacing at 1e6 is 1.2e-10).
    let far = pick::<T>(1e6, 1e6);
    let dt = pick::<T>(1e-4, 1e-13);
    let (r, _, _, speed) = one_step::<T>(method, dt, 1.0);
    assert!(r.is_ok(), "dt {dt:e} near the origin: {r:?}");
    let rel = (speed - stokes()).abs() / stokes();
    // Resolved: the speed within the rounding of the move (a spacing over `dt U`)
    // and the pair's coupling.
    let spacing = T::EPSILON.to_f64() * 5.0;
    let allowed = spacing / (dt * stokes()) + 2e-3;
    assert!(
        rel <= allowed,
        "dt {dt:e}: speed {speed}, Stokes {}",
        stokes()
    );
    let (r, _, _, _) = one_step::<T>(method, dt, far);
    assert!(
        matches!(r, Err(StepError::BadParameter(_))),
        "dt {dt:e} at {far:e}: {r:?}"
    );
}

#[test]
fn tiny_steps_are_refused_f64() {
    for method in JUDGED {
        tiny_steps_are_refused::<f64>(method);
    }
}

#[test]
fn tiny_steps_are_refused_f32() {
    for method in JUDGED {
        tiny_steps_are_refused::<f32>(method);
    }
}

/// A sphere of radius 1 touching a wall at `height` as written in f64 (centre at
/// `height + 1`), checked and stepped in `T` with contacts: the check and the step
/// give the same answer.
fn wall_check_agrees_with_step<T: Real>(height: f64) -> Result<(), StepError> {
    let s = Sphere {
        pos: [0.0, 0.0, height + 1.0],
        radius: 1.0,
        density: RHO,
    };
    let mut ps = particles::<T, 1>(&[s]);
    let mut p = params::<T>(0.01, Method::Overdamped, SolverKind::Newton);
    p.wall = Some(Wall::new(T::from_f64(height)));
    p.contacts = Some(hydrorattle::Contacts::new(4));
    let bonds = hydrorattle::BondSet::<T, 1>::new();
    let checked = check_step(&ps.state(), bonds.as_slice(), &p);
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
    let stepped = step(&mut ps, &bonds, &p, &mut store.workspace(), &mut NoForce).map(|_| ());
    assert_eq!(
        checked, stepped,
        "height {height:e}: check and step disagree"
    );
    stepped
}

#[test]
fn a_wall_far_from_the_origin_is_checked_as_the_step_sees_it() {
    // f32 at -3e7: the centre rounds onto the plane (spacing 2): refused by both.
    let below = Err(StepError::Particle(ParticleError::BelowWall {
        particle: 0,
    }));
    assert_eq!(wall_check_agrees_with_step::<f32>(-3e7), below);
    // f64 there, and f32 near the origin: touching is fine.
    assert_eq!(wall_check_agrees_with_step::<f64>(-3e7), Ok(()));
    assert_eq!(wall_check_agrees_with_step::<f32>(-3.0), Ok(()));
}
