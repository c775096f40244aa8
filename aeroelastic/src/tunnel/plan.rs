//! A campaign plan: forced-motion rows a tunnel engineer runs, each a configuration (its
//! forcing frequencies, amplitude ratio and mean angle) with its own wind speeds and pitch
//! amplitudes. Written by `aeroform diagnose` as the follow-up tests that would cover the
//! free runs outside the forced range (issue 42 item 4), read by `aeroform tunnel forced
//! --campaign-file`. File format `aeroform-campaign/1` (docs/DATA_FORMAT.md).

use serde::{Deserialize, Serialize};

use super::motion::{Campaign, Configuration, ForcedCase};
use crate::{Error, Result};
use identify::limits::{MAX_CASES, MAX_PITCH_DEG, MAX_SPEED};

/// The `format` tag of a campaign plan file.
pub const PLAN_FORMAT: &str = "aeroform-campaign/1";

/// One row of a plan: a configuration forced at each of `wind_speeds` × `amplitudes_deg`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanRow {
    /// Rank of the row (1 = the test that settles most; see the plan's `note`).
    pub rank: usize,
    /// The configuration: forcing frequencies \[Hz\], heave/pitch amplitude ratio
    /// \[mm/deg\], mean pitch \[deg\].
    pub configuration: Configuration,
    /// Wind speeds U \[m/s\], each in (0, 1000].
    pub wind_speeds: Vec<f64>,
    /// Pitch amplitudes \[deg\], each in (0, 90].
    pub amplitudes_deg: Vec<f64>,
    /// What the row is for (e.g. the free runs it covers); not read by the tunnel.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub covers: Vec<String>,
    /// Why it has its rank (e.g. the held-out gap of those runs over the noise level).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Records per case, each a fresh record of `record_duration_s` (absent: one record,
    /// ids `{config}-U{U}-A{A}`; present: ids `{config}-U{U}-A{A}-R{k}`, k = 1…repeats),
    /// in [1, 100]. Repeats of one condition add its evidence like one record `repeats`
    /// times as long.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeats: Option<usize>,
    /// Length of each record the row assumes \[s\], in (0, 3600] (absent: the tunnel's
    /// `--duration`); `aeroform tunnel forced --campaign-file` records at it when
    /// `--duration` is not given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub record_duration_s: Option<f64>,
    /// Predicted discrimination of the row \[-\]: the held-out residual energy by which
    /// the force level's consistent candidate and the baseline differ at the row's records,
    /// over the noise energy of one record, summed over the row's records (absent: not
    /// predicted, e.g. no significant force-level candidate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discrimination: Option<f64>,
}

/// A campaign plan (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CampaignPlan {
    /// Always [`PLAN_FORMAT`].
    pub format: String,
    /// What the plan is for and how its rows are ranked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The rows, in rank order.
    pub rows: Vec<PlanRow>,
}

impl CampaignPlan {
    /// Parses and checks a plan file's text; `source` names it in errors.
    ///
    /// # Errors
    /// [`Error::Toml`] for text that is not a plan (unknown key, wrong type, with line and
    /// column); [`Error::InvalidParameter`] naming `rows[i].field` for a wrong `format`, an
    /// empty plan, a speed, amplitude or frequency outside its range, or more cases than
    /// `MAX_CASES`.
    pub fn parse(text: &str, source: &str) -> Result<Self> {
        let plan: CampaignPlan = toml::from_str(text).map_err(|e| Error::Toml {
            source_name: source.to_string(),
            message: e.to_string(),
        })?;
        plan.check(source)?;
        Ok(plan)
    }

