//! Withheld-effect benchmark (DESIGN.md §5.5): data sets with a random effect (a catalogue
//! effect, none, or one outside the catalogue) at random strength, diagnosed without the
//! label; confusion matrix and shrink statistics.
//!
//! The benchmark knows the labels; the diagnosis does not (it receives the two data sets
//! only). A set counts as *strong* when its true gap is at least [`STRONG_RATIO`] times the
//! noise-level gap, both measured by the baseline on held-out data: the true gap is the
//! baseline's held-out gap on the set, the noise-level gap is the same quantity on its twin
//! (the same seed and noise draws with no effect). The ratio is the larger of the force-
//! and system-level ratios.

use identify::numerics::{median_finite, split_seed};
use serde::{Deserialize, Serialize};

use crate::blind::BlindEffect;
use diagnose::effect::{Effect, Verdict};

/// Least ratio true gap / noise-level gap of a *strong* set (the acceptance bar).
pub const STRONG_RATIO: f64 = 3.0;

/// The truths drawn by the benchmark, in table order: the catalogue's generated effects,
/// `none`, and the outside effect.
pub fn truths() -> Vec<BlindEffect> {
    with_none_and_outside(Effect::generated())
}

/// The truths of the drawn-shapes benchmark (`--shapes`): [`truths`] with the structural
/// polynomial and amplitude-dependent damping added (issue 29).
pub fn shapes_truths() -> Vec<BlindEffect> {
    with_none_and_outside(Effect::drawable())
}

/// `effects` as truths, then `none` and the outside effect.
fn with_none_and_outside(effects: Vec<Effect>) -> Vec<BlindEffect> {
    effects
        .into_iter()
        .map(BlindEffect::Catalogue)
        .chain([BlindEffect::None, BlindEffect::Buffeting])
        .collect()
}

/// One drawn benchmark set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BlindSpec {
    /// Index in the benchmark.
    pub index: usize,
    /// Seed of the set (noise, effect parameters), derived from the master seed.
    pub seed: u64,
    /// The truth (one of [`shapes_truths`]), written as its name.
    #[serde(with = "crate::blind::effect_name")]
    #[schemars(with = "String")]
    pub truth: BlindEffect,
    /// Strength in [0, 1] (0 barely detectable, 1 strong; mapped by the generator).
    pub strength: f64,
    /// The drawn campaign shape (`--shapes`); absent: the default scenario.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<CampaignShape>,
}

/// A campaign shape drawn per set by the broader benchmark (issues 10 and 29): 1–3
/// configurations of the paper's Table I in one of its two readings
/// ([`TableReading`]), 3–8 of the wind speeds 3 … 10 m/s, 3–8 of the pitch amplitudes
/// 3 … 24°, the alternate functional forms for a third of the sets, the paper's absolute
/// balance noise (range × 0.1 %, [`aeroelastic::tunnel::BalanceNoise::paper`]) instead of
/// noise relative to each record's peak; six free runs at speeds drawn uniformly from
/// 0.4–1.15 U_F (so that many leave the forced K range, per mode) and, in half of the
/// sets, a still-air decay (U = 0) besides.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CampaignShape {
    /// Configuration names (Table I).
    pub configurations: Vec<String>,
    /// Wind speeds \[m/s\], increasing.
    pub wind_speeds: Vec<f64>,
    /// Pitch amplitudes \[deg\], increasing.
    pub amplitudes_deg: Vec<f64>,
    /// Whether the effects use their alternate functional form.
    pub alternate_form: bool,
    /// Which reading of Table I the configuration letters mean.
    #[serde(default)]
    pub table: TableReading,
    /// Free-run speeds as multiples of U_F (0 = a still-air decay); empty: the scenario's.
    #[serde(default)]
    pub free_speed_factors: Vec<f64>,
    /// The truth's drawn rig and nonlinear law ([`crate::physics`], `aeroform diagnose
    /// --blind N --shapes` since round 20); absent: the scenario's plate rig and law.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<crate::physics::DrawnPhysics>,
}

