//! `aeroform lco`: limit-cycle oscillation at one speed or over a sweep (up and down),
//! written to `lco.json`.

use std::path::PathBuf;

use crate::progress::CountBar;
use aeroelastic::documents::{lco_run_document, lco_sweep_document};
use aeroelastic::lco::{Classification, SweepDirection, SweepProgress};
use anyhow::Context;
use clap::Args;

use crate::flutter_cmd::{load, parse_speeds};

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
}

fn class_name(c: &Classification) -> String {
    match c {
        Classification::Decay => "decay".into(),
        Classification::Lco => "LCO".into(),
        Classification::Divergent { time_left_bound } => {
            format!("divergent (left the bound at t = {time_left_bound:.3} s)")
        }
        Classification::Unsettled => "unsettled".into(),
    }
}

/// Runs `aeroform lco`.
pub fn run(args: &LcoArgs) -> anyhow::Result<()> {
    let l = load(&args.structure, &args.model, args.chord)?;
    let structure_name = args.structure.display().to_string();
    let model_name = args.model.display().to_string();
    crate::ensure_dir(&args.out)?;
    let path = args.out.join("lco.json");
    let json = if let Some(u) = args.speed {
        let r = l
            .lco_run(u, args.alpha0.to_radians())
            .with_context(|| format!("LCO run at U = {u} m/s"))?;
        println!(
            "U = {u} m/s: {}, pitch amplitude {:.4}°, heave amplitude {:.3} mm, {:.4} Hz",
            class_name(&r.result.classification),
            r.result.amplitude_alpha.to_degrees(),
            r.result.amplitude_h * 1e3,
            r.result.omega / (2.0 * std::f64::consts::PI)
        );
        lco_run_document(&structure_name, &model_name, &r)
    } else {
        let speeds = parse_speeds(args.sweep.as_deref().unwrap_or_default())?;
        let bar = CountBar::new("LCO", 2 * speeds.len());
        let obs = |p: SweepProgress| {
            let d = match p.direction {
                SweepDirection::Up => "up",
                SweepDirection::Down => "down",
                SweepDirection::Independent => "",
            };
            bar.tick(format!("{d} U = {:.3}", p.u));
        };
        let h = l.lco_sweep(
            &speeds,
            args.alpha0.to_radians(),
            args.alpha0_down.to_radians(),
            &obs,
        );
        bar.finish();
        let h = h.context("LCO sweep")?;
        println!(
            "{:>10} {:>28} {:>28}",
            "U [m/s]", "up: α amp [deg]", "down: α amp [deg]"
        );
        for (a, b) in h.up.iter().zip(&h.down) {
            println!(
                "{:>10.4} {:>12.4} {:>15} {:>12.4} {:>15}",
                a.u,
                a.amplitude_alpha.to_degrees(),
                class_name(&a.classification),
                b.amplitude_alpha.to_degrees(),
                class_name(&b.classification)
            );
        }
        let band = h.band();
        if !band.is_empty() {
            println!("hysteresis at U = {band:?}");
        }
        lco_sweep_document(&structure_name, &model_name, &h)
    };
    identify::io::write_atomic(&path, format!("{json:#}\n").as_bytes())?;
    println!("wrote {}", path.display());
    Ok(())
}
