//! Steps with Stokesian dynamics' near field (`Params::near`), against values computed
//! independently here: Stimson and Jeffery's (1926) exact series for two equal spheres
//! falling along their line of centres, the published side-by-side values at `s = 2.1`
//! (1.3917 `U0`, spin 0.137 `U0 / a`), Brenner's (1961) exact series for a sphere
//! approaching a wall (the series are `stokesian.rs`'s), and the bond projection of a
//! dimer's velocity solved in the test (`U = M F + M G^T lambda` with `G U = 0`) with the
//! two-sphere mobility of `stokesian::mobility`, itself checked there against the exact
//! series. Units: `a = 1`, `eta = 1`, buoyant weight 1 (density `3 / (4 pi)`, `g = 1`):
//! `U0 = 1 / (6 pi)`.

use crate::common;
use crate::stokesian::{brenner, sd, stimson_jeffery};

use std::f64::consts::PI;

use common::*;
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    BondSet, Brownian, Hydro, Layout, Method, NoForce, NoiseSqrt, ParticleSet, Periodic, Real,
    SolverKind, StepError, Wall, step,
};
use hydrorattle_heap::Buffers;

/// Stokes' speed of the unit sphere of unit buoyant weight in the unit fluid.
const U0: f64 = 1.0 / (6.0 * PI);
/// Density of unit buoyant weight for a unit sphere (`g = 1`).
const RHO1: f64 = 3.0 / (4.0 * PI);

/// Near-field parameters with the defaults.
fn near<T: Real>(method: Method, kind: SolverKind) -> hydrorattle::Params<T> {
    let mut p = params::<T>(1e-2, method, kind);
    p.near = Some(NearField::default());
    p
}

/// One vector a sphere.
type Vecs = Vec<[f64; 3]>;

/// One step of `spheres` with `bonds` (a chain when `true`) under `p`; the velocities
/// and spins after it.
fn one_step<T: Real, const N: usize>(
    p: &hydrorattle::Params<T>,
    spheres: &[Sphere],
    bonded: bool,
) -> Result<(Vecs, Vecs), StepError> {
    let mut ps: ParticleSet<T, N> = particles(spheres);
    ps.noise = Some(hydrorattle::Noise::new(1));
    let bonds: BondSet<T, N> = match bonded {
        true => BondSet::chain(&ps.pos[..spheres.len()]).expect("bonds"),
        false => BondSet::new(),
    };
    let mut buf = Buffers::<T>::new(Layout::for_params(p, spheres.len(), bonds.len()));
    let mut ws = buf.workspace();
    step(&mut ps, &bonds, p, &mut ws, &mut NoForce)?;
    let n = spheres.len();
    let v = (0..n).map(|i| f64s::<T>(ps.vel[i])).collect();
    let w = (0..n).map(|i| f64s::<T>(ps.omega[i])).collect();
    Ok((v, w))
}

/// Two unit spheres of unit weight, centres `s` apart along `axis`, about the origin.
fn pair(s: f64, axis: [f64; 3]) -> [Sphere; 2] {
    let c = scale(axis, s / 2.0);
    [
        Sphere {
            pos: scale(c, -1.0),
            radius: 1.0,
            density: RHO1,
        },
        Sphere {
            pos: c,
            radius: 1.0,
            density: RHO1,
        },
    ]
}

fn relative(got: f64, want: f64) -> f64 {
    (got / want - 1.0).abs()
}

