#!/usr/bin/env python3
"""Speed comparison: aeroform `identify` against pysindy 2.1 per-case `SINDy.fit`.

Acceptance (DESIGN/brief): 448 cases (7 configurations x 8 amplitudes x 8 wind speeds) of
10 s at 512 Hz, full identification (library, group STLSQ, a 50-value delta path, metrics):
aeroform must be >= 30x faster than pysindy's per-case SINDy.fit on the same data.

Steps
 1. Write the data set (DATA_FORMAT.md: manifest.toml + cases/*.csv, units mm/deg/N/N*m
    totals, B = 0.25 m, span 0.75 m, rho = 1.225) with forces from a known Eq. 19-type law
    (constant nondimensional coefficients, see LAW) plus seeded Gaussian noise; reused when
    a data set with the same fingerprint is already there.
 2. Run `aeroform identify DIR --out OUTDIR --group-by config --timing-json T.json`
    (built with `cargo build --release` when missing) and time the process wall clock.
 3. Load the same CSVs, build alpha, B*alpha_dot/U, h/B, h_dot/U (velocities from the known
    harmonic motion: NOT timed) and C_L, C_M, then time pysindy: for each case and each of
    the 50 deltas, `ps.SINDy(feature_library=LIB, optimizer=ps.STLSQ(threshold=delta))
    .fit(x, t=dt, x_dot=[C_L, C_M])`; and once per case with a single delta (pysindy's
    default threshold 0.1). Only the fits are timed (no CSV reading, no velocities).
    LIB is pysindy's PolynomialLibrary(degree=3, include_bias=False) with the paper's four
    terms (alpha alpha_dot^2, alpha^2 alpha_dot, h h_dot^2, h^2 h_dot) removed: 30 terms,
    the same candidate set as aeroform (`--library full34` for the plain 34-term library).
    pysindy has no group sparsity, so per-case fits are the closest equivalent; both targets
    (lift and moment) are fitted in one call, as aeroform identifies both.
 4. Print a table and write benches/peers/identify_speed.json.

Usage:
  benches/peers/.venv/bin/python benches/peers/identify_speed.py [--quick]
      [--data DIR] [--aeroform PATH] [--skip-aeroform] [--library paper30|full34]
"""
import argparse
import hashlib
import json
import os
import pathlib
import platform
import shutil
import subprocess
import sys
import time
import warnings

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
HERE = pathlib.Path(__file__).resolve().parent

# --- campaign (coordinator's reconstruction of the paper's Tables I-II) -------------------
CONFIGS = {  # name: (f_alpha [Hz], f_h [Hz], heave/pitch amplitude ratio [mm/deg])
    "A": (1.0, 0.7, 1.0),
    "B": (1.5, 0.7, 1.0),
    "C": (2.0, 0.7, 1.5),
    "D": (2.0, 1.3, 1.5),
    "E": (2.5, 1.3, 2.0),
    "F": (1.5, 1.1, 2.0),
    "G": (3.0, 1.7, 1.0),
}
AMPLITUDES = [3.0 * k for k in range(1, 9)]  # pitch amplitude [deg]
WIND_SPEEDS = [float(u) for u in range(3, 11)]  # [m/s]
QUICK = dict(configs=["A", "D"], amplitudes=[6.0, 24.0], wind_speeds=[4.0, 10.0])
CHORD = 0.25  # B [m]
SPAN = 0.75  # [m]
RHO = 1.225  # [kg/m^3]
FS = 512.0  # [Hz]
DURATION = 10.0  # [s]
SEED = 20230901  # case k uses numpy default_rng(SEED + k), k = index in manifest order
NOISE = 0.02  # noise std as a fraction of the clean force RMS, per channel

# Known Eq. 19-type law: constant nondimensional coefficients of
# C = sum_i c_i * term_i(alpha, B alpha_dot/U, h/B, h_dot/U), DATA_FORMAT term names.
# Signs follow DESIGN.md section 2 (h, lift positive down; alpha, moment positive nose-up).
LAW = {
    "lift": {
        "h_dot": -4.0,
        "alpha_dot": -1.2,
        "alpha": -5.5,
        "h": 0.4,
        "alpha*alpha_dot": 2.0,
        "alpha^3": 4.0,
        "alpha_dot^3": -3.0,
    },
    "moment": {
        "h_dot": 0.9,
        "alpha_dot": -0.3,
        "alpha": 1.4,
        "h": -0.1,
        "alpha*alpha_dot": -0.6,
        "alpha^3": -1.2,
        "alpha_dot^3": 1.0,
    },
}
DELTA_GRID = dict(min=1e-3, max=10.0, n=50)  # log grid of STLSQ thresholds for pysindy
SINGLE_DELTA = 0.1  # pysindy's default STLSQ threshold


