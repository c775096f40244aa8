"""aeroform from Python: identification of nonlinear aerodynamic force laws, flutter, limit
cycles and sim-to-real diagnosis on the Rust core (the same code as the ``aeroform``
command line, same results).

Every function returns the content of the document the command line writes
(``identification.json``, ``flutter.json``, ``lco.json``, ``diagnosis.json``) as Python
dicts, with numpy/pandas accessors on top. Bad input raises :class:`AeroformError` (a
``ValueError``) whose message names the file, line, field or term. Long computations
release the GIL. See docs/PYTHON.md.
"""

from __future__ import annotations

import json
import os
import tempfile
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import AeroformError
from .sweep import sweep, sweep_local

__version__: str = _core.__version__

__all__ = [
    "AeroformError",
    "Dataset",
    "Identification",
    "read_dataset",
    "identify",
    "flutter",
    "lco",
    "branch",
    "Branch",
    "diagnose",
    "diagnose_branch",
    "sweep",
    "sweep_local",
    "parse_speeds",
    "limits",
    "regressors",
]

PathLike = Union[str, "os.PathLike[str]"]

_SI_UNITS = {"heave": "m", "pitch": "rad", "lift": "N/m", "moment": "N*m/m"}
_CASE_META = (
    "config",
    "amplitude",
    "amplitude_ratio",
    "freq_pitch",
    "freq_heave",
    "mean_pitch",
)
_COLUMNS = ("t", "h", "alpha", "lift", "moment")


def _toml_value(v: Any, where: str) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float, np.integer, np.floating)):
        return repr(float(v))
    if isinstance(v, str):
        return json.dumps(v)
    raise AeroformError(f"{where}: unsupported value {v!r} (numbers, strings, booleans)")


def _toml_table(name: str, table: Mapping[str, Any]) -> str:
    lines = [f"[{name}]"]
    for k, v in table.items():
        lines.append(f"{json.dumps(str(k))} = {_toml_value(v, f'{name}.{k}')}")
    return "\n".join(lines) + "\n"


