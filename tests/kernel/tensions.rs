//! Bond tensions of every method in both precisions: the vertical
//! settling dimer against its closed form, and a chain's f32 tensions against f64.
//!
//! Before the fix the inertial methods' f32 tensions were the position multipliers,
//! rounding noise once the constraint displacement `dt^2 F / m` falls below an f32
//! position's rounding (`-0` for every bond at `dt = 0.001`).

use crate::common;

use common::*;
use hydrorattle::{BondSet, Method, NoForce, ParticleSet, Real, SolverKind, Workspace};
use std::f64::consts::PI;

const A1: f64 = 1.0;
const A2: f64 = 2.0;
const D: f64 = 4.5;

/// Tension and velocity of a rigid dimer, centres `d` apart, settling vertically with
/// the big sphere below (RPY far field, `eta = 1`, `|g| = 1`, density `RHO`, no fluid
/// density).
///
/// Both spheres move with one velocity `U`: with the pair block along the bond
/// `M = A + B` (see tests/kernel/dynamics.rs), `mu_k = 1 / (6 pi a_k)`, buoyant weights
/// `W_k = 4/3 pi a_k^3 RHO` and `T` pulling the small sphere down and the big one up,
/// `mu_1 (W_1 + T) + M (W_2 - T) = M (W_1 + T) + mu_2 (W_2 - T)`, so
/// `T = [(mu_2 - M) W_2 - (mu_1 - M) W_1] / (mu_1 + mu_2 - 2 M)` and
/// `U = mu_1 (W_1 + T) + M (W_2 - T)`. Steady, so the same for the inertial methods
/// (18.2237 at `d = 4.5`; without hydrodynamic interaction it would be
/// `(mu_2 W_2 - mu_1 W_1) / (mu_1 + mu_2) = 37.70`).
fn closed_form(d: f64) -> (f64, f64) {
    let w = |a: f64| 4.0 / 3.0 * PI * a.powi(3) * RHO;
    let mu = |a: f64| 1.0 / (6.0 * PI * a);
    let s = (A1 * A1 + A2 * A2) / (d * d);
    let m = ((1.0 + s / 3.0) + (1.0 - s)) / (8.0 * PI * d);
    let (w1, w2, mu1, mu2) = (w(A1), w(A2), mu(A1), mu(A2));
    let t = ((mu2 - m) * w2 - (mu1 - m) * w1) / (mu1 + mu2 - 2.0 * m);
    (t, mu1 * (w1 + t) + m * (w2 - t))
}

/// `-lambda d` of every bond after the last step (`Engine::tensions`).
fn tensions<T: Real>(ws: &Workspace<'_, T>, bonds: &[hydrorattle::Bond<T>]) -> Vec<f64> {
    ws.multipliers(bonds.len())
        .iter()
        .zip(bonds)
        .map(|(&l, b)| -(l * b.length).to_f64())
        .collect()
}

/// Every step's relative error of the dimer's tension from the closed form (springs:
/// `k (r - d)` against the closed form at the stretched length `r`).
fn dimer_errors<T: Real>(method: Method, dt: f64, steps: usize, resolve: bool) -> Vec<f64> {
    let (exact, u) = closed_form(D);
    let sphere = |z: f64, radius: f64| Sphere {
        pos: [0.3, -0.2, z],
        radius,
        density: RHO,
    };
    let mut ps: ParticleSet<T, 2> = particles(&[sphere(D, A1), sphere(0.0, A2)]);
    // Start at the steady velocity: the tension is steady from the first step.
    for v in &mut ps.vel {
        *v = v3::<T>(0.0, 0.0, -u);
    }
    let bonds: BondSet<T, 1> = BondSet::chain(&ps.pos[..2]).unwrap();
    let mut p = params::<T>(dt, method, SolverKind::Newton);
    p.resolve_tensions = resolve;
    let mut store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
    let mut ws = store.workspace();
    (0..steps)
        .map(|_| {
            run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, 1);
            if method == Method::Springs {
                let r = norm(sub(f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1])));
                let t = p.spring_stiffness.to_f64() * (r - D);
                return (t - closed_form(r).0) / closed_form(r).0;
            }
            (tensions(&ws, bonds.as_slice())[0] - exact) / exact
        })
        .collect()
}

