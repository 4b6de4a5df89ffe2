//! Constraints on the iterative near field (`Params::near` with `Params::matrix_free`,
//! bonds and pins by the Krylov solve whose every product is one conjugate-gradient
//! product of `M_SD`): against the dense near step with the same solver (`near_step.rs`
//! checks that one against exact two-sphere hydrodynamics) on chains of close beads;
//! a bonded dimer against the bond projection with the two-sphere mobility and against
//! Stimson and Jeffery's exact series and the published side-by-side value; the bonds
//! and pins held to the solver's tolerance, measured here from the positions; the same
//! bits run to run; the refusals, typed, with the state unchanged. Units: `a = 1`,
//! `eta = 1`, buoyant weight 1 for a unit sphere (`U0 = 1 / (6 pi)`).
#![cfg(all(feature = "near", feature = "periodic"))]

use crate::common;
use crate::near_step::projected;
use crate::stokesian::stimson_jeffery;

use std::f64::consts::PI;

use common::*;
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    Bond, BondSet, Brownian, Contacts, Method, NoForce, Noise, ParticleSet, Periodic, Real,
    SolverKind, Stage, StepError, StepReport, step,
};
use hydrorattle_heap::Buffers;

/// Stokes' speed of the unit sphere of unit buoyant weight in the unit fluid.
const U0: f64 = 1.0 / (6.0 * PI);
/// Density of unit buoyant weight for a unit sphere (`g = 1`).
const RHO1: f64 = 3.0 / (4.0 * PI);

/// Near-field parameters with rotation and the Krylov solver (`Auto` resolves to it on
/// the iterative path), time step `dt`; iterative when `iterative`; in the cubic box
/// of edge `l` if given.
pub(crate) fn near<T: Real>(iterative: bool, dt: f64, l: Option<f64>) -> hydrorattle::Params<T> {
    let mut p = params::<T>(dt, Method::Overdamped, SolverKind::Krylov);
    p.near = Some(NearField::default());
    p.rotation = true;
    p.matrix_free = iterative;
    p.periodic = l.map(|l| Periodic::new([T::from_f64(l); 3]).unwrap());
    p
}

/// What a run returns: each step's report and the positions after the last.
pub(crate) type Run<T> = (Vec<StepReport<T>>, Vec<[f64; 3]>);

/// `steps` steps of `spheres` with `rows` (bonds and pins) under `p` in one workspace,
/// or the first error with the state as it was before that step (asserted bit for bit).
pub(crate) fn run<T: Real>(
    p: &hydrorattle::Params<T>,
    spheres: &[Sphere],
    rows: &[Bond<T>],
    steps: usize,
) -> Result<Run<T>, StepError> {
    let mut ps: ParticleSet<T, 64> = particles(spheres);
    // A generator, so that a thermal step is refused by the near field, not for lack of it.
    ps.noise = Some(Noise::new(1));
    let mut set: BondSet<T, 64> = BondSet::new();
    for &b in rows {
        set.push(b, spheres.len()).unwrap();
    }
    let layout = hydrorattle::Layout::for_params(p, spheres.len(), rows.len());
    let mut buf = Buffers::<T>::new(layout);
    let mut ws = buf.workspace();
    let n = spheres.len();
    let mut reports = Vec::new();
    for _ in 0..steps {
        let before = snapshot(&ps);
        let r = step(&mut ps, &set, p, &mut ws, &mut NoForce);
        if let Err(e) = r {
            assert_eq!(before, snapshot(&ps), "{e:?}: the state moved");
            return Err(e);
        }
        reports.push(r.unwrap());
    }
    let pos = (0..n).map(|i| f64s::<T>(ps.pos[i])).collect();
    Ok((reports, pos))
}

/// The bonds of a chain along `spheres`, at their current lengths.
pub(crate) fn chain<T: Real>(spheres: &[Sphere]) -> Vec<Bond<T>> {
    let pos: Vec<T::V3> = spheres.iter().map(|s| T::v3_from(s.pos)).collect();
    let set: BondSet<T, 64> = BondSet::chain(&pos).unwrap();
    set.as_slice().to_vec()
}

