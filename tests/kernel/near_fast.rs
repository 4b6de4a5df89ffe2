//! The iterative near field on a matrix-free far field (`Params::near` with
//! `Params::matrix_free` and `Params::pse` in free space): the far field is the fast
//! free-space product's grand product (`FreeFast::apply_grand`), no `tri(2n)` blocks
//! stored. Checked against what the fast code did not compute:
//!
//! * the same step on the assembled far field (`near_iter.rs`, there checked against
//!   the dense near step) at the fast tolerances `1e-4` and `1e-8`: clusters with close
//!   pairs, both overdamped methods, bonds by Krylov, contacts, thermal `Overdamped`;
//! * two equal spheres at `s = 2.1`: Stimson and Jeffery's exact speed along their line
//!   of centres, the published side-by-side speed and spin across it (the references of
//!   `near_iter.rs`);
//! * the layout: no packed grand mobility, bytes linear in `n`;
//! * the refusals that remain, typed, the state unchanged.
//!
//! `cargo test --release --test kernel near_fast:: -- --nocapture`.
#![cfg(all(feature = "near", feature = "fast-free"))]

use crate::common;
use crate::near_iter::{Out, cluster, falls_as_exact, relative_gap};

use common::*;
use hydrorattle::integrate::{fast_storage, fast_vectors};
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    Bond, BondSet, Brownian, Contacts, Layout, Method, NoForce, Noise, ParticleSet, Real,
    SolverKind, StepError, StepReport, step,
};
use hydrorattle_heap::{Buffers, FreeBuffers};

/// The iterative near field with rotation; its far field the fast free-space product
/// at tolerance `fast`, else the assembled grand mobility.
fn near<T: Real>(method: Method, fast: Option<f64>) -> hydrorattle::Params<T> {
    let mut p = params::<T>(1e-2, method, SolverKind::Auto);
    p.near = Some(NearField::default());
    p.rotation = true;
    p.matrix_free = true;
    p.pse = fast;
    p
}

/// One step of `spheres` with `bonds` under `p` (thermal with the generator of `seed`),
/// the fast product's arrays as `fast_storage` and `fast_vectors` ask: its report and
/// the state after it, or the error with the state as before (asserted bit for bit).
fn one_step<T: Real>(
    p: &hydrorattle::Params<T>,
    spheres: &[Sphere],
    bonds: &[Bond<T>],
    seed: Option<u64>,
) -> Result<(StepReport<T>, Out), StepError> {
    let n = spheres.len();
    let mut ps: ParticleSet<T, 128> = particles(spheres);
    let mut set: BondSet<T, 128> = BondSet::new();
    for &b in bonds {
        set.push(b, n).unwrap();
    }
    let mut buf = Buffers::<T>::new(Layout::for_params(p, n, bonds.len()));
    let (pos, rad) = (&ps.pos[..n], &ps.radius[..n]);
    let mut arrays = FreeBuffers::<T>::for_step(fast_storage(p, pos, rad)?);
    let mut spare = vec![T::V3_ZERO; fast_vectors(p, n)];
    let mut ws = arrays.attach(buf.workspace()).with_fast_vectors(&mut spare);
    let get = |v: &[T::V3]| -> Vec<[f64; 3]> { (0..n).map(|i| f64s::<T>(v[i])).collect() };
    let before = (get(&ps.pos), get(&ps.vel), get(&ps.omega));
    let r = match seed {
        Some(s) => step_thermal(&mut ps, &set, p, &mut ws, &mut NoForce, &mut Noise::new(s)),
        None => step(&mut ps, &set, p, &mut ws, &mut NoForce),
    };
    let after = (get(&ps.pos), get(&ps.vel), get(&ps.omega));
    match r {
        Ok(r) => Ok((r, after)),
        Err(e) => {
            assert_eq!(before, after, "{e:?}: the state moved");
            Err(e)
        }
    }
}

