//! `host-demo figure1`: the paper's Figure 1 (the main job), with its table of cases,
//! claims and pictures.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Reproduce the paper's Figure 1: three helical chains settling.
#[derive(Debug, Args)]
pub struct Figure1 {
    /// Output directory.
    #[arg(long, default_value = "out/figure1")]
    out: PathBuf,
    /// Smoke run: at most 2000 steps per case.
    #[arg(long)]
    quick: bool,
    /// Also draw snapshots.png: side views of the cases at these times (comma
    /// separated, each from 0 to the duration; each drawn at the first step at or
    /// after it).
    #[arg(
        long,
        value_name = "T1,T2,...",
        value_delimiter = ',',
        num_args = 1,
        allow_negative_numbers = true
    )]
    at: Vec<f64>,
    /// Put a no-slip wall at z = H below the chains (every sphere must start above
    /// it): each chain lands on it; figure1.json gives the landing times and the
    /// final states on the wall.
    #[arg(long, value_name = "H", allow_negative_numbers = true)]
    wall: Option<f64>,
    /// Step with Stokesian dynamics' near field (the exact two-sphere lubrication of
    /// every pair within 4 mean radii, docs/NEAR.md; the defaults of `[near_field]`):
    /// dense, some ten times the cost of a step.
    #[arg(long)]
    near_field: bool,
}

impl Figure1 {
    /// Runs the three cases and prints their table.
    pub fn run(self) -> Result<()> {
        let (out, wall) = (&self.out, self.wall);
        let near = self
            .near_field
            .then(hydrorattle_host::scene::NearField::default);
        let s = hydrorattle_study::figure1::figure1_near(
            out,
            self.quick.then_some(2000),
            &self.at,
            wall,
            near,
        )?;
        println!(
            "case  D     head   extension verticality twist_rate head_speed outcome          t(ext>=0.95) wall_s"
        );
        for c in &s.cases {
            println!(
                "{:<5} {:<5.2} {:<6.3} {:<9.3} {:<11.3} {:<10.4} {:<10.3} {:<16} {:<12} {:.2}",
                c.case,
                c.dhat,
                c.head_ratio,
                c.extension,
                c.verticality,
                c.twist_rate,
                c.head_speed,
                c.outcome,
                c.time_to_stretch
                    .map_or("never".to_string(), |t| format!("{t:.1}")),
                c.wall_time_s
            );
        }
        if let Some(h) = s.wall_height {
            println!("wall at z = {h}: case landing_time contacts gap com_height");
            for c in &s.cases {
                let landing = c
                    .landing_time
                    .map_or("never".to_string(), |t| format!("{t:.2}"));
                match c.on_wall {
                    Some(w) => println!(
                        "  {:<4} {landing:<12} {:<8} {:<10.3e} {:.3}",
                        c.case, w.contacts, w.gap, w.com_height
                    ),
                    None => println!("  {:<4} {landing}", c.case),
                }
            }
        }
        println!("claim                case verdict    window");
        for c in &s.claims {
            let window = c
                .window
                .map_or("-".to_string(), |w| format!("[{:.1}, {:.1}]", w[0], w[1]));
            println!(
                "{:<20} {:<4} {:<10} {window}",
                c.id,
                c.case,
                c.verdict.name()
            );
        }
        for line in &s.pictures {
            println!("{line}");
        }
        println!(
            "three cases in {:.2} s (parallel), pictures in {:.3} s; wrote {}/figure1.json",
            s.wall_time_s,
            s.drawing_wall_time_s,
            out.display()
        );
        Ok(())
    }
}
