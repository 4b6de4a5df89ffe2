//! The iterative near field on PSE's grand product in the periodic box (`Params::near`
//! with `Params::matrix_free` and `Params::pse` in a box): the far field is
//! `Pse::apply_grand`, no `tri(2n)` blocks stored. Checked against what PSE did not
//! compute:
//!
//! * the same step on the Ewald sums' assembled grand mobility (`near_iter.rs`, there
//!   checked against the dense near step) at the PSE tolerances `1e-4` and `1e-8`: a
//!   random suspension at volume fraction 0.2, both overdamped methods, bonds by Krylov,
//!   hard contacts, thermal `Overdamped`;
//! * two equal spheres at `s = 2.1` in a box of edge 30: Stimson and Jeffery's exact
//!   speed along their line of centres and the published side-by-side speed, each less
//!   the box's known correction (Hasimoto's constant, as `near_box.rs` checks the Ewald
//!   path), and the spin across it;
//! * the layout: no packed grand mobility, bytes linear in `n`.
//!
//! `cargo test --release --test kernel near_pse:: -- --nocapture`.
#![cfg(all(feature = "near", feature = "pse"))]

use crate::common;
use crate::near_iter::{Out, RHO1, U0, relative_gap};
use crate::stokesian::stimson_jeffery;

use common::boxes::{config_radii, min_image};
use common::*;
use hydrorattle::integrate::pse_storage;
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    Bond, BondSet, Brownian, Contacts, Layout, Method, NoForce, Noise, ParticleSet, Periodic, Real,
    SolverKind, StepError, StepReport, step,
};
use hydrorattle_heap::{Buffers, PseBuffers};

/// Hasimoto's constant: a pair's translation blocks at `r << L` each shift by
/// `-2.837297 / (6 pi eta L)` in the box of edge `L`.
const HASIMOTO: f64 = 2.837297;

/// The iterative near field with rotation in the cubic box of edge `l`; its far field
/// PSE's grand product at tolerance `pse`, else the Ewald sums' assembled one.
fn near(method: Method, l: f64, pse: Option<f64>) -> hydrorattle::Params<f64> {
    let mut p = params::<f64>(1e-2, method, SolverKind::Auto);
    p.near = Some(NearField::default());
    p.rotation = true;
    p.matrix_free = true;
    p.periodic = Some(Periodic::new([l; 3]).unwrap());
    p.pse = pse;
    p
}

/// One step of `spheres` with `bonds` under `p` (thermal with the generator of `seed`),
/// PSE's arrays as `pse_storage` asks: its report and the state after it, or the error
/// with the state as before (asserted bit for bit).
fn one_step(
    p: &hydrorattle::Params<f64>,
    spheres: &[Sphere],
    bonds: &[Bond<f64>],
    seed: Option<u64>,
) -> Result<(StepReport<f64>, Out), StepError> {
    let n = spheres.len();
    let mut ps: ParticleSet<f64, 128> = particles(spheres);
    let mut set: BondSet<f64, 128> = BondSet::new();
    for &b in bonds {
        set.push(b, n).unwrap();
    }
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, n, bonds.len()));
    let mut arrays = PseBuffers::<f64>::for_step(pse_storage(p, &ps.radius[..n])?);
    let mut ws = arrays.attach(buf.workspace());
    let as3 = |v: &[<f64 as Real>::V3]| -> Vec<[f64; 3]> {
        v[..n].iter().map(|&x| f64s::<f64>(x)).collect()
    };
    let before = (as3(&ps.pos), as3(&ps.vel), as3(&ps.omega));
    let r = match seed {
        Some(s) => step_thermal(&mut ps, &set, p, &mut ws, &mut NoForce, &mut Noise::new(s)),
        None => step(&mut ps, &set, p, &mut ws, &mut NoForce),
    };
    let after = (as3(&ps.pos), as3(&ps.vel), as3(&ps.omega));
    match r {
        Ok(r) => Ok((r, after)),
        Err(e) => {
            assert_eq!(before, after, "{e:?}: the state moved");
            Err(e)
        }
    }
}

/// `n` spheres of radii 0.8 to 1.2 apart at random in the cubic box at volume fraction
/// 0.2 (its edge returned), densities 0.5 to 2 times `RHO1`.
fn suspension(n: usize, seed: u64) -> (Vec<Sphere>, f64) {
    let volume = n as f64 * 4.0 / 3.0 * core::f64::consts::PI * 1.04;
    let l = (volume / 0.2).cbrt();
    let (pos, rad) = config_radii(n, seed, [l; 3], [0.8, 1.2], false);
    assert_eq!(pos.len(), n);
    let spheres = pos
        .iter()
        .zip(&rad)
        .enumerate()
        .map(|(i, (&pos, &radius))| Sphere {
            pos,
            radius,
            density: RHO1 * (0.5 + 1.5 * ((i * 7) % 11) as f64 / 10.0),
        })
        .collect();
    (spheres, l)
}

