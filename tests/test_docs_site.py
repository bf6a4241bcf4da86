"""The documentation site's table of contents lists every page, a section such as
docs/theory/ through its own index.md (the build itself, with warnings as errors, is a
step of .ci/run: ``sphinx-build -W -b html docs ...``)."""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _toctree_entries(index: Path) -> set[str]:
    return set(re.findall(r"^([a-z_]+(?:/[a-z_]+)?)$", index.read_text(), re.M))


def test_every_page_is_in_the_toctree():
    sections = sorted(d for d in DOCS.iterdir()
                      if d.is_dir() and not d.name.startswith("_") and (d / "index.md").exists())
    assert "theory" in {d.name for d in sections}
    pages = {p.stem for p in DOCS.glob("*.md")} | {p.stem for p in DOCS.glob("*.rst")}
    assert pages - {"index"} | {f"{d.name}/index" for d in sections} == _toctree_entries(
        DOCS / "index.md")
    for section in sections:
        # a section's pages are listed in its own index
        assert {p.stem for p in section.glob("*.md")} - {"index"} == _toctree_entries(
            section / "index.md")


def test_the_docs_extra_names_the_builders():
    text = (DOCS.parent / "pyproject.toml").read_text()
    extra = re.search(r"^docs = \[(.*)\]$", text, re.M)
    assert extra is not None
    for tool in ("sphinx", "numpydoc", "myst-parser"):
        assert f'"{tool}' in extra.group(1)