/// A chain of `n` beads of radii 0.8 to 1.3 (or 1), bond `D = 1.05` (gaps of 0.05 mean
/// radii, the paper's chain), bent a little at every bead, about `c`.
pub(crate) fn bent_chain(n: usize, unequal: bool, c: [f64; 3]) -> Vec<Sphere> {
    let radii: Vec<f64> = (0..n)
        .map(|k| match unequal {
            true => 0.8 + 0.5 * ((k * 7 % 5) as f64) / 4.0,
            false => 1.0,
        })
        .collect();
    let dirs: Vec<[f64; 3]> = (0..n)
        .map(|k| {
            let t = 0.7 * k as f64;
            [1.0, 0.4 * t.sin(), 0.3 * t.cos() + 0.2]
        })
        .collect();
    let mut s = path(&radii, &dirs, 1.05, RHO1);
    let mid = scale(
        s.iter().fold([0.0; 3], |a, s| add(a, s.pos)),
        1.0 / n as f64,
    );
    for s in &mut s {
        s.pos = add(sub(s.pos, mid), c);
    }
    s
}

/// Largest bond error `| |r_ij| - d | / d` of `rows`' bonds in `pos` (f64, here).
pub(crate) fn bond_error<T: Real>(rows: &[Bond<T>], pos: &[[f64; 3]]) -> f64 {
    rows.iter()
        .filter(|b| b.j < pos.len())
        .map(|b| {
            let d = b.length.to_f64();
            (norm(sub(pos[b.i], pos[b.j])) - d).abs() / d
        })
        .fold(0.0, f64::max)
}

/// Chains of 2, 3 and 10 close beads (equal and unequal, free space, a box) falling
/// five steps: the iterative step with the Krylov solve ends where the dense near step
/// with the Krylov solve does, within the tolerances (the products' relative residual
/// and the bonds' relative error: 1e-10 in f64, 1e-5 in f32, the solver's default),
/// relative to the distance fallen; the reports count `M_SD`'s products (the start's,
/// one a Krylov iteration, the spins') and no dense formation.
fn matches_dense<T: Real>() {
    matches_dense_by::<T>(Method::Overdamped);
}

/// [`matches_dense`] by `method`; `Overdamped2`'s reports count the products of its
/// two velocity projections and two position projections (`M_SD` at the start,
/// at the predicted point, at the start again), its spins' and its two velocities'.
fn matches_dense_by<T: Real>(method: Method) {
    let tol = pick::<T>(1e-2, 1e-6);
    let dt = 0.1;
    let near = |iterative, dt, l| {
        let mut p = near::<T>(iterative, dt, l);
        p.method = method;
        p
    };
    for (n, unequal, l) in [
        (2, false, None),
        (3, true, None),
        (10, false, None),
        (10, true, None),
        (10, false, Some(40.0)),
    ] {
        let c = l.map_or([0.0; 3], |l| [l / 2.0; 3]);
        let spheres = bent_chain(n, unequal, c);
        let rows = chain::<T>(&spheres);
        let (rd, dense) = run::<T>(&near(false, dt, l), &spheres, &rows, 5).unwrap();
        let (ri, iter) = run::<T>(&near(true, dt, l), &spheres, &rows, 5).unwrap();
        let fallen = spheres
            .iter()
            .zip(&dense)
            .map(|(s, x)| norm(sub(*x, s.pos)))
            .fold(0.0, f64::max);
        let gap = iter
            .iter()
            .zip(&dense)
            .map(|(a, b)| norm(sub(*a, *b)))
            .fold(0.0, f64::max);
        let what = format!("{method:?}: {n} beads, unequal {unequal}, box {l:?}");
        println!(
            "{what}: fallen {fallen:.3e}, gap {:.1e}, products {:?}, pcg {:?}, krylov {:?} (dense {:?})",
            gap / fallen,
            ri.iter().map(|r| r.near_products).collect::<Vec<_>>(),
            ri.iter().map(|r| r.near_iterations).collect::<Vec<_>>(),
            ri.iter().map(|r| r.iterations).collect::<Vec<_>>(),
            rd.iter().map(|r| r.iterations).collect::<Vec<_>>(),
        );
        assert!(fallen > 0.5 * 5.0 * dt * U0, "{what}: fell {fallen}");
        assert!(gap < tol * fallen, "{what}: {gap:e} of {fallen:e}");
        for r in &ri {
            if method == Method::Overdamped {
                assert_eq!(r.near_products, r.iterations + 2, "{what}: {r:?}");
            } else {
                // The start's velocity and spins, the predicted point's velocity.
                assert!(r.near_products >= r.iterations + 3, "{what}: {r:?}");
            }
            assert!(r.near_pairs as usize >= n - 1, "{what}: {r:?}");
            assert_eq!(r.near_formations, 0, "{what}");
        }
        let formed = if method == Method::Overdamped { 1 } else { 2 };
        assert!(
            rd.iter().all(|r| r.near_formations == formed),
            "{what}: dense"
        );
    }
}

