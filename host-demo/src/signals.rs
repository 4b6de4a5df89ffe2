//! SIGTERM and SIGINT stop a run cleanly: the first sets a flag that the run reads
//! between steps (it checkpoints and exits with 128 + the signal's number: 143 for
//! SIGTERM, as SLURM's time limit and `scancel` send it, 130 for Ctrl-C); a second of
//! either ends the process at once, as without a handler.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::AtomicUsize;

use hydrorattle_host::sim::{Interrupted, Stop, stop::exit_status};
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

/// Installs the handlers; the [`Stop`] a run reads. Where a handler cannot be
/// installed the signal keeps its default (the process ends), said once.
pub fn install() -> Stop {
    let signal: &'static Arc<AtomicUsize> = Box::leak(Box::new(Arc::new(AtomicUsize::new(0))));
    for sig in [SIGTERM, SIGINT] {
        // The second signal ends the process: registered first, it sees the flag the
        // first one set.
        let shutdown = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let installed = flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&shutdown))
            .and_then(|_| flag::register(sig, shutdown))
            .and_then(|_| flag::register_usize(sig, Arc::clone(signal), sig as usize));
        if let Err(e) = installed {
            log::warn!("signal {sig}: no handler ({e}): it ends the process without a checkpoint");
        }
    }
    Stop::on(signal)
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
