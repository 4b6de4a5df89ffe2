//! Steps with the iterative near field (`Params::near` with `Params::matrix_free`:
//! conjugate gradients over the close pairs, `M_SD` never formed), against the dense near
//! step (`near_step.rs`, `near_box.rs`: there checked against Stimson and Jeffery's exact
//! series and the box's known correction) on clusters with close pairs, in free space,
//! in the box and above the wall, to the iteration's tolerance; against Stimson and
//! Jeffery's exact series, the published side-by-side values at `s = 2.1` and
//! Brenner's exact series for a sphere approaching the wall directly; the same bits run to run; and the
//! refusals, typed, with the state unchanged. Units: `a = 1`, `eta = 1`, buoyant weight
//! 1 (`U0 = 1 / (6 pi)`).
#![cfg(all(feature = "near", feature = "periodic"))]

use crate::common;
use crate::stokesian::{brenner, stimson_jeffery};

use std::f64::consts::PI;

use common::*;
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    Bond, BondSet, Contacts, Method, NoForce, Noise, ParticleSet, Periodic, Real, SolverKind,
    Stage, StepError, StepReport, Wall, step,
};
use hydrorattle_heap::Buffers;

/// Stokes' speed of the unit sphere of unit buoyant weight in the unit fluid.
pub(crate) const U0: f64 = 1.0 / (6.0 * PI);
/// Density of unit buoyant weight for a unit sphere (`g = 1`).
pub(crate) const RHO1: f64 = 3.0 / (4.0 * PI);

/// Positions, velocities and spins after a step.
pub(crate) type Out = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>);

/// Near-field parameters with the defaults and rotation; iterative when `iterative`; in
/// the cubic box of edge `l` if given.
fn near<T: Real>(method: Method, iterative: bool, l: Option<f64>) -> hydrorattle::Params<T> {
    let mut p = params::<T>(1e-2, method, SolverKind::Auto);
    p.near = Some(NearField::default());
    p.rotation = true;
    p.matrix_free = iterative;
    p.periodic = l.map(|l| Periodic::new([T::from_f64(l); 3]).unwrap());
    p
}

/// One step of `spheres` with `bonds` under `p`: its report and the state after it,
/// or the error with the state as it was before (asserted bit for bit).
fn one_step<T: Real>(
    p: &hydrorattle::Params<T>,
    spheres: &[Sphere],
    bonds: &[Bond<T>],
) -> Result<(StepReport<T>, Out), StepError> {
    let mut ps: ParticleSet<T, 128> = particles(spheres);
    // A generator, as a thermal step would need.
    ps.noise = Some(Noise::new(1));
    let mut set: BondSet<T, 128> = BondSet::new();
    for &b in bonds {
        set.push(b, spheres.len()).unwrap();
    }
    let mut buf = Buffers::<T>::new(hydrorattle::Layout::for_params(
        p,
        spheres.len(),
        bonds.len(),
    ));
    let mut ws = buf.workspace();
    let n = spheres.len();
    let get = |v: &[T::V3]| -> Vec<[f64; 3]> { (0..n).map(|i| f64s::<T>(v[i])).collect() };
    let before = (get(&ps.pos), get(&ps.vel), get(&ps.omega));
    match step(&mut ps, &set, p, &mut ws, &mut NoForce) {
        Ok(r) => Ok((r, (get(&ps.pos), get(&ps.vel), get(&ps.omega)))),
        Err(e) => {
            let after = (get(&ps.pos), get(&ps.vel), get(&ps.omega));
            assert_eq!(before, after, "{e:?}: the state moved");
            Err(e)
        }
    }
}

