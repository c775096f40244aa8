"""`aeroform.flutter` / `aeroform.lco` / `aeroform.branch` equal the CLI's flutter.json /
lco.json / branch.json and branch.csv."""

import json

import pytest

import aeroform
from conftest import SCENARIOS, max_difference, run_cli

S = SCENARIOS / "plate-rig.structure.toml"
M = SCENARIOS / "plate-truth.model.toml"


def test_flutter_equals_the_cli(tmp_path):
    run_cli("flutter", "--structure", S, "--model", M, "--speeds", "2:12:41", "--out", tmp_path)
    cli = json.loads((tmp_path / "flutter.json").read_text())
    py = aeroform.flutter(str(S), str(M), "2:12:41")
    assert max_difference(cli, py) == 0.0
    # The truth plate flutters near 6.6 m/s (structure file comment).
    assert 6.0 < py["critical"]["speed"] < 7.2


def test_lco_equals_the_cli(tmp_path):
    run_cli("lco", "--structure", S, "--model", M, "--speed", "12", "--out", tmp_path)
    cli = json.loads((tmp_path / "lco.json").read_text())
    py = aeroform.lco(str(S), str(M), speed=12.0)
    assert max_difference(cli, py) == 0.0
    run_cli("lco", "--structure", S, "--model", M, "--sweep", "6:9:3", "--out", tmp_path)
    cli = json.loads((tmp_path / "lco.json").read_text())
    py = aeroform.lco(str(S), str(M), sweep=[6.0, 7.5, 9.0])
    assert max_difference(cli, py) == 0.0


def test_structure_dict_and_identified_model(forced_dataset):
    st = {"air_density": 1.225, "chord": 0.25, "mass": 1.0933333333333333,
          "inertia": 0.0058037777777777775, "static_unbalance": 0.010933333333333333,
          "freq_heave": 2.0, "freq_pitch": 3.5, "damping_heave": 0.005, "damping_pitch": 0.005}
    truth = aeroform.flutter(st, str(M), "2:12:41")
    ident = aeroform.identify(forced_dataset)
    fl = aeroform.flutter(st, ident, "2:12:41")
    # The identified law predicts the truth's flutter speed within 5 %.
    assert abs(fl["critical"]["speed"] / truth["critical"]["speed"] - 1) < 0.05


def test_errors_name_the_file_and_field(tmp_path):
    with pytest.raises(aeroform.AeroformError, match="missing.toml"):
        aeroform.flutter(str(tmp_path / "missing.toml"), str(M), "2:12:5")
    bad = tmp_path / "s.toml"
    bad.write_text(S.read_text() + "\nmas = 1.0\n")
    with pytest.raises(aeroform.AeroformError, match="mas"):
        aeroform.flutter(str(bad), str(M), "2:12:5")
    with pytest.raises(aeroform.AeroformError, match="at least 2"):
        aeroform.flutter(str(S), str(M), [5.0])
    with pytest.raises(aeroform.AeroformError, match="speeds"):
        aeroform.flutter(str(S), str(M), "2:x:5")
    with pytest.raises(aeroform.AeroformError, match="exactly one"):
        aeroform.lco(str(S), str(M))
    with pytest.raises(aeroform.AeroformError, match="speeds"):
        aeroform.branch(str(S), str(M), "5")
    with pytest.raises(aeroform.AeroformError, match="no Hopf point"):
        aeroform.branch(str(BS), str(BM), "1:5")


BS = SCENARIOS / "bristol-spring1.structure.toml"
BM = SCENARIOS / "bristol-spring1.model.toml"
BMEAS = SCENARIOS / "bristol-spring1-lco-amplitudes.csv"


def test_branch_equals_the_cli(tmp_path):
    run_cli("branch", "--structure", BS, "--model", BM, "--speeds", "12:20",
            "--measured", BMEAS, "--out", tmp_path)
    cli = json.loads((tmp_path / "branch.json").read_text())
    py = aeroform.branch(str(BS), str(BM), (12.0, 20.0), measured=BMEAS)
    assert max_difference(cli, py) == 0.0
    assert py.csv == (tmp_path / "branch.csv").read_text()
    # The Bristol rig model is subcritical: Hopf near 17.96 m/s, one fold below it.
    assert abs(py["hopf_points"][0]["u"] - 17.957) < 5e-3
    assert len(py["folds"]) == 1 and py["folds"][0]["U_m_s"] < py["hopf_points"][0]["u"]
    cols = py.columns()
    n = sum(len(b["points"]) for b in py["branches"])
    assert len(cols["U_m_s"]) == n and cols["stable"].dtype == bool
    # Both stabilities are present on a subcritical branch.
    assert cols["stable"].any() and not cols["stable"].all()


