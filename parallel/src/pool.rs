//! A persistent pool built for the kernel's rounds of band jobs ([`Threads`](crate::Threads)).
//!
//! A step hands its [`Parallel`](hydrorattle::Parallel) tens of rounds of 16 jobs each
//! with serial work between them, so what a round costs beyond its jobs is paid many
//! times a step. The pool is shaped for that:
//!
//! * **The caller is worker 0.** A pool of `t` threads spawns `t - 1`; the thread that
//!   calls [`Pool::run`] takes jobs like the others, so `t` threads on `t` cores never
//!   oversubscribe (a rayon `install` blocks the caller and adds a thread that wants a
//!   core for the serial work between rounds).
//! * **Jobs are handed out by one atomic counter**: each job exactly once, to whichever
//!   thread asks first. The jobs share no mutable state, so any schedule gives the same
//!   bits.
//! * **Idle workers spin, then sleep.** After a round a worker spins on the round
//!   counter for [`SPIN`] (back-to-back rounds pay no wake-up; `HYDRORATTLE_SPIN_US`
//!   sets it), then sleeps on a
//!   condition variable (an idle pool burns no CPU); a new round wakes every sleeper
//!   with one broadcast. The caller waits for the last job the same way.
//!
//! The round counter `ticket` holds the round's number (`epoch`, the high bits) and the
//! next job's index (the low [`INDEX_BITS`]): a thread claims job `i` of round `e` by
//! swapping `(e, i)` for `(e, i + 1)`, so a thread that read an older round's data
//! cannot claim a job of a newer one.
//!
//! A job that panics does not stop the round: the other jobs run, the first payload is
//! kept, and the caller resumes the panic once every job has finished. A thread that
//! calls [`Pool::run`] from inside one of the pool's own jobs runs its jobs itself
//! (waiting for the pool would deadlock); calls from several outside threads take turns.

use std::any::Any;
use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::sync::atomic::Ordering::{AcqRel, Acquire, Relaxed, SeqCst};
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicU64, AtomicUsize};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// How long an idle thread spins before it sleeps, unless `HYDRORATTLE_SPIN_US` sets it
/// (microseconds, read when a pool is built; 0 sleeps after a few checks, for a machine shared
/// with other work, where a spinning thread spends its share of a core): the kernel's
/// gaps between rounds (a band round's reduction, Krylov and Lanczos vector work) are
/// mostly shorter, the serial preconditioner's longer; a futex wake-up costs tens of
/// microseconds.
pub const SPIN: Duration = Duration::from_micros(200);

/// [`SPIN`], or `HYDRORATTLE_SPIN_US` where it is a count of microseconds.
fn spin_time() -> Duration {
    std::env::var("HYDRORATTLE_SPIN_US")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .map_or(SPIN, Duration::from_micros)
}

/// Low bits of the round counter that index the round's jobs.
pub const INDEX_BITS: u32 = 24;

/// Jobs one round hands out (more are run in several rounds).
const MAX_JOBS: usize = (1 << INDEX_BITS) - 1;

/// Spins between two reads of the clock.
const SPINS_PER_CHECK: u32 = 64;

