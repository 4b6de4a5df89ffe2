//! `StepReport::factorizations` on a settling contact pile: the dense Newton solve
//! reports its factorisations from scratch (one a step: the factor then follows the
//! active set row by row, from round to round), the sweep and Krylov none; the pile
//! lands with every contact and wall link held.

use hydrorattle::{
    Bond, Contacts, Layout, Method, NoForce, Params, Real, SolverKind, State, Wall, step_slices,
};
use hydrorattle_heap::Buffers;

type V = <f64 as Real>::V3;

/// A fence of `fence` bonded heavy spheres on the wall around a column of `count` unit
/// spheres, `side x side` a layer, jittered by a fixed pattern (the geometry of
/// `examples/pile_cost.rs`; also `pile_krylov.rs`).
pub(crate) fn pile(
    fence: usize,
    side: usize,
    count: usize,
) -> (Vec<V>, Vec<f64>, Vec<f64>, Vec<Bond<f64>>) {
    let ring = 1.501 / (std::f64::consts::PI / fence as f64).sin();
    let (mut pos, mut radius, mut density) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..fence {
        let a = std::f64::consts::TAU * i as f64 / fence as f64;
        pos.push(V::new(ring * a.cos(), ring * a.sin(), 1.5));
        radius.push(1.5);
        density.push(10.0);
    }
    let jitter = |k: usize, c: usize| 0.1 * (((k * 7919 + c * 104_729) % 1000) as f64 / 1e3 - 0.5);
    let off = 1.15 * (side as f64 - 1.0);
    for k in 0..count {
        let (l, i, j) = (k / (side * side), (k / side) % side, k % side);
        pos.push(V::new(
            2.3 * i as f64 - off + jitter(k, 1),
            2.3 * j as f64 - off + jitter(k, 2),
            2.6 + 2.3 * l as f64 + jitter(k, 3),
        ));
        radius.push(1.0);
        density.push(4.5);
    }
    let bonds = (0..fence)
        .map(|i| Bond {
            i,
            j: (i + 1) % fence,
            length: 3.002,
        })
        .collect();
    (pos, radius, density, bonds)
}

/// Steps the pile 60 times with `kind`; returns the factorisations and rounds of
/// steps 30 to 59.
fn counts(kind: SolverKind) -> (u32, u32) {
    // 76 spheres: a fence of 12 around a 4 x 4 x 4 column.
    let (mut pos, radius, density, bonds) = pile(12, 4, 64);
    let n = pos.len();
    let mut p = Params::<f64>::new(0.2);
    p.method = Method::Overdamped;
    p.solver.kind = kind;
    p.solver.tolerance = 1e-10;
    p.solver.max_iterations = 5000;
    p.wall = Some(Wall::new(0.0));
    p.contacts = Some(Contacts::new(7 * n));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, bonds.len()));
    let mut ws = buf.workspace();
    let (mut vel, mut omega, mut time) = (vec![V::ZERO; n], vec![V::ZERO; n], 0.0);
    let (mut factorizations, mut rounds) = (0, 0);
    for k in 0..60 {
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        let r = step_slices(state, &bonds, &p, &mut ws, &mut NoForce).expect("step");
        if k >= 30 {
            factorizations += r.factorizations;
            rounds += r.contact_rounds;
        }
        // Every pair apart and every sphere above the wall, to the tolerance's order.
        for i in 0..n {
            assert!(
                pos[i].z >= radius[i] * (1.0 - 1e-9),
                "step {k}: {i} below the wall"
            );
            for j in 0..i {
                let gap = (pos[i] - pos[j]).length() / (radius[i] + radius[j]);
                assert!(gap >= 1.0 - 1e-9, "step {k}: {i} and {j} overlap ({gap})");
            }
        }
    }
    (factorizations, rounds)
}

#[test]
fn factorisations_are_counted() {
    let (f, rounds) = counts(SolverKind::Newton);
    println!("Newton: {f} factorisations in {rounds} rounds");
    // The factor of the active rows follows the set row by row, and is carried from
    // one round's solve to the next: one factorisation from scratch a step, however
    // often the set changes in it and however many rounds it takes (a factorisation at
    // each change of the set took 303 in these 61 rounds, one a round 61).
    assert!(
        rounds >= 30 && f <= 30,
        "{f} factorisations in 30 steps ({rounds} rounds)"
    );
    for kind in [SolverKind::Krylov, SolverKind::Sweep] {
        assert_eq!(counts(kind).0, 0, "{kind:?}");
    }
}
