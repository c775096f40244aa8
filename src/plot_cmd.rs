//! `aeroform plot OUTDIR`: redraws the figures and the report of a finished study from its
//! result files (`study.toml`, `identification.json`, `series/`, `flutter.json`,
//! `lco.json`, …) without recomputing anything.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use plots::study_report::render_all;
use study::run::names;
use study::Study;

/// Flags of `aeroform plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// Output folder of an earlier `aeroform run`.
    pub outdir: PathBuf,
}

/// Redraws figures and report.
pub fn run(args: &PlotArgs) -> anyhow::Result<()> {
    crate::outdir::check_complete(&args.outdir)?;
    let _lock = crate::outdir::Lock::for_folder(&args.outdir)?;
    let path = args.outdir.join(names::STUDY);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{} is not a study output folder", args.outdir.display()))?;
    // relative data paths are not needed: nothing is recomputed
    let study = Study::parse(&text, &path, &args.outdir)?;
    let figs = render_all(&study, &args.outdir, &crate::version())?;
    crate::ui::say!(
        "redrew {} figures and {}",
        figs.len(),
        args.outdir.join(names::REPORT).display()
    );
    crate::ui::document(&figs)
}
