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


# The entry points whose whole signature the README's API list writes out.
DOCUMENTED = ("read_log", "list_topics", "fit", "prepare", "observe", "excite",
              "evaluate_trajectory", "JointLog", "JointLog.from_dataframe",
              "FourierTrajectory", "identify_payload", "external_torque",
              "MomentumObserver")


def test_readme_signatures_match_the_module():
    """The API list gives every parameter of these entry points, in the module's order,
    with its default: a keyword the module adds shows up here before a user misses it."""
    import inspect
    import re

    import dvrk_ident as di

    if not README.exists():
        pytest.skip(f"{README} not found (installed without the sources)")
    text = " ".join(README.read_text().split())
    for name in DOCUMENTED:
        obj = di
        for part in name.split("."):
            obj = getattr(obj, part)
        written = re.search(r"`" + re.escape(name) + r"(\([^`]*\))`", text)
        assert written, f"{name}: no `{name}(...)` in the README"
        params = [p for p in inspect.signature(obj).parameters.values() if p.name != "self"]
        # The excitation options (`dvrk_ident._excite_options`) are written with the
        # library's defaults, also those the signature takes positionally as None.
        excite = di._excite_options.get(name, {})

        def shown(key, default):
            if isinstance(default, float) and default.is_integer():
                default = int(default)
            return f"{key}={default!r}".replace("'", '"')

        expected = []
        for p in params:
            if p.kind == p.VAR_KEYWORD and p.name == "options":
                given = {q.name for q in params}
                if excite:
                    expected += [shown(n, d) for n, d in excite.items() if n not in given]
                else:
                    # The fit options (`dvrk_ident._options`), each None unless given.
                    expected += [f"{n}=None" for n in di._options[name] if n not in given]
                continue
            if p.kind == p.KEYWORD_ONLY and "*" not in expected:
                expected.append("*")
            if p.default is p.empty:
                expected.append(p.name)
            else:
                expected.append(shown(p.name, excite.get(p.name, p.default)))
        assert written.group(1) == "(" + ", ".join(expected) + ")", name
