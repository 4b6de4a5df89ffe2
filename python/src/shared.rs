//! A system shared between Python threads. `step(n)` releases the GIL, so another
//! thread can read the system while it steps; a plain `#[pyclass]` would then raise
//! PyO3's `Already mutably borrowed`. Here the engine sits behind a mutex that a
//! stepping call holds for one step at a time:
//!
//! * a read from another thread waits (GIL released) for the end of the current step
//!   and sees the state between two steps: a consistent snapshot;
//! * a second `step` or a `set_state` while a `step(n)` runs raises `SystemBusyError`;
//! * a read from inside the step itself (a force callable reading the system) raises
//!   `SystemBusyError` too, naming what to read instead: the lock is not reentrant.
//!
//! The lock is fair to readers: a reader that finds it taken says so (`waiting`), and
//! the stepping call gives way between two steps until the waiting readers have had
//! it ([`Shared::give_way`]). A plain mutex lets the stepping thread, which unlocks
//! and locks again within microseconds, win it step after step while a reader sleeps
//! between tries: a read then waited for tens of steps.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, TryLockError};
use std::time::{Duration, Instant};

use pyo3::prelude::*;

use crate::errors::SystemBusyError;

/// How long a waiting reader sleeps between tries (GIL released), and a stepping
/// call between its looks for waiting readers.
const WAIT: Duration = Duration::from_micros(50);

/// The longest a stepping call gives way to waiting readers between two steps (a
/// reader that needs the GIL back from a busy Python thread may take Python's switch
/// interval, 5 ms, to come).
const GIVE_WAY: Duration = Duration::from_millis(20);

/// This thread's number (0 is nobody's).
fn me() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    thread_local!(static ID: u64 = NEXT.fetch_add(1, Ordering::Relaxed));
    ID.with(|id| *id)
}

/// A second `step(n)` or a change while one runs.
fn busy() -> PyErr {
    SystemBusyError::new_err(
        "the system is stepping in another call (one step(n) at a time; reads wait for the \
         end of the current step)",
    )
}

/// `X` behind a mutex, with the thread inside a step and whether a `step(n)` runs.
pub struct Shared<X> {
    inner: Mutex<X>,
    /// The thread holding the lock for a step (0: none).
    owner: AtomicU64,
    /// A `step(n)` call is running.
    stepping: AtomicBool,
    /// Readers waiting for the lock.
    waiting: AtomicUsize,
}

/// The lock held for one step; the owner mark goes with it.
pub struct StepLock<'a, X> {
    guard: MutexGuard<'a, X>,
    owner: &'a AtomicU64,
}

impl<X> Drop for StepLock<'_, X> {
    fn drop(&mut self) {
        self.owner.store(0, Ordering::Release);
    }
}

impl<X> std::ops::Deref for StepLock<'_, X> {
    type Target = X;
    fn deref(&self) -> &X {
        &self.guard
    }
}

impl<X> std::ops::DerefMut for StepLock<'_, X> {
    fn deref_mut(&mut self) -> &mut X {
        &mut self.guard
    }
}

/// A `step(n)` call's mark, cleared when the call ends.
pub struct Stepping<'a>(&'a AtomicBool);

impl Drop for Stepping<'_> {
    fn drop(&mut self) {
        self.0.store(false, Ordering::Release);
    }
}

impl<X> Shared<X> {
    /// `x`, shared.
    pub fn new(x: X) -> Self {
        Shared {
            inner: Mutex::new(x),
            owner: AtomicU64::new(0),
            stepping: AtomicBool::new(false),
            waiting: AtomicUsize::new(0),
        }
    }

    /// The state between two steps: waits (GIL released) while another thread is
    /// inside a step; `SystemBusyError` from inside a step on this thread.
    pub fn read(&self, py: Python<'_>) -> PyResult<MutexGuard<'_, X>> {
        if self.owner.load(Ordering::Acquire) == me() {
            return Err(SystemBusyError::new_err(
                "the system is inside a step on this thread (a force callable reads the \
                 positions it is passed, not the system)",
            ));
        }
        let mut marked = false;
        let guard = loop {
            match self.inner.try_lock() {
                Ok(g) => break g,
                // A panic cannot leave the engine half-stepped: a step commits last.
                Err(TryLockError::Poisoned(p)) => break p.into_inner(),
                Err(TryLockError::WouldBlock) => {
                    if !marked {
                        self.waiting.fetch_add(1, Ordering::AcqRel);
                        marked = true;
                    }
                    py.detach(|| std::thread::sleep(WAIT));
                }
            }
        };
        if marked {
            self.waiting.fetch_sub(1, Ordering::AcqRel);
        }
        Ok(guard)
    }

    /// Between two steps of a `step(n)` call: waits (at most [`GIVE_WAY`]) while
    /// readers wait for the lock, so that each gets it before the next step. Called
    /// without the GIL (the readers need it to take their turn).
    pub fn give_way(&self) {
        let start = Instant::now();
        while self.waiting.load(Ordering::Acquire) > 0 && start.elapsed() < GIVE_WAY {
            std::thread::sleep(WAIT);
        }
    }

    /// Whether a reader waits for the lock.
    pub fn readers_waiting(&self) -> bool {
        self.waiting.load(Ordering::Acquire) > 0
    }

    /// As [`Shared::read`], for a change of the state: `SystemBusyError` while a
    /// `step(n)` runs.
    pub fn write(&self, py: Python<'_>) -> PyResult<MutexGuard<'_, X>> {
        self.not_stepping()?;
        self.read(py)
    }

    fn not_stepping(&self) -> PyResult<()> {
        match self.stepping.load(Ordering::Acquire) {
            true => Err(busy()),
            false => Ok(()),
        }
    }

    /// Marks a `step(n)` call; `SystemBusyError` if one runs.
    pub fn begin(&self) -> PyResult<Stepping<'_>> {
        match self
            .stepping
            .compare_exchange(false, true, Ordering::AcqRel, Ordering::Acquire)
        {
            Ok(_) => Ok(Stepping(&self.stepping)),
            Err(_) => Err(busy()),
        }
    }

    /// The lock for one step, taken on any thread (GIL held or not): readers hold it
    /// only while they hold the GIL and never wait for anything inside it.
    pub fn step_lock(&self) -> StepLock<'_, X> {
        let guard = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        self.owner.store(me(), Ordering::Release);
        StepLock {
            guard,
            owner: &self.owner,
        }
    }
}
