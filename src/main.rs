//! aeroform command-line interface: parses flags, builds library objects, draws progress
//! bars and writes files. No physics lives here.

mod exit;
mod interrupt;
mod models;
mod outdir;
mod progress;
mod ui;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// `--version` text: the package version and the commit it was built from (`build.rs`).
const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), " (", env!("AEROFORM_GIT"), ")");

/// Nonlinear aeroelasticity from forced-motion wind-tunnel records.
#[derive(Debug, Parser)]
#[command(name = "aeroform", version = VERSION, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print the command's result document (JSON: identification.json, flutter.json, …) on
    /// stdout and nothing else there (implies --quiet).
    #[arg(long, global = true)]
    json: bool,
    /// No human-readable output on stdout and no progress bars (errors and warnings still
    /// go to stderr).
    #[arg(long, global = true)]
    quiet: bool,
    /// Figure style: `screen` (titles in the figures) or `paper` (no titles, panel letters
    /// (a), (b) …, PNG at 300 dpi with the resolution in its metadata and a PDF beside it,
    /// 7 in wide per 1200 design pixels).
    #[arg(long, global = true, default_value = "screen", value_parser = parse_style)]
    figure_style: plots::FigureStyle,
}

fn parse_style(s: &str) -> Result<plots::FigureStyle, String> {
    plots::FigureStyle::parse(s)
}

/// The command registry: one line per command, `Variant(module::Flags) => run`, its doc
/// comment the command's help line. The macro declares the module (`src/<module>.rs`),
/// the clap subcommand and the dispatch, so a new command is one file (its flags and a
/// `run(&Flags) -> anyhow::Result<_>`) plus one line here (issue 40 item 2). A command's
/// module may use the shared layers (`models`, `outdir`, `progress`, `ui`, `exit`,
/// `interrupt`), never another command's module.
macro_rules! commands {
    ($( $(#[$meta:meta])* $variant:ident($module:ident :: $flags:ident) => $run:ident, )*) => {
        $( mod $module; )*

        #[derive(Debug, Subcommand)]
        enum Command {
            $( $(#[$meta])* $variant($module::$flags), )*
        }

        impl Command {
            /// Runs the command (its result value, if any, is written by the command).
            fn run(self) -> anyhow::Result<()> {
                match self {
                    $( Command::$variant(a) => $module::$run(&a).map(drop), )*
                }
            }
        }
    };
}

commands! {
    /// Run a study file end to end (default: the built-in quickstart study).
    Run(run_cmd::RunArgs) => run,
    /// Identify the nonlinear aerodynamic force law (Eq. 19) of a data set folder.
    Identify(identify_cmd::IdentifyArgs) => run,
    /// Linear flutter and divergence of a structure with an aerodynamic model.
    Flutter(flutter_cmd::FlutterArgs) => run,
    /// Limit-cycle oscillation at one speed or over a sweep (up and down).
    Lco(lco_cmd::LcoArgs) => run,
    /// LCO branches by continuation (stable and unstable, folds, Floquet stability).
    Branch(branch_cmd::BranchArgs) => run,
    /// Virtual wind tunnel: forced-motion or free-response data sets.
    #[command(subcommand)]
    Tunnel(tunnel_cmd::TunnelCommand) => run,
    /// Redraw the figures and report of a study output folder from its result files.
    Plot(plot_cmd::PlotArgs) => run,
    /// Sim-to-real gap: where predictions and measurements differ, which unmodelled effect
    /// causes it, how far it shrinks (`--blind N`: the withheld-effect benchmark).
    Diagnose(diagnose_cmd::DiagnoseArgs) => run,
    /// A large job (flutter/LCO map over μ, σ, x_α, r²; withheld-effect benchmark) from a
    /// JSON specification, whole or one shard (`--shard i/n`, e.g. a Slurm array task).
    Sweep(sweep_cmd::SweepArgs) => run,
    /// Merges the part documents of `--shard` runs into the document of the whole run.
    Merge(merge_cmd::MergeArgs) => run,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    ui::init(ui::Mode {
        json: cli.json,
        quiet: cli.quiet,
    });
    plots::set_figure_style(cli.figure_style);
    interrupt::install();
    let result = cli.command.run();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // escaped for the terminal and clipped: file contents quoted in an error are
            // untrusted (issue 39, rows 4 and 5)
            let msg = exit::message(&e);
            eprintln!("error: {}", ui::escape(&ui::clip(&msg, 4096)));
            ExitCode::from(exit::code(&e))
        }
    }
}

/// `aeroform <version> (<git describe>)` of the commit the binary was built from (captured
/// by `build.rs`; `commit unknown` when it was built outside a git checkout): the
/// `version` row of the study and diagnosis reports.
fn version() -> String {
    format!(
        "aeroform {} ({})",
        env!("CARGO_PKG_VERSION"),
        env!("AEROFORM_GIT")
    )
}