    /// Checks the plan's values (see [`CampaignPlan::parse`]).
    ///
    /// # Errors
    /// As [`CampaignPlan::parse`], without the TOML errors.
    pub fn check(&self, source: &str) -> Result<()> {
        let bad = |field: String, value: f64, message: &str| Error::InvalidParameter {
            field: format!("{source}: {field}"),
            value,
            message: message.to_string(),
        };
        if self.format != PLAN_FORMAT {
            return Err(bad(
                "format".into(),
                f64::NAN,
                &format!("{:?} is not `{PLAN_FORMAT}`", self.format),
            ));
        }
        if self.rows.is_empty() {
            return Err(bad("rows".into(), 0.0, "a plan needs at least one row"));
        }
        let mut n = 0usize;
        for (i, r) in self.rows.iter().enumerate() {
            let c = &r.configuration;
            for (name, v) in [
                ("configuration.freq_pitch", c.freq_pitch),
                ("configuration.freq_heave", c.freq_heave),
            ] {
                if !(v.is_finite() && v > 0.0 && v <= 1e4) {
                    return Err(bad(
                        format!("rows[{i}].{name}"),
                        v,
                        "must be in (0, 1e4] Hz",
                    ));
                }
            }
            if !(c.amplitude_ratio.is_finite() && c.amplitude_ratio.abs() <= 1e3) {
                return Err(bad(
                    format!("rows[{i}].configuration.amplitude_ratio"),
                    c.amplitude_ratio,
                    "must be finite, |r| ≤ 1000 mm/deg",
                ));
            }
            if !(c.mean_pitch_deg.is_finite() && c.mean_pitch_deg.abs() <= MAX_PITCH_DEG) {
                return Err(bad(
                    format!("rows[{i}].configuration.mean_pitch_deg"),
                    c.mean_pitch_deg,
                    "must be within ±90 deg",
                ));
            }
            if !identify::dataset::is_valid_case_id(&c.name) {
                return Err(bad(
                    format!("rows[{i}].configuration.name"),
                    f64::NAN,
                    "must be a label of [A-Za-z0-9._-] characters",
                ));
            }
            for (j, &u) in r.wind_speeds.iter().enumerate() {
                if !(u.is_finite() && u > 0.0 && u <= MAX_SPEED) {
                    return Err(bad(
                        format!("rows[{i}].wind_speeds[{j}]"),
                        u,
                        "must be in (0, 1000] m/s",
                    ));
                }
            }
            for (j, &a) in r.amplitudes_deg.iter().enumerate() {
                if !(a.is_finite() && a > 0.0 && a <= MAX_PITCH_DEG) {
                    return Err(bad(
                        format!("rows[{i}].amplitudes_deg[{j}]"),
                        a,
                        "must be in (0, 90] deg",
                    ));
                }
            }
            if let Some(m) = r.repeats {
                if !(1..=100).contains(&m) {
                    return Err(bad(
                        format!("rows[{i}].repeats"),
                        m as f64,
                        "must be in [1, 100]",
                    ));
                }
            }
            if let Some(d) = r.record_duration_s {
                if !(d.is_finite() && d > 0.0 && d <= 3600.0) {
                    return Err(bad(
                        format!("rows[{i}].record_duration_s"),
                        d,
                        "must be in (0, 3600] s",
                    ));
                }
            }
            if r.wind_speeds.is_empty() || r.amplitudes_deg.is_empty() {
                return Err(bad(
                    format!("rows[{i}]"),
                    0.0,
                    "needs at least one wind speed and one amplitude",
                ));
            }
            n = n.saturating_add(
                r.wind_speeds
                    .len()
                    .saturating_mul(r.amplitudes_deg.len())
                    .saturating_mul(r.repeats.unwrap_or(1)),
            );
            if n > MAX_CASES {
                return Err(bad(
                    "rows".into(),
                    n as f64,
                    &format!("more than {MAX_CASES} cases"),
                ));
            }
        }
        let cases = self.cases();
        let mut ids: Vec<&str> = cases.iter().map(|c| c.id.as_str()).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(bad(
                "rows".into(),
                f64::NAN,
                &format!(
                    "case `{}` appears twice (same configuration, speed and amplitude)",
                    w[0]
                ),
            ));
        }
        Ok(())
    }

    /// The plan's cases, row by row, each row as [`Campaign::cases`] of its one
    /// configuration (ids `{config}-U{U}-A{A}`), each case `repeats` times with ids
    /// `{config}-U{U}-A{A}-R{k}` when the row has `repeats`.
    pub fn cases(&self) -> Vec<ForcedCase> {
        self.rows
            .iter()
            .flat_map(|r| {
                let grid = Campaign {
                    configurations: vec![r.configuration.clone()],
                    amplitudes_deg: r.amplitudes_deg.clone(),
                    wind_speeds: r.wind_speeds.clone(),
                }
                .cases();
                match r.repeats {
                    None => grid,
                    Some(m) => grid
                        .into_iter()
                        .flat_map(|c| {
                            (1..=m).map(move |k| ForcedCase {
                                id: format!("{}-R{k}", c.id),
                                ..c.clone()
                            })
                        })
                        .collect(),
                }
            })
            .collect()
    }

    /// The record length the rows ask for \[s\], when every row that gives one gives the
    /// same (`None` when no row gives one).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `rows[i].record_duration_s` when two rows ask for
    /// different lengths (record such a plan row by row).
    pub fn record_duration(&self) -> Result<Option<f64>> {
        let mut out: Option<f64> = None;
        for (i, r) in self.rows.iter().enumerate() {
            match (out, r.record_duration_s) {
                (Some(a), Some(b)) if a != b => {
                    return Err(Error::InvalidParameter {
                        field: format!("rows[{i}].record_duration_s"),
                        value: b,
                        message: format!("differs from an earlier row's {a} s"),
                    })
                }
                (None, Some(b)) => out = Some(b),
                _ => {}
            }
        }
        Ok(out)
    }

    /// The plan as TOML text (what [`CampaignPlan::parse`] reads back).
    ///
    /// # Errors
    /// [`Error::Toml`] if serialisation fails (it does not for a checked plan).
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Toml {
            source_name: "campaign plan".into(),
            message: e.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> CampaignPlan {
        CampaignPlan {
            format: PLAN_FORMAT.into(),
            note: Some("test".into()),
            rows: vec![PlanRow {
                rank: 1,
                configuration: Configuration {
                    name: "F".into(),
                    freq_pitch: 1.3,
                    freq_heave: 1.1,
                    amplitude_ratio: 2.0,
                    mean_pitch_deg: 0.0,
                },
                wind_speeds: vec![1.44, 2.25],
                amplitudes_deg: vec![1.0, 3.0],
                covers: vec!["free-2".into()],
                reason: None,
                repeats: None,
                record_duration_s: None,
                discrimination: None,
            }],
        }
    }

    #[test]
    fn a_plan_round_trips_and_gives_its_grid() {
        let p = plan();
        let text = p.to_toml().unwrap();
        let q = CampaignPlan::parse(&text, "plan.toml").unwrap();
        assert_eq!(p, q);
        let ids: Vec<String> = q.cases().into_iter().map(|c| c.id).collect();
        assert_eq!(
            ids,
            ["F-U1.44-A1", "F-U1.44-A3", "F-U2.25-A1", "F-U2.25-A3"]
        );
    }

    #[test]
    fn repeats_give_distinct_ids_and_count_against_the_limit() {
        let mut p = plan();
        p.rows[0].repeats = Some(2);
        p.rows[0].record_duration_s = Some(8.0);
        let text = p.to_toml().unwrap();
        let q = CampaignPlan::parse(&text, "plan.toml").unwrap();
        assert_eq!(p, q);
        let ids: Vec<String> = q.cases().into_iter().map(|c| c.id).collect();
        assert_eq!(ids.len(), 8);
        assert_eq!(ids[0], "F-U1.44-A1-R1");
        assert_eq!(ids[1], "F-U1.44-A1-R2");
        assert_eq!(q.record_duration().unwrap(), Some(8.0));
        // an old plan (no repeats, no duration) still reads
        let old = "format = \"aeroform-campaign/1\"\n[[rows]]\nrank = 1\nwind_speeds = [2.0]\n\
                   amplitudes_deg = [1.0]\n[rows.configuration]\nname = \"F\"\n\
                   freq_pitch = 1.3\nfreq_heave = 1.1\namplitude_ratio = 0.0\n\
                   mean_pitch_deg = 0.0\n";
        let o = CampaignPlan::parse(old, "old").unwrap();
        assert_eq!(o.cases()[0].id, "F-U2-A1");
        assert_eq!(o.record_duration().unwrap(), None);
        let mut p = plan();
        p.rows[0].repeats = Some(0);
        let e = p.check("plan.toml").unwrap_err().to_string();
        assert!(e.contains("rows[0].repeats"), "{e}");
        let mut p = plan();
        p.rows[0].record_duration_s = Some(-1.0);
        let e = p.check("plan.toml").unwrap_err().to_string();
        assert!(e.contains("rows[0].record_duration_s"), "{e}");
    }

    #[test]
    fn bad_plans_are_refused_naming_the_field() {
        let mut p = plan();
        p.rows[0].wind_speeds[1] = f64::NAN;
        let e = p.check("plan.toml").unwrap_err().to_string();
        assert!(e.contains("rows[0].wind_speeds[1]"), "{e}");
        let mut p = plan();
        p.rows[0].amplitudes_deg.push(1.0);
        let e = p.check("plan.toml").unwrap_err().to_string();
        assert!(e.contains("appears twice"), "{e}");
        let e = CampaignPlan::parse(
            "format = \"aeroform-campaign/1\"\nrows = []\nextra = 1\n",
            "p",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("extra"), "{e}");
        let e = CampaignPlan::parse("format = \"x\"\nrows = []\n", "p")
            .unwrap_err()
            .to_string();
        assert!(e.contains("format"), "{e}");
    }
}
