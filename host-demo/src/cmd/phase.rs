//! `host-demo phase`: the outcome map and the sensitivity table.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Outcome phase diagram over the bond gap D and the head ratio.
#[derive(Debug, Args)]
pub struct Phase {
    /// Output directory.
    #[arg(long, default_value = "out/phase")]
    out: PathBuf,
    /// Grid points per axis (at least 2).
    #[arg(long, default_value_t = 6)]
    grid: usize,
    /// Smoke run: at most 500 steps per cell.
    #[arg(long)]
    quick: bool,
    /// Skip the sensitivity table.
    #[arg(long)]
    no_sensitivity: bool,
}

impl Phase {
    /// Draws the map, then (unless skipped) writes the sensitivity tables.
    pub fn run(self) -> Result<()> {
        let (out, grid) = (&self.out, self.grid);
        anyhow::ensure!(grid >= 2, "--grid must be at least 2");
        let cap = self.quick.then_some(500);
        let t = Instant::now();
        hydrorattle_study::phase::phase(out, grid, cap)?;
        println!(
            "phase map ({grid} x {grid}) in {:.1} s: wrote {}/phase.png and phase.csv",
            t.elapsed().as_secs_f64(),
            out.display()
        );
        if !self.no_sensitivity {
            let t = Instant::now();
            let table = hydrorattle_study::phase::sensitivity(out, cap)?;
            print!("claims: in how many variants each holds\n{table}");
            println!(
                "sensitivity table in {:.1} s: wrote {}/sensitivity.csv, \
                 claims_sensitivity.csv and claims_variants.csv",
                t.elapsed().as_secs_f64(),
                out.display()
            );
        }
        Ok(())
    }
}
