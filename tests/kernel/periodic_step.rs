//! Steps in a periodic box (every method, solver and noise
//! with the Ewald-summed mobility; bonds, springs and contacts through the minimum
//! image), each checked against a value that does not come from the code under test:
//!
//! * a lone sphere settling under gravity against Hasimoto's expansion (the constant
//!   to 13 digits, written here);
//! * a dimer straddling a face against the same dimer shifted by box vectors (bit for
//!   bit), and against the same dimer unbroken by the face (to rounding);
//! * bond lengths, contact distances and overlaps measured here by the test's own
//!   minimum image;
//! * the refusals (a bond of half the box, a wall, the Oseen level), typed,
//!   with the state untouched.

use crate::common;

use common::*;
use hydrorattle::{
    Bond, BondError, BondSet, Brownian, Contacts, ExternalForce, Hydro, Layout, Method, NoForce,
    NoiseSqrt, Params, ParticleError, ParticleSet, Periodic, Real, SolverKind, StepError, Wall,
    step,
};
use hydrorattle_heap::Buffers;
use std::f64::consts::PI;

const METHODS: [Method; 5] = ALL_METHODS;

/// The test's own minimum image in a cubic box of edge `l`.
fn image(d: [f64; 3], l: f64) -> [f64; 3] {
    d.map(|x| x - l * (x / l).round())
}

fn cubic<T: Real>(l: f64) -> Periodic<T> {
    Periodic::new([T::from_f64(l); 3]).unwrap()
}

fn boxed<T: Real>(dt: f64, method: Method, l: f64) -> Params<T> {
    let mut p = params::<T>(dt, method, SolverKind::Auto);
    p.periodic = Some(cubic::<T>(l));
    p
}

fn one(pos: [f64; 3], radius: f64, density: f64) -> Sphere {
    Sphere {
        pos,
        radius,
        density,
    }
}

/// Hasimoto (1959): `6 pi eta a U / F` of a lone sphere in a cubic array.
fn hasimoto(x: f64) -> f64 {
    1.0 - 2.8372974794806 * x + 4.0 * PI / 3.0 * x.powi(3)
}

/// A lone unit sphere of density `RHO` (free Stokes speed 1 under `|g| = 1`) in boxes
/// `L/a = 5 ... 50`: its settling speed relative to the zero-mean fluid (the mode
/// `k = 0` is the mean pressure gradient that holds the net weight) is Hasimoto's.
fn lone_sphere<T: Real>() {
    let tol = pick::<T>(5e-6, 1e-13);
    for l in [5.0, 10.0, 20.0, 50.0] {
        for method in [
            Method::Overdamped,
            Method::Overdamped2,
            Method::Springs,
            Method::RattleStable,
        ] {
            for (matrix_free, rotation) in [(false, false), (true, false), (false, true)] {
                if matrix_free && !matches!(method, Method::Overdamped | Method::Springs) {
                    continue;
                }
                let mut ps = particles::<T, 1>(&[one([0.3, -1.2, 2.0], 1.0, RHO)]);
                let bonds = BondSet::<T, 1>::new();
                let mut p = boxed::<T>(1.0, method, l);
                p.matrix_free = matrix_free;
                // With rotation the stable method solves with the box's grand mobility.
                p.rotation = rotation;
                let mut buf = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
                let mut ws = buf.workspace();
                // The implicit drag reaches the terminal speed by halves (tau = dt = 1).
                let steps = if method == Method::RattleStable {
                    80
                } else {
                    1
                };
                run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, steps);
                let v = f64s::<T>(ps.vel[0]);
                let want = hasimoto(1.0 / l);
                let err = (-v[2] - want).abs();
                assert!(
                    err < tol,
                    "{method:?} L = {l}: {} vs {want} ({err:e})",
                    -v[2]
                );
                assert!(v[0].abs() < tol && v[1].abs() < tol, "{method:?}: {v:?}");
                let w = f64s::<T>(ps.omega[0]);
                assert!(w.iter().all(|x| x.abs() < tol), "{method:?}: spin {w:?}");
                if method == Method::Overdamped && !matrix_free && !rotation {
                    eprintln!(
                        "L/a = {l}: U 6 pi eta a / F = {:.16} (Hasimoto {want:.16}, error {err:.1e})",
                        -v[2]
                    );
                }
            }
        }
    }
}

