//! A STREAM-like probe of the machine and the product-path model
//! (docs/BENCHMARKS.md, "Product paths").
//!
//! `cargo run --release -p hydrorattle-parallel --example bandwidth -- [N] [THREADS] [CORES] [SAT]`
//! (defaults 4096, 2, 16, 0).
//!
//! 1. Memory bandwidth: a read-only sum (what a product does to its stored blocks) and
//!    a triad `a = b + s c` over 256 MB arrays, on 1 ... THREADS threads, best of five.
//! 2. Each product path at N beads on 1 and THREADS threads, best of five: the stored
//!    `f64` blocks (symmetric, 48 bytes and 36 flops a pair), the compact `f32` copy (24
//!    bytes, 36 `f32` flops) and the recompute path (no bytes, 63 + 36 flops): ns per
//!    pair and the bytes per second each stream drew; the assembly pass (the stored
//!    blocks written, 48 bytes a pair, and applied once); and for comparison the
//!    product from general blocks (72 bytes a pair: a wall's; the same bits). `BOX=L`:
//!    the stored blocks and the compact copy packed from them are those of a cubic
//!    periodic box of edge `L` (the Ewald mobility, also six scalars a pair; its
//!    assembly takes about 10 us a pair on one thread); the other rows stay free space.
//! 3. The plain step on one thread, round by round (`examples/stages.rs`): its
//!    constraint products `k` and its serial rest, and the model's step beside it.
//! 4. The model (`hydrorattle_parallel::model`): a pass's time per pair on `t` threads
//!    is the larger of its bytes over the bandwidth of `t` threads and its one-thread
//!    compute time over `t` (the one-thread times by CPU time, which a shared machine's
//!    queue does not inflate); the assembly moves twice what it writes
//!    (write-allocate); the serial rest does not shrink. The bandwidth of `t` threads is
//!    `min(t b1, B)` (`b1` one thread's read rate measured, `B` the machine's: measured
//!    here; for a machine of CORES cores `SAT b1`, or when SAT is 0 fitted to the
//!    issue's 16-core measurement of the stored path). The predicted speedup of the
//!    Overdamped step on each path on THREADS and CORES threads.

use std::time::Instant;

mod common;

use hydrorattle::glam::DVec3;
use hydrorattle::linalg::Sym;
use hydrorattle::mobility::periodic::{self, Ewald, Periodic};
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Parallel, Serial, band_scratch};
use hydrorattle::{Hydro, Real};
use hydrorattle_parallel::Threads;
use hydrorattle_parallel::model::{Machine, Path};

/// Doubles per probe array (256 MB: far beyond any last-level cache here).
const LEN: usize = 32 << 20;

/// Best of `k` runs of `f`, in seconds.
fn best(k: usize, f: impl FnMut()) -> f64 {
    best_both(k, f)[0]
}

/// Best of `k` runs of `f`, in seconds of the wall clock and of the process's CPU
/// time (each the best of its own).
fn best_both(k: usize, mut f: impl FnMut()) -> [f64; 2] {
    (0..k).fold([f64::INFINITY; 2], |b, _| {
        let (t0, c0) = (Instant::now(), common::cpu_ns());
        f();
        let cpu = (common::cpu_ns() - c0) as f64 * 1e-9;
        [b[0].min(t0.elapsed().as_secs_f64()), b[1].min(cpu)]
    })
}