/// The two readings of the paper's Table I. The printed table gives configuration D as
/// f_α 1.3 Hz, f_h 2.0 Hz ([`aeroelastic::tunnel::paper_configurations`]); the captions
/// of Figs. 14, 15, 17 and 21–27 give D as α = A sin(4πt), h = 1.5A sin(2.6πt), i.e.
/// f_α 2.0 Hz, f_h 1.3 Hz: the pitch and heave columns swapped
/// ([`aeroelastic::tunnel::caption_configurations`]).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum TableReading {
    /// Table I as printed (D: f_α 1.3 Hz, f_h 2.0 Hz).
    #[default]
    AsPrinted,
    /// As the figure captions state it (D: f_α 2.0 Hz, f_h 1.3 Hz).
    FigureCaptions,
}

impl TableReading {
    /// Name in reports (`table as printed`, `figure captions`).
    pub fn label(self) -> &'static str {
        match self {
            TableReading::AsPrinted => "Table I as printed",
            TableReading::FigureCaptions => "Table I as the figure captions state it",
        }
    }
}

impl CampaignShape {
    /// The shape of the set with seed `seed` (its own stream: `split_seed(seed, 11 …)`).
    pub fn draw(seed: u64) -> Self {
        let mut k = 11u64;
        let mut next = || {
            k += 1;
            split_seed(seed, k)
        };
        let mut pick = |pool: &[f64], count: usize| -> Vec<usize> {
            let mut idx: Vec<usize> = (0..pool.len()).collect();
            for i in (1..idx.len()).rev() {
                let j = (next() % (i as u64 + 1)) as usize;
                idx.swap(i, j);
            }
            let mut v = idx[..count.min(pool.len())].to_vec();
            v.sort_unstable();
            v
        };
        let configs = aeroelastic::tunnel::paper_configurations();
        let speeds: Vec<f64> = (3..=10).map(f64::from).collect();
        let amps: Vec<f64> = (1..=8).map(|i| 3.0 * i as f64).collect();
        let dummy = vec![0.0; configs.len()];
        let n_cfg = 1 + (split_seed(seed, 31) % 3) as usize;
        let n_u = 3 + (split_seed(seed, 32) % 6) as usize;
        let n_a = 3 + (split_seed(seed, 33) % 6) as usize;
        let alternate_form = split_seed(seed, 34).is_multiple_of(3);
        let cfg_idx = pick(&dummy, n_cfg);
        let u_idx = pick(&speeds, n_u);
        let a_idx = pick(&amps, n_a);
        let table = if split_seed(seed, 35).is_multiple_of(2) {
            TableReading::AsPrinted
        } else {
            TableReading::FigureCaptions
        };
        let unit = |i: u64| identify::numerics::unit_interval(split_seed(seed, i));
        let mut free_speed_factors: Vec<f64> = (0..6)
            .map(|i| ((0.4 + 0.75 * unit(40 + i)) * 1000.0).round() / 1000.0)
            .collect();
        free_speed_factors.sort_by(f64::total_cmp);
        if split_seed(seed, 36).is_multiple_of(2) {
            free_speed_factors.insert(0, 0.0);
        }
        CampaignShape {
            configurations: cfg_idx.iter().map(|&i| configs[i].name.clone()).collect(),
            wind_speeds: u_idx.iter().map(|&i| speeds[i]).collect(),
            amplitudes_deg: a_idx.iter().map(|&i| amps[i]).collect(),
            alternate_form,
            table,
            free_speed_factors,
            physics: None,
        }
    }

    /// [`CampaignShape::draw`] with the truth's rig and law drawn too
    /// ([`crate::physics::DrawnPhysics::draw`]): what `--shapes` runs.
    pub fn draw_with_physics(seed: u64) -> Self {
        CampaignShape {
            physics: Some(crate::physics::DrawnPhysics::draw(seed)),
            ..CampaignShape::draw(seed)
        }
    }

    /// Whether the free runs include a still-air decay.
    pub fn still_air(&self) -> bool {
        self.free_speed_factors.contains(&0.0)
    }

    /// Number of (configuration, wind speed) groups: what the force level's folds rest on.
    pub fn groups(&self) -> usize {
        self.configurations.len() * self.wind_speeds.len()
    }