/// Two equal spheres at `s = 2.1` fall along their line of centres at Stimson and
/// Jeffery's speed (within 0.5 %; RPY alone is 4.6 % fast, and that is asserted too, so
/// the check can tell), with both overdamped methods; side by side at 1.3917 `U0` and,
/// with rotation, spinning at 0.137 `U0 / a` (within 2 %).
fn two_spheres_fall<T: Real>() {
    let want = stimson_jeffery(2.1) * U0;
    for method in [Method::Overdamped, Method::Overdamped2] {
        let p = near::<T>(method, SolverKind::Auto);
        let (v, _) = one_step::<T, 2>(&p, &pair(2.1, [0.0, 0.0, 1.0]), false).unwrap();
        for vi in &v {
            let e = relative(-vi[2], want);
            assert!(e < 5e-3, "{method:?}: {} vs {want} ({e:e})", -vi[2]);
        }
        let mut far = p;
        far.near = None;
        let (v, _) = one_step::<T, 2>(&far, &pair(2.1, [0.0, 0.0, 1.0]), false).unwrap();
        assert!(relative(-v[0][2], want) > 0.03, "RPY alone {}", -v[0][2]);
    }
    let mut p = near::<T>(Method::Overdamped, SolverKind::Auto);
    p.rotation = true;
    let (v, w) = one_step::<T, 2>(&p, &pair(2.1, [1.0, 0.0, 0.0]), false).unwrap();
    for (vi, wi) in v.iter().zip(&w) {
        let e = relative(-vi[2], 1.3917 * U0);
        assert!(e < 5e-3, "side by side {} ({e:e})", -vi[2] / U0);
        let e = relative(norm(*wi), 0.137 * U0);
        assert!(e < 0.02, "spin {} ({e:e})", norm(*wi) / U0);
        // The spin is about the horizontal normal to the pair.
        assert!(wi[0].abs() + wi[2].abs() < 1e-3 * norm(*wi), "spin {wi:?}");
    }
    // The spheres spin in opposite senses.
    assert!(w[0][1] * w[1][1] < 0.0);
}

/// The projection of a dimer's velocity onto its bond, in the test: `U = M (F + G^T
/// lambda)`, `G = (e, -e)` with `e = r1 - r2`, `lambda` such that `e . (U1 - U2) = 0`;
/// `M` the translational blocks of the exact two-sphere mobility.
pub(crate) fn projected(spheres: &[Sphere; 2], weight: [f64; 2]) -> [[f64; 3]; 2] {
    let pos = [spheres[0].pos, spheres[1].pos];
    let m = sd::<f64>(None, &pos, &[1.0, 1.0]).unwrap();
    let tt = |u: [f64; 6]| -> [f64; 6] {
        core::array::from_fn(|r| (0..6).map(|c| m[r * 12 + c] * u[c]).sum())
    };
    let e = sub(pos[0], pos[1]);
    let f = [0.0, 0.0, -weight[0], 0.0, 0.0, -weight[1]];
    let g = [e[0], e[1], e[2], -e[0], -e[1], -e[2]];
    let (mf, mg) = (tt(f), tt(g));
    let dot6 = |a: [f64; 6], b: [f64; 6]| (0..6).map(|k| a[k] * b[k]).sum::<f64>();
    let lambda = -dot6(g, mf) / dot6(g, mg);
    let u: [f64; 6] = core::array::from_fn(|k| mf[k] + lambda * mg[k]);
    [[u[0], u[1], u[2]], [u[3], u[4], u[5]]]
}

/// A bonded pair (bond 2.1 radii) tilted 60 degrees from the vertical, one sphere three
/// times as heavy as the other, falls and turns as the bond projection with the exact
/// two-sphere mobility says (with every solver and both methods); its mean velocity is
/// Stimson and Jeffery's along the bond and the side-by-side value across it (within
/// 0.5 %), and the bond keeps its length.
fn bonded_pair_falls_and_turns<T: Real>() {
    let th = 60f64.to_radians();
    let axis = [th.sin(), 0.0, th.cos()];
    let mut spheres = pair(2.1, axis);
    spheres[0].density = 1.5 * RHO1;
    spheres[1].density = 0.5 * RHO1;
    let want = projected(&spheres, [1.5, 0.5]);
    // The mean force is one unit down: its parts along and across the bond.
    let (along, across) = (th.cos(), th.sin());
    for method in [Method::Overdamped, Method::Overdamped2] {
        for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
            let mut p = near::<T>(method, kind);
            p.solver.tolerance = T::from_f64(pick::<T>(1e-5, 1e-12));
            let (v, _) = one_step::<T, 2>(&p, &spheres, true).unwrap();
            let scale_u = norm(want[0]).max(norm(want[1]));
            for (got, w) in v.iter().zip(&want) {
                let e = norm(sub(*got, *w)) / scale_u;
                assert!(
                    e < pick::<T>(3e-3, 1e-3),
                    "{method:?} {kind:?}: {got:?} vs {w:?}"
                );
            }
            let mean = scale(add(v[0], v[1]), 0.5);
            let u_along = -dot(mean, axis);
            let perp = [axis[2], 0.0, -axis[0]];
            let u_across = dot(mean, perp).abs();
            let e = relative(u_along, stimson_jeffery(2.1) * U0 * along);
            assert!(e < 5e-3, "{method:?} {kind:?}: along {u_along} ({e:e})");
            let e = relative(u_across, 1.3917 * U0 * across);
            assert!(e < 5e-3, "{method:?} {kind:?}: across {u_across} ({e:e})");
            // The heavy sphere (0, the lower one) swings down: the bond turns.
            let turn = sub(v[1], v[0]);
            assert!(norm(turn) > 0.05 * norm(mean), "no turn {turn:?}");
        }
    }
}