/// A job as the kernel hands it.
type Job<'a> = &'a mut (dyn FnMut() + Send + 'a);

thread_local! {
    /// The pool whose round this thread is in (its address; 0: none).
    static INSIDE: Cell<usize> = const { Cell::new(0) };
}

/// What the caller and the workers share.
struct Shared {
    /// `epoch << INDEX_BITS | next job`: the round in progress and its next job.
    ticket: AtomicU64,
    /// Jobs in the round in progress.
    len: AtomicUsize,
    /// The round's first job (a `*mut Job`, its lifetime erased: see [`Shared::call`]).
    base: AtomicPtr<()>,
    /// Jobs of the round in progress that have finished.
    done: AtomicUsize,
    /// The pool is being dropped: workers leave at the next round.
    stop: AtomicBool,
    /// How long an idle thread spins before it sleeps.
    spin: Duration,
    /// The first panic payload of the round in progress.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    /// Workers asleep (or about to sleep) on `wake`.
    sleepers: AtomicUsize,
    /// The caller is asleep (or about to sleep) on `finished`.
    waiting: AtomicBool,
    /// The lock `wake` and `finished` sleep under.
    lock: Mutex<()>,
    /// A new round (or the stop) has been published.
    wake: Condvar,
    /// The round's last job has finished.
    finished: Condvar,
}

/// The epoch of a ticket.
fn epoch(ticket: u64) -> u64 {
    ticket >> INDEX_BITS
}

/// Locks `m`, ignoring poison (the pool's locks guard no invariant a panic can break).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Spins until `ready` gives `Some` or `time` has passed (asks once at least).
fn spin<T>(time: Duration, mut ready: impl FnMut() -> Option<T>) -> Option<T> {
    let start = Instant::now();
    loop {
        for _ in 0..SPINS_PER_CHECK {
            if let Some(t) = ready() {
                return Some(t);
            }
            std::hint::spin_loop();
        }
        if start.elapsed() >= time {
            return None;
        }
    }
}

impl Shared {
    /// Runs job `i` of the round whose first job is `base`, catching its panic.
    ///
    /// # Safety
    ///
    /// `base` is the first job of the round in progress, `i` is below its length, and
    /// this thread has claimed `i` (by the ticket swap, which gives each index of a round
    /// to one thread). The caller's [`Pool::run`] does not return, so its jobs and their
    /// borrows stay alive, until `done` counts job `i`, which happens after this returns.
    unsafe fn call(&self, base: *mut (), i: usize) {
        // SAFETY: see above; the job is reached by no other thread.
        let job: &mut Job<'_> = unsafe { &mut *base.cast::<Job<'_>>().add(i) };
        if let Err(payload) = panic::catch_unwind(AssertUnwindSafe(job)) {
            lock(&self.panic).get_or_insert(payload);
        }
    }

    /// Claims and runs jobs of the round of `ticket` until none is left.
    fn help(&self, mut ticket: u64) {
        loop {
            // Read after `ticket` (acquire): this round's length and jobs, or a later
            // round's, in which case the swap below fails.
            let len = self.len.load(Acquire);
            let base = self.base.load(Acquire);
            let i = (ticket & MAX_JOBS as u64) as usize;
            if i >= len {
                return;
            }
            match self
                .ticket
                .compare_exchange_weak(ticket, ticket + 1, AcqRel, Acquire)
            {
                Ok(_) => {
                    // SAFETY: the swap claimed job `i < len` of the round whose `len`
                    // and `base` were read: that round cannot end before `done` counts
                    // this job, so no later round has replaced them.
                    unsafe { self.call(base, i) };
                    ticket += 1;
                    // Nothing of the round is touched after this count.
                    if self.done.fetch_add(1, SeqCst) + 1 == len && self.waiting.load(SeqCst) {
                        drop(lock(&self.lock));
                        self.finished.notify_all();
                    }
                }
                Err(now) if epoch(now) == epoch(ticket) => ticket = now,
                Err(_) => return,
            }
        }
    }

    /// Waits (spinning, then asleep) for a round after `seen`; its ticket.
    fn next_round(&self, seen: u64) -> u64 {
        let fresh = || Some(self.ticket.load(Acquire)).filter(|&t| epoch(t) != seen);
        if let Some(t) = spin(self.spin, fresh) {
            return t;
        }
        let mut guard = lock(&self.lock);
        self.sleepers.fetch_add(1, SeqCst);
        loop {
            // SeqCst beside the publisher's store-then-load of `sleepers`: either it
            // sees this sleeper or this load sees its round.
            let t = self.ticket.load(SeqCst);
            if epoch(t) != seen {
                self.sleepers.fetch_sub(1, SeqCst);
                return t;
            }
            guard = self
                .wake
                .wait(guard)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }

    /// Publishes `ticket` (a new round, or the stop) and wakes the sleepers.
    fn publish(&self, ticket: u64) {
        self.ticket.store(ticket, SeqCst);
        if self.sleepers.load(SeqCst) > 0 {
            drop(lock(&self.lock));
            self.wake.notify_all();
        }
    }

    /// Waits (spinning, then asleep) until `len` jobs of the round have finished.
    fn wait_done(&self, len: usize) {
        if spin(self.spin, || (self.done.load(Acquire) >= len).then_some(())).is_some() {
            return;
        }
        let mut guard = lock(&self.lock);
        self.waiting.store(true, SeqCst);
        while self.done.load(SeqCst) < len {
            guard = self
                .finished
                .wait(guard)
                .unwrap_or_else(PoisonError::into_inner);
        }
        self.waiting.store(false, SeqCst);
    }
}

/// A worker: the rounds' jobs until the pool stops.
fn work(shared: Arc<Shared>) {
    INSIDE.set(Arc::as_ptr(&shared) as usize);
    let mut seen = 0;
    loop {
        let ticket = shared.next_round(seen);
        seen = epoch(ticket);
        if shared.stop.load(Acquire) {
            return;
        }
        shared.help(ticket);
    }
}

/// The pool: `threads - 1` workers and the calling thread.
pub struct Pool {
    shared: Arc<Shared>,
    /// The last round's epoch; held by the caller of a round, so callers take turns.
    turn: Mutex<u64>,
    workers: Vec<JoinHandle<()>>,
}

impl core::fmt::Debug for Pool {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Pool")
            .field("threads", &self.threads())
            .finish()
    }
}

