//! A falling cloud: the mean velocity of `N = 10^4` equal spheres placed by the
//! `[cloud]` generator, each pulled by the same force, from one fast free-space
//! product (`mobility::free_fast`), against the continuum result for a dilute
//! spherical cloud (Nitsche and Batchelor 1997): `U = U0 (1 + 6 N a / (5 R))`, `U0`
//! the Stokes speed of one sphere and `R` the radius of the ball the centres fill.
//!
//! Why the continuum value, and what the discrete cloud changes (derived, not fitted):
//!
//! * A ball of uniform force density `f` in fluid of the same viscosity moves as a
//!   Hadamard-Rybczynski drop of viscosity ratio 1, at `F_total / (5 pi eta R)`; the
//!   flow inside is `u_z = (f / 2 eta) (2 R^2 / 3 - 4 r^2 / 15 + 2 z^2 / 15)` (the
//!   Stokeslet convolved over the ball), whose mean over the ball is that speed. Each
//!   sphere adds its own Stokes speed `U0`: the mean sphere speed is `U` above.
//! * Self-exclusion: a sphere does not feel itself (`N - 1` others), nor spheres
//!   closer than `2a` (no overlaps): the continuum's Oseen velocity from a ball of
//!   radius `2a` about each sphere, `n (2a)^2 F / (3 eta) = 6 phi U0`, is missing
//!   (`phi = N a^3 / R^3`). The RPY correction beyond `2a`, a potential dipole, has no
//!   mean over such a ball's complement inside the cloud (the uniform ball's Newtonian
//!   potential is quadratic), so the expected mean speed is
//!   `U0 (1 + 6 (N - 1) a / (5 R) - 6 phi)`, up to `O(phi a / R)` from the spheres
//!   within `2a` of the surface and `O(phi^2)` from the placement's pair correlation.
//! * Sampling: the mean over the spheres of the pair sum is a U-statistic whose
//!   standard deviation is `2 sqrt(N) sigma_1`, `sigma_1` the spread over the ball of
//!   the continuum speed per sphere: the relative spread of `u_z` above over a uniform
//!   ball is `s = sqrt(160 / 39375) (15 / 8) = 0.1195`, so one cloud's mean speed
//!   scatters by `sigma = 2 s (6 / 5) sqrt(N) a / R` times `U0`.
//!
//! The test averages three seeds and asks for the expected value within 4 standard
//! deviations of that mean (`4 sigma / sqrt(3)`); the product's own error (tolerance
//! 1e-4 of the speed, relative) is some 50 times smaller.

use hydrorattle::Real;
use hydrorattle::mobility::free_fast::FreeFast;
use hydrorattle_heap::FreeBuffers;
use hydrorattle_host::scene::Cloud;

#[test]
fn a_falling_cloud_moves_at_the_continuum_speed_within_its_finite_n_correction() {
    let (n, a, room) = (10_000usize, 1.0, 100.0);
    let eta = 1.0;
    let u0 = 1.0 / (6.0 * std::f64::consts::PI * eta * a);
    let ff = FreeFast::<f64>::new(a, 1e-4, [2.0 * room; 3], n).unwrap();
    let size = ff.storage(n);
    let mut arrays = FreeBuffers::new(size);
    let mut store = arrays.storage();
    let seeds = [1, 2, 3];
    let mut speeds = Vec::new();
    for seed in seeds {
        let cloud = Cloud {
            count: n,
            cloud_radius: room + a,
            radius: a,
            polydispersity: 0.0,
            density: 1.0,
            centre: [0.0; 3],
            seed,
        };
        let ps = cloud.generate().unwrap();
        let pos: Vec<_> = ps.iter().map(|p| f64::v3_from(p.position)).collect();
        let radius = vec![a; n];
        let force = vec![f64::v3_from([0.0, 0.0, -1.0]); n];
        let mut u = vec![f64::V3_ZERO; n];
        ff.apply(eta, &pos, &radius, &force, &mut u, &mut store)
            .unwrap();
        let mean = -u.iter().map(|v| f64::v3_to_f64(*v)[2]).sum::<f64>() / n as f64;
        speeds.push(mean / u0);
    }
    let measured = speeds.iter().sum::<f64>() / seeds.len() as f64;
    let phi = n as f64 * (a / room).powi(3);
    let continuum = 1.0 + 6.0 * n as f64 * a / (5.0 * room);
    let expected = 1.0 + 6.0 * (n - 1) as f64 * a / (5.0 * room) - 6.0 * phi;
    let s = (160.0f64 / 39375.0).sqrt() * 15.0 / 8.0;
    let sigma = 2.0 * s * 1.2 * (n as f64).sqrt() * a / room / (seeds.len() as f64).sqrt();
    println!(
        "falling cloud, N = {n}, R/a = {room}: U/U0 per seed {speeds:?}, mean {measured:.4}; \
         continuum {continuum:.4}, with the finite-N correction {expected:.4}, sigma {sigma:.4}"
    );
    assert!(
        (measured - expected).abs() < 4.0 * sigma,
        "U/U0 = {measured}, expected {expected} +- {sigma}"
    );
}
