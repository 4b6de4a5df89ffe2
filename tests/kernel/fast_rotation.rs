//! Rotation in steps on the fast free-space product (`Params::pse` without a box or a
//! wall, with `Params::rotation`): the spins of torque-free spheres `W = M_rt F` from
//! the grand product (`FreeFast::apply_grand`), with the constraint forces in `F`.
//! Checked against values not from the fast code:
//!
//! * the spins against the same step's on the dense stored mobility within the
//!   requested tolerance: a polydisperse cloud with overlapping pairs (deterministic and
//!   thermal), a bonded chain by Krylov (the constraint forces in `F`);
//! * a pair at fixed separation against the closed form of the two-sphere RPY
//!   rotation-translation coupling, `W_1 = F_2 x (r_1 - r_2) / (8 pi eta r^3)`;
//! * the same bits twice; the refusals typed, the state untouched.
//!
//! `cargo test --release --test kernel fast_rotation:: -- --nocapture`.

use crate::common;
use crate::fast_step::{C, K, Push, arrays, assert_unsupported, chain, cloud, on, set};

use common::thermal::*;
use common::*;
use hydrorattle::integrate::{fast_storage, fast_vectors};
use hydrorattle::{
    BondSet, Drift, ExternalForce, Hydro, Layout, Method, NoForce, Noise, Params, Real, SolverKind,
    StepError, step,
};
use hydrorattle_heap::Buffers;
use std::f64::consts::PI;

/// Positions and spins after each step.
type Frames = Vec<(Vec<[f64; 3]>, Vec<[f64; 3]>)>;

/// `steps` steps of `p` from `s` (thermal with `seed`), the fast product's arrays and
/// its spins' vectors sized as `fast_storage` and `fast_vectors` ask where `p` takes
/// it; positions and spins after each.
fn run<const M: usize, const B: usize, E: ExternalForce<f64>>(
    s: &[Sphere],
    bonds: &BondSet<f64, B>,
    p: &Params<f64>,
    ext: &mut E,
    (steps, seed): (usize, Option<u64>),
) -> Result<Frames, StepError> {
    let n = s.len();
    let mut ps = set::<M>(s);
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, n, bonds.len()));
    let mut a = match p.pse {
        Some(_) => arrays(p, s, [1.0; 3]),
        None => hydrorattle_heap::FreeBuffers::default(),
    };
    let mut v = vec![f64::V3_ZERO; fast_vectors(p, n)];
    let ws = a.attach(buf.workspace());
    let mut ws = ws.with_fast_vectors(&mut v);
    let mut noise = seed.map(Noise::new);
    let mut out = vec![];
    for _ in 0..steps {
        match &mut noise {
            Some(g) => step_thermal(&mut ps, bonds, p, &mut ws, ext, g)?,
            None => step(&mut ps, bonds, p, &mut ws, ext)?,
        };
        let v3 = |x: &[<f64 as Real>::V3]| x[..n].iter().map(|&r| f64s::<f64>(r)).collect();
        out.push((v3(&ps.pos), v3(&ps.omega)));
    }
    Ok(out)
}

/// Largest spin difference over the largest spin.
pub(super) fn spin_error(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let big = a.iter().map(|w| norm(*w)).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| norm(sub(*x, *y)))
        .fold(0.0, f64::max);
    assert!(big > 0.0, "no spins");
    diff / big
}

/// `p` with rotation.
fn rotating(mut p: Params<f64>) -> Params<f64> {
    p.rotation = true;
    p
}

/// A thermal step (`kT = 1`, `eta = 1`) with rotation, under gravity (so that the
/// spheres spin).
fn thermal_rotating() -> Params<f64> {
    let mut p = rotating(thermal::<f64>(0.01, 1.0, Hydro::Rpy, Drift::Midpoint));
    p.gravity = f64::v3(0.0, 0.0, -1.0);
    p
}

