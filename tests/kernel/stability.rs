//! The explicit-drag scheme (Method::Rattle, the paper's) is stable only for
//! `dt < 2 m / zeta` (`zeta = 6 pi eta a`); beyond it the step must fail with an error
//! and leave the state untouched. The implicit-drag scheme stays bounded at any `dt`.
//!
//! Lone sphere, explicit drag, no force: `v' = v - dt (zeta/m) v = (1 - dt/tau) v` with
//! `tau = m / zeta`, stable iff `|1 - dt/tau| < 1`, i.e. `dt < 2 tau`.

use crate::common;

use common::*;
use hydrorattle::{BondSet, Method, NoForce, ParticleSet, Real, SolverKind, StepError, step};
use std::f64::consts::PI;

/// Momentum relaxation time `m / (6 pi eta a)` (eta = 1).
fn tau(a: f64, density: f64) -> f64 {
    4.0 / 3.0 * PI * a.powi(3) * density / (6.0 * PI * a)
}

/// Kinetic energy in `f64`.
fn kinetic<T: Real, const N: usize>(ps: &ParticleSet<T, N>) -> f64 {
    (0..ps.len())
        .map(|i| {
            let v = f64s::<T>(ps.vel[i]);
            0.5 * ps.mass(i).to_f64() * dot(v, v)
        })
        .sum()
}

/// Runs `steps` explicit-drag steps with gravity off from a fixed pattern of initial
/// velocities (every mode excited) and reports divergence: a returned error, or the
/// kinetic energy growing beyond 4 times its initial value (stable runs only lose it).
fn diverges<T: Real, const N: usize>(spheres: &[Sphere], dt: f64, steps: usize) -> bool {
    let mut ps: ParticleSet<T, N> = particles(spheres);
    let n = ps.len();
    for i in 0..n {
        let k = i as f64;
        ps.vel[i] = v3::<T>(
            0.1 + 0.1 * (1.3 * k).sin(),
            0.1 * (2.1 * k + 0.5).cos(),
            0.1 * (0.7 * k).sin(),
        );
    }
    let bonds: BondSet<T, N> = BondSet::chain(&ps.pos[..n]).unwrap();
    let mut p = params::<T>(dt, Method::Rattle, SolverKind::Newton);
    p.gravity = T::V3_ZERO;
    p.allow_overlap = true;
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(N, N));
    let mut ws = ws_store.workspace();
    let e0 = kinetic(&ps);
    for _ in 0..steps {
        if step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).is_err() || kinetic(&ps) > 4.0 * e0 {
            return true;
        }
    }
    false
}