def campaign(quick):
    sel = QUICK if quick else dict(configs=list(CONFIGS), amplitudes=AMPLITUDES, wind_speeds=WIND_SPEEDS)
    cases = []
    for c in sel["configs"]:
        f_a, f_h, ratio = CONFIGS[c]
        for u in sel["wind_speeds"]:
            for a in sel["amplitudes"]:
                cases.append(
                    dict(
                        id=f"{c}-U{u:g}-A{a:g}",
                        config=c,
                        wind_speed=u,
                        amplitude=a,
                        amplitude_ratio=ratio,
                        freq_pitch=f_a,
                        freq_heave=f_h,
                    )
                )
    return cases


def motion(case, t):
    """alpha [rad], alpha_dot [rad/s], h [m], h_dot [m/s] of the prescribed harmonic motion."""
    a = np.deg2rad(case["amplitude"])
    wa = 2 * np.pi * case["freq_pitch"]
    hm = case["amplitude_ratio"] * case["amplitude"] * 1e-3
    wh = 2 * np.pi * case["freq_heave"]
    return (
        a * np.sin(wa * t),
        a * wa * np.cos(wa * t),
        hm * np.sin(wh * t),
        hm * wh * np.cos(wh * t),
    )


def law_terms(al, ad, hb, hd):
    return {
        "alpha": al,
        "alpha_dot": ad,
        "h": hb,
        "h_dot": hd,
        "alpha*alpha_dot": al * ad,
        "alpha^3": al**3,
        "alpha_dot^3": ad**3,
    }


def fingerprint(cases):
    blob = json.dumps(
        dict(cases=cases, law=LAW, seed=SEED, noise=NOISE, fs=FS, duration=DURATION, v=1),
        sort_keys=True,
    )
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def write_dataset(d, cases):
    """Writes the data set folder; returns True when written, False when reused."""
    fp = fingerprint(cases)
    manifest = d / "manifest.toml"
    if manifest.exists() and f'fingerprint = "{fp}"' in manifest.read_text():
        return False
    if d.exists():
        shutil.rmtree(d)
    (d / "cases").mkdir(parents=True)
    n = int(round(DURATION * FS))
    t = np.arange(n) / FS
    q_lines = [
        'format = "aeroform-dataset/1"',
        f'name = "pysindy speed comparison, {len(cases)} forced cases"',
        'description = "Synthetic forced-motion records from a constant-coefficient Eq. 19-type '
        'law with seeded Gaussian force noise (benches/peers/identify_speed.py)."',
        "",
        "[section]",
        f"chord = {CHORD}",
        f"span = {SPAN}",
        f"air_density = {RHO}",
        "",
        "[units]",
        'heave = "mm"',
        'pitch = "deg"',
        'lift = "N"',
        'moment = "N*m"',
        "",
        "[extra]",
        'generator = "benches/peers/identify_speed.py"',
        f'fingerprint = "{fp}"',
        f"seed = {SEED}",
        'seed_rule = "case k (0-based, manifest order) draws from numpy.random.default_rng(seed + k): lift noise then moment noise"',
        f"noise_fraction_of_rms = {NOISE}",
        "law_lift = " + toml_inline(LAW["lift"]),
        "law_moment = " + toml_inline(LAW["moment"]),
        "",
    ]
    for k, c in enumerate(cases):
        al, ad, h, hd = motion(c, t)
        u = c["wind_speed"]
        x = (al, CHORD * ad / u, h / CHORD, hd / u)
        terms = law_terms(*x)
        cl = sum(v * terms[name] for name, v in LAW["lift"].items())
        cm = sum(v * terms[name] for name, v in LAW["moment"].items())
        q = 0.5 * RHO * u * u
        lift = cl * q * CHORD * SPAN  # total over span [N]
        mom = cm * q * CHORD**2 * SPAN  # total over span [N m]
        rng = np.random.default_rng(SEED + k)
        lift = lift + NOISE * np.sqrt(np.mean(lift**2)) * rng.standard_normal(n)
        mom = mom + NOISE * np.sqrt(np.mean(mom**2)) * rng.standard_normal(n)
        data = np.column_stack([t, h * 1e3, np.rad2deg(al), lift, mom])
        f = d / "cases" / f"{c['id']}.csv"
        np.savetxt(
            f,
            data,
            fmt=["%.9f", "%.9f", "%.9f", "%.9e", "%.9e"],
            delimiter=",",
            header="t,h,alpha,lift,moment",
            comments="",
        )
        q_lines += [
            "[[case]]",
            f'id = "{c["id"]}"',
            'kind = "forced"',
            f'file = "cases/{c["id"]}.csv"',
            f"wind_speed = {u:.1f}",
            f'config = "{c["config"]}"',
            f"amplitude = {c['amplitude']:.1f}",
            f"amplitude_ratio = {c['amplitude_ratio']:.1f}",
            f"freq_pitch = {c['freq_pitch']:.1f}",
            f"freq_heave = {c['freq_heave']:.1f}",
            "",
        ]
    tmp = d / ".manifest.toml.tmp"
    tmp.write_text("\n".join(q_lines))
    os.replace(tmp, manifest)
    return True