/// The sedimenting cloud (60 polydisperse spheres, overlapping pairs), `Overdamped` and
/// `Springs`: one step's spins on the fast product within its tolerance of the dense
/// stored step's, at `1e-3`, `1e-4` and `1e-6`. The thermal step's too (`W = M_rt F`
/// at the start: the kernel draws no rotational noise on any path; Cholesky noise on the
/// dense path, Lanczos here: the displacements differ, the spins not).
#[test]
fn cloud_spins_match_dense() {
    let s = cloud();
    let none = BondSet::<f64, 0>::new();
    let deterministic = |m| rotating(params::<f64>(0.05, m, SolverKind::Auto));
    let all = [1e-3, 1e-4, 1e-6];
    let cases = [
        (
            "Overdamped",
            deterministic(Method::Overdamped),
            None,
            &all[..],
        ),
        ("Springs", deterministic(Method::Springs), None, &all[..]),
        ("thermal", thermal_rotating(), Some(5), &all[1..2]),
    ];
    for (name, p, seed, tols) in cases {
        let dense = run::<C, 0, _>(&s, &none, &on(p, None), &mut NoForce, (1, seed)).unwrap();
        for &tol in tols {
            let fast = run::<C, 0, _>(&s, &none, &on(p, Some(tol)), &mut NoForce, (1, seed));
            let err = spin_error(&dense[0].1, &fast.unwrap()[0].1);
            println!("{name} tol {tol:e}: spins fast vs dense {err:.2e}");
            assert!(err < tol && err > 0.0, "{name} tol {tol}: {err}");
        }
    }
}

/// The bonded chain pushed apart, constrained by Krylov: the spins include the
/// constraint forces (without them they would differ by the tensions' share, checked
/// to be large), within the tolerance of the dense Krylov step's after one step.
#[test]
fn chain_spins_include_constraint_forces() {
    let (s, bonds) = chain();
    let p = rotating(params::<f64>(0.05, Method::Overdamped, SolverKind::Krylov));
    let dense = run::<K, { K - 1 }, _>(&s, &bonds, &on(p, None), &mut Push, (1, None)).unwrap();
    let free = BondSet::<f64, { K - 1 }>::new();
    let unbonded = run::<K, { K - 1 }, _>(&s, &free, &on(p, None), &mut Push, (1, None)).unwrap();
    let share = spin_error(&dense[0].1, &unbonded[0].1);
    assert!(
        share > 0.1,
        "the constraint forces change the spins by {share}"
    );
    for tol in [1e-4, 1e-6] {
        let got = run::<K, { K - 1 }, _>(&s, &bonds, &on(p, Some(tol)), &mut Push, (1, None));
        let err = spin_error(&dense[0].1, &got.unwrap()[0].1);
        println!("chain tol {tol:e}: spins fast vs dense {err:.2e} (tensions' share {share:.2})");
        assert!(err < tol, "tol {tol}: {err}");
    }
}

/// A force `F` on sphere 1 alone.
struct OnSecond([f64; 3]);

impl ExternalForce<f64> for OnSecond {
    fn add(
        &mut self,
        _pos: &[<f64 as Real>::V3],
        _radius: &[f64],
        force: &mut [<f64 as Real>::V3],
    ) {
        force[1] += f64::v3_from(self.0);
    }
}

