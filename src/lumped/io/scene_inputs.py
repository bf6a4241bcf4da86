"""Forcing and ground motion in scene files: the inline tables of ``force``, of
``[ground] motion`` and of ``[supports.<name>] motion`` (``docs/scenes.md``).

An input is a number (a constant), an expression string in ``t`` (the allowlist parser
:func:`lumped.laws.parser.parse_expression`, never ``eval``), or a table with ``kind``:

* ``{ kind = "sine", amplitude = A, omega = w, t_off = T }``: ``A sin(w t)`` for
  ``t <= T`` (``t_off`` optional);
* ``{ kind = "expression", expression = "..." }``;
* ``{ kind = "table", file = "record.at2", units = "g", factor = 1.0 }``: a CSV file
  (``time_column``, ``value_column``, ``delimiter``; default the first two columns) or a
  PEER ``.AT2``/``.VT2``/``.DT2`` record (by its suffix, or ``format = "csv" | "at2"``),
  read by :mod:`lumped.io.tables`; ``outside = "zero" | "hold"``. A relative ``file`` is
  relative to the scene file's folder.

A ground motion table also takes ``quantity = "acceleration" | "velocity" |
"displacement"`` (default ``"acceleration"``); a force's ``quantity``, if given, must be
``"force"``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ..scene.forcing import SineBurst

__all__ = ["forcing_input", "ground_input", "resolve_files", "checked_number", "GROUND_KEYS"]

#: Keys of the ``[ground]`` table.
GROUND_KEYS = ("motion", "v0", "x0")
_KINDS = ("sine", "expression", "table")
_KEYS = {
    "sine": {"kind", "amplitude", "omega", "t_off", "quantity"},
    "expression": {"kind", "expression", "quantity"},
    "table": {"kind", "file", "quantity", "units", "factor", "format", "time_column",
              "value_column", "delimiter", "outside"},
}
_MOTION = ("acceleration", "velocity", "displacement")


def checked_number(value: object, key: str, fail) -> float:
    """``value`` as a finite float, else ``fail(key, why)`` raised (a bool is no number)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(key, f"must be a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise fail(key, f"must be finite, got {value!r}")
    return x


def _expression(text: object, key: str, fail):
    if not isinstance(text, str):
        raise fail(key, f"must be an expression string, got {text!r}")
    from ..laws.parser import parse_expression

    try:
        return parse_expression(text, ["t"])
    except (TypeError, ValueError, SyntaxError) as err:
        raise fail(key, f"bad expression {text!r}: {err}") from None


def _input(spec: object, key: str, fail, base: Path, quantities: tuple[str, ...],
           default: str) -> tuple[str, Any]:
    """``(quantity, value)`` of one input (see the module notes)."""
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return default, checked_number(spec, key, fail)
    if isinstance(spec, str):
        return default, _expression(spec, key, fail)
    if not isinstance(spec, dict):
        raise fail(key, f"must be a number, an expression string or a table with `kind`, "
                   f"got {spec!r}")
    kind = spec.get("kind")
    if kind not in _KINDS:
        raise fail(f"{key} kind", f"must be one of {', '.join(_KINDS)}, got {kind!r}")
    extra = set(spec) - _KEYS[kind]
    if extra:
        raise fail(f"{key} {sorted(extra)[0]}",
                   f"unknown key for kind = {kind!r} (allowed: {', '.join(sorted(_KEYS[kind]))})")
    quantity = spec.get("quantity", default)
    if quantity not in quantities:
        raise fail(f"{key} quantity", f"must be {' or '.join(map(repr, quantities))} here, "
                   f"got {quantity!r}")
    if kind == "expression":
        if "expression" not in spec:
            raise fail(f"{key} expression", "missing")
        return quantity, _expression(spec["expression"], f"{key} expression", fail)
    if kind == "sine":
        for k in ("amplitude", "omega"):
            if k not in spec:
                raise fail(f"{key} {k}", "missing")
        amp = checked_number(spec["amplitude"], f"{key} amplitude", fail)
        omega = checked_number(spec["omega"], f"{key} omega", fail)
        t_off = spec.get("t_off", math.inf)
        if t_off != math.inf:
            t_off = checked_number(t_off, f"{key} t_off", fail)
        try:
            return quantity, SineBurst(amplitude=amp, omega=omega, t_off=t_off)
        except (TypeError, ValueError) as err:
            raise fail(key, str(err)) from None
    return quantity, _table(spec, key, fail, base, quantity)


def _table(spec: dict, key: str, fail, base: Path, quantity: str):
    from .tables import read_at2, read_table

    name = spec.get("file")
    if not isinstance(name, str) or not name:
        raise fail(f"{key} file", f"must be a file name, got {name!r}")
    path = Path(name)
    if not path.is_absolute():
        path = base / path
    fmt = spec.get("format")
    if fmt is None:
        fmt = "at2" if path.suffix.lower() in (".at2", ".vt2", ".dt2") else "csv"
    if fmt not in ("csv", "at2"):
        raise fail(f"{key} format", f"must be 'csv' or 'at2', got {fmt!r}")
    options: dict[str, Any] = {}
    if "units" in spec:
        if not isinstance(spec["units"], str):
            raise fail(f"{key} units", f"must be a unit name, got {spec['units']!r}")
        options["units"] = spec["units"]
    if "factor" in spec:
        options["factor"] = checked_number(spec["factor"], f"{key} factor", fail)
    if "outside" in spec:
        options["outside"] = spec["outside"]
    if fmt == "csv":
        for k in ("time_column", "value_column", "delimiter"):
            if k in spec:
                options[k] = spec[k]
    else:
        bad = [k for k in ("time_column", "value_column", "delimiter") if k in spec]
        if bad:
            raise fail(f"{key} {bad[0]}", "applies to a CSV file only")
    try:
        if fmt == "at2":
            return read_at2(path, quantity=quantity, **options)
        return read_table(path, quantity=quantity, **options)
    except (TypeError, ValueError, OSError) as err:
        raise fail(f"{key} file", f"{name!r}: {err}") from None


def forcing_input(spec: object, key: str, fail, base: Path) -> object:
    """A node's ``force``: a number, an expression, a SineBurst or a force Table."""
    return _input(spec, key, fail, base, ("force",), "force")[1]


def ground_input(tbl: object, key: str, fail, base: Path):
    """The :class:`~lumped.scene.GroundMotion` of a ``[ground]`` table."""
    from ..scene import GroundMotion

    if not isinstance(tbl, dict):
        raise fail(key, f"must be a table, got {tbl!r}")
    extra = set(tbl) - set(GROUND_KEYS)
    if extra:
        raise fail(f"{key} {sorted(extra)[0]}",
                   f"unknown key (allowed: {', '.join(GROUND_KEYS)})")
    if "motion" not in tbl:
        raise fail(f"{key} motion", "missing")
    quantity, value = _input(tbl["motion"], f"{key} motion", fail, base, _MOTION,
                             "acceleration")
    v0 = checked_number(tbl.get("v0", 0.0), f"{key} v0", fail)
    x0 = checked_number(tbl.get("x0", 0.0), f"{key} x0", fail)
    try:
        return GroundMotion(**{quantity: value}, v0=v0, x0=x0)
    except (TypeError, ValueError) as err:
        raise fail(f"{key} motion", str(err)) from None


def resolve_files(data: dict[str, Any], base_dir: str | Path) -> dict[str, Any]:
    """A copy of the scene-file tables ``data`` whose relative table ``file`` entries are
    made absolute against ``base_dir`` (so that the tables can be rebuilt elsewhere, as
    :func:`lumped.sweep.simulate_many` does)."""
    import copy

    out = copy.deepcopy(data)
    specs = [node.get("force") for node in (out.get("nodes") or {}).values()
             if isinstance(node, dict)]
    ground = out.get("ground")
    if isinstance(ground, dict):
        specs.append(ground.get("motion"))
    supports = out.get("supports")
    if isinstance(supports, dict):
        specs += [tbl.get("motion") for tbl in supports.values() if isinstance(tbl, dict)]
    for spec in specs:
        if isinstance(spec, dict) and spec.get("kind") == "table" \
                and isinstance(spec.get("file"), str) and not Path(spec["file"]).is_absolute():
            spec["file"] = str((Path(base_dir) / spec["file"]).resolve())
    return out
