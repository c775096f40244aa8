#!/usr/bin/env python3
"""Side-by-side LCO sweep: aeroform (Rust, ode_solvers Dop853) vs scipy solve_ivp(DOP853).

Same model (HP-1 typical section, Theodorsen aerodynamics with Jones' two lag states, cubic
hardening pitch spring k_a (alpha + 10 alpha^3); b = 1 m, omega_alpha = 1 rad/s, rho = 1),
same speeds (N from 0.8 U_F to 1.3 U_F, U_F from aeroform's p-method), same initial state
(alpha = 0.05 rad), same duration (>= 200 response cycles), same rtol/atol.

Usage (from the repository root):
    python3 -m venv benches/peers/.venv && benches/peers/.venv/bin/pip install numpy scipy
    benches/peers/.venv/bin/python benches/peers/lco_scipy.py [--speeds 100] [--cycles 200]
        [--scipy-speeds N]   # run scipy on every k-th speed only, to save time; the ratio is
                             # then computed per speed and extrapolated, and says so

It builds and runs `cargo run --release -p aeroelastic --example lco_sweep`, which prints
its timing as JSON, then runs scipy and prints the ratio and the agreement of the final states.
"""
import argparse
import json
import math
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

PI = math.pi


def model(u):
    """Right-hand side for wind speed u (mirrors aeroelastic::lco Rhs with the reference model)."""
    mu, r2, sigma, x_a, a = 20.0, 6.0 / 25.0, 0.4, 0.1, -0.2
    m = mu * PI
    i_a = r2 * m
    s_a = x_a * m
    k_h = m * sigma**2
    k_a = i_a
    k3 = 10.0 * k_a
    # total mass = structural - apparent mass (apparent mass matrix of the thin aerofoil)
    ma = np.array([[-PI, PI * a], [PI * a, -PI * (0.125 + a * a)]])
    mt = np.array([[m, s_a], [s_a, i_a]]) - ma
    mi = np.linalg.inv(mt)
    m00, m01, m10, m11 = mi[0, 0], mi[0, 1], mi[1, 0], mi[1, 1]
    c1 = 0.165 * 0.0455
    c2 = 0.335 * 0.3
    hb = 0.5 - a
    ea = 0.5 + a

    def rhs(t, y):
        h, al, hd, ad, x1, x2 = y
        w = hd + u * al + hb * ad
        wc = 0.5 * w + c1 * x1 + c2 * x2
        circ = 2.0 * PI * u * wc
        lift = -(circ + PI * u * ad)
        mom = ea * circ - PI * u * hb * ad
        g0 = lift - k_h * h
        g1 = mom - (k_a * al + k3 * al * al * al)
        return [hd, ad, m00 * g0 + m01 * g1, m10 * g0 + m11 * g1,
                u * (w - 0.0455 * x1), u * (w - 0.3 * x2)]

    return rhs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--speeds", type=int, default=100)
    ap.add_argument("--cycles", type=float, default=200.0)
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--atol", type=float, default=1e-10)
    ap.add_argument("--scipy-every", type=int, default=1,
                    help="run scipy on every k-th speed only (ratio per speed, extrapolated)")
    args = ap.parse_args()

    cmd = ["cargo", "run", "--quiet", "--release", "-p", "aeroelastic", "--example", "lco_sweep", "--",
           str(args.speeds), str(args.cycles), str(args.rtol), str(args.atol)]
    rust = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    speeds = rust["speeds"]
    t_end = rust["t_end"]
    idx = list(range(0, len(speeds), args.scipy_every))
    y0 = [0.0, rust["alpha0"], 0.0, 0.0, 0.0, 0.0]
    nfev = 0
    worst = 0.0
    t0 = time.perf_counter()
    for i in idx:
        sol = solve_ivp(model(speeds[i]), (0.0, t_end), y0, method="DOP853",
                        rtol=args.rtol, atol=args.atol)
        if not sol.success:
            print(f"scipy failed at U = {speeds[i]}: {sol.message}", file=sys.stderr)
        nfev += sol.nfev
        amp = max(abs(rust["amplitude_alpha"][i]), 1e-3)
        worst = max(worst, abs(sol.y[1, -1] - rust["final_alpha"][i]) / amp)
    t_scipy = time.perf_counter() - t0
    t_scipy_full = t_scipy * len(speeds) / len(idx)
    t_rust = rust["seconds_sequential"]
    out = {
        "speeds": len(speeds),
        "scipy_speeds_run": len(idx),
        "t_end": t_end,
        "rtol": args.rtol,
        "atol": args.atol,
        "aeroform_seconds_sequential": t_rust,
        "aeroform_seconds_parallel": rust["seconds_parallel"],
        "aeroform_rhs_evals": rust["rhs_evals"],
        "aeroform_rhs_evals_per_cycle": rust["rhs_evals_per_cycle"],
        "aeroform_rhs_evals_per_cycle_lco_runs": rust["rhs_evals_per_cycle_lco_runs"],
        "scipy_seconds": t_scipy,
        "scipy_seconds_for_all_speeds": t_scipy_full,
        "scipy_rhs_evals": nfev,
        "speedup_sequential": t_scipy_full / t_rust,
        "worst_final_alpha_difference_relative_to_amplitude": worst,
    }
    print(json.dumps(out, indent=2))
    print(f"aeroform is {out['speedup_sequential']:.0f}x faster than scipy DOP853 "
          f"({t_rust:.3f} s vs {t_scipy_full:.1f} s for {len(speeds)} speeds)"
          + ("" if args.scipy_every == 1 else f" [scipy timed on {len(idx)} speeds, scaled]"))


if __name__ == "__main__":
    main()
