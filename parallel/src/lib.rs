//! Runs the `hydrorattle` kernel's mobility work on several threads.
//!
//! The kernel is single-threaded and `no_std`; it cuts the assembly of the mobility and
//! its products into bands of block rows ([`hydrorattle::parallel`]) and hands them to
//! the workspace's [`Parallel`]. [`Threads`] runs them on a rayon pool:
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
//! the same bits on any number of threads (tested in `tests/bits.rs`).

use hydrorattle::Parallel;
use rayon::prelude::*;

pub mod model;
pub mod wide;

/// A rayon thread pool that runs the kernel's bands.
#[derive(Debug)]
pub struct Threads {
    pool: rayon::ThreadPool,
}

impl Threads {
    /// A pool of `threads` threads; 0 takes rayon's default (every core, or
    /// `RAYON_NUM_THREADS`).
    pub fn new(threads: usize) -> Result<Self, rayon::ThreadPoolBuildError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("hydrorattle-{i}"))
            .build()?;
        Ok(Self { pool })
    }

    /// Threads in the pool.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }
}

impl Parallel for Threads {
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]) {
        self.pool
            .install(|| jobs.par_iter_mut().with_max_len(1).for_each(|job| job()));
    }

    fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }
}
