//! Turns the checked study into library objects: the cases to identify (from a data set, a
//! synthetic campaign or the Table IV verification) and the aeroelastic sections.

use std::path::Path;
use std::sync::Arc;

use crate::error::{Context, Error, Result};
use crate::observe::Observer;
use aeroelastic::aero::{AeroModel, NonlinearAero};
use aeroelastic::files::{ModelFile, ModelKind};
use aeroelastic::section::Section;
use aeroelastic::structure::Structure;
use identify::dataset::{
    read_dataset, write_dataset, AngleUnit, CaseSpec, Dataset, ForceUnit, LengthUnit, Manifest,
    MomentUnit, Units,
};
use identify::library::Term;
use identify::preprocess::{PreprocessOptions, VelocityMethod};
use identify::record::{CaseMeta, NondimCase};
use identify::synthetic::{forced_record, HarmonicMotion, LawTerm, PolynomialLaw, Sampling};
use identify::workflow::prepare_dataset;

use aeroelastic::files::LoadedModel;
use aeroelastic::identified::{IdentifiedLaw, IdentifiedOptions};
use aeroelastic::tunnel::{self, ForcedOptions};
use identify::pipeline::Identification;

use crate::spec::{
    LawPreset, PreprocessSpec, Study, StudyModel, StudyStructure, SyntheticSpec, VelocityChoice,
    VirtualSpec,
};

/// The cases of the identification stage.
pub struct Cases {
    /// Name of the data (the `dataset` of `identification.json`).
    pub name: String,
    /// One-line description of the source for the report.
    pub source: String,
    /// Regression inputs.
    pub cases: Vec<NondimCase>,
    /// Wind-on and still-air balance forces of the shown cases (paper Figs. 4/5).
    pub forces: Vec<crate::paper::ForceDecomposition>,
}

impl Cases {
    /// Descriptors of every case.
    pub fn metas(&self) -> Vec<CaseMeta> {
        self.cases.iter().map(|c| c.meta.clone()).collect()
    }
}

/// Preprocessing options of the study.
pub fn preprocess(p: &PreprocessSpec) -> PreprocessOptions {
    PreprocessOptions {
        velocity: match p.velocity {
            VelocityChoice::Harmonic => VelocityMethod::Harmonic,
            VelocityChoice::Sg => VelocityMethod::SavitzkyGolay {
                half_window: p.sg_half_window,
                order: p.sg_order,
            },
            VelocityChoice::Auto => VelocityMethod::Auto,
        },
        subtract_nowind: p.subtract_nowind,
        sg_half_window: p.sg_half_window,
        sg_order: p.sg_order,
        ..PreprocessOptions::default()
    }
}

fn law(sy: &SyntheticSpec) -> Result<PolynomialLaw> {
    if sy.law.preset == LawPreset::Demo {
        return Ok(PolynomialLaw::demo());
    }
    let conv = |terms: &[crate::spec::LawTermSpec]| -> Result<Vec<LawTerm>> {
        terms
            .iter()
            .map(|t| {
                Ok(LawTerm {
                    powers: Term::parse(&t.term)?.powers,
                    coefficient: t.coefficient,
                })
            })
            .collect()
    };
    Ok(PolynomialLaw {
        lift: conv(&sy.law.lift)?,
        moment: conv(&sy.law.moment)?,
    })
}

/// Compact number for case ids: `4`, `7.5`.
fn id_num(v: f64) -> String {
    format!("{v}")
}

