//! Progress of long jobs (a run's steps, a map's cells), counted here and shown by
//! whatever display a front end installs: the CLI a terminal bar, the Python package
//! none. The library links no terminal crate.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

/// What shows a job's progress: told the units done, then that the job ended.
pub trait Display: Send + Sync {
    /// `done` units of the job are done.
    fn set_position(&self, done: u64);
    /// The job ended (done or not): clear what was shown.
    fn finish(&self);
}

/// Makes the display of a job of `total` units labelled `label`.
pub type Factory = fn(total: u64, label: &str) -> Box<dyn Display>;

static FACTORY: OnceLock<Factory> = OnceLock::new();

/// Installs the displays of every later [`Progress::new`] (once per process; `false`
/// when one was installed already).
pub fn install(factory: Factory) -> bool {
    FACTORY.set(factory).is_ok()
}

/// A job's progress over `total` units, shared between threads (`&Progress` is enough
/// to advance it).
pub struct Progress {
    done: AtomicU64,
    display: Option<Box<dyn Display>>,
}

impl Progress {
    /// Progress shown by the installed display, if any.
    pub fn new(total: u64, label: &str) -> Progress {
        Progress {
            done: AtomicU64::new(0),
            display: FACTORY.get().map(|f| f(total, label)),
        }
    }

    /// Progress that is counted but never shown.
    pub fn hidden(_total: u64) -> Progress {
        Progress {
            done: AtomicU64::new(0),
            display: None,
        }
    }

    /// Advances by `n` units.
    pub fn inc(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        if let Some(d) = &self.display {
            d.set_position(done);
        }
    }

    /// Sets the number of units done.
    pub fn set_position(&self, done: u64) {
        self.done.store(done, Ordering::Relaxed);
        if let Some(d) = &self.display {
            d.set_position(done);
        }
    }

    /// Units done so far.
    pub fn position(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// Ends the job's display.
    pub fn finish(&self) {
        if let Some(d) = &self.display {
            d.finish();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_progress_counts_across_threads() {
        let p = Progress::hidden(400);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| (0..100).for_each(|_| p.inc(1)));
            }
        });
        assert_eq!(p.position(), 400);
        p.set_position(7);
        assert_eq!(p.position(), 7);
    }
}