    /// The class a set is reported in: `3–4 groups` (leave-one-group-out folds), `5–11`,
    /// `12–24`, each with `, alternate` for the alternate forms.
    pub fn class(&self) -> String {
        let g = self.groups();
        let size = if g < 5 {
            "3–4 groups"
        } else if g < 12 {
            "5–11 groups"
        } else {
            "12–24 groups"
        };
        if self.alternate_form {
            format!("{size}, alternate forms")
        } else {
            format!("{size}, primary forms")
        }
    }

    /// The blind scenario of this shape: `base` with this campaign and absolute balance
    /// noise, and with the drawn rig and law when the shape has them (the rig's
    /// frequencies scaled so that its linear flutter speed is the drawn U_F,
    /// [`crate::physics::DrawnPhysics::scenario_files`]).
    ///
    /// # Errors
    /// As [`crate::physics::DrawnPhysics::scenario_files`].
    pub fn scenario(
        &self,
        base: &crate::blind::BlindScenario,
    ) -> crate::Result<crate::blind::BlindScenario> {
        let mut s = base.clone();
        let mut campaign = aeroelastic::tunnel::Campaign::paper();
        if self.table == TableReading::FigureCaptions {
            campaign.configurations = aeroelastic::tunnel::caption_configurations();
        }
        campaign
            .configurations
            .retain(|c| self.configurations.contains(&c.name));
        campaign.wind_speeds = self.wind_speeds.clone();
        campaign.amplitudes_deg = self.amplitudes_deg.clone();
        s.campaign = campaign;
        s.noise.balance_absolute = Some(aeroelastic::tunnel::BalanceNoise::paper());
        if !self.free_speed_factors.is_empty() {
            s.free_speed_factors = self.free_speed_factors.clone();
        }
        if let Some(p) = &self.physics {
            let (rig, model) = p.scenario_files()?;
            s.rig = rig;
            s.truth_model = model;
            s.flutter_speed = p.flutter_speed;
        }
        Ok(s)
    }

    /// The effects' functional form.
    pub fn form(&self) -> aeroelastic::effects::Form {
        if self.alternate_form {
            aeroelastic::effects::Form::Alternate
        } else {
            aeroelastic::effects::Form::Primary
        }
    }
}

/// Draws `n` sets from the master `seed`: truths uniformly over [`truths`] (a
/// balanced cyclic assignment, shuffled, so that every label gets ⌊n/11⌋ or ⌈n/11⌉ sets),
/// strengths uniform in [0, 1]. Each set's seed and strength depend only on (seed, index).
pub fn draw_specs(n: usize, seed: u64) -> Vec<BlindSpec> {
    draw_specs_from(n, seed, &truths())
}

