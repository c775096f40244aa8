"""Shared fixtures: the repository, the `aeroform` binary (built by scripts/test), and a
forced-motion data set written by the CLI's virtual wind tunnel."""

import json
import math
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"


def cli_binary() -> Path:
    """The CLI built from this checkout (AEROFORM_BIN overrides)."""
    p = Path(os.environ.get("AEROFORM_BIN", ROOT / "target" / "release" / "aeroform"))
    if not p.exists():
        pytest.fail(f"{p} not found: build it first (cargo build --release -p aeroform, as scripts/test does)")
    return p


def run_cli(*args: str) -> str:
    r = subprocess.run([str(cli_binary()), *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def max_difference(a, b, path="$"):
    """Largest |a − b| / max(1, |a|) over every number of two JSON documents; any
    structural difference (keys, lengths, strings, nulls) raises AssertionError."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), f"{path}: keys differ"
        return max([max_difference(a[k], b[k], f"{path}.{k}") for k in a] or [0.0])
    if isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        return max([max_difference(x, y, f"{path}[{i}]") for i, (x, y) in enumerate(zip(a, b))] or [0.0])
    if isinstance(a, bool) or a is None or isinstance(a, str):
        assert a == b, f"{path}: {a!r} != {b!r}"
        return 0.0
    assert isinstance(b, (int, float)) and not isinstance(b, bool), f"{path}: {a!r} vs {b!r}"
    if math.isnan(a) or math.isnan(b):
        assert math.isnan(a) and math.isnan(b), f"{path}: {a} vs {b}"
        return 0.0
    return abs(a - b) / max(1.0, abs(a))


@pytest.fixture(scope="session")
def forced_dataset(tmp_path_factory) -> Path:
    """Configuration D (4 amplitudes × 4 speeds) of the truth plate, 4 s records, with
    still-air runs (so the wind–no-wind subtraction is exercised)."""
    out = tmp_path_factory.mktemp("tunnel") / "ds"
    run_cli("tunnel", "forced", "--model", SCENARIOS / "plate-truth.model.toml",
            "--campaign", "config=D", "--still-air", "--duration", "4", "--out", out)
    return out


@pytest.fixture(scope="session")
def cli_identification(forced_dataset, tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("cli-id")
    run_cli("identify", forced_dataset, "--out", out, "--quiet")
    return json.loads((out / "identification.json").read_text())
