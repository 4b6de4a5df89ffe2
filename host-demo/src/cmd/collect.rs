//! `host-demo collect DIR`: a sweep's points in one table (and a chart).

use anyhow::Result;
use clap::Args;
use hydrorattle_host::sweep::cluster::ArrayJob;
use std::path::PathBuf;

/// Merge a sweep's points into DIR/collected.csv; list the points not done (exit
/// status 1 if any), with their array task and the `sbatch --array=...` line that
/// reruns only those when the sweep was emitted for SLURM.
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
            // With an emitted array job: each point's task, and the line that reruns
            // the tasks of the points a rerun would run.
            let job = ArrayJob::read(&self.dir)?;
            for p in &c.problems {
                let task = job.as_ref().map_or(String::new(), |j| {
                    format!(" [array task {}]", j.task_of(p.index))
                });
                println!("{} {}{task} {}", p.id, p.status, p.why);
            }
            let rerun: Vec<usize> = c
                .problems
                .iter()
                .filter(|p| p.reruns())
                .map(|p| p.index)
                .collect();
            if let Some(line) = job.as_ref().and_then(|j| j.rerun(&rerun)) {
                println!("{} points to run again: {line}", rerun.len());
            }
            let running = c.problems.iter().filter(|p| p.status == "running").count();
            if running > 0 {
                println!("{running} points running now (not to be submitted again)");
            }
            anyhow::bail!("{} of {} points are not done", c.problems.len(), c.points);
        }
        Ok(())
    }
}
