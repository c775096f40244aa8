"""The limits table walked through the Python arguments (docs/DATA_FORMAT.md "Limits"): each
limit whose ``set_by`` names a Python argument is exceeded — a count by one, a bound by one
unit — and the call raises AeroformError naming the argument (the CLI, study keys, sweep
specifications and files are walked by tests/limits.rs)."""

import pytest

import aeroform
from conftest import SCENARIOS

S = str(SCENARIOS / "plate-rig.structure.toml")
M = str(SCENARIOS / "plate-truth.model.toml")
LIMITS = aeroform.limits()


def over(name):
    """One unit (or one count) above the limit ``name``."""
    return LIMITS[name]["max"] + 1


def cases(dataset):
    n_speeds = int(over("MAX_SPEEDS"))
    st = {"air_density": 1.225, "chord": over("MAX_CHORD"), "mass": 1.0933333333333333,
          "inertia": 0.0058037777777777775, "static_unbalance": 0.010933333333333333,
          "freq_heave": 2.0, "freq_pitch": 3.5, "damping_heave": 0.005, "damping_pitch": 0.005}
    return [
        ("MAX_SPEED", "speeds", lambda: aeroform.flutter(S, M, [5.0, over("MAX_SPEED")])),
        ("MAX_SPEED", "speed", lambda: aeroform.lco(S, M, speed=over("MAX_SPEED"))),
        ("MAX_SPEED", "sweep", lambda: aeroform.lco(S, M, sweep=[5.0, over("MAX_SPEED")])),
        ("MAX_SPEED", "u_max", lambda: aeroform.branch(S, M, (5.0, over("MAX_SPEED")))),
        ("MAX_SPEEDS", "speeds", lambda: aeroform.flutter(S, M, f"1:2:{n_speeds}")),
        ("MAX_SPEEDS", "speeds",
         lambda: aeroform.flutter(S, M, [1.0 + i * 1e-4 for i in range(n_speeds)])),
        ("MAX_SPEEDS", "sweep",
         lambda: aeroform.lco(S, M, sweep=[1.0 + i * 1e-4 for i in range(n_speeds)])),
        ("MAX_CHORD", "chord", lambda: aeroform.flutter(st, M, "2:12:5")),
        ("MAX_DAMPING_RATIO", "damping_pitch",
         lambda: aeroform.flutter(dict(st, chord=0.25, damping_pitch=over("MAX_DAMPING_RATIO")),
                                  M, "2:12:5")),
        ("MAX_PITCH_DEG", "alpha0",
         lambda: aeroform.lco(S, M, speed=7.0, alpha0=over("MAX_PITCH_DEG"))),
        ("MAX_PITCH_DEG", "alpha0_down",
         lambda: aeroform.lco(S, M, sweep=[6.0, 7.0], alpha0_down=over("MAX_PITCH_DEG"))),
        ("MAX_ENSEMBLE", "ensemble",
         lambda: aeroform.identify(dataset, ensemble=int(over("MAX_ENSEMBLE")))),
        # members × cases one above the cap: refused before any work, as `--ensemble`
        ("MAX_ENSEMBLE_FITS", "ensemble",
         lambda: aeroform.identify(dataset, ensemble=int(
             LIMITS["MAX_ENSEMBLE_FITS"]["max"]
             // len(aeroform.read_dataset(dataset).case_ids) + 1))),
        ("MAX_N_DELTA", "n_delta",
         lambda: aeroform.identify(dataset, n_delta=int(over("MAX_N_DELTA")))),
        ("MAX_HARMONICS", "harmonics",
         lambda: aeroform.branch(S, M, "5:9", method="harmonic_balance",
                                 harmonics=int(over("MAX_HARMONICS")))),
        ("MAX_STEPS_PER_PERIOD", "steps_per_period",
         lambda: aeroform.branch(S, M, "5:9", steps_per_period=int(over("MAX_STEPS_PER_PERIOD")))),
        ("MAX_BRANCH_POINTS", "max_points",
         lambda: aeroform.branch(S, M, "5:9", max_points=int(over("MAX_BRANCH_POINTS")))),
        ("MAX_BLIND_SETS", "`n`",
         lambda: aeroform.sweep_local({"kind": "blind", "n": int(over("MAX_BLIND_SETS")),
                                       "seed": 1})),
    ]


def test_every_python_argument_beyond_its_limit_is_refused(forced_dataset):
    walked = set()
    for limit, argument, call in cases(str(forced_dataset)):
        with pytest.raises(aeroform.AeroformError) as e:
            call()
        assert argument in str(e.value), f"{limit}: `{argument}` not named in: {e.value}"
        walked.add(limit)
    # every limit a Python argument sets is walked
    python_set = {n for n, row in LIMITS.items() if "Python" in row["set_by"]}
    assert python_set <= walked, sorted(python_set - walked)


def test_the_table_is_the_documented_one():
    assert LIMITS["MAX_SPEED"] == {"max": 1000.0, "unit": "m/s",
                                   "set_by": LIMITS["MAX_SPEED"]["set_by"]}
    assert "Python" in LIMITS["MAX_HARMONICS"]["set_by"]