def toml_inline(table):
    return "{ " + ", ".join(f'"{k}" = {v}' for k, v in table.items()) + " }"


def run_aeroform(args, data_dir, out_dir):
    exe = pathlib.Path(args.aeroform) if args.aeroform else ROOT / "target" / "release" / "aeroform"
    if not exe.exists():
        if args.aeroform:
            sys.exit(f"error: --aeroform {exe} does not exist")
        print(f"building {exe} (cargo build --release) ...", flush=True)
        r = subprocess.run(["cargo", "build", "--release", "--bin", "aeroform"], cwd=ROOT)
        if r.returncode != 0 or not exe.exists():
            sys.exit("error: `cargo build --release` failed; cannot time aeroform")
    out_dir.mkdir(parents=True, exist_ok=True)
    tjson = out_dir / "timing.json"
    ident = out_dir / "identification.json"
    for f in (tjson, ident):
        if f.exists():
            f.unlink()
    cmd = [str(exe), "identify", str(data_dir), "--out", str(out_dir), "--group-by", "config",
           "--timing-json", str(tjson)]
    print("running: " + " ".join(cmd), flush=True)
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0 or not tjson.exists() or not ident.exists():
        tail = (r.stderr or r.stdout or "").strip().splitlines()[-8:]
        sys.exit(
            "error: `aeroform identify` is not available or failed "
            f"(exit code {r.returncode}; timing JSON {'present' if tjson.exists() else 'missing'}, "
            f"identification.json {'present' if ident.exists() else 'missing'}).\n"
            "The speed comparison needs the coordinator's CLI: `aeroform identify DIR --out OUTDIR "
            "--group-by config --timing-json T.json` writing OUTDIR/identification.json and "
            'T.json = {"read_s", "identify_s", "total_s", "cases"}.\n'
            "Use --skip-aeroform to time pysindy alone.\n"
            + ("aeroform output:\n  " + "\n  ".join(tail) if tail else "aeroform printed nothing")
        )
    timing = json.loads(tjson.read_text())
    for key in ("read_s", "identify_s", "total_s", "cases"):
        if key not in timing:
            sys.exit(f"error: {tjson} lacks `{key}`: {timing}")
    return dict(
        command=" ".join(cmd),
        wall_s=wall,
        read_s=float(timing["read_s"]),
        identify_s=float(timing["identify_s"]),
        total_s=float(timing["total_s"]),
        cases=int(timing["cases"]),
        delta_grid=delta_grid_from(ident),
    )


def delta_grid_from(ident_path):
    """The delta path recorded in identification.json settings, if any (a 50-value list, or
    min/max/count keys); None when not found."""
    try:
        settings = json.loads(ident_path.read_text()).get("settings", {})
    except (OSError, ValueError):
        return None
    for k, v in settings.items():
        if "delta" in k.lower() and isinstance(v, list) and len(v) >= 2 and all(
            isinstance(e, (int, float)) for e in v
        ):
            return dict(values=[float(e) for e in v], key=k)
    return None


def paper30_library_class(ps):
    """pysindy's PolynomialLibrary(degree=3, include_bias=False) without the paper's four
    terms alpha alpha_dot^2, alpha^2 alpha_dot, h h_dot^2, h^2 h_dot (input indices: 0 alpha,
    1 alpha_dot, 2 h, 3 h_dot); same transform code, 30 columns."""
    removed = {(0, 1, 1), (0, 0, 1), (2, 3, 3), (2, 2, 3)}

    class Paper30Library(ps.PolynomialLibrary):
        @staticmethod
        def _combinations(*a, **kw):
            return [c for c in ps.PolynomialLibrary._combinations(*a, **kw) if tuple(c) not in removed]

    return Paper30Library


