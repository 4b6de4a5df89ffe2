//! `host-demo sweep FILE --out DIR`: a sweep's points run here, listed, or handed to
//! an engine (SLURM, GNU parallel, row) as a job file.

use anyhow::Result;
use clap::Args;
use hydrorattle_host::sweep::{Engine, Selection, SlurmOptions, Sweep, run};
use std::path::PathBuf;
use std::time::Instant;

use super::args::positive;

/// Run a sweep file's points in `DIR/points/ID/` (finished points skipped,
/// unfinished ones resumed), or write the job script of an engine that runs them.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The sweep file (a scene with a `[sweep]` table, or `[sweep]` with `base = ...`).
    file: PathBuf,
    /// The sweep's folder.
    #[arg(long)]
    out: PathBuf,
    /// Run shard K of N only (K from 0, as SLURM array task ids): the points whose
    /// index is K modulo N.
    #[arg(long, value_name = "K/N", conflicts_with = "point")]
    shard: Option<String>,
    /// Run this point only (its id, or a unique prefix of at least 4 characters).
    #[arg(long, value_name = "ID")]
    point: Option<String>,
    /// Points run at once (default: the CPUs available).
    #[arg(long, value_name = "J")]
    jobs: Option<usize>,
    /// Checkpoint every T of simulated time (default: about ten per run).
    #[arg(long, value_name = "T", value_parser = positive)]
    checkpoint_every: Option<f64>,
    /// Wait for points another process is running (each holds its point's lock),
    /// rather than skip them.
    #[arg(long, conflicts_with_all = ["dry_run", "emit"])]
    wait: bool,
    /// Expand and check the sweep, list its points, run nothing.
    #[arg(long, conflicts_with_all = ["shard", "point", "emit"])]
    dry_run: bool,
    /// Write the point folders and an engine's job file instead of running:
    /// DIR/slurm.sh (slurm), DIR/parallel.sh (parallel) or DIR/workflow.toml (row).
    #[arg(long, value_name = "ENGINE", value_parser = Engine::from_name, conflicts_with_all = ["shard", "point"])]
    emit: Option<Engine>,
    /// SLURM: array tasks (default: one per point, at most 1000).
    #[arg(long, value_name = "N")]
    tasks: Option<usize>,
    /// SLURM: at most M tasks at once (%M).
    #[arg(long, value_name = "M")]
    throttle: Option<usize>,
    /// SLURM: partition.
    #[arg(long)]
    partition: Option<String>,
    /// SLURM (and row): time limit per task, as HH:MM:SS.
    #[arg(long)]
    time: Option<String>,
    /// SLURM: CPUs per task; GNU parallel: jobs at once.
    #[arg(long, default_value_t = 1)]
    cpus: usize,
    /// The host-demo the engine runs (default: this program, by its absolute path).
    #[arg(long, value_name = "PATH")]
    program: Option<PathBuf>,
}

impl SweepArgs {
    /// Lists, emits or runs the selected points.
    pub fn run(self) -> Result<()> {
        let sweep = Sweep::from_path(&self.file)?;
        if self.dry_run {
            for p in &sweep.points {
                let json = hydrorattle_host::sweep::id::canonical_json(&p.statepoint);
                println!("{} {json}", p.id);
            }
            eprintln!("{} points, all valid", sweep.points.len());
            return Ok(());
        }
        if let Some(engine) = self.emit {
            let opts = SlurmOptions {
                tasks: self.tasks,
                throttle: self.throttle,
                partition: self.partition,
                time: self.time,
                cpus: self.cpus,
                program: self.program,
            };
            let (path, command) =
                hydrorattle_host::sweep::emit(engine, &sweep, &self.file, &self.out, &opts)?;
            println!(
                "{} points; wrote {}\n{command}",
                sweep.points.len(),
                path.display()
            );
            return Ok(());
        }
        let selection = match (self.shard, self.point) {
            (Some(s), _) => Selection::shard(&s)?,
            (None, Some(id)) => Selection::Point(id),
            (None, None) => Selection::All,
        };
        let jobs = self
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let t = Instant::now();
        let opts = run::Options {
            jobs,
            checkpoint_every: self.checkpoint_every,
            wait: self.wait,
        };
        let report = hydrorattle_host::sweep::run_points(&sweep, &self.out, &selection, opts)?;
        println!(
            "{report} in {:.1} s; wrote {}",
            t.elapsed().as_secs_f64(),
            self.out.display()
        );
        if !report.failed.is_empty() {
            anyhow::bail!("{} points could not be run", report.failed.len());
        }
        Ok(())
    }
}