/// Read and triad bandwidth (GB/s) on `pool`, in 64 chunks handed out as jobs.
fn stream(pool: &Threads, a: &mut [f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let chunk = LEN / 64;
    let mut sums = vec![0.0; LEN.div_ceil(chunk)];
    let read = best(5, || {
        // Eight running sums a chunk: the adds' latency must not be what is measured.
        let sum = |x: &[f64]| {
            let lanes = x.chunks_exact(8).fold([0.0; 8], |mut s, v| {
                for (s, &v) in s.iter_mut().zip(v) {
                    *s += v;
                }
                s
            });
            lanes.iter().sum::<f64>()
        };
        let mut jobs: Vec<_> = sums
            .iter_mut()
            .zip(b.chunks(chunk))
            .map(|(s, x)| move || *s = sum(x))
            .collect();
        pool.run(&mut jobs_of(&mut jobs));
        std::hint::black_box(sums.iter().sum::<f64>());
    });
    let triad = best(5, || {
        let mut jobs: Vec<_> = a
            .chunks_mut(chunk)
            .zip(b.chunks(chunk).zip(c.chunks(chunk)))
            .map(|(a, (b, c))| {
                move || {
                    for ((a, &b), &c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + 3.0 * c;
                    }
                }
            })
            .collect();
        pool.run(&mut jobs_of(&mut jobs));
    });
    (
        8.0 * LEN as f64 / read / 1e9,
        24.0 * LEN as f64 / triad / 1e9,
    )
}

/// `jobs` as the [`Parallel`] interface takes them.
fn jobs_of<F: FnMut() + Send>(jobs: &mut [F]) -> Vec<&mut (dyn FnMut() + Send)> {
    jobs.iter_mut()
        .map(|j| j as &mut (dyn FnMut() + Send))
        .collect()
}

/// Seconds per product of each path (stored, compact, recompute), of the assembly
/// pass (stored blocks and a first product, `parallel::assemble_apply`) and of the
/// product from general blocks at `n` beads on `par`, by the wall clock and by CPU time.
fn paths(n: usize, par: &dyn Parallel) -> [[f64; 2]; 5] {
    let pos = common::helix(n);
    let radius = vec![1.0; n];
    let x: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).sin(), 0.5, 1.0))
        .collect();
    let (mut y, mut z) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; band_scratch(n)]);
    let mut mu: Vec<Sym<f64>> = vec![[0.0; 6]; n * (n + 1) / 2];
    match std::env::var("BOX")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
    {
        // The box's Ewald blocks (symmetric too: the same six scalars a pair).
        Some(l) => {
            let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.0).unwrap();
            let t0 = Instant::now();
            periodic::assemble(par, &ew, 1.0, &pos, &radius, &mut mu).unwrap();
            eprintln!(
                "  ({} threads: stored and compact from the box of edge {l}, Ewald assembly \
                 {:.0} ns/pair)",
                par.threads(),
                t0.elapsed().as_secs_f64() / (n * (n + 1) / 2) as f64 * 1e9
            );
        }
        None => parallel::assemble::<f64>(par, Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap(),
    }
    let general = {
        let mut mu9 = vec![f64::M3_ZERO; n * (n + 1) / 2];
        parallel::assemble::<f64>(par, Hydro::Rpy, 1.0, &pos, &radius, &mut mu9).unwrap();
        best_both(5, || {
            parallel::product::<f64>(par, &mu9, n, &x, &mut y, &mut z)
        })
    };
    let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
    reduced::copy_apply::<f64>(par, &mu, n, &mut copy, &x, &mut y, &mut z);
    let packed = best(3, || {
        reduced::copy_apply::<f64>(par, &mu, n, &mut copy, &x, &mut y, &mut z)
    });
    let stored = best_both(5, || {
        parallel::product::<f64>(par, &mu, n, &x, &mut y, &mut z)
    });
    let compact = best_both(5, || {
        reduced::apply::<f64>(par, &copy, n, &x, &mut y, &mut z)
    });
    let free = best_both(3, || {
        parallel::free_product::<f64>(par, Hydro::Rpy, 1.0, &pos, &radius, &x, &mut y, &mut z)
            .unwrap()
    });
    let (f, rad) = (&x[..], &radius[..]);
    let assembly = best_both(3, || {
        parallel::assemble_apply::<f64>(par, Hydro::Rpy, 1.0, &pos, rad, &mut mu, f, &mut y, &mut z)
            .unwrap()
    });
    eprintln!(
        "  ({} threads: packing the copy while applying it {:.2} ns/pair)",
        par.threads(),
        packed / (n * (n + 1) / 2) as f64 * 1e9
    );
    [stored, compact, free, assembly, general]
}

