//! `Method::Overdamped2` matrix-free (`Params::matrix_free`): the predictor-corrector
//! with every mobility a product where it is used (the pair products in free space and
//! in the Ewald box, the fast free-space product, PSE in a box). Checked against values
//! not from the matrix-free code:
//!
//! * the same steps on the stored mobility (the dense `Overdamped2`) within rounding
//!   on the pair products (free space, the box and above a wall: the same bits in free
//!   space and above the wall), with and without bonds (every solver), and
//!   within the fast products' tolerance on the fast free-space product and PSE;
//! * the order of the scheme: a small cluster falling through a rotating flow, against
//!   a fine-step reference, on the fast product: the error falls by about 4 as the step
//!   halves (`Overdamped` by about 2);
//! * a step that fails in its corrector leaves the state as it was; thermal noise is
//!   refused, typed.
//!
//! The allocation count is in `tests/kernel/alloc.rs` (its counting allocator).
//! `cargo test --release --test kernel free_o2:: -- --nocapture`.

use crate::common;
use crate::fast_rotation::spin_error;
use crate::fast_step::{arrays, on, relative, set};

use common::boxes::config_radii;
use common::*;
use hydrorattle::integrate::{fast_vectors, pse_storage};
use hydrorattle::{
    BondSet, Brownian, ExternalForce, Layout, Method, NoForce, Params, ParticleSet, Periodic, Real,
    SolverKind, StepError, Wall, step,
};
use hydrorattle_heap::{Buffers, FreeBuffers, PseBuffers};

/// One vector a sphere.
type Points = Vec<[f64; 3]>;

/// `steps` steps of `p` from the spheres `s` (the fast products' arrays sized where `p`
/// takes them); the positions and spins at the end.
fn run<const M: usize, const B: usize>(
    s: &[Sphere],
    bonds: &BondSet<f64, B>,
    p: &Params<f64>,
    ext: &mut impl ExternalForce<f64>,
    steps: usize,
) -> Result<(Points, Points), StepError> {
    let mut ps = set::<M>(s);
    let n = s.len();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, n, bonds.len()));
    let boxed = p.periodic.is_some();
    let mut fast = match p.pse {
        Some(_) if !boxed => arrays(p, s, [1.0; 3]),
        _ => FreeBuffers::default(),
    };
    let mut pse = PseBuffers::for_step(pse_storage(p, &ps.radius[..n]).unwrap());
    let mut spare = vec![f64::V3_ZERO; fast_vectors(p, n)];
    let ws = buf.workspace();
    let mut ws = match boxed {
        true => pse.attach(ws),
        false => fast.attach(ws).with_fast_vectors(&mut spare),
    };
    for _ in 0..steps {
        step(&mut ps, bonds, p, &mut ws, ext)?;
    }
    let f = |v: &[<f64 as Real>::V3]| v[..n].iter().map(|&r| f64s::<f64>(r)).collect();
    Ok((f(&ps.pos), f(&ps.omega)))
}

const K: usize = 12;

/// `K` polydisperse spheres (radii 0.5 to 1), apart, densities 2 to 6, in a cube of
/// edge `edge`.
fn spheres(edge: f64) -> Vec<Sphere> {
    let (pos, rad) = config_radii(K, 5, [edge; 3], [0.5, 1.0], false);
    assert_eq!(pos.len(), K);
    (0..K)
        .map(|i| Sphere {
            pos: pos[i],
            radius: rad[i],
            density: 2.0 + (i % 5) as f64,
        })
        .collect()
}

/// `Overdamped2` at `dt` with the solver `kind`, matrix-free or stored.
fn o2(dt: f64, kind: SolverKind, matrix_free: bool) -> Params<f64> {
    let mut p = params::<f64>(dt, Method::Overdamped2, kind);
    p.matrix_free = matrix_free;
    p
}

