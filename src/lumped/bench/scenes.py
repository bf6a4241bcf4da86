r"""What the benchmark runs: the scenes (one mass, a linear spring and a Bingham dashpot),
the common error grid and targets, the ladders of settings, and the exact ``x`` of a scene
on the grid (:func:`reference_grid`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._validate import as_positive
from ..scene.forcing import SineBurst, paper_F1, paper_F2, zero_forcing
from ..solvers.closed.closed_form import BinghamOscillator

__all__ = [
    "GRID_DT",
    "TARGETS",
    "YARDSTICK_ITERATIONS",
    "BenchScene",
    "PAPER_SCENES",
    "OWN_SCENES",
    "SCENES",
    "Ladders",
    "FULL",
    "QUICK",
    "generic_scene",
    "reference_grid",
    "check_ladders",
]

#: Step of the common grid on which errors are measured.
GRID_DT = 1e-3
#: Error targets of the summary (absolute, in units of x).
TARGETS = (1e-3, 1e-5, 1e-7, 1e-9, 1e-11)
#: Iterations of the yardstick loop (one unit of benchmark time).
YARDSTICK_ITERATIONS = 500_000


# --------------------------------------------------------------------------- scenes


@dataclass(frozen=True)
class BenchScene:
    """One benchmark problem: parameters, initial state and forcing.

    Attributes
    ----------
    name : str
        Short identifier used in the tables.
    osc : BinghamOscillator
        ``m, k, gamma, tau`` (``tau = mu_s N_f``).
    x0, v0 : float
        Initial state (consistent forces are derived by each method).
    forcing : SineBurst or None
        ``A sin(w t)`` up to ``t_off``; ``None`` for no forcing.
    t_end : float
        End of the scored interval.
    note : str
        What the scene exercises.
    """

    name: str
    osc: BinghamOscillator
    x0: float
    v0: float = 0.0
    forcing: SineBurst | None = None
    t_end: float = 5.0
    note: str = ""

    @property
    def force(self) -> Callable[[float], float]:
        """The forcing as a callable (``zero_forcing`` when there is none)."""
        return zero_forcing if self.forcing is None else self.forcing

    @property
    def length_scale(self) -> float:
        """Displacement scale ``L = max(|x0|, tau / k, A / k)`` used to set scipy's ``atol``."""
        amp = 0.0 if self.forcing is None else abs(self.forcing.amplitude)
        return max(abs(self.x0), self.osc.tau / self.osc.k, amp / self.osc.k)


_PAPER_OSC = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)

#: The four scenarios of the paper's Section 3.
PAPER_SCENES: tuple[BenchScene, ...] = (
    BenchScene("forcing-F1", _PAPER_OSC, 0.0, forcing=paper_F1,
               note="eq. (17a): stays stuck, x = 0 exactly"),
    BenchScene("forcing-F2", _PAPER_OSC, 0.0, forcing=paper_F2,
               note="eq. (17b): slips while forced, sticks after"),
    BenchScene("release-0.005", _PAPER_OSC, 0.005, note="k x0 < tau: never moves"),
    BenchScene("release-0.5", _PAPER_OSC, 0.5, note="free decay to a stretched rest"),
)

#: Variations: other k, gamma, tau, amplitude and frequency, and repeated stick/break-out.
OWN_SCENES: tuple[BenchScene, ...] = (
    BenchScene("stiff-k1e4", BinghamOscillator(1.0, 1e4, 1.0, 1.0), 0.01,
               note="k = 1e4 (w = 100), about 50 half-swings before sticking"),
    BenchScene("viscous-soft", BinghamOscillator(1.0, 10.0, 0.2, 0.5), 0.3,
               note="k = 10, gamma = 0.2, tau = 0.5: heavily damped slip"),
    BenchScene("near-coulomb", BinghamOscillator(1.0, 100.0, 1e3, 1.0), 0.3,
               note="gamma = 1e3: close to Coulomb friction"),
    BenchScene("high-yield-forced", BinghamOscillator(1.0, 100.0, 1.0, 5.0), 0.0,
               forcing=SineBurst(8.0, 3.0 * math.pi, 2.0),
               note="tau = 5, A = 8, w = 3 pi, off at t = 2"),
    BenchScene("fast-forcing", BinghamOscillator(1.0, 100.0, 5.0, 2.0), 0.0,
               forcing=SineBurst(20.0, 40.0 * math.pi, 3.0),
               note="A = 20 at 20 Hz, gamma = 5, tau = 2, off at t = 3"),
    BenchScene("stick-breakout", BinghamOscillator(1.0, 100.0, 1.0, 1.0), 0.0,
               forcing=SineBurst(1.5, 2.0 * math.pi, 4.0),
               note="A = 1.5 at 1 Hz, off at t = 4: sticks and breaks out twice per period"),
)

