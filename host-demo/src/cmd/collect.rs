//! `host-demo collect DIR`: a sweep's points in one table (and a chart).

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Merge a sweep's points into DIR/collected.csv; list missing and failed points
/// (exit status 1 if any).
#[derive(Debug, Args)]
pub struct Collect {
    /// The sweep's folder.
    dir: PathBuf,
    /// Chart: this parameter (a dotted key) on the horizontal axis...
    #[arg(long, requires = "y")]
    x: Option<String>,
    /// ...and this column of collected.csv on the vertical (replica means, bars:
    /// standard error).
    #[arg(long, requires = "x")]
    y: Option<String>,
}

impl Collect {
    /// Writes the table; a point not done is listed, and makes this an error.
    pub fn run(self) -> Result<()> {
        let chart = self.x.as_deref().zip(self.y.as_deref());
        let c = hydrorattle_study::collect::collect(&self.dir, chart)?;
        println!("{} points; wrote {}", c.points, c.csv.display());
        if let Some(p) = &c.chart {
            println!("wrote {}", p.display());
        }
        if !c.problems.is_empty() {
            for (id, status, why) in &c.problems {
                println!("{id} {status} {why}");
            }
            anyhow::bail!("{} of {} points are not done", c.problems.len(), c.points);
        }
        Ok(())
    }
}