/// The pair products in free space (rotation on: spins from the matrix-free `rt`
/// products), in the Ewald box and above a wall (`z = -2`): five steps matrix-free
/// within rounding of the stored `Overdamped2`'s, and no block stored.
#[test]
fn pair_products_match_stored() {
    let none = BondSet::<f64, 0>::new();
    for (boxed, wall) in [(false, false), (true, false), (false, true)] {
        let s = spheres(12.0);
        let place = |mut p: Params<f64>| {
            p.rotation = !boxed;
            p.periodic = boxed.then(|| Periodic::new([12.0; 3]).unwrap());
            p.wall = wall.then(|| Wall::new(-2.0));
            p
        };
        let stored = place(o2(0.05, SolverKind::Auto, false));
        let free = place(o2(0.05, SolverKind::Auto, true));
        assert_eq!(Layout::for_params(&free, K, 0).blocks, 0);
        let a = run::<K, 0>(&s, &none, &stored, &mut NoForce, 5).unwrap();
        let b = run::<K, 0>(&s, &none, &free, &mut NoForce, 5).unwrap();
        // (No spins in the box: rotation is off there.)
        let spin = match boxed {
            true => 0.0,
            false => spin_error(&a.1, &b.1),
        };
        let err = relative(&s, &a.0, &b.0);
        println!("box {boxed} wall {wall}: matrix-free vs stored {err:.2e}, spins {spin:.2e}");
        assert!(
            err < 1e-13 && spin < 1e-13,
            "box {boxed} wall {wall}: {err:e} {spin:e}"
        );
    }
}

/// A bonded chain of 8 beads, sedimenting with a twist: matrix-free `Overdamped2` within
/// rounding of the stored one with every solver (Krylov's products, the sweep's and
/// Newton's blocks evaluated where read), in free space and in the Ewald box.
#[test]
fn constrained_pairs_match_stored() {
    const C: usize = 8;
    let scene = helix(C, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let bonds: BondSet<f64, { C - 1 }> = {
        let ps: ParticleSet<f64, C> = particles(&scene);
        BondSet::chain(&ps.pos[..C]).unwrap()
    };
    for boxed in [false, true] {
        for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
            let place = |mut p: Params<f64>| {
                // (A rotating flow is not periodic: in the box gravity alone.)
                if !boxed {
                    p.vorticity = f64::v3(0.0, 0.0, 0.3);
                }
                p.periodic = boxed.then(|| Periodic::new([14.0; 3]).unwrap());
                p
            };
            let stored = place(o2(0.02, kind, false));
            let free = place(o2(0.02, kind, true));
            let a = run::<C, { C - 1 }>(&scene, &bonds, &stored, &mut NoForce, 4).unwrap();
            let b = run::<C, { C - 1 }>(&scene, &bonds, &free, &mut NoForce, 4).unwrap();
            let err = relative(&scene, &a.0, &b.0);
            println!("box {boxed} {kind:?}: matrix-free vs stored {err:.2e}");
            assert!(err < 1e-9, "box {boxed} {kind:?}: {err:e}");
        }
    }
}

