//! Kernel benchmarks (criterion): the stage functions on `Vec`-backed slices, and one
//! `step()` of every method on a settling chain.
//!
//! * `assemble_tt`, `assemble_grand`, `cholesky` (of `mu_tt`), `cholesky_solve` and
//!   `sym_matvec` at N = 8, 25, 100, 256 in f64 and f32;
//! * `step()` per `Method` at N = 8, 16, 25, 64, 128, 256 (and 512 for the overdamped
//!   methods and springs) in f64 and f32;
//! * `scaling/...`: `step_slices` on runtime-sized chains up to N = 2048 (Overdamped
//!   stored and matrix-free, RattleStable), and `solver/...`: dense Newton against
//!   Krylov at N = 16 ... 64 (the `Auto` switch), f64, with iteration counts printed;
//! * `noise_sqrt/{Cholesky,Lanczos}/N`: the thermal overdamped step (kT = 1, midpoint)
//!   with each square root of the mobility at N = 64 ... 1024, Lanczos iterations
//!   printed (the `NoiseSqrt::Auto` crossover);
//! * `brownian/{Deterministic,Lanczos}/N`: the Brownian Overdamped step (kT = 1,
//!   midpoint, Lanczos) and the deterministic one at N = 256 ... 2048 (their
//!   ratio at 1024 and cost exponent), iteration counts printed;
//! * `products/{stored_f64,compact_f32,recompute}/N`: one product `mu_tt x` by each
//!   path at N = 1024, 4096, 8192, one thread, bytes streamed as the throughput;
//! * `contacts/...`: one overdamped step (first and second order) of a folded 25-bead
//!   chain with and without hard contacts, f64, with contact and round counts printed.
//!
//! Particle sets up to N = 512 are built on the stack, so criterion runs on a thread
//! with a large stack; workspaces are on the heap, sized per method.
//!
//! Run: `cargo bench --bench kernel` (add `-- --quick` for a faster pass, or a filter
//! such as `-- step/Rattle`). Results land in `target/criterion/`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, BenchmarkId, Criterion};
use hydrorattle::linalg::{cholesky, cholesky_solve, sym_matvec};
use hydrorattle::mobility::{Hydro, assemble_grand, assemble_tt};
use hydrorattle::{
    Bond, BondSet, Brownian, Layout, Method, NoForce, Noise, NoiseSqrt, Params, Particle,
    ParticleSet, Real, SolverKind, State, step, step_slices,
};
use hydrorattle_heap::Buffers;

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

