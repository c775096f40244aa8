//! `aeroform branch`: LCO branches by continuation from each Hopf point (stable and
//! unstable, folds, Floquet stability), written to `branch.csv`, `branch.json` and a
//! bifurcation diagram; `--measured` overlays measured amplitudes and reports their
//! distance to the predicted branch of the same stability.

use std::path::PathBuf;

use aeroelastic::branch::{
    measured_distances, read_measured_amplitudes, BranchEnd, BranchMethod, BranchOptions,
    BranchProgress, Lens, LensBranch, SectionParameter,
};
use anyhow::Context;
use clap::Args;

use crate::models::load;

/// Flags of `aeroform branch`.
#[derive(Debug, Args)]
pub struct BranchArgs {
    /// Structure file (TOML).
    #[arg(long)]
    pub structure: PathBuf,
    /// Aerodynamic model: a model TOML file or an identification.json.
    #[arg(long)]
    pub model: PathBuf,
    /// Speed range `a:b` [m/s]: Hopf points are searched and branches continued in it.
    #[arg(long)]
    pub speeds: String,
    /// Measured amplitudes (CSV with columns branch, wind_speed_m_s, heave_amp_m,
    /// pitch_amp_rad) to overlay and compare.
    #[arg(long)]
    pub measured: Option<PathBuf>,
    /// Largest number of points per branch.
    #[arg(long, default_value_t = 200)]
    pub max_points: usize,
    /// RK4 steps per period (shooting integration, or the harmonic-balance orbit's
    /// variational equation for the Floquet multipliers).
    #[arg(long, default_value_t = 128)]
    pub steps_per_period: usize,
    /// Orbit discretisation: `shooting` or `harmonic_balance`.
    #[arg(long, default_value = "shooting")]
    pub method: BranchMethod,
    /// Harmonics of the harmonic-balance series.
    #[arg(long, default_value_t = 5)]
    pub harmonics: usize,
    /// Chord B [m] for an identification.json model.
    #[arg(long)]
    pub chord: Option<f64>,
    /// Also continue the orbit at `--at-speed` in this parameter of the section, at that
    /// fixed speed: `k_h`, `k_alpha`, `c_h`, `c_alpha`, `rho`, or a polynomial coefficient
    /// `pitch_stiffness[P]`, `heave_stiffness[P]`, `pitch_damping[P]`, `heave_damping[P]`
    /// (written to `branch_parameter.csv` and `branch.json`'s `parameter`).
    #[arg(long, requires_all = ["parameter_range", "at_speed"])]
    pub parameter: Option<String>,
    /// Range `a:b` of `--parameter` (its own unit; it must hold the section's value).
    #[arg(long, requires = "parameter")]
    pub parameter_range: Option<String>,
    /// Speed [m/s] of the orbit continued in `--parameter`: the stable orbit of the first
    /// branch that has one there, else its unstable one.
    #[arg(long, requires = "parameter")]
    pub at_speed: Option<f64>,
    /// Output folder, written as a whole (created if missing; an earlier aeroform result
    /// there is replaced, never mixed with the new one).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Replace an existing output folder that aeroform did not write.
    #[arg(long)]
    pub force: bool,
}

impl BranchArgs {
    /// The files these flags name for reading.
    fn inputs(&self) -> Vec<crate::outdir::Input<'_>> {
        use crate::outdir::Input;
        let mut v = vec![
            Input::new("--structure", &self.structure),
            Input::new("--model", &self.model),
        ];
        v.extend(self.measured.iter().map(|p| Input::new("--measured", p)));
        v
    }
}

/// Parses `a:b` into a checked range.
///
/// # Errors
/// [`crate::exit::Usage`] (exit code 2) naming `--speeds`; a speed above the limits table's
/// `MAX_SPEED` is a [`aeroform::limits::LimitError`] (also exit code 2).
fn parse_range(s: &str) -> anyhow::Result<(f64, f64)> {
    let (a, b) = split_pair(s)
        .filter(|&(a, b)| a > 0.0 && b > a)
        .ok_or_else(|| {
            crate::exit::Usage(format!(
                "--speeds `{s}`: expected `a:b` with 0 < a < b [m/s]"
            ))
        })?;
    aeroform::limits::positive_at_most("--speeds", b, aeroform::limits::MAX_SPEED, "m/s")?;
    Ok((a, b))
}

/// `a:b` as two finite numbers, or `None`.
fn split_pair(s: &str) -> Option<(f64, f64)> {
    let (a, b) = s.split_once(':')?;
    let a: f64 = a.trim().parse().ok()?;
    let b: f64 = b.trim().parse().ok()?;
    (a.is_finite() && b.is_finite()).then_some((a, b))
}

