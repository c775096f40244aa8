//! `aeroform tunnel forced|free`: the virtual wind tunnel writes data sets.

use std::path::PathBuf;

use aeroelastic::files::LoadedModel;
use aeroelastic::tunnel::{self, ForcedOptions, FreeOptions, TunnelProgress};
use anyhow::Context;
use clap::{Args, Subcommand};

use crate::models::load;
use crate::outdir::{Input, OutDir};
use crate::progress::CountBar;
use aeroform::limits::{abs_at_most, parse_speeds, MAX_PITCH_DEG};

/// `aeroform tunnel` subcommands.
#[derive(Debug, Subcommand)]
pub enum TunnelCommand {
    /// Prescribed-motion records (paper campaign or one configuration).
    Forced(ForcedArgs),
    /// Free response of the section on springs at a list of wind speeds.
    Free(FreeArgs),
    /// A withheld-effect data-set pair (the blind benchmark's scenario): `forced/` and
    /// `free/` folders plus `truth.json`, to diagnose with `aeroform diagnose` or any other
    /// program.
    Blind(BlindArgs),
}

/// Flags of `aeroform tunnel blind`.
#[derive(Debug, Args)]
pub struct BlindArgs {
    /// Effect: a catalogue name (`static_offset`, `added_mass`, `time_delay`,
    /// `higher_order`, `dynamic_stall`, `vortex_shedding`, `structural_cubic`, `freeplay`,
    /// `friction`), `none` or `buffeting` (outside the catalogue).
    #[arg(long)]
    pub effect: String,
    /// Strength in [0, 1] (0 barely detectable, 1 strong).
    #[arg(long, default_value_t = 0.8)]
    pub strength: f64,
    /// Use the effect's alternate functional form.
    #[arg(long)]
    pub alternate: bool,
    /// Seed of every random draw (recorded in truth.json and the manifests).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/blind-set")]
    pub out: PathBuf,
    /// Replace an existing output folder that aeroform did not write.
    #[arg(long)]
    pub force: bool,
}

/// Flags of `aeroform tunnel forced`.
#[derive(Debug, Args)]
pub struct ForcedArgs {
    /// Aerodynamic model: a model TOML file or an identification.json.
    #[arg(long)]
    pub model: PathBuf,
    /// `paper` (configurations A–G) or `config=X` (one configuration).
    #[arg(long, default_value = "paper")]
    pub campaign: aeroelastic::tunnel::CampaignName,
    /// A campaign plan file (`aeroform-campaign/1`, e.g. the `follow_up.campaign.toml`
    /// that `aeroform diagnose` writes): its rows' cases instead of `--campaign`.
    #[arg(long, conflicts_with = "campaign")]
    pub campaign_file: Option<PathBuf>,
    /// Output data-set folder.
    #[arg(long, default_value = "out/forced")]
    pub out: PathBuf,
    /// Master seed of every random draw (recorded in the manifest).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also record still-air runs (inertial forces of the 0.82 kg plate) with random offsets.
    #[arg(long)]
    pub still_air: bool,
    /// Record duration [s] (default: the campaign file's `record_duration_s`, else 10).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Chord B [m] for an identification.json model.
    #[arg(long)]
    pub chord: Option<f64>,
    /// Replace an existing output folder that aeroform did not write.
    #[arg(long)]
    pub force: bool,
}

/// Flags of `aeroform tunnel free`.
#[derive(Debug, Args)]
pub struct FreeArgs {
    /// Structure file (TOML).
    #[arg(long)]
    pub structure: PathBuf,
    /// Aerodynamic model: a model TOML file or an identification.json.
    #[arg(long)]
    pub model: PathBuf,
    /// Wind speeds `a:b:n` or a comma list [m/s].
    #[arg(long)]
    pub speeds: String,
    /// Output data-set folder.
    #[arg(long, default_value = "out/free")]
    pub out: PathBuf,
    /// Master seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Record duration [s].
    #[arg(long, default_value_t = 20.0)]
    pub duration: f64,
    /// Initial pitch [deg].
    #[arg(long, default_value_t = 2.0)]
    pub alpha0: f64,
    /// Do not record lift and moment.
    #[arg(long)]
    pub no_forces: bool,
    /// Chord B [m] for an identification.json model.
    #[arg(long)]
    pub chord: Option<f64>,
    /// Replace an existing output folder that aeroform did not write.
    #[arg(long)]
    pub force: bool,
}

/// Runs `aeroform tunnel …`.
pub fn run(cmd: &TunnelCommand) -> anyhow::Result<()> {
    match cmd {
        TunnelCommand::Forced(a) => forced(a),
        TunnelCommand::Free(a) => free(a),
        TunnelCommand::Blind(a) => blind(a),
    }
}

