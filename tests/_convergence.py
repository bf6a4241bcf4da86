"""Convergence of a fixed-step ladder of runs as the step halves: the check shared by the
random-network property suite and its regressions (tests/solvers)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

#: Extra halvings of the step allowed when the first three levels do not show convergence.
EXTRA_LEVELS = 2


def distances(sols: list, n_nodes: int) -> tuple[float, float]:
    """Distances of the displacements of ``sols[-3]`` and ``sols[-2]`` to ``sols[-1]``
    (steps ``4 h``, ``2 h``, ``h``) on the coarse grid."""
    xcols = slice(1, 1 + 2 * n_nodes, 2)
    d0 = np.abs(sols[-3].data[:, xcols] - sols[-1].data[::4, xcols]).max()
    d1 = np.abs(sols[-2].data[:, xcols] - sols[-1].data[::2, xcols]).max()
    return float(d0), float(d1)


def assert_converges(sols: list, n_nodes: int, dt: float, vmax: float, scale: float,
                     rerun: Callable[[float], object]) -> int:
    """The runs ``sols`` (steps ``dt``, ``dt / 2``, ``dt / 4``) converge as the step halves.

    Either the distance to the finest run shrinks (``d1 <= 0.9 d0``), or it is already
    within a first-order bound (``dt |v|``): near-degenerate stick positions (spring
    force ~ yield force) make the distance erratic at small values, while a method that
    does not converge (BDF2 bouncing off a string) is off by O(1).

    A *grazing* impact (a string that the exact motion only just reaches) is missed by
    the coarse runs and hit by the fine ones: the distance shrinks only once every run of
    the ladder hits it. So when the three levels fail, the ladder goes on by up to
    :data:`EXTRA_LEVELS` halvings (``rerun(step)`` gives the run at ``step``), and the
    test holds on its last three runs -- a method that does not converge fails there too.
    Returns the number of extra halvings used."""
    sols = list(sols)
    for extra in range(EXTRA_LEVELS + 1):
        d0, d1 = distances(sols, n_nodes)
        bound = 0.5 * dt / 2**extra * (1.0 + vmax)
        if d1 <= max(0.9 * d0 + 1e-7 * scale, bound):
            return extra
        if extra == EXTRA_LEVELS:
            break
        finer = rerun(dt / 2 ** len(sols))
        assert finer.ok, finer.message
        assert np.all(np.isfinite(finer.data))
        sols.append(finer)
    raise AssertionError(f"no convergence: {d0!r} -> {d1!r}")


def assert_within_bdf2s_own_error(scene, sol, names, dt: float, t_end: float,
                                  s: int) -> None:
    """The displacements of ``sol`` (output every ``dt``) within those of ``bdf2`` at
    ``dt / (2 s)`` by at most that run's own error, its distance to the run at ``dt /
    s`` (second order: its error is a third of that)."""
    from lumped import simulate

    fine, finer = (simulate(scene, method="bdf2", dt=dt / k, t_end=t_end) for k in (s, 2 * s))
    for name in names:
        ref = np.asarray(finer.x[name])[::2 * s]
        own = np.max(np.abs(np.asarray(fine.x[name])[::s] - ref))
        err = np.max(np.abs(np.asarray(sol.x[name]) - ref))
        assert err <= own, (name, err, own)