/// A branched cluster of `n` spheres (radii 0.8 to 1.5, densities 0.5 to 2 times
/// `RHO1`), each new sphere at a gap of 0.005 to 0.6 mean radii from a random earlier
/// one and clear of all (by the minimum image in the box of edge `l`), about `c`.
pub(crate) fn cluster(n: usize, seed: u64, l: Option<f64>, c: [f64; 3]) -> Vec<Sphere> {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut rand = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let image = |d: [f64; 3]| match l {
        Some(l) => d.map(|x| x - l * (x / l).round()),
        None => d,
    };
    let mut out = vec![Sphere {
        pos: c,
        radius: 1.0,
        density: RHO1,
    }];
    while out.len() < n {
        let k = (rand() * out.len() as f64) as usize;
        let a = 0.8 + 0.7 * rand();
        let gap = 0.005 + 0.6 * rand() * rand();
        let (z, phi) = (2.0 * rand() - 1.0, 2.0 * PI * rand());
        let r = (1.0 - z * z).sqrt();
        let e = [r * phi.cos(), r * phi.sin(), z];
        let d = out[k].radius + a + gap * 0.5 * (out[k].radius + a);
        let mut pos = add(out[k].pos, scale(e, d));
        if let Some(l) = l {
            pos = pos.map(|x| x.rem_euclid(l));
        }
        let clear = out.iter().all(|s| {
            let d = norm(image(sub(pos, s.pos)));
            d > (s.radius + a) * (1.0 + 0.0025)
        });
        if clear {
            out.push(Sphere {
                pos,
                radius: a,
                density: RHO1 * (0.5 + 1.5 * rand()),
            });
        }
    }
    out
}

/// Largest difference of `a` from `b` over the largest of `b`.
pub(crate) fn relative_gap(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let big = b.iter().map(|v| norm(*v)).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| norm(sub(*x, *y)))
        .fold(0.0, f64::max);
    diff / big
}

/// Clusters of 2 to 50 spheres with close pairs, in free space and in a box: the
/// iterative step's velocities and spins are the dense near step's within the
/// iteration's tolerance (relative residual 1e-10 in f64, 1e-5 in f32, the solver's
/// default; the error is that times the inner system's condition, and f32's dense
/// inversions carry their own rounding), with both overdamped methods; the report
/// counts the close pairs, the products (one or two) and their iterations.
fn matches_dense<T: Real>() {
    let tol = pick::<T>(5e-3, 1e-7);
    for (n, seed, l) in [
        (2, 1, None),
        (7, 2, None),
        (20, 3, None),
        (50, 4, None),
        (6, 5, Some(9.0)),
        (20, 6, Some(14.0)),
        (50, 7, Some(20.0)),
    ] {
        let c = l.map_or([0.0; 3], |l| [l / 2.0; 3]);
        let spheres = cluster(n, seed, l, c);
        for method in [Method::Overdamped, Method::Overdamped2] {
            let dense = one_step::<T>(&near(method, false, l), &spheres, &[]).unwrap();
            let (r, iter) = one_step::<T>(&near(method, true, l), &spheres, &[]).unwrap();
            let what = format!("{n} spheres, {l:?}, {method:?}");
            let dv = relative_gap(&iter.1, &dense.1.1);
            let dw = relative_gap(&iter.2, &dense.1.2);
            println!(
                "{what}: pairs {}, products {}, iterations {}, velocities {dv:.1e}, spins {dw:.1e}",
                r.near_pairs, r.near_products, r.near_iterations
            );
            assert!(dv < tol && dw < tol, "{what}: {dv:e} {dw:e}");
            assert!(
                r.near_pairs as usize >= n - 1,
                "{what}: a tree's pairs at least"
            );
            let products = if method == Method::Overdamped { 1 } else { 2 };
            assert_eq!(r.near_products, products, "{what}");
            assert!(r.near_iterations >= products, "{what}");
            assert_eq!(r.near_formations, 0, "{what}: formed M_SD");
            assert_eq!(dense.0.near_formations, products, "{what}: dense");
        }
    }
}

/// Two equal spheres at `s = 2.1` by the iterative step, free space: along their line
/// of centres at Stimson and Jeffery's speed, side by side at 1.3917 `U0` (within
/// 0.5 %), spinning at 0.137 `U0 / a` (within 2 %), with both overdamped methods.
fn pair_falls<T: Real>() {
    for method in [Method::Overdamped, Method::Overdamped2] {
        let p = near::<T>(method, true, None);
        let one = |p: &_, s: &[Sphere]| one_step::<T>(p, s, &[]).unwrap();
        falls_as_exact(&p, &format!("{method:?}"), one);
    }
}

