//! A step that fails returns a typed error and leaves the caller's state bit-identical
//! (positions, velocities, angular velocities, time); bad inputs are refused up front.
//! Property test: from random valid chains, any step either succeeds with every bond
//! within tolerance or fails with the state unchanged.

use crate::common;

use common::*;
use hydrorattle::{
    BondSet, Method, NoForce, ParticleError, ParticleSet, Real, SolverKind, Stage, StepError, step,
};
use proptest::prelude::*;

const ALL: [Method; 5] = [
    Method::Overdamped,
    Method::Overdamped2,
    Method::Rattle,
    Method::RattleStable,
    Method::Springs,
];
const CONSTRAINED: [Method; 4] = [
    Method::Overdamped,
    Method::Overdamped2,
    Method::Rattle,
    Method::RattleStable,
];

/// The chain scene after a few ordinary steps (non-zero velocities, time > 0).
fn warmed_chain<T: Real>(method: Method) -> (ParticleSet<T, 8>, BondSet<T, 8>) {
    let (mut ps, bonds) = chain_scene().build::<T, 8, 8>();
    let mut p = params::<T>(0.05, method, SolverKind::Newton);
    p.rotation = method == Method::RattleStable;
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
    let mut ws = ws_store.workspace();
    run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, 3);
    (ps, bonds)
}

/// One Newton step or one sweep cannot reach a tight tolerance after a large step.
fn no_convergence<T: Real>() {
    for method in CONSTRAINED {
        for kind in [SolverKind::Sweep, SolverKind::Newton] {
            let (mut ps, bonds) = warmed_chain::<T>(method);
            let mut p = params::<T>(1.0, method, kind);
            p.solver.max_iterations = 1;
            p.solver.tolerance = T::from_f64(pick::<T>(2e-6, 1e-13));
            let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
            let mut ws = ws_store.workspace();
            let before = snapshot(&ps);
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
            let what = format!("{method:?} {kind:?}");
            assert_failed_unchanged(
                &before,
                &ps,
                &r,
                |e| {
                    matches!(
                        e,
                        StepError::NoConvergence {
                            stage: Stage::Positions | Stage::Velocities,
                            ..
                        }
                    )
                },
                &what,
            );
        }
    }
}

/// NaN from the force hook, immediately or only from its second call (the
/// predictor-corrector's second evaluation, or the next step).
fn nan_force<T: Real>() {
    for method in ALL {
        let (mut ps, bonds) = warmed_chain::<T>(method);
        let mut p = params::<T>(0.01, method, SolverKind::Newton);
        p.rotation = method == Method::RattleStable;
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
        let mut ws = ws_store.workspace();
        let mut at_once = |_: &[T::V3], _: &[T], f: &mut [T::V3]| {
            f[2] = T::v3_from([f64::NAN, 0.0, 0.0]);
        };
        let before = snapshot(&ps);
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut at_once);
        let what = format!("{method:?} NaN force");
        assert_failed_unchanged(
            &before,
            &ps,
            &r,
            |e| *e == StepError::NonFiniteForce { particle: 2 },
            &what,
        );

        let mut calls = 0;
        let mut later = |_: &[T::V3], _: &[T], f: &mut [T::V3]| {
            calls += 1;
            if calls >= 2 {
                f[5] = T::v3_from([0.0, f64::INFINITY, 0.0]);
            }
        };
        let mut failed = false;
        for _ in 0..3 {
            let before = snapshot(&ps);
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut later);
            if r.is_err() {
                let what = format!("{method:?} delayed infinite force");
                assert_failed_unchanged(
                    &before,
                    &ps,
                    &r,
                    |e| *e == StepError::NonFiniteForce { particle: 5 },
                    &what,
                );
                failed = true;
                break;
            }
        }
        assert!(failed, "{method:?}: infinite force never reported");
    }
}

/// Two spheres 2.2 apart pushed together: the unconstrained move ends at a separation of
/// about 1.5 (closing speed `2 F (1/(6 pi) - mu_pair,parallel)`), an overlap, which the
/// default policy rejects; allowing overlap, the same step goes through.
fn overlap<T: Real>() {
    for method in [Method::Overdamped, Method::Overdamped2] {
        let spheres = [
            Sphere {
                pos: [1.1, 0.0, 0.0],
                radius: 1.0,
                density: RHO,
            },
            Sphere {
                pos: [-1.1, 0.0, 0.0],
                radius: 1.0,
                density: RHO,
            },
        ];
        let mut ps: ParticleSet<T, 2> = particles(&spheres);
        let bonds: BondSet<T, 1> = BondSet::new();
        let mut p = params::<T>(0.1, method, SolverKind::Newton);
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
        let mut ws = ws_store.workspace();
        let mut push = |_: &[T::V3], _: &[T], f: &mut [T::V3]| {
            f[0] += T::v3_from([-154.0, 0.0, 0.0]);
            f[1] += T::v3_from([154.0, 0.0, 0.0]);
        };
        let before = snapshot(&ps);
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut push);
        let what = format!("{method:?} overlap");
        assert_failed_unchanged(
            &before,
            &ps,
            &r,
            |e| *e == StepError::Overlap { i: 0, j: 1 },
            &what,
        );
        p.allow_overlap = true;
        step(&mut ps, &bonds, &p, &mut ws, &mut push).expect("overlap allowed");
        let s = norm(sub(f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1])));
        assert!(s > 0.0 && s < 2.0, "{method:?}: separation {s}");
    }
}