fn main() {
    let arg = |k: usize, d: f64| {
        std::env::args()
            .nth(k)
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let (n, threads, cores, target_sat) = (
        arg(1, 4096.0) as usize,
        arg(2, 2.0) as usize,
        arg(3, 16.0),
        arg(4, 0.0),
    );
    let pools: Vec<Threads> = (1..=threads).map(|t| Threads::new(t).unwrap()).collect();
    let (mut a, b, c) = (vec![0.0; LEN], vec![1.0; LEN], vec![2.0; LEN]);
    let mut bw = Vec::new();
    for pool in &pools {
        let (read, triad) = stream(pool, &mut a, &b, &c);
        println!(
            "stream {} threads: read {read:.1} GB/s, triad {triad:.1} GB/s",
            pool.threads()
        );
        bw.push(read);
    }
    drop((a, b, c));
    let (b1, bmax) = (bw[0], bw.iter().cloned().fold(0.0, f64::max));
    let pairs = (n * (n + 1) / 2) as f64;
    let ns = |s: f64| s / pairs * 1e9;
    let one = paths(n, &Serial);
    let many = paths(n, pools.last().unwrap());
    for (k, path) in Path::ALL.into_iter().enumerate() {
        let (ns1, nst) = (ns(one[k][0]), ns(many[k][0]));
        println!(
            "N = {n} {path:?}: 1 thread {ns1:.2} ns/pair {:.1} GB/s ({:.2} ns CPU); \
             {threads} threads {nst:.2} ns/pair {:.1} GB/s ({:.2}x)",
            path.bytes() / ns1,
            ns(one[k][1]),
            path.bytes() / nst,
            ns1 / nst
        );
    }
    let (a1, at) = (ns(one[3][0]), ns(many[3][0]));
    println!(
        "N = {n} assembly pass (stored, fused first product): 1 thread {a1:.2} ns/pair \
         ({:.2} ns CPU, writes {:.1} GB/s); {threads} threads {at:.2} ns/pair, writes {:.1} GB/s \
         ({:.2}x)",
        ns(one[3][1]),
        Path::Stored.written() / a1,
        Path::Stored.written() / at,
        a1 / at
    );
    let (g1, gt) = (ns(one[4][0]), ns(many[4][0]));
    println!(
        "N = {n} general blocks (a wall's, 72 bytes a pair): 1 thread {g1:.2} ns/pair {:.1} GB/s          ({:.2} ns CPU); {threads} threads {gt:.2} ns/pair {:.1} GB/s ({:.2}x)",
        72.0 / g1,
        ns(one[4][1]),
        72.0 / gt,
        g1 / gt
    );
    // The step on one thread, round by round (`examples/stages.rs`): its products `k`
    // and its serial rest, for the model; and the model checked against it.
    let (steps, _, report) = common::timed::run(n, 2, "plain", &Serial);
    let step = steps[1..].iter().min_by_key(|s| s.cpu).unwrap();
    let in_rounds: u64 = step.rounds.iter().map(|r| r.cpu).sum();
    let k = report.iterations as f64;
    let serial = ns(step.cpu.saturating_sub(in_rounds) as f64 * 1e-9);
    // One-thread inputs by CPU time (which a shared machine's queue does not inflate).
    let here = Machine {
        b1,
        b: bmax,
        ns: [0, 1, 2, 4].map(|q| ns(one[q][1])),
        assembly: ns(one[3][1]),
        serial,
    };
    let products: Vec<f64> = step.rounds[1..]
        .iter()
        .filter(|r| r.cpu * 3 > step.rounds[1].cpu)
        .map(|r| ns(r.cpu as f64 * 1e-9))
        .collect();
    println!(
        "step, 1 thread (CPU ns a pair): measured {:.2} = assembly {:.2} + {} products of {:.2} \
         (mean) + serial {serial:.2}; MODEL {:.2} = {:.2} + {k} x {:.2} + {serial:.2}",
        ns(step.cpu as f64 * 1e-9),
        ns(step.rounds[0].cpu as f64 * 1e-9),
        products.len(),
        products.iter().sum::<f64>() / products.len().max(1) as f64,
        here.step(Path::Stored, 1.0, k),
        here.assembly(Path::Stored, 1.0),
        here.product(Path::Stored, 1.0)
    );
    let speedup = |m: &Machine, path: Path, t: f64| m.step(path, 1.0, k) / m.step(path, t, k);
    println!(
        "model: a thread's share of the step, stored path: assembly {:.0} %, products {:.0} %, \
         serial {:.1} %",
        100.0 * here.assembly(Path::Stored, 1.0) / here.step(Path::Stored, 1.0, k),
        100.0 * k * here.product(Path::Stored, 1.0) / here.step(Path::Stored, 1.0, k),
        100.0 * serial / here.step(Path::Stored, 1.0, k)
    );
    // The model machine's bandwidth in units of one thread's (`SAT`), or else fitted to
    // the 16-core Xeon: stored f64 at N = 4096, 4.87x on 16 threads, measured
    // when the stored path read general blocks (72 bytes a pair).
    let with = |sat: f64| Machine {
        b: sat * b1,
        ..here
    };
    let sat = match target_sat {
        s if s > 0.0 => s,
        _ => (10..=400)
            .map(|s| s as f64 / 10.0)
            .min_by(|&a, &b| {
                let miss = |s: f64| (speedup(&with(s), Path::General, 16.0) - 4.87).abs();
                miss(a).total_cmp(&miss(b))
            })
            .unwrap_or(1.0),
    };
    let big = with(sat);
    println!(
        "model: b1 = {b1:.1} GB/s a thread, B = {bmax:.1} GB/s here ({:.2} b1); the {cores}-core \
         machine B = {sat:.1} b1 (general f64 blocks there: 8 threads {:.2}x, 16 threads \
         {:.2}x; the issue measured 4.57x and 4.87x)",
        bmax / b1,
        speedup(&big, Path::General, 8.0),
        speedup(&big, Path::General, 16.0)
    );
    for (label, t, m) in [
        ("MODEL of this machine", threads as f64, here),
        ("MODEL of the bigger machine", cores, big),
    ] {
        for path in Path::ALL.into_iter().chain([Path::General]) {
            println!(
                "  {label}, {t} threads, {path:?}: step {:.1} ns/pair, speedup {:.2}x over its 1 thread, \
                 {:.2}x over 1 thread Stored",
                m.step(path, t, k),
                speedup(&m, path, t),
                m.step(Path::Stored, 1.0, k) / m.step(path, t, k)
            );
        }
        println!("  {label}, {t} threads: fastest {:?}", m.fastest(t, k));
    }
}