def test_branch_by_harmonic_balance_finds_the_same_fold(tmp_path):
    run_cli("branch", "--structure", BS, "--model", BM, "--speeds", "12:20",
            "--method", "harmonic_balance", "--out", tmp_path)
    cli = json.loads((tmp_path / "branch.json").read_text())
    hb = aeroform.branch(str(BS), str(BM), (12.0, 20.0), method="harmonic_balance")
    assert max_difference(cli, hb) == 0.0
    assert hb["settings"]["options"]["method"] == "harmonic_balance"
    sh = aeroform.branch(str(BS), str(BM), (12.0, 20.0))
    f_hb, f_sh = hb["folds"][0]["U_m_s"], sh["folds"][0]["U_m_s"]
    assert abs(f_hb - f_sh) < 1e-4 * f_sh
    with pytest.raises(aeroform.AeroformError, match="collocation"):
        aeroform.branch(str(BS), str(BM), (12.0, 20.0), method="collocation")


def test_lag_law_is_flown_like_any_model(tmp_path):
    """The law with memory (`identify --law lag`'s lag_law.json, here through the model file
    `kind = "lag"` of the plate rig) in flutter, lco and branch: the CLI's documents, and a
    stall-flutter cycle above the flutter speed (tests/lag_flight.rs: U_F 4.13 m/s)."""
    lag = SCENARIOS / "plate-lag.model.toml"
    run_cli("flutter", "--structure", S, "--model", lag, "--speeds", "2:8:61", "--out", tmp_path / "f")
    cli = json.loads((tmp_path / "f" / "flutter.json").read_text())
    py = aeroform.flutter(str(S), str(lag), "2:8:61")
    assert max_difference(cli, py) == 0.0
    assert 4.0 < py["critical"]["speed"] < 4.3
    run_cli("lco", "--structure", S, "--model", lag, "--speed", "5", "--out", tmp_path / "l")
    cli = json.loads((tmp_path / "l" / "lco.json").read_text())
    py = aeroform.lco(str(S), str(lag), speed=5.0)
    assert max_difference(cli, py) == 0.0
    assert py["run"]["classification"] == "Lco"
    run_cli("branch", "--structure", S, "--model", lag, "--speeds", "3:6", "--out", tmp_path / "b")
    cli = json.loads((tmp_path / "b" / "branch.json").read_text())
    py = aeroform.branch(str(S), str(lag), "3:6")
    assert max_difference(cli["hopf_points"], py["hopf_points"]) == 0.0
    assert py["branches"][0]["criticality"] == "supercritical"


def test_diagnose_branch_makes_the_commands_input_choices():
    """`aeroform.diagnose_branch` reads its inputs through the same library request as
    `aeroform diagnose --measured-branch` (diagnose::bifurcation::inputs): the same
    refusals, naming what is missing or wrong, before any fit runs."""
    # a table carries no [structure]: one must be given
    with pytest.raises(aeroform.AeroformError, match="no structure"):
        aeroform.diagnose_branch(BMEAS, BM)
    with pytest.raises(aeroform.AeroformError, match="--onset"):
        aeroform.diagnose_branch(BMEAS, BM, structure=BS, onsets=["fast"])
    with pytest.raises(aeroform.AeroformError, match="--no-lco"):
        aeroform.diagnose_branch(BMEAS, BM, structure=BS, no_lco=["-3"])


def test_branch_in_a_parameter_equals_the_cli(tmp_path):
    run_cli("branch", "--structure", BS, "--model", BM, "--speeds", "12:20",
            "--parameter", "pitch_stiffness[3]", "--parameter-range", "0:10000",
            "--at-speed", "16", "--out", tmp_path)
    cli = json.loads((tmp_path / "branch.json").read_text())
    py = aeroform.branch(str(BS), str(BM), (12.0, 20.0), parameter="pitch_stiffness[3]",
                         parameter_range=(0.0, 10000.0), at_speed=16.0)
    assert max_difference(cli, py) == 0.0
    p = py["parameter"]
    assert p["start_value"] == 5007.38
    assert sum(e["kind"] == "fold" for e in p["events"]) == 2
    with pytest.raises(aeroform.AeroformError, match="all three"):
        aeroform.branch(str(BS), str(BM), (12.0, 20.0), parameter="k_alpha")
    with pytest.raises(aeroform.AeroformError, match="parameter"):
        aeroform.branch(str(BS), str(BM), (12.0, 20.0), parameter="k_beta",
                        parameter_range=(0.0, 1.0), at_speed=16.0)
