//! `aeroform sweep SPEC.json [--shard i/n]` and `aeroform merge OUT PART...`: large jobs
//! split into shards (e.g. a Slurm job array) and merged into the document of the unsplit
//! run (`diagnose::sweep`; docs/PYTHON.md "Scale-out").

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use diagnose::sweep::{merge, parse_shard, SweepSpec};
use identify::io::write_atomic;

use crate::outdir::Input;
use crate::progress::CountBar;

/// Flags of `aeroform sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Sweep specification (JSON: `{"kind": "flutter_map", ...}` or `{"kind": "blind", ...}`).
    pub spec: PathBuf,
    /// Run only shard i of n (items whose index ≡ i mod n) and write a part document.
    #[arg(long)]
    pub shard: Option<String>,
    /// Output file (default `sweep.json`, or `sweep.part-I-of-N.json` with `--shard`).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Flags of `aeroform merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Output file: the document of the whole sweep.
    pub out: PathBuf,
    /// Part documents written by `--shard` runs (any order).
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
}

/// Writes the document atomically into its folder, registered as a shared folder: an
/// interrupt removes this process's temporary file, and temporary files of dead processes
/// there are removed first (the kill campaign of tests/campaign.rs found `merge` leaving
/// `.OUT.PID.tmp` after SIGINT).
fn write_json(
    path: &std::path::Path,
    v: &serde_json::Value,
    inputs: &[Input<'_>],
) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    crate::outdir::refuse_symlink(path, "output file")?;
    let _shared = crate::outdir::SharedDir::begin(dir, &[path], inputs)?;
    write_atomic(path, format!("{v:#}\n").as_bytes())?;
    Ok(())
}

/// Runs `aeroform sweep`.
pub fn run(args: &SweepArgs) -> anyhow::Result<()> {
    let spec = SweepSpec::read(&args.spec)?;
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let out = args.out.clone().unwrap_or_else(|| match shard {
        Some((i, n)) => PathBuf::from(format!("sweep.part-{i}-of-{n}.json")),
        None => PathBuf::from("sweep.json"),
    });
    let inputs = [Input::new("SPEC", &args.spec)];
    // refused before the (long) run, not after it
    crate::outdir::refuse_overlap(&out, "--out", &inputs)?;
    // a refusal while running (a file the specification names) names the specification
    let spec_ctx = || format!("sweep {}", args.spec.display());
    let doc = match shard {
        Some((i, n)) => spec.run_shard(i, n).with_context(spec_ctx)?,
        None => {
            let bar = CountBar::new("sweep", spec.n_items());
            let doc = spec.run_local(&|i| bar.tick(format!("item {i}")));
            bar.finish();
            doc.with_context(spec_ctx)?
        }
    };
    write_json(&out, &doc, &inputs)?;
    crate::ui::say!("{} items; wrote {}", spec.n_items(), out.display());
    crate::ui::document(&doc)
}

/// Runs `aeroform merge`. An OUT that is one of the parts (the same file, by any path) is
/// refused before anything is read or written.
pub fn merge_run(args: &MergeArgs) -> anyhow::Result<()> {
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
    write_json(&args.out, &doc, &inputs)?;
    crate::ui::say!("merged {} parts; wrote {}", parts.len(), args.out.display());
    crate::ui::document(&doc)
}