fn blind(a: &BlindArgs) -> anyhow::Result<()> {
    use aeroelastic::effects::Form;
    use benchmark::blind::{generate, write_blind, BlindScenario};
    let effect = benchmark::blind::BlindEffect::from_name(&a.effect)?;
    if !(0.0..=1.0).contains(&a.strength) {
        return Err(
            crate::exit::Usage(format!("--strength {}: must be in [0, 1]", a.strength)).into(),
        );
    }
    let form = if a.alternate {
        Form::Alternate
    } else {
        Form::Primary
    };
    let set = generate(effect, a.strength, form, a.seed, &BlindScenario::default())?;
    let dir = OutDir::begin(&a.out, "tunnel blind", a.force, &[])?;
    write_blind(dir.path(), &set)?;
    dir.commit()?;
    crate::ui::say!(
        "wrote {} forced cases to {}, {} free runs to {} and the truth to {}",
        set.forced.records.len(),
        a.out.join("forced").display(),
        set.free.records.len(),
        a.out.join("free").display(),
        a.out.join("truth.json").display()
    );
    crate::ui::document(&aeroform::documents::TunnelBlindSummary {
        out: a.out.display().to_string(),
        forced_cases: set.forced.records.len(),
        free_runs: set.free.records.len(),
        seed: a.seed.to_string(),
    })
}

/// The `manifest.toml` just written to `dir`, as JSON (for `--json`; `Null` otherwise).
fn manifest_json(dir: &std::path::Path) -> anyhow::Result<serde_json::Value> {
    if !crate::ui::mode().json {
        return Ok(serde_json::Value::Null);
    }
    let path = dir.join("manifest.toml");
    let text =
        identify::io::read_text(&path).with_context(|| format!("reading {}", path.display()))?;
    let v: toml::Value = toml::from_str(&text).with_context(|| format!("{}", path.display()))?;
    Ok(serde_json::to_value(v)?)
}

fn forced(a: &ForcedArgs) -> anyhow::Result<()> {
    let (cases, planned) = match &a.campaign_file {
        Some(path) => {
            let text = identify::io::read_text(path)
                .with_context(|| format!("--campaign-file {}", path.display()))?;
            let plan =
                aeroelastic::tunnel::CampaignPlan::parse(&text, &path.display().to_string())
                    .context("--campaign-file")?;
            let d = plan.record_duration().context("--campaign-file")?;
            (plan.cases(), d)
        }
        None => (a.campaign.campaign().context("--campaign")?.cases(), None),
    };
    let duration = a.duration.or(planned).unwrap_or(10.0);
    let mut opts = ForcedOptions::paper(a.seed);
    if a.still_air {
        opts = opts.with_paper_still_air();
    }
    let records = cases.len() * if a.still_air { 2 } else { 1 };
    aeroform::limits::samples("--duration", "rate", records, duration, opts.rate)?;
    let m = LoadedModel::load(&a.model, a.chord).context("model file")?;
    opts.duration = duration;
    opts.section.chord = m.model.chord();
    let mut inputs = vec![Input::new("--model", &a.model)];
    if let Some(p) = &a.campaign_file {
        inputs.push(Input::new("--campaign-file", p));
    }
    let dir = OutDir::begin(&a.out, "tunnel forced", a.force, &inputs)?;
    let bar = CountBar::new("cases", cases.len());
    let obs = |p: TunnelProgress| bar.tick(p.id);
    let r = tunnel::forced_dataset(m.model.as_ref(), &cases, &opts, &obs);
    bar.finish();
    let (manifest, records) = r.context("virtual wind tunnel (forced)")?;
    tunnel::write(dir.path(), &manifest, &records)?;
    dir.commit()?;
    crate::ui::say!(
        "wrote {} forced cases (model {}, seed {}) to {}",
        records.len(),
        m.model.name(),
        a.seed,
        a.out.display()
    );
    crate::ui::document(&aeroform::documents::TunnelForcedSummary {
        out: a.out.display().to_string(),
        cases: records.len(),
        model: m.model.name().to_string(),
        seed: a.seed.to_string(),
        manifest: manifest_json(&a.out)?,
    })
}

fn free(a: &FreeArgs) -> anyhow::Result<()> {
    let speeds = parse_speeds("--speeds", &a.speeds)?;
    abs_at_most("--alpha0", a.alpha0, MAX_PITCH_DEG, "deg")?;
    let mut opts = FreeOptions::new(a.seed);
    aeroform::limits::samples("--duration", "rate", speeds.len(), a.duration, opts.rate)?;
    let l = load(&a.structure, &a.model, a.chord)?;
    opts.duration = a.duration;
    opts.initial = [0.0, a.alpha0.to_radians(), 0.0, 0.0];
    opts.record_forces = !a.no_forces;
    let bar = CountBar::new("speeds", speeds.len());
    let obs = |p: TunnelProgress| bar.tick(p.id);
    let r = tunnel::free_dataset(&l.section, &speeds, &opts, &obs);
    bar.finish();
    let (manifest, records, runs) = r.context("virtual wind tunnel (free)")?;
    let dir = OutDir::begin(
        &a.out,
        "tunnel free",
        a.force,
        &[
            Input::new("--structure", &a.structure),
            Input::new("--model", &a.model),
        ],
    )?;
    tunnel::write(dir.path(), &manifest, &records)?;
    dir.commit()?;
    for run in &runs {
        if let Some(t) = run.left_bound_at {
            crate::ui::say!(
                "U = {} m/s: left the bound at t = {t:.3} s (record truncated)",
                run.u
            );
        }
    }
    crate::ui::say!(
        "wrote {} free-response cases to {}",
        records.len(),
        a.out.display()
    );
    crate::ui::document(&aeroform::documents::TunnelFreeSummary {
        out: a.out.display().to_string(),
        runs: records.len(),
        seed: a.seed.to_string(),
        manifest: manifest_json(&a.out)?,
        left_bound_at_s: runs.iter().map(|r| r.left_bound_at).collect(),
    })
}
