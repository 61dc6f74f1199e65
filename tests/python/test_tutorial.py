"""Runs the tutorial of crates/dvrk-py/README.md: its ```python blocks in order, in one
namespace, in a temporary directory."""

import os
from pathlib import Path

import pytest

from conftest import REPO, SHARED

README = REPO / "crates" / "dvrk-py" / "README.md"


def python_blocks(text):
    blocks, current = [], None
    for line in text.splitlines():
        if current is None and line.strip() == "```python":
            current = []
        elif current is not None and line.strip() == "```":
            blocks.append("\n".join(current))
            current = None
        elif current is not None:
            current.append(line)
    return blocks


def test_tutorial(tmp_path, monkeypatch, capsys):
    if not README.exists():
        pytest.skip(f"{README} not found (installed without the sources)")
    blocks = python_blocks(README.read_text())
    assert len(blocks) >= 6
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("DVRK_DATA", str(SHARED / "data" / "dvrk"))
    namespace = {"__name__": "tutorial"}
    for k, block in enumerate(blocks):
        code = compile(block, f"{README}:block{k + 1}", "exec")
        exec(code, namespace)
    out = capsys.readouterr().out
    assert "7 115" in out
    assert Path("psm_ols.json").exists() and Path("excitation.mcap").exists()
    if (SHARED / "data" / "dvrk" / "psm" / "one_results.csv").exists():
        assert "[0.1027 0.1839 0.1983 0.1344 0.2402 0.2119 0.2638]" in out
