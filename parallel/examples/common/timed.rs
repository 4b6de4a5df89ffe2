//! A [`Parallel`] that times each round of jobs the kernel hands it, and the helix's
//! steps run through it (`examples/stages.rs`, `examples/bandwidth.rs`).

use std::sync::Mutex;
use std::time::Instant;

use hydrorattle::glam::DVec3;
use hydrorattle::{Layout, NoForce, Noise, Parallel, State, StepReport, step_slices};
use hydrorattle_heap::Buffers;

use super::cpu_ns;

/// Nanoseconds the calling thread has run on a CPU.
pub fn thread_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// One round of jobs: how many, its wall and CPU nanoseconds, and the CPU time of the
/// thread that ran the most (the round's wall time on idle cores, waits aside).
#[derive(Clone, Copy, Debug)]
pub struct Round {
    /// Jobs in the round.
    pub jobs: usize,
    /// Wall-clock nanoseconds.
    pub wall: u64,
    /// CPU nanoseconds of all the process's threads.
    pub cpu: u64,
    /// CPU nanoseconds of the thread that ran the most of the round's jobs.
    pub busiest: u64,
    /// CPU nanoseconds of the calling thread (the one that steps) in the round.
    pub caller: u64,
}

/// A [`Parallel`] that runs its rounds on `inner` and logs each.
#[derive(Debug)]
pub struct Timed<'a> {
    /// Where the rounds run.
    pub inner: &'a dyn Parallel,
    /// The rounds run so far.
    pub log: Mutex<Vec<Round>>,
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
        let (t0, c0, m0) = (Instant::now(), cpu_ns(), thread_ns());
        self.inner.run(&mut refs);
        let (wall, cpu) = (t0.elapsed().as_nanos() as u64, cpu_ns() - c0);
        let caller = thread_ns() - m0;
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
            caller,
        };
        self.log.lock().unwrap().push(round);
    }

    fn threads(&self) -> usize {
        self.inner.threads()
    }
}

/// A step's rounds (each band round with its reduction), its total wall and CPU time.
pub struct Step {
    /// Its rounds in order.
    pub rounds: Vec<Round>,
    /// Wall-clock nanoseconds.
    pub wall: u64,
    /// CPU nanoseconds.
    pub cpu: u64,
    /// CPU nanoseconds of the calling thread.
    pub caller: u64,
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
                last.caller += r.caller;
            }
            _ => out.push(r),
        }
    }
    out
}

/// The helix's steps in `mode` (`steps + 1` of them: the first touches the
/// workspace's pages) through `inner`, each timed round by round; the final positions'
/// digest (FNV-1a over their bits: the same from every build and thread count that
/// keeps the bits) and the last step's report.
pub fn run(
    n: usize,
    steps: usize,
    mode: &str,
    inner: &dyn Parallel,
) -> (Vec<Step>, u64, StepReport<f64>) {
    let start = super::helix(n);
    let bonds = super::chain(&start);
    let (radius, density) = (vec![1.0; n], vec![4.5; n]);
    let p = super::params(mode);
    let mut store = Buffers::<f64>::new(Layout::for_params(&p, n, n - 1));
    let timed = Timed {
        inner,
        log: Mutex::new(Vec::new()),
    };
    let mut ws = store.workspace().with_parallel(&timed);
    let mut pos = start.clone();
    let (mut vel, mut omega, mut time) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n], 0.0);
    let mut noise = Noise::new(7);
    let (mut taken, mut report) = (Vec::new(), StepReport::default());
    for _ in 0..=steps {
        timed.log.lock().unwrap().clear();
        let (t0, c0, m0) = (Instant::now(), cpu_ns(), thread_ns());
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: p.brownian.map(|_| &mut noise),
        };
        report = step_slices(state, &bonds, &p, &mut ws, &mut NoForce).unwrap();
        let (wall, cpu) = (t0.elapsed().as_nanos() as u64, cpu_ns() - c0);
        let caller = thread_ns() - m0;
        let rounds = merge(&timed.log.lock().unwrap());
        taken.push(Step {
            rounds,
            wall,
            cpu,
            caller,
        });
    }
    let digest = pos
        .iter()
        .flat_map(|v| v.to_array())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x0100_0000_01b3)
        });
    (taken, digest, report)
}
