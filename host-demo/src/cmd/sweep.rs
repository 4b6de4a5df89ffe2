//! `host-demo sweep FILE --out DIR`: a sweep's points run here, listed, or handed to
//! an engine (SLURM, GNU parallel, row) as a job file; `host-demo sweep --frozen --out
//! DIR`: the points frozen in DIR when it was emitted (what the engines' tasks run).

use anyhow::Result;
use clap::Args;
use hydrorattle_host::sim::Stop;
use hydrorattle_host::sweep::{Engine, Selection, SlurmOptions, Sweep, run};
use std::path::PathBuf;
use std::time::Instant;

use super::args::positive;
use crate::signals::Stopped;

/// Run a sweep file's points in `DIR/points/ID/` (finished points skipped,
/// unfinished ones resumed), or write the job script of an engine that runs them.
/// SIGTERM or Ctrl-C checkpoints the running points and starts no other (exit status
/// 143 or 130); running the same command again goes on.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The sweep file (a scene with a `[sweep]` table, or `[sweep]` with `base = ...`).
    #[arg(required_unless_present = "frozen")]
    file: Option<PathBuf>,
    /// The sweep's folder (one sweep per folder: another sweep's is refused).
    #[arg(long)]
    out: PathBuf,
    /// Run the points frozen in DIR (`DIR/frozen`, `DIR/sweep.json`) when the sweep was
    /// emitted or first run, reading no sweep file: what the emitted tasks run.
    #[arg(long, conflicts_with_all = ["file", "emit", "dry_run"])]
    frozen: bool,
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
    /// Checkpoint every T of simulated time (default: about ten per run); emitted
    /// scripts pass it on.
    #[arg(long, value_name = "T", value_parser = positive)]
    checkpoint_every: Option<f64>,
    /// Wait for points another process is running (each holds its point's lock),
    /// rather than skip them.
    #[arg(long, conflicts_with_all = ["dry_run", "emit"])]
    wait: bool,
    /// Expand and check the sweep, list its points (id and state point, in sweep
    /// order), run and write nothing. With --emit: check every setting and print the
    /// job file that would be written, writing nothing.
    #[arg(long, conflicts_with_all = ["shard", "point"])]
    dry_run: bool,
    /// Write the point folders, the frozen scenes and an engine's job file instead of
    /// running: DIR/slurm.sh (slurm), DIR/parallel.sh (parallel) or DIR/workflow.toml
    /// (row). Every setting is checked before anything is written.
    #[arg(long, value_name = "ENGINE", value_parser = Engine::from_name, conflicts_with_all = ["shard", "point"])]
    emit: Option<Engine>,
    /// SLURM: array tasks, at least 1 and at most the points (default: one per point,
    /// at most 1000).
    #[arg(long, value_name = "N")]
    tasks: Option<usize>,
    /// SLURM: at most M tasks at once (%M).
    #[arg(long, value_name = "M")]
    throttle: Option<usize>,
    /// SLURM: partition.
    #[arg(long)]
    partition: Option<String>,
    /// SLURM (and row): time limit per task: minutes, MM:SS, HH:MM:SS, D-HH,
    /// D-HH:MM, D-HH:MM:SS, or infinite (SLURM only).
    #[arg(long)]
    time: Option<String>,
    /// SLURM: memory per node (4G, 4GB, 500M).
    #[arg(long)]
    mem: Option<String>,
    /// SLURM: the job's name (default hydrorattle-sweep).
    #[arg(long, value_name = "NAME")]
    job_name: Option<String>,
    /// SLURM: SIGTERM this many seconds before the time limit, for the running steps to
    /// end and checkpoint (default 60; give more when a step takes longer).
    #[arg(long, value_name = "S")]
    signal_lead: Option<u32>,
    /// SLURM: another sbatch option, written as an #SBATCH line as given
    /// (`--sbatch-arg=--gres=gpu:1`); repeat for more.
    #[arg(long, value_name = "OPTION", allow_hyphen_values = true)]
    sbatch_arg: Vec<String>,
    /// SLURM: account charged.
    #[arg(long)]
    account: Option<String>,
    /// SLURM: quality of service.
    #[arg(long)]
    qos: Option<String>,
    /// SLURM: node features required.
    #[arg(long)]
    constraint: Option<String>,
    /// SLURM: CPUs per task; GNU parallel: jobs at once.
    #[arg(long, default_value_t = 1)]
    cpus: usize,
    /// The host-demo the engine runs (default: this program, by its absolute path).
    #[arg(long, value_name = "PATH")]
    program: Option<PathBuf>,
}