/// Every method against the closed form, with the tensions solved again from the
/// displacements ([`hydrorattle::Params::resolve_tensions`]) and, in f64, also without
/// (f64's default): the position multipliers then carry the velocity stage's tolerance
/// (`1e-10` of `|b . v| dt / d^2`), 6e-6 of the tension at dt 0.01. In f32 (where the
/// default is on) they are rounding noise without it: not checked.
fn dimer_tension<T: Real>() {
    let f64_too = T::EPSILON.to_f64() < 1e-10;
    for method in ALL_METHODS {
        for (dt, resolve) in [(0.01, true), (0.001, true), (0.01, false), (0.001, false)] {
            if !resolve && !f64_too {
                continue;
            }
            let errors = dimer_errors::<T>(method, dt, 300, resolve);
            let worst = errors.iter().fold(0.0f64, |a, e| a.max(e.abs()));
            let last = errors[errors.len() - 1];
            println!("{method:?} dt {dt} resolve {resolve}: last {last:+.2e}, worst {worst:.2e}");
            if method == Method::Overdamped2 {
                // Its multipliers are only the final projection's correction (the host's
                // `Engine::tensions` is `None`): nowhere near the tension.
                assert!((1.0 + last).abs() < 1e-3, "{method:?} dt {dt}: {last}");
                continue;
            }
            let inertial = matches!(method, Method::Rattle | Method::RattleStable);
            // Springs relax onto the stretched length (rate k (mu_1 + mu_2 - 2 M) = 47):
            // the last 20 steps, 0.28 time units in at dt 0.001.
            let (from, tol) = match method {
                Method::Springs => (280, pick::<T>(1e-2, 1e-5)),
                _ if inertial && !resolve => (0, 1e-5),
                // f32: the implicit step's start-velocity correction carries 0.5 % noise
                // at dt 0.001 (the others 1e-3 or less).
                _ => (0, pick::<T>(1e-2, 1e-8)),
            };
            let worst = errors[from..].iter().fold(0.0f64, |a, e| a.max(e.abs()));
            assert!(
                worst < tol,
                "{method:?} dt {dt} resolve {resolve}: worst error {worst:e}"
            );
        }
    }
}

/// A 6-bead chain settling for 300 steps: f32 tensions agree with f64 (before the fix
/// `rattle-stable` at dt 0.01 gave f64 `[0.30 0.78 0.24 0.05 0.67]`-like tensions and
/// f32 `[-28 -30 -29 -20 -9]`).
fn chain_agreement<T: Real>() -> Vec<(Method, SolverKind, f64, Vec<f64>)> {
    let scene = chain_scene();
    let scene = Scene {
        spheres: scene.spheres[..6].to_vec(),
        ..scene
    };
    let mut out = Vec::new();
    let every = [SolverKind::Newton, SolverKind::Sweep, SolverKind::Krylov];
    // The overdamped multipliers are as accurate as the position solve (`tol d / (dt
    // mu)`, python/tests/test_system.py): a sweep stopping at f32's tolerance leaves
    // 1e-2 of them at dt 0.001; Newton overshoots the tolerance.
    let runs = [
        (Method::Overdamped, &every[..1]),
        (Method::Rattle, &every[..]),
        (Method::RattleStable, &every[..]),
    ];
    for (method, kinds) in runs {
        for (kind, dt) in kinds.iter().flat_map(|&k| [(k, 0.01), (k, 0.001)]) {
            let (mut ps, bonds): (ParticleSet<T, 6>, BondSet<T, 5>) = scene.build();
            // The default: resolved in f32, the position multipliers in f64.
            let p = params::<T>(dt, method, kind);
            let mut store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(6, 5));
            let mut ws = store.workspace();
            run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, 300);
            out.push((method, kind, dt, tensions(&ws, bonds.as_slice())));
        }
    }
    out
}

#[test]
fn chain_f32_matches_f64() {
    let (single, double) = (chain_agreement::<f32>(), chain_agreement::<f64>());
    // The forces' scale: the heaviest bead's buoyant weight (41).
    let scale = 4.0 / 3.0 * PI * 1.3f64.powi(3) * RHO;
    for ((method, kind, dt, t32), (.., t64)) in single.iter().zip(&double) {
        let worst = t32
            .iter()
            .zip(t64)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        println!("{method:?} {kind:?} dt {dt}: f32 {t32:.4?}\n  f64 {t64:.4?}");
        assert!(
            worst < 1e-3 * scale,
            "{method:?} dt {dt}: {worst:e} of {scale:e}"
        );
    }
}

both_precisions! {
    dimer_tension_closed_form => dimer_tension;
}
