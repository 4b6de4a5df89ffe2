//! Steps on the PSE path (`Params::pse`): the matrix-free
//! product and the Krylov metric's product (bonds, contacts) read `Pse::apply`; the
//! Brownian noise is PSE's own (`Pse::noise_in`, tested in `tests/kernel/pse_brownian.rs`).
//! Each PSE step is checked against the same step on the exact Ewald path (itself
//! checked against Hasimoto's expansion in `tests/kernel/periodic_step.rs`) within the
//! requested tolerance; repeats give the same bits; the combinations that need the
//! assembled matrix are refused, typed, with the state untouched.

use crate::common;

use common::boxes::config_radii;
use common::*;
use hydrorattle::integrate::pse_storage;
use hydrorattle::{
    Bond, BondSet, Brownian, Contacts, ExternalForce, Layout, Method, NoForce, NoiseSqrt, Params,
    ParticleSet, Periodic, Real, SolverKind, StepError, step,
};
use hydrorattle_heap::{Buffers, PseBuffers};

const L: f64 = 9.0;
const N: usize = 16;

/// PSE's arrays for a step of `p` over `ps` (empty where the step needs none).
fn pse_arrays<T: Real, const M: usize>(p: &Params<T>, ps: &ParticleSet<T, M>) -> PseBuffers<T> {
    PseBuffers::for_step(pse_storage(p, &ps.radius[..ps.len()]).expect("pse parameters"))
}

/// `steps` steps of `p`; the positions after each.
fn run<T: Real, const M: usize, const B: usize, E: ExternalForce<T>>(
    ps: &mut ParticleSet<T, M>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ext: &mut E,
    steps: usize,
) -> Result<Vec<Vec<[f64; 3]>>, StepError> {
    let mut buf = Buffers::<T>::new(Layout::for_params(p, ps.len(), bonds.len()));
    let mut arrays = pse_arrays(p, ps);
    let mut ws = arrays.attach(buf.workspace());
    let mut out = vec![];
    for _ in 0..steps {
        step(ps, bonds, p, &mut ws, ext)?;
        out.push(ps.pos[..ps.len()].iter().map(|&r| f64s::<T>(r)).collect());
    }
    Ok(out)
}

/// `N` polydisperse spheres (radii 0.5 to 1), apart, densities 2 to 6 (so the forces
/// differ), in the cubic box of edge `L`.
fn suspension() -> Vec<Sphere> {
    let (pos, rad) = config_radii(N, 11, [L; 3], [0.5, 1.0], false);
    assert_eq!(pos.len(), N);
    pos.iter()
        .zip(&rad)
        .enumerate()
        .map(|(i, (&pos, &radius))| Sphere {
            pos,
            radius,
            density: 2.0 + (i % 5) as f64,
        })
        .collect()
}

fn boxed(method: Method, tol: Option<f64>) -> Params<f64> {
    let mut p = params::<f64>(0.05, method, SolverKind::Auto);
    p.periodic = Some(Periodic::new([L; 3]).unwrap());
    p.matrix_free = true;
    p.pse = tol;
    p
}

/// Largest displacement difference over the largest displacement.
fn relative(start: &[Sphere], a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let big = start
        .iter()
        .zip(a)
        .map(|(s, r)| norm(sub(*r, s.pos)))
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| norm(sub(*x, *y)))
        .fold(0.0, f64::max);
    diff / big
}

/// Unconstrained sedimentation (`Overdamped`, `Springs` without bonds): one step on
/// the PSE path within the tolerance of the Ewald step, at `1e-3`, `1e-4` and `1e-6`.
#[test]
fn overdamped_matches_ewald() {
    let s = suspension();
    let none = BondSet::<f64, 0>::new();
    for method in [Method::Overdamped, Method::Springs] {
        let mut ps = particles::<f64, N>(&s);
        let ewald = run(&mut ps, &none, &boxed(method, None), &mut NoForce, 1).unwrap();
        for tol in [1e-3, 1e-4, 1e-6] {
            let mut ps = particles::<f64, N>(&s);
            let pse = run(&mut ps, &none, &boxed(method, Some(tol)), &mut NoForce, 1).unwrap();
            let err = relative(&s, &ewald[0], &pse[0]);
            println!("{method:?} tol {tol:e}: PSE vs Ewald {err:.2e}");
            assert!(err < tol, "{method:?} tol {tol}: {err}");
            assert!(err > 0.0, "PSE did not run");
        }
    }
}

