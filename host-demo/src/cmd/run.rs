//! `host-demo run SCENE --out DIR`: one scene file's run, then its pictures.

use anyhow::Result;
use clap::Args;
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
    pub fn run(self) -> Result<()> {
        let r = hydrorattle_host::sim::run_scene_file(
            &self.scene,
            &self.out,
            self.limits.limits(),
            self.checkpoint_every,
            true,
            self.limits.threads,
        )?;
        hydrorattle_study::pictures::draw_run(&self.out, &r, true)?;
        let name = hydrorattle_host::sim::scene_name(&self.scene);
        report(&name, &r.summary, &self.out)
    }
}
