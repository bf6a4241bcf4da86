"""The README's Python example and the scripts in examples/ run as written."""

from __future__ import annotations

import re
import runpy
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_examples_run(tmp_path, monkeypatch, capsys):
    text = (ROOT / "README.md").read_text()
    blocks = [b.split("```", 1)[0] for b in text.split("```python")[1:]]
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    first = {}
    exec(compile(blocks[0], "README.md", "exec"), first)
    assert (tmp_path / "F2.csv").exists()
    assert capsys.readouterr().out.strip()
    second = {}
    exec(compile(blocks[1], "README.md", "exec"), second)
    assert second["sol"].ok and second["sol"].x["mass"].shape == (5001,)


@pytest.mark.parametrize("script", ["paper_quickstart.py"])
def test_example_script_runs(script, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [script])
    runpy.run_path(str(ROOT / "examples" / script), run_name="__main__")
    assert capsys.readouterr().out.strip()


def test_sweep_study_runs_small(tmp_path, monkeypatch, capsys):
    pytest.importorskip("matplotlib")
    monkeypatch.setattr(sys, "argv", ["sweep_study.py", "--small", "--out", str(tmp_path)])
    runpy.run_path(str(ROOT / "examples" / "sweep_study.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "120 scenes" in out and "all ran to the end: True" in out
    # eq. (19): below the yield force the mass never moves
    assert re.search(r"stick time 5 s in (\d+) of \1 scenes", out)
    assert "within the stick band |x| <= tau/k = 0.01: True" in out
    assert (tmp_path / "sweep_study.png").read_bytes()[:4] == b"\x89PNG"


def _python_blocks(text: str) -> list[str]:
    """The ```python blocks of a Markdown page (indented ones included), dedented."""
    import re
    import textwrap

    return [textwrap.dedent(m.group(2)) for m in
            re.finditer(r"^([ \t]*)```python\n(.*?)^\1```", text, re.M | re.S)]


@pytest.mark.parametrize("page", sorted(p.name for p in (ROOT / "docs").glob("*.md")
                                         if "```python" in p.read_text()))
def test_docs_python_examples_run(page, tmp_path, monkeypatch):
    """Every Python example of the documentation pages runs as written (in page order,
    one namespace per page)."""
    blocks = _python_blocks((ROOT / "docs" / page).read_text())
    assert blocks
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for i, block in enumerate(blocks):
        exec(compile(block, f"docs/{page} block {i + 1}", "exec"), namespace)