SCENES: tuple[BenchScene, ...] = PAPER_SCENES + OWN_SCENES


@dataclass(frozen=True)
class Ladders:
    """Settings swept by the benchmark.

    ``dts``: the step sizes of the fixed-step methods; ``eps`` x ``rtols``: the
    regularisation and tolerances of the tanh-regularised scipy peers; ``tol_rtols``: the
    tolerances of the tolerance-driven methods (the event-driven scipy peers, and any
    method of ours driven by ``rtol``/``atol`` that has no ladder of its own); ``atol`` is
    always ``rtol`` times the scene's displacement scale.
    """

    dts: tuple[float, ...]
    eps: tuple[float, ...]
    rtols: tuple[float, ...]
    tol_rtols: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-13)
    creep_t_end: float = 100.0
    creep_rtol: float = 1e-10
    max_nfev: int = 200_000
    min_time: float = 0.05
    slow_min_dt: float = 1e-4
    event_dts: tuple[float, ...] = tuple(1e-3 * 10.0 ** (-j / 6.0) for j in range(13))


FULL = Ladders(
    dts=(1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6),
    eps=(1e-5, 1e-7, 1e-9, 1e-11, 1e-13),
    rtols=(1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-13),
    tol_rtols=(1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13),
    max_nfev=50_000,
    slow_min_dt=2e-5,
)
QUICK = Ladders(
    dts=(1e-2, 1e-3, 1e-4, 1e-5),
    eps=(1e-5, 1e-9),
    rtols=(1e-6, 1e-10),
    tol_rtols=(1e-6, 1e-9, 1e-12),
    max_nfev=50_000,
    min_time=0.02,
    slow_min_dt=1e-3,
    event_dts=tuple(1e-3 * 10.0 ** (-j / 4.0) for j in range(5)),
)


def generic_scene(scene: BenchScene):
    """``scene`` as a :class:`lumped.scene.Scene`: one mass, a ``linear_spring`` and a
    ``bingham`` dashpot, both from ground to the mass, and the same forcing."""
    from ..laws import get_law
    from ..scene import Element, Mass, Scene

    o = scene.osc
    forces = {} if scene.forcing is None else {"mass": scene.forcing}
    return Scene(
        [Mass("mass", m=o.m, x0=scene.x0, v0=scene.v0)],
        [Element("spring", get_law("linear_spring").bind(k=o.k), "ground", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=o.gamma, tau=o.tau),
                 "ground", "mass")],
        forces,
    )


# --------------------------------------------------------------------------- reference


def reference_grid(scene: BenchScene, grid_dt: float = GRID_DT) -> np.ndarray:
    """Exact ``x`` on the common grid ``t_i = i * grid_dt``, ``0 <= t_i <= t_end``."""
    from ..reference import reference_for_grid

    traj = reference_for_grid(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.forcing,
                              dt=grid_dt, t_end=scene.t_end)
    return np.asarray(traj.x, dtype=float)


def check_ladders(ladders: Ladders, grid_dt: float = GRID_DT) -> None:
    """Every ``dt`` must divide the grid step or be a multiple of it."""
    for dt in ladders.dts:
        as_positive("dt", dt)
        r = grid_dt / dt
        q = r if r >= 1 else 1 / r
        if abs(q - round(q)) > 1e-9 * q:
            raise ValueError(f"`dt` = {dt!r} neither divides nor is a multiple of {grid_dt!r}")
