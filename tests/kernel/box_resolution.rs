//! Coordinates a periodic box cannot resolve: a centre so far from the origin that the
//! spacing of its coordinates reaches half its radius leaves nothing of the minimum
//! image (`x - round(x / L) L` is rounding). Such a position given at the start, or a
//! step that would carry a sphere there (gravity of 1e160), is refused by name
//! (`ParticleError::Unresolved`), the state kept, instead of as a pair of nested
//! spheres; a far but resolved position still steps.

use crate::common::*;
use hydrorattle::{
    Layout, Method, NoForce, ParticleError, Periodic, Real, SolverKind, StepError, step,
};
use hydrorattle_heap::Buffers;

/// Two spheres of radius 1 in a box of 10, the first at `x0` along x, gravity `g`
/// downwards; one Overdamped step of 0.01. The second is neutrally buoyant, so that
/// the first settles through the box (equal weights would only move the fluid: the
/// box's mean velocity is zero).
fn one_step<T: Real>(x0: f64, g: f64) -> (Result<(), StepError>, Vec<u64>, Vec<u64>) {
    let s = |x: f64, density: f64| Sphere {
        pos: [x, 0.0, 0.0],
        radius: 1.0,
        density,
    };
    let mut ps = particles::<T, 2>(&[s(x0, RHO), s(4.0, 0.0)]);
    let mut p = params::<T>(0.01, Method::Overdamped, SolverKind::Newton);
    p.gravity = v3::<T>(0.0, 0.0, -g);
    let edge = T::from_f64(10.0);
    p.periodic = Some(Periodic::new([edge; 3]).expect("a valid box"));
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
    let bonds = hydrorattle::BondSet::<T, 1>::new();
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut store.workspace(), &mut NoForce).map(|_| ());
    (r, before, snapshot(&ps))
}

fn far_coordinates_are_named<T: Real>() {
    let unresolved = Err(StepError::Particle(ParticleError::Unresolved {
        particle: 0,
    }));
    // Given there: refused before anything is computed.
    let (r, before, after) = one_step::<T>(pick::<T>(1e30, 1e300), 1.0);
    assert_eq!(r, unresolved, "a centre at 1e300");
    assert_eq!(before, after, "state kept");
    // Carried there by the step (a settling speed of about 1e160, 1e30 in f32).
    let (r, before, after) = one_step::<T>(0.0, pick::<T>(1e30, 1e160));
    assert!(
        matches!(
            r,
            Err(StepError::Particle(ParticleError::Unresolved { .. }))
        ),
        "gravity of 1e160: {r:?}"
    );
    assert_eq!(before, after, "state kept");
    // Far from the origin but resolved (spacing well below the radius): it steps.
    let (r, _, _) = one_step::<T>(pick::<T>(1e4, 1e12), 1.0);
    assert_eq!(r, Ok(()), "a centre far out but resolved");
}

#[test]
fn far_coordinates_are_named_f64() {
    far_coordinates_are_named::<f64>();
}

#[test]
fn far_coordinates_are_named_f32() {
    far_coordinates_are_named::<f32>();
}
