//! `aeroform merge OUT PART...`: the part documents of `--shard` runs (`aeroform sweep`,
//! `aeroform diagnose --blind N --shard i/n`) merged into the document of the unsplit run
//! (`benchmark::sweep::merge`; docs/PYTHON.md "Scale-out").

use std::path::PathBuf;

use anyhow::Context;
use benchmark::sweep::merge;
use clap::Args;

use crate::outdir::Input;

/// Flags of `aeroform merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Output file: the document of the whole sweep.
    pub out: PathBuf,
    /// Part documents written by `--shard` runs (any order).
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
}

/// Runs `aeroform merge`. An OUT that is one of the parts (the same file, by any path) is
/// refused before anything is read or written.
pub fn run(args: &MergeArgs) -> anyhow::Result<()> {
    let same = |a: &std::path::Path, b: &std::path::Path| match (a.canonicalize(), b.canonicalize())
    {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    };
    if let Some(p) = args.parts.iter().find(|p| same(&args.out, p)) {
        crate::exit::refuse!(
            "merge: OUT {} is also one of the parts ({}); give a new file for the merged document",
            args.out.display(),
            p.display()
        );
    }
    let parts = args
        .parts
        .iter()
        .map(|p| {
            let text =
                identify::io::read_text(p).with_context(|| format!("reading {}", p.display()))?;
            let v: serde_json::Value = serde_json::from_str(&text)
                .with_context(|| format!("{}: not JSON", p.display()))?;
            Ok((p.display().to_string(), v))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let doc = merge(&parts)?;
    let inputs: Vec<_> = args.parts.iter().map(|p| Input::new("PART", p)).collect();
    crate::outdir::write_json(&args.out, &doc, &inputs)?;
    crate::ui::say!("merged {} parts; wrote {}", parts.len(), args.out.display());
    crate::ui::document(&doc)
}