/// [`draw_specs`] over the given `truths` (e.g. [`shapes_truths`]).
pub fn draw_specs_from(n: usize, seed: u64, truths: &[BlindEffect]) -> Vec<BlindSpec> {
    let mut order: Vec<usize> = (0..n).map(|i| i % truths.len()).collect();
    // Fisher–Yates with the mixed stream.
    for i in (1..n).rev() {
        let j = (split_seed(seed, 1_000_000 + i as u64) % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    (0..n)
        .map(|i| {
            let s = split_seed(seed, i as u64);
            BlindSpec {
                index: i,
                seed: s,
                truth: truths[order[i]],
                strength: identify::numerics::unit_interval(split_seed(s, 7)),
                shape: None,
            }
        })
        .collect()
}

/// What the diagnosis of one set gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BlindOutcome {
    /// The drawn set.
    pub spec: BlindSpec,
    /// The verdict (written as its name); `null` when the set failed (`error` says why).
    pub verdict: Option<Verdict>,
    /// Verdict confidence.
    pub confidence: f64,
    /// True gap / noise-level gap (max over levels; 1 for effect-free sets); `null` when
    /// the set failed.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub gap_ratio: f64,
    /// Headline plain shrink of the verdict (1 − after/before); `null` when the set failed.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub shrink: f64,
    /// Headline excess shrink of the verdict; `null` when the set failed.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub excess_shrink: f64,
    /// Plain held-out shrink of the true effect's own candidate, when it was scored.
    pub true_candidate_shrink: Option<f64>,
    /// Effect parameters the generator used (for the weak-cell analysis; never given to
    /// the diagnosis).
    #[serde(default)]
    pub parameters: Vec<(String, f64)>,
    /// Error message when the set could not be generated or diagnosed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Wall time of generation + diagnosis \[s\].
    pub seconds: f64,
    /// Free runs outside the forced range (system level's coverage), when assessed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncovered_runs: Option<usize>,
    /// The closed loop of an `extrapolation` (`diagnose --blind … --follow-up`): the
    /// recommended forced tests run on the truth and the set diagnosed again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub follow_up: Option<FollowUpOutcome>,
}

/// What the follow-up tests of one set gave ([`diagnose::follow_up::plan`] run on the truth).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FollowUpOutcome {
    /// Forced cases added (rows × wind speeds × amplitudes of the plan).
    pub cases: usize,
    /// Rows of the plan (one per configuration).
    pub rows: usize,
    /// The verdict on the set with the follow-up cases (written as its name).
    pub verdict: Verdict,
    /// Its confidence.
    pub confidence: f64,
    /// True gap / noise-level gap after the follow-up (the effect-free twin given the same
    /// tests; 1 for effect-free sets): whether the effect is visible once the runs are
    /// covered ([`STRONG_RATIO`]).
    pub gap_ratio: f64,
    /// Free runs still outside the forced range after the follow-up.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncovered_runs: Option<usize>,
}

impl BlindOutcome {
    /// The verdict's name for tables and messages; `error` for a failed set.
    pub fn verdict_name(&self) -> &'static str {
        self.verdict.map_or("error", Verdict::name)
    }

    /// Whether the true gap is at least [`STRONG_RATIO`] × the noise-level gap.
    pub fn strong(&self) -> bool {
        self.gap_ratio >= STRONG_RATIO
    }

    /// Whether the follow-up verdict is the right one (as [`BlindOutcome::correct`]);
    /// `None` without a follow-up.
    pub fn follow_up_correct(&self) -> Option<bool> {
        let f = self.follow_up.as_ref()?;
        let mut o = self.clone();
        o.verdict = Some(f.verdict);
        Some(o.correct())
    }

    /// Whether the verdict is the right one (`unexplained` is right for the outside effect;
    /// `none` or `extrapolation` for an effect-free set, whose only gap can come from
    /// tables extrapolated beyond the forced range).
    pub fn correct(&self) -> bool {
        let Some(verdict) = self.verdict else {
            return false;
        };
        match self.spec.truth {
            BlindEffect::Buffeting => verdict == Verdict::Unexplained,
            BlindEffect::None => matches!(verdict, Verdict::None | Verdict::Extrapolation),
            BlindEffect::Catalogue(e) => verdict == Verdict::Effect(e),
        }
    }
}

/// Acceptance statistics of a benchmark. A share or median over no sets is NaN, written
/// `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BlindSummary {
    /// Sets run.
    pub n: usize,
    /// Sets that failed to generate or diagnose.
    pub failed: usize,
    /// Strong catalogue sets.
    pub catalogue_strong: usize,
    /// Top-1 accuracy on strong catalogue sets.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub catalogue_top1: f64,
    /// Effect-free sets.
    pub none_sets: usize,
    /// Share of effect-free sets diagnosed `none`.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub none_rate: f64,
    /// Effect-free sets named an effect with confidence ≥ 0.5.
    #[serde(default)]
    pub none_named_confident: usize,
    /// Strong outside-effect sets.
    pub outside_strong: usize,
    /// Share of strong outside-effect sets diagnosed `unexplained`.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub outside_unexplained: f64,
    /// Median plain shrink of the verdict on strong catalogue sets named correctly.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub median_shrink_named: f64,
    /// Median plain shrink of the true effect's candidate on all strong catalogue sets.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub median_shrink_true_candidate: f64,
    /// Median excess shrink of the verdict on strong catalogue sets named correctly.
    #[serde(with = "nan_as_null")]
    #[schemars(with = "Option<f64>")]
    pub median_excess_shrink_named: f64,
    /// Top-1 accuracy per catalogue effect on its strong sets (name, correct, total).
    pub per_effect: Vec<(String, usize, usize)>,
    /// Mean wall time per set \[s\].
    pub mean_seconds: f64,
}