/// [`pair_falls`]'s checks of the step `one` of two equal spheres at `s = 2.1` under
/// `p` (`what` names it): along their line of centres, then side by side.
pub(crate) fn falls_as_exact<T: Real, P>(
    p: &P,
    what: &str,
    one: impl Fn(&P, &[Sphere]) -> (StepReport<T>, Out),
) {
    let pair = |axis: [f64; 3]| {
        let d = scale(axis, 1.05);
        [-1.0, 1.0].map(|s| Sphere {
            pos: scale(d, s),
            radius: 1.0,
            density: RHO1,
        })
    };
    let (r, (_, v, _)) = one(p, &pair([0.0, 0.0, 1.0]));
    assert_eq!(r.near_pairs, 1, "{what}");
    let want = stimson_jeffery(2.1) * U0;
    for vi in &v {
        let e = (-vi[2] / want - 1.0).abs();
        assert!(e < 5e-3, "{what} along: {} U0", -vi[2] / U0);
    }
    let (_, (_, v, w)) = one(p, &pair([1.0, 0.0, 0.0]));
    for (vi, wi) in v.iter().zip(&w) {
        let e = (-vi[2] / (1.3917 * U0) - 1.0).abs();
        assert!(e < 5e-3, "{what} across: {} U0", -vi[2] / U0);
        let e = (norm(*wi) / (0.137 * U0) - 1.0).abs();
        assert!(e < 0.02, "{what} spin: {} U0", norm(*wi) / U0);
    }
}

