//! `aeroform lco`: limit-cycle oscillation at one speed or over a sweep (up and down),
//! written to `lco.json`.

use std::path::PathBuf;

use crate::progress::CountBar;
use aeroelastic::documents::{lco_run_document, lco_sweep_document};
use aeroelastic::lco::{
    Classification, KIteration, LcoOptions, LcoResult, SweepDirection, SweepPlan, SweepProgress,
};
use anyhow::Context;
use clap::Args;

use crate::models::load;
use aeroform::limits::{abs_at_most, parse_speeds, positive_at_most, MAX_PITCH_DEG, MAX_SPEED};

/// Flags of `aeroform lco`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("where").required(true).args(["speed", "sweep"])))]
pub struct LcoArgs {
    /// Structure file (TOML).
    #[arg(long)]
    pub structure: PathBuf,
    /// Aerodynamic model: a model TOML file or an identification.json.
    #[arg(long)]
    pub model: PathBuf,
    /// One wind speed [m/s].
    #[arg(long)]
    pub speed: Option<f64>,
    /// Sweep `a:b:n` (or a comma list), integrated upward and downward.
    #[arg(long)]
    pub sweep: Option<String>,
    /// Initial pitch perturbation [deg] (the upward sweep and single runs).
    #[arg(long, default_value_t = 2.0)]
    pub alpha0: f64,
    /// Initial pitch [deg] of the downward sweep (large, to reach an upper LCO branch).
    #[arg(long, default_value_t = 20.0)]
    pub alpha0_down: f64,
    /// Chord B [m] for an identification.json model.
    #[arg(long)]
    pub chord: Option<f64>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// LCO amplitudes of the first N members of the model's ensemble (identification.json
    /// from `identify --ensemble`) at the speed or the sweep's speeds (upward runs from
    /// --alpha0): intervals in lco.json under `ensemble`.
    #[arg(long, value_name = "N")]
    pub ensemble: Option<usize>,
}

fn class_name(r: &LcoResult) -> String {
    match r.classification {
        Classification::Decay => "decay".into(),
        Classification::Lco => "LCO".into(),
        Classification::Divergent { time_left_bound } => {
            format!("divergent (left the bound at t = {time_left_bound:.3} s)")
        }
        Classification::Unsettled => format!("unsettled ({})", r.stop.name()),
    }
}

/// Runs `aeroform lco`.
pub fn run(args: &LcoArgs) -> anyhow::Result<()> {
    if let Some(u) = args.speed {
        positive_at_most("--speed", u, MAX_SPEED, "m/s")?;
    }
    let sweep_speeds = match &args.sweep {
        Some(s) => parse_speeds("--sweep", s)?,
        None => Vec::new(),
    };
    abs_at_most("--alpha0", args.alpha0, MAX_PITCH_DEG, "deg")?;
    abs_at_most("--alpha0-down", args.alpha0_down, MAX_PITCH_DEG, "deg")?;
    let l = load(&args.structure, &args.model, args.chord)?;
    let opts = LcoOptions::default();
    // K-dependent models (identified laws) iterate K to each cycle's own; the others run once.
    let k_iteration = KIteration::default();
    let pert = l.section.perturbation(args.alpha0.to_radians());
    let pert_down = l.section.perturbation(args.alpha0_down.to_radians());
    let path = args.out.join("lco.json");
    crate::outdir::refuse_symlink(&args.out, "--out")?;
    let _out = crate::outdir::SharedDir::begin(
        &args.out,
        &[&path],
        &[
            crate::outdir::Input::new("--structure", &args.structure),
            crate::outdir::Input::new("--model", &args.model),
        ],
    )?;
    let structure_name = args.structure.display().to_string();
    let model_name = args.model.display().to_string();
    let doc = if let Some(u) = args.speed {
        let r = l
            .section
            .lco_run_k(u, &pert, &opts, &k_iteration)
            .with_context(|| format!("LCO run at U = {u} m/s"))?;
        crate::ui::say!(
            "U = {u} m/s: {}, pitch amplitude {:.4}°, heave amplitude {:.3} mm, {:.4} Hz",
            class_name(&r),
            r.amplitude_alpha.to_degrees(),
            r.amplitude_h * 1e3,
            r.omega / (2.0 * std::f64::consts::PI)
        );
        lco_run_document(&structure_name, &model_name, &l.section, &r)
    } else {
        let speeds = sweep_speeds.clone();
        let bar = CountBar::new("LCO", 2 * speeds.len());
        let obs = |p: SweepProgress| {
            let d = match p.direction {
                SweepDirection::Up => "up",
                SweepDirection::Down => "down",
                SweepDirection::Independent => "",
            };
            bar.tick(format!("{d} U = {:.3}", p.u));
        };
        let plan = SweepPlan {
            perturbation_up: pert,
            perturbation_down: Some(pert_down),
            k_iteration,
        };
        let h = l.section.lco_sweeps(&speeds, &plan, &opts, &obs);
        bar.finish();
        let h = h.context("LCO sweep")?;
        crate::ui::say!(
            "{:>10} {:>28} {:>28}",
            "U [m/s]",
            "up: α amp [deg]",
            "down: α amp [deg]"
        );
        for (a, b) in h.up.iter().zip(&h.down) {
            crate::ui::say!(
                "{:>10.4} {:>12.4} {:>15} {:>12.4} {:>15}",
                a.u,
                a.amplitude_alpha.to_degrees(),
                class_name(a),
                b.amplitude_alpha.to_degrees(),
                class_name(b)
            );
        }
        let band = h.band();
        if !band.is_empty() {
            crate::ui::say!("hysteresis at U = {band:?}");
        }
        lco_sweep_document(&structure_name, &model_name, &l.section, &h)
    };
    let mut doc = doc;
    if let Some(n) = args.ensemble {
        let speeds = match args.speed {
            Some(u) => vec![u],
            None => sweep_speeds.clone(),
        };
        let (laws, e) = crate::models::ensemble_laws(&args.model, l.section.aero.chord(), n)?;
        let le = aeroelastic::ensemble::lco_ensemble(
            &l.structure,
            &laws,
            &e,
            l.file.air_density,
            &speeds,
            args.alpha0.to_radians(),
            &opts,
        )
        .context("ensemble LCO runs")?;
        for p in &le.points {
            match p.amplitude_alpha_deg.interval {
                Some(i) => crate::ui::say!(
                    "ensemble U = {} m/s: pitch amplitude median {:.4}°, {:.0} % interval [{:.4}, {:.4}]° ({} of {} members in LCO)",
                    p.u, i.median, 100.0 * le.level, i.lower, i.upper, p.amplitude_alpha_deg.found, le.members
                ),
                None => crate::ui::say!("ensemble U = {} m/s: no member in LCO", p.u),
            }
        }
        for f in &le.failures {
            crate::ui::warning!("warning: ensemble: {f}");
        }
        doc.ensemble = Some(le);
    }
    let json = doc.to_value();
    identify::io::write_atomic(&path, format!("{json:#}\n").as_bytes())?;
    crate::ui::say!("wrote {}", path.display());
    crate::ui::document(&json)
}
