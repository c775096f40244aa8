//! LCO sweep timing: the benchmark model (HP-1, Theodorsen–Jones, cubic pitch spring) at N
//! speeds from 0.8 U_F to 1.3 U_F, each run integrated for a fixed duration of at least
//! `cycles` response cycles from α = 0.05 rad. Prints one JSON object (speeds, tolerances,
//! timings, RHS evaluations, cycles, final amplitudes) for `benches/peers/lco_scipy.py`.
//!
//! Usage: `cargo run --release -p aeroelastic --example lco_sweep -- [n_speeds] [cycles] [rtol] [atol]`

use std::time::Instant;

use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
use aeroelastic::lco::{LcoOptions, LcoResult};
use aeroelastic::reference::hp1_cubic_pitch;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let get = |i: usize, d: f64| args.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(d);
    let n = get(0, 100.0) as usize;
    let cycles = get(1, 200.0);
    let rtol = get(2, 1e-8);
    let atol = get(3, 1e-10);
    let alpha0 = 0.05;
    let s = hp1_cubic_pitch();
    let fo = FlutterOptions {
        u_min: 0.05,
        u_max: 4.0,
        n_speeds: 80,
        tol_rel: 1e-10,
    };
    let uf = match s.flutter(FlutterMethod::P, &fo) {
        Ok(r) => r.flutter.map(|f| f.u).unwrap_or(f64::NAN),
        Err(e) => {
            eprintln!("flutter analysis failed: {e}");
            std::process::exit(1);
        }
    };
    let speeds: Vec<f64> = (0..n)
        .map(|i| uf * (0.8 + 0.5 * i as f64 / (n.max(2) - 1) as f64))
        .collect();
    // Response frequency ≤ 0.7 ω_α over the range, so this many pitch periods hold ≥ `cycles`
    // response cycles.
    let opts = LcoOptions {
        rtol,
        atol,
        max_periods: cycles / 0.64,
        stop_when_classified: false,
        ..LcoOptions::default()
    };
    let t_end = opts.max_periods * 2.0 * std::f64::consts::PI / s.structure.omega_alpha();
    let y0 = s.perturbation(alpha0);
    let t0 = Instant::now();
    let seq: Vec<LcoResult> = speeds
        .iter()
        .map(|&u| s.lco_run(u, &y0, &opts).expect("run"))
        .collect();
    let t_seq = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let par = s
        .lco_scan_parallel(&speeds, &y0, &opts, &|_| {})
        .expect("scan");
    let t_par = t1.elapsed().as_secs_f64();
    assert_eq!(par.len(), seq.len());
    let evals: u64 = seq.iter().map(|r| r.rhs_evals).sum();
    let steps: u64 = seq.iter().map(|r| r.steps).sum();
    let ncyc: usize = seq.iter().map(|r| r.cycles).sum();
    let lco: Vec<&LcoResult> = seq.iter().filter(|r| r.u > uf * 1.01).collect();
    let lco_evals: u64 = lco.iter().map(|r| r.rhs_evals).sum();
    let lco_cycles: usize = lco.iter().map(|r| r.cycles).sum();
    let out = serde_json::json!({
        "model": s.aero.name() + " + cubic pitch spring (HP-1)",
        "u_flutter": uf,
        "speeds": speeds,
        "t_end": t_end,
        "rtol": rtol,
        "atol": atol,
        "alpha0": alpha0,
        "seconds_sequential": t_seq,
        "seconds_parallel": t_par,
        "threads": rayon::current_num_threads(),
        "rhs_evals": evals,
        "steps": steps,
        "cycles": ncyc,
        "rhs_evals_per_cycle": evals as f64 / ncyc.max(1) as f64,
        "rhs_evals_per_cycle_lco_runs": lco_evals as f64 / lco_cycles.max(1) as f64,
        "final_alpha": seq.iter().map(|r| r.final_state[1]).collect::<Vec<_>>(),
        "amplitude_alpha": seq.iter().map(|r| r.amplitude_alpha).collect::<Vec<_>>(),
    });
    println!("{out}");
}
