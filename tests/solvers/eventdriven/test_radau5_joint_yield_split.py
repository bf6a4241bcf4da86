"""Two ``radau5`` runs near the joint yield force of stuck dashpots in parallel (issue
29; the dashpots of ``tests/_joint_yield.py``) that crept and stopped after 12
backward-Euler bridges until the stage split of the forces among them was solved to
round-off (:func:`lumped.solvers.radau.cone_split.cone_solver`).

1. A mass on the three dashpots to ground under a sine burst on a constant offset
   ``1e-9`` (relative) within their joint yield force, the offset a Python callable
   (which the static hold does not take: the steps must hold the split): the burst drives
   it past that force, it slides, and after the burst it stops under the offset. The
   stage read the split from the momentum rows, whose ``m / h`` beside the forces' ``1``
   left it to the SVD's round-off, ``eps m / h`` (``1e-6`` of the yield force on steps of
   ``1e-13`` s, 1000 times the load's margin): the stuck mode and the mode with the
   shear-thickening dashpot at its flat yield end alternated at one ``t``, a stop at
   ``t = 0.2687`` after 12 bridges (``rtol = 1e-10``).
2. The same dashpots between two free masses, loaded so that their force (``f m_A / (m_A
   + m)``) is ``1e-9`` within the joint yield force: the masses move together. The split
   scattered by up to ``1e-6`` of the yield force as the steps shrank (the masses'
   velocities, ``m / h`` in the momentum rows, beside the forces), the mode alternated
   and the run stopped after 12 bridges at ``t = 3.6e-5`` (``rtol = 1e-6``); it takes 8
   steps now.

Both agree with ``bdf2`` within ``bdf2``'s own error (its run at ``dt`` against ``dt /
2``), and ``compiled=True`` (which runs such scenes in the Python loop: locks in parallel)
gives the same numbers.
"""

from __future__ import annotations

import math

import numpy as np
from _joint_yield import JOINT, TAUS, M, joint_yield_laws

from lumped import simulate
from lumped.scene import Element, Mass, Scene, SineBurst

DT, T_END = 0.025 / 4, 0.5


class _OffsetBurst:
    def __init__(self, c: float, a: float, omega: float, t_off: float) -> None:
        self.c, self.burst = c, SineBurst(a, omega, t_off)

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        return self.burst.breakpoints(t0, t1)

    def __call__(self, t: float) -> float:
        return self.c + self.burst(t)


def _both_loops(scene: Scene, rtol: float, atol: float):
    """The ``radau5`` run in the Python loop, checked equal to ``compiled=True``'s."""
    sol = simulate(scene, method="radau5", dt=DT, t_end=T_END, rtol=rtol, atol=atol,
                   compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    again = simulate(scene, method="radau5", dt=DT, t_end=T_END, rtol=rtol, atol=atol,
                     compiled=True)
    assert np.array_equal(again.t, sol.t)
    for kind in ("x", "v", "F"):
        for name, values in getattr(sol, kind).items():
            assert np.array_equal(getattr(again, kind)[name], values), (kind, name)
    return sol


def _agrees_with_bdf2(sol, scene: Scene, dt: float, floor: float) -> None:
    """Positions, velocities and the total dashpot force on the last node within
    ``bdf2``'s own error at ``dt / 2`` (its distance to its run at ``dt``), plus
    ``floor`` (where that error is at round-off)."""
    coarse = simulate(scene, method="bdf2", dt=dt, t_end=T_END)
    fine = simulate(scene, method="bdf2", dt=dt / 2, t_end=T_END)

    def on_grid(run, values):
        return np.interp(sol.t, run.t, values)

    def total(run):
        return sum(np.asarray(run.F[f"e{k}"]) for k in range(3))

    pairs = [(sol.x[name], coarse.x[name], fine.x[name]) for name in sol.x]
    pairs += [(sol.v[name], coarse.v[name], fine.v[name]) for name in sol.v]
    pairs.append((total(sol), total(coarse), total(fine)))
    for got, c, f in pairs:
        ref = on_grid(fine, f)
        own = np.abs(on_grid(coarse, c) - ref).max()
        assert np.abs(np.asarray(got) - ref).max() <= own + floor


def test_a_mass_that_slides_then_sticks_just_within_under_a_callable_offset():
    """Stopped from ``t = 0.2681`` (``bdf2``'s too) under the offset: at rest to the
    velocity tolerance, every force within its yield band and their sum the offset, to
    the forces' tolerance. (It ends on the slip branches, its rate ``1e-18`` at the flat
    yield end of the shear-thickening dashpot: ``atol`` is ``1e-13``.)"""
    rtol, atol = 1e-10, 1e-13
    offset = JOINT * (1.0 - 1e-9)
    elements = [Element(f"e{k}", law, "ground", "m0") for k, law in enumerate(joint_yield_laws())]
    scene = Scene([Mass("m0", m=M)], elements,
                  {"m0": _OffsetBurst(offset, 0.1 * JOINT, 4.0 * math.pi, 0.25)})
    sol = _both_loops(scene, rtol, atol)
    assert sol.stats["steps"] <= 800, sol.stats
    late = np.asarray(sol.t) >= 0.27
    assert np.all(np.abs(np.asarray(sol.v["m0"])[late]) <= atol)
    total = np.zeros(int(late.sum()))
    for k, tau in enumerate(TAUS):
        F = np.asarray(sol.F[f"e{k}"])[late]
        assert np.all(np.abs(F) <= tau + rtol * JOINT), (k, np.abs(F).max() - tau)
        total += F
    assert np.all(np.abs(total - offset) <= rtol * JOINT)
    _agrees_with_bdf2(sol, scene, DT / 16, 0.0)


def test_a_group_between_two_free_masses_just_within():
    """The masses move together at ``a = f / (m_A + m)`` (exact: ``x = a t^2 / 2``), the
    group carrying ``m_A a``, ``1e-9`` within its joint yield force, each force within
    its yield band (the stage rule's split: in proportion to the yield forces)."""
    rtol, atol = 1e-6, 1e-9
    laws = joint_yield_laws()
    elements = [Element(f"e{k}", law, "mA", "m0") for k, law in enumerate(laws)]
    f = JOINT * (1.0 - 1e-9) * (1.0 + M)
    scene = Scene([Mass("mA", m=1.0), Mass("m0", m=M)], elements, {"m0": f})
    sol = _both_loops(scene, rtol, atol)
    assert sol.stats["steps"] <= 20 and not sol.events, sol.stats
    a = f / (1.0 + M)
    t = np.asarray(sol.t)
    for name in ("mA", "m0"):
        assert np.allclose(sol.x[name], 0.5 * a * t**2, rtol=rtol, atol=atol)
        assert np.allclose(sol.v[name], a * t, rtol=rtol, atol=atol)
    total = np.zeros(len(t))
    for k, tau in enumerate(TAUS):
        F = np.asarray(sol.F[f"e{k}"])
        assert np.all(np.abs(F) <= tau), (k, np.abs(F).max() - tau)
        total += F
    assert np.all(np.abs(total - a) <= rtol * JOINT)  # (m_A = 1)
    _agrees_with_bdf2(sol, scene, DT / 16, rtol * a * T_END)
