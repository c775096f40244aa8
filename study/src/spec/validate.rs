//! The study file's range and consistency checks, one function per section of the file
//! (`[data]`, `[identify]`, `[structure]`, `[aero]`, `[flutter]`, `[branch]`, `[lco]`,
//! `[outputs]`). Each returns `Err((dotted key, message))` for the first value it refuses;
//! [`Study::parse`](super::Study::parse) turns that key into the line of the file.
//!
//! The sections are checked in a fixed order (the order of [`study`]), so that a file with
//! several faults is always refused for the same one.

use aeroelastic::files::{ModelFile, ModelKind};

use super::types::{
    DataSpec, FlutterSpec, LcoSpec, StudyModel, StudySpec, StudyStructure, SyntheticSpec,
    TableIvSpec, VirtualSpec, FIGURE_KINDS, STRUCTURE_KEYS,
};
use crate::limits::{abs_at_most, positive_at_most, samples, LimitError, MAX_CASES, MAX_SPEED};

/// A refusal: the dotted key of the value and the message.
type Invalid = (String, String);

/// The result of one check.
type Check = Result<(), Invalid>;

fn err(k: &str, m: String) -> Check {
    Err((k.to_string(), m))
}

/// `v` finite and > 0.
fn pos(k: &str, v: f64) -> Check {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err((k.to_string(), format!("{v} must be finite and > 0")))
    }
}

/// `v` finite.
fn fin(k: &str, v: f64) -> Check {
    if v.is_finite() {
        Ok(())
    } else {
        Err((k.to_string(), format!("{v} must be finite")))
    }
}

/// A cap or plausibility check of `crate::limits`, made before anything is allocated.
fn lim(r: Result<f64, LimitError>) -> Check {
    r.map(|_| ()).map_err(|e| (e.field, e.message))
}

