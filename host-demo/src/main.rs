//! `host-demo`: runs hydrorattle scenes, reproduces the paper's Figure 1, maps outcomes.

use anyhow::Result;
use clap::{Parser, Subcommand};
use host_demo::sim::{RunOptions, Summary};
use host_demo::sizing::{DEFAULT_LIMIT, DEFAULT_OUTPUT_LIMIT, Limits, limit_from_gib};
use std::path::PathBuf;
use std::process::ExitCode;

/// Settling bead chains and aggregates in Stokes flow with exact bond constraints
/// (HydroRATTLE).
#[derive(Debug, Parser)]
#[command(name = "host-demo", version, about, long_about = None)]
struct Cli {
    /// More log output: -v info, -vv debug, -vvv trace (RUST_LOG overrides).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,

    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run one scene file and write its trajectory, observables and summary.
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Largest step storage allowed, GiB: a scene needing more is refused before
        /// anything is built (storage grows as the square of the bead count).
        #[arg(long, default_value_t = (DEFAULT_LIMIT >> 30) as f64, value_name = "GIB", value_parser = gib)]
        max_storage: f64,
        /// Largest trajectory output allowed, GiB: a scene whose frames would need more
        /// is refused while it is read (at its `every` or `duration` line).
        #[arg(long, default_value_t = (DEFAULT_OUTPUT_LIMIT >> 30) as f64, value_name = "GIB", value_parser = gib)]
        max_output: f64,
        /// Write DIR/checkpoint.json every T of simulated time (rounded to whole steps),
        /// for `host-demo resume`.
        #[arg(long, value_name = "T", value_parser = positive)]
        checkpoint_every: Option<f64>,
        /// Threads for the mobility of scenes from 512 beads on (0: every core); the
        /// trajectory's bits do not depend on it.
        #[arg(long, default_value_t = 0)]
        threads: usize,
    },
    /// Continue a run from its checkpoint (DIR/checkpoint.json, DIR/scene.toml) to a
    /// later time: the same bytes as one run to that time.
    Resume {
        /// The output directory of the run.
        dir: PathBuf,
        /// Simulated time to run to.
        #[arg(long, value_name = "T", value_parser = positive)]
        until: f64,
        /// Keep writing checkpoints every T of simulated time.
        #[arg(long, value_name = "T", value_parser = positive)]
        checkpoint_every: Option<f64>,
        /// As for `run`.
        #[arg(long, default_value_t = (DEFAULT_LIMIT >> 30) as f64, value_name = "GIB", value_parser = gib)]
        max_storage: f64,
        /// As for `run`.
        #[arg(long, default_value_t = (DEFAULT_OUTPUT_LIMIT >> 30) as f64, value_name = "GIB", value_parser = gib)]
        max_output: f64,
        /// As for `run`.
        #[arg(long, default_value_t = 0)]
        threads: usize,
    },
    /// Reproduce the paper's Figure 1: three helical chains settling.
    Figure1 {
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
    },
    /// Figure 1's trajectories against a reference at a small time step: RMS deviation
    /// over time and agreement horizons of the main job's settings and alternatives.
    Reference {
        /// Output directory.
        #[arg(long, default_value = "out/reference")]
        out: PathBuf,
        /// Time step of the reference.
        #[arg(long, default_value_t = 0.005, value_parser = positive)]
        dt: f64,
        /// Smoke run: at most 2000 steps per run.
        #[arg(long)]
        quick: bool,
    },
    /// Outcome phase diagram over the bond gap D and the head ratio.
    Phase {
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
    },
    /// Run a sweep file's points in DIR/points/<id>/ (finished points skipped,
    /// unfinished ones resumed), or write the job script of an engine that runs them.
    Sweep {
        /// The sweep file (a scene with a [sweep] table, or [sweep] with base = ...).
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
        /// Expand and check the sweep, list its points, run nothing.
        #[arg(long, conflicts_with_all = ["shard", "point", "emit"])]
        dry_run: bool,
        /// Write the point folders and an engine's job file instead of running:
        /// DIR/slurm.sh, DIR/parallel.sh or DIR/workflow.toml (row).
        #[arg(long, value_enum, conflicts_with_all = ["shard", "point"])]
        emit: Option<host_demo::sweep::Engine>,
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
    },
    /// Merge a sweep's points into DIR/collected.csv; list missing and failed points
    /// (exit status 1 if any).
    Collect {
        /// The sweep's folder.
        dir: PathBuf,
        /// Chart: this parameter (a dotted key) on the horizontal axis...
        #[arg(long, requires = "y")]
        x: Option<String>,
        /// ...and this column of collected.csv on the vertical (replica means, bars:
        /// standard error).
        #[arg(long, requires = "x")]
        y: Option<String>,
    },
    /// Accuracy and speed charts of the integrators and solvers.
    Chart {
        /// Output directory.
        #[arg(long, default_value = "out/charts")]
        out: PathBuf,
        /// Smoke run: fewer and shorter runs.
        #[arg(long)]
        quick: bool,
    },
}

