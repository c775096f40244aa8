//! `aeroform run [STUDY] [--out DIR]`: runs a study end to end (the built-in quickstart
//! when no file is given) and prints the time of each stage.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use study::run::{names, run_study};
use study::Study;

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
    /// Replace an existing output folder that aeroform did not write (it is replaced as a
    /// whole, never mixed with the new results).
    #[arg(long)]
    pub force: bool,
}

/// Runs the study.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let mut study = match &args.study {
        Some(p) => Study::read(p)?,
        None => Study::quickstart()?,
    };
    if let Some(s) = args.seed {
        study.spec.seed = s;
        study.text = with_seed(&study.text, s);
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&study.spec.name));
    let t0 = Instant::now();
    let study_inputs = study.inputs();
    let inputs: Vec<_> = study_inputs
        .iter()
        .map(|(k, p)| crate::outdir::Input::new(k, p))
        .collect();
    let dir = crate::outdir::OutDir::begin(&out, "run", args.force, &inputs)?;
    let mut timings = run_study(&study, dir.path(), &crate::progress::Terminal::new())?;
    let t = Instant::now();
    plots::study_report::render_all(&study, dir.path(), &crate::version())?;
    timings.push(("figures+report", t.elapsed().as_secs_f64()));
    dir.commit()?;
    crate::ui::say!(
        "study `{}` ({}) done; results in {}",
        study.spec.name,
        study.path.display(),
        out.display()
    );
    for (stage, s) in &timings {
        crate::ui::say!("  {stage:<16} {s:>8.2} s");
    }
    let total = t0.elapsed().as_secs_f64();
    crate::ui::say!("  {:<16} {:>8.2} s", "total", total);
    if crate::ui::mode().json {
        let figures: serde_json::Value = study::files::read_json(&out.join(names::FIGURE_LIST))?;
        crate::ui::document(&aeroform::documents::RunSummary {
            study: study.spec.name.clone(),
            out: out.display().to_string(),
            seed: study.spec.seed.to_string(),
            timings_s: timings
                .iter()
                .map(|(k, v)| ((*k).to_string(), *v))
                .collect(),
            total_s: total,
            figures,
        })?;
    }
    Ok(())
}

/// The study text with its top-level `seed` replaced by `seed` (so that `study.toml` in the
/// output folder, and `aeroform plot`, see the seed actually used).
fn with_seed(text: &str, seed: u64) -> String {
    let mut top = true;
    let mut out = format!("seed = {seed}  # set by `aeroform run --seed`\n");
    for line in text.lines() {
        if line.trim_start().starts_with('[') {
            top = false;
        }
        let is_seed = top && line.trim_start().starts_with("seed") && line.contains('=');
        if !is_seed {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_override_replaces_only_the_top_level_seed() {
        let t = "name = \"x\"\nseed = 3\n[data.table_iv]\nrepeats = 2\nseed_like = 1\n";
        let s = with_seed(t, 7);
        let v: toml::Table = s.parse().unwrap();
        assert_eq!(v["seed"].as_integer(), Some(7));
        assert!(s.contains("seed_like = 1"));
        assert_eq!(s.matches("seed =").count(), 1);
    }
}
