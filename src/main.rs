//! aeroform command-line interface: parses flags, builds library objects, draws progress
//! bars and writes files. No physics lives here.

mod diagnose_cmd;
mod flutter_cmd;
mod identify_cmd;
mod interrupt;
mod lco_cmd;
mod plot_cmd;
mod progress;
mod run_cmd;
mod study;
mod tunnel_cmd;

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
    /// Linear flutter and divergence of a structure with an aerodynamic model.
    Flutter(flutter_cmd::FlutterArgs),
    /// Limit-cycle oscillation at one speed or over a sweep (up and down).
    Lco(lco_cmd::LcoArgs),
    /// Virtual wind tunnel: forced-motion or free-response data sets.
    #[command(subcommand)]
    Tunnel(tunnel_cmd::TunnelCommand),
    /// Redraw the figures and report of a study output folder from its result files.
    Plot(plot_cmd::PlotArgs),
    /// Sim-to-real gap: where predictions and measurements differ, which unmodelled effect
    /// causes it, how far it shrinks (`--blind N`: the withheld-effect benchmark).
    Diagnose(diagnose_cmd::DiagnoseArgs),
}

/// Heap retention fix (docs/SCALE.md finding 1): glibc's dynamic mmap threshold rises to
/// the size of the largest freed block (up to 32 MB), after which the large per-case
/// temporaries of identification are served from the thread arenas, interleave with the
/// long-lived columns and are never returned: 448 cases × 60 s peaked at 7.3 GB instead of
/// 1.2 GB. A fixed 1 MiB threshold (which also disables the dynamic adjustment) serves every
/// block of 1 MiB or more by `mmap` and returns it on free. An explicit
/// `MALLOC_MMAP_THRESHOLD_` in the environment is respected, and
/// `AEROFORM_MALLOC_DEFAULTS=1` keeps glibc's defaults (for measurements,
/// benches/scale/run.sh).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn bound_heap_retention() {
    let keep = std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_some()
        || std::env::var_os("AEROFORM_MALLOC_DEFAULTS").is_some_and(|v| v == "1");
    if !keep {
        // SAFETY: `mallopt` only changes allocator parameters; it is called first thing in
        // `main`, before any other thread exists.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
        }
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn bound_heap_retention() {}

fn main() -> ExitCode {
    bound_heap_retention();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => run_cmd::run(&a),
        Command::Identify(a) => identify_cmd::run(&a).map(|_| ()),
        Command::Flutter(a) => flutter_cmd::run(&a),
        Command::Lco(a) => lco_cmd::run(&a),
        Command::Tunnel(c) => tunnel_cmd::run(&c),
        Command::Plot(a) => plot_cmd::run(&a),
        Command::Diagnose(a) => diagnose_cmd::run(&a),
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
