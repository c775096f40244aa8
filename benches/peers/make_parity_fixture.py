#!/usr/bin/env python3
"""Write the pysindy 2.1 STLSQ parity fixture for aeroform.

Outputs (paths relative to the repository root):
  identify/tests/fixtures/pysindy_parity.csv   columns x0,x1,x2,x3,y (shortest round-trip
                                               float repr, so Rust parses the same doubles)
  identify/tests/fixtures/pysindy_parity.json  pysindy version, seed, feature names, and the
                                               options + fitted coefficients of every run

Signals (aeroform regressors, DESIGN.md §2), B = 0.25 m, U = 8 m/s, 1500 samples at 200 Hz:
  x0 = alpha       two-frequency harmonic pitch, amplitude ~0.3 rad
  x1 = B alpha'/U  its exact derivative, nondimensional
  x2 = h/B         multi-sine heave
  x3 = h'/U        its exact derivative, nondimensional
  y                sparse law with a small-scale cubic term ((B alpha'/U)^3), plus
                   seeded Gaussian noise; small seeded noise is also added to x (a
                   measured record is never an exact polynomial identity).

Each run is fitted through the public pysindy API:
  ps.SINDy(feature_library=ps.PolynomialLibrary(degree=3, include_bias=False),
           optimizer=ps.STLSQ(...)).fit(x, t=dt, x_dot=y[:, None])
(SINDy.fit accepts a 1-column x_dot although its docstring asks for x's shape; the
target is then regressed on the library of x). The script asserts that this equals
STLSQ(...).fit(library.fit_transform(x), y) bit for bit.

Usage: benches/peers/.venv/bin/python benches/peers/make_parity_fixture.py
"""
import json
import pathlib
import warnings

import numpy as np
import pysindy as ps
import scipy
import sklearn

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIX = ROOT / "identify" / "tests" / "fixtures"
SEED = 20230721
N = 1500
DT = 1.0 / 200.0
B = 0.25
U = 8.0

# True sparse law (names in pysindy's order): the (B alpha'/U)^3 term is small-scale:
# its column has squared norm ~ 1e-3, far below alpha = 0.05, so pysindy's ridge shrinks it.
LAW = {
    "x0": 1.2,
    "x1": -0.8,
    "x2": 0.5,
    "x3": -1.5,
    "x0 x1": 0.6,
    "x0^3": 2.0,
    "x1^3": 40.0,
}
NOISE_Y = 2e-3
NOISE_X = 1e-5

RUNS = [
    # threshold, alpha, max_iter, unbias, normalize_columns
    dict(threshold=0.05, alpha=0.05, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.05, alpha=0.05, max_iter=20, unbias=False, normalize_columns=False),
    dict(threshold=0.1, alpha=0.0, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.1, alpha=0.0, max_iter=20, unbias=False, normalize_columns=False),
    dict(threshold=0.01, alpha=1e-3, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.01, alpha=1e-3, max_iter=20, unbias=False, normalize_columns=False),
    dict(threshold=0.1, alpha=0.05, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.1, alpha=0.05, max_iter=1, unbias=False, normalize_columns=False),
    dict(threshold=0.02, alpha=0.05, max_iter=20, unbias=True, normalize_columns=True),
    dict(threshold=0.02, alpha=0.05, max_iter=20, unbias=False, normalize_columns=True),
    dict(threshold=100.0, alpha=0.05, max_iter=20, unbias=True, normalize_columns=False),
]


def signals(rng):
    t = np.arange(N) * DT
    w1, w2 = 2 * np.pi * 1.5, 2 * np.pi * 2.3
    a1, a2, p2 = 0.2, 0.1, 0.4
    alpha = a1 * np.sin(w1 * t) + a2 * np.sin(w2 * t + p2)
    alpha_dot = a1 * w1 * np.cos(w1 * t) + a2 * w2 * np.cos(w2 * t + p2)
    v1, v2, q2 = 2 * np.pi * 0.7, 2 * np.pi * 1.1, 1.0
    b1, b2 = 0.02, 0.01  # [m]
    h = b1 * np.sin(v1 * t) + b2 * np.sin(v2 * t + q2)
    h_dot = b1 * v1 * np.cos(v1 * t) + b2 * v2 * np.cos(v2 * t + q2)
    x = np.column_stack([alpha, B * alpha_dot / U, h / B, h_dot / U])
    x = x + NOISE_X * rng.standard_normal(x.shape)
    return t, x


def harmonic_signals(rng):
    """Campaign-like single-frequency forced motion (configuration D, U = 7 m/s, A = 12 deg):
    alpha = A sin(2 pi f_a t), h = 1.5 mm/deg * A sin(2 pi f_h t), exact velocities, 512 Hz,
    no noise on x. Under such motion the 34-term library is rank deficient
    (alpha_dot^2 = w^2 (A^2 - alpha^2) and its products), so only ridge runs (alpha > 0) are
    well posed."""
    n, dt, u = 2048, 1.0 / 512.0, 7.0
    t = np.arange(n) * dt
    a, wa = np.deg2rad(12.0), 2 * np.pi * 2.0
    hm, wh = 1.5 * 12.0 * 1e-3, 2 * np.pi * 1.3
    x = np.column_stack(
        [
            a * np.sin(wa * t),
            B * a * wa * np.cos(wa * t) / u,
            hm * np.sin(wh * t) / B,
            hm * wh * np.cos(wh * t) / u,
        ]
    )
    return dt, u, x