class Dataset:
    """A data set (docs/DATA_FORMAT.md) in memory: manifest plus one record per case, in SI
    per unit span (h [m], alpha [rad], lift [N/m], moment [N·m/m])."""

    def __init__(self, inner: "_core.Dataset") -> None:
        self._inner = inner

    @classmethod
    def from_arrays(
        cls,
        cases: Sequence[Mapping[str, Any]],
        *,
        name: str,
        chord: float,
        span: float = 1.0,
        air_density: float = 1.225,
        units: Optional[Mapping[str, str]] = None,
        structure: Optional[Mapping[str, float]] = None,
        description: Optional[str] = None,
    ) -> "Dataset":
        """Builds a data set from numpy arrays (or pandas DataFrames).

        Each case is a mapping with ``id``, ``wind_speed`` [m/s], optional ``kind``
        (``"forced"`` default or ``"free"``), optional per-case metadata (``config``,
        ``amplitude``, ``amplitude_ratio``, ``freq_pitch``, ``freq_heave``,
        ``mean_pitch``, ``extra``) and the columns ``t``, ``h``, ``alpha``, ``lift``,
        ``moment`` either as arrays or as a DataFrame under ``frame`` with those column
        names. ``units`` gives the columns' units as in the manifest's ``[units]`` (default
        SI per unit span: m, rad, N/m, N*m/m). The manifest and every column are validated
        as the folder reader validates them (uniform sampling, finite values, units…).
        """
        u = dict(_SI_UNITS)
        if units is not None:
            unknown = set(units) - set(u)
            if unknown:
                raise AeroformError(
                    f"units: unknown key(s) {sorted(unknown)}; expected heave, pitch, lift, moment"
                )
            u.update(units)
        text = 'format = "aeroform-dataset/1"\n'
        text += f"name = {json.dumps(name)}\n"
        if description is not None:
            text += f"description = {json.dumps(description)}\n"
        text += _toml_table(
            "section", {"chord": chord, "span": span, "air_density": air_density}
        )
        if structure is not None:
            text += _toml_table("structure", structure)
        text += _toml_table("units", u)
        ids: List[str] = []
        cols: Dict[str, List[Any]] = {c: [] for c in _COLUMNS}
        for i, case in enumerate(cases):
            where = f"cases[{i}]"
            if "id" not in case or "wind_speed" not in case:
                raise AeroformError(f"{where}: `id` and `wind_speed` are required")
            cid = str(case["id"])
            ids.append(cid)
            text += "[[case]]\n"
            text += f"id = {json.dumps(cid)}\n"
            text += f"kind = {json.dumps(str(case.get('kind', 'forced')))}\n"
            text += f"file = {json.dumps(cid + '.csv')}\n"
            text += f"wind_speed = {_toml_value(case['wind_speed'], where + '.wind_speed')}\n"
            for k in _CASE_META:
                if case.get(k) is not None:
                    text += f"{k} = {_toml_value(case[k], f'{where}.{k}')}\n"
            known = set(_CASE_META) | set(_COLUMNS) | {"id", "kind", "wind_speed", "frame", "extra"}
            unknown = set(case) - known
            if unknown:
                raise AeroformError(f"{where} (`{cid}`): unknown key(s) {sorted(unknown)}")
            frame = case.get("frame")
            for c in _COLUMNS:
                if frame is not None:
                    v = frame[c] if c in frame.columns else None
                else:
                    v = case.get(c)
                if v is None:
                    if c in ("lift", "moment"):
                        cols[c].append(None)
                        continue
                    raise AeroformError(f"{where} (`{cid}`): column `{c}` is missing")
                a = np.ascontiguousarray(np.asarray(v, dtype=np.float64))
                if a.ndim != 1:
                    raise AeroformError(
                        f"{where} (`{cid}`): column `{c}` must be one-dimensional, has shape {a.shape}"
                    )
                cols[c].append(a)
            if case.get("extra") is not None:
                text += _toml_table("case.extra", case["extra"])
        inner = _core.dataset_from_columns(
            text, ids, cols["t"], cols["h"], cols["alpha"], cols["lift"], cols["moment"]
        )
        return cls(inner)

    @property
    def name(self) -> str:
        """The manifest's name."""
        return self._inner.name

    @property
    def case_ids(self) -> List[str]:
        """Case ids in manifest order."""
        return self._inner.case_ids()

    @property
    def cases(self) -> List[Dict[str, Any]]:
        """Per-case metadata (id, kind, wind_speed, config, amplitude…, samples, dt)."""
        return json.loads(self._inner.cases_json())

    @property
    def manifest_toml(self) -> str:
        """The manifest as TOML text."""
        return self._inner.manifest_toml()

    def columns(self, case_id: str) -> Dict[str, np.ndarray]:
        """Columns of one case in SI per unit span: t, h, alpha, lift, moment."""
        return self._inner.columns(case_id)

    def to_frame(self, case_id: str) -> Any:
        """One case as a pandas DataFrame (SI per unit span)."""
        import pandas as pd

        return pd.DataFrame(self.columns(case_id))

    def write(self, path: PathLike) -> None:
        """Writes the data set as a folder (manifest.toml + CSV in the manifest's units)."""
        self._inner.write(os.fspath(path))

    def __repr__(self) -> str:
        return f"Dataset({self.name!r}, {len(self.case_ids)} cases)"


def limits() -> Dict[str, Dict[str, Any]]:
    """The limits table (docs/DATA_FORMAT.md, "Limits"): for each entry (``MAX_SPEED``, …)
    its bound ``max`` (largest allowed value, of |x| for signed quantities), ``unit`` and
    where a user sets it (``set_by``). Every argument of this package is checked against
    it and an :class:`AeroformError` names the argument."""
    return {
        name: {"max": mx, "unit": unit, "set_by": set_by}
        for name, mx, unit, set_by in _core.limits()
    }


def regressors() -> List[Dict[str, Any]]:
    """The registered regressors (``regress::plugins``, the list ``aeroform identify --help``
    shows): per regressor its ``name``, ``aliases``, ``doc``, ``path_parameter`` (``name``,
    ``unit``) and ``options`` (``name``, ``type``, ``default``, ``min``, ``max``, ``doc``): the
    keys :func:`identify` accepts in ``regressor_options``."""
    return json.loads(_core.regressors())


