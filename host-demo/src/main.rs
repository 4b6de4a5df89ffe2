//! `host-demo`: runs hydrorattle scenes, reproduces the paper's Figure 1, maps outcomes.
//! A thin command line over the host library (`hydrorattle-host`: scenes, runs,
//! trajectories, sweeps) and the Figure 1 study (`hydrorattle-study`: figures, claims,
//! charts, pictures): each subcommand parses its arguments in `cmd/` and calls them.

mod bar;
mod cmd;
mod signals;

use clap::{Parser, Subcommand};
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
    Run(cmd::run::Run),
    Resume(cmd::resume::Resume),
    Figure1(cmd::figure1::Figure1),
    Reference(cmd::reference::Reference),
    Phase(cmd::phase::Phase),
    Sweep(Box<cmd::sweep::SweepArgs>),
    Collect(cmd::collect::Collect),
    Chart(cmd::chart::Chart),
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.verbose);
    bar::install();
    let stop = signals::install();
    let done = match cli.command {
        Command::Run(c) => c.run(stop),
        Command::Resume(c) => c.run(stop),
        Command::Figure1(c) => c.run(),
        Command::Reference(c) => c.run(),
        Command::Phase(c) => c.run(),
        Command::Sweep(c) => c.run(stop, cli.verbose),
        Command::Collect(c) => c.run(),
        Command::Chart(c) => c.run(),
    };
    match done {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // A stop on request exits as the signal would have (143, 130): documented,
            // and told apart from a failure.
            signals::exit_code(&e).map_or(ExitCode::FAILURE, ExitCode::from)
        }
    }
}
