//! Hard contacts on the iterative near field (`Params::near` with `Params::matrix_free`
//! and `Params::contacts`): spheres settling onto a pinned floor, onto the wall and onto
//! each other,
//! each step against the dense near step from the same state with the same solver
//! (`near_step.rs` checks that one against exact two-sphere hydrodynamics); no pair
//! overlapping beyond twice the solver's tolerance, measured here from the positions;
//! the floor's pins held bit for bit; the same bits run to run; with the Krylov solve,
//! the sweep and Newton (their table of `M_SD`'s columns, one product a row). Units:
//! `a = 1`, `eta = 1`, `g = 1`, no fluid density.
#![cfg(all(feature = "contacts", feature = "pins"))]

use crate::common;
use crate::near_con::{near, run};

use std::f64::consts::PI;

use common::*;
use hydrorattle::{
    Bond, BondSet, Contacts, Layout, Method, NoForce, ParticleSet, Real, SolverKind, Wall, step,
};
use hydrorattle_heap::Buffers;

/// Density of a unit sphere of buoyant weight 4 (`g = 1`, no fluid density).
const HEAVY: f64 = 3.0 / PI;

/// Spheres of floor `k` (of the 3 x 3 floor, spacing 2.1) or of sphere `on`, offset
/// `(dx, dy)` across, radius `a`, at surface gap `h` above it.
fn above(on: &Sphere, a: f64, (dx, dy): (f64, f64), h: f64) -> Sphere {
    let d = on.radius + a + h;
    let dz = (d * d - dx * dx - dy * dy).sqrt();
    Sphere {
        pos: add(on.pos, [dx, dy, dz]),
        radius: a,
        density: HEAVY,
    }
}

/// A pinned 3 x 3 floor of unit spheres (gaps 0.1; first nine) and five heavy spheres
/// of radii 0.8 to 1.2 dropped on it within 0.002 to 0.02 of the floor, one of them on
/// another: every pair of them within the near field's cutoff of some other.
fn bed() -> Vec<Sphere> {
    let mut s: Vec<Sphere> = (0..9)
        .map(|k| Sphere {
            pos: [2.1 * (k % 3) as f64 - 2.1, 2.1 * (k / 3) as f64 - 2.1, 0.0],
            radius: 1.0,
            density: HEAVY,
        })
        .collect();
    let a = above(&s[4], 1.0, (0.3, 0.2), 0.004);
    let b = above(&s[8], 1.2, (-0.4, 0.1), 0.01);
    let c = above(&s[3], 0.8, (0.2, -0.3), 0.002);
    let d = above(&a, 0.9, (0.2, -0.1), 0.003);
    let e = above(&s[1], 1.1, (0.5, 0.0), 0.02);
    s.extend([a, b, c, d, e]);
    s
}

/// The pin rows of the spheres `s` (three a sphere): the floor's.
fn floor<T: Real>(s: &[Sphere]) -> Vec<Bond<T>> {
    (0..s.len())
        .flat_map(|i| Bond::pins(i, T::from_f64(s[i].radius)))
        .collect()
}

/// Largest relative overlap `1 - |r_ij| / (a_i + a_j)` of any pair (0 if none).
fn overlap(s: &[Sphere], x: &[[f64; 3]]) -> f64 {
    let mut worst = 0.0f64;
    for i in 0..x.len() {
        for j in 0..i {
            let sigma = s[i].radius + s[j].radius;
            worst = worst.max(1.0 - norm(sub(x[i], x[j])) / sigma);
        }
    }
    worst
}

/// With contacts, dense (`matrix_free = false`) or iterative; the solver `kind`, `dt =
/// 1`.
fn with_contacts<T: Real>(iterative: bool, kind: SolverKind) -> hydrorattle::Params<T> {
    let mut p = near::<T>(iterative, 1.0, None);
    p.contacts = Some(Contacts::new(32));
    p.solver.kind = kind;
    // The sweep converges linearly on a jammed set (`docs/CONTACTS.md`): f64 took more
    // than the default 100 sweeps here.
    if kind == SolverKind::Sweep {
        p.solver.max_iterations = 5000;
    }
    p
}