def read_dataset(path: PathLike) -> Dataset:
    """Reads a data-set folder (manifest.toml + case CSV files, docs/DATA_FORMAT.md)."""
    return Dataset(_core.read_dataset(os.fspath(path)))


def _as_dataset(d: Union[Dataset, PathLike]) -> Dataset:
    return d if isinstance(d, Dataset) else read_dataset(d)


class Identification(dict):  # type: ignore[type-arg]
    """The ``identification.json`` document (a dict) with numpy/pandas accessors."""

    def case_ids(self) -> List[str]:
        """Identified case ids, in document order."""
        return [c["id"] for c in self["cases"]]

    def coefficients(self, channel: str = "moment") -> Tuple[List[str], np.ndarray]:
        """(term names, array n_cases × n_terms) of the library-term coefficients of
        ``channel`` (``moment`` or ``lift``); a term not in a case's fit is 0, a
        coefficient that is not identifiable (null) is NaN."""
        _check_channel(channel)
        terms: List[str] = list(self["library"]["terms"])
        for c in self["cases"]:
            for t in c[channel]["terms"]:
                if t not in terms:
                    terms.append(t)
        a = np.zeros((len(self["cases"]), len(terms)))
        for i, c in enumerate(self["cases"]):
            for t, v in c[channel]["terms"].items():
                a[i, terms.index(t)] = np.nan if v is None else v
        return terms, a

    def to_frame(self, channel: Optional[str] = None) -> Any:
        """A pandas DataFrame, one row per case and channel: id, channel, wind_speed,
        k_alpha, k_h, every term coefficient, the Eq. 19 derivatives (A1..A4 / H1..H4,
        N1..N3) and the metrics (r2, mfwa, key_frequency_loss)."""
        import pandas as pd

        rows = []
        for ch in [channel] if channel else ["lift", "moment"]:
            _check_channel(ch)
            for c in self["cases"]:
                f = c[ch]
                row: Dict[str, Any] = {
                    "id": c["id"],
                    "channel": ch,
                    "wind_speed": c.get("wind_speed"),
                    "k_alpha": c.get("k_alpha"),
                    "k_h": c.get("k_h"),
                }
                for t, v in f.get("terms", {}).items():
                    row[t] = np.nan if v is None else v
                for t, v in (f.get("eq19") or {}).items():
                    row[t] = np.nan if v is None else v
                for m in ("r2", "mfwa", "key_frequency_loss"):
                    if m in f:
                        row[m] = f[m]
                rows.append(row)
        return pd.DataFrame(rows)

    def to_pysindy(self, channel: str = "moment") -> Dict[str, Any]:
        """Coefficients in pysindy's layout: ``feature_names`` as
        ``SINDy.get_feature_names()`` spells them for inputs named ``alpha, alpha_dot, h,
        h_dot`` (products separated by spaces, e.g. ``alpha^2 h``), ``coefficients`` an
        array n_cases × n_features as ``SINDy.coefficients()`` (one row per target = case)
        and ``targets`` the case ids."""
        terms, a = self.coefficients(channel)
        return {
            "input_features": ["alpha", "alpha_dot", "h", "h_dot"],
            "feature_names": [t.replace("*", " ") for t in terms],
            "coefficients": a,
            "targets": self.case_ids(),
        }

    def write(self, path: PathLike) -> None:
        """Writes the document as JSON (a model file for :func:`flutter` and the CLI)."""
        with open(path, "w", encoding="utf-8") as f:
            json.dump(self, f, indent=2)
            f.write("\n")


def _check_channel(ch: str) -> None:
    if ch not in ("lift", "moment"):
        raise AeroformError(f"channel `{ch}`: expected `lift` or `moment`")