/// Serde form of a statistic that is NaN over no sets: NaN is written `null` (JSON has no
/// NaN) and `null` reads back as NaN, so that a benchmark document reads as its own type.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        if x.is_nan() {
            s.serialize_none()
        } else {
            s.serialize_f64(*x)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// A whole benchmark: settings, every outcome, confusion matrices and the summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BlindReport {
    /// Always `aeroform-blind/1`.
    pub format: String,
    /// Master seed.
    pub seed: u64,
    /// Row labels (truth).
    pub truth_labels: Vec<String>,
    /// Column labels (verdict).
    pub verdict_labels: Vec<String>,
    /// Confusion matrix over all sets: `all[i][j]` = sets of truth i diagnosed j.
    pub confusion_all: Vec<Vec<usize>>,
    /// Confusion matrix over strong sets (and every effect-free set).
    pub confusion_strong: Vec<Vec<usize>>,
    /// Acceptance statistics.
    pub summary: BlindSummary,
    /// The same statistics per campaign-shape class ([`CampaignShape::class`]), then per
    /// truth-law form (Eq. 19 or not, with drawn physics), Table I reading, with or without
    /// a still-air decay, and with every free run covered or not (`not: …`), when the
    /// shapes were drawn.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub per_shape: Vec<(String, BlindSummary)>,
    /// Every set.
    pub outcomes: Vec<BlindOutcome>,
}

fn ratio(num: usize, den: usize) -> f64 {
    if den == 0 {
        f64::NAN
    } else {
        num as f64 / den as f64
    }
}