fn synthetic(study: &Study, sy: &SyntheticSpec, out: &Path) -> Result<Dataset> {
    let section = identify::record::SectionGeometry {
        chord: sy.section.chord,
        span: sy.section.span,
        air_density: sy.section.air_density,
    };
    let law = law(sy)?;
    let sampling = Sampling {
        rate: sy.rate,
        duration: sy.duration,
        force_noise: sy.force_noise,
        heave_noise: sy.heave_noise,
        pitch_noise: sy.pitch_noise,
    };
    let mut cases = Vec::new();
    let mut records = Vec::new();
    let mut index: u64 = 0;
    for c in &sy.config {
        for &u in &sy.speeds {
            for &a in &sy.amplitudes_deg {
                let id = format!("{}-U{}-A{}", c.name, id_num(u), id_num(a));
                let mut spec = CaseSpec::forced(&id, format!("cases/{id}.csv"), u);
                spec.config = Some(c.name.clone());
                spec.amplitude = Some(a);
                spec.amplitude_ratio = Some(c.mm_per_deg);
                spec.freq_pitch = Some(c.freq_pitch);
                spec.freq_heave = Some(c.freq_heave);
                let motion = HarmonicMotion {
                    freq_pitch: c.freq_pitch,
                    freq_heave: c.freq_heave,
                    amp_pitch: a.to_radians(),
                    amp_heave: c.mm_per_deg * a * 1e-3,
                    mean_pitch: 0.0,
                };
                let meta = CaseMeta {
                    id: id.clone(),
                    wind_speed: u,
                    config: Some(c.name.clone()),
                    amplitude: Some(a.to_radians()),
                    amplitude_ratio: Some(c.mm_per_deg),
                    freq_pitch: Some(c.freq_pitch),
                    freq_heave: Some(c.freq_heave),
                    mean_pitch: None,
                };
                // one independent stream per case, derived from the study seed
                let seed = study.spec.seed.wrapping_mul(1_000_003).wrapping_add(index);
                index += 1;
                records.push(
                    forced_record(meta, &section, &motion, &law, &sampling, seed)
                        .with_context(|| format!("generating case {id}"))?,
                );
                cases.push(spec);
            }
        }
    }
    let mut extra = toml::Table::new();
    extra.insert(
        "generator".into(),
        "aeroform run (synthetic campaign)".into(),
    );
    extra.insert("study".into(), study.spec.name.clone().into());
    extra.insert("seed".into(), toml::Value::Integer(study.spec.seed as i64));
    let manifest = Manifest {
        name: format!("{} (synthetic)", study.spec.name),
        description: Some(format!(
            "Synthetic forced-motion campaign: {} configuration(s) × {} speeds × {} amplitudes, \
             law `{}`, force noise {} of peak, heave noise {} m, pitch noise {} rad.",
            sy.config.len(),
            sy.speeds.len(),
            sy.amplitudes_deg.len(),
            match sy.law.preset {
                LawPreset::Demo => "demo",
                LawPreset::Custom => "custom",
            },
            sy.force_noise,
            sy.heave_noise,
            sy.pitch_noise
        )),
        section,
        structure: None,
        units: Units {
            heave: LengthUnit::Mm,
            pitch: AngleUnit::Deg,
            lift: ForceUnit::N,
            moment: MomentUnit::Nm,
        },
        convention: Default::default(),
        cases,
        extra: Some(extra),
    };
    let root = out.join("dataset");
    if sy.write_dataset {
        identify::io::create_dir_below(out, Path::new("dataset/cases"))?;
        write_dataset(&root, &manifest, &records)
            .with_context(|| format!("writing the data set to {}", root.display()))?;
    }
    Ok(Dataset {
        root,
        manifest,
        records,
    })
}

/// The model of `[data.virtual]` (file or inline) for the rig chord `chord`.
///
/// # Errors
/// The model file cannot be read or parsed, or the inline model is invalid.
pub fn virtual_model(study: &Study, v: &VirtualSpec, chord: f64) -> Result<Arc<dyn AeroModel>> {
    if let Some(p) = &v.model {
        let path = study.base.join(p);
        let m = LoadedModel::load(&path, Some(chord))
            .with_context(|| format!("data.virtual.model: {}", path.display()))?;
        return Ok(m.model);
    }
    let Some(a) = &v.aero else {
        return Err(Error::Study("[data.virtual]: no model".into()));
    };
    model_of(a.kind, chord, a, true, &study.base).context("[data.virtual.aero]")
}

