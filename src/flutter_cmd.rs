//! `aeroform flutter`: linear flutter and divergence of a structure + aerodynamic model,
//! V–g / V–f data written to `flutter.json`.

use std::path::{Path, PathBuf};

use aeroelastic::files::{LoadedModel, StructureFile};
use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
use aeroelastic::section::Section;
use anyhow::Context;
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
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum MethodArg {
    Pk,
    P,
}

/// Structure file, model and section of a structure/model pair.
pub struct Loaded {
    pub file: StructureFile,
    pub model: LoadedModel,
    pub section: Section,
}

/// Reads a structure file and a model file and builds the section.
pub fn load(structure: &Path, model: &Path, chord: Option<f64>) -> anyhow::Result<Loaded> {
    // The library's errors name the file and the field.
    let file = StructureFile::read(structure).context("structure file")?;
    let st = file.structure().context("structure file")?;
    let loaded = LoadedModel::load(model, chord.or(file.chord)).context("model file")?;
    let section =
        Section::new(st, loaded.model.clone(), file.air_density).context("building the section")?;
    if let Some(t) = &loaded.identified {
        for w in &t.warnings {
            eprintln!("warning: {}: {w}", model.display());
        }
    }
    Ok(Loaded {
        file,
        model: loaded,
        section,
    })
}

/// Parses `a:b:n` (n ≥ 1 speeds from a to b) or a comma list `3,4,5.5`.
pub fn parse_speeds(s: &str) -> anyhow::Result<Vec<f64>> {
    let bad = || anyhow::anyhow!("speeds `{s}`: expected `a:b:n` or a comma list like `3,4,5`");
    let v: Vec<f64> = if let Some((a, rest)) = s.split_once(':') {
        let (b, n) = rest.split_once(':').ok_or_else(bad)?;
        let a: f64 = a.trim().parse().map_err(|_| bad())?;
        let b: f64 = b.trim().parse().map_err(|_| bad())?;
        let n: usize = n.trim().parse().map_err(|_| bad())?;
        match n {
            0 => return Err(bad()),
            1 => vec![a],
            _ => (0..n)
                .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                .collect(),
        }
    } else {
        s.split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
            .collect::<anyhow::Result<_>>()?
    };
    if v.iter().any(|u| !(u.is_finite() && *u > 0.0)) {
        anyhow::bail!("speeds `{s}`: every speed must be finite and > 0");
    }
    Ok(v)
}

/// Runs `aeroform flutter`.
pub fn run(args: &FlutterArgs) -> anyhow::Result<()> {
    let speeds = parse_speeds(&args.speeds)?;
    if speeds.len() < 2 {
        anyhow::bail!(
            "speeds `{}`: a flutter scan needs at least 2 speeds",
            args.speeds
        );
    }
    let l = load(&args.structure, &args.model, args.chord)?;
    let method = match args.method {
        MethodArg::Pk => FlutterMethod::Pk,
        MethodArg::P => FlutterMethod::P,
    };
    let opts = FlutterOptions {
        u_min: speeds.iter().copied().fold(f64::INFINITY, f64::min),
        u_max: speeds.iter().copied().fold(0.0, f64::max),
        n_speeds: speeds.len(),
        tol_rel: 1e-8,
    };
    let fa = l
        .section
        .flutter(method, &opts)
        .context("flutter analysis")?;
    crate::ensure_dir(&args.out)?;
    let b = l.section.aero.chord();
    let point = fa.flutter.map(|f| {
        serde_json::json!({
            "speed": f.u,
            "omega": f.omega,
            "frequency_hz": f.omega / (2.0 * std::f64::consts::PI),
            "reduced_frequency": b * f.omega / f.u,
            "mode": f.mode,
            "u_reduced": f.u_reduced,
            "omega_ratio": f.omega_ratio,
        })
    });
    let json = serde_json::json!({
        "format": "aeroform-flutter/1",
        "structure": args.structure.display().to_string(),
        "model": args.model.display().to_string(),
        "model_name": fa.model,
        "air_density": l.file.air_density,
        "chord": b,
        "critical": point,
        "divergence_speed": fa.divergence_speed,
        "analysis": fa,
        "identified": l.model.identified,
    });
    let path = args.out.join("flutter.json");
    identify::io::write_atomic(&path, format!("{json:#}\n").as_bytes())?;
    match fa.flutter {
        Some(f) => println!(
            "flutter: U_F = {:.4} m/s, f_F = {:.4} Hz (K = {:.4}, mode {})",
            f.u,
            f.omega / (2.0 * std::f64::consts::PI),
            b * f.omega / f.u,
            f.mode
        ),
        None if fa.unstable_at_u_min => println!(
            "flutter: already unstable at the lowest speed {} m/s (U_F is below the scan)",
            opts.u_min
        ),
        None => println!(
            "flutter: none between {} and {} m/s",
            opts.u_min, opts.u_max
        ),
    }
    if let Some(f) = fa.failed.first() {
        println!(
            "warning: {} point(s) of the scan failed and were skipped (first at U = {:.4} m/s: {})",
            fa.failed.len(),
            f.u,
            f.message
        );
    }
    match fa.divergence_speed {
        Some(u) => println!("divergence: U_D = {u:.4} m/s"),
        None => println!("divergence: none"),
    }
    println!("wrote {}", path.display());
    Ok(())
}
