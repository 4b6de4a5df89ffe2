//! Free draining has no pair term: its matrix-free product is the diagonal alone, `O(N)`
//! (no pair visited), with the bits the banded all-pairs product gave (each row its
//! self term plus the pairs' zero blocks). Checked against the closed form
//! `u_i = f_i / (6 pi eta a_i)`, against the stored product bit for bit, and by a pair
//! the all-pairs product could not pass: two nested spheres, which any pair visit
//! refuses (`ParticleError::Nested`), are no error to a product that visits none. A
//! lattice of 50,000 free-draining spheres then takes a matrix-free step (its start
//! and acceptance checks run over the cell list).
//!
//! `cargo test --release --test kernel free_draining::`

use crate::common;

use std::f64::consts::PI;

use common::*;
use hydrorattle::glam::DVec3;
use hydrorattle::parallel::{self, Serial, band_scratch};
use hydrorattle::{
    BondSet, Hydro, Layout, Method, NoForce, Params, Particle, ParticleSet, SolverKind, step,
};
use hydrorattle_heap::Buffers;

/// Spheres on a jittered cubic lattice of spacing 3 (radii 0.5 to 1.2), a force each.
fn lattice(n: usize) -> (Vec<DVec3>, Vec<f64>, Vec<DVec3>) {
    let side = (n as f64).cbrt().ceil() as usize;
    let mut rng = common::fuzz::Rng(5);
    let (mut pos, mut radius, mut force) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..n {
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        let mut jitter = || 0.2 * (rng.unit() - 0.5);
        pos.push(DVec3::new(
            3.0 * i as f64 + jitter(),
            3.0 * j as f64 + jitter(),
            3.0 * l as f64 + jitter(),
        ));
        radius.push(0.5 + 0.7 * rng.unit());
        force.push(DVec3::new(rng.unit() - 0.5, -0.0, 1.0 - k as f64));
    }
    (pos, radius, force)
}

#[test]
fn the_free_draining_product_is_the_diagonal() {
    let eta = 1.3;
    let (mut pos, mut radius, force) = lattice(200);
    // Sphere 1 inside sphere 0: a pair an all-pairs product refuses.
    pos[1] = pos[0] + DVec3::new(0.1, 0.0, 0.0);
    (radius[0], radius[1]) = (1.2, 0.5);
    let n = pos.len();
    let mut u = vec![DVec3::ZERO; n];
    let mut z = vec![DVec3::ZERO; band_scratch(n)];
    parallel::free_product::<f64>(
        &Serial,
        Hydro::FreeDraining,
        eta,
        &pos,
        &radius,
        &force,
        &mut u,
        &mut z,
    )
    .expect("no pair is visited, nested or not");
    for i in 0..n {
        let exact = force[i] / (6.0 * PI * eta * radius[i]);
        let err = (u[i] - exact).length() / exact.length();
        assert!(
            err <= 4e-16,
            "sphere {i}: {} against {exact}, {err:e}",
            u[i]
        );
        // A `-0` force component gives `+0`, as the sum over zero pair blocks did.
        assert_eq!(u[i].y.to_bits(), 0, "sphere {i}");
    }
}

/// A free-draining step matrix-free and stored: the same bits.
#[test]
fn free_draining_matrix_free_keeps_the_stored_bits() {
    const N: usize = 64;
    let (pos, radius, _) = lattice(N);
    let list: Vec<Particle<f64>> = (0..N)
        .map(|i| Particle::new(pos[i], radius[i], 3.0))
        .collect();
    let bits = |matrix_free: bool| {
        let mut ps = ParticleSet::<f64, N>::from_slice(&list, false).unwrap();
        let mut p = params::<f64>(0.05, Method::Overdamped, SolverKind::Auto);
        p.hydro = Hydro::FreeDraining;
        p.matrix_free = matrix_free;
        let bonds = BondSet::<f64, 1>::new();
        let mut store = Buffers::<f64>::new(Layout::for_params(&p, N, 0));
        for _ in 0..3 {
            step(&mut ps, &bonds, &p, &mut store.workspace(), &mut NoForce).unwrap();
        }
        snapshot(&ps)
    };
    assert_eq!(bits(true), bits(false));
}

/// 50,000 free-draining spheres, one matrix-free step: set-up (the particle set's pair
/// check) and the step (product, acceptance) over the cell list and the diagonal.
/// Before, the product alone visited every pair (1.25e9 a product).
#[test]
fn fifty_thousand_free_draining_spheres_step() {
    // The particle set is built on the stack before it is boxed.
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(fifty_thousand)
        .unwrap()
        .join()
        .unwrap();
}

fn fifty_thousand() {
    const N: usize = 50_000;
    let (pos, radius, _) = lattice(N);
    let list: Vec<Particle<f64>> = (0..N)
        .map(|i| Particle::new(pos[i], radius[i], 3.0))
        .collect();
    let mut ps: Box<ParticleSet<f64, N>> =
        Box::new(ParticleSet::from_slice(&list, false).expect("no overlap"));
    let mut p: Params<f64> = params(0.05, Method::Overdamped, SolverKind::Auto);
    p.hydro = Hydro::FreeDraining;
    p.matrix_free = true;
    let bonds = BondSet::<f64, 1>::new();
    let mut store = Buffers::<f64>::new(Layout::for_params(&p, N, 0));
    let z0 = ps.pos[N - 1].z;
    step(&mut *ps, &bonds, &p, &mut store.workspace(), &mut NoForce).unwrap();
    // Each sphere sinks by its own Stokes speed times dt, nothing else.
    let w = |a: f64| 4.0 / 3.0 * PI * a.powi(3) * 3.0;
    let expect = z0 - 0.05 * w(radius[N - 1]) / (6.0 * PI * p.viscosity * radius[N - 1]);
    assert!((ps.pos[N - 1].z - expect).abs() <= 1e-12 * z0.abs().max(1.0));
}
