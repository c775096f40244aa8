//! `aeroform identify DATASET`: read, preprocess, identify, write `identification.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::{Args, ValueEnum};
use identify::dataset::{read_dataset_with, ReadOptions};
use identify::identifiability::BasisMode;
use identify::library::LibraryKind;
use identify::pipeline::{GroupBy, Identification, IdentifySettings, RegressorChoice};
use identify::preprocess::{PreprocessOptions, VelocityMethod};
use identify::regress::plugin::{OptionValue, Regressor};
use identify::regress::plugins;
use identify::regress::{GroupRule, Measure};
use identify::workflow::prepare_dataset;

use crate::progress::IdentifyBar;

/// Flags of `aeroform identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    /// Data set folder (manifest.toml + case CSV files).
    pub dataset: PathBuf,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// How cases share one sparse support.
    #[arg(long, value_enum, default_value_t = GroupByArg::Config)]
    pub group_by: GroupByArg,
    /// Candidate library: the paper's 30 terms or all 34 cubic monomials.
    #[arg(long, value_enum, default_value_t = LibraryArg::Paper30)]
    pub library: LibraryArg,
    /// `canonical`: fit on the canonical identifiable basis; `full`: the whole library
    /// (a rank-deficient library is then an error).
    #[arg(long, value_enum, default_value_t = BasisArg::Canonical)]
    pub basis: BasisArg,
    /// Sparse optimiser: a registered regressor (see `--help` for the list and options).
    #[arg(long, default_value = "stlsq", value_parser = regressor_names(), long_help = plugins::help(plugins::registry()))]
    pub regressor: String,
    /// An option of the chosen regressor, `NAME=VALUE` (repeatable; the list under
    /// `--regressor` in `--help`).
    #[arg(long, value_name = "NAME=VALUE")]
    pub regressor_option: Vec<String>,
    /// Threshold measure: scale-free contribution ‖ξθ‖/‖y‖ or the paper's raw |ξ|.
    #[arg(long, value_enum, default_value_t = MeasureArg::Contribution)]
    pub measure: MeasureArg,
    /// Group-removal rule of group STLSQ.
    #[arg(long, value_enum, default_value_t = GroupRuleArg::Norm)]
    pub group_rule: GroupRuleArg,
    /// Ridge λ on the column-normalised library (0 = least squares).
    #[arg(long, default_value_t = 0.0)]
    pub ridge: f64,
    /// Number of δ values on the path.
    #[arg(long)]
    pub n_delta: Option<usize>,
    /// Number of key frequencies of the Eq. 14 loss.
    #[arg(long)]
    pub k_key: Option<usize>,
    /// Deprecated spelling of `--regressor-option alpha=A`.
    #[arg(long, hide = true)]
    pub pysindy_alpha: Option<f64>,
    /// Deprecated spelling of `--regressor-option unbias=false`.
    #[arg(long, hide = true)]
    pub pysindy_no_unbias: bool,
    /// How α̇ and ḣ are obtained from the measured motion.
    #[arg(long, value_enum, default_value_t = VelocityArg::Auto)]
    pub velocity: VelocityArg,
    /// Do not subtract still-air runs named by `nowind_file`.
    #[arg(long)]
    pub no_nowind: bool,
    /// Reverse the lift direction the manifest declares (`[convention] lift`, "down" when
    /// absent): for data exported lift-positive-up without a declaration.
    #[arg(long)]
    pub flip_lift: bool,
    /// Write stage timings (read_s, prepare_s, identify_s, total_s, cases) to this JSON file.
    #[arg(long)]
    pub timing_json: Option<PathBuf>,
    /// Block-bootstrap ensemble of N members (intervals of every coefficient and
    /// derivative, written to the `ensemble` section of identification.json; with
    /// `--law lag`, residual block bootstrap: intervals of τ₁, τ₂, α*, m in lag_law.json's
    /// `report.ensemble`).
    #[arg(long, value_name = "N")]
    pub ensemble: Option<usize>,
    /// Seed of the ensemble's draws (recorded in the output).
    #[arg(long, default_value_t = 2024)]
    pub seed: u64,
    /// Level of the ensemble intervals, in (0, 1).
    #[arg(long, default_value_t = identify::ensemble::DEFAULT_LEVEL)]
    pub level: f64,
    /// Law kind: `memoryless` (the polynomial law of identification.json) or `lag` (a law
    /// with one separation state, written to lag_law.json; the sparse-regression flags
    /// above do not apply to it).
    #[arg(long, value_enum, default_value_t = LawArg::Memoryless)]
    pub law: LawArg,
    /// With `--law lag`: hold out the cases whose reduced frequency (`k=0.1`), mean angle
    /// (`mean=15`, deg) or pitch amplitude (`amplitude=10`, deg) is nearest the value, fit
    /// the memoryless and the lag law on the others and score both on them.
    #[arg(long, value_name = "k=K|mean=DEG|amplitude=DEG")]
    pub hold_out: Option<String>,
    /// With `--law lag`: `true` adds the instantaneous static Kirchhoff lift
    /// α_e·κ(x₀(α_e)) to the lift support beside the lagged α_e·κ(x), `false` leaves it out
    /// (default: the support of `identify::lag::LagFitOptions::default`).
    #[arg(long, value_name = "true|false")]
    pub lag_static_lift: Option<bool>,
    /// With `--law lag`: pitch-rate share c of the law's effective angle,
    /// α_e = α + ḣ/U + c·Bα̇/U, fixed (not fitted), in [−1, 1]; (½ − a)/2 is the
    /// three-quarter-chord downwash of records whose moment is about a semichords aft of
    /// mid-chord (0.5 about the quarter chord). Default 0.
    #[arg(long, value_name = "C")]
    pub lag_rate_share: Option<f64>,
    /// With `--law lag`: `true` replaces the Kirchhoff lift α_e·κ(x) by the separated-flow
    /// blend of Hansen, Gaunaa & Madsen (2004), α_e·(x + (1 − x)(1 + 3s)/(4(1 + s))),
    /// s = √x₀(α_e), in the lift support and in the moment candidates (with its
    /// centre-of-pressure column); equal to the Kirchhoff lift in steady flow. Default false.
    #[arg(long, value_name = "true|false")]
    pub lag_blend: Option<bool>,
    /// With `--law lag`: pressure lag τ_p [convective times b/U] of the separation input
    /// (Beddoes–Leishman's leading-edge pressure lag), fixed, in [0, 100]; 0 = off
    /// (default). The start value with `--lag-fit-pressure-lag true`.
    #[arg(long, value_name = "TAU")]
    pub lag_pressure_lag: Option<f64>,
    /// With `--law lag`: `true` fits the rate share c by output error (a parameter of the
    /// Levenberg–Marquardt fit, bounded to [0, 1]) instead of holding it at `--lag-rate-share`.
    #[arg(long, value_name = "true|false")]
    pub lag_fit_rate_share: Option<bool>,
    /// With `--law lag`: `true` fits the pressure lag τ_p by output error (a parameter of
    /// the Levenberg–Marquardt fit, bounded to [0, 6] b/U) instead of holding it at
    /// `--lag-pressure-lag`.
    #[arg(long, value_name = "true|false")]
    pub lag_fit_pressure_lag: Option<bool>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LawArg {
    Memoryless,
    Lag,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum GroupByArg {
    Config,
    WindSpeed,
    Amplitude,
    None,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum LibraryArg {
    Paper30,
    Full34,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum BasisArg {
    Canonical,
    Full,
}

/// The names and aliases of the registered regressors (`--regressor`'s possible values).
fn regressor_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(plugins::registry().iter().flat_map(|r| {
        std::iter::once(clap::builder::PossibleValue::new(r.name())).chain(
            r.aliases()
                .iter()
                .map(|a| clap::builder::PossibleValue::new(*a).hide(true)),
        )
    }))
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum MeasureArg {
    Contribution,
    Coefficient,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum GroupRuleArg {
    Norm,
    All,
    Any,
    Mean,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum VelocityArg {
    Auto,
    Harmonic,
    Sg,
}

impl IdentifyArgs {
    /// The regressor choice of `--regressor` and `--regressor-option` (each value parsed
    /// by the option's declared type).
    ///
    /// # Errors
    /// A usage error naming the option for a value without `=`, an option the regressor
    /// does not have, or a value not of its type.
    pub fn regressor_choice(&self) -> anyhow::Result<RegressorChoice> {
        let reg: &dyn Regressor = plugins::find(&self.regressor)?;
        let mut pairs: Vec<(String, String)> = Vec::new();
        for o in &self.regressor_option {
            let (k, v) = o.split_once('=').ok_or_else(|| {
                crate::exit::Usage(format!("`--regressor-option {o}`: expected NAME=VALUE"))
            })?;
            pairs.push((k.trim().to_string(), v.to_string()));
        }
        if let Some(a) = self.pysindy_alpha {
            pairs.push(("alpha".to_string(), a.to_string()));
        }
        if self.pysindy_no_unbias {
            pairs.push(("unbias".to_string(), "false".to_string()));
        }
        let mut choice = RegressorChoice::new(reg.name());
        for (k, v) in pairs {
            let spec = reg.options().iter().find(|s| s.name == k).ok_or_else(|| {
                crate::exit::Usage(format!(
                    "`--regressor-option {k}=…`: `{}` has {}",
                    reg.name(),
                    if reg.options().is_empty() {
                        "no options".to_string()
                    } else {
                        format!(
                            "the options {}",
                            reg.options()
                                .iter()
                                .map(|s| s.name)
                                .collect::<Vec<_>>()
                                .join(", ")
                        )
                    }
                ))
            })?;
            let value: OptionValue = spec
                .parse(reg.name(), &v)
                .map_err(|e| crate::exit::Usage(format!("`--regressor-option`: {e}")))?;
            choice = choice.with(&k, value);
        }
        Ok(choice)
    }

    /// Identification settings these flags select (validated by the library).
    ///
    /// # Errors
    /// As [`IdentifyArgs::regressor_choice`].
    pub fn settings(&self) -> anyhow::Result<IdentifySettings> {
        let mut s = IdentifySettings {
            library: match self.library {
                LibraryArg::Paper30 => LibraryKind::Paper30,
                LibraryArg::Full34 => LibraryKind::Full34,
            },
            basis: match self.basis {
                BasisArg::Canonical => BasisMode::Canonical,
                BasisArg::Full => BasisMode::Full,
            },
            measure: match self.measure {
                MeasureArg::Contribution => Measure::Contribution,
                MeasureArg::Coefficient => Measure::Coefficient,
            },
            group_rule: match self.group_rule {
                GroupRuleArg::Norm => GroupRule::Norm,
                GroupRuleArg::All => GroupRule::All,
                GroupRuleArg::Any => GroupRule::Any,
                GroupRuleArg::Mean => GroupRule::Mean,
            },
            ridge: self.ridge,
            regressor: self.regressor_choice()?,
            group_by: match self.group_by {
                GroupByArg::Config => GroupBy::Config,
                GroupByArg::WindSpeed => GroupBy::WindSpeed,
                GroupByArg::Amplitude => GroupBy::Amplitude,
                GroupByArg::None => GroupBy::None,
            },
            ..IdentifySettings::default()
        };
        if let Some(n) = self.n_delta {
            s.n_delta = n;
        }
        if let Some(k) = self.k_key {
            s.k_key = k;
        }
        Ok(s)
    }

    /// Preprocessing options these flags select.
    pub fn preprocess(&self) -> PreprocessOptions {
        PreprocessOptions {
            velocity: match self.velocity {
                VelocityArg::Auto => VelocityMethod::Auto,
                VelocityArg::Harmonic => VelocityMethod::Harmonic,
                VelocityArg::Sg => VelocityMethod::SavitzkyGolay {
                    half_window: identify::preprocess::DEFAULT_SG_HALF_WINDOW,
                    order: identify::preprocess::DEFAULT_SG_ORDER,
                },
            },
            subtract_nowind: !self.no_nowind,
            ..PreprocessOptions::default()
        }
    }
}

/// Runs `aeroform identify`: the memoryless law (`OUT/identification.json`) or, with
/// `--law lag`, the lag law (`OUT/lag_law.json`).
pub fn run(args: &IdentifyArgs) -> anyhow::Result<()> {
    match args.law {
        LawArg::Lag => run_lag(args),
        LawArg::Memoryless => {
            if args.hold_out.is_some() {
                return Err(crate::exit::Usage(
                    "`--hold-out` compares the memoryless law with the lag law: it needs `--law lag`"
                        .to_string(),
                )
                .into());
            }
            run_memoryless(args).map(|_| ())
        }
    }
}

/// The memoryless identification; returns the result (also written to
/// `OUT/identification.json`).
fn run_memoryless(args: &IdentifyArgs) -> anyhow::Result<Identification> {
    let settings = args.settings()?;
    settings
        .validate()
        .context("invalid identification option")?;
    let pre = args.preprocess();
    pre.check().context("invalid preprocessing option")?;
    if let Some(n) = args.ensemble {
        // before any data are read (a u64 count would otherwise fail only after the fit)
        aeroform::limits::count("--ensemble", n as u128, aeroform::limits::MAX_ENSEMBLE)?;
        if n < 2 {
            return Err(crate::exit::Usage(format!(
                "`--ensemble`: {n} member; an interval needs at least 2"
            ))
            .into());
        }
        // a regressor or ridge the bootstrap cannot re-fit: refused now, not after the fit
        identify::ensemble::check_settings(&settings)
            .map_err(|e| crate::exit::Usage(format!("`--ensemble`: {e}")))?;
        // members × cases bounded before any case is read (the manifest alone)
        let manifest = identify::dataset::open_dataset(
            &args.dataset,
            &ReadOptions {
                flip_lift: args.flip_lift,
            },
        )
        .with_context(|| format!("reading data set {}", args.dataset.display()))?;
        aeroform::limits::ensemble_fits("--ensemble", n, manifest.cases.len() as u128)?;
    }

    let path = args.out.join("identification.json");
    let t_start = Instant::now();
    // streamed case by case (identify::workflow::prepare_streaming): memory does not grow
    // with the number of cases; the per-case preparation runs with the reading
    let bar = IdentifyBar::new();
    let streamed = checked_stream(args, &path, &settings, &pre, &|p| bar.observe(p));
    let mut streamed = match streamed {
        Ok(s) => s,
        Err(e) => {
            bar.finish();
            return Err(e);
        }
    };
    let stream_s = t_start.elapsed().as_secs_f64();
    let convention = streamed.manifest.convention;
    if !convention.is_scanlan() && !crate::ui::silent() {
        crate::ui::warning!(
            "{}: columns read as {} and converted to Scanlan's (h, lift down; alpha, moment nose-up)",
            args.dataset.display(),
            convention.describe()
        );
    }
    let n_cases = streamed.prepared.len();
    if n_cases == 0 {
        bar.finish();
        crate::exit::refuse!(
            "{}: the data set has no forced-motion case to identify",
            args.dataset.display()
        );
    }
    // wall time of the pass split by stage: the preparation's own wall time, the rest in
    // proportion of the reading and preprocessing thread-seconds
    let sec = streamed.seconds;
    let rest = (stream_s - sec.prepare).max(0.0);
    let share = sec.read / (sec.read + sec.preprocess).max(f64::MIN_POSITIVE);
    let (read_s, prepare_s) = (rest * share, rest * (1.0 - share));

    // every input is read and checked: only now is the output folder created
    let (written, inputs) = outputs(args, &path);
    let _out = crate::outdir::SharedDir::begin(&args.out, &written, &inputs)?;
    let t_id = Instant::now();
    // the per-case work is not needed past the group stage (the ensemble reads the cases
    // again): freed case by case as the result is made
    let result = streamed
        .prepared
        .identify_all_and_clear(&streamed.manifest.name, &|p| bar.observe(p));
    bar.finish();
    let mut result = result.context("identification")?;
    let identify_s = t_id.elapsed().as_secs_f64() + sec.prepare;
    if let Some(n) = args.ensemble {
        let t_e = Instant::now();
        let mut es = identify::ensemble::EnsembleSettings::new(n, args.seed);
        es.level = args.level;
        // the cases are read again, batch by batch, each checked unchanged
        let e = streamed
            .bootstrap(&result, &es)
            .context("ensemble (block bootstrap)")?;
        result.ensemble = Some(e);
        if !crate::ui::silent() {
            crate::ui::say!(
                "ensemble: {n} block-bootstrap members (seed {}) in {:.3} s",
                args.seed,
                t_e.elapsed().as_secs_f64()
            );
        }
    }

    result.write(&path)?;
    let total_s = t_start.elapsed().as_secs_f64();
    if let Some(t) = &args.timing_json {
        write_timing(t, read_s, prepare_s, identify_s, total_s, n_cases)?;
    }
    if !crate::ui::silent() {
        crate::ui::say!("{}", result.summary_table());
        crate::ui::say!(
            "{} cases: read {read_s:.3} s, preprocess {prepare_s:.3} s, identify {identify_s:.3} s; wrote {}",
            n_cases,
            path.display()
        );
    }
    crate::ui::document(&result)?;
    Ok(result)
}

fn write_timing(
    path: &Path,
    read_s: f64,
    prepare_s: f64,
    identify_s: f64,
    total_s: f64,
    cases: usize,
) -> anyhow::Result<()> {
    let json = serde_json::to_string_pretty(&aeroform::documents::IdentifyTiming {
        read_s,
        prepare_s,
        identify_s,
        total_s,
        cases,
    })?;
    identify::io::write_atomic(path, format!("{json}\n").as_bytes())?;
    Ok(())
}

/// `--law lag`: fit the lag law (with the held-out comparison when asked), then write
/// `OUT/lag_law.json`. Nothing is written unless the fit succeeds.
/// The files the command writes (`document` and `--timing-json`) and its input, the data
/// set.
fn outputs<'a>(
    args: &'a IdentifyArgs,
    document: &'a Path,
) -> (Vec<&'a Path>, [crate::outdir::Input<'a>; 1]) {
    let mut written = vec![document];
    written.extend(args.timing_json.as_deref());
    (
        written,
        [crate::outdir::Input::new("DATASET", &args.dataset)],
    )
}

/// Checks the files the command writes ([`outputs`]) against its input before anything is
/// read (no output may be, contain or lie inside the data set; `--out` no symbolic link),
/// then reads the data set: (data set, seconds to read it).
fn checked_read(
    args: &IdentifyArgs,
    document: &Path,
) -> anyhow::Result<(identify::dataset::Dataset, f64)> {
    let (written, inputs) = outputs(args, document);
    for w in &written {
        crate::outdir::refuse_overlap(w, "output file", &inputs)?;
    }
    crate::outdir::refuse_symlink(&args.out, "--out")?;
    let t = Instant::now();
    let options = ReadOptions {
        flip_lift: args.flip_lift,
    };
    let dataset = read_dataset_with(&args.dataset, &options)
        .with_context(|| format!("reading data set {}", args.dataset.display()))?;
    Ok((dataset, t.elapsed().as_secs_f64()))
}

/// [`checked_read`]'s checks, then the data set streamed case by case into the first stage
/// of the identification ([`identify::workflow::prepare_streaming`]).
fn checked_stream(
    args: &IdentifyArgs,
    document: &Path,
    settings: &IdentifySettings,
    pre: &PreprocessOptions,
    observer: &dyn Fn(identify::pipeline::Progress),
) -> anyhow::Result<identify::workflow::StreamedDataset> {
    let (written, inputs) = outputs(args, document);
    for w in &written {
        crate::outdir::refuse_overlap(w, "output file", &inputs)?;
    }
    crate::outdir::refuse_symlink(&args.out, "--out")?;
    let options = ReadOptions {
        flip_lift: args.flip_lift,
    };
    identify::workflow::prepare_streaming(&args.dataset, &options, pre, settings, observer)
        .with_context(|| format!("reading data set {}", args.dataset.display()))
}

fn run_lag(args: &IdentifyArgs) -> anyhow::Result<()> {
    use identify::lag::{HoldOut, LagFitOptions, LagLawDocument};
    if let Some(n) = args.ensemble {
        aeroform::limits::count("--ensemble", n as u128, aeroform::limits::MAX_ENSEMBLE)?;
        if n < 2 || args.hold_out.is_some() {
            return Err(crate::exit::Usage(format!(
                "`--ensemble {n}` with `--law lag`: needs at least 2 members and no \
                 `--hold-out` (the intervals are of the law fitted on every case)"
            ))
            .into());
        }
    }
    let hold_out = match &args.hold_out {
        Some(s) => Some(
            s.parse::<HoldOut>()
                .map_err(|e| crate::exit::Usage(format!("`--hold-out`: {e}")))?,
        ),
        None => None,
    };
    let pre = args.preprocess();
    pre.check().context("invalid preprocessing option")?;
    let path = args.out.join("lag_law.json");
    let t_start = Instant::now();
    let (dataset, read_s) = checked_read(args, &path)?;
    let t_prep = Instant::now();
    let prepared = prepare_dataset(&dataset, &pre).context("preprocessing")?;
    let prepare_s = t_prep.elapsed().as_secs_f64();
    if prepared.cases.is_empty() {
        crate::exit::refuse!(
            "{}: the data set has no forced-motion case to identify",
            args.dataset.display()
        );
    }
    let t_id = Instant::now();
    let mut opts = LagFitOptions::default();
    if let Some(on) = args.lag_static_lift {
        opts.lift_columns
            .retain(|c| *c != identify::lag::LagColumn::KirchhoffStatic);
        if on {
            opts.lift_columns
                .push(identify::lag::LagColumn::KirchhoffStatic);
        }
    }
    if let Some(c) = args.lag_rate_share {
        opts.rate_share = c;
    }
    if args.lag_blend == Some(true) {
        opts = opts.with_blend();
    }
    if let Some(t) = args.lag_pressure_lag {
        opts.pressure_lag = t;
    }
    opts.fit_rate_share = args.lag_fit_rate_share.unwrap_or(false);
    opts.fit_pressure_lag = args.lag_fit_pressure_lag.unwrap_or(false);
    let result = match hold_out {
        Some(h) => identify::lag::held_out(&prepared.cases, h, &opts).map(|(f, _)| f),
        None => identify::lag::fit(&prepared.cases, &opts),
    };
    // a refused law or a prediction outside the fitted range is about the input: exit 2
    // (`exit::code` knows `Unphysical` and `OutsideFittedRange`)
    let mut fit = result.context("lag-law identification")?;
    let identify_s = t_id.elapsed().as_secs_f64();
    if let Some(n) = args.ensemble {
        let t_e = Instant::now();
        let mut es = identify::ensemble::EnsembleSettings::new(n, args.seed);
        es.level = args.level;
        let series = prepared
            .cases
            .iter()
            .map(|c| identify::lag::LagSeries::with_rate_share(c, opts.rate_share))
            .collect::<identify::Result<Vec<_>>>()
            .context("lag-law ensemble")?;
        let e = identify::lag::ensemble::bootstrap(&series, &fit, &opts, &es)
            .context("lag-law ensemble (residual block bootstrap)")?;
        if !crate::ui::silent() {
            crate::ui::say!(
                "ensemble: {n} residual block-bootstrap members (seed {}, {} refused) in {:.3} s",
                args.seed,
                e.refused,
                t_e.elapsed().as_secs_f64()
            );
        }
        fit.report.ensemble = Some(e);
    }
    let doc = LagLawDocument::from_fit(&fit, &dataset.manifest.name, prepared.cases[0].chord)?;

    // the fit succeeded: only now is the output folder created and written
    let (written, inputs) = outputs(args, &path);
    let _out = crate::outdir::SharedDir::begin(&args.out, &written, &inputs)?;
    identify::io::write_atomic(&path, doc.to_json()?.as_bytes())?;
    let total_s = t_start.elapsed().as_secs_f64();
    if let Some(t) = &args.timing_json {
        write_timing(
            t,
            read_s,
            prepare_s,
            identify_s,
            total_s,
            prepared.cases.len(),
        )?;
    }
    if !crate::ui::silent() {
        crate::ui::say!("{}", lag_table(&fit));
        crate::ui::say!(
            "{} cases: read {read_s:.3} s, preprocess {prepare_s:.3} s, lag law {identify_s:.3} s; wrote {}",
            prepared.cases.len(),
            path.display()
        );
    }
    crate::ui::document(&doc)?;
    Ok(())
}

/// The human-readable table of a lag-law fit.
fn lag_table(fit: &identify::lag::LagFit) -> String {
    use std::fmt::Write;
    let r = &fit.report;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "lag law: τ₁ dx/ds + x = x₀(α_e − τ₂·Bα̇/(2U)), x₀ = 1/(1 + |α/α*|^(2m))"
    );
    let _ = writeln!(
        s,
        "{:<12} {:>12} {:>12}  unit",
        "parameter", "value", "std. error"
    );
    for p in &r.parameters {
        let se = p
            .standard_error
            .map_or("-".to_string(), |v| format!("{v:.4}"));
        let extra = if p.name == "alpha_star" {
            format!(" ({:.2} deg)", p.value.to_degrees())
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "{:<12} {:>12.4} {:>12}  {}{extra}",
            p.symbol, p.value, se, p.unit
        );
    }
    if let Some(e) = &r.ensemble {
        for p in &e.parameters {
            let _ = writeln!(
                s,
                "{:<12} {:.0} % interval [{:.4}, {:.4}], median {:.4} ({} of {} members)",
                p.name,
                100.0 * e.level,
                p.interval.lower,
                p.interval.upper,
                p.interval.median,
                e.members - e.refused,
                e.members
            );
        }
    }
    match r.tau_correlation {
        Some(c) if r.tau_collinear => {
            let _ = writeln!(
                s,
                "corr(τ₁, τ₂) = {c:.3}: nearly collinear, the records fix little more than a combination of the two lags"
            );
        }
        Some(c) => {
            let _ = writeln!(s, "corr(τ₁, τ₂) = {c:.3}");
        }
        None => {
            let _ = writeln!(s, "corr(τ₁, τ₂): JᵀJ singular, no correlation");
        }
    }
    let terms = |ch: &identify::lag::LagChannel| {
        ch.terms
            .iter()
            .map(|(c, v)| format!("{v:+.4}·{}", c.label()))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let _ = writeln!(s, "C_L = {}", terms(&fit.law.lift));
    let _ = writeln!(s, "C_M = {}", terms(&fit.law.moment));
    let _ = writeln!(
        s,
        "{:<28} {:>7} {:>7} {:>7} {:>9} {:>9}",
        "case (fitted)", "K", "mean°", "amp°", "R² C_L", "R² C_M"
    );
    for c in &r.cases {
        let _ = writeln!(
            s,
            "{:<28} {:>7.4} {:>7.2} {:>7.2} {:>9.4} {:>9.4}",
            c.id, c.k, c.mean_deg, c.amplitude_deg, c.r2_lift, c.r2_moment
        );
    }
    if let Some(h) = &r.held_out {
        let _ = writeln!(
            s,
            "held out ({}): memoryless law (cubic, 30 terms + constant, one fit on the training cases) vs lag law",
            h.spec
        );
        let _ = writeln!(
            s,
            "{:<28} {:>7} {:>7} {:>11} {:>11} {:>11} {:>11}",
            "case (held out)",
            "K",
            "mean°",
            "memo R² C_L",
            "lag R² C_L",
            "memo R² C_M",
            "lag R² C_M"
        );
        for row in &h.rows {
            let _ = writeln!(
                s,
                "{:<28} {:>7.4} {:>7.2} {:>11.4} {:>11.4} {:>11.4} {:>11.4}",
                row.id,
                row.k,
                row.mean_deg,
                row.memoryless_r2_lift,
                row.lag_r2_lift,
                row.memoryless_r2_moment,
                row.lag_r2_moment
            );
        }
        let _ = write!(
            s,
            "{:<28} {:>7} {:>7} {:>11.4} {:>11.4} {:>11.4} {:>11.4}",
            "mean",
            "",
            "",
            h.mean_r2_lift[0],
            h.mean_r2_lift[1],
            h.mean_r2_moment[0],
            h.mean_r2_moment[1]
        );
    }
    s.trim_end().to_string()
}
