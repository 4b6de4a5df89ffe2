//! `host-demo resume DIR --until T`: a run continued from its checkpoint.

use anyhow::Result;
use clap::Args;
use hydrorattle_host::sim::{RunOptions, Stop};
use std::path::PathBuf;

use super::args::{RunLimits, positive, report};

/// Continue a run from its checkpoint (DIR/checkpoint.json, DIR/scene.toml) to a
/// later time: the same bytes as one run to that time.
#[derive(Debug, Args)]
pub struct Resume {
    /// The output directory of the run.
    dir: PathBuf,
    /// Simulated time to run to.
    #[arg(long, value_name = "T", value_parser = positive)]
    until: f64,
    /// Keep writing checkpoints every T of simulated time.
    #[arg(long, value_name = "T", value_parser = positive)]
    checkpoint_every: Option<f64>,
    #[command(flatten)]
    limits: RunLimits,
}

impl Resume {
    /// Resumes the run, then draws its pictures.
    /// SIGTERM or Ctrl-C (`stop`) checkpoints it again and ends it (143 or 130).
    pub fn run(self, stop: Stop) -> Result<()> {
        let limits = self.limits.limits();
        let opts = RunOptions {
            threads: self.limits.threads,
            stop,
            ..RunOptions::files(limits, self.checkpoint_every, true)
        };
        let r = hydrorattle_host::sim::resume(&self.dir, self.until, limits, opts)?;
        hydrorattle_study::pictures::draw_run(&self.dir, &r, false)?;
        report(&r.summary.scene.clone(), &r.summary, &self.dir)
    }
}
