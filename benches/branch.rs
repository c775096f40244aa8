//! Criterion benchmark: a 100-point LCO branch by continuation (shooting + pseudo-arclength,
//! `aeroelastic::branch`) against the time-integration sweep (Dop853, rtol 1e-10, each
//! speed started from the previous speed's final state) that finds the same stable
//! amplitudes to 0.1 %, both on the cubic-pitch-spring HP-1 section of `benches/lco.rs`
//! and in one group so that one run gives the ratio.
//!
//! Two time-integration baselines: the continuation sweep (`lco_sweep`, each speed from the
//! previous final state) and independent runs from one fixed perturbation (α₀ = 0.05 rad).
//! The branch uses 64 RK4 steps per period (the set-up check shows it still meets 0.1 %).
//! A third contender is the same branch by harmonic balance (5 harmonics; the aerodynamics
//! is linear, so it is the form condensed onto h and α, with multipliers from 64 steps of
//! the exponential trapezoidal rule plus a Richardson step), checked against the sweep the
//! same way. Every contender's time includes the Hopf search (`lco_branches`).
//!
//! Before timing, the set-up checks that the sweep's amplitudes agree with the branch
//! (Newton-corrected orbit at each sweep speed) to 0.1 % and prints the largest
//! difference; the sweep covers 100 speeds over the stable part of the branch.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};

use aeroelastic::branch::{BranchMethod, BranchOptions};
use aeroelastic::lco::{Classification, KIteration, LcoOptions, SweepDirection};
use aeroelastic::reference::hp1_cubic_pitch;

fn branch_vs_sweep(c: &mut Criterion) {
    let s = hp1_cubic_pitch();
    let opts = BranchOptions {
        max_points: 100,
        ds_max: 0.1,
        steps_per_period: 64,
        ..BranchOptions::default()
    };
    let set = s.lco_branches(1.5, 4.0, &opts, &|_| {}).expect("branch");
    let b = &set.branches[0];
    assert_eq!(b.points.len(), 100, "{:?}", b.stop);
    let uf = b.hopf.u;
    let u_end = b.points.last().expect("points").u;
    // 100 speeds from 2 % above the Hopf point to the end of the branch.
    let u0 = 1.02 * uf;
    let speeds: Vec<f64> = (0..100)
        .map(|i| u0 + (u_end - u0) * i as f64 / 99.0)
        .collect();
    let lco = LcoOptions::default();
    let y0 = s.perturbation(0.05);
    let sweep = || {
        s.lco_sweep(
            &speeds,
            SweepDirection::Up,
            &y0,
            &lco,
            &KIteration::default(),
            &|_| {},
        )
        .expect("sweep")
    };
    // Independent runs from the same fixed perturbation (no continuation between speeds).
    let fixed = || {
        speeds
            .iter()
            .map(|&u| s.lco_run(u, &y0, &lco).expect("run"))
            .collect::<Vec<_>>()
    };
    let mut worst_fixed: f64 = 0.0;
    for r in &fixed() {
        if r.classification != Classification::Lco {
            worst_fixed = f64::INFINITY;
            continue;
        }
        let o = s.orbit_on_branch(b, r.u, true, &opts).expect("orbit");
        worst_fixed =
            worst_fixed.max((o.amplitude_alpha - r.amplitude_alpha).abs() / r.amplitude_alpha);
    }
    eprintln!("fixed-perturbation runs: largest amplitude difference {worst_fixed:.2e}");
    let runs = sweep();
    let mut worst: f64 = 0.0;
    for r in &runs {
        assert_eq!(r.classification, Classification::Lco, "U = {}", r.u);
        let o = s.orbit_on_branch(b, r.u, true, &opts).expect("orbit");
        worst = worst.max((o.amplitude_alpha - r.amplitude_alpha).abs() / r.amplitude_alpha);
    }
    eprintln!(
        "branch: 100 points, U = {:.4} … {:.4} (U_F = {uf:.4}); sweep 100 speeds {u0:.4} … {u_end:.4}; \
         largest amplitude difference {:.2e}",
        b.points[0].u, u_end, worst
    );
    assert!(worst < 1e-3, "sweep and branch differ by {worst}");
    // The same 100-point branch by harmonic balance (5 harmonics), checked the same way.
    // Its scaled arclength counts the sine and cosine coefficients of h and α, so the same
    // ds covers more U: ds_max 0.075 makes its 100 points just reach the sweep's end.
    let hb = BranchOptions {
        method: BranchMethod::HarmonicBalance,
        ds_max: 0.075,
        ..opts
    };
    let set_hb = s.lco_branches(1.5, 4.0, &hb, &|_| {}).expect("hb branch");
    let bh = &set_hb.branches[0];
    assert_eq!(bh.points.len(), 100, "{:?}", bh.stop);
    assert!(
        bh.points.last().expect("points").u >= u_end,
        "HB branch ends earlier"
    );
    let mut worst_hb: f64 = 0.0;
    for r in &runs {
        let o = s.orbit_on_branch(bh, r.u, true, &hb).expect("hb orbit");
        worst_hb = worst_hb.max((o.amplitude_alpha - r.amplitude_alpha).abs() / r.amplitude_alpha);
    }
    eprintln!(
        "harmonic balance: 100 points, U = {:.4} … {:.4}; largest amplitude difference to the sweep {:.2e}",
        bh.points[0].u,
        bh.points.last().expect("points").u,
        worst_hb
    );
    assert!(worst_hb < 1e-3, "sweep and HB branch differ by {worst_hb}");
    let mut g = c.benchmark_group("branch");
    g.sample_size(10);
    // Flat sampling: the fixed-perturbation baseline takes seconds per iteration.
    g.sampling_mode(SamplingMode::Flat);
    g.bench_function("continuation_100_points", |bch| {
        bch.iter(|| {
            s.lco_branches(1.5, 4.0, &opts, &|_| {})
                .expect("branch")
                .branches[0]
                .points
                .len()
        })
    });
    g.bench_function("harmonic_balance_100_points", |bch| {
        bch.iter(|| {
            s.lco_branches(1.5, 4.0, &hb, &|_| {})
                .expect("branch")
                .branches[0]
                .points
                .len()
        })
    });
    g.bench_function("time_integration_sweep_100_speeds", |bch| {
        bch.iter(|| sweep().len())
    });
    g.bench_function("time_integration_fixed_perturbation_100_speeds", |bch| {
        bch.iter(|| fixed().len())
    });
    g.finish();
}

criterion_group!(benches, branch_vs_sweep);
criterion_main!(benches);
