"""The numerical examples of Section 3 of the paper, as named built-in scenarios.

All four use ``gamma = 1``, ``mu_s N_f = 1``, ``m = 1``, ``k = 100``; the paper steps
them with ``dt = 1e-4``.  The names are part of the command-line contract:

=================  =============================================  ==========
name               forcing                                        x(0), v(0)
=================  =============================================  ==========
``forcing-F1``     F1 = 0.5 sin(5 pi t) on [0, 1], 0 after (17a)  0, 0
``forcing-F2``     F2 = 10 sin(5 pi t) on [0, 1], 0 after (17b)   0, 0
``release-0.005``  none                                           0.005, 0
``release-0.5``    none                                           0.5, 0
=================  =============================================  ==========
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .scene import GROUND, Element, Mass, Scene
from .scene.forcing import paper_F1, paper_F2, zero_forcing
from .simulate import simulate
from .solvers.closed.closed_form import BinghamOscillator
from .trajectory import Trajectory

__all__ = [
    "Scenario",
    "PAPER_OSCILLATOR",
    "PAPER_SCENARIOS",
    "PAPER_DT",
    "PAPER_T_END",
    "PAPER_METHODS",
    "get_scenario",
    "run_scenario",
    "scenario_scene",
]

#: Methods the paper scenarios run with; the first, the paper's Algorithm 1, is the default.
PAPER_METHODS = ("closed-bdf1", "closed-bdf2", "bdf1", "bdf2", "auto", "exact")

#: The paper's parameters (Section 3): gamma = 1, mu_s N_f = 1, m = 1, k = 100.
PAPER_OSCILLATOR = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)
PAPER_DT = 1e-4
PAPER_T_END = 5.0


@dataclass(frozen=True)
class Scenario:
    """A single-mass Bingham problem: parameters, initial state and forcing."""

    name: str
    osc: BinghamOscillator
    x0: float
    v0: float
    forcing: Callable[[float], float]
    description: str


PAPER_SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario("forcing-F1", PAPER_OSCILLATOR, 0.0, 0.0, paper_F1,
                 "F1 = 0.5 sin(5 pi t) on [0, 1] (eq. 17a): stays stuck, eq. (19)"),
        Scenario("forcing-F2", PAPER_OSCILLATOR, 0.0, 0.0, paper_F2,
                 "F2 = 10 sin(5 pi t) on [0, 1] (eq. 17b): stick-slip, Figures 6-9"),
        Scenario("release-0.005", PAPER_OSCILLATOR, 0.005, 0.0, zero_forcing,
                 "x(0) = 0.005, F = 0: k x(0) < mu_s N_f, never moves (Figure 10)"),
        Scenario("release-0.5", PAPER_OSCILLATOR, 0.5, 0.0, zero_forcing,
                 "x(0) = 0.5, F = 0: decays, rests with a stretched spring (Figures 11-14)"),
    )
}


def get_scenario(name: str) -> Scenario:
    """Return the built-in scenario called ``name``; ``ValueError`` lists the known names."""
    try:
        return PAPER_SCENARIOS[name]
    except (KeyError, TypeError):
        known = ", ".join(PAPER_SCENARIOS)
        raise ValueError(f"unknown scenario {name!r}; known scenarios: {known}") from None


def scenario_scene(scenario: Scenario | str) -> Scene:
    """The scenario as a :class:`~lumped.scene.Scene`: a mass ``"mass"`` joined to ground by
    a ``"spring"`` (``linear_spring``) and a ``"dashpot"`` (``bingham``)."""
    from .laws import get_law

    s = get_scenario(scenario) if isinstance(scenario, str) else scenario
    return Scene(
        [Mass("mass", s.osc.m, x0=s.x0, v0=s.v0)],
        [
            Element("spring", get_law("linear_spring").bind(k=s.osc.k), GROUND, "mass"),
            Element("dashpot", get_law("bingham").bind(gamma=s.osc.gamma, tau=s.osc.tau),
                    GROUND, "mass"),
        ],
        forces={"mass": s.forcing},
    )


def run_scenario(
    scenario: Scenario | str,
    *,
    method: str = "closed-bdf1",
    dt: float = PAPER_DT,
    t_end: float = PAPER_T_END,
) -> Trajectory:
    """Run a scenario with any method of :data:`PAPER_METHODS` and return its trajectory.

    ``closed-bdf1`` (the default) is the paper's Algorithm 1, ``closed-bdf2`` its BDF2 twin,
    ``bdf1``/``bdf2`` the generic Newton solver, ``auto`` what :func:`lumped.simulate`
    picks, and ``exact`` the event-driven reference of :mod:`lumped.reference`.
    """
    s = get_scenario(scenario) if isinstance(scenario, str) else scenario
    if method not in PAPER_METHODS:
        raise ValueError(f"`method` must be one of {PAPER_METHODS}, got {method!r}")
    sol = simulate(scenario_scene(s), method=method, dt=dt, t_end=t_end)
    return Trajectory(
        t=sol.t, x=sol.x["mass"], v=sol.v["mass"], F_s=sol.F["spring"], F_d=sol.F["dashpot"],
        method=sol.method, stats=sol.stats,
    )