/// Largest stable `dt` by bisection on a log scale, to relative precision 1e-3.
fn empirical_limit<T: Real, const N: usize>(spheres: &[Sphere], lo: f64, hi: f64) -> f64 {
    let steps = 400;
    let (mut lo, mut hi) = (lo, hi);
    assert!(
        !diverges::<T, N>(spheres, lo, steps),
        "dt {lo} should be stable"
    );
    assert!(
        diverges::<T, N>(spheres, hi, steps),
        "dt {hi} should be unstable"
    );
    while hi / lo > 1.001 {
        let mid = (lo * hi).sqrt();
        if diverges::<T, N>(spheres, mid, steps) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

/// The guard's estimate, read from the `Unstable` error of a huge step.
fn guard_limit<T: Real, const N: usize>(spheres: &[Sphere]) -> f64 {
    let mut ps: ParticleSet<T, N> = particles(spheres);
    let n = ps.len();
    let bonds: BondSet<T, N> = BondSet::chain(&ps.pos[..n]).unwrap();
    let mut p = params::<T>(1e6, Method::Rattle, SolverKind::Newton);
    p.stability_guard = true;
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(N, N));
    let mut ws = ws_store.workspace();
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    assert_failed_unchanged(
        &before,
        &ps,
        &r,
        |e| matches!(e, StepError::Unstable { .. }),
        "guard",
    );
    match r {
        Err(StepError::Unstable { limit, dt }) => {
            assert_eq!(dt, 1e6);
            limit
        }
        _ => unreachable!(),
    }
}

fn lone_sphere_limit<T: Real>() {
    let (a, rho) = (1.3, 2.0);
    let two_tau = 2.0 * tau(a, rho);
    let lone = [Sphere {
        pos: [0.0; 3],
        radius: a,
        density: rho,
    }];
    let found = empirical_limit::<T, 1>(&lone, 0.5 * two_tau, 2.0 * two_tau);
    let guard = guard_limit::<T, 1>(&lone);
    eprintln!(
        "lone sphere: empirical explicit-drag limit {found:.5} = {:.4} x 2m/zeta ({two_tau:.5}); guard {guard:.6}",
        found / two_tau
    );
    assert!(
        (found / two_tau - 1.0).abs() < 0.02,
        "limit {found} vs 2m/zeta {two_tau}"
    );
    assert!(
        (guard / two_tau - 1.0).abs() < pick::<T>(1e-5, 1e-10),
        "guard {guard}"
    );
}

/// The paper's 25-bead helix (head 2^(1/3), tails 1, D = 1.5) and a dimer (radii 1, 2):
/// the empirical limit, reported relative to `2 m / zeta` of a tail. Bonds remove the
/// stiffest relative modes, so the guard's unconstrained estimate must not exceed it.
fn chain_limits<T: Real>() {
    let two_tau_tail = 2.0 * tau(1.0, RHO);
    let dimer = path(&[1.0, 2.0], &[[0.6, 0.0, 0.8]], 1.5, RHO);
    let found = empirical_limit::<T, 2>(&dimer, 0.2, 20.0);
    let guard = guard_limit::<T, 2>(&dimer);
    eprintln!(
        "dimer 1+2: empirical limit {found:.4} = {:.3} x 2m/zeta(small sphere); guard {guard:.4}",
        found / two_tau_tail
    );
    assert!(
        guard <= found * 1.002,
        "guard {guard} above empirical {found}"
    );
    let helix = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let found = empirical_limit::<T, 25>(&helix, 0.05, 10.0);
    let guard = guard_limit::<T, 25>(&helix);
    eprintln!(
        "25-bead helix: empirical limit {found:.4} = {:.3} x 2m/zeta(tail) ({two_tau_tail}); guard {guard:.4} = {:.3} x",
        found / two_tau_tail,
        guard / two_tau_tail
    );
    assert!(
        guard <= found * 1.002,
        "guard {guard} above empirical {found}"
    );
    assert!(found < 2.0 * two_tau_tail, "limit {found}");
}

/// Beyond the limit the explicit scheme blows up (the dimer's constraint solve gives up
/// first; the lone sphere overflows); the step that fails returns an
/// error and leaves the set bit-identical. Every state committed before is finite.
fn blow_up_is_an_error<T: Real>() {
    for (name, spheres) in [
        (
            "lone",
            vec![Sphere {
                pos: [0.0; 3],
                radius: 1.0,
                density: RHO,
            }],
        ),
        ("dimer", path(&[1.0, 2.0], &[[0.6, 0.0, 0.8]], 1.5, RHO)),
    ] {
        let mut ps: ParticleSet<T, 2> = particles(&spheres);
        let n = ps.len();
        let bonds: BondSet<T, 2> = BondSet::chain(&ps.pos[..n]).unwrap();
        let p = params::<T>(10.0 * tau(1.0, RHO), Method::Rattle, SolverKind::Newton);
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 2));
        let mut ws = ws_store.workspace();
        let mut failed = None;
        for k in 0..5000 {
            let before = snapshot(&ps);
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
            if let Err(e) = r {
                assert_eq!(
                    before,
                    snapshot(&ps),
                    "{name}: state changed by the failing step"
                );
                failed = Some((k, e));
                break;
            }
            for i in 0..n {
                assert!(
                    T::v3_is_finite(ps.pos[i]) && T::v3_is_finite(ps.vel[i]),
                    "{name}: non-finite state committed"
                );
            }
        }
        let (k, e) = failed.unwrap_or_else(|| panic!("{name}: never failed"));
        let vmax = (0..n)
            .map(|i| norm(f64s::<T>(ps.vel[i])))
            .fold(0.0, f64::max);
        eprintln!("{name} at dt = 10 m/zeta: step {k} failed with {e}; last |v| = {vmax:.3e}");
        if name == "lone" {
            // A lone sphere has no constraint solve that could fail first.
            assert!(vmax > 1e3, "{name}: failed before blowing up ({e})");
        }
    }
}