/// Twelve steps of the bed from the iterative step's own states, with each solver:
/// every step ends where the dense near step with the same solver (its entries read
/// from the stored `M_SD`) from the same state ends, within the tolerances (the
/// constraint rows' relative error and the products' relative residual: 1e-10 in f64,
/// 1e-5 in f32) relative to the step's move, amplified by the lubrication's
/// conditioning near contact (measured: up to 34 times the tolerance in f64, 20 in
/// f32; the test allows 200, 1000 for the sweep, which stops anywhere inside its
/// tolerance): contacts form (floor and pile), as many as the dense step holds; no
/// pair overlaps beyond twice the tolerance; the floor does not move, bit for bit.
fn settles_as_dense<T: Real>() {
    for kind in [SolverKind::Krylov, SolverKind::Newton, SolverKind::Sweep] {
        settles_with::<T>(Method::Overdamped, kind, &bed(), 9, None, 3);
    }
}

/// [`settles_as_dense`] and [`settles_on_the_wall`] by `Overdamped2` (its predictor's
/// and its trapezoid's projections hold the contacts, along `M_SD` at the start), with
/// the Krylov solve and Newton.
fn settles_as_dense2<T: Real>() {
    for kind in [SolverKind::Krylov, SolverKind::Newton] {
        settles_with::<T>(Method::Overdamped2, kind, &bed(), 9, None, 3);
        settles_with::<T>(Method::Overdamped2, kind, &on_the_wall(), 0, Some(0.0), 2);
    }
}

/// Five heavy spheres dropped onto the wall (within 0.002 to 0.01 of it, two of them
/// on others) settle as the dense near step from the same state settles them, with the
/// Krylov solve and Newton (the same measures as [`settles_as_dense`]): the wall's
/// links held, one-sided, beside the pair contacts, the iterative product's far field
/// the wall's and its near field the wall's sphere corrections.
fn settles_on_the_wall<T: Real>() {
    for kind in [SolverKind::Krylov, SolverKind::Newton] {
        settles_with::<T>(Method::Overdamped, kind, &on_the_wall(), 0, Some(0.0), 2);
    }
}

/// Five heavy spheres within 0.002 to 0.01 of the wall at height 0, two of them on
/// others ([`settles_on_the_wall`]).
fn on_the_wall() -> [Sphere; 5] {
    let ground = |x: f64, y: f64, a: f64, h: f64| Sphere {
        pos: [x, y, a + h],
        radius: a,
        density: HEAVY,
    };
    let (a, b) = (ground(0.0, 0.0, 1.0, 0.002), ground(2.3, 0.2, 1.2, 0.01));
    let c = ground(-1.0, 2.0, 0.8, 0.004);
    let d = above(&a, 0.9, (0.3, -0.2), 0.003);
    let e = above(&b, 1.1, (0.4, 0.1), 0.02);
    [a, b, c, d, e]
}