/// Every check of a study, in the file's order of sections.
pub(super) fn study(s: &StudySpec) -> Check {
    if let Some(k) = s.structure.as_ref().and_then(StudyStructure::unknown_key) {
        return err(
            &format!("structure.{k}"),
            format!(
                "unknown field `{k}`, expected one of {}",
                STRUCTURE_KEYS
                    .iter()
                    .map(|k| format!("`{k}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
    if s.name.is_empty()
        || !s
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
    {
        return err("name", format!("`{}` must match [A-Za-z0-9._-]+", s.name));
    }
    if let Some(d) = &s.data {
        data(d)?;
    }
    let has_virtual = s.data.as_ref().is_some_and(|d| d.virtual_tunnel.is_some());
    let id = s.identify.clone().unwrap_or_default();
    identify(&id, s.data.as_ref())?;
    if (s.flutter.is_some() || s.lco.is_some() || s.branch.is_some())
        && (s.structure.is_none() || s.aero.is_none())
    {
        return err(
            if s.structure.is_none() {
                "structure"
            } else {
                "aero"
            },
            "the flutter, LCO and branch stages need [structure] and [aero]".into(),
        );
    }
    if let Some(outer) = &s.structure {
        structure(outer)?;
    }
    if let Some(a) = &s.aero {
        check_aero("aero", a, s.data.is_some())?;
        if a.kind == ModelKind::Identified && !a.nonlinear.is_empty() {
            return err(
                "aero.nonlinear",
                "the identified model brings its own nonlinear terms; remove [[aero.nonlinear]]"
                    .into(),
            );
        }
    }
    if let Some(f) = &s.flutter {
        let no_file = s.aero.as_ref().is_none_or(|a| a.file.is_none());
        flutter(f, s.data.is_some(), has_virtual, no_file)?;
    }
    if let Some(b) = &s.branch {
        branch(b)?;
    }
    if let Some(l) = &s.lco {
        lco(l, has_virtual)?;
    }
    outputs(s, &id)
}

/// `[data]`: exactly one source, and that source's values.
fn data(d: &DataSpec) -> Check {
    let n = [
        d.dataset.is_some(),
        d.synthetic.is_some(),
        d.table_iv.is_some(),
        d.virtual_tunnel.is_some(),
    ]
    .iter()
    .filter(|b| **b)
    .count();
    if n != 1 {
        return err(
            "data",
            format!("give exactly one of dataset, [data.synthetic], [data.table_iv], [data.virtual] ({n} given)"),
        );
    }
    if let Some(v) = &d.virtual_tunnel {
        virtual_tunnel(v)?;
    }
    if let Some(sy) = &d.synthetic {
        synthetic(sy)?;
    }
    if let Some(t) = &d.table_iv {
        table_iv(t)?;
    }
    Ok(())
}

/// The number of cases a virtual campaign records, before the still-air doubling: the
/// paper campaign's 7 configurations × 64, or one configuration's 64.
fn virtual_cases(v: &VirtualSpec) -> usize {
    if v.campaign == aeroelastic::tunnel::CampaignName::Paper {
        448
    } else {
        64
    }
}

/// The number of cases of a synthetic campaign (configurations × amplitudes × speeds).
fn synthetic_cases(sy: &SyntheticSpec) -> u128 {
    sy.config.len() as u128 * sy.amplitudes_deg.len() as u128 * sy.speeds.len() as u128
}

/// `[data.virtual]`.
fn virtual_tunnel(v: &VirtualSpec) -> Check {
    if v.model.is_some() == v.aero.is_some() {
        return err(
            "data.virtual",
            "give exactly one of `model` (a model file) and [data.virtual.aero]".into(),
        );
    }
    pos("data.virtual.duration", v.duration)?;
    let records = virtual_cases(v) * if v.still_air { 2 } else { 1 };
    lim(samples(
        "data.virtual.duration",
        "data.virtual.duration",
        records,
        v.duration,
        512.0,
    ))?;
    if let Some(a) = &v.aero {
        check_aero("data.virtual.aero", a, false)?;
    }
    Ok(())
}

/// `[data.synthetic]`: the section, the grid of cases and its cap, the configurations
/// (below the Nyquist frequency), the noise levels and the law's terms.
fn synthetic(sy: &SyntheticSpec) -> Check {
    pos("data.synthetic.section.chord", sy.section.chord)?;
    pos("data.synthetic.section.span", sy.section.span)?;
    pos("data.synthetic.section.air_density", sy.section.air_density)?;
    pos("data.synthetic.rate", sy.rate)?;
    pos("data.synthetic.duration", sy.duration)?;
    if sy.config.is_empty() {
        return err("data.synthetic.config", "at least one configuration".into());
    }
    lim(positive_at_most(
        "data.synthetic.section.chord",
        sy.section.chord,
        100.0,
        "m",
    ))?;
    lim(positive_at_most(
        "data.synthetic.section.span",
        sy.section.span,
        1000.0,
        "m",
    ))?;
    lim(positive_at_most(
        "data.synthetic.section.air_density",
        sy.section.air_density,
        2000.0,
        "kg/m^3",
    ))?;
    let n_cases = synthetic_cases(sy);
    if n_cases > MAX_CASES as u128 {
        return err(
            "data.synthetic.speeds",
            format!(
                "{} configurations × {} amplitudes × {} speeds = {n_cases} cases \
                 exceed the cap of {MAX_CASES} (the limits table's MAX_CASES: \
                 `run` holds every case)",
                sy.config.len(),
                sy.amplitudes_deg.len(),
                sy.speeds.len()
            ),
        );
    }
    lim(samples(
        "data.synthetic.duration",
        "data.synthetic.rate",
        n_cases as usize,
        sy.duration,
        sy.rate,
    ))?;
    for (i, a) in sy.amplitudes_deg.iter().enumerate() {
        lim(positive_at_most(
            &format!("data.synthetic.amplitudes_deg[{i}]"),
            *a,
            90.0,
            "deg",
        ))?;
    }
    for (i, u) in sy.speeds.iter().enumerate() {
        lim(positive_at_most(
            &format!("data.synthetic.speeds[{i}]"),
            *u,
            MAX_SPEED,
            "m/s",
        ))?;
    }
    for (i, c) in sy.config.iter().enumerate() {
        for (k, f) in [("freq_pitch", c.freq_pitch), ("freq_heave", c.freq_heave)] {
            if f.is_finite() && f >= 0.5 * sy.rate {
                return err(
                    &format!("data.synthetic.config[{i}].{k}"),
                    format!(
                        "{f} Hz is not below the Nyquist frequency {} Hz of \
                         rate = {} Hz",
                        0.5 * sy.rate,
                        sy.rate
                    ),
                );
            }
        }
        lim(positive_at_most(
            &format!("data.synthetic.config[{i}].mm_per_deg"),
            c.mm_per_deg,
            1000.0,
            "mm/deg",
        ))?;
    }
    for (ch, terms) in [("lift", &sy.law.lift), ("moment", &sy.law.moment)] {
        for (i, t) in terms.iter().enumerate() {
            fin(
                &format!("data.synthetic.law.{ch}[{i}].coefficient"),
                t.coefficient,
            )?;
        }
    }
    for (i, c) in sy.config.iter().enumerate() {
        if !identify::dataset::is_valid_case_id(&c.name) {
            return err(
                &format!("data.synthetic.config[{i}].name"),
                format!("`{}` must match [A-Za-z0-9._-]+", c.name),
            );
        }
        pos(
            &format!("data.synthetic.config[{i}].freq_pitch"),
            c.freq_pitch,
        )?;
        pos(
            &format!("data.synthetic.config[{i}].freq_heave"),
            c.freq_heave,
        )?;
        pos(
            &format!("data.synthetic.config[{i}].mm_per_deg"),
            c.mm_per_deg,
        )?;
    }
    for (k, vals) in [
        ("data.synthetic.amplitudes_deg", &sy.amplitudes_deg),
        ("data.synthetic.speeds", &sy.speeds),
    ] {
        if vals.is_empty() {
            return err(k, "at least one value".into());
        }
        for v in vals.iter() {
            pos(k, *v)?;
        }
    }
    for (k, v) in [
        ("data.synthetic.force_noise", sy.force_noise),
        ("data.synthetic.heave_noise", sy.heave_noise),
        ("data.synthetic.pitch_noise", sy.pitch_noise),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return err(k, format!("{v} must be finite and ≥ 0"));
        }
    }
    for (ch, terms) in [("lift", &sy.law.lift), ("moment", &sy.law.moment)] {
        for (i, t) in terms.iter().enumerate() {
            if let Err(e) = identify::library::Term::parse(&t.term) {
                return err(&format!("data.synthetic.law.{ch}[{i}].term"), e.to_string());
            }
        }
    }
    Ok(())
}

/// `[data.table_iv]`.
fn table_iv(t: &TableIvSpec) -> Check {
    if t.repeats == 0 {
        return err("data.table_iv.repeats", "must be ≥ 1".into());
    }
    pos("data.table_iv.rate", t.rate)?;
    pos("data.table_iv.duration", t.duration)?;
    if t.repeats > MAX_CASES {
        return err(
            "data.table_iv.repeats",
            format!(
                "{} exceeds the cap of {MAX_CASES} (the limits table's MAX_CASES)",
                t.repeats
            ),
        );
    }
    lim(samples(
        "data.table_iv.duration",
        "data.table_iv.rate",
        t.repeats,
        t.duration,
        t.rate,
    ))?;
    if !(t.sigma.is_finite() && t.sigma >= 0.0) {
        return err(
            "data.table_iv.sigma",
            format!("{} must be finite and ≥ 0", t.sigma),
        );
    }
    for (k, c) in [
        ("data.table_iv.moment", &t.moment),
        ("data.table_iv.lift", &t.lift),
    ] {
        for v in c.iter() {
            fin(k, *v)?;
        }
    }
    Ok(())
}

/// `[identify]`: the settings, the ensemble (members × cases within
/// `MAX_ENSEMBLE_FITS`, where the cases are known from the file) and its level.
fn identify(id: &super::types::IdentifySpec, data: Option<&DataSpec>) -> Check {
    if let Err(e) = id.settings.validate() {
        return err("identify.settings", e.to_string());
    }
    if let Some(n) = id.ensemble {
        if !(2..=crate::limits::MAX_ENSEMBLE).contains(&n) {
            return err(
                "identify.ensemble",
                format!("{n} members: expected 2 … {}", crate::limits::MAX_ENSEMBLE),
            );
        }
        if let Err(e) = identify::ensemble::check_settings(&id.settings) {
            return err("identify.ensemble", e.to_string());
        }
        // every member's coefficients of every case are held until the result is
        // written: members × cases bounded (a `[data] dataset`'s cases are counted when
        // it is read, `run::identify_stage`)
        let cases = data.and_then(|d| {
            if let Some(sy) = &d.synthetic {
                Some(synthetic_cases(sy))
            } else if let Some(t) = &d.table_iv {
                Some(t.repeats as u128)
            } else {
                d.virtual_tunnel.as_ref().map(|v| virtual_cases(v) as u128)
            }
        });
        if let Some(c) = cases {
            if let Err(e) = crate::limits::ensemble_fits("identify.ensemble", n, c) {
                return err(&e.field, e.message);
            }
        }
    }
    if !(id.ensemble_level > 0.0 && id.ensemble_level < 1.0) {
        return err(
            "identify.ensemble_level",
            format!("{}: expected a level in (0, 1)", id.ensemble_level),
        );
    }
    Ok(())
}

/// `[structure]`: the nondimensional parameters positive and within their caps, the
/// damping ratios in [0, 10], the pitch cubic finite.
fn structure(outer: &StudyStructure) -> Check {
    let st = &outer.linear;
    for (k, v) in [
        ("structure.mu", st.mu),
        ("structure.r_alpha2", st.r_alpha2),
        ("structure.semi_chord", st.semi_chord),
        ("structure.omega_alpha", st.omega_alpha),
        ("structure.rho", st.rho),
        ("structure.sigma", st.sigma),
    ] {
        pos(k, v)?;
    }
    for (k, v, max) in [
        ("structure.mu", st.mu, 1e6),
        ("structure.r_alpha2", st.r_alpha2, 100.0),
        ("structure.sigma", st.sigma, 100.0),
        ("structure.semi_chord", st.semi_chord, 50.0),
        ("structure.omega_alpha", st.omega_alpha, 1e5),
        ("structure.rho", st.rho, 2000.0),
    ] {
        lim(positive_at_most(k, v, max, ""))?;
    }
    lim(abs_at_most(
        "structure.x_alpha",
        st.x_alpha,
        10.0,
        "semi-chords",
    ))?;
    fin("structure.pitch_cubic", outer.pitch_cubic)?;
    for (k, v) in [
        ("structure.zeta_h", st.zeta_h),
        ("structure.zeta_alpha", st.zeta_alpha),
    ] {
        if !(v.is_finite() && (0.0..=10.0).contains(&v)) {
            return err(k, format!("{v} must be finite and in [0, 10]"));
        }
    }
    Ok(())
}

/// `[flutter]`: the speed range and its grid, the references finite, and each run's model
/// usable here (`lag` needs `aero.file`: `no_file` says it is missing).
fn flutter(f: &FlutterSpec, has_data: bool, has_virtual: bool, no_file: bool) -> Check {
    pos("flutter.u_min", f.u_min)?;
    pos("flutter.u_max", f.u_max)?;
    lim(positive_at_most("flutter.u_max", f.u_max, MAX_SPEED, "m/s"))?;
    if f.n_speeds > crate::limits::MAX_SPEEDS {
        return err(
            "flutter.n_speeds",
            format!(
                "{} exceeds the cap of {}",
                f.n_speeds,
                crate::limits::MAX_SPEEDS
            ),
        );
    }
    lim(positive_at_most("flutter.tol_rel", f.tol_rel, 0.1, ""))?;
    for (i, r) in f.run.iter().enumerate() {
        if let Some(x) = r.reference {
            for v in [x.u_reduced, x.omega_ratio, x.divergence]
                .into_iter()
                .flatten()
            {
                fin(&format!("flutter.run[{i}].reference"), v)?;
            }
        }
    }
    if f.u_max <= f.u_min {
        return err(
            "flutter.u_max",
            format!("{} must exceed u_min = {}", f.u_max, f.u_min),
        );
    }
    if f.n_speeds < 2 {
        return err("flutter.n_speeds", "must be ≥ 2".into());
    }
    for (i, r) in f.run.iter().enumerate() {
        if let Some(m) = r.model {
            let k = format!("flutter.run[{i}].model");
            check_model(&k, m, has_data, has_virtual)?;
            if m == StudyModel::Kind(ModelKind::Lag) && no_file {
                return err(
                    &k,
                    "`lag` flies the lag_law.json named by `aero.file`; [aero] has none".into(),
                );
            }
        }
    }
    Ok(())
}

/// `[branch]`: the speed interval, the point, step and harmonic counts within their caps.
fn branch(b: &super::types::BranchSpec) -> Check {
    let [a, c] = b.speeds;
    lim(positive_at_most("branch.speeds[0]", a, MAX_SPEED, "m/s"))?;
    lim(positive_at_most("branch.speeds[1]", c, MAX_SPEED, "m/s"))?;
    if c <= a {
        return err("branch.speeds", format!("[{a}, {c}]: expected a < b"));
    }
    use identify::limits::{MAX_BRANCH_POINTS, MAX_STEPS_PER_PERIOD};
    if !(2..=MAX_BRANCH_POINTS).contains(&b.max_points) {
        return err(
            "branch.max_points",
            format!("{}: expected 2 … {MAX_BRANCH_POINTS}", b.max_points),
        );
    }
    if !(16..=MAX_STEPS_PER_PERIOD).contains(&b.steps_per_period) {
        return err(
            "branch.steps_per_period",
            format!(
                "{}: expected 16 … {MAX_STEPS_PER_PERIOD}",
                b.steps_per_period
            ),
        );
    }
    let hmax = identify::limits::MAX_HARMONICS;
    if !(1..=hmax).contains(&b.harmonics) {
        return err(
            "branch.harmonics",
            format!("{}: expected 1 … {hmax}", b.harmonics),
        );
    }
    Ok(())
}

/// `[lco]`: the speeds, the integration's periods and tolerances, the perturbations, and a
/// truth to compare with only where `[data.virtual]` gives one.
fn lco(l: &LcoSpec, has_virtual: bool) -> Check {
    if l.speeds.is_empty() {
        return err("lco.speeds", "at least one speed".into());
    }
    for v in &l.speeds {
        pos("lco.speeds", *v)?;
    }
    if l.speeds.len() > crate::limits::MAX_SPEEDS {
        return err(
            "lco.speeds",
            format!(
                "{} speeds exceed the cap of {}",
                l.speeds.len(),
                crate::limits::MAX_SPEEDS
            ),
        );
    }
    for (i, v) in l.speeds.iter().enumerate() {
        lim(positive_at_most(
            &format!("lco.speeds[{i}]"),
            *v,
            MAX_SPEED,
            "m/s",
        ))?;
    }
    for (i, v) in l.phase_speeds.iter().enumerate() {
        lim(positive_at_most(
            &format!("lco.phase_speeds[{i}]"),
            *v,
            MAX_SPEED,
            "m/s",
        ))?;
    }
    lim(positive_at_most(
        "lco.max_periods",
        l.max_periods,
        crate::limits::MAX_PERIODS,
        "periods",
    ))?;
    lim(positive_at_most(
        "lco.phase_periods",
        l.phase_periods,
        crate::limits::MAX_PHASE_PERIODS,
        "periods",
    ))?;
    lim(positive_at_most("lco.rtol", l.rtol, 1.0, ""))?;
    lim(positive_at_most("lco.atol", l.atol, 1.0, ""))?;
    lim(abs_at_most(
        "lco.perturbation_deg",
        l.perturbation_deg,
        crate::limits::MAX_PITCH_DEG,
        "deg",
    ))?;
    lim(abs_at_most(
        "lco.perturbation_down_deg",
        l.perturbation_down_deg,
        90.0,
        "deg",
    ))?;
    pos("lco.max_periods", l.max_periods)?;
    pos("lco.rtol", l.rtol)?;
    pos("lco.atol", l.atol)?;
    pos("lco.phase_periods", l.phase_periods)?;
    pos("lco.perturbation_deg", l.perturbation_deg)?;
    if l.compare_truth && !has_virtual {
        return err(
            "lco.compare_truth",
            "needs a [data.virtual] source (the truth model)".into(),
        );
    }
    Ok(())
}

/// `[outputs]` (series cases named once each, known figure kinds) and the preprocessing's
/// window, which is checked last as it always was.
fn outputs(s: &StudySpec, id: &super::types::IdentifySpec) -> Check {
    for (i, c) in s.outputs.series_cases.iter().enumerate() {
        if !identify::dataset::is_valid_case_id(c) {
            return err(
                &format!("outputs.series_cases[{i}]"),
                format!("`{c}` is not a case id ([A-Za-z0-9._-]+)"),
            );
        }
        // a repeated case drew its figures again (10× the time, issue 39 row 7)
        if let Some(j) = s.outputs.series_cases[..i].iter().position(|x| x == c) {
            return err(
                &format!("outputs.series_cases[{i}]"),
                format!("`{c}` is already entry {j} of the list; name each case once"),
            );
        }
    }
    if id.preprocess.sg_half_window > 100_000 || id.preprocess.sg_order > 20 {
        return err(
            "identify.preprocess.sg_half_window",
            format!(
                "half window {} (≤ 100000) and order {} (≤ 20) out of range",
                id.preprocess.sg_half_window, id.preprocess.sg_order
            ),
        );
    }
    if let Some(f) = &s.outputs.figures {
        for (i, k) in f.iter().enumerate() {
            if !FIGURE_KINDS.contains(&k.as_str()) {
                return err(
                    &format!("outputs.figures[{i}]"),
                    format!("`{k}`: expected one of {}", FIGURE_KINDS.join(", ")),
                );
            }
        }
    }
    Ok(())
}

/// Checks where a model may be used: `identified` only where `allow_identified` (a study
/// with data), `truth` only where `allow_truth` (a flutter run of a study with
/// `[data.virtual]`).
fn check_model(
    k: &str,
    m: StudyModel,
    allow_identified: bool,
    allow_truth: bool,
) -> Result<(), (String, String)> {
    match m {
        StudyModel::IDENTIFIED if !allow_identified => Err((
            k.to_string(),
            "`identified` needs [data] (the model comes from this study's identification)".into(),
        )),
        StudyModel::Truth if !allow_truth => Err((
            k.to_string(),
            "`truth` needs a [data.virtual] source and is a flutter-run model only".into(),
        )),
        _ => Ok(()),
    }
}

/// Checks an `[aero]`-like table (a [`ModelFile`]) whose dotted prefix is `prefix`: a kind
/// the study can build (not `dynamic_stall`; `identified` only where `allow_identified`),
/// no `chord` (the study's), a `file` for `lag` only (its lag_law.json; an `identified` model
/// is the study's own), an
/// elastic axis on the chord, 1..=8 lag roots, nonlinear terms that convert
/// ([`aeroelastic::files::NonlinearSpec::to_term`]).
fn check_aero(prefix: &str, a: &ModelFile, allow_identified: bool) -> Result<(), (String, String)> {
    let key = |k: &str| format!("{prefix}.{k}");
    check_model(
        &key("model"),
        StudyModel::Kind(a.kind),
        allow_identified,
        false,
    )?;
    if a.kind == ModelKind::DynamicStall {
        return Err((
            key("model"),
            "`dynamic_stall` is a model-file kind only (`aeroform lco --model`), not a study's"
                .into(),
        ));
    }
    if a.chord.is_some() {
        return Err((
            key("chord"),
            "the chord of a study's model is the structure's (2 semi_chord; 0.25 m for [data.virtual])"
                .into(),
        ));
    }
    match (a.kind, &a.file) {
        (ModelKind::Lag, None) => {
            return Err((
                key("file"),
                "`lag` needs `file`: a lag_law.json (`aeroform identify DATASET --law lag`), \
                 relative to the study file"
                    .into(),
            ))
        }
        (ModelKind::Identified, Some(_)) => {
            return Err((
                key("file"),
                "a study's `identified` model is its own identification; give no `file`".into(),
            ))
        }
        (k, Some(_)) if k != ModelKind::Lag => {
            return Err((
                key("file"),
                format!("`{k}` takes no `file` (only `lag` does: its lag_law.json)"),
            ))
        }
        _ => {}
    }
    if let Some(e) = a.elastic_axis {
        if !(e.is_finite() && e.abs() <= 1.0) {
            return Err((
                key("elastic_axis"),
                format!("{e} must be finite and on the chord, in [-1, 1] semi-chords"),
            ));
        }
    }
    if let Some(n) = a.rfa_lags {
        if !(1..=8).contains(&n) {
            return Err((key("n_lag"), format!("{n} must be in 1..=8")));
        }
    }
    for (i, t) in a.nonlinear.iter().enumerate() {
        if let Err((field, m)) = t.to_term() {
            return Err((key(&format!("nonlinear[{i}].{field}")), m));
        }
    }
    Ok(())
}