/// Confusion matrices and acceptance statistics of a set of outcomes.
pub fn summarize(seed: u64, outcomes: Vec<BlindOutcome>) -> BlindReport {
    let tl = if outcomes.iter().any(|o| !truths().contains(&o.spec.truth)) {
        shapes_truths()
    } else {
        truths()
    };
    let vl: Vec<Verdict> = Verdict::all().collect();
    let mut all = vec![vec![0usize; vl.len()]; tl.len()];
    let mut strong = vec![vec![0usize; vl.len()]; tl.len()];
    for o in outcomes.iter().filter(|o| o.error.is_none()) {
        let (Some(i), Some(j)) = (
            tl.iter().position(|t| *t == o.spec.truth),
            o.verdict.and_then(|v| vl.iter().position(|l| *l == v)),
        ) else {
            continue;
        };
        all[i][j] += 1;
        if o.strong() || o.spec.truth == BlindEffect::None {
            strong[i][j] += 1;
        }
    }
    let summary = summary_of(&outcomes);
    let mut classes: Vec<String> = outcomes
        .iter()
        .filter_map(|o| o.spec.shape.as_ref().map(CampaignShape::class))
        .collect();
    classes.sort();
    classes.dedup();
    let per_shape = classes
        .into_iter()
        .map(|c| {
            let sub: Vec<BlindOutcome> = outcomes
                .iter()
                .filter(|o| o.spec.shape.as_ref().is_some_and(|s| s.class() == c))
                .cloned()
                .collect();
            (c, summary_of(&sub))
        })
        .collect::<Vec<_>>();
    let mut per_shape = per_shape;
    // the splits of issue 29: truth law form (drawn physics), Table I reading, still-air
    // decay, free runs covered
    type Split = (&'static str, fn(&BlindOutcome) -> Option<bool>);
    let splits: [Split; 4] = [
        ("truth law in the Eq. 19 form", |o| {
            o.spec
                .shape
                .as_ref()
                .and_then(|s| s.physics.as_ref())
                .map(|p| matches!(p.law, crate::physics::DrawnLaw::Eq19 { .. }))
        }),
        ("Table I as printed", |o| {
            o.spec
                .shape
                .as_ref()
                .map(|s| s.table == TableReading::AsPrinted)
        }),
        ("with a still-air decay", |o| {
            o.spec.shape.as_ref().map(CampaignShape::still_air)
        }),
        ("every free run covered", |o| {
            o.uncovered_runs.map(|u| u == 0)
        }),
    ];
    let shaped = outcomes.iter().any(|o| o.spec.shape.is_some());
    for (name, f) in splits.into_iter().filter(|_| shaped) {
        for want in [true, false] {
            let sub: Vec<BlindOutcome> = outcomes
                .iter()
                .filter(|o| f(o) == Some(want))
                .cloned()
                .collect();
            if !sub.is_empty() {
                let label = if want {
                    name.to_string()
                } else {
                    format!("not: {name}")
                };
                per_shape.push((label, summary_of(&sub)));
            }
        }
    }
    BlindReport {
        format: "aeroform-blind/1".into(),
        seed,
        truth_labels: tl.iter().map(|t| t.name().to_string()).collect(),
        verdict_labels: vl.iter().map(|v| v.name().to_string()).collect(),
        confusion_all: all,
        confusion_strong: strong,
        summary,
        per_shape,
        outcomes,
    }
}

/// The acceptance statistics of `outcomes`.
fn summary_of(outcomes: &[BlindOutcome]) -> BlindSummary {
    let ok: Vec<&BlindOutcome> = outcomes.iter().filter(|o| o.error.is_none()).collect();
    let is_cat = |o: &&&BlindOutcome| matches!(o.spec.truth, BlindEffect::Catalogue(_));
    let cat_strong: Vec<&&BlindOutcome> = ok.iter().filter(|o| o.strong()).filter(is_cat).collect();
    let none: Vec<&&BlindOutcome> = ok
        .iter()
        .filter(|o| o.spec.truth == BlindEffect::None)
        .collect();
    let out_strong: Vec<&&BlindOutcome> = ok
        .iter()
        .filter(|o| o.spec.truth == BlindEffect::Buffeting && o.strong())
        .collect();
    let per_effect = Effect::ALL
        .iter()
        .map(|e| {
            let sets: Vec<_> = cat_strong
                .iter()
                .filter(|o| o.spec.truth == BlindEffect::Catalogue(*e))
                .collect();
            (
                e.name().to_string(),
                sets.iter().filter(|o| o.correct()).count(),
                sets.len(),
            )
        })
        .collect();
    BlindSummary {
        n: outcomes.len(),
        failed: outcomes.len() - ok.len(),
        catalogue_strong: cat_strong.len(),
        catalogue_top1: ratio(
            cat_strong.iter().filter(|o| o.correct()).count(),
            cat_strong.len(),
        ),
        none_sets: none.len(),
        none_rate: ratio(none.iter().filter(|o| o.correct()).count(), none.len()),
        none_named_confident: none
            .iter()
            .filter(|o| matches!(o.verdict, Some(Verdict::Effect(_))) && o.confidence >= 0.5)
            .count(),
        outside_strong: out_strong.len(),
        outside_unexplained: ratio(
            out_strong.iter().filter(|o| o.correct()).count(),
            out_strong.len(),
        ),
        median_shrink_named: median_finite(
            &cat_strong
                .iter()
                .filter(|o| o.correct())
                .map(|o| o.shrink)
                .collect::<Vec<f64>>(),
        ),
        median_shrink_true_candidate: median_finite(
            &cat_strong
                .iter()
                .filter_map(|o| o.true_candidate_shrink)
                .collect::<Vec<f64>>(),
        ),
        median_excess_shrink_named: median_finite(
            &cat_strong
                .iter()
                .filter(|o| o.correct())
                .map(|o| o.excess_shrink)
                .collect::<Vec<f64>>(),
        ),
        per_effect,
        mean_seconds: if outcomes.is_empty() {
            0.0
        } else {
            outcomes.iter().map(|o| o.seconds).sum::<f64>() / outcomes.len() as f64
        },
    }
}

/// The confusion matrix as a Markdown table (rows truth, columns verdict).
pub fn confusion_markdown(rows: &[String], cols: &[String], m: &[Vec<usize>]) -> String {
    // a verdict name gets its short label; anything else (not a verdict) is shown as is
    let short = |s: &str| -> String {
        diagnose::effect::Verdict::from_name(s)
            .map_or_else(|_| s.to_string(), |v| v.short_label().into())
    };
    let mut s = String::from("| truth \\ verdict |");
    for c in cols {
        s.push_str(&format!(" {} |", short(c)));
    }
    s.push_str(" n |\n|---|");
    for _ in cols {
        s.push_str("---:|");
    }
    s.push_str("---:|\n");
    for (r, row) in rows.iter().zip(m) {
        s.push_str(&format!("| {r} |"));
        for v in row {
            if *v == 0 {
                s.push_str(" · |");
            } else {
                s.push_str(&format!(" {v} |"));
            }
        }
        s.push_str(&format!(" {} |\n", row.iter().sum::<usize>()));
    }
    s
}

/// The acceptance lines of a report, one per criterion, with PASS/FAIL against the issue's
/// bars (top-1 ≥ 90 %, none ≥ 95 %, unexplained ≥ 80 %, median shrink ≥ 70 %).
pub fn acceptance_lines(s: &BlindSummary) -> Vec<String> {
    let pf = |ok: bool| if ok { "PASS" } else { "FAIL" };
    vec![
        format!(
            "catalogue top-1 on strong sets: {:.1} % of {} (bar 90 %) {}",
            100.0 * s.catalogue_top1,
            s.catalogue_strong,
            pf(s.catalogue_top1 >= 0.9)
        ),
        format!(
            "`none`/`extrapolation` on effect-free sets: {:.1} % of {} (bar 97 %) {}",
            100.0 * s.none_rate,
            s.none_sets,
            pf(s.none_rate >= 0.97)
        ),
        format!(
            "effect-free sets named an effect with confidence ≥ 0.5: {} (bar 0) {}",
            s.none_named_confident,
            pf(s.none_named_confident == 0)
        ),
        format!(
            "`unexplained` on strong outside-effect sets: {:.1} % of {} (bar 80 %) {}",
            100.0 * s.outside_unexplained,
            s.outside_strong,
            pf(s.outside_unexplained >= 0.8)
        ),
        format!(
            "median held-out shrink, named effect added (strong, correct): {:.1} % (bar 70 %) {}; \
             excess shrink {:.1} %; true effect's candidate on all strong sets {:.1} %",
            100.0 * s.median_shrink_named,
            pf(s.median_shrink_named >= 0.7),
            100.0 * s.median_excess_shrink_named,
            100.0 * s.median_shrink_true_candidate
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Drawn shapes stay in their ranges, depend only on the seed, cover every size and
    /// give the alternate forms to about a third of the sets.
    #[test]
    fn campaign_shapes_are_drawn_in_range_and_reproducibly() {
        let shapes: Vec<CampaignShape> = (0..600)
            .map(|i| CampaignShape::draw(split_seed(9, i)))
            .collect();
        for s in &shapes {
            assert!((1..=3).contains(&s.configurations.len()), "{s:?}");
            assert!((3..=8).contains(&s.wind_speeds.len()), "{s:?}");
            assert!((3..=8).contains(&s.amplitudes_deg.len()), "{s:?}");
            assert!(s.wind_speeds.windows(2).all(|w| w[0] < w[1]));
            assert!(s.wind_speeds.iter().all(|u| (3.0..=10.0).contains(u)));
            assert!(s.amplitudes_deg.iter().all(|a| (3.0..=24.0).contains(a)));
            let sc = s.scenario(&crate::blind::BlindScenario::default()).unwrap();
            assert_eq!(sc.campaign.configurations.len(), s.configurations.len());
            assert!(sc.noise.balance_absolute.is_some());
        }
        assert_eq!(CampaignShape::draw(split_seed(9, 3)), shapes[3]);
        // issue 29: free runs over 0.4–1.15 U_F, a still-air decay in about half of the
        // sets, both readings of Table I
        for s in &shapes {
            let wind: Vec<f64> = s
                .free_speed_factors
                .iter()
                .copied()
                .filter(|f| *f > 0.0)
                .collect();
            assert_eq!(wind.len(), 6, "{s:?}");
            assert!(wind.iter().all(|f| (0.4..=1.15).contains(f)), "{s:?}");
            let sc = s.scenario(&crate::blind::BlindScenario::default()).unwrap();
            assert_eq!(sc.free_speed_factors, s.free_speed_factors);
            let d = sc.campaign.configurations.iter().find(|c| c.name == "D");
            if let Some(d) = d {
                let printed = s.table == TableReading::AsPrinted;
                assert_eq!(d.freq_pitch, if printed { 1.3 } else { 2.0 }, "{s:?}");
            }
        }
        let still = shapes.iter().filter(|s| s.still_air()).count();
        assert!(
            (250..350).contains(&still),
            "{still} of 600 with a still-air decay"
        );
        let captions = shapes
            .iter()
            .filter(|s| s.table == TableReading::FigureCaptions)
            .count();
        assert!(
            (250..350).contains(&captions),
            "{captions} of 600 caption readings"
        );
        let alt = shapes.iter().filter(|s| s.alternate_form).count();
        assert!((150..250).contains(&alt), "{alt} of 600 alternate");
        for class in ["3–4 groups", "5–11 groups", "12–24 groups"] {
            assert!(
                shapes.iter().any(|s| s.class().starts_with(class)),
                "{class}"
            );
        }
    }

    fn outcome(truth: &str, verdict: &str, ratio: f64, shrink: f64) -> BlindOutcome {
        BlindOutcome {
            spec: BlindSpec {
                index: 0,
                seed: 1,
                truth: BlindEffect::from_name(truth).unwrap(),
                strength: 0.5,
                shape: None,
            },
            verdict: Some(Verdict::from_name(verdict).unwrap()),
            confidence: 0.9,
            gap_ratio: ratio,
            shrink,
            excess_shrink: shrink,
            true_candidate_shrink: Some(shrink),
            parameters: vec![],
            error: None,
            seconds: 0.1,
            uncovered_runs: None,
            follow_up: None,
        }
    }

    #[test]
    fn draws_are_balanced_and_deterministic() {
        let a = draw_specs(330, 42);
        assert_eq!(a, draw_specs(330, 42));
        assert_ne!(a, draw_specs(330, 43));
        for t in truths() {
            assert_eq!(a.iter().filter(|s| s.truth == t).count(), 30, "{t}");
        }
        let mean = a.iter().map(|s| s.strength).sum::<f64>() / 330.0;
        assert!((mean - 0.5).abs() < 0.06, "{mean}");
        assert!(a.iter().all(|s| (0.0..1.0).contains(&s.strength)));
    }

    #[test]
    fn summary_counts_only_strong_sets_for_accuracy() {
        let r = summarize(
            3,
            vec![
                outcome("friction", "friction", 5.0, 0.8),
                outcome("friction", "none", 1.2, 0.0), // weak: not counted
                outcome("freeplay", "structural_cubic", 4.0, 0.5),
                outcome("none", "none", 1.0, 0.0),
                outcome("none", "higher_order", 1.0, 0.0),
                outcome("buffeting", "unexplained", 6.0, 0.1),
            ],
        );
        let s = &r.summary;
        assert_eq!(s.catalogue_strong, 2);
        assert!((s.catalogue_top1 - 0.5).abs() < 1e-12);
        assert!((s.none_rate - 0.5).abs() < 1e-12);
        assert!((s.outside_unexplained - 1.0).abs() < 1e-12);
        assert!((s.median_shrink_named - 0.8).abs() < 1e-12);
        let fi = r.truth_labels.iter().position(|l| l == "friction").unwrap();
        let ni = r.verdict_labels.iter().position(|l| l == "none").unwrap();
        assert_eq!(r.confusion_all[fi][ni], 1);
        assert_eq!(r.confusion_strong[fi][ni], 0);
        let md = confusion_markdown(&r.truth_labels, &r.verdict_labels, &r.confusion_all);
        assert!(md.contains("| friction |"), "{md}");
        assert_eq!(acceptance_lines(s).len(), 5);
    }
}