/// Twelve steps of `spheres` (the first `pinned` of them pinned, the wall at `wall` if
/// given) by `method` with the solver `kind`, each against the dense step from the
/// same state; at
/// least `contacts` pair contacts held at some step (and two wall links, with the wall).
fn settles_with<T: Real>(
    method: Method,
    kind: SolverKind,
    spheres: &[Sphere],
    pinned: usize,
    wall: Option<f64>,
    contacts: u32,
) {
    let rows = floor::<T>(&spheres[..pinned]);
    let setup = |iterative| {
        let mut p = with_contacts::<T>(iterative, kind);
        p.method = method;
        p.wall = wall.map(|h| Wall::new(T::from_f64(h)));
        p
    };
    let (pd, pi) = (setup(false), setup(true));
    let tol = pi.solver.tolerance.to_f64();
    // Within twice the tolerance (the over-relaxed sweep stops just inside its own
    // measure: 1.2e-5 in f32).
    let slack = 2.0 * tol + 8.0 * T::EPSILON.to_f64();
    // The sweep stops anywhere in its tolerance band; the others end closer.
    let allow = if kind == SolverKind::Sweep {
        1e3
    } else {
        200.0
    };
    let n = spheres.len();
    let mut ps: ParticleSet<T, 16> = particles(spheres);
    let mut set: BondSet<T, 32> = BondSet::new();
    for &b in &rows {
        set.push(b, n).unwrap();
    }
    let buffers = |p| Buffers::<T>::new(Layout::for_params(p, n, rows.len()));
    let (mut bi, mut bd) = (buffers(&pi), buffers(&pd));
    let (mut wi, mut wd) = (bi.workspace(), bd.workspace());
    let at = |ps: &ParticleSet<T, 16>| -> Vec<[f64; 3]> {
        (0..n).map(|i| f64s::<T>(ps.pos[i])).collect()
    };
    let (mut held, mut walls) = (0, 0);
    for k in 0..12 {
        let s = at(&ps);
        let mut dense = ps.clone();
        let ri = step(&mut ps, &set, &pi, &mut wi, &mut NoForce).unwrap();
        let rd = step(&mut dense, &set, &pd, &mut wd, &mut NoForce).unwrap();
        let (xi, xd) = (at(&ps), at(&dense));
        let moved = s
            .iter()
            .zip(&xd)
            .map(|(s, x)| norm(sub(*x, *s)))
            .fold(0.0, f64::max);
        let apart = xi
            .iter()
            .zip(&xd)
            .map(|(a, b)| norm(sub(*a, *b)))
            .fold(0.0, f64::max);
        println!(
            "{method:?} {kind:?} step {k}: contacts {} (dense {}), wall {} (dense {}), rounds {}, krylov {} (dense {}), products {}, pcg {}, moved {moved:.2e}, apart {:.1e}, overlap {:.1e}",
            ri.contacts,
            rd.contacts,
            ri.wall_contacts,
            rd.wall_contacts,
            ri.contact_rounds,
            ri.iterations,
            rd.iterations,
            ri.near_products,
            ri.near_iterations,
            apart / moved,
            overlap(spheres, &xi),
        );
        assert_eq!(
            (ri.contacts, ri.wall_contacts),
            (rd.contacts, rd.wall_contacts),
            "{kind:?} step {k}: {ri:?} / {rd:?}"
        );
        assert!(
            apart < allow * tol * moved,
            "step {k}: {apart:e} of {moved:e}"
        );
        assert!(overlap(spheres, &xi) <= slack, "step {k}: overlap");
        for (s, x) in spheres.iter().zip(&xi) {
            let below = wall.map_or(0.0, |h| 1.0 - (x[2] - h) / s.radius);
            assert!(below <= slack, "step {k}: {below:e} below the wall");
        }
        assert_eq!(ri.near_formations, 0);
        for i in 0..pinned {
            let pin = f64s::<T>(T::v3_from(spheres[i].pos)).map(f64::to_bits);
            assert_eq!(pin, xi[i].map(f64::to_bits), "step {k}: the floor moved");
        }
        held = held.max(ri.contacts);
        walls = walls.max(ri.wall_contacts);
    }
    // The floor, the pile (one on another) and a neighbour: several contacts held; on
    // the wall, the two piles and the spheres resting on it.
    assert!(held >= contacts, "{kind:?}: contacts held: {held}");
    assert!(
        wall.is_none() || walls >= 2,
        "{kind:?}: wall links held: {walls}"
    );
}

/// Two runs of six steps end on the same bits and report the same counts.
fn same_bits<T: Real>() {
    let spheres = bed();
    let rows = floor::<T>(&spheres[..9]);
    let p = with_contacts::<T>(true, SolverKind::Krylov);
    let bits = || {
        let (r, x) = run::<T>(&p, &spheres, &rows, 6).unwrap();
        let x: Vec<[u64; 3]> = x.iter().map(|v| v.map(f64::to_bits)).collect();
        (x, r)
    };
    let (a, b) = (bits(), bits());
    assert!(a.1.iter().any(|r| r.contacts > 0), "no contact: {:?}", a.1);
    assert_eq!(a, b);
}

both_precisions! {
    settles_as_dense2 => settles_as_dense2;
    settles_as_dense => settles_as_dense;
    settles_on_the_wall => settles_on_the_wall;
    same_bits => same_bits;
}
