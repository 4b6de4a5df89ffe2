//! One `step()` of every method on a settling chain with compile-time capacities
//! (`step/...`), and the sweep solver on bonds alone (`step_sweep/...`), f64 and f32.

use criterion::{BatchSize, BenchmarkId, Criterion};
use hydrorattle::{
    BondSet, Method, NoForce, Params, Particle, ParticleSet, Real, SolverKind, step,
};

use crate::shared::chain_geometry;

const METHODS: [Method; 5] = [
    Method::Overdamped,
    Method::Overdamped2,
    Method::Rattle,
    Method::RattleStable,
    Method::Springs,
];

/// One `step()` of each listed method on an `N`-bead settling chain (density 4.5,
/// St = 1, dt = 0.01, default Newton solver, RPY). Every iteration restarts from the
/// same state (an O(N) copy made outside the timed region).
fn step_benches<T: Real, const N: usize, const B: usize>(
    c: &mut Criterion,
    prec: &str,
    methods: &[Method],
) {
    solver_step_benches::<T, N, B>(c, ("step", SolverKind::Auto), prec, methods);
}

/// [`step_benches`] with the solver `kind`, in the group `name/method/prec/N`.
fn solver_step_benches<T: Real, const N: usize, const B: usize>(
    c: &mut Criterion,
    (name, kind): (&str, SolverKind),
    prec: &str,
    methods: &[Method],
) {
    let (p, r) = chain_geometry(N);
    let mut init = ParticleSet::<T, N>::new();
    for (x, a) in p.iter().zip(&r) {
        let part = Particle::new(T::v3_from(*x), T::from_f64(*a), T::from_f64(4.5));
        init.push(part).unwrap();
    }
    init.validate(false).unwrap();
    let bonds = BondSet::<T, B>::chain(&init.pos).unwrap();
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(N, B));
    let mut ws = ws_store.workspace();
    for &method in methods {
        let mut params = Params::new(T::from_f64(0.01));
        params.method = method;
        params.solver.kind = kind;
        // The run must succeed; check once outside the timing.
        let mut probe = init.clone();
        step(&mut probe, &bonds, &params, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("{method:?} N = {N}: {e}"));
        let mut g = c.benchmark_group(format!("{name}/{method:?}/{prec}"));
        g.bench_function(BenchmarkId::from_parameter(N), |b| {
            b.iter_batched_ref(
                || init.clone(),
                |ps| step(ps, &bonds, &params, &mut ws, &mut NoForce).unwrap(),
                BatchSize::LargeInput,
            )
        });
        g.finish();
    }
}

pub(crate) fn all_steps<T: Real>(c: &mut Criterion, prec: &str) {
    let overdamped = [Method::Overdamped, Method::Overdamped2, Method::Springs];
    step_benches::<T, 8, 7>(c, prec, &METHODS);
    step_benches::<T, 16, 15>(c, prec, &METHODS);
    step_benches::<T, 25, 24>(c, prec, &METHODS);
    step_benches::<T, 64, 63>(c, prec, &METHODS);
    step_benches::<T, 128, 127>(c, prec, &METHODS);
    step_benches::<T, 256, 255>(c, prec, &METHODS);
    step_benches::<T, 512, 511>(c, prec, &overdamped);
    // The paper's sweep on bonds alone (no contacts: never over-relaxed, the firmware's
    // solver): its cost is unchanged by the contact sweep's over-relaxation.
    let sweep = ("step_sweep", SolverKind::Sweep);
    let bonded = [Method::Overdamped, Method::Rattle];
    solver_step_benches::<T, 25, 24>(c, sweep, prec, &bonded);
    solver_step_benches::<T, 64, 63>(c, sweep, prec, &bonded);
}