/// A dimer whose bond crosses the face `x = 8 = 16` of the box of edge 8, every
/// coordinate in `[8, 16)`: shifted by `-3L` on every axis the coordinates fall in
/// `(-16, -8]`, where the floating-point grid is the same, so every sum the step forms
/// rounds the same way and the shifted run must give the same bits.
fn straddling(shift: f64) -> Vec<Sphere> {
    vec![
        one([15.75 + shift, 12.0 + shift, 12.5 + shift], 0.25, RHO),
        one([8.25 + shift, 12.25 + shift, 11.75 + shift], 0.3, RHO),
    ]
}

/// The bond at its minimum-image length (`BondSet::push_current` measures free space).
fn dimer_bond<T: Real>(s: &[Sphere], l: f64) -> BondSet<T, 1> {
    let d = norm(image(sub(s[0].pos, s[1].pos), l));
    let mut b = BondSet::new();
    b.push(
        Bond {
            i: 0,
            j: 1,
            length: T::from_f64(d),
        },
        2,
    )
    .unwrap();
    b
}

/// A sideways pull on sphere 0 and a push on sphere 1, so the dimer turns and drifts.
struct Twist;
impl<T: Real> ExternalForce<T> for Twist {
    fn add(&mut self, _pos: &[T::V3], _radius: &[T], force: &mut [T::V3]) {
        force[0] += T::v3_from([0.5, -1.5, 0.25]);
        force[1] += T::v3_from([-0.25, 1.0, 0.5]);
    }
}

/// The variants each method is run in: plain, with rotation (the box's `rt`, `rr`
/// blocks), matrix-free, thermal (Cholesky and Lanczos), contacts, and the three solvers.
fn variants<T: Real>(method: Method) -> Vec<Params<T>> {
    let base = boxed::<T>(0.01, method, 8.0);
    let mut out = vec![base];
    out.push(Params {
        rotation: true,
        ..base
    });
    for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
        let mut p = base;
        p.solver.kind = kind;
        out.push(p);
    }
    if matches!(method, Method::Overdamped | Method::Springs) {
        let mut p = base;
        p.matrix_free = true;
        out.push(p);
        p.rotation = true;
        out.push(p);
    }
    if matches!(
        method,
        Method::Overdamped | Method::Springs | Method::RattleStable
    ) {
        for sqrt in [NoiseSqrt::Cholesky, NoiseSqrt::Lanczos] {
            if method == Method::RattleStable && sqrt == NoiseSqrt::Lanczos {
                continue;
            }
            let mut p = base;
            p.brownian = Some(Brownian::new(T::from_f64(0.05)));
            p.noise_sqrt = sqrt;
            out.push(p);
        }
    }
    if matches!(method, Method::Overdamped | Method::Overdamped2) {
        let mut p = base;
        p.contacts = Some(Contacts::new(2));
        out.push(p);
    }
    out
}

fn run_dimer<T: Real>(
    s: &[Sphere],
    p: &Params<T>,
    steps: usize,
) -> (ParticleSet<T, 2>, Vec<String>) {
    let mut ps = particles::<T, 2>(s);
    let bonds = dimer_bond::<T>(s, 8.0);
    ps.noise = p.brownian.map(|_| hydrorattle::Noise::new(7));
    let mut buf = Buffers::<T>::new(Layout::for_params(p, 2, 1));
    let mut ws = buf.workspace();
    let reports = (0..steps)
        .map(|k| {
            let r = step(&mut ps, &bonds, p, &mut ws, &mut Twist);
            let r = r.unwrap_or_else(|e| panic!("{:?} step {k}: {e}", p.method));
            format!("{r:?}")
        })
        .collect();
    (ps, reports)
}