/// `stability_guard = true` refuses a step beyond the limit (and accepts one below).
fn guard_refuses<T: Real>() {
    let lone = [Sphere {
        pos: [0.0; 3],
        radius: 1.0,
        density: RHO,
    }];
    let two_tau = 2.0 * tau(1.0, RHO);
    let mut ps: ParticleSet<T, 1> = particles(&lone);
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut p = params::<T>(1.05 * two_tau, Method::Rattle, SolverKind::Newton);
    p.stability_guard = true;
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(1, 1));
    let mut ws = ws_store.workspace();
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    assert_failed_unchanged(
        &before,
        &ps,
        &r,
        |e| matches!(e, StepError::Unstable { .. }),
        "guard",
    );
    p.dt = T::from_f64(0.95 * two_tau);
    step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).expect("below the limit");
}

/// Implicit drag at `dt = 100 m/zeta`: a lone settling sphere goes straight to its Stokes
/// velocity (backward Euler: `v' = (tau v + dt U) / (tau + dt)`), and a chain with
/// random initial velocities and no gravity loses kinetic energy every step.
fn implicit_bounded<T: Real>() {
    let dt = 100.0 * tau(1.0, RHO);
    let lone = [Sphere {
        pos: [0.0; 3],
        radius: 1.0,
        density: RHO,
    }];
    let mut ps: ParticleSet<T, 1> = particles(&lone);
    let bonds: BondSet<T, 1> = BondSet::new();
    let p = params::<T>(dt, Method::RattleStable, SolverKind::Newton);
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(1, 1));
    let mut ws = ws_store.workspace();
    let mut v = 0.0;
    for _ in 0..50 {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
        v = (v + dt * 1.0) / (1.0 + dt);
        let got = f64s::<T>(ps.vel[0]);
        assert!(
            norm(sub(got, [0.0, 0.0, -v])) < pick::<T>(1e-5, 1e-12),
            "v = {got:?}, want {v}"
        );
    }
    let mut ps: ParticleSet<T, 8> = particles(&chain_scene().spheres);
    let n = ps.len();
    for i in 0..n {
        let k = i as f64;
        ps.vel[i] = v3::<T>((1.3 * k).sin(), (2.1 * k).cos(), (0.7 * k).sin());
    }
    let bonds: BondSet<T, 8> = BondSet::chain(&ps.pos[..n]).unwrap();
    let mut p = params::<T>(dt, Method::RattleStable, SolverKind::Newton);
    p.gravity = T::V3_ZERO;
    p.allow_overlap = true;
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
    let mut ws = ws_store.workspace();
    let mut e = kinetic(&ps);
    for k in 0..50 {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
        let e1 = kinetic(&ps);
        assert!(
            e1 <= e * (1.0 + 1e-6) + 1e-30,
            "step {k}: kinetic energy {e} -> {e1}"
        );
        e = e1;
    }
    assert!(bond_error(&ps, &bonds) < pick::<T>(2e-5, 2e-10));
}

/// Between the linear limit and outright blow-up, the explicit scheme on the helix does
/// not diverge: the unstable mode saturates into a period-2 shiver (velocities flip sign
/// every step, kinetic energy constant and far above the initial one, in a quiescent
/// fluid where it must decay) and every step "succeeds". The guard is the defence:
/// its estimate lies below the empirical limit, so it refuses such a `dt`.
fn silent_regime_needs_guard<T: Real>() {
    let spheres = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let dt = 0.8;
    assert!(
        diverges::<T, 25>(&spheres, dt, 400),
        "dt {dt} should be beyond the limit"
    );
    let mut ps: ParticleSet<T, 25> = particles(&spheres);
    let bonds: BondSet<T, 24> = BondSet::chain(&ps.pos[..25]).unwrap();
    let mut p = params::<T>(dt, Method::Rattle, SolverKind::Newton);
    p.gravity = T::V3_ZERO;
    p.stability_guard = true;
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(25, 24));
    let mut ws = ws_store.workspace();
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    assert_failed_unchanged(
        &before,
        &ps,
        &r,
        |e| matches!(e, StepError::Unstable { .. }),
        "guard on the helix",
    );
    eprintln!("helix at dt {dt}: guard says {}", r.unwrap_err());
}

both_precisions! {
    helix_silent_instability_caught_by_guard => silent_regime_needs_guard;
    lone_sphere_explicit_drag_limit_is_2m_over_zeta => lone_sphere_limit;
    chain_explicit_drag_limits => chain_limits;
    explicit_drag_blow_up_returns_error => blow_up_is_an_error;
    stability_guard_refuses_large_dt => guard_refuses;
    implicit_drag_bounded_at_100_tau => implicit_bounded;
}