fn virtual_campaign(
    study: &Study,
    v: &VirtualSpec,
    out: &Path,
    obs: &dyn Observer,
) -> Result<(Dataset, String)> {
    let campaign = v.campaign.campaign().context("data.virtual.campaign")?;
    let mut opts = ForcedOptions::paper(study.spec.seed);
    opts.name = format!("{} (virtual wind tunnel)", study.spec.name);
    opts.duration = v.duration;
    if v.still_air {
        opts = opts.with_paper_still_air();
    }
    let model = virtual_model(study, v, opts.section.chord)?;
    let cases = campaign.cases();
    let bar = obs.counter("tunnel", cases.len());
    let r = tunnel::forced_dataset(&*model, &cases, &opts, &|_| bar.inc(1));
    bar.finish();
    let (manifest, records) = r.context("data.virtual: forced campaign")?;
    let root = out.join("dataset");
    if v.write_dataset {
        identify::io::create_dir_below(out, Path::new("dataset/cases"))?;
        tunnel::write(&root, &manifest, &records)
            .with_context(|| format!("writing the data set to {}", root.display()))?;
    }
    let source = format!(
        "virtual wind tunnel, campaign `{}` ({} cases), model `{}`, {} s at {} Hz, paper noise{}",
        v.campaign,
        cases.len(),
        model.name(),
        opts.duration,
        opts.rate,
        if v.still_air {
            ", still-air runs subtracted"
        } else {
            ""
        }
    );
    Ok((
        Dataset {
            root,
            manifest,
            records,
        },
        source,
    ))
}

/// Builds the cases of `[data]`.
///
/// # Errors
/// Reading or generating the data, or preprocessing a case (the message names it).
pub fn cases(study: &Study, out: &Path, obs: &dyn Observer) -> Result<Option<Cases>> {
    let Some(d) = &study.spec.data else {
        return Ok(None);
    };
    let id = study.spec.identify.clone().unwrap_or_default();
    let pre = preprocess(&id.preprocess);
    pre.check().context("identify.preprocess")?;
    if let Some(t) = &d.table_iv {
        let seeds: Vec<u64> = (0..t.repeats as u64)
            .map(|i| study.spec.seed.wrapping_add(i))
            .collect();
        let cases = identify::paper::table_iv_cases(
            &identify::paper::TableIvGroup {
                coefficients: t.moment,
            },
            &identify::paper::TableIvGroup {
                coefficients: t.lift,
            },
            &identify::paper::TableIvSampling {
                rate: t.rate,
                duration: t.duration,
                sigma: t.sigma,
                ..identify::paper::TableIvSampling::default()
            },
            &seeds,
        )
        .context("data.table_iv")?;
        return Ok(Some(Cases {
            name: "paper Table IV (Eq. 15/16)".into(),
            source: format!(
                "Eq. 15/16 verification: {} noise realisations, σ = {}, {} s at {} Hz",
                t.repeats, t.sigma, t.duration, t.rate
            ),
            cases,
            forces: vec![],
        }));
    }
    let (dataset, source) = if let Some(sy) = &d.synthetic {
        let ds = synthetic(study, sy, out)?;
        let src = ds.manifest.description.clone().unwrap_or_default();
        (ds, src)
    } else if let Some(v) = &d.virtual_tunnel {
        virtual_campaign(study, v, out, obs)?
    } else if let Some(p) = &d.dataset {
        let dir = study.base.join(p);
        let ds =
            read_dataset(&dir).with_context(|| format!("reading data set {}", dir.display()))?;
        (ds, format!("data set {}", p.display()))
    } else {
        return Err(Error::Study("[data]: no source".into()));
    };
    let name = dataset.manifest.name.clone();
    let forces = if study
        .figure_kinds()
        .iter()
        .any(|k| k == "force_decomposition")
    {
        let wanted = &study.spec.outputs.series_cases;
        let ids: Vec<String> = if wanted.is_empty() {
            let r = &dataset.records;
            r.first()
                .into_iter()
                .chain(r.last().filter(|_| r.len() > 1))
                .map(|r| r.meta.id.clone())
                .collect()
        } else {
            wanted.clone()
        };
        crate::paper::force_decompositions(&dataset, &ids)
    } else {
        vec![]
    };
    let prepared = prepare_with_bar(dataset, &pre, obs)?;
    if prepared.is_empty() {
        return Err(Error::Study(
            "the data have no forced-motion case to identify".into(),
        ));
    }
    Ok(Some(Cases {
        name,
        source,
        cases: prepared,
        forces,
    }))
}

