"""Data sets from folders and from arrays; bad input raises with the place named."""

import numpy as np
import pandas as pd
import pytest

import aeroform
from conftest import max_difference


def test_from_arrays_identifies_like_the_folder(forced_dataset):
    folder = aeroform.read_dataset(forced_dataset)
    # The still-air runs are subtracted by the folder path; give the arrays the
    # aerodynamic forces instead: identify without subtraction on both sides.
    cases = []
    for meta in folder.cases:
        cols = folder.columns(meta["id"])
        c = {"id": meta["id"], "wind_speed": meta["wind_speed"], "config": meta.get("config"),
             "freq_pitch": meta.get("freq_pitch"), "freq_heave": meta.get("freq_heave")}
        if c["id"] == folder.cases[0]["id"]:
            c["frame"] = pd.DataFrame(cols)  # DataFrames are accepted too
        else:
            c.update(cols)
        cases.append({k: v for k, v in c.items() if v is not None})
    arrays = aeroform.Dataset.from_arrays(cases, name=folder.name, chord=0.25, span=0.75)
    assert arrays.case_ids == folder.case_ids
    a = aeroform.identify(arrays, subtract_nowind=False)
    b = aeroform.identify(folder, subtract_nowind=False)
    d = max_difference(dict(b)["cases"], dict(a)["cases"])
    print(f"arrays vs folder: {d:.3e}")
    assert d <= 1e-9  # dt is re-estimated from t = t0 + i·dt (last-bit differences)


def _one_case(**over):
    t = np.arange(512) / 256.0
    c = {"id": "c1", "wind_speed": 8.0, "t": t, "h": 0.01 * np.sin(2 * np.pi * 1.3 * t),
         "alpha": 0.1 * np.sin(2 * np.pi * 2 * t), "lift": np.sin(t), "moment": np.cos(t)}
    c.update(over)
    return c


def test_bad_arrays_raise_naming_case_column_and_row():
    ok = aeroform.Dataset.from_arrays([_one_case()], name="x", chord=0.25)
    assert ok.columns("c1")["alpha"].shape == (512,)
    bad = _one_case()
    bad["moment"] = bad["moment"].copy()
    bad["moment"][7] = np.nan
    with pytest.raises(aeroform.AeroformError, match=r"c1.*moment.*row 7"):
        aeroform.Dataset.from_arrays([bad], name="x", chord=0.25)
    t = np.arange(512) / 256.0
    t[100] = t[99]
    with pytest.raises(aeroform.AeroformError, match=r"c1:100: field `t`"):
        aeroform.Dataset.from_arrays([_one_case(t=t)], name="x", chord=0.25)
    with pytest.raises(aeroform.AeroformError, match="heave"):
        aeroform.Dataset.from_arrays([_one_case()], name="x", chord=0.25, units={"heave": "km"})
    with pytest.raises(aeroform.AeroformError, match="chord"):
        aeroform.Dataset.from_arrays([_one_case()], name="x", chord=-1.0)
    with pytest.raises(aeroform.AeroformError, match="lift"):
        aeroform.Dataset.from_arrays([_one_case(lift=None)], name="x", chord=0.25)
    with pytest.raises(aeroform.AeroformError, match="shape"):
        aeroform.Dataset.from_arrays([_one_case(h=np.zeros((512, 2)))], name="x", chord=0.25)


def test_folder_errors_carry_the_readers_message(tmp_path):
    (tmp_path / "manifest.toml").write_text('format = "aeroform-dataset/2"\n')
    with pytest.raises(aeroform.AeroformError, match=r"manifest.toml.*format"):
        aeroform.read_dataset(tmp_path)
    with pytest.raises(aeroform.AeroformError, match="nowhere"):
        aeroform.read_dataset(tmp_path / "nowhere")


def test_write_and_read_back(tmp_path):
    ds = aeroform.Dataset.from_arrays([_one_case()], name="x", chord=0.25,
                                      units={"heave": "mm", "pitch": "deg"})
    ds.write(tmp_path / "out")
    back = aeroform.read_dataset(tmp_path / "out")
    assert back.case_ids == ["c1"]
    np.testing.assert_allclose(back.columns("c1")["alpha"], ds.columns("c1")["alpha"], rtol=1e-12)
