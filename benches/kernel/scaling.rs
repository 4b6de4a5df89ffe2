//! `step_slices` on runtime-sized chains: `scaling/...`, `noise_sqrt/...`,
//! `brownian/...` and `solver/...`, f64, iteration counts printed next to the times.

use criterion::{BatchSize, BenchmarkId, Criterion};
use hydrorattle::{
    Bond, Brownian, Layout, Method, NoForce, Noise, NoiseSqrt, Params, Real, SolverKind, State,
    step_slices,
};
use hydrorattle_heap::Buffers;

use crate::shared::chain_geometry;

/// `step_slices` on runtime-sized state (no compile-time capacity), f64: the scaling
/// targets. `group/label/N`. Prints the constraint iterations per step
/// (operator products for Krylov) next to the times: counts, not only seconds.
pub(crate) fn scaling_bench(
    c: &mut Criterion,
    group: &str,
    label: &str,
    sizes: &[usize],
    setup: impl Fn(&mut Params<f64>),
) {
    let mut g = c.benchmark_group(format!("{group}/{label}"));
    for &n in sizes {
        let (p, r) = chain_geometry(n);
        let pos0: Vec<glam::DVec3> = p.iter().map(|&x| f64::v3_from(x)).collect();
        let bonds: Vec<Bond<f64>> = (1..n)
            .map(|i| Bond {
                i: i - 1,
                j: i,
                length: (pos0[i] - pos0[i - 1]).length(),
            })
            .collect();
        let density = vec![4.5; n];
        let mut params = Params::new(0.01);
        setup(&mut params);
        let mut store = Buffers::<f64>::new(Layout::for_params(&params, n, bonds.len()));
        let mut ws = store.workspace();
        let zero = vec![glam::DVec3::ZERO; n];
        let go = |pos: &mut Vec<glam::DVec3>, ws: &mut hydrorattle::Workspace<'_, f64>| {
            let (mut vel, mut omega, mut time) = (zero.clone(), zero.clone(), 0.0);
            let mut noise = Noise::new(1);
            let state = State {
                pos,
                vel: &mut vel,
                omega: &mut omega,
                radius: &r,
                density: &density,
                time: &mut time,
                noise: params.brownian.map(|_| &mut noise),
            };
            step_slices(state, &bonds, &params, ws, &mut NoForce).unwrap()
        };
        let r = go(&mut pos0.clone(), &mut ws);
        let (its, lz, mid) = (r.iterations, r.noise_iterations, r.velocity_iterations);
        eprintln!(
            "{group}/{label}/{n}: {its} constraint iterations, {lz} Lanczos iterations, {mid} midpoint projection iterations per step"
        );
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter_batched_ref(
                || pos0.clone(),
                |pos| go(pos, &mut ws),
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

pub(crate) fn scaling(c: &mut Criterion) {
    let big = [64, 128, 256, 512, 1024, 2048];
    scaling_bench(c, "scaling", "Overdamped", &big, |_| {});
    scaling_bench(c, "scaling", "Overdamped-matrix-free", &big[..5], |p| {
        p.matrix_free = true
    });
    scaling_bench(c, "scaling", "RattleStable", &big[..4], |p| {
        p.method = Method::RattleStable
    });
    // The thermal step's square root of the mobility: Cholesky against Lanczos (the
    // `NoiseSqrt::Auto` crossover), kT = 1, midpoint drift.
    for (label, sqrt) in [
        ("Cholesky", NoiseSqrt::Cholesky),
        ("Lanczos", NoiseSqrt::Lanczos),
    ] {
        scaling_bench(
            c,
            "noise_sqrt",
            label,
            &[64, 96, 128, 256, 512, 1024],
            |p| {
                p.brownian = Some(Brownian::new(1.0));
                p.noise_sqrt = sqrt;
            },
        );
    }
    // The Brownian Overdamped step (kT = 1, midpoint, Lanczos) against
    // the deterministic one on the same chain, N = 256 ... 2048, in one run: the ratio
    // at N = 1024 (target <= 3) and the thermal step's cost exponent (target <= 2.2).
    // The two are taken in turn at each N, so that a change in the load of a shared
    // machine falls on both sides of a ratio rather than on one.
    for n in [256, 512, 1024, 2048] {
        scaling_bench(c, "brownian", "Deterministic", &[n], |_| {});
        scaling_bench(c, "brownian", "Lanczos", &[n], |p| {
            p.brownian = Some(Brownian::new(1.0));
            p.noise_sqrt = NoiseSqrt::Lanczos;
        });
    }
    let small = [16, 24, 32, 48, 64];
    for (label, kind) in [
        ("Newton", SolverKind::Newton),
        ("Krylov", SolverKind::Krylov),
    ] {
        scaling_bench(c, "solver/Overdamped", label, &small, |p| {
            p.solver.kind = kind
        });
        scaling_bench(c, "solver/RattleStable", label, &small, |p| {
            p.method = Method::RattleStable;
            p.solver.kind = kind;
        });
    }
}