/// Two unit spheres 2.1 apart about the origin, their line of centres tilted 60
/// degrees from the vertical, of buoyant weights `w`.
fn tilted_dimer(w: [f64; 2]) -> [Sphere; 2] {
    let th = 60f64.to_radians();
    let c = scale([th.sin(), 0.0, th.cos()], 1.05);
    let mut spheres = [scale(c, -1.0), c].map(|pos| Sphere {
        pos,
        radius: 1.0,
        density: RHO1,
    });
    for (s, w) in spheres.iter_mut().zip(w) {
        s.density = w * RHO1;
    }
    spheres
}

/// A bonded pair (bond 2.1 radii) tilted 60 degrees, one sphere three times as heavy
/// as the other, by the iterative step: it falls and turns as the bond projection with
/// the two-sphere mobility says (`near_step::projected`), its mean velocity is Stimson
/// and Jeffery's along the bond and 1.3917 `U0` across it (within 0.5 %), with the
/// solver `Krylov` and `Auto`.
fn bonded_pair<T: Real>() {
    bonded_pair_by::<T>(Method::Overdamped);
}

/// [`bonded_pair`] by `method`.
fn bonded_pair_by<T: Real>(method: Method) {
    let th = 60f64.to_radians();
    let axis = [th.sin(), 0.0, th.cos()];
    let spheres = tilted_dimer([1.5, 0.5]);
    let want = projected(&spheres, [1.5, 0.5]);
    let (along, across) = (th.cos(), th.sin());
    for kind in [SolverKind::Krylov, SolverKind::Auto] {
        let mut p = near::<T>(true, 1e-2, None);
        p.method = method;
        p.solver.kind = kind;
        p.solver.tolerance = T::from_f64(pick::<T>(1e-5, 1e-12));
        let rows = chain::<T>(&spheres);
        let (r, x) = run::<T>(&p, &spheres, &rows, 1).unwrap();
        // (`Overdamped2`'s trapezoid of projected velocities keeps the bond to
        // within its tolerance: its constraint forces are the velocity projection's.)
        let solved = match method {
            Method::Overdamped => r[0].iterations > 0,
            _ => r[0].max_tension.to_f64() > 0.0,
        };
        assert!(solved, "{kind:?}: no constraint solve");
        let v: Vec<[f64; 3]> = x
            .iter()
            .zip(&spheres)
            .map(|(x, s)| scale(sub(*x, s.pos), 1.0 / 1e-2))
            .collect();
        let scale_u = norm(want[0]).max(norm(want[1]));
        for (got, w) in v.iter().zip(&want) {
            let e = norm(sub(*got, *w)) / scale_u;
            assert!(e < pick::<T>(3e-3, 1e-3), "{kind:?}: {got:?} vs {w:?}");
        }
        let mean = scale(add(v[0], v[1]), 0.5);
        let u_along = -dot(mean, axis);
        let perp = [axis[2], 0.0, -axis[0]];
        let u_across = dot(mean, perp).abs();
        let e = (u_along / (stimson_jeffery(2.1) * U0 * along) - 1.0).abs();
        assert!(e < 5e-3, "{kind:?}: along {u_along} ({e:e})");
        let e = (u_across / (1.3917 * U0 * across) - 1.0).abs();
        assert!(e < 5e-3, "{kind:?}: across {u_across} ({e:e})");
        let turn = sub(v[1], v[0]);
        assert!(norm(turn) > 0.05 * norm(mean), "no turn {turn:?}");
    }
}

/// A chain of twelve close beads hung from a pinned first bead, twenty steps: after
/// each, every bond's error measured here is within the solver's tolerance (and
/// rounding), the pinned bead is where it started, bit for bit, and the free end has
/// swung.
fn bonds_held<T: Real>() {
    bonds_held_by::<T>(Method::Overdamped);
}

/// [`bonds_held`] by `method`.
fn bonds_held_by<T: Real>(method: Method) {
    let spheres = bent_chain(12, true, [0.0; 3]);
    let mut rows = chain::<T>(&spheres);
    rows.extend(Bond::pins(0, T::from_f64(spheres[0].radius)));
    let mut p = near::<T>(true, 0.2, None);
    p.method = method;
    let tol = p.solver.tolerance.to_f64();
    let slack = tol + 8.0 * T::EPSILON.to_f64();
    let mut s = spheres.clone();
    for k in 0..20 {
        let (r, x) = run::<T>(&p, &s, &rows, 1).unwrap();
        let e = bond_error(&rows, &x);
        assert!(e <= slack, "step {k}: bond error {e:e}");
        assert!(r[0].residual.to_f64() <= tol, "step {k}: {r:?}");
        let pin = T::v3_from(spheres[0].pos);
        assert_eq!(
            f64s::<T>(pin).map(f64::to_bits),
            x[0].map(f64::to_bits),
            "step {k}: the pin moved"
        );
        for (s, x) in s.iter_mut().zip(x) {
            s.pos = x;
        }
    }
    let swung = norm(sub(s[11].pos, spheres[11].pos));
    assert!(swung > 20.0 * 0.2 * U0 * 0.1, "the end moved {swung}");
}