/// Preprocesses a data set in chunks (each chunk in parallel inside
/// [`prepare_dataset`]) so that a progress bar can follow; same result and order as one
/// call on the whole data set.
fn prepare_with_bar(
    dataset: Dataset,
    pre: &PreprocessOptions,
    obs: &dyn Observer,
) -> Result<Vec<NondimCase>> {
    const CHUNK: usize = 32;
    let Dataset {
        root,
        manifest,
        records,
    } = dataset;
    let bar = obs.counter("prepare", records.len());
    let mut out = Vec::with_capacity(records.len());
    let mut rest = records;
    while !rest.is_empty() {
        let tail = rest.split_off(rest.len().min(CHUNK));
        let n = rest.len();
        let chunk = Dataset {
            root: root.clone(),
            manifest: manifest.clone(),
            records: rest,
        };
        let prepared = prepare_dataset(&chunk, pre).context("preprocessing");
        let prepared = match prepared {
            Ok(p) => p,
            Err(e) => {
                bar.finish();
                return Err(e);
            }
        };
        out.extend(prepared.cases);
        bar.inc(n);
        rest = tail;
    }
    bar.finish();
    Ok(out)
}

/// The linear structure of `[structure]` (nondimensional → SI) with its cubic pitch spring.
///
/// # Errors
/// Out-of-range parameters, naming the field.
pub fn structure(s: &StudyStructure) -> Result<Structure> {
    s.spec().resolve().context("[structure]")
}

/// The model of kind `kind` with the parameters of the study's model table `a` (the
/// keys `kind` uses; [`ModelFile::for_kind`]) for the chord `chord` \[m\], with `a`'s
/// nonlinear terms when `terms`, built by the one model constructor
/// [`LoadedModel::from_spec`]; a `file` (the `lag` kind's lag_law.json) is relative to
/// `base`, the study file's folder.
///
/// # Errors
/// `identified` (the study's own law comes from [`Derived`]) or invalid parameters.
pub fn model_of(
    kind: ModelKind,
    chord: f64,
    a: &ModelFile,
    terms: bool,
    base: &Path,
) -> Result<Arc<dyn AeroModel>> {
    if kind == ModelKind::Identified {
        return Err(Error::Study(
            "the study's `identified` model comes from its identification, not from [aero]".into(),
        ));
    }
    let mut spec = a.for_kind(kind);
    if !terms {
        spec.nonlinear.clear();
    }
    Ok(LoadedModel::from_spec(&spec, "[aero]", base, Some(chord))?.model)
}

/// Models derived from the study's own data: the identified law (when `[aero]` or a
/// flutter run asks for `identified`).
#[derive(Default)]
pub struct Derived {
    /// The identified Eq. 19 law as a nonlinear model (linear part: derivative tables).
    pub identified: Option<NonlinearAero>,
    /// The laws of the identification's bootstrap members (`[identify] ensemble`), for the
    /// intervals of the flutter and LCO stages.
    pub members: Option<Members>,
}

/// The bootstrap members of an identification as laws (a member that cannot be built keeps
/// its reason), with the ensemble they come from (seed, level).
#[derive(Debug, Clone)]
pub struct Members {
    /// Per member, the law or why it could not be built.
    pub laws: Vec<std::result::Result<IdentifiedLaw, String>>,
    /// The `ensemble` section of `identification.json`.
    pub ensemble: identify::ensemble::Ensemble,
}

/// The options of the study's identified law: the chord 2b, and `[aero]`'s `n_lag`,
/// `groups` and `missing` (the keys an `identified` model file uses; the defaults of
/// [`IdentifiedOptions::new`] without them).
fn identified_options(study: &Study, s: &StudyStructure) -> IdentifiedOptions {
    let mut o = IdentifiedOptions::new(2.0 * s.linear.semi_chord);
    if let Some(a) = &study.spec.aero {
        let f = a.for_kind(ModelKind::Identified);
        o.rfa_lags = f.rfa_lags.unwrap_or(o.rfa_lags);
        o.groups = f.groups;
        o.missing = f.missing.unwrap_or(o.missing);
    }
    o
}

