//! `RattleStable` at temperature: Langevin dynamics with the
//! implicit hydrodynamic drag, checked against exact results.
//!
//! Units: a unit sphere of mass `m = 1` (density `3 / 4 pi`) in a fluid of viscosity
//! `1 / 6 pi`, so `zeta = 6 pi eta a = 1`, the velocity relaxation time `m / zeta = 1`
//! and `h = zeta dt / m = dt`; `kT = 1`; no gravity. Exact values:
//!
//! * continuous time (every `dt -> 0` check): `<m v_x^2> = kT`; the velocity
//!   autocorrelation `<v_x(0) v_x(t)> = (kT / m) exp(-zeta t / m)`; a trimer with two
//!   rigid bonds has `<K> = (3N - B) kT / 2 = 7/2`;
//! * the discretised scheme `(m + zeta dt) v' = m v + g dt`, `<g^2> = 2 kT zeta / dt`
//!   (the kernel's choice, `src/integrate/stable.rs`), for any `dt`: `v' = c v + noise`
//!   with `c = 1 / (1 + h)`, stationary `<(m + zeta dt / 2) v_x^2> = kT`, and the
//!   displacement over `L` steps `<X^2> = 2 (kT / zeta) L dt - (kT m / zeta^2) 4 (1 + h)
//!   / (2 + h) (1 - c^L)` (the discrete Ornstein-Uhlenbeck sums; long-time diffusion
//!   exactly `kT / zeta`).
//!
//! Each statistical check uses block standard errors, asserts its own power, and
//! states the time-step bias it expects.

use crate::common;

use common::thermal::block_mean;
use common::*;
use hydrorattle::{
    BondSet, Brownian, Hydro, Layout, Method, NoForce, Noise, NoiseSqrt, ParticleSet, Real,
    SolverKind, StepError, step,
};
use hydrorattle_heap::Buffers;
use std::f64::consts::PI;

/// Density of a unit sphere of mass 1.
const RHO: f64 = 3.0 / (4.0 * PI);

/// `RattleStable` at `kT = 1`, `zeta = 1` per unit sphere, no gravity.
fn langevin<T: Real>(dt: f64, hydro: Hydro) -> hydrorattle::Params<T> {
    let mut p = params::<T>(dt, Method::RattleStable, SolverKind::Auto);
    p.viscosity = T::from_f64(1.0 / (6.0 * PI));
    p.gravity = T::V3_ZERO;
    p.hydro = hydro;
    p.brownian = Some(Brownian::new(T::ONE));
    p
}

fn unit(pos: [f64; 3]) -> Sphere {
    Sphere {
        pos,
        radius: 1.0,
        density: RHO,
    }
}

/// `steps` steps of a lone sphere (seed `seed`), calling `observe(position, velocity,
/// angular velocity)` after each.
fn lone(
    p: &hydrorattle::Params<f64>,
    seed: u64,
    steps: usize,
    mut observe: impl FnMut([f64; 3], [f64; 3], [f64; 3]),
) {
    let mut ps: ParticleSet<f64, 1> = particles(&[unit([0.0; 3])]);
    ps.noise = Some(Noise::new(seed));
    let bonds = BondSet::<f64, 0>::new();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, 1, 0));
    let mut ws = buf.workspace();
    for k in 0..steps {
        step(&mut ps, &bonds, p, &mut ws, &mut NoForce).unwrap_or_else(|e| panic!("step {k}: {e}"));
        observe(
            ps.pos[0].to_array(),
            ps.vel[0].to_array(),
            ps.omega[0].to_array(),
        );
    }
}