/// The fast far field's step against the assembled one's, `what` naming it: velocities
/// and spins within `bound` of the largest; both report the same close pairs and
/// products, neither forms `M_SD`.
fn compare<T: Real>(
    p: hydrorattle::Params<T>,
    tol: f64,
    spheres: &[Sphere],
    bonds: &[Bond<T>],
    seed: Option<u64>,
    bound: f64,
    what: &str,
) {
    let (ra, assembled) = one_step::<T>(&p, spheres, bonds, seed).unwrap();
    let fast_p = hydrorattle::Params {
        pse: Some(tol),
        ..p
    };
    let (rf, fast) = one_step::<T>(&fast_p, spheres, bonds, seed).unwrap();
    let (dv, dw) = (
        relative_gap(&fast.1, &assembled.1),
        relative_gap(&fast.2, &assembled.2),
    );
    println!(
        "{what}, tol {tol:e}: pairs {}, products {}/{}, iterations {}/{}, velocities {dv:.1e}, spins {dw:.1e}",
        rf.near_pairs, rf.near_products, ra.near_products, rf.near_iterations, ra.near_iterations
    );
    assert!(dv < bound && dw < bound, "{what}, tol {tol}: {dv:e} {dw:e}");
    assert!(dv > 0.0, "{what}: the fast far field did not run");
    assert_eq!(rf.near_pairs, ra.near_pairs, "{what}");
    assert_eq!(rf.near_formations, 0, "{what}: formed M_SD");
}

/// Clusters of 7 to 60 spheres with close pairs (gaps down to 0.005 radii), both
/// overdamped methods: the fast far field's velocities and spins are the assembled far
/// field's within a small multiple of the fast tolerance (`1e-4`, `1e-8`; f32 at
/// `1e-4`, within its own rounding of the conjugate gradients).
fn matches_assembled<T: Real>() {
    let tols: &[f64] = match is_single::<T>() {
        true => &[1e-4],
        false => &[1e-4, 1e-8],
    };
    for (n, seed) in [(7, 2), (20, 3), (60, 4)] {
        let spheres = cluster(n, seed, None, [0.0; 3]);
        for method in [Method::Overdamped, Method::Overdamped2] {
            for &tol in tols {
                let bound = pick::<T>(5e-3, 20.0 * tol);
                let what = format!("{n} spheres, {method:?}");
                compare(
                    near::<T>(method, None),
                    tol,
                    &spheres,
                    &[],
                    None,
                    bound,
                    &what,
                );
            }
        }
    }
}

/// Every method the iterative near field serves, on the fast far field against the
/// assembled one: bonds by Krylov in `Overdamped` and `Overdamped2`, hard contacts,
/// and thermal `Overdamped` (the far field's Lanczos root on the fast product, the same
/// deviates) with and without bonds.
fn serves_every_method<T: Real>() {
    let spheres = cluster(20, 5, None, [0.0; 3]);
    // A chain along the cluster's first spheres, each bond at its length.
    let bonds: Vec<Bond<T>> = (1..6)
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: T::from_f64(norm(sub(spheres[i].pos, spheres[i - 1].pos))),
        })
        .collect();
    let tol = pick::<T>(1e-4, 1e-8);
    let bound = pick::<T>(5e-3, 1e-6);
    for method in [Method::Overdamped, Method::Overdamped2] {
        let mut p = near::<T>(method, None);
        p.solver.kind = SolverKind::Krylov;
        compare(
            p,
            tol,
            &spheres,
            &bonds,
            None,
            bound,
            &format!("bonds, {method:?}"),
        );
    }
    let mut p = near::<T>(Method::Overdamped, None);
    p.contacts = Some(Contacts::new(64));
    p.dt = T::from_f64(0.5);
    compare(p, tol, &spheres, &[], None, bound, "contacts");
    // Thermal: the same deviates; the Lanczos roots of the two far fields differ by
    // the fast tolerance and Lanczos's own (`Params::lanczos`).
    let mut p = near::<T>(Method::Overdamped, None);
    p.brownian = Some(Brownian::new(T::from_f64(1e-2)));
    p.allow_overlap = true;
    let bound = pick::<T>(5e-3, 1e-4);
    compare(p, tol, &spheres, &[], Some(7), bound, "thermal");
    p.solver.kind = SolverKind::Krylov;
    compare(p, tol, &spheres, &bonds, Some(8), bound, "thermal, bonds");
}