/// Parses `--parameter-range a:b` (finite, a < b; signs free: a coefficient may be
/// negative).
///
/// # Errors
/// [`crate::exit::Usage`] naming `--parameter-range`.
fn parse_parameter_range(s: &str) -> anyhow::Result<[f64; 2]> {
    let (a, b) = split_pair(s).filter(|&(a, b)| b > a).ok_or_else(|| {
        crate::exit::Usage(format!(
            "--parameter-range `{s}`: expected `a:b` with finite a < b"
        ))
    })?;
    Ok([a, b])
}

/// The lens, its range and the speed of `--parameter`, checked before any computation.
///
/// # Errors
/// [`crate::exit::Usage`] naming the flag.
fn parameter_request(
    args: &BranchArgs,
) -> anyhow::Result<Option<(SectionParameter, [f64; 2], f64)>> {
    let Some(name) = &args.parameter else {
        return Ok(None);
    };
    let lens = SectionParameter::parse(name)
        .map_err(|e| crate::exit::Usage(format!("--parameter: {e}")))?;
    let range = parse_parameter_range(args.parameter_range.as_deref().unwrap_or(""))?;
    let u = args.at_speed.unwrap_or(f64::NAN);
    if !(u.is_finite() && u > 0.0) {
        return Err(crate::exit::Usage(format!("--at-speed {u}: expected a speed > 0 [m/s]")).into());
    }
    Ok(Some((lens, range, u)))
}

fn stop_text(s: &BranchEnd) -> String {
    match s {
        BranchEnd::SpeedRange { u } => format!("left the speed range at U = {u:.4} m/s"),
        BranchEnd::Amplitude { amplitude_alpha } => format!(
            "pitch amplitude {:.2}° above the limit",
            amplitude_alpha.to_degrees()
        ),
        BranchEnd::Equilibrium { u } => format!("returned to the equilibrium at U = {u:.4} m/s"),
        BranchEnd::MaxPoints => "point limit reached".into(),
        BranchEnd::NotConverged { message, .. } => format!("did not converge {message}"),
    }
}

