r"""Runs with **new numbers**: what a user gets after editing a number of a scene.

A benchmark that repeats a run on one scene object measures a warm process: every
module the run needs is loaded and every kernel of those numbers is compiled. A user
who changes the spring stiffness ``k`` and runs again gets none of that for the new
numbers. :func:`new_factor` hands out ``1 + 1e-6 (n + r)``, with ``n`` counting the calls
in this process and ``r`` in ``[0, 1)`` drawn once per process, so a stiffness scaled by
it is a value never run before in the process, nor (but by a chance of about ``1e-16``)
by an earlier process whose compiled code sits in the disk cache;
:func:`bench_scene_with_new_numbers` and :func:`scene_with_new_numbers` build a new
scene object with it, which no other run has touched.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from .scenes import BenchScene, Ladders
from .timing import time_call

if TYPE_CHECKING:
    from .methods import Method

__all__ = ["NEW_REPEATS", "NewTimes", "new_factor", "bench_scene_with_new_numbers",
           "scene_with_new_numbers", "time_new_numbers"]

_COUNTER = itertools.count(1)
#: Drawn once per process (from the operating system's entropy): earlier processes,
#: which started from the same counter, ran other numbers.
_OFFSET = random.Random().random()


def new_factor() -> float:
    """``1 + 1e-6 (n + r)`` (see the module notes): never the same twice in a process."""
    return 1.0 + 1e-6 * (next(_COUNTER) + _OFFSET)


def bench_scene_with_new_numbers(scene: BenchScene, factor: float | None = None) -> BenchScene:
    """``scene`` with its stiffness ``k`` times ``factor`` (default: :func:`new_factor`).

    The other numbers are kept; the motion moves by a relative ``~1e-6``, so the run is
    timed, not scored against the exact solution of ``scene``.
    """
    factor = new_factor() if factor is None else factor
    return replace(scene, osc=replace(scene.osc, k=scene.osc.k * factor))


def scene_with_new_numbers(scene, factor: float | None = None, *,
                           parameters: Iterable[str] = ("k",)):
    """A new :class:`~lumped.scene.Scene` like ``scene`` with every law parameter named in
    ``parameters`` (default: the springs' ``k``) times ``factor`` (default:
    :func:`new_factor`).

    The nodes, the other parameters, the forces and the ground motion are ``scene``'s; every
    element gets a newly bound law, so nothing compiled for ``scene``'s laws is reused.
    Raises ``ValueError`` when no element has such a parameter (nothing would change).
    """
    from ..scene import Element, Scene

    names = set(parameters)
    if not any(p in names for el in scene.elements for p in el.law.params):
        raise ValueError(f"`parameters`: no element of the scene has any of {sorted(names)}")
    factor = new_factor() if factor is None else factor
    elements = []
    for el in scene.elements:
        values = {p: v * factor if p in names else v for p, v in el.law.params.items()}
        elements.append(Element(el.name, el.law.law.bind(**values), el.a, el.b, el.F0))
    return Scene(scene.nodes, elements, scene.force_specs, ground_motion=scene.ground_motion)


#: At most this many runs with new numbers per setting of ``lumped bench`` (the user's
#: columns, :mod:`lumped.bench.runner`).
NEW_REPEATS = 20


@dataclass(frozen=True)
class NewTimes:
    """The runs with new numbers of one setting: the smallest CPU time (``best``), the
    first run's, how many ran, and why they stopped (``''`` when none failed)."""

    best: float
    first: float
    runs: int
    message: str


def time_new_numbers(scene: BenchScene, method: Method, setting: dict, ladders: Ladders,
                     repeats: int) -> NewTimes:
    """``repeats`` runs of ``setting``, each with new numbers of its own on a new scene
    object (:func:`bench_scene_with_new_numbers`), each timed once by ``method.solve``
    (a :class:`~lumped.bench.methods.Method`); all ``nan`` with the reason when one
    fails (the warm row stands)."""
    times: list[float] = []
    for _ in range(max(repeats, 1)):
        fresh = bench_scene_with_new_numbers(scene)
        try:
            runner = method.solve(fresh, setting, ladders)
            solved, cpu, _ = time_call(runner, min_time=0.0, max_repeats=1)
            if not np.all(np.isfinite(solved.x)):
                raise FloatingPointError("non-finite x in the solution")
        except Exception as err:  # say why this column is empty
            return NewTimes(math.nan, math.nan, 0,
                            f"new numbers (k x {fresh.osc.k / scene.osc.k!r}): "
                            f"{type(err).__name__}: {err}")
        times.append(cpu)
    return NewTimes(min(times), times[0], len(times), "")
