//! What a round of jobs costs on `Threads` beyond its jobs: the hand-out, the wake-ups
//! and the wait for the last job (docs/BENCHMARKS.md, "The pool").
//!
//! `cargo run --release -p hydrorattle-parallel --example rounds -- [THREADS] [JOBS] [WORK] [GAP] [ROUNDS]`
//! (defaults 2, 16, 20, 50, 200): ROUNDS rounds of JOBS jobs of WORK microseconds of
//! arithmetic each, with GAP microseconds of arithmetic on the calling thread between
//! rounds (the kernel's serial work), the whole repeated 15 times. Printed: the wall time
//! of `run` (least and median over the rounds) over the ideal `ceil(JOBS / THREADS)
//! WORK`, and the process's CPU time a round (best of the 15 batches) over `JOBS WORK`
//! (a pool thread spinning through a gap adds CPU time). On a shared machine the queue
//! for a core inflates the median; the least is the pool's own cost.

use std::time::Instant;

mod common;

use hydrorattle::Parallel;
use hydrorattle_parallel::Threads;

/// Busy arithmetic for about `us` microseconds (`per_us` iterations each).
fn work(us: f64, per_us: f64) -> f64 {
    let mut x = 1.0f64;
    for _ in 0..(us * per_us) as u64 {
        x = std::hint::black_box(x * 1.000_000_1 + 1e-9);
    }
    x
}

fn main() {
    let arg = common::arg;
    let (threads, jobs, work_us, gap_us, rounds) =
        (arg(1, 2), arg(2, 16), arg(3, 20), arg(4, 50), arg(5, 200));
    // Iterations a microsecond, by CPU time (not inflated by a queue for the core).
    let per_us = {
        let c0 = common::timed::thread_ns();
        work(20_000.0, 100.0);
        2e6 / ((common::timed::thread_ns() - c0) as f64 * 1e-3)
    };
    let pool = Threads::new(threads).unwrap();
    let (mut walls, mut best_cpu) = (Vec::new(), f64::INFINITY);
    let caller = std::thread::current().id();
    let elsewhere = std::sync::atomic::AtomicUsize::new(0);
    for _ in 0..15 {
        let c0 = common::cpu_ns();
        for _ in 0..rounds {
            let mut each: Vec<_> = (0..jobs)
                .map(|_| {
                    || {
                        std::hint::black_box(work(work_us as f64, per_us));
                        if std::thread::current().id() != caller {
                            elsewhere.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        }
                    }
                })
                .collect();
            let mut refs: Vec<&mut (dyn FnMut() + Send)> = each
                .iter_mut()
                .map(|j| j as &mut (dyn FnMut() + Send))
                .collect();
            let t0 = Instant::now();
            pool.run(&mut refs);
            walls.push(t0.elapsed().as_secs_f64() * 1e6);
            std::hint::black_box(work(gap_us as f64, per_us));
        }
        let cpu = (common::cpu_ns() - c0) as f64 * 1e-3 / rounds as f64 - gap_us as f64;
        best_cpu = best_cpu.min(cpu);
    }
    walls.sort_by(f64::total_cmp);
    let ideal = jobs.div_ceil(threads) as f64 * work_us as f64;
    let cpu_ideal = (jobs * work_us) as f64;
    let (least, median) = (walls[0], walls[walls.len() / 2]);
    println!(
        "{} threads, {jobs} jobs of {work_us} us, gap {gap_us} us: a round's wall least {least:.1} us, \
         median {median:.1} us (ideal {ideal:.0}: {:+.1}, {:+.1} us); CPU {best_cpu:.1} us a round \
         (jobs {cpu_ideal:.0}: {:+.1} us, best batch); {:.0} % of the jobs on other threads; load {}",
        Parallel::threads(&pool),
        least - ideal,
        median - ideal,
        best_cpu - cpu_ideal,
        100.0 * elsewhere.into_inner() as f64 / (15 * rounds * jobs) as f64,
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
