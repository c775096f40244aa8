//! `aeroform run [STUDY] [--out DIR]`: runs a study end to end (the built-in quickstart
//! when no file is given) and prints the time of each stage.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use crate::study::{run::run_study, Study};

/// Flags of `aeroform run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Study file (TOML); default: the built-in quickstart study.
    pub study: Option<PathBuf>,
    /// Output folder (default `out/<study name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Override the study's seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Do not print the identification summary.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the study.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let mut study = match &args.study {
        Some(p) => Study::read(p)?,
        None => Study::quickstart()?,
    };
    if let Some(s) = args.seed {
        study.spec.seed = s;
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&study.spec.name));
    let t0 = Instant::now();
    let timings = run_study(&study, &out, args.quiet)?;
    println!(
        "study `{}` ({}) done; results in {}",
        study.spec.name,
        study.path.display(),
        out.display()
    );
    for (stage, s) in &timings {
        println!("  {stage:<16} {s:>8.2} s");
    }
    println!("  {:<16} {:>8.2} s", "total", t0.elapsed().as_secs_f64());
    Ok(())
}
