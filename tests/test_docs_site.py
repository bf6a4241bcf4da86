"""The documentation site's table of contents lists every page (the build itself, with
warnings as errors, is a step of .ci/run: ``sphinx-build -W -b html docs ...``)."""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_every_page_is_in_the_toctree():
    index = (DOCS / "index.md").read_text()
    listed = set(re.findall(r"^([a-z_]+)$", index, re.M))
    pages = {p.stem for p in DOCS.glob("*.md")} | {p.stem for p in DOCS.glob("*.rst")}
    assert pages - {"index"} == listed


def test_the_docs_extra_names_the_builders():
    text = (DOCS.parent / "pyproject.toml").read_text()
    extra = re.search(r"^docs = \[(.*)\]$", text, re.M)
    assert extra is not None
    for tool in ("sphinx", "numpydoc", "myst-parser"):
        assert f'"{tool}' in extra.group(1)
