//! `host-demo run SCENE --out DIR`: one scene file's run, then its pictures.

use anyhow::Result;
use clap::Args;
use hydrorattle_host::sim::{RunOptions, Stop};
use std::path::PathBuf;

use super::args::{RunLimits, positive, report};

/// Run one scene file and write its trajectory, observables and summary.
#[derive(Debug, Args)]
pub struct Run {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    limits: RunLimits,
    /// Write DIR/checkpoint.json every T of simulated time (rounded to whole steps),
    /// for `host-demo resume`.
    #[arg(long, value_name = "T", value_parser = positive)]
    checkpoint_every: Option<f64>,
}

impl Run {
    /// Runs the scene, then draws its pictures from the result (a picture that cannot
    /// be drawn is reported; the run's files stay).
    /// SIGTERM or Ctrl-C (`stop`) checkpoints the run and ends it (exit status 143 or
    /// 130); `host-demo resume` continues it.
    pub fn run(self, stop: Stop) -> Result<()> {
        let limits = self.limits.limits();
        let opts = RunOptions {
            threads: self.limits.threads,
            stop,
            ..RunOptions::files(limits, self.checkpoint_every, true)
        };
        let r = hydrorattle_host::sim::run_scene_file_with(&self.scene, &self.out, limits, opts)?;
        hydrorattle_study::pictures::draw_run(&self.out, &r, true)?;
        let name = hydrorattle_host::sim::scene_name(&self.scene);
        report(&name, &r.summary, &self.out)
    }
}
