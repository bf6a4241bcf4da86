"""The loads of the locks' correction on ``radau5``'s dense output
(:meth:`lumped.solvers.radau.locked_forces.LockedForces.loads`): every forcing with a kind
code, a table's too, evaluated at all the output times at once with the callable's own
numbers; only a callable without one is called per time."""

from __future__ import annotations

import numpy as np

from lumped import Element, Mass, Scene, get_law
from lumped.io import Table
from lumped.scene import GroundMotion, SineBurst
from lumped.scene.ground import _PiecewiseMotion
from lumped.solvers.radau.locked_forces import LockedForces


def _scenes() -> list[Scene]:
    ts = np.linspace(0.0, 1.0, 9)
    record = Table(ts, np.cos(7.0 * ts), quantity="acceleration")
    spring = get_law("linear_spring").bind(k=10.0)

    def scene(names: str, forces: dict, ground=None) -> Scene:
        return Scene([Mass(n, 1.0 + k) for k, n in enumerate(names)],
                     [Element(f"k{n}", spring, "ground", n) for n in names], forces,
                     ground_motion=ground)

    # a force table beside the other kinds, and a ground record alone or beside a load
    return [scene("abcde", {"a": Table(ts, np.sin(3.0 * ts), quantity="force"),
                            "b": SineBurst(0.7, 5.0, 0.6), "c": 0.25,
                            "d": lambda t: t * t, "e": "0.5*t"}),
            scene("abc", {"a": SineBurst(0.7, 5.0, 0.6), "b": 0.25},
                  GroundMotion(acceleration=record))]


def test_the_loads_read_tables_at_all_times_at_once(monkeypatch):
    ts = np.concatenate([np.linspace(-0.1, 1.1, 97), np.linspace(0.0, 1.0, 9)])
    calls = []
    for cls in (Table, _PiecewiseMotion):  # (a force table, a ground record's a(t))
        real = cls.__call__
        monkeypatch.setattr(cls, "__call__",
                            lambda self, t, real=real: calls.append(t) or real(self, t))
    for scene in _scenes():
        want = np.array([[fn(float(t)) for fn in scene.forcing] for t in ts])
        calls.clear()
        got = LockedForces(scene).loads(ts)
        # the callables' own doubles, and no table called per time (before: once per
        # time and node with a table or a record, 106 and 318 calls)
        assert np.array_equal(got, want)
        assert calls == []