/// Two runs of three steps of 30 spheres in a box end on the same bits.
fn same_bits<T: Real>() {
    let l = 16.0;
    let spheres = cluster(30, 11, Some(l), [8.0; 3]);
    let p = near::<T>(Method::Overdamped, true, Some(l));
    let run = || {
        let mut s = spheres.clone();
        for _ in 0..3 {
            let (_, (x, _, _)) = one_step::<T>(&p, &s, &[]).unwrap();
            for (s, x) in s.iter_mut().zip(x) {
                s.pos = x;
            }
        }
        s.iter()
            .map(|s| s.pos.map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(run(), run());
}

/// Refused, typed, the state unchanged: what the iterative path does not serve (the
/// wall's hydrodynamics, refused before, now stepped; PSE's far field, free space's and
/// the box's: `near_fast.rs`, `near_pse.rs`), the conjugate gradients
/// stopped before they converge, and more close pairs than the storage holds (its
/// Brownian steps: `near_iter_brownian.rs`).
fn refusals<T: Real>() {
    let spheres = cluster(20, 21, None, [0.0; 3]);
    let base = near::<T>(Method::Overdamped, true, None);
    let bond = Bond {
        i: 0,
        j: 1,
        length: T::from_f64(norm(sub(spheres[1].pos, spheres[0].pos))),
    };
    // Bonds by the sweep, contacts alone by Krylov and by Newton step
    // (`near_con.rs`, `near_contacts.rs`); refused before.
    let mut p = base;
    p.solver.kind = SolverKind::Sweep;
    one_step::<T>(&p, &spheres, &[bond]).unwrap();
    let mut p = base;
    p.contacts = Some(Contacts::new(64));
    one_step::<T>(&p, &spheres, &[]).unwrap();
    p.solver.kind = SolverKind::Newton;
    one_step::<T>(&p, &spheres, &[]).unwrap();
    // Above the wall (its links one-sided constraints): stepped (`wall_matches_dense`).
    let mut p = base;
    p.wall = Some(Wall::new(T::from_f64(-40.0)));
    let (r, _) = one_step::<T>(&p, &spheres, &[]).unwrap();
    assert!(r.near_products >= 1, "{r:?}");
    // One iteration cannot solve twenty coupled spheres.
    let mut p = base;
    p.solver.max_iterations = 1;
    match one_step::<T>(&p, &spheres, &[]) {
        Err(StepError::NoConvergence {
            stage: Stage::Mobility,
            iterations: 1,
            ..
        }) => {}
        other => panic!("one iteration: {other:?}"),
    }
    // Every pair of 100 spheres inside a cutoff of 40 radii: 4950 pairs, above the
    // storage's 48 a sphere.
    let lattice: Vec<Sphere> = (0..100)
        .map(|k| Sphere {
            pos: [(k % 5) as f64, (k / 5 % 5) as f64, (k / 25) as f64].map(|x| 2.5 * x),
            radius: 1.0,
            density: RHO1,
        })
        .collect();
    let mut p = base;
    p.near = Some(NearField {
        cutoff: T::from_f64(40.0),
        ..NearField::default()
    });
    match one_step::<T>(&p, &lattice, &[]) {
        Err(StepError::Unsupported(m)) => assert!(m.contains("close pairs"), "{m}"),
        other => panic!("too many pairs: {other:?}"),
    }
}

macro_rules! both {
    ($($name:ident),*) => {
        $(mod $name {
            #[test]
            fn f32() { super::$name::<f32>() }
            #[test]
            fn f64() { super::$name::<f64>() }
        })*
    };
}

/// Clusters of 1 to 20 spheres above the wall, the lowest within 0.01 to 0.5 radii of
/// it: the iterative step's velocities and spins are the dense near step's (the same
/// wall corrections, the same Blake far field) within the iteration's tolerance, as in
/// free space ([`matches_dense`]); every sphere inside the wall's cutoff counts as one
/// entry besides the close pairs.
fn wall_matches_dense<T: Real>() {
    let tol = pick::<T>(5e-3, 1e-7);
    for (n, seed, gap) in [(1, 1, 0.1), (2, 31, 0.01), (7, 32, 0.05), (20, 33, 0.5)] {
        let spheres = cluster(n, seed, None, [0.0; 3]);
        let floor = spheres
            .iter()
            .map(|s| s.pos[2] - s.radius)
            .fold(f64::INFINITY, f64::min);
        let wall = floor - gap;
        let at_wall = |iterative| {
            let mut p = near::<T>(Method::Overdamped, iterative, None);
            p.wall = Some(Wall::new(T::from_f64(wall)));
            p
        };
        let (rd, dense) = one_step::<T>(&at_wall(false), &spheres, &[]).unwrap();
        let (r, iter) = one_step::<T>(&at_wall(true), &spheres, &[]).unwrap();
        // Spins over the largest velocity too (radii near 1): a lone sphere does not spin.
        let big = dense.1.iter().map(|v| norm(*v)).fold(0.0, f64::max);
        let apart = |a: &[[f64; 3]], b: &[[f64; 3]]| {
            let d = a.iter().zip(b).map(|(x, y)| norm(sub(*x, *y)));
            d.fold(0.0, f64::max) / big
        };
        let (dv, dw) = (apart(&iter.1, &dense.1), apart(&iter.2, &dense.2));
        let what = format!("{n} spheres, gap {gap}");
        println!(
            "{what}: entries {}, iterations {}, velocities {dv:.1e}, spins {dw:.1e}",
            r.near_pairs, r.near_iterations
        );
        assert!(dv < tol && dw < tol, "{what}: {dv:e} {dw:e}");
        let walls = spheres
            .iter()
            .filter(|s| (s.pos[2] - wall) / s.radius - 1.0 < 4.0)
            .count();
        assert!(
            walls >= 1 && r.near_pairs as usize >= n - 1 + walls,
            "{what}"
        );
        assert_eq!(r.near_formations, 0, "{what}: formed M_SD");
        assert!(rd.near_formations >= 1, "{what}: dense");
    }
}

/// A sphere at `h / a = 1.1` above the wall by the iterative step approaches it at
/// Brenner's speed (his exact series, `stokesian.rs`), within 0.5 %, as the dense step
/// does (`near_step.rs`); one entry (the sphere near the wall), solved exactly by the
/// preconditioner: one iteration a product.
fn wall_approach<T: Real>() {
    let sphere = [Sphere {
        pos: [0.0, 0.0, 1.1],
        radius: 1.0,
        density: RHO1,
    }];
    let want = brenner(1.1) * U0;
    let mut p = near::<T>(Method::Overdamped, true, None);
    p.dt = T::from_f64(0.1);
    p.wall = Some(Wall::new(T::ZERO));
    let (r, (_, v, _)) = one_step::<T>(&p, &sphere, &[]).unwrap();
    let e = (-v[0][2] / want - 1.0).abs();
    println!(
        "{} U0 against Brenner's {} U0 ({e:.1e})",
        -v[0][2] / U0,
        want / U0
    );
    assert!(e < 5e-3, "{} vs {want} ({e:e})", -v[0][2]);
    assert_eq!(r.near_pairs, 1, "{r:?}");
    assert_eq!(r.near_iterations, r.near_products, "{r:?}");
}

both!(
    matches_dense,
    pair_falls,
    same_bits,
    refusals,
    wall_matches_dense,
    wall_approach
);
