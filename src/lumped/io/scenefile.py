"""Scene files: a :class:`~lumped.scene.Scene` and its solver settings written in TOML.

A scene file is data, never code: law names are looked up in the built-in library,
numbers must be TOML numbers, and a forcing expression string is parsed by the
allowlist parser :func:`lumped.laws.parser.parse_expression` (no ``eval``). The format
is documented in ``docs/scenes.md``; in short::

    [solver]                       # optional; command-line values override it
    method = "auto"                # any of lumped.solvers.registry.METHODS
    dt = 1e-4
    t_end = 5.0

    [nodes.mass]                   # a node with `mass` is a Mass, without it a Junction
    mass = 1.0
    x0 = 0.5                       # optional, default 0
    v0 = 0.0                       # optional, default 0 (masses only)
    force = "0.5*sin(5*pi*t)"      # optional: a number, an expression in t, or
    # force = { kind = "sine", amplitude = 0.5, omega = 15.707963267948966, t_off = 1.0 }

    [elements.spring]
    law = "linear_spring"
    between = ["ground", "mass"]   # a then b: q = x_b - x_a, +F on a, -F on b
    parameters = { k = 100.0 }
    # F0 = 50.0                    # optional initial force, checked against the law

    [ground]                       # optional: a moving ground (states relative to it)
    motion = { kind = "table", file = "record.at2", quantity = "acceleration", units = "g" }

    [supports.belt]                # optional: a named support with its own motion; an
    motion = { kind = "expression", quantity = "velocity", expression = "0.3" }
    # x0 = 0.0, v0 = 0.0           # element names it in `between` (not with [ground])

Inputs (``force``, ``[ground] motion``, ``[supports.<name>] motion``) are read by
:mod:`lumped.io.scene_inputs`; a table's ``file`` is relative to the scene file's folder.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from ..scene import Element, Junction, Mass, Scene
from .scene_inputs import checked_number, forcing_input, ground_input

__all__ = ["load_scene", "read_scene_file", "scene_from_dict", "SceneFileError",
           "SETTINGS_KEYS"]

#: Keys of the ``[solver]`` table.
SETTINGS_KEYS = ("method", "dt", "t_end", "rtol", "atol")

_NODE_KEYS = {"mass", "x0", "v0", "force"}
_ELEMENT_KEYS = {"law", "between", "parameters", "F0"}


class SceneFileError(ValueError):
    """Bad content in a scene file; the message names the file, the key and the value."""


def load_scene(path: str | Path) -> tuple[Scene, dict[str, Any]]:
    """Read a TOML scene file.

    Returns
    -------
    scene : Scene
    settings : dict
        The ``[solver]`` table (``method``, ``dt``, ``t_end``, ``rtol``, ``atol``; only those
        given).

    Raises
    ------
    SceneFileError
        For unreadable TOML or bad content, naming the file, the key and the value.
    """
    return scene_from_dict(read_scene_file(path), source=str(path),
                           base_dir=Path(path).parent)


def read_scene_file(path: str | Path) -> dict[str, Any]:
    """The parsed TOML tables of a scene file, unchecked (for :func:`scene_from_dict`, or
    to change some values first, as :func:`lumped.sweep.simulate_many` does).

    Raises
    ------
    SceneFileError
        If the file is missing or not valid TOML, naming the file.
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise SceneFileError(f"{path}: no such scene file") from None
    except tomllib.TOMLDecodeError as err:
        raise SceneFileError(f"{path}: not valid TOML: {err}") from None