impl Pool {
    /// A pool of `threads` threads (at least 1): the caller and `threads - 1` spawned
    /// ones, named `hydrorattle-1` and on.
    pub fn new(threads: usize) -> std::io::Result<Self> {
        let shared = Arc::new(Shared {
            ticket: AtomicU64::new(0),
            len: AtomicUsize::new(0),
            base: AtomicPtr::new(std::ptr::null_mut()),
            done: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
            spin: spin_time(),
            panic: Mutex::new(None),
            sleepers: AtomicUsize::new(0),
            waiting: AtomicBool::new(false),
            lock: Mutex::new(()),
            wake: Condvar::new(),
            finished: Condvar::new(),
        });
        let mut pool = Pool {
            shared,
            turn: Mutex::new(0),
            workers: Vec::new(),
        };
        for k in 1..threads.max(1) {
            let shared = pool.shared.clone();
            // On failure `pool` is dropped here, which stops and joins those spawned.
            let handle = thread::Builder::new()
                .name(format!("hydrorattle-{k}"))
                .spawn(move || work(shared))?;
            pool.workers.push(handle);
        }
        Ok(pool)
    }

    /// Threads that run a round's jobs: the workers and the caller.
    pub fn threads(&self) -> usize {
        self.workers.len() + 1
    }

    /// Runs every job exactly once on the pool's threads (this one among them) and
    /// returns when all have finished; a job's panic is resumed here after that.
    pub fn run(&self, jobs: &mut [Job<'_>]) {
        let me = Arc::as_ptr(&self.shared) as usize;
        if self.workers.is_empty() || jobs.len() < 2 || INSIDE.get() == me {
            for job in jobs.iter_mut() {
                job();
            }
            return;
        }
        for chunk in jobs.chunks_mut(MAX_JOBS) {
            self.round(chunk, me);
        }
    }

    /// One round of at most [`MAX_JOBS`] jobs.
    fn round(&self, jobs: &mut [Job<'_>], me: usize) {
        let mut turn = lock(&self.turn);
        *turn += 1;
        let s = &*self.shared;
        let len = jobs.len();
        s.done.store(0, Relaxed);
        s.len.store(len, Relaxed);
        // The only pointer to the jobs while the round runs (the `&mut` is not used
        // again until every job has finished).
        s.base.store(jobs.as_mut_ptr().cast(), Relaxed);
        let ticket = *turn << INDEX_BITS;
        // Release (SeqCst): a worker that reads this ticket reads the stores above.
        s.publish(ticket);
        let outer = INSIDE.replace(me);
        s.help(ticket);
        s.wait_done(len);
        INSIDE.set(outer);
        // Every job has finished and counted itself; no worker holds `base` any more.
        s.base.store(std::ptr::null_mut(), Relaxed);
        let payload = lock(&s.panic).take();
        drop(turn);
        if let Some(payload) = payload {
            panic::resume_unwind(payload);
        }
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        let turn = self.turn.get_mut().unwrap_or_else(PoisonError::into_inner);
        *turn += 1;
        self.shared.stop.store(true, SeqCst);
        self.shared.publish(*turn << INDEX_BITS);
        for handle in self.workers.drain(..) {
            // A worker catches its jobs' panics; nothing else in it panics.
            let _ = handle.join();
        }
    }
}
