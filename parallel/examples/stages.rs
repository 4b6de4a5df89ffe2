//! Where a step's time goes: the rounds of band jobs the kernel hands to its
//! [`Parallel`] (assembly, products, acceptance), timed one by one, and the rest of the
//! step (the kernel's serial work: preconditioner, Krylov and Lanczos vector work,
//! forces, copies) as the difference (docs/BENCHMARKS.md, "Serial parts").
//!
//! `cargo run --release -p hydrorattle-parallel --example stages -- [N] [STEPS] [THREADS] [MODE]`
//! (defaults 4096, 3, 1, `plain`; MODE as in `examples/speedup.rs`: `plain`, `compact`,
//! `free`, `brownian`, `brownian-compact`).
//!
//! Every round is timed by the wall clock and by the CPU time the process's threads ran
//! (`/proc/self/task/*/schedstat`; a thread waiting for a core on a shared machine adds
//! wall time, not CPU time; a pool thread spinning for the next round adds CPU time).
//! Per step: the rounds' latency (wall time beyond the busiest thread's jobs, summed)
//! and, outside the rounds, the stepping thread's own CPU time beside the process's. A round of bands is followed by the round that adds the
//! bands' partial sums (a few microseconds); the two are reported as one. The rounds of
//! the best step (by CPU time) are printed in order with what the step does there, read
//! from the integrator (`src/integrate/overdamped.rs`, `brownian.rs`): the first round
//! of the plain step is the fused assembly and first product, the last one the
//! acceptance's pair check, the others the constraint solve's products.

use hydrorattle::{Parallel, Serial};
use hydrorattle_parallel::Threads;

mod common;

fn main() {
    let arg = common::arg;
    let (n, steps, threads) = (arg(1, 4096), arg(2, 3), arg(3, 1));
    let mode = std::env::args().nth(4).unwrap_or_else(|| "plain".into());
    let pool = Threads::new(threads).unwrap();
    let inner: &dyn Parallel = if threads == 1 { &Serial } else { &pool };
    let (taken, digest, _) = common::timed::run(n, steps, &mode, inner);
    println!("positions after {} steps: digest {digest:016x}", steps + 1);
    let pairs = (n * (n + 1) / 2) as f64;
    let best = taken[1..].iter().min_by_key(|s| s.cpu).unwrap();
    let ms = |ns: u64| ns as f64 * 1e-6;
    let per_pair = |ns: u64| ns as f64 / pairs;
    println!(
        "N = {n} {mode}, {threads} thread(s), best of {steps} steps by CPU time: step {:.2} ms wall, \
         {:.2} ms CPU ({:.2} ns CPU a pair); load {}",
        ms(best.wall),
        ms(best.cpu),
        per_pair(best.cpu),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    let (mut in_wall, mut in_cpu, mut in_busiest, mut in_caller) = (0, 0, 0, 0);
    for (k, r) in best.rounds.iter().enumerate() {
        in_wall += r.wall;
        in_cpu += r.cpu;
        in_busiest += r.busiest;
        in_caller += r.caller;
        println!(
            "  round {k:2} ({:2} jobs): {:8.2} ms wall {:8.2} ms CPU {:6.2} ns CPU a pair, \
             {:5.1} % of the step's CPU; busiest thread {:8.2} ms CPU ({:.2} of the even share)",
            r.jobs,
            ms(r.wall),
            ms(r.cpu),
            per_pair(r.cpu),
            100.0 * r.cpu as f64 / best.cpu as f64,
            ms(r.busiest),
            r.busiest as f64 * threads as f64 / r.cpu.max(1) as f64
        );
    }
    let (out_wall, out_cpu) = (
        best.wall.saturating_sub(in_wall),
        best.cpu.saturating_sub(in_cpu),
    );
    // On idle cores a step takes its serial part plus each round's busiest thread.
    println!(
        "  on idle cores (serial CPU + busiest threads): {:.2} ms",
        ms(out_cpu + in_busiest)
    );
    println!(
        "  outside the rounds (serial): {:.2} ms wall {:.2} ms CPU, {:.1} % of the step's CPU \
         ({:.1} % of its wall); the stepping thread's CPU there {:.2} ms",
        ms(out_wall),
        ms(out_cpu),
        100.0 * out_cpu as f64 / best.cpu as f64,
        100.0 * out_wall as f64 / best.wall as f64,
        ms(best.caller.saturating_sub(in_caller))
    );
    // What the rounds cost beyond their busiest thread's jobs: hand-out, wake-ups,
    // waiting for the last job, and (on a shared machine) waiting for a core.
    println!(
        "  round latency (wall - busiest thread's CPU) summed over the step's {} rounds: {:.2} ms \
         ({:.1} % of the step's wall)",
        best.rounds.len(),
        ms(in_wall.saturating_sub(in_busiest)),
        100.0 * in_wall.saturating_sub(in_busiest) as f64 / best.wall as f64
    );
}
