"""Runs the walk-through of docs/PYTHON.md: every ```python block, in order, in one
namespace, in a scratch folder holding a link to the repository's scenarios/. Blocks
fenced ```py are examples that are not executed (the Dask cluster of 1000 benchmark sets;
python/tests/test_sweep.py runs the cluster)."""

import os
import re
from pathlib import Path

from conftest import ROOT, cli_binary


def test_python_md_walkthrough_runs(tmp_path, monkeypatch):
    text = (ROOT / "docs" / "PYTHON.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 4
    (tmp_path / "scenarios").symlink_to(ROOT / "scenarios")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", f"{cli_binary().parent}{os.pathsep}{os.environ['PATH']}")
    ns: dict = {}
    for i, code in enumerate(blocks):
        exec(compile(code, f"docs/PYTHON.md block {i + 1}", "exec"), ns)