def load_cases(data_dir, cases):
    """CSV -> (x (n,4) nondimensional regressors, y (n,2) [C_L, C_M], dt). Not timed."""
    out = []
    for c in cases:
        a = np.loadtxt(data_dir / "cases" / f"{c['id']}.csv", delimiter=",", skiprows=1)
        t, h_mm, al_deg, lift, mom = a.T
        dt = float(np.polyfit(np.arange(len(t)), t, 1)[0])
        u = c["wind_speed"]
        al = np.deg2rad(al_deg)
        h = h_mm * 1e-3
        _, ad, _, hd = motion(c, t)  # exact velocities of the prescribed harmonic motion
        x = np.column_stack([al, CHORD * ad / u, h / CHORD, hd / u])
        q = 0.5 * RHO * u * u
        y = np.column_stack([lift / SPAN / (q * CHORD), mom / SPAN / (q * CHORD**2)])
        out.append((x, y, dt))
    return out


def time_pysindy(ps, make_lib, data, deltas):
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    n_terms = None
    for k, (x, y, dt) in enumerate(data):
        if len(deltas) > 1 and k and k % 32 == 0:
            el = time.perf_counter() - t0
            print(f"  {k}/{len(data)} cases, {el:.0f} s, ~{el / k * (len(data) - k):.0f} s left",
                  file=sys.stderr, flush=True)
        for d in deltas:
            m = ps.SINDy(feature_library=make_lib(), optimizer=ps.STLSQ(threshold=float(d)))
            m.fit(x, t=dt, x_dot=y)
            n_terms = m.coefficients().shape[1]
    return time.perf_counter() - t0, n_terms