def scene_from_dict(data: dict[str, Any], *, source: str = "<scene>",
                    base_dir: str | Path | None = None) -> tuple[Scene, dict]:
    """Build ``(scene, settings)`` from the parsed TOML tables (see :func:`load_scene`).

    ``base_dir`` is the folder a table's relative ``file`` is read from (default: the
    current directory; :func:`load_scene` passes the scene file's folder)."""
    base = Path(base_dir) if base_dir is not None else Path()

    def fail(key: str, msg: str) -> SceneFileError:
        return SceneFileError(f"{source}: {key}: {msg}")

    unknown = set(data) - {"solver", "nodes", "elements", "ground", "supports"}
    if unknown:
        raise fail(sorted(unknown)[0], "unknown top-level table (expected solver, nodes, "
                   "elements, ground, supports)")

    settings = _settings(data.get("solver", {}), fail)

    nodes_tbl = data.get("nodes")
    if not isinstance(nodes_tbl, dict) or not nodes_tbl:
        raise fail("nodes", "a scene needs a [nodes.<name>] table for each node")
    nodes: list[Mass | Junction] = []
    forces: dict[str, object] = {}
    for name, spec in nodes_tbl.items():
        key = f"[nodes.{name}]"
        _check_table(spec, key, _NODE_KEYS, fail)
        try:
            x0 = checked_number(spec.get("x0", 0.0), f"{key} x0", fail)
            if "mass" in spec:
                m = checked_number(spec["mass"], f"{key} mass", fail)
                v0 = checked_number(spec.get("v0", 0.0), f"{key} v0", fail)
                nodes.append(Mass(name, m=m, x0=x0, v0=v0))
            else:
                if "v0" in spec:
                    raise fail(f"{key} v0", "a junction (no `mass`) has no initial velocity "
                               "of its own; it follows from the laws")
                nodes.append(Junction(name, x0=x0))
        except (TypeError, ValueError) as err:
            if isinstance(err, SceneFileError):
                raise
            raise fail(key, str(err)) from None
        if "force" in spec:
            forces[name] = forcing_input(spec["force"], f"{key} force", fail, base)

    elements_tbl = data.get("elements", {})
    if not isinstance(elements_tbl, dict):
        raise fail("elements", f"must be a table of [elements.<name>] tables, got {elements_tbl!r}")
    elements: list[Element] = []
    for name, spec in elements_tbl.items():
        key = f"[elements.{name}]"
        _check_table(spec, key, _ELEMENT_KEYS, fail)
        law = _law(spec, key, fail)
        between = spec.get("between")
        if (not isinstance(between, list) or len(between) != 2
                or not all(isinstance(s, str) for s in between)):
            raise fail(f"{key} between", f"must be a list of two node names, got {between!r}")
        F0 = spec.get("F0")
        if F0 is not None:
            F0 = checked_number(F0, f"{key} F0", fail)
        try:
            elements.append(Element(name, law, between[0], between[1], F0=F0))
        except (TypeError, ValueError) as err:
            raise fail(key, str(err)) from None
    ground = ground_input(data["ground"], "[ground]", fail, base) if "ground" in data else None
    supports_tbl = data.get("supports", {})
    if not isinstance(supports_tbl, dict):
        raise fail("supports", f"must be a table of [supports.<name>] tables, got "
                   f"{supports_tbl!r}")
    supports = {name: ground_input(spec, f"[supports.{name}]", fail, base)
                for name, spec in supports_tbl.items()}
    try:
        scene = Scene(nodes, elements, forces, ground_motion=ground, supports=supports)
    except (TypeError, ValueError) as err:
        raise SceneFileError(f"{source}: {err}") from None
    return scene, settings


def _check_table(spec: object, key: str, allowed: set[str], fail) -> None:
    """``spec`` must be a TOML table whose keys are all in ``allowed``."""
    if not isinstance(spec, dict):
        raise fail(key, f"must be a table, got {spec!r}")
    extra = set(spec) - allowed
    if extra:
        raise fail(f"{key} {sorted(extra)[0]}",
                   f"unknown key (allowed: {', '.join(sorted(allowed))})")


def _settings(tbl: object, fail) -> dict[str, Any]:
    if not isinstance(tbl, dict):
        raise fail("[solver]", f"must be a table, got {tbl!r}")
    extra = set(tbl) - set(SETTINGS_KEYS)
    if extra:
        raise fail(f"[solver] {sorted(extra)[0]}",
                   f"unknown key (allowed: {', '.join(SETTINGS_KEYS)})")
    out: dict[str, Any] = {}
    if "method" in tbl:
        from ..solvers.registry import METHODS

        if tbl["method"] not in METHODS:
            raise fail("[solver] method", f"must be one of {METHODS}, got {tbl['method']!r}")
        out["method"] = tbl["method"]
    for k in ("dt", "t_end", "rtol", "atol"):
        if k in tbl:
            val = checked_number(tbl[k], f"[solver] {k}", fail)
            if not val > 0.0:
                raise fail(f"[solver] {k}", f"must be positive, got {val!r}")
            out[k] = val
    return out


def _law(spec: dict, key: str, fail):
    name = spec.get("law")
    if not isinstance(name, str):
        raise fail(f"{key} law", f"must be the name of a law, got {name!r}")
    from ..laws import BUILTIN_LAWS, get_law

    try:
        law = get_law(name)
    except (KeyError, ValueError):
        raise fail(f"{key} law", f"unknown law {name!r} (known: {', '.join(sorted(BUILTIN_LAWS))})"
                   ) from None
    params = spec.get("parameters", {})
    if not isinstance(params, dict):
        raise fail(f"{key} parameters", f"must be a table of numbers, got {params!r}")
    values = {k: checked_number(v, f"{key} parameters.{k}", fail) for k, v in params.items()}
    try:
        return law.bind(**values)
    except (TypeError, ValueError) as err:
        raise fail(f"{key} parameters", f"{err}") from None