/// Two spheres of radii 0.7 and 1.3 apart (`r` from 2.2 to 9), a force on the second
/// only: the first spins at the two-sphere RPY coupling
/// `W_1 = F_2 x (r_1 - r_2) / (8 pi eta r^3)` (the rotlet; RPY's sphere factors leave
/// it unchanged beyond contact), the second, torque-free and alone pushed, not at all
/// (no self coupling), both to the fast product's tolerance; the dense step as well.
#[test]
fn pair_spin_against_closed_form() {
    let f = [0.3, -1.1, 0.8];
    for r in [2.2, 3.5, 9.0] {
        let d = [0.6 * r, 0.0, 0.8 * r];
        let s = vec![
            Sphere {
                pos: d,
                radius: 0.7,
                density: 0.0,
            },
            Sphere {
                pos: [0.0; 3],
                radius: 1.3,
                density: 0.0,
            },
        ];
        let mut p = rotating(params::<f64>(0.05, Method::Overdamped, SolverKind::Auto));
        p.gravity = f64::V3_ZERO;
        p.viscosity = 0.8;
        let want = cross(f, d).map(|x| x / (8.0 * PI * 0.8 * r * r * r));
        let none = BondSet::<f64, 0>::new();
        let tol = 1e-6;
        for q in [on(p, None), on(p, Some(tol))] {
            let got = run::<2, 0, _>(&s, &none, &q, &mut OnSecond(f), (1, None)).unwrap();
            let w = &got[0].1;
            let err = norm(sub(w[0], want)) / norm(want);
            println!(
                "r {r}, pse {:?}: W_1 against the closed form {err:.2e}",
                q.pse
            );
            assert!(err < tol, "r {r} {:?}: {err}", q.pse);
            assert!(norm(w[1]) < tol * norm(want), "W_2 = {:?}", w[1]);
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Three thermal steps with rotation twice from the same start and seed: the same
/// bits (positions, velocities, spins).
#[test]
fn same_bits_twice() {
    let s = cloud();
    let none = BondSet::<f64, 0>::new();
    let p = on(thermal_rotating(), Some(1e-4));
    let once = || run::<C, 0, _>(&s, &none, &p, &mut NoForce, (3, Some(9))).unwrap();
    let (a, b) = (once(), once());
    let bits = |f: &Frames| -> Vec<u64> {
        f.iter()
            .flat_map(|(x, w)| x.iter().chain(w).flatten().map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
}

/// With rotation the fast step asks for the grand product's storage (more reals than
/// without) and `2 n` vectors; without the vectors, or with PSE in a box, the step is
/// refused typed, the state untouched; what the fast product refuses without rotation
/// it refuses with it (the stored path).
#[test]
fn refusals_with_rotation() {
    let (s, bonds) = chain();
    let fast = on(
        rotating(params::<f64>(0.05, Method::Overdamped, SolverKind::Auto)),
        Some(1e-4),
    );
    let pos: Vec<_> = s.iter().map(|x| f64::v3_from(x.pos)).collect();
    let rad: Vec<f64> = s.iter().map(|x| x.radius).collect();
    let plain = Params {
        rotation: false,
        ..fast
    };
    let (grand, trans) = (
        fast_storage(&fast, &pos, &rad).unwrap().unwrap(),
        fast_storage(&plain, &pos, &rad).unwrap().unwrap(),
    );
    assert!(grand.reals > trans.reals, "{grand:?} against {trans:?}");
    assert_eq!(
        (fast_vectors(&fast, K), fast_vectors(&plain, K)),
        (2 * K, 0)
    );
    // The fast arrays without the spins' vectors.
    let mut ps = set::<K>(&s);
    let before = snapshot(&ps);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&fast, K, K - 1));
    let mut a = arrays(&fast, &s, [1.0; 3]);
    let mut ws = a.attach(buf.workspace());
    let r = step(&mut ps, &bonds, &fast, &mut ws, &mut NoForce);
    let typed = |e: &StepError| matches!(e, StepError::BadParameter(w) if w.contains("fast free-space vectors"));
    assert_failed_unchanged(&before, &ps, &r, typed, "no vectors");
    // Still refused: PSE in a box with rotation, the stored path with rotation.
    let cases = [
        (
            "PSE box",
            Params {
                periodic: hydrorattle::Periodic::new([40.0; 3]).ok(),
                ..fast
            },
            "PSE with rotation",
        ),
        (
            "stored",
            Params {
                matrix_free: false,
                ..fast
            },
            "products only",
        ),
    ];
    for (name, p, why) in cases {
        assert_unsupported((&s, &bonds), &p, why, name);
    }
}
