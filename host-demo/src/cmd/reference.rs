//! `host-demo reference`: Figure 1's trajectories against a small-dt reference.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

use super::args::positive;

/// Figure 1's trajectories against a reference at a small time step: RMS deviation
/// over time and agreement horizons of the main job's settings and alternatives.
#[derive(Debug, Args)]
pub struct Reference {
    /// Output directory.
    #[arg(long, default_value = "out/reference")]
    out: PathBuf,
    /// Time step of the reference.
    #[arg(long, default_value_t = 0.005, value_parser = positive)]
    dt: f64,
    /// Smoke run: at most 2000 steps per run.
    #[arg(long)]
    quick: bool,
}

impl Reference {
    /// Runs the reference and the variants, prints horizons and verdicts; a full run
    /// whose main-job verdicts differ from the reference's is an error.
    pub fn run(self) -> Result<()> {
        let (out, dt, quick) = (&self.out, self.dt, self.quick);
        let report = hydrorattle_study::reference::reference(out, dt, quick.then_some(2000))?;
        println!(
            "case variant                     method       dt      horizon(>0.1a) horizon(>0.5a) outcome (reference)"
        );
        for c in &report.cases {
            for v in &c.variants {
                let h = |x: Option<f64>| x.map_or("never".to_string(), |t| format!("{t}"));
                println!(
                    "{:<4} {:<27} {:<12} {:<7} {:<14} {:<14} {} ({})",
                    c.case,
                    v.variant.name,
                    format!("{:?}", v.variant.method),
                    v.variant.dt,
                    h(v.horizons[0]),
                    h(v.horizons[1]),
                    v.outcome,
                    c.reference_outcome
                );
            }
        }
        println!(
            "\nclaim                reference  {}",
            report.variant_names.join(" | ")
        );
        for v in &report.verdicts {
            let others: Vec<String> = v.variants.iter().map(|x| format!("{x:?}")).collect();
            println!(
                "{:<20} {:<10} {}",
                v.id,
                format!("{:?}", v.reference),
                others.join(" | ")
            );
        }
        println!("wrote {}", out.join("reference.json").display());
        // The main job's verdicts must be the reference's (a full run only: a smoke
        // run's claims mean little).
        let differ: Vec<&str> = report
            .verdicts
            .iter()
            .filter(|v| v.variants.first() != Some(&v.reference))
            .map(|v| v.id.as_str())
            .collect();
        if !quick && !differ.is_empty() {
            anyhow::bail!(
                "the main job's verdicts differ from the dt = {dt} reference's: {}",
                differ.join(", ")
            );
        }
        Ok(())
    }
}