def identify(
    dataset: Union[Dataset, PathLike],
    *,
    velocity: str = "auto",
    subtract_nowind: bool = True,
    regressor_options: Optional[Mapping[str, Any]] = None,
    pysindy_alpha: Optional[float] = None,
    pysindy_unbias: Optional[bool] = None,
    ensemble: Optional[int] = None,
    seed: int = 2024,
    level: float = 0.9,
    **settings: Any,
) -> Identification:
    """Identification of a data set, as ``aeroform identify``: returns the content of
    ``identification.json``.

    ``settings`` are the fields of the identification settings (the ``settings`` object
    of identification.json): ``library`` (``paper30``/``full34``), ``basis``
    (``canonical``/``full``), ``measure`` (``contribution``/``coefficient``),
    ``group_rule`` (``norm``/``all``/``any``/``mean``), ``group_by`` (``config``/
    ``wind_speed``/``amplitude``/``none``), ``ridge``, ``n_delta``, ``k_key``,
    ``kept_terms``, … and ``regressor``: the name of a registered regressor (see
    :func:`regressors`: ``stlsq``, ``pysindy``, ``least_squares`` alias ``lsq``) or the
    settings' dict form (``{"kind": name, option: value, …}``). ``regressor_options`` are
    the chosen regressor's options (``{"alpha": 0.1}`` for ``pysindy``);
    ``pysindy_alpha``/``pysindy_unbias`` are the deprecated spellings of its ``alpha`` and
    ``unbias``. An unknown name raises :class:`AeroformError` naming it.

    ``ensemble=N`` adds a block-bootstrap ensemble of N members (``seed``, interval
    ``level``), as ``aeroform identify --ensemble N --seed S --level L``: the ``ensemble``
    section with intervals of every coefficient and derivative, which
    ``flutter(..., ensemble=N)`` propagates to the flutter and divergence speeds.
    """
    ds = _as_dataset(dataset)
    reg = settings.get("regressor", "stlsq")
    opts: Dict[str, Any] = dict(regressor_options or {})
    if pysindy_alpha is not None:
        opts.setdefault("alpha", pysindy_alpha)
    if pysindy_unbias is not None:
        opts.setdefault("unbias", pysindy_unbias)
    if isinstance(reg, str):
        settings["regressor"] = {"kind": reg, **opts}
    elif isinstance(reg, Mapping):
        settings["regressor"] = {**reg, **opts}
    else:
        raise AeroformError(f"regressor `{reg!r}`: expected a name or a dict")
    text = _core.identify(
        ds._inner, json.dumps(settings), velocity, subtract_nowind, ensemble, seed, level
    )
    return Identification(json.loads(text))


def parse_speeds(speeds: Union[str, Iterable[float]]) -> List[float]:
    """``"a:b:n"`` (n speeds from a to b, as the CLI), a comma list, or numbers."""
    if isinstance(speeds, str):
        s = speeds.strip()
        try:
            if ":" in s:
                a, b, n = s.split(":")
                lo, hi, k = float(a), float(b), int(n)
                if k < 1:
                    raise ValueError
                cap = int(limits()["MAX_SPEEDS"]["max"])
                if k > cap:
                    raise AeroformError(
                        f"speeds `{speeds}`: {k} speeds, at most {cap} (MAX_SPEEDS)"
                    )
                if k == 1:
                    return [lo]
                return [lo + (hi - lo) * i / (k - 1) for i in range(k)]
            return [float(x) for x in s.split(",")]
        except ValueError:
            raise AeroformError(
                f"speeds `{speeds}`: expected `a:b:n` or a comma list like `3,4,5`"
            ) from None
    return [float(u) for u in np.asarray(list(speeds), dtype=np.float64).ravel()]


class _Files:
    """Structure/model given as paths, dicts or an Identification: temporary files for
    the core, which reads files."""

    def __init__(self, structure: Any, model: Any) -> None:
        self._dir: Optional[tempfile.TemporaryDirectory] = None  # type: ignore[type-arg]
        self.structure = self._file(structure, "structure.toml")
        self.model = self._file(model, "model.json")

    def _file(self, x: Any, name: str) -> str:
        if isinstance(x, (str, os.PathLike)):
            return os.fspath(x)
        if isinstance(x, Mapping):
            if self._dir is None:
                self._dir = tempfile.TemporaryDirectory(prefix="aeroform-")
            path = os.path.join(self._dir.name, name)
            with open(path, "w", encoding="utf-8") as f:
                if name.endswith(".json"):
                    json.dump(x, f)
                else:
                    f.write(_toml_body(x, "structure"))
            return path
        raise AeroformError(f"{name}: expected a path or a dict, got {type(x).__name__}")

    def __enter__(self) -> "_Files":
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._dir is not None:
            self._dir.cleanup()


