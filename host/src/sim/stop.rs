//! Stopping a run on request (SIGTERM from a SLURM time limit or `scancel`, Ctrl-C):
//! the request is a flag the caller's signal handler sets, read between steps, never
//! inside one. A run that sees it writes a checkpoint at the step it reached, leaves
//! its files under their temporary names (what the checkpoint marks), and ends with
//! [`Interrupted`]; resumed, it ends with the bytes of a run never stopped.
//!
//! The library installs no handler (the host library links no CLI crate): the CLI
//! registers SIGTERM and SIGINT to set the flag to the signal's number.

use std::fmt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// SIGTERM's number, the signal [`Stop::after_step`] stands for.
const SIGTERM: usize = 15;

/// A stop request: a flag set to a signal number (0: run on), or a step count.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stop {
    flag: Option<&'static AtomicUsize>,
    after: Option<u64>,
}

impl Stop {
    /// Stops when `flag` is set to a non-zero value (a signal number).
    pub fn on(flag: &'static AtomicUsize) -> Stop {
        Stop {
            flag: Some(flag),
            after: None,
        }
    }

    /// Stops before the step after step `n`, as a SIGTERM arriving then would: a
    /// stopped run at a step chosen in advance (the recovery tests' partial states).
    pub fn after_step(n: u64) -> Stop {
        Stop {
            flag: None,
            after: Some(n),
        }
    }

    /// The signal asked for, if a stop was.
    pub fn requested(&self) -> Option<usize> {
        self.flag
            .map(|f| f.load(Ordering::Relaxed))
            .filter(|&s| s != 0)
    }

    /// [`requested`](Self::requested), or SIGTERM once `done` steps reach
    /// [`after_step`](Self::after_step)'s count.
    pub fn requested_after(&self, done: u64) -> Option<usize> {
        let at = self.after.is_some_and(|n| done >= n).then_some(SIGTERM);
        self.requested().or(at)
    }
}

/// The exit status of a process stopped by signal `signal`: 128 plus its number, as a
/// shell reports a process the signal ended (143 for SIGTERM, 130 for SIGINT).
pub fn exit_status(signal: usize) -> u8 {
    u8::try_from(128 + signal.min(127)).unwrap_or(255)
}

/// A run stopped on request between two steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Interrupted {
    /// The signal that asked for the stop.
    pub signal: usize,
    /// Steps done.
    pub step: u64,
    /// Simulated time reached.
    pub time: f64,
    /// The checkpoint written at that step (None for a run without files).
    pub checkpoint: Option<PathBuf>,
}

impl fmt::Display for Interrupted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "stopped by signal {} after step {} (t = {})",
            self.signal, self.step, self.time
        )?;
        match &self.checkpoint {
            Some(c) => write!(
                f,
                "; checkpoint {} (rerun or resume to continue)",
                c.display()
            ),
            None => write!(f, "; nothing written"),
        }
    }
}

impl std::error::Error for Interrupted {}