/// The laws of every bootstrap member of `id` for the study's chord 2b.
///
/// # Errors
/// No `[structure]`, or the ensemble section does not match the identification.
pub fn member_laws(study: &Study, id: &Identification) -> Result<Members> {
    let Some(s) = &study.spec.structure else {
        return Err(Error::Study(
            "the ensemble's laws need [structure] (its chord)".into(),
        ));
    };
    let (laws, e) = aeroelastic::ensemble::member_laws(id, &identified_options(study, s), None)
        .context("building the ensemble's laws")?;
    Ok(Members {
        laws,
        ensemble: e.clone(),
    })
}

/// The identified law of `id` for the study's chord 2b.
///
/// # Errors
/// The law cannot be built (too few reduced frequencies, a null derivative, …).
pub fn identified_model(study: &Study, id: &Identification) -> Result<NonlinearAero> {
    let Some(s) = &study.spec.structure else {
        return Err(Error::Study(
            "the identified model needs [structure] (its chord)".into(),
        ));
    };
    let law = IdentifiedLaw::from_identification(id, &identified_options(study, s))
        .context("building the identified Eq. 19 model")?;
    Ok(law.model().clone())
}

/// The truth model of `[data.virtual]` for the study's chord 2b.
///
/// # Errors
/// No virtual source, or as [`virtual_model`].
pub fn truth_model(study: &Study, s: &StudyStructure) -> Result<Arc<dyn AeroModel>> {
    let Some(v) = study
        .spec
        .data
        .as_ref()
        .and_then(|d| d.virtual_tunnel.as_ref())
    else {
        return Err(Error::Study(
            "the `truth` model needs a [data.virtual] source".into(),
        ));
    };
    virtual_model(study, v, 2.0 * s.linear.semi_chord)
}

/// A model of the study by name: `identified` (from `derived`), `truth`, or a kind built
/// with `[aero]`'s parameters (with its nonlinear terms when `terms`).
fn named_aero(
    study: &Study,
    model: StudyModel,
    s: &StudyStructure,
    a: &ModelFile,
    derived: &Derived,
    terms: bool,
) -> Result<Arc<dyn AeroModel>> {
    match model {
        StudyModel::IDENTIFIED => match &derived.identified {
            Some(m) => Ok(Arc::new(m.clone())),
            None => Err(Error::Study(
                "the identified model is not available (no identification)".into(),
            )),
        },
        StudyModel::Truth => truth_model(study, s),
        StudyModel::Kind(kind) => model_of(kind, 2.0 * s.linear.semi_chord, a, terms, &study.base),
    }
}

/// The section of the flutter stage for `model` (nonlinear terms do not enter a linear
/// flutter analysis).
///
/// # Errors
/// As [`structure`] and [`model_of`].
pub fn linear_section(study: &Study, model: StudyModel, derived: &Derived) -> Result<Section> {
    let (Some(s), Some(a)) = (&study.spec.structure, &study.spec.aero) else {
        return Err(Error::Study("[structure] and [aero] are required".into()));
    };
    Ok(Section::new(
        structure(s)?,
        named_aero(study, model, s, a, derived, false)?,
        s.linear.rho,
    )?)
}

/// The nonlinear section of the LCO stage: `[aero]` plus its nonlinear terms.
///
/// # Errors
/// As [`linear_section`]; invalid nonlinear terms.
pub fn nonlinear_section(study: &Study, derived: &Derived) -> Result<Section> {
    let (Some(s), Some(a)) = (&study.spec.structure, &study.spec.aero) else {
        return Err(Error::Study("[structure] and [aero] are required".into()));
    };
    let aero = named_aero(study, StudyModel::Kind(a.kind), s, a, derived, true)?;
    Ok(Section::new(structure(s)?, aero, s.linear.rho)?)
}
