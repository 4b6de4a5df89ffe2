//! Golden digests of stored overdamped steps in a periodic box: the paper's 25-bead
//! helix in a cubic box of edge 20, hashed bit for bit after `K` steps. The pins were
//! taken with the box's mobility stored in nine-scalar blocks, before it moved to
//! six-scalar symmetric ones (`linalg::Sym`): the symmetric storage keeps every bit,
//! because every Ewald block is symmetric in bits (`mobility::periodic`'s tests).
//! Regenerate only for a deliberate change of the arithmetic.

use crate::common;

use common::*;
use hydrorattle::{BondSet, Layout, Method, NoForce, ParticleSet, Periodic, Real, SolverKind};

const K: usize = 10;
const DT: f64 = 0.05;

/// `(method, solver, precision, digest)`.
const PINS: [(Method, SolverKind, &str, u64); 6] = [
    (
        Method::Overdamped,
        SolverKind::Newton,
        "f64",
        0xc052_aa9b_88b3_e91e,
    ),
    (
        Method::Overdamped,
        SolverKind::Krylov,
        "f64",
        0x69e8_7aba_648c_32c3,
    ),
    (
        Method::Overdamped2,
        SolverKind::Newton,
        "f64",
        0x6692_70c0_1e9f_6926,
    ),
    (
        Method::Overdamped,
        SolverKind::Newton,
        "f32",
        0x8f61_b58f_72db_7f77,
    ),
    (
        Method::Overdamped,
        SolverKind::Krylov,
        "f32",
        0x022f_e274_40e2_7d5e,
    ),
    (
        Method::Overdamped2,
        SolverKind::Newton,
        "f32",
        0x0c6b_d438_c07a_e364,
    ),
];

fn digest<T: Real>(method: Method, kind: SolverKind) -> u64 {
    let scene = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, 25> = particles(&scene);
    let bonds: BondSet<T, 24> = BondSet::chain(&ps.pos[..25]).unwrap();
    let mut p = params::<T>(DT, method, kind);
    p.periodic = Some(Periodic::new([T::from_f64(20.0); 3]).unwrap());
    let mut buf = hydrorattle_heap::Buffers::<T>::new(Layout::for_params(&p, 25, 24));
    let mut ws = buf.workspace();
    run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, K);
    state_digest(&ps)
}

/// The box stores its mobility as free space does (six scalars a block): the same
/// layout, and the bytes of both, before (nine scalars a block) and now.
#[test]
fn box_layout_is_the_free_space_layout() {
    for method in [Method::Overdamped, Method::Overdamped2] {
        for n in [25, 4096] {
            let free = params::<f64>(DT, method, SolverKind::Krylov);
            let mut p = free;
            p.periodic = Some(Periodic::new([20.0; 3]).unwrap());
            let (boxed, open) = (
                Layout::for_params(&p, n, 0),
                Layout::for_params(&free, n, 0),
            );
            assert_eq!(boxed, open, "{method:?} n {n}");
            let k = if method == Method::Overdamped2 { 2 } else { 1 };
            let nine = Layout {
                blocks: boxed.blocks + k * n * (n + 1) / 2,
                scalars: boxed.scalars - 6 * k * n * (n + 1) / 2,
                ..boxed
            };
            eprintln!(
                "{method:?} n {n}: {} bytes (f64) in a box, {} with nine-scalar blocks",
                boxed.bytes::<f64>(),
                nine.bytes::<f64>()
            );
        }
    }
}

fn golden<T: Real>() {
    let precision = if is_single::<T>() { "f32" } else { "f64" };
    let mut mismatches = Vec::new();
    for &(method, kind, prec, pin) in PINS.iter().filter(|e| e.2 == precision) {
        let got = digest::<T>(method, kind);
        eprintln!("golden box {method:?} {kind:?} {prec}: got {got:#018x}, pinned {pin:#018x}");
        if got != pin {
            mismatches.push((method, kind, got));
        }
    }
    assert!(
        mismatches.is_empty(),
        "box digests changed: {mismatches:x?}"
    );
}

both_precisions! {
    box_golden_digest => golden;
}