fn init_logging(verbose: u8) {
    let level = match verbose {
        0 => log::LevelFilter::Warn,
        1 => log::LevelFilter::Info,
        2 => log::LevelFilter::Debug,
        _ => log::LevelFilter::Trace,
    };
    let mut builder = env_logger::Builder::new();
    builder.filter_level(level);
    if let Ok(spec) = std::env::var("RUST_LOG") {
        builder.parse_filters(&spec);
    }
    builder.format_timestamp_millis().init();
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run {
            scene: scene_path,
            out,
            max_storage,
            max_output,
            checkpoint_every,
            threads,
        } => {
            let limits = limits(max_storage, max_output);
            let r = host_demo::sim::run_scene_file(
                &scene_path,
                &out,
                limits,
                checkpoint_every,
                true,
                threads,
            )?;
            let name = host_demo::sim::scene_name(&scene_path);
            report(&name, &r.summary, &out)?;
        }
        Command::Resume {
            dir,
            until,
            checkpoint_every,
            max_storage,
            max_output,
            threads,
        } => {
            let limits = limits(max_storage, max_output);
            let opts = RunOptions {
                threads,
                ..RunOptions::files(limits, checkpoint_every, true)
            };
            let r = host_demo::sim::resume(&dir, until, limits, opts)?;
            host_demo::pictures::draw_run(&dir, &r, false)?;
            report(&r.summary.scene.clone(), &r.summary, &dir)?;
        }
        Command::Reference { out, dt, quick } => {
            let report = host_demo::reference::reference(&out, dt, quick.then_some(2000))?;
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
        }
        Command::Figure1 {
            out,
            quick,
            at,
            wall,
        } => {
            let s = host_demo::figure1::figure1_wall(&out, quick.then_some(2000), &at, wall)?;
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
        }
        Command::Phase {
            out,
            grid,
            quick,
            no_sensitivity,
        } => {
            anyhow::ensure!(grid >= 2, "--grid must be at least 2");
            let cap = quick.then_some(500);
            let t = std::time::Instant::now();
            host_demo::phase::phase(&out, grid, cap)?;
            println!(
                "phase map ({grid} x {grid}) in {:.1} s: wrote {}/phase.png and phase.csv",
                t.elapsed().as_secs_f64(),
                out.display()
            );
            if !no_sensitivity {
                let t = std::time::Instant::now();
                let table = host_demo::phase::sensitivity(&out, cap)?;
                print!("claims: in how many variants each holds\n{table}");
                println!(
                    "sensitivity table in {:.1} s: wrote {}/sensitivity.csv, \
                     claims_sensitivity.csv and claims_variants.csv",
                    t.elapsed().as_secs_f64(),
                    out.display()
                );
            }
        }
        Command::Sweep {
            file,
            out,
            shard,
            point,
            jobs,
            checkpoint_every,
            dry_run,
            emit,
            tasks,
            throttle,
            partition,
            time,
            cpus,
            program,
        } => {
            use host_demo::sweep::{Selection, Sweep, run};
            let sweep = Sweep::from_path(&file)?;
            if dry_run {
                for p in &sweep.points {
                    println!(
                        "{} {}",
                        p.id,
                        host_demo::sweep::id::canonical_json(&p.statepoint)
                    );
                }
                eprintln!("{} points, all valid", sweep.points.len());
                return Ok(());
            }
            if let Some(engine) = emit {
                let opts = host_demo::sweep::SlurmOptions {
                    tasks,
                    throttle,
                    partition,
                    time,
                    cpus,
                    program,
                };
                let (path, command) = host_demo::sweep::emit(engine, &sweep, &file, &out, &opts)?;
                println!(
                    "{} points; wrote {}\n{command}",
                    sweep.points.len(),
                    path.display()
                );
                return Ok(());
            }
            let selection = match (shard, point) {
                (Some(s), _) => Selection::shard(&s)?,
                (None, Some(id)) => Selection::Point(id),
                (None, None) => Selection::All,
            };
            let jobs =
                jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let t = std::time::Instant::now();
            let opts = run::Options {
                jobs,
                checkpoint_every,
            };
            let report = host_demo::sweep::run_points(&sweep, &out, &selection, opts)?;
            println!(
                "{report} in {:.1} s; wrote {}",
                t.elapsed().as_secs_f64(),
                out.display()
            );
            if !report.failed.is_empty() {
                anyhow::bail!("{} points could not be run", report.failed.len());
            }
        }
        Command::Collect { dir, x, y } => {
            let chart = x.as_deref().zip(y.as_deref());
            let c = host_demo::sweep::collect(&dir, chart)?;
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
        }
        Command::Chart { out, quick } => {
            let t = std::time::Instant::now();
            for note in host_demo::charts::charts(&out, quick)? {
                println!("{note}");
            }
            println!(
                "charts in {:.1} s: wrote {}",
                t.elapsed().as_secs_f64(),
                out.display()
            );
        }
    }
    Ok(())
}

/// The limits a scene is read under.
fn limits(max_storage: f64, max_output: f64) -> Limits {
    Limits {
        storage: limit_from_gib(max_storage).unwrap_or(DEFAULT_LIMIT),
        output: limit_from_gib(max_output).map_or(DEFAULT_OUTPUT_LIMIT, |b| b as u64),
    }
}

/// Prints a run's one-line report; a run that stopped early is an error.
fn report(name: &str, s: &Summary, out: &std::path::Path) -> Result<()> {
    println!(
        "{name}: {} of {} steps in {:.2} s ({:.0} steps/s); outcome {}; extension {:.3}, verticality {:.3}, twist rate {:.4}; wrote {}",
        s.steps_done,
        s.steps,
        s.wall_time_s,
        s.steps_per_second,
        s.outcome,
        s.final_observables.extension,
        s.final_observables.verticality,
        s.twist_rate,
        out.display()
    );
    if let Some(f) = &s.failure {
        anyhow::bail!("{name}: the run stopped early: {f}");
    }
    Ok(())
}

/// A positive, finite number.
fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a positive number, not {s:?}")),
    }
}

/// A positive number of GiB.
fn gib(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if limit_from_gib(x).is_some() => Ok(x),
        _ => Err(format!("expected a positive number of GiB, not {s:?}")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.verbose);
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