HARMONIC_RUNS = [
    dict(threshold=0.1, alpha=0.05, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.1, alpha=0.05, max_iter=20, unbias=False, normalize_columns=False),
    dict(threshold=0.05, alpha=0.05, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.01, alpha=1e-3, max_iter=20, unbias=True, normalize_columns=False),
    dict(threshold=0.01, alpha=1e-3, max_iter=20, unbias=False, normalize_columns=False),
]


def fit_runs(x, y, dt, theta, names, run_opts):
    runs = []
    for opts in run_opts:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = ps.SINDy(
                feature_library=ps.PolynomialLibrary(degree=3, include_bias=False),
                optimizer=ps.STLSQ(**opts),
            )
            model.fit(x, t=dt, x_dot=y[:, None])
            coef = np.asarray(model.coefficients())[0]
            opt = ps.STLSQ(**opts)
            opt.fit(theta, y)
        assert np.array_equal(coef, opt.coef_[0]), "SINDy.fit != optimizer.fit"
        # Margin of every thresholding decision (relative distance of |coef| to the
        # threshold over the whole history); a tiny margin would make parity fragile.
        hist = [np.asarray(h)[0] for h in opt.history_[1:]]
        margin = min(
            (abs(abs(c) - opts["threshold"]) / opts["threshold"] for h in hist for c in h if c != 0.0),
            default=float("inf"),
        )
        runs.append(
            dict(
                options=opts,
                iterations=len(hist),
                threshold_margin=None if margin == float("inf") else margin,
                support=[n for n, c in zip(names, coef) if c != 0.0],
                coefficients=[float(c) for c in coef],
            )
        )
        print(f"{opts} iters={len(hist)} margin={margin:.2e} support={runs[-1]['support']}")
    return runs


def write_fixture(stem, x, y, meta):
    FIX.mkdir(parents=True, exist_ok=True)
    lines = ["x0,x1,x2,x3,y"]
    for row, yi in zip(x, y):
        lines.append(",".join(repr(float(v)) for v in row) + "," + repr(float(yi)))
    (FIX / f"{stem}.csv").write_text("\n".join(lines) + "\n")
    (FIX / f"{stem}.json").write_text(json.dumps(meta, indent=1, allow_nan=False) + "\n")
    print(f"cond(theta) = {meta['condition_number']:.3e}; wrote {FIX / stem}.{{csv,json}}")


def common_meta(names, theta):
    s = np.linalg.svd(theta, compute_uv=False)
    return dict(
        generator="benches/peers/make_parity_fixture.py",
        pysindy_version=ps.__version__ if hasattr(ps, "__version__") else "2.1.0",
        numpy_version=np.__version__,
        scipy_version=scipy.__version__,
        sklearn_version=sklearn.__version__,
        variables=["alpha", "B*alpha_dot/U", "h/B", "h_dot/U"],
        fit_call=(
            "ps.SINDy(feature_library=ps.PolynomialLibrary(degree=3, include_bias=False), "
            "optimizer=ps.STLSQ(**options)).fit(x, t=dt, x_dot=y[:, None]); "
            "identical to STLSQ(**options).fit(library.fit_transform(x), y)"
        ),
        library="ps.PolynomialLibrary(degree=3, include_bias=False)",
        feature_names=names,
        column_norms=[float(c) for c in np.linalg.norm(theta, axis=0)],
        singular_values=[float(v) for v in s],
        condition_number=float(s[0] / s[-1]),
        numerical_rank=int(np.sum(s > s[0] * len(s) * np.finfo(float).eps)),
    )


def main():
    # 1. Generic fixture: two-frequency pitch, multi-sine heave, noisy x and y.
    rng = np.random.default_rng(SEED)
    t, x = signals(rng)
    lib = ps.PolynomialLibrary(degree=3, include_bias=False)
    theta = np.asarray(lib.fit_transform(x))
    names = lib.get_feature_names()
    w_true = np.array([LAW.get(n, 0.0) for n in names])
    y = theta @ w_true + NOISE_Y * rng.standard_normal(N)
    runs = fit_runs(x, y, DT, theta, names, RUNS)
    meta = common_meta(names, theta)
    meta.update(
        seed=SEED,
        rng="numpy.random.default_rng(seed): x noise (N x 4) first, then y noise (N)",
        n_samples=N,
        dt=DT,
        chord=B,
        wind_speed=U,
        noise_std=dict(x=NOISE_X, y=NOISE_Y),
        true_law=LAW,
        runs=runs,
    )
    write_fixture("pysindy_parity", x, y, meta)

    # 2. Harmonic fixture: the campaign's motion, rank-deficient library, ridge runs only.
    rng = np.random.default_rng(SEED + 1)
    dt, u, x = harmonic_signals(rng)
    theta = np.asarray(lib.fit_transform(x))
    y = theta @ w_true + NOISE_Y * rng.standard_normal(len(x))
    runs = fit_runs(x, y, dt, theta, names, HARMONIC_RUNS)
    meta = common_meta(names, theta)
    meta.update(
        seed=SEED + 1,
        rng="numpy.random.default_rng(seed): y noise (N)",
        n_samples=len(x),
        dt=dt,
        chord=B,
        wind_speed=u,
        motion="configuration D (f_alpha 2.0 Hz, f_h 1.3 Hz, 1.5 mm/deg), A = 12 deg, U = 7 m/s",
        noise_std=dict(x=0.0, y=NOISE_Y),
        true_law=LAW,
        runs=runs,
    )
    write_fixture("pysindy_parity_harmonic", x, y, meta)


if __name__ == "__main__":
    main()
