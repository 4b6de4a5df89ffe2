//! Golden digests: the paper's 25-bead helix after K = 50 steps, hashed bit for bit
//! (FNV-1a over the `to_bits()` of every position and velocity component; f32 values
//! are widened to f64 first, which is exact). Two fresh runs must agree with each other
//! and with the pinned constant.
//!
//! The pins are regression/determinism guards, not physics: they change whenever the
//! arithmetic of a step changes (operation order, solver, compiler or target floating
//! point). To regenerate after an intended change, run
//! `cargo test --release --test kernel determinism:: -- --nocapture` and copy the printed
//! `got` values into `PINS`.

use crate::common;

use common::*;
use hydrorattle::{BondSet, Method, NoForce, ParticleSet, Real, SolverKind};

const K: usize = 50;
const DT: f64 = 0.02;

/// `(method, precision, digest)`.
const PINS: [(Method, &str, u64); 4] = [
    (Method::Overdamped, "f64", 0xbb30_f6ce_486c_75c0),
    (Method::RattleStable, "f64", 0x74c7_a6a6_d653_953c),
    (Method::Overdamped, "f32", 0x42d5_ed17_f087_2c40),
    (Method::RattleStable, "f32", 0x99d3_cbe8_54be_3f47),
];

/// The helix scene: head of radius 2^(1/3) at index 0, 24 tails of radius 1, helix
/// radius 3, rise 0.5 per bead, bond lengths 1.5 (a_i + a_j), equal density 4.5.
/// `dirty` first runs a different integration (rotation resolved, sweeps) in the same
/// workspace: stale scratch must not leak into the result.
fn digest<T: Real>(method: Method, dirty: bool) -> u64 {
    let scene = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let fresh: ParticleSet<T, 25> = particles(&scene);
    let bonds: BondSet<T, 24> = BondSet::chain(&fresh.pos[..25]).unwrap();
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(25, 24));
    let mut ws = ws_store.workspace();
    if dirty {
        let mut other = fresh.clone();
        let mut p = params::<T>(0.1, Method::RattleStable, SolverKind::Sweep);
        p.rotation = true;
        run(&mut other, &bonds, &p, &mut ws, &mut NoForce, 3);
    }
    let mut ps = fresh;
    let p = params::<T>(DT, method, SolverKind::Newton);
    run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, K);
    state_digest(&ps)
}

fn golden<T: Real>() {
    let precision = if is_single::<T>() { "f32" } else { "f64" };
    let mut mismatches = Vec::new();
    for method in [Method::Overdamped, Method::RattleStable] {
        let first = digest::<T>(method, false);
        let second = std::thread::spawn(move || digest::<T>(method, true))
            .join()
            .unwrap();
        assert_eq!(first, second, "{method:?} {precision}: two runs differ");
        let pin = PINS
            .iter()
            .find(|(m, p, _)| *m == method && *p == precision)
            .map(|&(_, _, d)| d)
            .unwrap();
        eprintln!("golden {method:?} {precision}: got {first:#018x}, pinned {pin:#018x}");
        if first != pin {
            mismatches.push(format!(
                "{method:?} {precision}: got {first:#018x}, pinned {pin:#018x}"
            ));
        }
    }
    assert!(
        mismatches.is_empty(),
        "golden digests changed: {mismatches:?}"
    );
}

both_precisions! {
    helix_golden_digest => golden;
}