def blas_threads():
    """BLAS/OpenMP thread pools numpy uses (threadpoolctl ships with scikit-learn)."""
    try:
        from threadpoolctl import threadpool_info

        return [dict(api=i.get("internal_api"), threads=i.get("num_threads")) for i in threadpool_info()]
    except Exception:  # informational only
        return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="8 cases (A, D x A6, A24 x U4, U10)")
    ap.add_argument("--data", help="data set folder (default out/peers/identify_speed/data[-quick])")
    ap.add_argument("--aeroform", help="aeroform binary (default target/release/aeroform, built if missing)")
    ap.add_argument("--skip-aeroform", action="store_true", help="time pysindy only")
    ap.add_argument("--library", choices=["paper30", "full34"], default="paper30")
    ap.add_argument("--json", default=str(HERE / "identify_speed.json"), help="result file")
    args = ap.parse_args()

    import pysindy as ps  # noqa: E402  (after argparse so --help works without the venv)
    import scipy
    import sklearn

    cases = campaign(args.quick)
    base = ROOT / "out" / "peers" / "identify_speed"
    data_dir = pathlib.Path(args.data) if args.data else base / ("data-quick" if args.quick else "data")
    t0 = time.perf_counter()
    written = write_dataset(data_dir, cases)
    print(f"data set: {data_dir} ({len(cases)} cases, {'written' if written else 'reused'} "
          f"in {time.perf_counter() - t0:.1f} s)", flush=True)

    aero = None
    if not args.skip_aeroform:
        aero = run_aeroform(args, data_dir, base / ("aeroform-quick" if args.quick else "aeroform"))
        if aero["cases"] != len(cases):
            sys.exit(f"error: aeroform identified {aero['cases']} cases, expected {len(cases)}")

    if aero and aero["delta_grid"] and len(aero["delta_grid"]["values"]) == DELTA_GRID["n"]:
        deltas = np.array(aero["delta_grid"]["values"])
        grid_src = f"identification.json settings.{aero['delta_grid']['key']}"
    else:
        deltas = np.logspace(np.log10(DELTA_GRID["min"]), np.log10(DELTA_GRID["max"]), DELTA_GRID["n"])
        grid_src = f"np.logspace(log10({DELTA_GRID['min']}), log10({DELTA_GRID['max']}), {DELTA_GRID['n']})"

    data = load_cases(data_dir, cases)
    if args.library == "paper30":
        lib_cls = paper30_library_class(ps)
        make_lib = lambda: lib_cls(degree=3, include_bias=False)  # noqa: E731
    else:
        make_lib = lambda: ps.PolynomialLibrary(degree=3, include_bias=False)  # noqa: E731
    print(f"timing pysindy: {len(data)} cases x {len(deltas)} deltas ...", flush=True)
    p50, n_terms = time_pysindy(ps, make_lib, data, deltas)
    p1, _ = time_pysindy(ps, make_lib, data, [SINGLE_DELTA])
    nc = len(data)

    res = dict(
        cases=nc,
        samples_per_case=int(data[0][0].shape[0]),
        campaign="quick" if args.quick else "full (7 configs x 8 amplitudes x 8 wind speeds)",
        data_dir=str(data_dir),
        library=f"{args.library} ({n_terms} terms)",
        targets=["C_L", "C_M"],
        delta_grid=dict(source=grid_src, n=len(deltas), min=float(deltas.min()), max=float(deltas.max())),
        single_delta=SINGLE_DELTA,
        pysindy=dict(
            version=ps.__version__ if hasattr(ps, "__version__") else "2.1.0",
            call="ps.SINDy(feature_library=LIB, optimizer=ps.STLSQ(threshold=delta)).fit(x, t=dt, x_dot=[C_L, C_M])",
            fits_50_delta_s=p50,
            fits_1_delta_s=p1,
            per_case_50_delta_ms=1e3 * p50 / nc,
            per_case_1_delta_ms=1e3 * p1 / nc,
            per_fit_ms=1e3 * p50 / (nc * len(deltas)),
        ),
        aeroform=aero,
        environment=dict(
            python=platform.python_version(),
            numpy=np.__version__,
            scipy=scipy.__version__,
            sklearn=sklearn.__version__,
            cpu_count=os.cpu_count(),
            blas_threads=blas_threads(),
            machine=platform.machine(),
        ),
    )
    if aero:
        res["ratios"] = dict(
            pysindy50_over_aeroform_identify=p50 / aero["identify_s"],
            pysindy50_over_aeroform_wall=p50 / aero["wall_s"],
            pysindy1_over_aeroform_identify=p1 / aero["identify_s"],
            pysindy1_over_aeroform_wall=p1 / aero["wall_s"],
        )
        res["acceptance"] = dict(
            criterion="pysindy 50-delta fit time / aeroform identify_s >= 30",
            passed=res["ratios"]["pysindy50_over_aeroform_identify"] >= 30.0,
        )
    else:
        res["ratios"] = None
        res["acceptance"] = dict(
            criterion="pysindy 50-delta fit time / aeroform identify_s >= 30",
            passed=None,
            note="aeroform not timed (--skip-aeroform)",
        )

    rows = []
    if aero:
        rows += [
            ("aeroform identify_s (T.json)", aero["identify_s"], ""),
            ("aeroform total_s (T.json)", aero["total_s"], ""),
            ("aeroform process wall time", aero["wall_s"], ""),
        ]
    rows += [
        (f"pysindy {len(deltas)} deltas (fits only)", p50, f"{1e3 * p50 / nc:.1f} ms/case"),
        ("pysindy 1 delta (fits only)", p1, f"{1e3 * p1 / nc:.1f} ms/case"),
    ]
    print(f"\n{nc} cases x {res['samples_per_case']} samples, library {res['library']}, targets C_L, C_M")
    print(f"delta grid: {grid_src}")
    print(f"{'':38s} {'time [s]':>10s}")
    for name, v, note in rows:
        print(f"{name:38s} {v:10.3f}  {note}")
    if aero:
        r = res["ratios"]
        print(f"\nratio pysindy(50 delta) / aeroform identify_s : {r['pysindy50_over_aeroform_identify']:8.1f}x")
        print(f"ratio pysindy(50 delta) / aeroform wall       : {r['pysindy50_over_aeroform_wall']:8.1f}x")
        print(f"ratio pysindy(1 delta)  / aeroform identify_s : {r['pysindy1_over_aeroform_identify']:8.1f}x")
        print(f"ratio pysindy(1 delta)  / aeroform wall       : {r['pysindy1_over_aeroform_wall']:8.1f}x")
        print(f"acceptance (>= 30x on identify_s): {'PASS' if res['acceptance']['passed'] else 'FAIL'}")
    out = pathlib.Path(args.json)
    tmp = out.with_name("." + out.name + ".tmp")
    tmp.write_text(json.dumps(res, indent=1) + "\n")
    os.replace(tmp, out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
