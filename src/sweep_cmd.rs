//! `aeroform sweep SPEC.json [--shard i/n]`: large jobs split into shards (e.g. a Slurm job
//! array), merged by `aeroform merge` (`merge_cmd`) into the document of the unsplit run
//! (`benchmark::sweep`; docs/PYTHON.md "Scale-out").

use std::path::PathBuf;

use anyhow::Context;
use benchmark::sweep::{parse_shard, SweepSpec};
use clap::Args;

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
    crate::outdir::write_json(&out, &doc, &inputs)?;
    crate::ui::say!("{} items; wrote {}", spec.n_items(), out.display());
    crate::ui::document(&doc)
}
