//! Runs the `hydrorattle` kernel's mobility work on several threads.
//!
//! The kernel is single-threaded and `no_std`; it cuts the assembly of the mobility and
//! its products into bands of block rows ([`hydrorattle::parallel`]) and hands them to
//! the workspace's [`Parallel`]. [`Threads`] runs them on a pool of threads:
//!
//! ```
//! use hydrorattle::{Layout, Method};
//! use hydrorattle_heap::Buffers;
//! use hydrorattle_parallel::Threads;
//!
//! let threads = Threads::new(2).unwrap();
//! let mut store = Buffers::<f64>::new(Layout::new(Method::Overdamped, false, 600, 599));
//! let ws = store.workspace().with_parallel(&threads);
//! # let _ = ws;
//! ```
//!
//! The bands and the order of every sum depend on the bead count alone, so a run gives
//! the same bits on any number of threads (tested in `tests/parallel/bits.rs`).
//!
//! **The pool** ([`pool`]) is this crate's own, shaped for the kernel's many short
//! rounds: the thread that steps is one of the pool's threads (`Threads::new(t)` spawns
//! `t - 1`, so `t` threads on `t` cores never oversubscribe), jobs are handed out by an
//! atomic counter, and idle threads spin for [`pool::SPIN`] before they sleep, so that
//! back-to-back rounds pay no wake-up while an idle pool burns no CPU. A job's panic
//! reaches the caller after the round has finished; calls from several threads take
//! turns; dropping the pool stops and joins its threads.

use hydrorattle::Parallel;

pub mod model;
pub mod pool;
pub mod wide;

/// The pool that runs the kernel's bands: the calling thread and `threads() - 1` more.
#[derive(Debug)]
pub struct Threads {
    pool: pool::Pool,
}

impl Threads {
    /// A pool of `threads` threads, the caller among them; 0 takes every core
    /// ([`std::thread::available_parallelism`]), or `RAYON_NUM_THREADS` where it is a
    /// positive count (the variable that also sets the host's sweeps, which run on
    /// rayon). An error where a thread cannot be spawned.
    pub fn new(threads: usize) -> std::io::Result<Self> {
        let threads = match threads {
            0 => default_threads(),
            t => t,
        };
        Ok(Self {
            pool: pool::Pool::new(threads)?,
        })
    }

    /// Threads in the pool, the caller's among them.
    pub fn threads(&self) -> usize {
        self.pool.threads()
    }
}

/// Every core, or `RAYON_NUM_THREADS` where it is a positive count.
fn default_threads() -> usize {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .filter(|&t: &usize| t > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |t| t.get()))
}

impl Parallel for Threads {
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]) {
        self.pool.run(jobs);
    }

    fn threads(&self) -> usize {
        self.pool.threads()
    }
}