/// The straddling dimer and its copy shifted by `(-24, -24, -24)`: the same bits for
/// every method, solver, noise and contacts.
fn translation_bits<T: Real>() {
    for method in METHODS {
        for p in variants::<T>(method) {
            let (a, ra) = run_dimer::<T>(&straddling(0.0), &p, 6);
            let (b, rb) = run_dimer::<T>(&straddling(-24.0), &p, 6);
            assert_eq!(ra, rb, "{method:?}: reports");
            let shift = T::v3_from([24.0; 3]);
            for k in 0..2 {
                assert_eq!(
                    f64s::<T>(b.pos[k] + shift),
                    f64s::<T>(a.pos[k]),
                    "{method:?} {p:?}"
                );
                assert_eq!(f64s::<T>(b.vel[k]), f64s::<T>(a.vel[k]), "{method:?}");
                assert_eq!(f64s::<T>(b.omega[k]), f64s::<T>(a.omega[k]), "{method:?}");
            }
        }
    }
}

/// The straddling dimer keeps its bond's minimum-image length (measured here), and
/// moves as the same dimer placed whole inside the box (sphere 1 shifted by `+L` along
/// `x`) does, to rounding.
fn straddling_bond<T: Real>() {
    let tol = pick::<T>(2e-4, 1e-9);
    for method in METHODS {
        for p in variants::<T>(method) {
            let s = straddling(0.0);
            let mut whole = s.clone();
            whole[1].pos[0] += 8.0;
            let (a, _) = run_dimer::<T>(&s, &p, 20);
            let (b, _) = run_dimer::<T>(&whole, &p, 20);
            let d = norm(image(sub(s[0].pos, s[1].pos), 8.0));
            let r = norm(image(sub(f64s::<T>(a.pos[0]), f64s::<T>(a.pos[1])), 8.0));
            if method != Method::Springs {
                assert!(
                    (r / d - 1.0).abs() < pick::<T>(1e-4, 1e-9),
                    "{method:?}: |r| = {r}, d = {d}"
                );
            }
            let moved = norm(sub(f64s::<T>(a.pos[0]), s[0].pos));
            assert!(moved > 1e-3, "{method:?}: the dimer did not move");
            for k in 0..2 {
                let (x, mut y) = (f64s::<T>(a.pos[k]), f64s::<T>(b.pos[k]));
                if k == 1 {
                    y[0] -= 8.0;
                }
                let e = norm(sub(x, y));
                assert!(
                    e < tol,
                    "{method:?} {:?}: sphere {k} off by {e:e}",
                    p.solver.kind
                );
                let (wa, wb) = (f64s::<T>(a.omega[k]), f64s::<T>(b.omega[k]));
                let w = norm(sub(wa, wb));
                assert!(
                    w < tol * (1.0 + norm(wa)),
                    "{method:?}: omega {k} off by {w:e}"
                );
                if p.rotation {
                    assert!(norm(wa) > 1e-3, "{method:?}: no spin with rotation");
                }
            }
        }
    }
}

/// Two spheres pushed towards each other through the face `x = 0 = L`: the contact
/// holds them at touching distance (measured by the test's minimum image); without
/// contacts (overlap allowed) the same push makes them overlap.
fn contacts_across<T: Real>() {
    struct Squeeze;
    impl<T: Real> ExternalForce<T> for Squeeze {
        fn add(&mut self, _pos: &[T::V3], _radius: &[T], force: &mut [T::V3]) {
            force[0] += T::v3_from([-40.0, 0.0, 0.0]);
            force[1] += T::v3_from([40.0, 0.0, 0.0]);
        }
    }
    let l = 8.0;
    let s = [
        one([0.7, 4.0, 4.0], 0.5, RHO),
        one([7.3, 4.1, 4.0], 0.5, RHO),
    ];
    for method in [Method::Overdamped, Method::Overdamped2] {
        for with in [true, false] {
            let mut ps = particles::<T, 2>(&s);
            let bonds = BondSet::<T, 1>::new();
            let mut p = boxed::<T>(0.01, method, l);
            if with {
                p.contacts = Some(Contacts::new(1));
            } else {
                p.allow_overlap = true;
            }
            let mut buf = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
            let mut ws = buf.workspace();
            let reports = run(&mut ps, &bonds, &p, &mut ws, &mut Squeeze, 40);
            let r = norm(image(sub(f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1])), l));
            if with {
                let tol = 2.0 * p.solver.tolerance.to_f64();
                assert!(r >= 1.0 - tol, "{method:?}: overlap, |r| = {r}");
                assert!(r < 1.0 + 1e-3, "{method:?}: not in contact, |r| = {r}");
                assert_eq!(reports.last().unwrap().contacts, 1);
            } else {
                assert!(
                    r < 0.9,
                    "{method:?}: the push should overlap them (|r| = {r})"
                );
            }
        }
    }
}