/// A 40-bead chain of equal and of unequal close beads falling three steps: the
/// iterative step's constraint solve takes about as many products as the dense
/// step's (whose band preconditioner reads `M_SD`'s own entries), at most one more a
/// step on average. With the far field's entries alone the iterative solve took about
/// twice as many: its band had no lubrication between the bonded beads, whose relative
/// mobility along the bond it overstated several times.
fn products_as_dense<T: Real>() {
    for unequal in [false, true] {
        let spheres = bent_chain(40, unequal, [0.0; 3]);
        let rows = chain::<T>(&spheres);
        let (rd, _) = run::<T>(&near(false, 0.1, None), &spheres, &rows, 3).unwrap();
        let (ri, _) = run::<T>(&near(true, 0.1, None), &spheres, &rows, 3).unwrap();
        let mean = |r: &[StepReport<T>]| {
            r.iter().map(|r| r.iterations as f64).sum::<f64>() / r.len() as f64
        };
        let (d, i) = (mean(&rd), mean(&ri));
        println!("unequal {unequal}: Krylov products a step, dense {d}, iterative {i}");
        assert!(i <= d + 1.0, "unequal {unequal}: iterative {i}, dense {d}");
    }
}

/// Two runs of four steps of a ten-bead chain in a box end on the same bits, and
/// report the same counts.
fn same_bits<T: Real>() {
    let spheres = bent_chain(10, true, [10.0; 3]);
    let rows = chain::<T>(&spheres);
    let p = near::<T>(true, 0.1, Some(20.0));
    let bits = || {
        let (r, x) = run::<T>(&p, &spheres, &rows, 4).unwrap();
        let x: Vec<[u64; 3]> = x.iter().map(|v| v.map(f64::to_bits)).collect();
        (x, r)
    };
    assert_eq!(bits(), bits());
}

/// What was refused steps (the sweep, Newton, contacts, `Overdamped2` and thermal
/// noise, the bonds held); a product of the constraint solve that does not converge
/// within the iterations allowed is `NoConvergence` at the mobility, the state
/// unchanged.
fn refusals<T: Real>() {
    let spheres = bent_chain(6, false, [0.0; 3]);
    let rows = chain::<T>(&spheres);
    let base = near::<T>(true, 0.1, None);
    // The sweep and Newton step, on their table of `M_SD`'s columns; refused before.
    for kind in [SolverKind::Sweep, SolverKind::Newton] {
        let mut p = base;
        p.solver.kind = kind;
        let (r, x) = run::<T>(&p, &spheres, &rows, 1).unwrap();
        assert_eq!(
            r[0].near_products as usize,
            rows.len() + 2,
            "{kind:?}: {r:?}"
        );
        let e = bond_error(&rows, &x);
        assert!(
            e <= p.solver.tolerance.to_f64() + 8.0 * T::EPSILON.to_f64(),
            "{kind:?}"
        );
    }
    // `Overdamped2` steps, the bonds held (refused before).
    let mut p = base;
    p.method = Method::Overdamped2;
    let (r, x) = run::<T>(&p, &spheres, &rows, 1).unwrap();
    assert!(
        r[0].max_tension.to_f64() > 0.0 && r[0].near_products > 0,
        "{r:?}"
    );
    assert!(bond_error(&rows, &x) <= p.solver.tolerance.to_f64() + 8.0 * T::EPSILON.to_f64());
    // Thermal noise steps, the bonds held (refused before; `near_con_brownian.rs`).
    let mut p = base;
    p.brownian = Some(Brownian::new(T::from_f64(1e-3)));
    let (r, x) = run::<T>(&p, &spheres, &rows, 1).unwrap();
    assert!(
        r[0].noise_iterations > 0 && r[0].velocity_iterations > 0,
        "{r:?}"
    );
    assert!(bond_error(&rows, &x) <= p.solver.tolerance.to_f64() + 8.0 * T::EPSILON.to_f64());
    // Contacts with the Krylov solve step (`near_contacts.rs`); refused before.
    let mut p = base;
    p.contacts = Some(Contacts::new(16));
    let (r, x) = run::<T>(&p, &spheres, &rows, 1).unwrap();
    assert!(r[0].iterations > 0, "{r:?}");
    assert!(bond_error(&rows, &x) <= p.solver.tolerance.to_f64() + 8.0 * T::EPSILON.to_f64());
    // Weightless beads whose bonds are 2 % short of their separations: the start's
    // product has nothing to solve, the constraint solve's products do, and two
    // conjugate-gradient iterations cannot solve six coupled close beads.
    let light: Vec<Sphere> = spheres
        .iter()
        .map(|s| Sphere { density: 0.0, ..*s })
        .collect();
    let short: Vec<Bond<T>> = rows
        .iter()
        .map(|b| Bond {
            length: b.length * T::from_f64(0.98),
            ..*b
        })
        .collect();
    let mut p = base;
    p.fluid_density = T::ZERO;
    p.solver.max_iterations = 2;
    match run::<T>(&p, &light, &short, 1) {
        Err(StepError::NoConvergence {
            stage: Stage::Mobility,
            ..
        }) => {}
        other => panic!("two iterations: {other:?}"),
    }
    // With its iterations the same step holds the shortened bonds.
    p.solver.max_iterations = base.solver.max_iterations;
    let (r, x) = run::<T>(&p, &light, &short, 1).unwrap();
    assert!(r[0].iterations > 0 && r[0].near_iterations > 0, "{r:?}");
    let e = bond_error(&short, &x);
    assert!(e <= p.solver.tolerance.to_f64() + 8.0 * T::EPSILON.to_f64());
}

