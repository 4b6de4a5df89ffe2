//! `host-demo chart`: accuracy and speed charts of the integrators and solvers.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Accuracy and speed charts of the integrators and solvers.
#[derive(Debug, Args)]
pub struct Chart {
    /// Output directory.
    #[arg(long, default_value = "out/charts")]
    out: PathBuf,
    /// Smoke run: fewer and shorter runs.
    #[arg(long)]
    quick: bool,
}

impl Chart {
    /// Runs the charts' studies and prints their notes.
    pub fn run(self) -> Result<()> {
        let t = Instant::now();
        for note in hydrorattle_study::charts::charts(&self.out, self.quick)? {
            println!("{note}");
        }
        println!(
            "charts in {:.1} s: wrote {}",
            t.elapsed().as_secs_f64(),
            self.out.display()
        );
        Ok(())
    }
}