fn all_steps<T: Real>(c: &mut Criterion, prec: &str) {
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

/// `step_slices` on runtime-sized state (no compile-time capacity), f64: the scaling
/// targets. `group/label/N`. Prints the constraint iterations per step
/// (operator products for Krylov) next to the times: counts, not only seconds.
fn scaling_bench(
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

fn scaling(c: &mut Criterion) {
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

/// A Figure 1 (b)-like helix: head of radius 2^(1/3) then 24 unit tails, bonds
/// 1.05 (a_i + a_j), helix radius 3, rise 0.5 per bead.
fn short_helix() -> Vec<([f64; 3], f64)> {
    let mut out: Vec<([f64; 3], f64)> = Vec::new();
    let mut phi = 0.0f64;
    for k in 0..25 {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if let Some(&(_, prev)) = out.last() {
            let d = 1.05 * (prev + a);
            phi += 2.0 * ((d * d - 0.25f64).sqrt() / 6.0).asin();
        }
        out.push(([3.0 * phi.cos(), 3.0 * phi.sin(), 0.5 * k as f64], a));
    }
    out
}

/// One step on the 25-bead helix of [`short_helix`] after 1000 steps of dt = 0.1 with
/// hard contacts (t = 100: folded, beads touching), f64: the first- and second-order
/// overdamped steps with and without contacts (`contacts/...`). Prints the contacts
/// held, the active-set rounds and the Newton iterations of the timed step: counts next
/// to times.
fn contact_benches(c: &mut Criterion) {
    const N: usize = 25;
    let mut ps = ParticleSet::<f64, N>::new();
    for (x, a) in short_helix() {
        ps.push(Particle::new(f64::v3_from(x), a, 4.5)).unwrap();
    }
    let bonds = BondSet::<f64, 24>::chain(&ps.pos).unwrap();
    let with = |method, contacts: bool| {
        let mut q = Params::<f64>::new(0.1);
        q.method = method;
        q.solver.kind = SolverKind::Newton;
        q.contacts = contacts.then(|| hydrorattle::Contacts::new(3 * N));
        // Without contacts spheres may overlap (else the step is refused).
        q.allow_overlap = !contacts;
        q
    };
    let settle = with(Method::Overdamped2, true);
    let mut store = Buffers::<f64>::new(Layout::for_params(&settle, N, 24));
    let (mut held, mut most, mut rounds) = (0u64, 0, 0u64);
    for _ in 0..1000 {
        let r = step(
            &mut ps,
            &bonds,
            &settle,
            &mut store.workspace(),
            &mut NoForce,
        )
        .unwrap();
        held += u64::from(r.contacts);
        most = most.max(r.contacts);
        rounds += u64::from(r.contact_rounds);
    }
    eprintln!(
        "contacts: settling 1000 steps: {:.2} contacts held per step (at most {most}), {:.2} active-set rounds per final projection",
        held as f64 / 1000.0,
        rounds as f64 / 1000.0
    );
    for (label, method, contacts) in [
        ("overdamped", Method::Overdamped, false),
        ("overdamped+contacts", Method::Overdamped, true),
        ("overdamped2", Method::Overdamped2, false),
        ("overdamped2+contacts", Method::Overdamped2, true),
    ] {
        let q = with(method, contacts);
        let mut store = Buffers::<f64>::new(Layout::for_params(&q, N, 24));
        let rep = step(
            &mut ps.clone(),
            &bonds,
            &q,
            &mut store.workspace(),
            &mut NoForce,
        );
        match rep {
            Ok(r) => eprintln!(
                "contacts/{label}: {} contacts held, {} active-set rounds, {} Newton iterations",
                r.contacts, r.contact_rounds, r.iterations
            ),
            Err(e) => {
                eprintln!("contacts/{label}: refused ({e}); not timed");
                continue;
            }
        }
        let mut g = c.benchmark_group(format!("contacts/{label}"));
        g.bench_function(BenchmarkId::from_parameter(N), |b| {
            b.iter_batched_ref(
                || ps.clone(),
                |s| {
                    let _ = black_box(step(s, &bonds, &q, &mut store.workspace(), &mut NoForce));
                },
                BatchSize::LargeInput,
            )
        });
        g.finish();
    }
}

/// Sizes of the product-path benches.
const PATH_SIZES: [usize; 3] = [1024, 4096, 8192];

/// One product `y = mu_tt x` by each path on one thread (`products/{stored_f64,
/// compact_f32,recompute}/N`): the stored `f64` blocks (symmetric: 48 bytes a pair), the compact
/// `f32` copy (24 bytes) and the recompute path (pairs evaluated, nothing read).
/// Criterion reports the bytes a product streams as its throughput (the recompute
/// path's as pairs); ns per pair is the time over `N (N + 1) / 2`.
fn product_paths(c: &mut Criterion) {
    use criterion::Throughput;
    use hydrorattle::noise::reduced;
    use hydrorattle::parallel::{self, Serial, band_scratch};
    for &n in &PATH_SIZES {
        let (p, rad) = chain_geometry(n);
        let pos: Vec<glam::DVec3> = p.iter().map(|&x| f64::v3_from(x)).collect();
        let x: Vec<glam::DVec3> = (0..n)
            .map(|i| glam::DVec3::new((i as f64).sin(), 0.5, 1.0))
            .collect();
        let (mut y, mut z) = (
            vec![glam::DVec3::ZERO; n],
            vec![glam::DVec3::ZERO; band_scratch(n)],
        );
        let pairs = (n * (n + 1) / 2) as u64;
        let mut mu: Vec<hydrorattle::linalg::Sym<f64>> = vec![[0.0; 6]; n * (n + 1) / 2];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &rad, &mut mu).unwrap();
        let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
        reduced::copy_apply::<f64>(&Serial, &mu, n, &mut copy, &x, &mut y, &mut z);
        let mut g = c.benchmark_group("products/stored_f64");
        g.throughput(Throughput::Bytes(48 * pairs));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| parallel::product::<f64>(&Serial, black_box(&mu), n, &x, &mut y, &mut z))
        });
        g.finish();
        drop(mu);
        let mut g = c.benchmark_group("products/compact_f32");
        g.throughput(Throughput::Bytes(24 * pairs));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| reduced::apply::<f64>(&Serial, black_box(&copy), n, &x, &mut y, &mut z))
        });
        g.finish();
        drop(copy);
        let mut g = c.benchmark_group("products/recompute");
        g.throughput(Throughput::Elements(pairs));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                parallel::free_product::<f64>(
                    &Serial,
                    Hydro::Rpy,
                    1.0,
                    black_box(&pos),
                    &rad,
                    &x,
                    &mut y,
                    &mut z,
                )
                .unwrap()
            })
        });
        g.finish();
    }
}

fn run() {
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500))
        .nresamples(10_000)
        .configure_from_args();
    product_paths(&mut c);
    scaling(&mut c);
    contact_benches(&mut c);
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