/// The fast products: `Overdamped2` on the fast free-space product (rotation on: spins
/// from its grand product) and on PSE in the box, three steps within a small multiple
/// of the tolerance of the stored `Overdamped2`; with bonds by Krylov too.
#[test]
fn fast_products_match_stored() {
    let none = BondSet::<f64, 0>::new();
    let s = spheres(12.0);
    for tol in [1e-4, 1e-6] {
        let mut dense = o2(0.05, SolverKind::Auto, false);
        dense.rotation = true;
        let fast = on(dense, Some(tol));
        let mut dense = on(dense, None);
        dense.matrix_free = false;
        let a = run::<K, 0>(&s, &none, &dense, &mut NoForce, 3).unwrap();
        let b = run::<K, 0>(&s, &none, &fast, &mut NoForce, 3).unwrap();
        let (err, spin) = (relative(&s, &a.0, &b.0), spin_error(&a.1, &b.1));
        println!("fast free tol {tol:e}: vs stored {err:.2e}, spins {spin:.2e}");
        assert!(
            err < 3.0 * tol && spin < 3.0 * tol,
            "tol {tol}: {err:e} {spin:e}"
        );
        assert!(err > 0.0, "the fast product did not run");

        let boxed = |pse: Option<f64>| {
            let mut p = o2(0.05, SolverKind::Auto, pse.is_some());
            p.periodic = Some(Periodic::new([12.0; 3]).unwrap());
            p.pse = pse;
            p
        };
        let a = run::<K, 0>(&s, &none, &boxed(None), &mut NoForce, 3).unwrap();
        let b = run::<K, 0>(&s, &none, &boxed(Some(tol)), &mut NoForce, 3).unwrap();
        let err = relative(&s, &a.0, &b.0);
        println!("PSE tol {tol:e}: vs stored Ewald {err:.2e}");
        assert!(err < 3.0 * tol && err > 0.0, "PSE tol {tol}: {err:e}");
    }
    // A chain by Krylov on the fast free-space product.
    const C: usize = 8;
    let scene = helix(C, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let ps: ParticleSet<f64, C> = particles(&scene);
    let bonds: BondSet<f64, { C - 1 }> = BondSet::chain(&ps.pos[..C]).unwrap();
    let mut dense = o2(0.02, SolverKind::Krylov, false);
    dense.vorticity = f64::v3(0.0, 0.0, 0.3);
    let fast = on(dense, Some(1e-6));
    let a = run::<C, { C - 1 }>(&scene, &bonds, &dense, &mut NoForce, 4).unwrap();
    let b = run::<C, { C - 1 }>(&scene, &bonds, &fast, &mut NoForce, 4).unwrap();
    let err = relative(&scene, &a.0, &b.0);
    println!("fast free chain (Krylov) tol 1e-6: vs stored {err:.2e}");
    assert!(err < 3e-6 && err > 0.0, "{err:e}");
}

/// The scheme's order on the fast free-space product: 6 spheres falling through a
/// rotating flow (`Omega = 0.3 z`) to `t = 4` at `dt = 0.2, 0.1, 0.05`, against
/// `Overdamped2` at `dt = 0.05 / 16` on the same product. `Overdamped2`'s error falls
/// by about 4 as the step halves, `Overdamped`'s by about 2.
#[test]
fn second_order_on_fast_product() {
    const M: usize = 6;
    let s: Vec<Sphere> = [
        [3.0, 0.0, 0.0],
        [0.5, 2.6, 0.4],
        [-2.4, 1.0, -0.5],
        [-1.0, -2.9, 0.8],
        [1.9, -2.2, -1.6],
        [0.2, 0.3, 2.5],
    ]
    .iter()
    .enumerate()
    .map(|(i, &pos)| Sphere {
        pos,
        radius: 0.6 + 0.08 * i as f64,
        density: 2.0 + (i % 3) as f64,
    })
    .collect();
    let none = BondSet::<f64, 0>::new();
    let at = |method, dt: f64| {
        let mut p = params::<f64>(dt, method, SolverKind::Auto);
        p.vorticity = f64::v3(0.0, 0.0, 0.3);
        let p = on(p, Some(1e-7));
        let steps = (4.0 / dt).round() as usize;
        run::<M, 0>(&s, &none, &p, &mut NoForce, steps).unwrap().0
    };
    let reference = at(Method::Overdamped2, 0.05 / 16.0);
    for (method, order) in [(Method::Overdamped, 2.0), (Method::Overdamped2, 4.0)] {
        let err: Vec<f64> = [0.2, 0.1, 0.05]
            .iter()
            .map(|&dt| relative(&s, &reference, &at(method, dt)))
            .collect();
        let ratios = [err[0] / err[1], err[1] / err[2]];
        let shown: Vec<String> = err.iter().map(|e| format!("{e:.3e}")).collect();
        println!("{method:?}: errors {shown:?}, ratios {ratios:.2?}");
        for r in ratios {
            assert!(
                (r - order).abs() < 0.2 * order,
                "{method:?}: ratios {ratios:?}"
            );
        }
    }
}

/// A step that stretches the cloud past the margin the fast product was sized with
/// (`integrate::FAST_MARGIN` radii): a heavy and a light sphere side by side, `dt = 4`,
/// their predicted heights some 17 radii apart. The corrector's product derives
/// parameters over the predicted cloud: the step within the tolerance of the stored
/// `Overdamped2`'s (refused before, as beyond the fast product's extent).
#[test]
fn fast_predictor_beyond_margin() {
    let s = [
        Sphere {
            pos: [0.0, 0.0, 0.0],
            radius: 1.0,
            density: 20.0,
        },
        Sphere {
            pos: [6.0, 0.0, 0.0],
            radius: 1.0,
            density: 1.0,
        },
    ];
    let none = BondSet::<f64, 0>::new();
    let dense = o2(4.0, SolverKind::Auto, false);
    let a = run::<2, 0>(&s, &none, &dense, &mut NoForce, 1).unwrap();
    let b = run::<2, 0>(&s, &none, &on(dense, Some(1e-6)), &mut NoForce, 1).unwrap();
    let apart = a.0[1][2] - a.0[0][2];
    let err = relative(&s, &a.0, &b.0);
    println!("heights {apart:.1} apart: fast vs stored {err:.2e}");
    assert!(apart > 8.0 * 1.0 + 4.0, "{apart}");
    assert!(err < 3e-6 && err > 0.0, "{err:e}");
}

/// A step whose corrector fails (the external force is not finite at the predicted
/// point) is refused with the state untouched, on the pair products and on the fast
/// product; thermal noise with `Overdamped2` is refused, typed, matrix-free too.
#[test]
fn refused_steps_leave_state() {
    let s = spheres(12.0);
    let none = BondSet::<f64, 0>::new();
    for fast in [None, Some(1e-6)] {
        let mut p = o2(0.05, SolverKind::Auto, true);
        p.pse = fast;
        let mut ps = set::<K>(&s);
        let mut buf = Buffers::<f64>::new(Layout::for_params(&p, K, 0));
        let mut a = match fast {
            Some(_) => arrays(&p, &s, [1.0; 3]),
            None => FreeBuffers::default(),
        };
        let mut ws = a.attach(buf.workspace());
        let before = (ps.pos, ps.vel, ps.omega, ps.time);
        let mut calls = 0;
        let mut second_fails = |_: &[<f64 as Real>::V3], _: &[f64], f: &mut [<f64 as Real>::V3]| {
            calls += 1;
            if calls == 2 {
                f[3] = f64::v3(f64::NAN, 0.0, 0.0);
            }
        };
        let r = step(&mut ps, &none, &p, &mut ws, &mut second_fails);
        assert_eq!(
            r,
            Err(StepError::NonFiniteForce { particle: 3 }),
            "{fast:?}"
        );
        assert_eq!(before, (ps.pos, ps.vel, ps.omega, ps.time), "{fast:?}");
        let mut hot = p;
        hot.brownian = Some(Brownian::new(1.0));
        ps.noise = Some(hydrorattle::Noise::new(1));
        let r = step(&mut ps, &none, &hot, &mut ws, &mut NoForce);
        assert!(
            matches!(r, Err(StepError::Unsupported(_))),
            "{fast:?}: {r:?}"
        );
        assert_eq!(before, (ps.pos, ps.vel, ps.omega, ps.time), "{fast:?}");
        // The same workspace then takes the step.
        step(&mut ps, &none, &p, &mut ws, &mut NoForce).unwrap();
        assert!(ps.time > before.3);
    }
}