def _toml_body(d: Mapping[str, Any], where: str) -> str:
    lines = []
    for k, v in d.items():
        if isinstance(v, Mapping) or (isinstance(v, (list, tuple)) and v and isinstance(v[0], Mapping)):
            raise AeroformError(
                f"{where}.{k}: tables are not supported in a structure dict; give a TOML file"
            )
        lines.append(f"{k} = {_toml_value(v, f'{where}.{k}')}")
    return "\n".join(lines) + "\n"


def flutter(
    structure: Any,
    model: Any,
    speeds: Union[str, Iterable[float]] = "1:20:96",
    *,
    method: str = "pk",
    chord: Optional[float] = None,
    ensemble: Optional[int] = None,
) -> Dict[str, Any]:
    """Flutter and divergence, as ``aeroform flutter``: returns the content of
    ``flutter.json`` (``critical`` is the flutter point or None). ``ensemble=N``: the
    same analysis for the first N members of the model's ensemble (an identification
    made with ``ensemble=``), intervals under ``ensemble``, as ``--ensemble N``.

    ``structure``: a structure TOML file or a dict of its scalar keys; ``model``: a model
    TOML file, an identification.json, or an :class:`Identification`; ``speeds``: the scan
    (``"a:b:n"`` or numbers, at least 2)."""
    u = parse_speeds(speeds)
    with _Files(structure, model) as f:
        return json.loads(_core.flutter(f.structure, f.model, u, method, chord, ensemble))


def lco(
    structure: Any,
    model: Any,
    *,
    speed: Optional[float] = None,
    sweep: Union[str, Iterable[float], None] = None,
    alpha0: float = 2.0,
    alpha0_down: float = 20.0,
    chord: Optional[float] = None,
) -> Dict[str, Any]:
    """Limit cycles, as ``aeroform lco``: one run at ``speed`` [m/s], or upward and
    downward sweeps over ``sweep`` (initial pitch ``alpha0`` / ``alpha0_down`` [deg]).
    Returns the content of ``lco.json``."""
    sw = None if sweep is None else parse_speeds(sweep)
    with _Files(structure, model) as f:
        return json.loads(
            _core.lco(f.structure, f.model, speed, sw, alpha0, alpha0_down, chord)
        )


class Branch(dict):  # type: ignore[type-arg]
    """The ``branch.json`` document (a dict) of :func:`branch`, with the ``branch.csv``
    table as :attr:`csv` and as numpy columns / a pandas DataFrame."""

    csv: str

    def columns(self) -> Dict[str, np.ndarray]:
        """The ``branch.csv`` columns as numpy arrays (``stable`` as bool): ``U_m_s``,
        ``stable``, ``amplitude_alpha_deg``, ``amplitude_h_m``, ``omega_rad_s``,
        ``max_floquet``, ``branch``, ``amplitude1_alpha_deg``, ``amplitude1_h_m``."""
        lines = self.csv.strip().splitlines()
        names = lines[0].split(",")
        rows = [line.split(",") for line in lines[1:]]
        out: Dict[str, np.ndarray] = {}
        for j, name in enumerate(names):
            col = [r[j] for r in rows]
            if name == "stable":
                out[name] = np.array([c == "true" for c in col], dtype=bool)
            elif name == "branch":
                out[name] = np.array([int(c) for c in col], dtype=np.int64)
            else:
                out[name] = np.array([float(c) for c in col], dtype=np.float64)
        return out

    def to_frame(self) -> Any:
        """The ``branch.csv`` table as a pandas DataFrame."""
        import pandas as pd

        return pd.DataFrame(self.columns())


