//! The flags of `aeroform diagnose` ([`DiagnoseArgs`]): below both the command's entry
//! (`diagnose_cmd`) and its measured-branch mode (`diagnose_cmd::measured_branch`), which
//! read them, so neither imports the other for them (issue 40, docs/DECISIONS.md "No import
//! circles, checked").

use std::path::PathBuf;

use clap::Args;

/// How the bifurcation-level candidates are fitted (`--fit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FitArg {
    /// Forward differences of whole diagrams.
    Differences,
    /// The smooth objective and its orbit sensitivities.
    Sensitivities,
}

impl From<FitArg> for diagnose::bifurcation::FitJacobian {
    fn from(f: FitArg) -> Self {
        match f {
            FitArg::Differences => Self::Differences,
            FitArg::Sensitivities => Self::Sensitivities,
        }
    }
}

/// Flags of `aeroform diagnose`.
#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Forced-motion data-set folder (DATA_FORMAT.md).
    #[arg(required_unless_present_any = ["blind", "model"])]
    pub dataset: Option<PathBuf>,
    /// Further forced-motion data-set folders of the same section, diagnosed with FORCED
    /// as one campaign (e.g. the follow-up tests recorded from `follow_up.campaign.toml`);
    /// may be repeated. Case ids that repeat get the folder name as prefix.
    #[arg(long, requires = "dataset")]
    pub forced_extra: Vec<PathBuf>,
    /// Free-response data-set folder of the same section (enables the system level); may
    /// be repeated (e.g. LCO records and a still-air decay of the same rig).
    #[arg(long)]
    pub free: Vec<PathBuf>,
    /// The sim's aerodynamic model for free-response data or a measured bifurcation
    /// diagram alone: a model file (`*.model.toml`) or an `identification.json`; needs
    /// `--free` or `--measured-branch` and no forced data set.
    #[arg(long, conflicts_with = "dataset")]
    pub model: Option<PathBuf>,
    /// Nominal structure file (`*.structure.toml`) replacing the free data set's
    /// `[structure]`.
    #[arg(long)]
    pub structure: Option<PathBuf>,
    /// Diagnose at the bifurcation level: a measured bifurcation diagram, either a CSV
    /// table (docs/DATA_FORMAT.md, "Measured bifurcation diagram") or a free-response data
    /// set of LCO records (one point per record). Needs `--model`; the structure is
    /// `--structure` or the `[structure]` of the records' (or the first `--free`) data set;
    /// `--free` data sets give still-air decays (structure first). Writes
    /// `bifurcation.json`, figures and `diagnosis.html`.
    #[arg(long, requires = "model", conflicts_with_all = ["dataset", "blind"])]
    pub measured_branch: Option<PathBuf>,
    /// With `--measured-branch`: a measured flutter onset (Hopf point),
    /// `U[:F][:sub|super][:sd=SD]` — speed [m/s], then in any order its frequency [Hz], its
    /// criticality and the speed's standard uncertainty [m/s] (default 1 %); may be
    /// repeated. Adds to a table's `onset` rows (the record route has no table).
    #[arg(
        long,
        requires = "measured_branch",
        value_name = "U[:F][:sub|super][:sd=SD]"
    )]
    pub onset: Vec<String>,
    /// With `--measured-branch`: no LCO observed at speed U [m/s], `U[:PITCH_RAD[:HEAVE_M]]`
    /// with the largest pitch [rad] and heave [m] perturbation tried (peak; `-` when
    /// unknown); may be repeated. Adds to a table's `none` rows.
    #[arg(
        long = "no-lco",
        requires = "measured_branch",
        value_name = "U[:PITCH_RAD[:HEAVE_M]]"
    )]
    pub no_lco: Vec<String>,
    /// Output folder (created if missing); default `out/diagnosis` or `out/blind`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Master seed of every random draw (fold assignment; benchmark labels, strengths and
    /// noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run the withheld-effect benchmark on N generated data sets instead.
    #[arg(long, conflicts_with_all = ["dataset", "free", "model"])]
    pub blind: Option<u128>,
    /// Replace an existing output folder that aeroform did not write.
    #[arg(long)]
    pub force: bool,
    /// With `--blind`: run only shard i of n (sets whose index ≡ i mod n, each with its
    /// global seed) and write `blind.part-I-of-N.json`; `aeroform merge` joins the parts.
    #[arg(long, requires = "blind")]
    pub shard: Option<String>,
    /// With `--blind`: draw each set's campaign shape too (1–3 Table I configurations,
    /// 3–8 wind speeds, 3–8 amplitudes, alternate forms for a third, absolute balance
    /// noise) and report the statistics per shape class (with `--shard`: the parts of this
    /// benchmark, merged by `aeroform merge`).
    #[arg(long, requires = "blind")]
    pub shapes: bool,
    /// With `--blind`: the benchmark at the bifurcation level instead (generated rigs with
    /// a withheld structural or aerodynamic effect, each a measured bifurcation diagram;
    /// writes `branch-blind.json`).
    #[arg(long, requires = "blind", conflicts_with_all = ["shard", "shapes"])]
    pub branch_level: bool,
    /// With `--blind N --branch-level`: mis-give each rig's structure (one DOF's
    /// frequency 3–8 % off, recorded per set as `misgiven`) and add two still-air decays
    /// of the truth, so that the structure is identified from them first (issue 42).
    #[arg(long, requires = "branch_level")]
    pub misgiven_structure: bool,
    /// At the bifurcation level (`--measured-branch`, `--blind N --branch-level`): how the
    /// candidates are fitted. `differences`: forward differences of whole diagrams, points
    /// interpolated between continuation points (the default); `sensitivities`: each
    /// point's orbit corrected at its own speed, fitted by the orbits' derivatives (about
    /// 0.4 of the time; lower optima, which can change the named variant: DECISIONS, "The
    /// smooth bifurcation-level objective, round 33").
    #[arg(long, value_enum, default_value_t = FitArg::Differences)]
    pub fit: FitArg,
    /// With `--blind`: close the loop of every `extrapolation` (issue 42 item 4): run the
    /// recommended forced tests (the plan `diagnose` writes as `follow_up.campaign.toml`)
    /// on the set's truth and diagnose the set again; blind.json records the second verdict
    /// per set and confusion.md how many it got right.
    #[arg(long, requires = "blind", conflicts_with_all = ["shard", "branch_level"])]
    pub follow_up: bool,
}

impl DiagnoseArgs {
    /// Every file and folder these flags name for reading (the output may not be, contain
    /// or lie inside one of them: `outdir::refuse_overlap`).
    pub fn inputs(&self) -> Vec<crate::outdir::Input<'_>> {
        use crate::outdir::Input;
        let mut v: Vec<Input<'_>> = self
            .dataset
            .iter()
            .map(|p| Input::new("FORCED", p))
            .collect();
        v.extend(
            self.forced_extra
                .iter()
                .map(|p| Input::new("--forced-extra", p)),
        );
        v.extend(self.free.iter().map(|p| Input::new("--free", p)));
        v.extend(self.model.iter().map(|p| Input::new("--model", p)));
        v.extend(self.structure.iter().map(|p| Input::new("--structure", p)));
        v.extend(
            self.measured_branch
                .iter()
                .map(|p| Input::new("--measured-branch", p)),
        );
        v
    }
}