/// Oseen interactions are not positive definite for close spheres (pair mobility along
/// the line of centres `1/(4 pi eta s)` exceeds the self term `1/(6 pi eta a)` when
/// `s < 1.5 a`): the inertial methods' Cholesky factorisations fail, typed, state intact.
fn not_positive_definite<T: Real>() {
    let spheres = [
        Sphere {
            pos: [0.6, 0.0, 0.0],
            radius: 1.0,
            density: RHO,
        },
        Sphere {
            pos: [-0.6, 0.0, 0.0],
            radius: 1.0,
            density: RHO,
        },
    ];
    let list: Vec<hydrorattle::Particle<T>> = spheres
        .iter()
        .map(|s| {
            hydrorattle::Particle::new(
                T::v3_from(s.pos),
                T::from_f64(s.radius),
                T::from_f64(s.density),
            )
        })
        .collect();
    for (method, stage) in [
        (Method::Rattle, Stage::Mobility),
        (Method::RattleStable, Stage::Drag),
    ] {
        let mut ps: ParticleSet<T, 2> = ParticleSet::from_slice(&list, true).unwrap();
        ps.vel[0] = v3::<T>(0.1, 0.2, 0.3);
        let bonds: BondSet<T, 1> = BondSet::new();
        let mut p = params::<T>(0.01, method, SolverKind::Newton);
        p.hydro = hydrorattle::Hydro::Oseen;
        p.allow_overlap = true;
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
        let mut ws = ws_store.workspace();
        let before = snapshot(&ps);
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
        let what = format!("{method:?} Oseen");
        assert_failed_unchanged(
            &before,
            &ps,
            &r,
            |e| matches!(e, StepError::Linalg { stage: s, error: hydrorattle::LinalgError::NotPositiveDefinite { .. } } if *s == stage),
            &what,
        );
        // The same pair with RPY (overlapping branch, positive definite) steps fine.
        p.hydro = hydrorattle::Hydro::Rpy;
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).expect("RPY overlap branch");
    }
}

/// Bad time steps and viscosities, and massless particles with inertial methods.
fn bad_inputs<T: Real>() {
    let (mut ps, bonds) = warmed_chain::<T>(Method::Overdamped);
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
    let mut ws = ws_store.workspace();
    let before = snapshot(&ps);
    for method in ALL {
        for dt in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            let p = params::<T>(dt, method, SolverKind::Newton);
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
            let what = format!("{method:?} dt {dt}");
            assert_failed_unchanged(&before, &ps, &r, |e| *e == StepError::BadTimeStep, &what);
        }
        for eta in [0.0, -1.0, f64::NAN] {
            let mut p = params::<T>(0.01, method, SolverKind::Newton);
            p.viscosity = T::from_f64(eta);
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
            let what = format!("{method:?} viscosity {eta}");
            assert_failed_unchanged(
                &before,
                &ps,
                &r,
                |e| *e == StepError::BadParameter("viscosity"),
                &what,
            );
        }
    }
    // A massless (density 0) bead: fine overdamped, refused by the inertial methods.
    ps.density[4] = T::ZERO;
    let before = snapshot(&ps);
    for method in [Method::Rattle, Method::RattleStable] {
        let p = params::<T>(0.01, method, SolverKind::Newton);
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
        let what = format!("{method:?} massless");
        let want = StepError::Particle(ParticleError::Massless { particle: 4 });
        assert_failed_unchanged(&before, &ps, &r, |e| *e == want, &what);
    }
    let p = params::<T>(0.01, Method::Overdamped, SolverKind::Newton);
    step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).expect("massless bead, overdamped");
}

/// A tolerance below what the precision can reach is refused at once (not
/// iterated to a huge cap), a non-finite or non-advancing time is refused, and the
/// tolerance bounds the relative length error as documented, compressed bonds included.
fn tolerance_and_time<T: Real>() {
    let (mut ps, bonds) = warmed_chain::<T>(Method::Overdamped);
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
    let mut ws = ws_store.workspace();
    let before = snapshot(&ps);
    let mut p = params::<T>(0.05, Method::Overdamped, SolverKind::Newton);
    p.solver.tolerance = T::from_f64(1e-310_f64.max(pick::<T>(1e-7, 1e-16)));
    p.solver.max_iterations = u32::MAX;
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    assert!(matches!(r, Err(StepError::BadParameter(_))), "{r:?}");
    assert_eq!(before, snapshot(&ps));
    let p = params::<T>(0.05, Method::Overdamped, SolverKind::Newton);
    for time in [f64::NAN, f64::INFINITY, pick::<T>(1e9, 1e18)] {
        let mut bad = ps.clone();
        bad.time = T::from_f64(time);
        let r = step(&mut bad, &bonds, &p, &mut ws, &mut NoForce);
        assert!(
            matches!(r, Err(StepError::BadParameter(_))),
            "time {time}: {r:?}"
        );
    }
    // Every bond within the tolerance of its length, measured as documented.
    for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
        let mut p = params::<T>(0.2, Method::Overdamped, kind);
        p.solver.tolerance = T::from_f64(pick::<T>(1e-3, 1e-6));
        let mut ps = ps.clone();
        for _ in 0..5 {
            step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
            let (_, worst) = bonds.max_residual(&ps.pos[..ps.len()]);
            assert!(
                worst <= p.solver.tolerance,
                "{kind:?}: {worst} > {}",
                p.solver.tolerance
            );
        }
    }
}