/// A bond not shorter than half the smallest edge is refused with its index, the state
/// untouched; so are a radius of half the box, a box with a wall or with the Oseen
/// level, and FENE's maximum extension of half the box.
fn refusals<T: Real>() {
    let s = [
        one([1.0, 1.0, 1.0], 0.2, RHO),
        one([2.0, 1.0, 1.0], 0.2, RHO),
        one([1.0, 2.9, 1.0], 0.2, RHO),
    ];
    let mut ps = particles::<T, 3>(&s);
    let mut bonds = BondSet::<T, 2>::new();
    bonds.push_current(0, 1, &ps.pos[..3]).unwrap();
    bonds.push_current(0, 2, &ps.pos[..3]).unwrap();
    let before = snapshot(&ps);
    let mut buf = Buffers::<T>::new(Layout::all(3, 2));
    let mut ws = buf.workspace();
    for method in METHODS {
        // Edge 3.8: the second bond (1.9) is half of it.
        let p = Params {
            periodic: Some(
                Periodic::new([T::from_f64(4.0), T::from_f64(3.8), T::from_f64(5.0)]).unwrap(),
            ),
            ..params::<T>(0.01, method, SolverKind::Auto)
        };
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
        let bad = |e: &StepError| *e == StepError::Bond(BondError::BadLength { bond: 1 });
        assert_failed_unchanged(&before, &ps, &r, bad, "bond of half the box");
        assert!(format!("{}", r.unwrap_err()).contains("bond 1"));
        // A larger box takes the same step.
        let ok = Params {
            periodic: Some(cubic::<T>(4.0)),
            ..p
        };
        let mut copy = particles::<T, 3>(&s);
        step(&mut copy, &bonds, &ok, &mut ws, &mut NoForce).unwrap();
    }
    let base = boxed::<T>(0.01, Method::Overdamped, 4.0);
    let cases: [(Params<T>, &str); 2] = [
        (
            Params {
                wall: Some(Wall::new(T::ZERO)),
                ..base
            },
            "wall",
        ),
        (
            Params {
                hydro: Hydro::Oseen,
                ..base
            },
            "Oseen",
        ),
    ];
    for (p, what) in cases {
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
        let unsupported =
            |e: &StepError| matches!(e, StepError::Unsupported(m) if m.contains(what));
        assert_failed_unchanged(&before, &ps, &r, unsupported, what);
    }
    let fene = Params {
        method: Method::Springs,
        fene: Some(T::from_f64(2.0)),
        ..base
    };
    let r = step(&mut ps, &bonds, &fene, &mut ws, &mut NoForce);
    assert_failed_unchanged(
        &before,
        &ps,
        &r,
        |e| matches!(e, StepError::BadParameter(_)),
        "fene",
    );
    let big = particles::<T, 3>(&[one([1.0, 1.0, 1.0], 2.0, RHO)]);
    let mut big = big;
    let before_big = snapshot(&big);
    let none = BondSet::<T, 2>::new();
    let r = step(&mut big, &none, &base, &mut ws, &mut NoForce);
    let radius =
        |e: &StepError| *e == StepError::Particle(ParticleError::BadRadius { particle: 0 });
    assert_failed_unchanged(&before_big, &big, &r, radius, "radius of half the box");
}

both_precisions! {
    lone_sphere_hasimoto => lone_sphere;
    translation_same_bits => translation_bits;
    straddling_bond_kept => straddling_bond;
    contacts_across_the_face => contacts_across;
    refused_typed_state_kept => refusals;
}
