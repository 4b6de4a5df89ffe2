//! SIGTERM and SIGINT stop a run cleanly: the first sets a flag that the run reads
//! between steps (it checkpoints and exits with 128 + the signal's number: 143 for
//! SIGTERM, as SLURM's time limit and `scancel` send it, 130 for Ctrl-C), and says so
//! at once, since a step can take minutes. A second one of either ends the process at
//! once, mid-step, with a message: nothing more is written, so every file stays as a
//! kill would leave it, which a run is built to survive: the last complete checkpoint
//! stays valid (it marks only bytes written before it was saved; the bytes after it,
//! a frame cut off included, are cut away by the resume), and a run without one runs
//! again from the start.

use std::fmt;
use std::sync::atomic::{AtomicUsize, Ordering};

use hydrorattle_host::sim::{Interrupted, Stop, stop::exit_status};
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

/// Installs the handlers; the [`Stop`] a run reads. Where a handler cannot be
/// installed the signals keep their default (the process ends), said once.
pub fn install() -> Stop {
    let flag: &'static AtomicUsize = Box::leak(Box::new(AtomicUsize::new(0)));
    // A thread of its own reads the signals: it can print, and it acts on a second
    // signal while the run is inside a step.
    let watched = Signals::new([SIGTERM, SIGINT]).and_then(|mut signals| {
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                for sig in signals.forever() {
                    on_signal(flag, sig);
                }
            })
    });
    if let Err(e) = watched {
        log::warn!("SIGTERM, SIGINT: no handler ({e}): they end the process without a checkpoint");
    }
    Stop::on(flag)
}

/// The first signal asks for a stop after the step under way; the second ends the
/// process now.
fn on_signal(flag: &AtomicUsize, sig: i32) {
    let first = flag
        .compare_exchange(0, sig as usize, Ordering::SeqCst, Ordering::SeqCst)
        .is_ok();
    if first {
        eprintln!(
            "host-demo: signal {sig}: stopping after the step under way, with a checkpoint \
             there (send it again to end at once, without one)"
        );
        return;
    }
    eprintln!(
        "host-demo: signal {sig} again: ending at once, mid-step, writing nothing more: the \
         last checkpoint written stays valid (resume from it, or rerun the sweep); a run \
         without one runs again from the start"
    );
    // `_exit`: no destructor runs, so no file is renamed or removed half-way.
    signal_hook::low_level::exit(i32::from(exit_status(sig as usize)));
}

/// A sweep that stopped on request (its points checkpointed).
#[derive(Debug, Clone, Copy)]
pub struct Stopped(pub usize);

impl fmt::Display for Stopped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "stopped by signal {}", self.0)
    }
}

impl std::error::Error for Stopped {}

/// The exit status of an error that is a stop on request: 128 + the signal.
pub fn exit_code(e: &anyhow::Error) -> Option<u8> {
    let signal = e
        .downcast_ref::<Interrupted>()
        .map(|i| i.signal)
        .or_else(|| e.downcast_ref::<Stopped>().map(|s| s.0))?;
    Some(exit_status(signal))
}