/// The discrete scheme at `h = 1` (dt = the relaxation time), where it is far from
/// continuous time: `<(m + zeta dt / 2) v_x^2> = kT` exactly, i.e. `<m v_x^2> = 2/3`
/// (the impulse covariance that makes `<m v^2> = kT` exact would give 1 instead), and
/// the displacement over 10 steps has the discrete Ornstein-Uhlenbeck value 17.336
/// (continuous time: 18; the exact-equipartition covariance: 27.3). With rotation the
/// same for the spin: moment `I = 2/5`, rotational drag `8 pi eta a^3 = 4/3`, so
/// `<(I + 2/3 dt) w_x^2> = kT`. 2e5 steps: standard errors 0.3 % (velocities) and
/// 0.6 % (displacements).
#[test]
fn lone_sphere_discrete_equipartition_and_diffusion_at_dt_equal_to_the_relaxation_time() {
    let dt = 1.0;
    let mut p = langevin::<f64>(dt, Hydro::Rpy);
    p.rotation = true;
    let (steps, lag) = (200_000, 10);
    let (mut v2, mut w2, mut x2) = (Vec::new(), Vec::new(), Vec::new());
    let mut origin = [0.0; 3];
    let mut k = 0;
    lone(&p, 11, steps, |x, v, w| {
        v2.push(v.iter().map(|c| c * c).sum::<f64>() / 3.0);
        w2.push(w.iter().map(|c| c * c).sum::<f64>() / 3.0);
        k += 1;
        if k % lag == 0 {
            x2.push((0..3).map(|c| (x[c] - origin[c]).powi(2)).sum::<f64>() / 3.0);
            origin = x;
        }
    });
    let (h, c) = (dt, 1.0 / (1.0 + dt));
    let (mv2, se) = block_mean(&v2, 50);
    let want = 1.0 / (1.0 + h / 2.0);
    eprintln!("h = 1: <m v_x^2> = {mv2:.5} +- {se:.5}, exact for the scheme {want:.5}");
    assert!(se < 0.005 && (mv2 - want).abs() < 3.0 * se);
    let (i, zr) = (0.4, 4.0 / 3.0);
    let (iw2, se_w) = block_mean(&w2, 50);
    let want_w = 1.0 / (i + zr * dt / 2.0);
    eprintln!("h = 1: <w_x^2> = {iw2:.5} +- {se_w:.5}, exact for the scheme {want_w:.5}");
    assert!(se_w < 0.005 * want_w && (iw2 - want_w).abs() < 3.0 * se_w);
    let l = lag as f64;
    let msd = 2.0 * l * dt - 4.0 * (1.0 + h) / (2.0 + h) * (1.0 - c.powi(lag));
    let (mx2, se_x) = block_mean(&x2, 50);
    eprintln!(
        "h = 1: <X^2> over {lag} steps = {mx2:.4} +- {se_x:.4}, exact for the scheme {msd:.4}"
    );
    assert!(se_x < 0.01 * msd && (mx2 - msd).abs() < 3.0 * se_x);
    // The continuous-time value is 4 % away: resolved.
    assert!((18.0 - msd).abs() > 6.0 * se_x);
}

/// Continuous time: at `h = 0.002` the stationary `<m v_x^2> = 1 / (1 + h/2)` is 0.1 %
/// below `kT`, and the velocity autocorrelation `c^n = exp(-n ln(1 + h))` is 0.1 % above
/// `exp(-zeta t / m)` at `t = m / zeta` (0.2 % at `2 m / zeta`): both under a fifth of the
/// standard errors of 3.2e6 steps (T = 6400 relaxation times). The autocorrelation at
/// lags 0.5, 1 and 2 relaxation times, per block, from every 10th step.
#[test]
fn lone_sphere_equipartition_and_velocity_autocorrelation() {
    let dt = 0.002;
    let p = langevin::<f64>(dt, Hydro::FreeDraining);
    let steps = 3_200_000;
    let mut v = Vec::with_capacity(steps / 10);
    let mut k = 0;
    lone(&p, 12, steps, |_, vel, _| {
        k += 1;
        if k % 10 == 0 {
            v.push(vel);
        }
    });
    let blocks = 40;
    let len = v.len() / blocks;
    for lag_t in [0.0, 0.5, 1.0, 2.0] {
        let lag = (lag_t / (10.0 * dt)).round() as usize;
        let per_block: Vec<f64> = v
            .chunks_exact(len)
            .map(|b| {
                let pairs = b.len() - lag;
                (0..pairs)
                    .map(|s| (0..3).map(|c| b[s][c] * b[s + lag][c]).sum::<f64>() / 3.0)
                    .sum::<f64>()
                    / pairs as f64
            })
            .collect();
        let (m, se) = block_mean(&per_block, blocks);
        let want = (-lag_t).exp();
        eprintln!("C({lag_t}) = {m:.5} +- {se:.5}, exact kT/m exp(-zeta t/m) = {want:.5}");
        assert!(se < 0.012, "too few samples: {se}");
        assert!(
            (m - want).abs() < 3.0 * se,
            "lag {lag_t}: {m} vs {want} (se {se})"
        );
    }
}