/// Runs `aeroform branch`.
pub fn run(args: &BranchArgs) -> anyhow::Result<()> {
    // before anything is computed (`OutDir::begin` checks it again)
    crate::outdir::refuse_overlap(&args.out, "--out", &args.inputs())?;
    let (u_min, u_max) = parse_range(&args.speeds)?;
    let lens_request = parameter_request(args)?;
    let opts = BranchOptions {
        max_points: args.max_points,
        steps_per_period: args.steps_per_period,
        method: args.method,
        harmonics: args.harmonics,
        ..BranchOptions::default()
    };
    // The counts against the limits table, before any file is read, named by their flag
    // (`branch.max_points` is `--max-points`).
    if let Err(aeroelastic::Error::InvalidParameter {
        field,
        value,
        message,
    }) = opts.check()
    {
        let flag = field.trim_start_matches("branch.").replace('_', "-");
        return Err(crate::exit::Usage(format!(
            "--{flag} = {}: {message}",
            identify::limits::show(value)
        ))
        .into());
    }
    let l = load(&args.structure, &args.model, args.chord)?;
    let measured = match &args.measured {
        Some(p) => Some(read_measured_amplitudes(p).context("measured amplitudes")?),
        None => None,
    };
    let bar = crate::progress::CountBar::new("branch", args.max_points);
    let obs = |p: BranchProgress| {
        bar.set(
            p.points,
            format!(
                "branch {}: U = {:.4} m/s, α = {:.3}°",
                p.branch,
                p.u,
                p.amplitude_alpha.to_degrees()
            ),
        )
    };
    let set = l.branches(u_min, u_max, &opts, &obs);
    bar.finish();
    let set = set.with_context(|| format!("LCO branches in U = {u_min}…{u_max} m/s"))?;
    for (i, b) in set.branches.iter().enumerate() {
        crate::ui::say!(
            "branch {i}: Hopf point U = {:.4} m/s, {:.4} Hz, {}; {} orbits, {}",
            b.hopf.u,
            b.hopf.omega / std::f64::consts::TAU,
            b.criticality,
            b.points.len(),
            stop_text(&b.stop)
        );
        if let BranchEnd::NotConverged { message, .. } = &b.stop {
            crate::ui::warning!("warning: branch {i} stopped early: it did not converge {message}");
        }
        for e in &b.events {
            crate::ui::say!(
                "  {:?} at U = {:.4} m/s, pitch amplitude {:.3}°, heave amplitude {:.2} mm",
                e.kind,
                e.u,
                e.amplitude_alpha.to_degrees(),
                e.amplitude_h * 1e3
            );
        }
    }
    let dist = measured
        .as_deref()
        .map(|m| measured_distances(&set, m))
        .unwrap_or_default();
    if !dist.is_empty() {
        crate::ui::say!(
            "{:>9} {:>9} {:>14} {:>14} {:>12} {:>12}",
            "U [m/s]",
            "branch",
            "meas α1 [deg]",
            "pred α1 [deg]",
            "Δα1 [deg]",
            "Δh1 [mm]"
        );
        for d in &dist {
            let f =
                |v: Option<f64>, k: f64| v.map_or("—".to_string(), |x| format!("{:.3}", x * k));
            crate::ui::say!(
                "{:>9.3} {:>9} {:>14} {:>14} {:>12} {:>12}{}",
                d.measured.u,
                if d.measured.stable {
                    "stable"
                } else {
                    "unstable"
                },
                f(d.measured.amplitude_alpha, 180.0 / std::f64::consts::PI),
                f(d.predicted_alpha, 180.0 / std::f64::consts::PI),
                f(d.d_alpha, 180.0 / std::f64::consts::PI),
                f(d.d_h, 1e3),
                match (d.predicted_alpha, d.speed_gap) {
                    (Some(_), _) => String::new(),
                    (None, Some(gap)) => format!(
                        "  (no predicted branch of this stability here; nearest {gap:.3} m/s away)"
                    ),
                    (None, None) => "  (no predicted orbit of this stability)".to_string(),
                }
            );
        }
    }
    let lens = match lens_request {
        Some((lens, range, u)) => Some(continue_in_parameter(&l.section, &set, &lens, range, u, &opts)?),
        None => None,
    };
    let mut doc = aeroelastic::documents::branch_document(
        &args.structure.display().to_string(),
        &args.model.display().to_string(),
        &set,
        &dist,
    );
    doc.parameter = lens.clone();
    let json = doc.to_value();
    // staged, locked and moved into place as a whole (issue 27, row 6); taken once the
    // branches are computed, so that a refused input never touches the folder
    let dir = crate::outdir::OutDir::begin(&args.out, "branch", args.force, &args.inputs())?;
    let staged = dir.path().to_path_buf();
    identify::io::write_atomic(
        &staged.join("branch.csv"),
        aeroelastic::documents::branch_csv(&set).as_bytes(),
    )?;
    identify::io::write_atomic(
        &staged.join("branch.json"),
        format!("{json:#}\n").as_bytes(),
    )?;
    if let Some(lb) = &lens {
        identify::io::write_atomic(
            &staged.join("branch_parameter.csv"),
            aeroelastic::documents::lens_csv(lb).as_bytes(),
        )?;
    }
    let fig = plots::save(
        &plots::adapters::aeroelastic::branch_figure(&set, &dist, vec![]),
        &staged,
        "branch_diagram",
    )
    .context("bifurcation diagram")?;
    let png = fig.png.file_name().map(std::path::PathBuf::from);
    if let Some(lb) = &lens {
        plots::save(
            &plots::adapters::aeroelastic::lens_figure(lb),
            &staged,
            "branch_parameter",
        )
        .context("diagram in the parameter")?;
    }
    let out = dir.commit()?;
    crate::ui::say!(
        "wrote {}, {}, {}",
        out.join("branch.csv").display(),
        out.join("branch.json").display(),
        png.map_or_else(|| out.clone(), |p| out.join(p)).display()
    );
    crate::ui::document(&json)
}

/// The orbit at `u` continued in `lens` over `range`
/// ([`aeroelastic::section::Section::continue_set_in`]); prints its folds and stability
/// changes.
///
/// # Errors
/// Those of `continue_set_in`: no branch has an orbit at `u` is a usage error of
/// `--at-speed`.
fn continue_in_parameter(
    section: &aeroelastic::section::Section,
    set: &aeroelastic::branch::BranchSet,
    lens: &SectionParameter,
    range: [f64; 2],
    u: f64,
    opts: &BranchOptions,
) -> anyhow::Result<LensBranch> {
    let lb = match section.continue_set_in(set, lens, range, u, opts) {
        Err(aeroelastic::Error::InvalidParameter { field, message, .. }) if field == "at_speed" => {
            return Err(crate::exit::Usage(format!("--at-speed {u}: {message}")).into())
        }
        r => r.with_context(|| format!("continuation in {} at U = {u} m/s", lens.name()))?,
    };
    let start = &lb.points[lb.start_index].orbit;
    crate::ui::say!(
        "{} at U = {u:.4} m/s from {} ({} orbit, pitch amplitude {:.3}°): {} orbits over {:.6}…{:.6}",
        lb.parameter,
        lb.start_value,
        if start.stable { "stable" } else { "unstable" },
        start.amplitude_alpha.to_degrees(),
        lb.points.len(),
        lb.points.first().map_or(f64::NAN, |q| q.value),
        lb.points.last().map_or(f64::NAN, |q| q.value)
    );
    for e in &lb.events {
        crate::ui::say!(
            "  {:?} at {} = {:.6}, pitch amplitude {:.3}°",
            e.kind,
            lb.parameter,
            e.value,
            e.amplitude_alpha.to_degrees()
        );
    }
    Ok(lb)
}
