"""Type stubs of the extension module `aeroform._core` (Rust, PyO3)."""

from typing import Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

class AeroformError(ValueError):
    """Bad input (the message names the file, line, field or term) or a computation that
    cannot proceed."""

class Dataset:
    """A data set in memory: manifest and records in SI per unit span."""
    @property
    def name(self) -> str: ...
    @property
    def root(self) -> str: ...
    def case_ids(self) -> List[str]: ...
    def manifest_toml(self) -> str: ...
    def cases_json(self) -> str: ...
    def columns(self, id: str) -> Dict[str, npt.NDArray[np.float64]]: ...
    def write(self, dir: str) -> None: ...

def read_dataset(path: str) -> Dataset: ...
def regressors() -> str: ...
def dataset_from_columns(
    manifest_toml: str,
    ids: List[str],
    t: List[npt.NDArray[np.float64]],
    h: List[npt.NDArray[np.float64]],
    alpha: List[npt.NDArray[np.float64]],
    lift: List[Optional[npt.NDArray[np.float64]]],
    moment: List[Optional[npt.NDArray[np.float64]]],
) -> Dataset: ...
def identify(
    dataset: Dataset,
    settings_json: str,
    velocity: str,
    subtract_nowind: bool,
    ensemble: Optional[int] = None,
    seed: int = 2024,
    level: float = 0.9,
) -> str: ...
def flutter(
    structure: str,
    model: str,
    speeds: List[float],
    method: str = "pk",
    chord: Optional[float] = None,
    ensemble: Optional[int] = None,
) -> str: ...
def lco(
    structure: str,
    model: str,
    speed: Optional[float] = None,
    sweep: Optional[List[float]] = None,
    alpha0: float = 2.0,
    alpha0_down: float = 20.0,
    chord: Optional[float] = None,
) -> str: ...
def branch(
    structure: str,
    model: str,
    u_min: float,
    u_max: float,
    measured: Optional[str] = None,
    max_points: int = 200,
    steps_per_period: int = 128,
    chord: Optional[float] = None,
) -> Tuple[str, str]: ...
def diagnose(forced: Dataset, free: Optional[Dataset] = None, seed: int = 1) -> str: ...
def diagnose_branch(
    measured: str,
    model: str,
    structure: Optional[str] = None,
    free: List[str] = ...,
    onsets: List[str] = ...,
    no_lco: List[str] = ...,
) -> str: ...
def limits() -> List[Tuple[str, float, str, str]]: ...
def sweep_n_items(spec_json: str) -> int: ...
def sweep_run_items(spec_json: str, indices: List[int]) -> str: ...
def sweep_assemble(spec_json: str, items_json: List[str]) -> str: ...
def sweep_local(spec_json: str) -> str: ...
