"""Parameter sets of a sweep: grids, lists, dotted paths into a scene-file dict.

A parameter is named by a *dotted path* into the tables of a scene file
(``docs/scenes.md``)::

    nodes.mass.x0                    nodes.mass.force.amplitude
    elements.dashpot.parameters.tau  elements.spring.parameters.k

A sweep is either a **grid**, a dict ``{path: values}`` whose Cartesian product gives the
scenes (the first path varies slowest), or a **list** of dicts ``{path: value}``, one per
scene.
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["ParameterSets", "parameter_sets", "set_path", "get_path", "parse_grid_spec"]


class ParameterSets:
    """The scenes of a sweep as rows of parameter values.

    Attributes
    ----------
    names : tuple of str
        The parameter paths, in column order.
    rows : list of tuple
        One tuple of values per scene, in ``names`` order.
    grid : dict of str to numpy.ndarray, or None
        For a grid, the values along each axis (``len(rows)`` is the product of their
        lengths, row-major: the last name varies fastest); ``None`` for a list.
    """

    def __init__(self, names: Sequence[str], rows: list[tuple], grid: dict | None) -> None:
        self.names = tuple(names)
        self.rows = rows
        self.grid = grid

    def __len__(self) -> int:
        return len(self.rows)

    def as_dicts(self) -> list[dict[str, Any]]:
        """One ``{path: value}`` dict per scene."""
        return [dict(zip(self.names, row, strict=True)) for row in self.rows]

    def column(self, name: str) -> list:
        """The values of one parameter over all scenes."""
        i = self.names.index(name)
        return [row[i] for row in self.rows]


def parameter_sets(parameters: object) -> ParameterSets:
    """Normalise ``parameters`` (a grid dict or a list of dicts) to :class:`ParameterSets`.

    Raises
    ------
    TypeError, ValueError
        Naming ``parameters`` and the offending entry.
    """
    if isinstance(parameters, Mapping):
        if not parameters:
            raise ValueError("`parameters` is an empty grid: give at least one path")
        names, axes = [], {}
        for name, values in parameters.items():
            _check_name(name)
            if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
                raise TypeError(f"`parameters[{name!r}]` must be a sequence of values, "
                                f"got {values!r}")
            vals = list(np.asarray(values).tolist()) if isinstance(values, np.ndarray) \
                else list(values)
            if not vals:
                raise ValueError(f"`parameters[{name!r}]` is empty")
            names.append(name)
            axes[name] = np.asarray(vals)
        rows = list(itertools.product(*(list(v.tolist()) for v in axes.values())))
        return ParameterSets(names, rows, axes)
    if isinstance(parameters, Sequence) and not isinstance(parameters, (str, bytes)):
        if not parameters:
            raise ValueError("`parameters` is an empty list: give at least one scene")
        first = parameters[0]
        if not isinstance(first, Mapping):
            raise TypeError(f"`parameters[0]` must be a dict of path -> value, got {first!r}")
        names = list(first)
        for name in names:
            _check_name(name)
        rows = []
        for i, entry in enumerate(parameters):
            if not isinstance(entry, Mapping) or set(entry) != set(names):
                raise ValueError(f"`parameters[{i}]` must be a dict with the keys {names}, "
                                 f"got {entry!r}")
            rows.append(tuple(entry[n] for n in names))
        return ParameterSets(names, rows, None)
    raise TypeError("`parameters` must be a dict (a grid: path -> values) or a list of dicts "
                    f"(path -> value), got {type(parameters).__name__}")


def _check_name(name: object) -> None:
    if not isinstance(name, str) or not name or any(not part for part in name.split(".")):
        raise ValueError(f"parameter names are dotted paths like 'nodes.mass.x0', got {name!r}")


def get_path(data: Mapping[str, Any], path: str) -> Any:
    """The value at ``path`` in nested dicts; ``KeyError`` naming the path if absent."""
    node: Any = data
    for part in path.split("."):
        if not isinstance(node, Mapping) or part not in node:
            raise KeyError(path)
        node = node[part]
    return node


def set_path(data: dict[str, Any], path: str, value: Any) -> None:
    """Set ``path`` in nested dicts (in place). The parent table must exist, except that a
    missing ``force`` table of a node is created (so ``nodes.m.force.amplitude`` works on a
    scene without forcing only together with the other keys of a sine table)."""
    parts = path.split(".")
    node: Any = data
    for depth, part in enumerate(parts[:-1]):
        if isinstance(node, Mapping) and part not in node and part == "force" and depth == 2:
            node[part] = {}
        if not isinstance(node, Mapping) or part not in node:
            raise ValueError(f"parameter {path!r}: the template has no table "
                             f"{'.'.join(parts[:depth + 1])!r}")
        if not isinstance(node[part], dict):
            raise ValueError(f"parameter {path!r}: {'.'.join(parts[:depth + 1])!r} is "
                             f"{node[part]!r}, not a table")
        node = node[part]
    node[parts[-1]] = value


def apply(template: Mapping[str, Any], values: Mapping[str, Any]) -> dict[str, Any]:
    """A deep copy of the scene-file dict ``template`` with ``values`` set at their paths."""
    data = copy.deepcopy(dict(template))
    for path, value in values.items():
        set_path(data, path, _plain(value))
    return data


def _plain(value: Any) -> Any:
    """numpy scalars to Python numbers (scene files take TOML numbers)."""
    if isinstance(value, np.generic):
        return value.item()
    return value


def parse_grid_spec(spec: str) -> tuple[str, list[float]]:
    """Parse a command-line grid axis.

    ``"path=start:stop:num"`` gives ``num`` evenly spaced values including both ends
    (``numpy.linspace``); ``"path=a,b,c"`` gives the listed values; ``"path=v"`` one value.

    >>> parse_grid_spec("nodes.mass.force.amplitude=0:20:5")
    ('nodes.mass.force.amplitude', [0.0, 5.0, 10.0, 15.0, 20.0])
    """
    if not isinstance(spec, str) or "=" not in spec:
        raise ValueError(f"`--grid` must look like 'path=start:stop:num' or 'path=a,b,c', "
                         f"got {spec!r}")
    name, _, rhs = spec.partition("=")
    name = name.strip()
    _check_name(name)
    try:
        if ":" in rhs:
            parts = rhs.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop, num = float(parts[0]), float(parts[1]), int(parts[2])
            if num < 1 or not (math.isfinite(start) and math.isfinite(stop)):
                raise ValueError
            values = [float(v) for v in np.linspace(start, stop, num)]
        else:
            values = [float(v) for v in rhs.split(",")]
            if not all(math.isfinite(v) for v in values):
                raise ValueError
    except ValueError:
        raise ValueError(f"`--grid` {spec!r}: values must be 'start:stop:num' (num >= 1) or "
                         "a comma-separated list of finite numbers") from None
    return name, values