/// A chain of 5 beads under gravity plus a twist, constrained by Krylov (the only
/// solver of `Auto` with PSE): positions after 3 steps within the tolerance of the
/// Ewald path's, bonds held to the solver's tolerance.
#[test]
fn constrained_krylov_matches_ewald() {
    const C: usize = 5;
    let chain: Vec<Sphere> = (0..C)
        .map(|k| Sphere {
            pos: [1.0 + 1.7 * k as f64, 4.0 + 0.3 * (k % 2) as f64, 4.5],
            radius: 0.6 + 0.03 * k as f64,
            density: 3.0,
        })
        .collect();
    let mut bonds = BondSet::<f64, { C - 1 }>::new();
    for k in 0..C - 1 {
        let d = norm(sub(chain[k + 1].pos, chain[k].pos));
        bonds
            .push(
                Bond {
                    i: k,
                    j: k + 1,
                    length: d,
                },
                C,
            )
            .unwrap();
    }
    let mut ewald_p = boxed(Method::Overdamped, None);
    ewald_p.solver.kind = SolverKind::Krylov;
    let mut ps = particles::<f64, C>(&chain);
    let ewald = run(&mut ps, &bonds, &ewald_p, &mut Push, 3).unwrap();
    for tol in [1e-4, 1e-6] {
        let p = boxed(Method::Overdamped, Some(tol));
        assert_eq!(p.solver_kind(C, C - 1), SolverKind::Krylov);
        let mut ps = particles::<f64, C>(&chain);
        let pse = run(&mut ps, &bonds, &p, &mut Push, 3).unwrap();
        let err = relative(&chain, &ewald[2], &pse[2]);
        println!("chain tol {tol:e}: PSE vs Ewald after 3 steps {err:.2e}");
        assert!(err < tol, "tol {tol}: {err}");
        for b in bonds.as_slice() {
            let r = norm(sub(pse[2][b.i], pse[2][b.j]));
            assert!((r - b.length).abs() < 1e-8 * b.length, "bond {r}");
        }
    }
}

/// A push along `x` on the first half, against `-x` on the rest.
struct Push;

impl<T: Real> ExternalForce<T> for Push {
    fn add(&mut self, _pos: &[T::V3], _radius: &[T], force: &mut [T::V3]) {
        let n = force.len();
        for (i, f) in force.iter_mut().enumerate() {
            let s = if i < n / 2 { 30.0 } else { -30.0 };
            *f += v3::<T>(s, 0.0, 0.0);
        }
    }
}

/// Four spheres in a row pushed together (and through the face at `x = 0`) with hard
/// contacts by Krylov: the contacts held, no overlap by the test's own minimum image,
/// the positions within the tolerance of the Ewald path's after 4 steps.
#[test]
fn contacts_match_ewald() {
    const C: usize = 4;
    let s: Vec<Sphere> = (0..C)
        .map(|k| Sphere {
            pos: [[7.6, 8.9, 1.2, 2.5][k], 4.0, 4.0 + 0.1 * k as f64],
            radius: 0.5,
            density: 1.0,
        })
        .collect();
    let none = BondSet::<f64, 0>::new();
    let with = |tol| {
        let mut p = boxed(Method::Overdamped, tol);
        p.solver.kind = SolverKind::Krylov;
        p.contacts = Some(Contacts::new(8));
        p
    };
    let mut ps = particles::<f64, C>(&s);
    let ewald = run(&mut ps, &none, &with(None), &mut Push, 4).unwrap();
    let mut ps = particles::<f64, C>(&s);
    let pse = run(&mut ps, &none, &with(Some(1e-5)), &mut Push, 4).unwrap();
    for (k, step) in pse.iter().enumerate() {
        for i in 0..C {
            for j in 0..i {
                let r = norm(min_image(sub(step[i], step[j])));
                assert!(r > 1.0 - 1e-8, "step {k}: {i} {j} at {r}");
            }
        }
    }
    let closest = |step: &[[f64; 3]]| {
        let r = |i: usize, j: usize| norm(min_image(sub(step[i], step[j])));
        r(1, 0).min(r(2, 1)).min(r(3, 2))
    };
    assert!(closest(&pse[3]) < 1.0 + 1e-8, "no contact held");
    assert!(closest(&ewald[3]) < 1.0 + 1e-8, "no contact held");
    let err = relative(&s, &ewald[3], &pse[3]);
    println!("contacts tol 1e-5: PSE vs Ewald after 4 steps {err:.2e}");
    assert!(err < 1e-5, "{err}");
}

