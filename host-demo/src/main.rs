//! `host-demo`: runs hydrorattle scenes, reproduces the paper's Figure 1, maps outcomes.

use anyhow::Result;
use clap::{Parser, Subcommand};
use host_demo::scene::Scene;
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
    },
    /// Reproduce the paper's Figure 1: three helical chains settling.
    Figure1 {
        /// Output directory.
        #[arg(long, default_value = "out/figure1")]
        out: PathBuf,
    },
    /// Outcome phase diagram over the bond gap D and the head ratio.
    Phase {
        /// Output directory.
        #[arg(long, default_value = "out/phase")]
        out: PathBuf,
    },
    /// Accuracy and speed charts of the integrators and solvers.
    Chart {
        /// Output directory.
        #[arg(long, default_value = "out/charts")]
        out: PathBuf,
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
        Command::Run { scene, out } => {
            let scene = Scene::from_path(&scene)?;
            log::info!(
                "scene: {} particles, {} bonds, {:?}, {} steps",
                scene.particles.len(),
                scene.bonds.len(),
                scene.integrator.method,
                scene.integrator.steps()
            );
            println!("run: not wired yet (would write to {})", out.display());
        }
        Command::Figure1 { out } => {
            let cases = Scene::figure1()?;
            log::info!("figure 1: {} cases", cases.len());
            println!("figure1: not wired yet (would write to {})", out.display());
        }
        Command::Phase { out } => {
            println!("phase: not wired yet (would write to {})", out.display());
        }
        Command::Chart { out } => {
            println!("chart: not wired yet (would write to {})", out.display());
        }
    }
    Ok(())
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