/// A trimer of unit spheres, two rigid bonds of length 3 (free draining and RPY): its
/// mean kinetic energy is `(3N - B) kT / 2 = 3.5` as `dt -> 0`. The time-step bias is
/// smaller than the lone sphere's `-h/2` (measured free draining at `h = 0.1`: 3.442
/// +- 0.012, -1.6 %, against -5 %), so at `h = 0.01` about -0.16 %, a quarter of the
/// standard error of 6e5 steps (6000 relaxation times, 0.65 %). The bonds hold to the
/// solver's tolerance.
fn trimer_kinetic_energy(hydro: Hydro, seed: u64) {
    let dt = 0.01;
    let mut p = langevin::<f64>(dt, hydro);
    // Freely jointed: the end beads may pass through each other.
    p.allow_overlap = true;
    let mut ps: ParticleSet<f64, 3> =
        particles(&[unit([0.0; 3]), unit([3.0, 0.0, 0.0]), unit([3.0, 3.0, 0.0])]);
    let bonds: BondSet<f64, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
    ps.noise = Some(Noise::new(seed));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 3, 2));
    let mut ws = buf.workspace();
    let steps = 600_000;
    let mut ke = Vec::with_capacity(steps);
    let mut worst: f64 = 0.0;
    for k in 0..steps {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        if k >= 2_000 {
            ke.push(ps.vel.iter().map(|v| 0.5 * v.length_squared()).sum::<f64>());
        }
        worst = worst.max(bonds.max_residual(&ps.pos).1);
    }
    let (m, se) = block_mean(&ke, 50);
    eprintln!(
        "trimer {hydro:?}: <K> = {m:.4} +- {se:.4}, exact (3N - B) kT/2 = 3.5; bonds within {worst:.1e}"
    );
    assert!(se < 0.01 * 3.5, "too few samples: {se}");
    assert!((m - 3.5).abs() < 3.0 * se, "{m} vs 3.5 (se {se})");
    // Without the projection of the velocities it would be 4.5 (3N/2).
    assert!(4.5 - m > 10.0 * se);
    assert!(worst < 1e-8);
}

#[test]
fn trimer_kinetic_energy_free_draining() {
    trimer_kinetic_energy(Hydro::FreeDraining, 21);
}

#[test]
fn trimer_kinetic_energy_rpy() {
    trimer_kinetic_energy(Hydro::Rpy, 22);
}

/// The same seed gives the same bits (f32 and f64, with and without rotation); a step
/// refused after the deviates were drawn (a constraint solve capped at one sweep)
/// leaves the state and the generator as they were; the Lanczos square root is refused
/// by name (the drag is factored densely), `Auto` runs Cholesky; `kT = 0` is the
/// deterministic step bit for bit.
fn determinism_and_refusals<T: Real>() {
    let trimer = || -> ParticleSet<T, 3> {
        particles(&[unit([0.0; 3]), unit([3.0, 0.0, 0.0]), unit([3.0, 3.0, 0.0])])
    };
    let bonds: BondSet<T, 2> = BondSet::chain(&trimer().pos[..3]).unwrap();
    let mut buf = Buffers::<T>::new(Layout::all(3, 2));
    for rotation in [false, true] {
        let mut p = langevin::<T>(0.05, Hydro::Rpy);
        p.rotation = rotation;
        let run = |p: &hydrorattle::Params<T>, buf: &mut Buffers<T>| {
            let mut ps = trimer();
            ps.noise = Some(Noise::new(5));
            let mut ws = buf.workspace();
            for _ in 0..50 {
                step(&mut ps, &bonds, p, &mut ws, &mut NoForce).unwrap();
            }
            ps
        };
        let (a, b) = (run(&p, &mut buf), run(&p, &mut buf));
        assert_eq!(snapshot(&a), snapshot(&b));
        assert_ne!(a.noise, Some(Noise::new(5)), "the generator advanced");
        let mut q = p;
        q.brownian = Some(Brownian::new(T::ZERO));
        let mut det = p;
        det.brownian = None;
        assert_eq!(snapshot(&run(&q, &mut buf)), snapshot(&run(&det, &mut buf)));
        assert_ne!(snapshot(&run(&q, &mut buf)), snapshot(&a));
        // Refusals after drawing, and by name: state and generator kept.
        let mut ps = a.clone();
        let before = snapshot(&ps);
        let mut capped = p;
        capped.solver.kind = SolverKind::Sweep;
        capped.solver.max_iterations = 1;
        let mut lanczos = p;
        lanczos.noise_sqrt = NoiseSqrt::Lanczos;
        for (bad, what) in [(capped, "one sweep"), (lanczos, "Lanczos")] {
            let r = step(&mut ps, &bonds, &bad, &mut buf.workspace(), &mut NoForce);
            let refused = |e: &StepError| {
                matches!(
                    e,
                    StepError::NoConvergence { .. } | StepError::Unsupported(_)
                )
            };
            assert_failed_unchanged(&before, &ps, &r, refused, what);
            assert_eq!(ps.noise, a.noise, "{what}: generator changed");
        }
    }
}

both_precisions! {
    determinism => determinism_and_refusals;
}