/// A bonded pair (bond 2.1 radii, tilted 60 degrees, buoyant weights 1.9 and 0.1)
/// falling and turning for 32 time units by the iterative step, f64, the products and
/// the constraints to 1e-12: against a run at `dt = 1/16`, halving `dt` from 2 to 0.5
/// cuts `Overdamped2`'s error about four times (second order: 3 to 5 allowed) and
/// `Overdamped`'s about twice (1.5 to 2.5), the pair having turned by more than 0.2
/// radians.
#[test]
fn overdamped2_second_order() {
    let spheres = tilted_dimer([1.9, 0.1]);
    let rows = chain::<f64>(&spheres);
    let end = 32.0;
    let at = |method, dt: f64| {
        let mut p = near::<f64>(true, dt, None);
        p.method = method;
        p.solver.tolerance = 1e-12;
        p.solver.max_iterations = 1000;
        let (_, x) = run::<f64>(&p, &spheres, &rows, (end / dt).round() as usize).unwrap();
        x
    };
    for (method, low, high) in [
        (Method::Overdamped2, 3.0, 5.0),
        (Method::Overdamped, 1.5, 2.5),
    ] {
        let exact = at(method, 1.0 / 16.0);
        let turned = {
            let (a, b) = (sub(spheres[1].pos, spheres[0].pos), sub(exact[1], exact[0]));
            (dot(a, b) / (norm(a) * norm(b))).acos()
        };
        assert!(turned > 0.2, "{method:?}: turned {turned}");
        let error = |dt| {
            let x = at(method, dt);
            x.iter()
                .zip(&exact)
                .map(|(a, b)| norm(sub(*a, *b)))
                .fold(0.0, f64::max)
        };
        let e: Vec<f64> = [2.0, 1.0, 0.5].map(error).to_vec();
        let ratios = [e[0] / e[1], e[1] / e[2]];
        println!("{method:?}: turned {turned:.3}, errors {e:?}, ratios {ratios:.2?}");
        for r in ratios {
            assert!(r > low && r < high, "{method:?}: errors {e:?}");
        }
    }
}

/// `Overdamped2` ([`matches_dense`], [`bonded_pair`], [`bonds_held`]).
fn matches_dense2<T: Real>() {
    matches_dense_by::<T>(Method::Overdamped2);
}

fn bonded_pair2<T: Real>() {
    bonded_pair_by::<T>(Method::Overdamped2);
}

fn bonds_held2<T: Real>() {
    bonds_held_by::<T>(Method::Overdamped2);
}

both_precisions! {
    matches_dense2 => matches_dense2;
    bonded_pair2 => bonded_pair2;
    bonds_held2 => bonds_held2;
    matches_dense => matches_dense;
    bonded_pair => bonded_pair;
    bonds_held => bonds_held;
    products_as_dense => products_as_dense;
    same_bits => same_bits;
    refusals => refusals;
}