/// Two equal spheres at `s = 2.1` on the fast far field (`1e-4` and `1e-8`; f32 at
/// `1e-4`, the finest its precision reaches): along their line of centres at Stimson
/// and Jeffery's exact speed, side by side at 1.3917 `U0` (within 0.5 %), spinning at
/// 0.137 `U0 / a` (within 2 %), as `near_iter.rs` checks the assembled far field.
fn pair_falls<T: Real>() {
    let tols: &[f64] = match is_single::<T>() {
        true => &[1e-4],
        false => &[1e-4, 1e-8],
    };
    for &tol in tols {
        for method in [Method::Overdamped, Method::Overdamped2] {
            let p = near::<T>(method, Some(tol));
            let one = |p: &_, s: &[Sphere]| one_step::<T>(p, s, &[], None).unwrap();
            falls_as_exact(&p, &format!("{tol:e} {method:?}"), one);
        }
    }
}

/// The layout of the fast far field's step holds no packed grand mobility: exactly
/// `tri(2n)` blocks below the assembled far field's, and linear in `n` (its bytes at
/// 4000 spheres four times those at 1000, within 1 %), every method it serves.
fn storage_is_linear<T: Real>() {
    let tri2 = |n: usize| 2 * n * (2 * n + 1) / 2;
    let m3 = core::mem::size_of::<T::M3>();
    for (method, thermal) in [
        (Method::Overdamped, false),
        (Method::Overdamped2, false),
        (Method::Overdamped, true),
    ] {
        let with = |fast: Option<f64>, n: usize| {
            let mut p = near::<T>(method, fast);
            p.brownian = thermal.then(|| Brownian::new(T::ONE));
            Layout::for_params(&p, n, 0)
        };
        for n in [1000, 4000] {
            let (fast, assembled) = (with(Some(1e-4), n), with(None, n));
            assert_eq!(fast.blocks + tri2(n), assembled.blocks, "{method:?} {n}");
            let bytes = assembled.bytes::<T>() - fast.bytes::<T>();
            assert_eq!(bytes, tri2(n) * m3, "{method:?} {n}");
        }
        let (small, large) = (with(Some(1e-4), 1000), with(Some(1e-4), 4000));
        let ratio = large.bytes::<T>() as f64 / small.bytes::<T>() as f64;
        println!(
            "{method:?}, thermal {thermal}: {} bytes at 1000, ratio {ratio:.4} to 4000; the assembled far field's tri(2000) blocks {} bytes",
            small.bytes::<T>(),
            tri2(1000) * m3
        );
        assert!((ratio / 4.0 - 1.0).abs() < 0.01, "{method:?}: {ratio}");
    }
}

/// What stays refused on the fast far field, typed, the state unchanged: the sweep
/// with bonds (it tabulates along products the fast product's checks do not admit:
/// Krylov serves them). PSE's grand product in a box is served (`near_pse.rs`).
fn refusals<T: Real>() {
    let spheres = cluster(12, 21, None, [0.0; 3]);
    let bond = Bond {
        i: 0,
        j: 1,
        length: T::from_f64(norm(sub(spheres[1].pos, spheres[0].pos))),
    };
    let mut p = near::<T>(Method::Overdamped, Some(1e-4));
    p.solver.kind = SolverKind::Sweep;
    match one_step::<T>(&p, &spheres, &[bond], None) {
        Err(StepError::Unsupported(m)) => assert!(m.contains("Sweep"), "{m}"),
        other => panic!("sweep: {other:?}"),
    }
}

crate::both_precisions! {
    matches_assembled => matches_assembled;
    serves_every_method => serves_every_method;
    pair_falls => pair_falls;
    storage_is_linear => storage_is_linear;
    refusals => refusals;
}