/// A sphere at `h / a = 1.1` above the wall approaches it at Brenner's speed, within
/// 0.5 % (the far field alone is 3 times faster; asserted).
fn sphere_approaches_the_wall<T: Real>() {
    let sphere = [Sphere {
        pos: [0.0, 0.0, 1.1],
        radius: 1.0,
        density: RHO1,
    }];
    let want = brenner(1.1) * U0;
    let mut p = near::<T>(Method::Overdamped, SolverKind::Auto);
    p.dt = T::from_f64(0.1);
    p.wall = Some(Wall::new(T::ZERO));
    let (v, _) = one_step::<T, 1>(&p, &sphere, false).unwrap();
    let e = relative(-v[0][2], want);
    assert!(e < 5e-3, "{} vs {want} ({e:e})", -v[0][2]);
    p.near = None;
    let (v, _) = one_step::<T, 1>(&p, &sphere, false).unwrap();
    assert!(-v[0][2] > 2.0 * want, "far field alone {}", -v[0][2]);
}

both_precisions! {
    two_spheres_fall_along_and_across => two_spheres_fall;
    bonded_pair => bonded_pair_falls_and_turns;
    wall_approach => sphere_approaches_the_wall;
}

/// The near field's storage is counted only when it is on: `tri(2n)` blocks and
/// `(6n)^2` scalars, and the stored mobility in blocks of nine.
#[test]
fn storage_only_with_the_near_field() {
    let n = 5;
    let off = params::<f64>(1e-2, Method::Overdamped, SolverKind::Krylov);
    let mut on = off;
    on.near = Some(NearField::default());
    let (a, b) = (
        Layout::for_params(&off, n, 4),
        Layout::for_params(&on, n, 4),
    );
    let tri = |k: usize| k * (k + 1) / 2;
    assert_eq!(b.blocks, a.blocks + tri(n) + tri(2 * n));
    assert_eq!(b.scalars, a.scalars - 6 * tri(n) + 36 * n * n);
    assert_eq!((a.vectors, a.indices), (b.vectors, b.indices));
}

/// What the near field does not serve is refused with a typed error naming it, before
/// anything moves.
#[test]
fn unsupported_combinations_are_refused() {
    let spheres = pair(2.5, [0.0, 0.0, 1.0]);
    let base = near::<f64>(Method::Overdamped, SolverKind::Auto);
    let mut cases: Vec<(&str, hydrorattle::Params<f64>)> = Vec::new();
    for method in [Method::Rattle, Method::RattleStable, Method::Springs] {
        cases.push(("method", hydrorattle::Params { method, ..base }));
    }
    for hydro in [Hydro::Oseen, Hydro::FreeDraining] {
        cases.push(("hydro", hydrorattle::Params { hydro, ..base }));
    }
    // (`matrix_free` is the iterative near field: its refusals are `near_iter.rs`'s.)
    let cell = Periodic::new([20.0; 3]).unwrap();
    cases.push((
        "box by PSE",
        hydrorattle::Params {
            periodic: Some(cell),
            pse: Some(1e-3),
            ..base
        },
    ));
    let mut lanczos = base;
    lanczos.brownian = Some(Brownian::new(1.0));
    lanczos.noise_sqrt = NoiseSqrt::Lanczos;
    cases.push(("lanczos", lanczos));
    for (what, p) in cases {
        let e = one_step::<f64, 2>(&p, &spheres, false).unwrap_err();
        assert!(matches!(e, StepError::Unsupported(_)), "{what}: {e:?}");
    }
    let mut bad = base;
    bad.near = Some(NearField {
        min_gap: 0.0,
        ..NearField::default()
    });
    let e = one_step::<f64, 2>(&bad, &spheres, false).unwrap_err();
    assert!(matches!(e, StepError::BadParameter(_)), "min_gap 0: {e:?}");
}
