"""Large jobs on Dask (``dask.distributed``): the withheld-effect benchmark and
flutter/LCO maps over structural parameters, split into tasks of the Rust core.

A sweep is a specification (a dict, the JSON of ``diagnose::sweep::SweepSpec``)::

    {"kind": "blind", "n": 1000, "seed": 1}
    {"kind": "flutter_map", "structure": "s.toml", "model": "m.toml",
     "speeds": [1, 2, ..., 40], "grid": {"mu": [...], "sigma": [...],
     "x_alpha": [...], "r2": [...]}, "lco_speeds": [...]}

Every item depends only on the specification and its global index (a benchmark set's
seed comes from the master seed and the index), so the gathered document is the one
:func:`sweep_local` computes in one process, whatever the split, the order of completion
or the workers lost on the way (Dask reruns a lost task; the rerun gives the same item).
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional

from . import _core


def _spec_json(spec: Mapping[str, Any]) -> str:
    s = dict(spec)
    # Workers may start in another folder: resolve file paths here.
    for key in ("structure", "model"):
        if key in s and isinstance(s[key], (str, os.PathLike)):
            s[key] = os.path.abspath(os.fspath(s[key]))
    text = json.dumps(s)
    _core.sweep_n_items(text)  # validates; raises AeroformError naming the field
    return text


def _run_chunk(spec_json: str, indices: List[int]) -> str:
    """One Dask task: the items ``indices`` as a JSON array (runs on a worker)."""
    return _core.sweep_run_items(spec_json, indices)


def sweep_local(spec: Mapping[str, Any]) -> Dict[str, Any]:
    """The whole sweep in this process (rayon over the items): the reference document."""
    return json.loads(_core.sweep_local(_spec_json(spec)))


def sweep(
    spec: Mapping[str, Any],
    client: Optional[Any] = None,
    *,
    chunk_size: Optional[int] = None,
    retries: int = 3,
) -> Dict[str, Any]:
    """Runs a sweep on a Dask ``client`` (``dask.distributed.Client``) and gathers one
    document equal to :func:`sweep_local` (``client=None`` runs it locally).

    The items are split into chunks of ``chunk_size`` consecutive indices (default: about
    four tasks per worker thread), one task each; ``retries`` reruns a task whose
    computation raised. A task on a worker that dies is rescheduled by the scheduler
    (up to its ``distributed.scheduler.allowed-failures``)."""
    text = _spec_json(spec)
    if client is None:
        return json.loads(_core.sweep_local(text))
    n = _core.sweep_n_items(text)
    if chunk_size is None:
        threads = sum(client.nthreads().values()) or 1
        chunk_size = max(1, -(-n // (4 * threads)))
    if chunk_size < 1:
        raise _core.AeroformError(f"chunk_size = {chunk_size}: must be >= 1")
    chunks = [list(range(i, min(i + chunk_size, n))) for i in range(0, n, chunk_size)]
    futures = client.map(
        _run_chunk,
        [text] * len(chunks),
        chunks,
        retries=retries,
        pure=False,
    )
    parts = client.gather(futures)
    return json.loads(_core.sweep_assemble(text, list(parts)))