both_precisions! {
    tolerance_and_time_are_checked => tolerance_and_time;
    no_convergence_leaves_state => no_convergence;
    nan_force_leaves_state => nan_force;
    overlap_leaves_state => overlap;
    not_positive_definite_leaves_state => not_positive_definite;
    bad_inputs_are_refused => bad_inputs;
}

// ---------------------------------------------------------------------------------
// Property test: random valid chains.
// ---------------------------------------------------------------------------------

/// A random chain and a random step.
#[derive(Clone, Debug)]
struct Case {
    radii: Vec<f64>,
    dirs: Vec<[f64; 3]>,
    spacing: Vec<f64>,
    dt: f64,
    method: usize,
    newton: bool,
    steps: usize,
}

fn case() -> impl Strategy<Value = Case> {
    (4usize..=12).prop_flat_map(|n| {
        (
            prop::collection::vec(0.5f64..1.5, n),
            prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), n - 1),
            prop::collection::vec(1.0f64..1.6, n - 1),
            -3.0f64..0.0,
            0usize..4,
            any::<bool>(),
            1usize..4,
        )
            .prop_map(
                |(radii, dirs, spacing, log_dt, method, newton, steps)| Case {
                    radii,
                    dirs,
                    spacing,
                    dt: 10f64.powf(log_dt),
                    method,
                    newton,
                    steps,
                },
            )
    })
}

/// Builds the chain (bond `k` along `dir_k + 0.8 x`, of length `spacing_k (a_k + a_k+1)`, at least touching),
/// or `None` when the random walk makes non-neighbours overlap or a direction vanishes.
fn chain_of(c: &Case) -> Option<Vec<Sphere>> {
    let mut spheres = vec![Sphere {
        pos: [0.0; 3],
        radius: c.radii[0],
        density: RHO,
    }];
    for k in 1..c.radii.len() {
        // A drift along x keeps most random walks free of non-neighbour overlaps.
        let u = add(c.dirs[k - 1], [0.8, 0.0, 0.0]);
        let len = norm(u);
        if len < 0.1 {
            return None;
        }
        let d = c.spacing[k - 1] * (c.radii[k - 1] + c.radii[k]);
        spheres.push(Sphere {
            pos: add(spheres[k - 1].pos, scale(u, d / len)),
            radius: c.radii[k],
            density: RHO,
        });
    }
    for i in 0..spheres.len() {
        for j in 0..i {
            let s = norm(sub(spheres[i].pos, spheres[j].pos));
            if s < spheres[i].radius + spheres[j].radius {
                return None;
            }
        }
    }
    Some(spheres)
}

fn random_chain_property<T: Real>(c: &Case) -> Result<(), TestCaseError> {
    let Some(spheres) = chain_of(c) else {
        return Err(TestCaseError::reject("overlapping random walk"));
    };
    let mut ps: ParticleSet<T, 12> = particles(&spheres);
    let n = ps.len();
    let bonds: BondSet<T, 12> = BondSet::chain(&ps.pos[..n]).unwrap();
    let method = CONSTRAINED[c.method];
    let kind = if c.newton {
        SolverKind::Newton
    } else {
        SolverKind::Sweep
    };
    let p = params::<T>(c.dt, method, kind);
    let tol = p.solver.tolerance.to_f64() + 16.0 * T::EPSILON.to_f64();
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(12, 12));
    let mut ws = ws_store.workspace();
    for k in 0..c.steps {
        let before = snapshot(&ps);
        match step(&mut ps, &bonds, &p, &mut ws, &mut NoForce) {
            Ok(r) => {
                let err = bond_error(&ps, &bonds);
                prop_assert!(
                    err <= tol,
                    "step {k}: bond error {err:e} (report {:e})",
                    r.residual.to_f64()
                );
                if matches!(method, Method::Rattle | Method::RattleStable) {
                    let rate = bond_rate_error(&ps, &bonds, c.dt);
                    prop_assert!(rate <= tol, "step {k}: bond rate error {rate:e}");
                }
            }
            Err(e) => {
                prop_assert_eq!(
                    before,
                    snapshot(&ps),
                    "step {} failed ({}) and changed the state",
                    k,
                    e
                );
                break;
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 32,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_chains_hold_or_fail_cleanly_f64(c in case()) {
        random_chain_property::<f64>(&c)?;
    }

    #[test]
    fn random_chains_hold_or_fail_cleanly_f32(c in case()) {
        random_chain_property::<f32>(&c)?;
    }
}
