"""Every example in the documentation runs: the README's Python blocks, the Python blocks
of every page in docs/ and its sections (docs/theory/), the docstring examples of every
module (as doctests) and the scripts in examples/."""

from __future__ import annotations

import doctest
import importlib
import pkgutil
import re
import runpy
import sys
import textwrap
from pathlib import Path

import pytest

import lumped

ROOT = Path(__file__).resolve().parents[1]
_BLOCK = re.compile(r"^( *)```python[ \t]*\n(.*?)^\1```", re.MULTILINE | re.DOTALL)


def python_blocks(text: str) -> list[str]:
    """The ```python fenced blocks of a Markdown text (indented ones dedented)."""
    return [textwrap.dedent(m.group(2)) for m in _BLOCK.finditer(text)]


def _run_blocks(blocks: list[str], where: str) -> dict:
    namespace: dict = {"__name__": "__docs__"}
    for i, block in enumerate(blocks):
        exec(compile(block, f"{where} [python block {i + 1}]", "exec"), namespace)
    return namespace


@pytest.fixture
def quiet_plots(monkeypatch, tmp_path):
    """Run in a scratch directory, with matplotlib (if any) drawing off screen."""
    monkeypatch.chdir(tmp_path)
    try:
        import matplotlib
    except ImportError:
        yield tmp_path
        return
    matplotlib.use("Agg")
    yield tmp_path
    import matplotlib.pyplot as plt

    plt.close("all")


def test_readme_python_examples_run(quiet_plots, capsys):
    blocks = python_blocks((ROOT / "README.md").read_text())
    assert len(blocks) == 2
    first = _run_blocks(blocks[:1], "README.md")
    assert (quiet_plots / "F2.csv").exists()
    assert capsys.readouterr().out.strip()
    assert first["sol"].success and first["sol"].method == "closed-bdf1"
    second = _run_blocks(blocks[1:], "README.md")
    assert second["sol"].ok and second["sol"].x["mass"].shape == (5001,)


DOCS = ROOT / "docs"
# the pages of docs/ and of its sections (docs/theory/, ...), not the build output
ALL_PAGES = sorted(p for p in [*DOCS.glob("*.md"), *DOCS.glob("[!_]*/*.md")])
DOC_PAGES = [p for p in ALL_PAGES if python_blocks(p.read_text())]


def _page_id(page: Path) -> str:
    return page.relative_to(DOCS).as_posix()


def test_the_pages_with_examples_are_found():
    assert "theory/index.md" in {_page_id(p) for p in ALL_PAGES}
    names = {_page_id(p) for p in DOC_PAGES}
    assert {"laws.md", "scenes.md", "reference.md", "solution.md", "index.md"} <= names


@pytest.mark.parametrize("page", DOC_PAGES, ids=_page_id)
def test_docs_page_examples_run(page, quiet_plots):
    _run_blocks(python_blocks(page.read_text()), f"docs/{_page_id(page)}")


def _modules_with_examples() -> list[str]:
    found = []
    for info in pkgutil.walk_packages(lumped.__path__, "lumped."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        if any(t.examples for t in doctest.DocTestFinder().find(module)):
            found.append(info.name)
    return found


DOCTEST_MODULES = _modules_with_examples()


def test_docstring_examples_are_found():
    assert {"lumped.result", "lumped.scene.oscillator", "lumped.laws.catalogue"} <= set(
        DOCTEST_MODULES)


@pytest.mark.parametrize("name", DOCTEST_MODULES)
def test_docstring_examples_pass(name, quiet_plots):
    result = doctest.testmod(importlib.import_module(name), report=True,
                             optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0 and result.attempted > 0


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



def test_isolator_example_runs(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    mod = runpy.run_path(str(ROOT / "examples" / "isolator.py"), run_name="isolator")
    numbers = mod["main"](tmp_path / "isolator.png")
    assert (tmp_path / "isolator.png").read_bytes()[:4] == b"\x89PNG"
    assert numbers["peak ground acceleration (g)"] == pytest.approx(0.3, abs=1e-9)
    # the isolator cuts the storey's acceleration and drift; the slider sticks at times
    assert numbers["peak storey acceleration, isolated (g)"] < \
        0.5 * numbers["peak storey acceleration, fixed base (g)"]
    assert numbers["peak storey drift, isolated (mm)"] < \
        0.5 * numbers["peak storey drift, fixed base (mm)"]
    assert numbers["time stuck (s)"] > 1.0


def test_bingham_damper_example_runs(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    mod = runpy.run_path(str(ROOT / "examples" / "bingham_damper.py"), run_name="damper")
    rows = mod["main"](tmp_path / "bingham_damper.png")
    assert (tmp_path / "bingham_damper.png").read_bytes()[:4] == b"\x89PNG"
    for row in rows:  # energy per cycle 4 tau U + pi U^2 omega / gamma, and zeta_eq
        assert row["E_d"] == pytest.approx(row["E_exact"], rel=1e-4)
        assert row["zeta_eq"] == pytest.approx(row["zeta_exact"], rel=1e-4)
        assert row["rig_error"] < 1e-4
