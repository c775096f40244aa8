//! aeroform command-line interface: parses flags, builds library objects, draws progress
//! bars and writes files. No physics lives here.

mod identify_cmd;
mod plot_cmd;
mod progress;
mod run_cmd;
mod study;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Nonlinear aeroelasticity from forced-motion wind-tunnel records.
#[derive(Debug, Parser)]
#[command(name = "aeroform", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a study file end to end (default: the built-in quickstart study).
    Run(run_cmd::RunArgs),
    /// Identify the nonlinear aerodynamic force law (Eq. 19) of a data set folder.
    Identify(identify_cmd::IdentifyArgs),
    /// Redraw the figures and report of a study output folder from its result files.
    Plot(plot_cmd::PlotArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => run_cmd::run(&a),
        Command::Identify(a) => identify_cmd::run(&a).map(|_| ()),
        Command::Plot(a) => plot_cmd::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Creates the output folder (and parents), with a message naming it on failure.
fn ensure_dir(dir: &PathBuf) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("cannot create output folder {}: {e}", dir.display()))
}
