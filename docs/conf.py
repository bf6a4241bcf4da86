"""Sphinx configuration of the lumped documentation site.

Build (warnings are errors)::

    python -m pip install -e ".[docs]" && sphinx-build -W -b html docs docs/_build/html

The Markdown pages are read by myst-parser; the API reference is generated from the
numpydoc docstrings by autodoc/autosummary (``api.md``).
"""

from __future__ import annotations

import importlib.metadata

project = "lumped"
author = "the lumped developers"
copyright = "2026, the lumped developers"  # noqa: A001 - Sphinx's name
release = importlib.metadata.version("lumped")
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]

# Markdown: $...$ maths, ::: fences, and anchors for the headings, so that the pages'
# links to each other (`laws.md#declaring-a-law`) resolve.
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# API reference: one page per module, written by autosummary at build time.
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections say it
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

html_theme = "alabaster"
html_title = "lumped"
html_static_path: list[str] = []
