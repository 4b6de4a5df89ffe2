//! Storage budgets: the paper's chain (N = 25, B = 24) in f32, particles +
//! bonds + workspace, measured with `size_of` and the method's [`Layout`]. The table
//! for f32 and f64 prints with `--nocapture` and is copied into docs/STORAGE.md.
//!
//! Also: a workspace of exactly the layout's size works for every method, rotation
//! flag and solver; one element short of any count is a typed error that leaves the
//! state alone; and the step's result does not depend on what the storage held before
//! (stale or NaN contents are never read).

use crate::common;

use common::*;
use hydrorattle::{
    BondSet, Layout, Method, NoForce, ParticleSet, Real, SolverKind, StepError, Workspace, step,
};

const N: usize = 25;
const B: usize = 24;
const KB: usize = 1024;

/// `(method, rotation, budget in bytes)`; `None`: no budget set (reported only).
const BUDGETS: [(Method, bool, Option<usize>); 6] = [
    (Method::Overdamped, false, Some(40 * KB)),
    (Method::Overdamped2, false, Some(64 * KB)),
    (Method::Rattle, false, Some(64 * KB)),
    (Method::RattleStable, false, Some(64 * KB)),
    (Method::RattleStable, true, None),
    (Method::Springs, false, Some(24 * KB)),
];

fn total<T: Real>(method: Method, rotation: bool) -> usize {
    core::mem::size_of::<ParticleSet<T, N>>()
        + core::mem::size_of::<BondSet<T, B>>()
        + Layout::new(method, rotation, N, B).bytes::<T>()
}

#[test]
fn paper_chain_fits_the_budgets() {
    eprintln!("| method | rotation | f32 bytes | f64 bytes | f32 budget |");
    eprintln!("|---|---|---|---|---|");
    let mut over = Vec::new();
    for (method, rotation, budget) in BUDGETS {
        let (single, double) = (
            total::<f32>(method, rotation),
            total::<f64>(method, rotation),
        );
        let shown = budget.map_or("-".to_string(), |b| b.to_string());
        eprintln!("| {method:?} | {rotation} | {single} | {double} | {shown} |");
        if budget.is_some_and(|b| single > b) {
            over.push((method, rotation, single, budget));
        }
    }
    let free = |bytes: usize| {
        core::mem::size_of::<ParticleSet<f32, N>>()
            + core::mem::size_of::<BondSet<f32, B>>()
            + bytes
    };
    let mf = Layout::new(Method::Overdamped, false, N, B).matrix_free(
        Method::Overdamped,
        SolverKind::Auto,
        N,
        B,
    );
    let mf64 = core::mem::size_of::<ParticleSet<f64, N>>()
        + core::mem::size_of::<BondSet<f64, B>>()
        + mf.bytes::<f64>();
    eprintln!(
        "| Overdamped matrix-free | false | {} | {mf64} | - |",
        free(mf.bytes::<f32>())
    );
    // Thermal noise: the Cholesky factor and the midpoint's vectors on top.
    let th = Layout::new(Method::Overdamped, false, N, B).thermal(Method::Overdamped, N, B);
    let th64 = core::mem::size_of::<ParticleSet<f64, N>>()
        + core::mem::size_of::<BondSet<f64, B>>()
        + th.bytes::<f64>();
    eprintln!(
        "| Overdamped thermal | false | {} | {th64} | - |",
        free(th.bytes::<f32>())
    );
    // Hard contacts: 3 per bead counted as extra constraints, Newton solver
    // (the Figure 1 scenes' settings).
    for (method, capacity) in [(Method::Overdamped, 75), (Method::Overdamped2, 75)] {
        let mut p = hydrorattle::Params::<f32>::new(0.1);
        p.method = method;
        p.solver.kind = SolverKind::Newton;
        p.contacts = Some(hydrorattle::Contacts::new(capacity));
        let l = Layout::for_params(&p, N, B);
        let d64 = core::mem::size_of::<ParticleSet<f64, N>>()
            + core::mem::size_of::<BondSet<f64, B>>()
            + l.bytes::<f64>();
        eprintln!(
            "| {method:?} with {capacity} contacts | false | {} | {d64} | - |",
            free(l.bytes::<f32>())
        );
    }
    assert!(over.is_empty(), "over budget: {over:?}");
}

/// One step of a settling 25-bead helix in a workspace of exactly `layout`, whose
/// every element starts as `fill` (NaN included: a step must overwrite what it reads).
/// Returns the result and the state's bits before and after.
fn step_in<T: Real>(
    method: Method,
    rotation: bool,
    kind: SolverKind,
    layout: Layout,
    fill: f64,
) -> (
    Result<hydrorattle::StepReport<T>, StepError>,
    Vec<u64>,
    Vec<u64>,
) {
    let scene = helix(N, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, N> = particles(&scene);
    let bonds: BondSet<T, B> = BondSet::chain(&ps.pos[..N]).unwrap();
    let before = snapshot(&ps);
    let mut blocks = vec![T::M3_IDENTITY * T::from_f64(fill); layout.blocks];
    let mut vectors = vec![T::v3_from([fill; 3]); layout.vectors];
    let mut scalars = vec![T::from_f64(fill); layout.scalars];
    let mut indices = vec![usize::MAX; layout.indices];
    let mut ws = Workspace::new(&mut blocks, &mut vectors, &mut scalars, &mut indices);
    let mut p = params::<T>(0.02, method, kind);
    p.rotation = rotation;
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    (r, before, snapshot(&ps))
}

fn exact_layouts<T: Real>() {
    for method in [
        Method::Overdamped,
        Method::Overdamped2,
        Method::Rattle,
        Method::RattleStable,
        Method::Springs,
    ] {
        for rotation in [false, true] {
            for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
                let l = Layout::with_solver(method, rotation, kind, N, B);
                let (clean, before, after) = step_in::<T>(method, rotation, kind, l, 0.0);
                let clean = clean.unwrap_or_else(|e| panic!("{method:?} {kind:?}: {e}"));
                assert_ne!(before, after);
                let (dirty, _, after_dirty) = step_in::<T>(method, rotation, kind, l, f64::NAN);
                assert_eq!(
                    dirty,
                    Ok(clean),
                    "{method:?} {rotation} {kind:?}: stale read"
                );
                assert_eq!(
                    after, after_dirty,
                    "{method:?} {rotation} {kind:?}: stale read"
                );
                let counts = [l.blocks, l.vectors, l.scalars, l.indices];
                for (c, &count) in counts.iter().enumerate() {
                    if count == 0 {
                        continue;
                    }
                    let mut short = l;
                    *[
                        &mut short.blocks,
                        &mut short.vectors,
                        &mut short.scalars,
                        &mut short.indices,
                    ][c] -= 1;
                    let (r, before, after) = step_in::<T>(method, rotation, kind, short, 0.0);
                    assert!(
                        matches!(r, Err(StepError::Storage { .. })),
                        "{method:?} {rotation} {kind:?} count {c}: {r:?}"
                    );
                    assert_eq!(before, after, "state changed on a refused step");
                }
            }
        }
    }
}

both_precisions! {
    exact_layout_suffices_and_one_less_is_refused => exact_layouts;
}
