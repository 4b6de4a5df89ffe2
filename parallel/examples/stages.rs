//! Where a step's time goes: the rounds of band jobs the kernel hands to its
//! [`Parallel`] (assembly, products, acceptance), timed one by one, and the rest of the
//! step (the kernel's serial work: preconditioner, Krylov and Lanczos vector work,
//! forces, copies) as the difference (docs/BENCHMARKS.md, "Serial parts").
//!
//! `cargo run --release -p hydrorattle-parallel --example stages -- [N] [STEPS] [THREADS] [MODE]`
//! (defaults 4096, 3, 1, `plain`; MODE as in `examples/speedup.rs`: `plain`, `compact`,
//! `free`, `brownian`).
//!
//! Every round is timed by the wall clock and by the CPU time the process's threads ran
//! (`/proc/self/task/*/schedstat`; a thread waiting for a core on a shared machine adds
//! wall time, not CPU time). A round of bands is followed by the round that adds the
//! bands' partial sums (a few microseconds); the two are reported as one. The rounds of
//! the best step (by CPU time) are printed in order with what the step does there, read
//! from the integrator (`src/integrate/overdamped.rs`, `brownian.rs`): the first round
//! of the plain step is the fused assembly and first product, the last one the
//! acceptance's pair check, the others the constraint solve's products.

use std::sync::Mutex;
use std::time::Instant;

use hydrorattle::glam::DVec3;
use hydrorattle::{Layout, NoForce, Noise, Parallel, Serial, State, step_slices};
use hydrorattle_heap::Buffers;
use hydrorattle_parallel::Threads;

mod common;
use common::cpu_ns;

/// Nanoseconds the calling thread has run on a CPU.
fn thread_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// One round of jobs: how many, its wall and CPU nanoseconds, and the CPU time of the
/// thread that ran the most (the round's wall time on idle cores, waits aside).
#[derive(Clone, Copy, Debug)]
struct Round {
    jobs: usize,
    wall: u64,
    cpu: u64,
    busiest: u64,
}

/// A [`Parallel`] that runs its rounds on `inner` and logs each.
#[derive(Debug)]
struct Timed<'a> {
    inner: &'a dyn Parallel,
    log: Mutex<Vec<Round>>,
}

impl Parallel for Timed<'_> {
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]) {
        // Each job's CPU time, summed by the thread that ran it.
        let by_thread = Mutex::new(std::collections::HashMap::<std::thread::ThreadId, u64>::new());
        let mut timed: Vec<_> = jobs
            .iter_mut()
            .map(|job| {
                let by_thread = &by_thread;
                move || {
                    let c = thread_ns();
                    job();
                    let id = std::thread::current().id();
                    *by_thread.lock().unwrap().entry(id).or_default() += thread_ns() - c;
                }
            })
            .collect();
        let mut refs: Vec<&mut (dyn FnMut() + Send)> = timed
            .iter_mut()
            .map(|j| j as &mut (dyn FnMut() + Send))
            .collect();
        let (t0, c0) = (Instant::now(), cpu_ns());
        self.inner.run(&mut refs);
        let (wall, cpu) = (t0.elapsed().as_nanos() as u64, cpu_ns() - c0);
        let busiest = by_thread
            .into_inner()
            .unwrap()
            .into_values()
            .max()
            .unwrap_or(0);
        let round = Round {
            jobs: jobs.len(),
            wall,
            cpu,
            busiest,
        };
        self.log.lock().unwrap().push(round);
    }

    fn threads(&self) -> usize {
        self.inner.threads()
    }
}

/// A step's rounds (each band round with its reduction), its total wall and CPU time.
struct Step {
    rounds: Vec<Round>,
    wall: u64,
    cpu: u64,
}

/// The band rounds of `log`, each with the reduction round after it (a round of bands
/// whose time is under a twentieth of the one before is taken for its reduction).
fn merge(log: &[Round]) -> Vec<Round> {
    let mut out: Vec<Round> = Vec::new();
    for &r in log {
        match out.last_mut() {
            Some(last) if r.wall * 20 < last.wall && r.cpu * 20 < last.cpu.max(1) => {
                last.wall += r.wall;
                last.cpu += r.cpu;
                last.busiest += r.busiest;
            }
            _ => out.push(r),
        }
    }
    out
}

fn main() {
    let arg = common::arg;
    let (n, steps, threads) = (arg(1, 4096), arg(2, 3), arg(3, 1));
    let mode = std::env::args().nth(4).unwrap_or_else(|| "plain".into());
    let start = common::helix(n);
    let bonds = common::chain(&start);
    let (radius, density) = (vec![1.0; n], vec![4.5; n]);
    let p = common::params(&mode);
    let mut store = Buffers::<f64>::new(Layout::for_params(&p, n, n - 1));
    let pool = Threads::new(threads).unwrap();
    let inner: &dyn Parallel = if threads == 1 { &Serial } else { &pool };
    let timed = Timed {
        inner,
        log: Mutex::new(Vec::new()),
    };
    let mut ws = store.workspace().with_parallel(&timed);
    let mut pos = start.clone();
    let (mut vel, mut omega, mut time) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n], 0.0);
    let mut noise = Noise::new(7);
    let mut taken = Vec::new();
    // One step more than asked: the first touches the workspace's pages.
    for _ in 0..=steps {
        timed.log.lock().unwrap().clear();
        let (t0, c0) = (Instant::now(), cpu_ns());
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: p.brownian.map(|_| &mut noise),
        };
        step_slices(state, &bonds, &p, &mut ws, &mut NoForce).unwrap();
        let (wall, cpu) = (t0.elapsed().as_nanos() as u64, cpu_ns() - c0);
        let rounds = merge(&timed.log.lock().unwrap());
        taken.push(Step { rounds, wall, cpu });
    }
    // FNV-1a over the final positions' bits: the same digest from every build and thread
    // count that keeps the bits.
    let digest = pos
        .iter()
        .flat_map(|v| v.to_array())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x0100_0000_01b3)
        });
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
    let (mut in_wall, mut in_cpu, mut in_busiest) = (0, 0, 0);
    for (k, r) in best.rounds.iter().enumerate() {
        in_wall += r.wall;
        in_cpu += r.cpu;
        in_busiest += r.busiest;
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
         ({:.1} % of its wall)",
        ms(out_wall),
        ms(out_cpu),
        100.0 * out_cpu as f64 / best.cpu as f64,
        100.0 * out_wall as f64 / best.wall as f64
    );
}