def branch(
    structure: Any,
    model: Any,
    speeds: Union[str, Tuple[float, float]],
    *,
    measured: Optional[PathLike] = None,
    max_points: int = 200,
    steps_per_period: int = 128,
    chord: Optional[float] = None,
    method: str = "shooting",
    harmonics: int = 5,
    parameter: Optional[str] = None,
    parameter_range: Optional[Tuple[float, float]] = None,
    at_speed: Optional[float] = None,
) -> Branch:
    """LCO branches by continuation, as ``aeroform branch``: from every Hopf point of the
    linear flutter analysis in the speed range ``speeds`` (``"a:b"`` or ``(a, b)`` [m/s]),
    periodic orbits continued in U by pseudo-arclength (``method``: ``"shooting"`` or
    ``"harmonic_balance"`` with ``harmonics`` harmonics), stability by Floquet multipliers,
    folds marked. ``measured``: a CSV of measured amplitudes
    (columns ``branch, wind_speed_m_s, heave_amp_m, pitch_amp_rad``) compared with the
    branch of the same stability. With ``parameter`` (``"k_alpha"``,
    ``"pitch_stiffness[3]"``… as ``--parameter``), ``parameter_range = (a, b)`` and
    ``at_speed`` [m/s], the orbit at that speed is also continued in the parameter, at that
    fixed speed (``["parameter"]``, as ``branch.json``). Returns the content of
    ``branch.json`` as a :class:`Branch` (``.csv``, ``.columns()``, ``.to_frame()``)."""
    if isinstance(speeds, str):
        parts = speeds.split(":")
        try:
            if len(parts) != 2:
                raise ValueError
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise AeroformError(
                f"speeds `{speeds}`: expected `a:b` with 0 < a < b [m/s]"
            ) from None
    else:
        lo, hi = (float(x) for x in speeds)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
        raise AeroformError(f"speeds ({lo}, {hi}): expected 0 < a < b [m/s], finite")
    meas = None if measured is None else os.fspath(measured)
    with _Files(structure, model) as f:
        doc, csv = _core.branch(
            f.structure, f.model, lo, hi, meas, max_points, steps_per_period, chord,
            method, harmonics, parameter,
            None if parameter_range is None else tuple(float(x) for x in parameter_range),
            at_speed,
        )
    out = Branch(json.loads(doc))
    out.csv = csv
    return out


def diagnose(
    forced: Union[Dataset, PathLike],
    free: Union[Dataset, PathLike, None] = None,
    *,
    seed: int = 1,
) -> Dict[str, Any]:
    """Sim-to-real diagnosis, as ``aeroform diagnose``: returns the content of
    ``diagnosis.json`` (verdict, gap, where, candidates, levels)."""
    fr = None if free is None else _as_dataset(free)._inner
    return json.loads(_core.diagnose(_as_dataset(forced)._inner, fr, seed))


def diagnose_branch(
    measured: PathLike,
    model: PathLike,
    *,
    structure: Optional[PathLike] = None,
    free: Iterable[PathLike] = (),
    onsets: Iterable[str] = (),
    no_lco: Iterable[str] = (),
) -> Dict[str, Any]:
    """Bifurcation-level diagnosis, as ``aeroform diagnose --measured-branch``: the sim's
    bifurcation diagram (Hopf, folds, LCO branches) against a measured one, the catalogue's
    candidates fitted by continuation and scored by leave-one-speed-out. ``measured``: a
    CSV table of amplitudes (rows ``point``, ``onset``, ``none``; docs/DATA_FORMAT.md) or a
    data-set folder of records; ``model``: the sim's aerodynamic model file; ``structure``:
    a structure file, or ``None`` for the data sets' ``[structure]``; ``free``: further
    data sets (still-air decays); ``onsets`` / ``no_lco``: rows as the command's
    ``--onset U[:F][:sub|super][:sd=SD]`` and ``--no-lco U[:PITCH[:HEAVE]]``. The input
    choices are the library's, the same as the command's. Returns the content of
    ``bifurcation.json``."""
    st = None if structure is None else os.fspath(structure)
    return json.loads(
        _core.diagnose_branch(
            os.fspath(measured),
            os.fspath(model),
            st,
            [os.fspath(f) for f in free],
            [str(o) for o in onsets],
            [str(a) for a in no_lco],
        )
    )
