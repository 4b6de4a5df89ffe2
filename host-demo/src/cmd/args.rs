//! What several subcommands parse the same way: storage and output limits, positive
//! numbers, and a run's one-line report.

use anyhow::Result;
use clap::Args;
use hydrorattle_host::sim::Summary;
use hydrorattle_host::sizing::{DEFAULT_LIMIT, DEFAULT_OUTPUT_LIMIT, Limits, limit_from_gib};
use std::path::Path;

/// The limits a scene is read under, and the threads of a run.
#[derive(Debug, Args)]
pub struct RunLimits {
    /// Largest step storage allowed, GiB: a scene needing more is refused before
    /// anything is built (storage grows as the square of the bead count).
    #[arg(long, default_value_t = (DEFAULT_LIMIT >> 30) as f64, value_name = "GIB", value_parser = gib)]
    pub max_storage: f64,
    /// Largest trajectory output allowed, GiB: a scene whose frames would need more
    /// is refused while it is read (at its `every` or `duration` line).
    #[arg(long, default_value_t = (DEFAULT_OUTPUT_LIMIT >> 30) as f64, value_name = "GIB", value_parser = gib)]
    pub max_output: f64,
    /// Threads for the mobility of scenes from 512 beads on (0: every core); the
    /// trajectory's bits do not depend on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
}

impl RunLimits {
    /// The limits a scene is read under.
    pub fn limits(&self) -> Limits {
        Limits {
            storage: limit_from_gib(self.max_storage).unwrap_or(DEFAULT_LIMIT),
            output: limit_from_gib(self.max_output).map_or(DEFAULT_OUTPUT_LIMIT, |b| b as u64),
        }
    }
}

/// Prints a run's one-line report; a run that stopped early is an error.
pub fn report(name: &str, s: &Summary, out: &Path) -> Result<()> {
    println!(
        "{name}: {} of {} steps in {:.2} s ({:.0} steps/s); outcome {}; extension {:.3}, verticality {:.3}, twist rate {:.4}; wrote {}",
        s.steps_done,
        s.steps,
        s.wall_time_s,
        s.steps_per_second,
        s.outcome,
        s.final_observables.extension,
        s.final_observables.verticality,
        s.twist_rate,
        out.display()
    );
    if let Some(f) = &s.failure {
        anyhow::bail!("{name}: the run stopped early: {f}");
    }
    Ok(())
}

/// A positive, finite number.
pub fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a positive number, not {s:?}")),
    }
}

/// A positive number of GiB.
fn gib(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if limit_from_gib(x).is_some() => Ok(x),
        _ => Err(format!("expected a positive number of GiB, not {s:?}")),
    }
}
