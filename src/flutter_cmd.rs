//! `aeroform flutter`: linear flutter and divergence of a structure + aerodynamic model,
//! V–g / V–f data written to `flutter.json`.

use std::path::PathBuf;

use aeroelastic::documents::{flutter_document, flutter_options};
use aeroelastic::flutter::FlutterMethod;
use anyhow::Context;

use crate::models::load;
use crate::outdir::Input;
use clap::{Args, ValueEnum};

/// Flags of `aeroform flutter`.
#[derive(Debug, Args)]
pub struct FlutterArgs {
    /// Structure file (TOML: mass, inertia, static_unbalance, freq_heave, freq_pitch, …).
    #[arg(long)]
    pub structure: PathBuf,
    /// Aerodynamic model: a model TOML file or an identification.json.
    #[arg(long)]
    pub model: PathBuf,
    /// Speed scan `a:b:n` [m/s] (n speeds from a to b).
    #[arg(long, default_value = "1:20:96")]
    pub speeds: String,
    /// Flutter method: p-k (exact frequency response) or p (time-domain realisation).
    #[arg(long, value_enum, default_value_t = MethodArg::Pk)]
    pub method: MethodArg,
    /// Chord B [m] for an identification.json model (else `chord` of the structure file).
    #[arg(long)]
    pub chord: Option<f64>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Flutter and divergence of the first N members of the model's ensemble (an
    /// identification.json written with `identify --ensemble`): intervals in flutter.json.
    #[arg(long, value_name = "N")]
    pub ensemble: Option<usize>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum MethodArg {
    Pk,
    P,
}

/// Runs `aeroform flutter`.
pub fn run(args: &FlutterArgs) -> anyhow::Result<()> {
    let speeds = aeroform::limits::parse_speeds("--speeds", &args.speeds)?;
    if speeds.len() < 2 {
        crate::exit::refuse!(
            "speeds `{}`: a flutter scan needs at least 2 speeds",
            args.speeds
        );
    }
    let l = load(&args.structure, &args.model, args.chord)?;
    let method = match args.method {
        MethodArg::Pk => FlutterMethod::Pk,
        MethodArg::P => FlutterMethod::P,
    };
    let opts = flutter_options(&speeds).context("--speeds")?;
    let fa = l
        .section
        .flutter(method, &opts)
        .context("flutter analysis")?;
    let path = args.out.join("flutter.json");
    crate::outdir::refuse_symlink(&args.out, "--out")?;
    let _out = crate::outdir::SharedDir::begin(
        &args.out,
        &[&path],
        &[
            Input::new("--structure", &args.structure),
            Input::new("--model", &args.model),
        ],
    )?;
    let b = l.section.aero.chord();
    let ensemble = match args.ensemble {
        Some(n) => Some(
            l.flutter_ensemble(&args.model, method, &speeds, Some(n))
                .context("ensemble flutter analysis")?,
        ),
        None => None,
    };
    let mut doc = flutter_document(
        &args.structure.display().to_string(),
        &args.model.display().to_string(),
        &l,
        &fa,
    );
    doc.ensemble = ensemble.clone();
    let json = doc.to_value();
    identify::io::write_atomic(&path, format!("{json:#}\n").as_bytes())?;
    match fa.flutter {
        Some(f) => crate::ui::say!(
            "flutter: U_F = {:.4} m/s, f_F = {:.4} Hz (K = {:.4}, mode {})",
            f.u,
            f.omega / (2.0 * std::f64::consts::PI),
            b * f.omega / f.u,
            f.mode
        ),
        None if fa.unstable_at_u_min => crate::ui::say!(
            "flutter: already unstable at the lowest speed {} m/s (U_F is below the scan)",
            opts.u_min
        ),
        None => crate::ui::say!(
            "flutter: none between {} and {} m/s",
            speeds.iter().copied().fold(f64::INFINITY, f64::min),
            speeds.iter().copied().fold(0.0, f64::max)
        ),
    }
    if let Some(f) = fa.failed.first() {
        crate::ui::say!(
            "warning: {} point(s) of the scan failed and were skipped (first at U = {:.4} m/s: {})",
            fa.failed.len(),
            f.u,
            f.message
        );
    }
    // U_D is the root of the static stiffness (no scan): say when it lies outside the scan
    let (lo, hi) = (
        speeds.iter().copied().fold(f64::INFINITY, f64::min),
        speeds.iter().copied().fold(0.0, f64::max),
    );
    match fa.divergence_speed {
        Some(u) if u < lo || u > hi => crate::ui::say!(
            "divergence: U_D = {u:.4} m/s (outside the scanned {lo}–{hi} m/s: from the static \
             stiffness, not the scan)"
        ),
        Some(u) => crate::ui::say!("divergence: U_D = {u:.4} m/s"),
        None => crate::ui::say!("divergence: none (no positive root of the static stiffness)"),
    }
    if let Some(e) = &ensemble {
        let show =
            |name: &str, q: &aeroelastic::ensemble::MemberQuantity, unit: &str| match q.interval {
                Some(i) => crate::ui::say!(
                "{name}: median {:.4} {unit}, {:.0} % interval [{:.4}, {:.4}] ({} of {} members)",
                i.median,
                100.0 * e.level,
                i.lower,
                i.upper,
                q.found,
                e.members
            ),
                None => crate::ui::say!("{name}: none in any of the {} members", e.members),
            };
        show("ensemble U_F", &e.flutter_speed, "m/s");
        show("ensemble f_F", &e.flutter_frequency_hz, "Hz");
        show("ensemble U_D", &e.divergence_speed, "m/s");
        for f in &e.failures {
            crate::ui::warning!("warning: ensemble: {f}");
        }
    }
    crate::ui::say!("wrote {}", path.display());
    crate::ui::document(&json)
}