/// PSE's step against the Ewald sums' (`p`, `pse` None), `what` naming it: velocities
/// and spins within `bound` of the largest; both report the same close pairs, neither
/// forms `M_SD`.
fn compare(
    p: hydrorattle::Params<f64>,
    tol: f64,
    (spheres, bonds): (&[Sphere], &[Bond<f64>]),
    seed: Option<u64>,
    bound: f64,
    what: &str,
) {
    let (ra, ewald) = one_step(&p, spheres, bonds, seed).unwrap();
    let pse_p = hydrorattle::Params {
        pse: Some(tol),
        ..p
    };
    let (rf, pse) = one_step(&pse_p, spheres, bonds, seed).unwrap();
    let (dv, dw) = (
        relative_gap(&pse.1, &ewald.1),
        relative_gap(&pse.2, &ewald.2),
    );
    println!(
        "{what}, tol {tol:e}: pairs {}, products {}/{}, iterations {}/{}, velocities {dv:.1e}, spins {dw:.1e}",
        rf.near_pairs, rf.near_products, ra.near_products, rf.near_iterations, ra.near_iterations
    );
    assert!(dv < bound && dw < bound, "{what}, tol {tol}: {dv:e} {dw:e}");
    assert!(dv > 0.0, "{what}: PSE's far field did not run");
    assert!(rf.near_pairs > 0, "{what}: no close pair");
    assert_eq!(rf.near_pairs, ra.near_pairs, "{what}");
    assert_eq!(rf.near_formations, 0, "{what}: formed M_SD");
}

/// Random suspensions of 20 and 60 spheres at volume fraction 0.2, both overdamped
/// methods: PSE's velocities and spins are the Ewald sums' within 20 times the PSE
/// tolerance (`1e-4`, `1e-8`).
#[test]
fn matches_ewald() {
    for (n, seed) in [(20, 3), (60, 4)] {
        let (spheres, l) = suspension(n, seed);
        for method in [Method::Overdamped, Method::Overdamped2] {
            for tol in [1e-4, 1e-8] {
                let what = format!("{n} spheres, {method:?}");
                let p = near(method, l, None);
                compare(p, tol, (&spheres, &[]), None, 20.0 * tol, &what);
            }
        }
    }
}

/// Bonds at their lengths (minimum image) from each of the first six spheres to its
/// nearest, where that is not among them.
fn nearest_bonds(spheres: &[Sphere], l: f64) -> Vec<Bond<f64>> {
    let d = |i: usize, j: usize| norm(min_image(sub(spheres[j].pos, spheres[i].pos), [l; 3]));
    (0..6)
        .filter_map(|i| {
            let j = (0..spheres.len())
                .filter(|&j| j != i)
                .min_by(|&a, &b| d(i, a).total_cmp(&d(i, b)))?;
            (j > 5).then(|| Bond {
                i,
                j,
                length: d(i, j),
            })
        })
        .collect()
}

/// Bonds by Krylov in `Overdamped` and `Overdamped2`, hard contacts, and thermal `Overdamped` (the far
/// field's Lanczos root on PSE's grand product, the same deviates) with and without
/// bonds, against the Ewald sums' step.
#[test]
fn constrained_and_thermal() {
    let (spheres, l) = suspension(30, 5);
    let bonds = nearest_bonds(&spheres, l);
    assert!(!bonds.is_empty());
    let tol = 1e-8;
    for method in [Method::Overdamped, Method::Overdamped2] {
        let mut p = near(method, l, None);
        p.solver.kind = SolverKind::Krylov;
        let what = format!("bonds, {method:?}");
        compare(p, tol, (&spheres, &bonds), None, 1e-6, &what);
    }
    let mut p = near(Method::Overdamped, l, None);
    p.contacts = Some(Contacts::new(64));
    p.dt = 0.5;
    compare(p, tol, (&spheres, &[]), None, 1e-6, "contacts");
    let mut p = near(Method::Overdamped, l, None);
    p.brownian = Some(Brownian::new(1e-2));
    p.allow_overlap = true;
    compare(p, tol, (&spheres, &[]), Some(7), 1e-4, "thermal");
    p.solver.kind = SolverKind::Krylov;
    compare(p, tol, (&spheres, &bonds), Some(8), 1e-4, "thermal, bonds");
}