impl SweepArgs {
    /// Lists, emits or runs the selected points; `stop` ends the run between steps,
    /// `verbose` is passed on to emitted tasks.
    pub fn run(self, stop: Stop, verbose: u8) -> Result<()> {
        let selection = match (&self.shard, &self.point) {
            (Some(s), _) => Selection::shard(s)?,
            (None, Some(id)) => Selection::Point(id.clone()),
            (None, None) => Selection::All,
        };
        let jobs = self
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let opts = run::Options {
            jobs,
            checkpoint_every: self.checkpoint_every,
            wait: self.wait,
            stop,
        };
        let t = Instant::now();
        let report = match &self.file {
            None => hydrorattle_host::sweep::run_frozen(&self.out, &selection, opts)?,
            Some(file) if self.dry_run => {
                return match self.emit {
                    Some(engine) => self.preview(engine, &Sweep::from_path(file)?, file, verbose),
                    None => list(file),
                };
            }
            Some(file) => match (&selection, self.emit) {
                (Selection::Point(id), None) => {
                    hydrorattle_host::sweep::run_point_of_file(file, &self.out, id, opts)?
                }
                (_, Some(engine)) => {
                    return self.emit(engine, &Sweep::from_path(file)?, file, verbose);
                }
                (_, None) => {
                    let sweep = Sweep::from_path(file)?;
                    hydrorattle_host::sweep::run_points(&sweep, &self.out, &selection, opts)?
                }
            },
        };
        println!(
            "{report} in {:.1} s; wrote {}",
            t.elapsed().as_secs_f64(),
            self.out.display()
        );
        if let Some(sig) = report.signal {
            return Err(Stopped(sig).into());
        }
        if !report.failed.is_empty() {
            anyhow::bail!("{} points could not be run", report.failed.len());
        }
        Ok(())
    }

    /// The engine settings as given.
    fn slurm(&self, verbose: u8) -> SlurmOptions {
        SlurmOptions {
            tasks: self.tasks,
            throttle: self.throttle,
            partition: self.partition.clone(),
            time: self.time.clone(),
            mem: self.mem.clone(),
            account: self.account.clone(),
            qos: self.qos.clone(),
            constraint: self.constraint.clone(),
            cpus: self.cpus,
            program: self.program.clone(),
            checkpoint_every: self.checkpoint_every,
            verbose,
            job_name: self.job_name.clone(),
            signal_lead: self.signal_lead,
            extra: self.sbatch_arg.clone(),
        }
    }

    /// Prints the engine's job file, writing nothing.
    fn preview(
        &self,
        engine: Engine,
        sweep: &Sweep,
        file: &std::path::Path,
        verbose: u8,
    ) -> Result<()> {
        let opts = self.slurm(verbose);
        let job = hydrorattle_host::sweep::emit::job_file(engine, sweep, file, &self.out, &opts)?;
        print!("{}", job.text);
        eprintln!(
            "{} points; would write {} (and the point folders); nothing written\n{}",
            sweep.points.len(),
            job.path.display(),
            job.command
        );
        Ok(())
    }

    /// Writes the engine's job file.
    fn emit(
        &self,
        engine: Engine,
        sweep: &Sweep,
        file: &std::path::Path,
        verbose: u8,
    ) -> Result<()> {
        let opts = self.slurm(verbose);
        let (path, command) = hydrorattle_host::sweep::emit(engine, sweep, file, &self.out, &opts)?;
        println!(
            "{} points; wrote {}\n{command}",
            sweep.points.len(),
            path.display()
        );
        Ok(())
    }
}

/// `--dry-run`: checks every point of the sweep file (each scene resolved and let go)
/// and lists their ids and state points in sweep order.
fn list(file: &std::path::Path) -> Result<()> {
    use std::io::Write;
    let points = Sweep::check_path(file)?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (id, statepoint) in &points {
        writeln!(out, "{id} {statepoint}")?;
    }
    out.flush()?;
    eprintln!("{} points, all valid; nothing run or written", points.len());
    Ok(())
}
