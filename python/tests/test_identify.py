"""`aeroform.identify` equals `aeroform identify` (identification.json) to 1e-12."""

import json

import numpy as np
import pytest

import aeroform
from conftest import max_difference, run_cli


def test_identify_equals_the_cli_identification_json(forced_dataset, cli_identification):
    ident = aeroform.identify(aeroform.read_dataset(forced_dataset))
    d = max_difference(cli_identification, dict(ident))
    print(f"largest relative difference to the CLI: {d:.3e}")
    assert d <= 1e-12
    assert len(ident["cases"]) == len(cli_identification["cases"]) > 0


def test_settings_have_the_cli_meaning(forced_dataset, tmp_path):
    run_cli("identify", forced_dataset, "--out", tmp_path, "--quiet",
            "--group-by", "none", "--regressor", "lsq", "--library", "full34")
    cli = json.loads((tmp_path / "identification.json").read_text())
    ident = aeroform.identify(forced_dataset, group_by="none", regressor="lsq", library="full34")
    assert max_difference(cli, dict(ident)) <= 1e-12
    assert ident["settings"]["group_by"] == "none"


def test_regressors_come_from_the_registry_and_take_their_options(forced_dataset, tmp_path):
    regs = {r["name"]: r for r in aeroform.regressors()}
    assert {"stlsq", "pysindy", "least_squares"} <= regs.keys()
    assert "lsq" in regs["least_squares"]["aliases"]
    alpha = [o for o in regs["pysindy"]["options"] if o["name"] == "alpha"][0]
    assert alpha["type"] == "number" and alpha["default"] == 0.05
    run_cli("identify", forced_dataset, "--out", tmp_path, "--quiet", "--group-by", "none",
            "--regressor", "pysindy", "--regressor-option", "alpha=0.1")
    cli = json.loads((tmp_path / "identification.json").read_text())
    assert cli["settings"]["regressor"] == {"kind": "pysindy", "alpha": 0.1, "max_iter": 20, "unbias": True}
    ident = aeroform.identify(forced_dataset, group_by="none", regressor="pysindy",
                              regressor_options={"alpha": 0.1})
    assert max_difference(cli, dict(ident)) <= 1e-12
    with pytest.raises(aeroform.AeroformError, match="pysindy.alpha"):
        aeroform.identify(forced_dataset, regressor="pysindy", regressor_options={"alpha": -1})
    with pytest.raises(aeroform.AeroformError, match="stlsq.alpha"):
        aeroform.identify(forced_dataset, regressor_options={"alpha": 0.1})


def test_unknown_setting_and_bad_values_raise_naming_them(forced_dataset):
    with pytest.raises(aeroform.AeroformError, match="n_delt"):
        aeroform.identify(forced_dataset, n_delt=10)
    with pytest.raises(aeroform.AeroformError, match="velocity"):
        aeroform.identify(forced_dataset, velocity="spline")
    with pytest.raises(aeroform.AeroformError, match="regressor"):
        aeroform.identify(forced_dataset, regressor="lasso")


def test_frames_arrays_and_pysindy_export(forced_dataset):
    ident = aeroform.identify(forced_dataset)
    terms, a = ident.coefficients("moment")
    assert a.shape == (len(ident["cases"]), len(terms))
    case0 = ident["cases"][0]
    for j, t in enumerate(terms):
        v = case0["moment"]["terms"].get(t, 0.0)
        assert (np.isnan(a[0, j]) and v is None) or a[0, j] == v
    df = ident.to_frame("moment")
    assert list(df["id"]) == ident.case_ids()
    assert df["A2"].tolist() == [c["moment"]["eq19"]["A2"] for c in ident["cases"]]
    ps = ident.to_pysindy("moment")
    assert ps["coefficients"].shape == (len(ps["targets"]), len(ps["feature_names"]))
    assert "alpha^3" in ps["feature_names"]
    assert all("*" not in f for f in ps["feature_names"])
