//! Kernel benchmarks (criterion): the stage functions on `Vec`-backed slices, and one
//! `step()` of every method on a settling chain.
//!
//! * `assemble_tt`, `assemble_grand`, `cholesky` (of `mu_tt`), `cholesky_solve` and
//!   `sym_matvec` at N = 8, 25, 100, 256 in f64 and f32;
//! * `step()` per `Method` at N = 8, 16, 25, 64, 128, 256 (and 512 for the overdamped
//!   methods and springs) in f64 and f32.
//!
//! The workspace for N = 512 is ~150 MB (f64), so criterion runs on a thread with a
//! 2 GiB stack and each size's workspace lives in that thread's stack frame.
//!
//! Run: `cargo bench --bench kernel` (add `-- --quick` for a faster pass, or a filter
//! such as `-- step/Rattle`). Results land in `target/criterion/`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, BenchmarkId, Criterion};
use hydrorattle::linalg::{cholesky, cholesky_solve, sym_matvec};
use hydrorattle::mobility::{Hydro, assemble_grand, assemble_tt};
use hydrorattle::{BondSet, Method, NoForce, Params, Particle, ParticleSet, Real, step};

/// Stage sizes.
const STAGE_SIZES: [usize; 4] = [8, 25, 100, 256];

/// Centres and radii of an `n`-bead chain: a head of radius 2^(1/3), then tails of
/// radius 1, bonds 1.5 (a_i + a_j), along a gently winding climbing path (no overlaps).
fn chain_geometry(n: usize) -> (Vec<[f64; 3]>, Vec<f64>) {
    let mut pos = Vec::with_capacity(n);
    let mut rad = Vec::with_capacity(n);
    let mut at = [0.0f64; 3];
    let mut prev = 0.0;
    for k in 0..n {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if k > 0 {
            let t = 0.6 * k as f64;
            let dir = [t.cos(), t.sin(), 0.8];
            let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            for c in 0..3 {
                at[c] += dir[c] / len * 1.5 * (a + prev);
            }
        }
        pos.push(at);
        rad.push(a);
        prev = a;
    }
    (pos, rad)
}

fn stage_benches<T: Real>(c: &mut Criterion, prec: &str) {
    let data: Vec<(usize, Vec<T::V3>, Vec<T>)> = STAGE_SIZES
        .iter()
        .map(|&n| {
            let (p, r) = chain_geometry(n);
            (
                n,
                p.iter().map(|&x| T::v3_from(x)).collect(),
                r.iter().map(|&a| T::from_f64(a)).collect(),
            )
        })
        .collect();
    let eta = T::ONE;

    let mut g = c.benchmark_group(format!("assemble_tt/{prec}"));
    for (n, pos, rad) in &data {
        let mut out = vec![T::M3_ZERO; n * n];
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| assemble_tt(Hydro::Rpy, eta, black_box(pos), rad, &mut out).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("assemble_grand/{prec}"));
    for (n, pos, rad) in &data {
        let mut out = vec![T::M3_ZERO; 4 * n * n];
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| assemble_grand(Hydro::Rpy, eta, black_box(pos), rad, &mut out).unwrap())
        });
    }
    g.finish();

    // The factorisation overwrites its input: each iteration gets a fresh copy
    // (made outside the timed region).
    let mut g = c.benchmark_group(format!("cholesky_tt/{prec}"));
    for (n, pos, rad) in &data {
        let n = *n;
        let mut mu = vec![T::M3_ZERO; n * n];
        assemble_tt(Hydro::Rpy, eta, pos, rad, &mut mu).unwrap();
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter_batched_ref(
                || mu.clone(),
                |m| cholesky::<T>(black_box(m), n).unwrap(),
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("cholesky_solve_tt/{prec}"));
    for (n, pos, rad) in &data {
        let n = *n;
        let mut fac = vec![T::M3_ZERO; n * n];
        assemble_tt(Hydro::Rpy, eta, pos, rad, &mut fac).unwrap();
        cholesky::<T>(&mut fac, n).unwrap();
        let rhs = vec![T::v3(T::ZERO, T::ZERO, -T::ONE); n];
        let mut x = rhs.clone();
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                x.copy_from_slice(&rhs);
                cholesky_solve::<T>(black_box(&fac), n, &mut x);
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("sym_matvec_tt/{prec}"));
    for (n, pos, rad) in &data {
        let n = *n;
        let mut mu = vec![T::M3_ZERO; n * n];
        assemble_tt(Hydro::Rpy, eta, pos, rad, &mut mu).unwrap();
        let f = vec![T::v3(T::ZERO, T::ZERO, -T::ONE); n];
        let mut u = vec![T::V3_ZERO; n];
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| sym_matvec::<T>(black_box(&mu), n, &f, &mut u))
        });
    }
    g.finish();
}

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
    let (p, r) = chain_geometry(N);
    let mut init = ParticleSet::<T, N>::new();
    for (x, a) in p.iter().zip(&r) {
        let part = Particle::new(T::v3_from(*x), T::from_f64(*a), T::from_f64(4.5));
        init.push(part).unwrap();
    }
    init.validate(false).unwrap();
    let bonds = BondSet::<T, B>::chain(&init.pos).unwrap();
    let mut ws_store = hydrorattle::workspace::Buffers::<T>::new(hydrorattle::Layout::all(N, B));
    let mut ws = ws_store.workspace();
    for &method in methods {
        let mut params = Params::new(T::from_f64(0.01));
        params.method = method;
        // The run must succeed; check once outside the timing.
        let mut probe = init.clone();
        step(&mut probe, &bonds, &params, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("{method:?} N = {N}: {e}"));
        let mut g = c.benchmark_group(format!("step/{method:?}/{prec}"));
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

fn all_steps<T: Real>(c: &mut Criterion, prec: &str) {
    let overdamped = [Method::Overdamped, Method::Overdamped2, Method::Springs];
    step_benches::<T, 8, 7>(c, prec, &METHODS);
    step_benches::<T, 16, 15>(c, prec, &METHODS);
    step_benches::<T, 25, 24>(c, prec, &METHODS);
    step_benches::<T, 64, 63>(c, prec, &METHODS);
    step_benches::<T, 128, 127>(c, prec, &METHODS);
    step_benches::<T, 256, 255>(c, prec, &METHODS);
    step_benches::<T, 512, 511>(c, prec, &overdamped);
}

fn run() {
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500))
        .nresamples(10_000)
        .configure_from_args();
    stage_benches::<f64>(&mut c, "f64");
    stage_benches::<f32>(&mut c, "f32");
    all_steps::<f64>(&mut c, "f64");
    all_steps::<f32>(&mut c, "f32");
    c.final_summary();
}

fn main() {
    std::thread::Builder::new()
        .name("kernel-bench".into())
        .stack_size(2 << 30)
        .spawn(run)
        .expect("spawn the benchmark thread")
        .join()
        .expect("benchmark thread panicked");
}