fn min_image(r: [f64; 3]) -> [f64; 3] {
    r.map(|x| x - L * (x / L).round())
}

/// What needs the assembled matrix is refused with PSE, typed, the state untouched;
/// so is missing PSE storage.
#[test]
fn refusals() {
    let s = suspension();
    let none = BondSet::<f64, 0>::new();
    let mut bonds = BondSet::<f64, 1>::new();
    bonds
        .push(
            Bond {
                i: 0,
                j: 1,
                length: norm(sub(s[0].pos, s[1].pos)).min(4.0),
            },
            N,
        )
        .unwrap();
    let pse = boxed(Method::Overdamped, Some(1e-4));
    let cases: Vec<(&str, Params<f64>, bool)> = vec![
        (
            "stored",
            Params {
                matrix_free: false,
                ..pse
            },
            false,
        ),
        (
            "RattleStable",
            Params {
                matrix_free: false,
                method: Method::RattleStable,
                ..pse
            },
            false,
        ),
        (
            "Newton",
            Params {
                solver: hydrorattle::Solver {
                    kind: SolverKind::Newton,
                    ..pse.solver
                },
                ..pse
            },
            true,
        ),
        (
            // The box's rotation blocks are Ewald's alone.
            "rotation",
            Params {
                rotation: true,
                ..pse
            },
            false,
        ),
        (
            "Sweep",
            Params {
                solver: hydrorattle::Solver {
                    kind: SolverKind::Sweep,
                    ..pse.solver
                },
                ..pse
            },
            true,
        ),
    ];
    for (name, p, bonded) in cases {
        let mut ps = particles::<f64, N>(&s);
        let before = ps.pos;
        let r = match bonded {
            true => run(&mut ps, &bonds, &p, &mut NoForce, 1),
            false => run(&mut ps, &none, &p, &mut NoForce, 1),
        };
        match r {
            Err(StepError::Unsupported(why)) => assert!(why.contains("PSE"), "{name}: {why}"),
            other => panic!("{name}: {other:?}"),
        }
        assert_eq!(ps.pos, before, "{name}");
    }
    // Cholesky noise without a stored mobility (refused for matrix_free already).
    let mut p = pse;
    p.brownian = Some(Brownian::new(1.0));
    p.noise_sqrt = NoiseSqrt::Cholesky;
    let mut ps = particles::<f64, N>(&s);
    ps.noise = Some(hydrorattle::Noise::new(1));
    assert!(matches!(
        run(&mut ps, &none, &p, &mut NoForce, 1),
        Err(StepError::Unsupported(_))
    ));
    // No PSE storage in the workspace.
    let mut ps = particles::<f64, N>(&s);
    let before = ps.pos;
    let mut buf = Buffers::<f64>::new(Layout::for_params(&pse, N, 0));
    let mut ws = buf.workspace();
    match step(&mut ps, &none, &pse, &mut ws, &mut NoForce) {
        Err(StepError::BadParameter(what)) => assert!(what.contains("PSE"), "{what}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(ps.pos, before);
    // A tolerance outside PSE's range.
    let bad = Params {
        pse: Some(0.0),
        ..pse
    };
    assert!(pse_storage(&bad, &[0.5; N]).is_err());
    let mut ps = particles::<f64, N>(&s);
    let mut ws = buf.workspace();
    assert!(matches!(
        step(&mut ps, &none, &bad, &mut ws, &mut NoForce),
        Err(StepError::BadParameter(_))
    ));
}