/// Two equal spheres at `s = 2.1` in the box of edge 30 on PSE's far field (`1e-4`,
/// `1e-8`), both overdamped methods: along their line of centres at Stimson and
/// Jeffery's exact speed, side by side at 1.3917 `U0`, each less the box's shift
/// `2 HASIMOTO / L` in `U0` (within 10 % of that shift, itself 19 % of `U0`);
/// across, spinning at 0.137 `U0 / a` within 2 % and the shift's share.
#[test]
fn pair_falls_in_a_box() {
    let l = 30.0;
    let shift = 2.0 * HASIMOTO / l * U0;
    let pair = |axis: [f64; 3]| {
        let d = scale(axis, 1.05);
        [-1.0, 1.0].map(|s| Sphere {
            pos: add([l / 2.0; 3], scale(d, s)),
            radius: 1.0,
            density: RHO1,
        })
    };
    for tol in [1e-4, 1e-8] {
        for method in [Method::Overdamped, Method::Overdamped2] {
            let p = near(method, l, Some(tol));
            for (axis, free) in [
                ([0.0, 0.0, 1.0], stimson_jeffery(2.1) * U0),
                ([1.0, 0.0, 0.0], 1.3917 * U0),
            ] {
                let (r, (_, v, w)) = one_step(&p, &pair(axis), &[], None).unwrap();
                assert_eq!(r.near_pairs, 1);
                for (vi, wi) in v.iter().zip(&w) {
                    let miss = ((free + vi[2]) / shift - 1.0).abs();
                    assert!(
                        miss < 0.1,
                        "{tol:e} {method:?} {axis:?}: {} U0",
                        -vi[2] / U0
                    );
                    if axis[0] == 1.0 {
                        let e = (norm(*wi) / (0.137 * U0) - 1.0).abs();
                        assert!(e < 0.02 + HASIMOTO / l, "spin {} U0", norm(*wi) / U0);
                    }
                }
            }
        }
    }
}

/// The layout of PSE's near step holds no packed grand mobility: exactly `tri(2n)`
/// blocks below the Ewald sums', and linear in `n` (its bytes at 4000 spheres four times
/// those at 1000, within 1 %), every method it serves; PSE's own arrays are the grand
/// product's.
#[test]
fn storage_is_linear() {
    let tri2 = |n: usize| 2 * n * (2 * n + 1) / 2;
    let m3 = core::mem::size_of::<<f64 as Real>::M3>();
    for (method, thermal) in [
        (Method::Overdamped, false),
        (Method::Overdamped2, false),
        (Method::Overdamped, true),
    ] {
        let with = |pse: Option<f64>, n: usize| {
            let mut p = near(method, 40.0, pse);
            p.brownian = thermal.then(|| Brownian::new(1.0));
            Layout::for_params(&p, n, 0)
        };
        for n in [1000, 4000] {
            let (pse, ewald) = (with(Some(1e-4), n), with(None, n));
            assert_eq!(pse.blocks + tri2(n), ewald.blocks, "{method:?} {n}");
            let bytes = ewald.bytes::<f64>() - pse.bytes::<f64>();
            assert_eq!(bytes, tri2(n) * m3, "{method:?} {n}");
        }
        let (small, large) = (with(Some(1e-4), 1000), with(Some(1e-4), 4000));
        let ratio = large.bytes::<f64>() as f64 / small.bytes::<f64>() as f64;
        assert!((ratio / 4.0 - 1.0).abs() < 0.01, "{method:?}: {ratio}");
    }
    let radius = [1.0; 50];
    let grand = pse_storage(&near(Method::Overdamped, 40.0, Some(1e-4)), &radius);
    let mut plain = near(Method::Overdamped, 40.0, Some(1e-4));
    plain.near = None;
    let plain = pse_storage(&plain, &radius);
    let (grand, plain) = (grand.unwrap().unwrap(), plain.unwrap().unwrap());
    assert_eq!(grand.vectors, 2 * plain.vectors);
    assert!(grand.complex > plain.complex);
}

/// What stays refused on PSE's far field, typed, the state unchanged: the sweep with
/// bonds (it tabulates along blocks PSE does not have: Krylov serves them), and a
/// workspace without PSE's arrays.
#[test]
fn refusals() {
    let (spheres, l) = suspension(20, 21);
    let bonds = nearest_bonds(&spheres, l);
    let mut p = near(Method::Overdamped, l, Some(1e-4));
    p.solver.kind = SolverKind::Sweep;
    match one_step(&p, &spheres, &bonds, None) {
        Err(StepError::Unsupported(m)) => assert!(m.contains("Sweep"), "{m}"),
        other => panic!("sweep: {other:?}"),
    }
    let p = near(Method::Overdamped, l, Some(1e-4));
    let mut ps: ParticleSet<f64, 128> = particles(&spheres);
    let before = ps.pos;
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, spheres.len(), 0));
    let set: BondSet<f64, 1> = BondSet::new();
    match step(&mut ps, &set, &p, &mut buf.workspace(), &mut NoForce) {
        Err(StepError::BadParameter(m)) => assert!(m.contains("PSE"), "{m}"),
        other => panic!("no PSE arrays: {other:?}"),
    }
    assert_eq!(ps.pos, before);
}
