"""``radau5`` on a junction whose Herschel-Bulkley ``n < 1`` dashpot stops in finite time
(issue 29, :mod:`lumped.solvers.modes.finite_stop`).

A junction ``j1`` between a Herschel-Bulkley dashpot to ground (``q = v_j``) and a linear
spring to ground (``F = -k x_j``), released with the spring's force beyond the yield force:
its balance ``F_1 = -k x_j`` and the law give, with ``delta = k x_j - tau``,

.. math::

    \\delta' = -k \\gamma\\, \\delta^n, \\qquad
    \\delta(t) = \\bigl(\\delta_0^{1-n} - (1 - n) k \\gamma t\\bigr)^{1/(1-n)},

until ``delta = 0`` at ``t* = delta_0^{1-n} / ((1 - n) k gamma)``; then the dashpot
sticks at its yield force and ``x_j = tau / k`` for good. Near ``t*``, ``delta ~ (t* -
t)^{1/(1-n)}`` (``(t* - t)^5`` at ``n = 0.8``). Before the fix, the runs at ``rtol``
``1e-3`` and ``5e-4`` (``n = 0.8``, ``0.9``) and ``1e-4`` (``n = 0.9``) landed again and
again on the dashpot's guard, the full laws kept it slipping, and the run crept on until
its work budget stopped it (the ``LUMPED_LARGE`` draw of the Python-loop property did the
same at ``t = 0.285``, 19 490 passes for 499 steps).
"""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

K, GAMMA, TAU, XJ0 = 10.0, 10.0, 0.1, 0.05
T_END = 0.2
#: A work budget of 2000 passes: more than 20 times what every run here takes.
MAX_STEPS = 2000


def _scene(n: float) -> Scene:
    return Scene([Mass("m0", m=1.0), Junction("j1", x0=XJ0)],
                 [Element("e0", get_law("linear_spring").bind(k=1.0), "ground", "m0"),
                  Element("e1", get_law("herschel_bulkley").bind(gamma=GAMMA, tau=TAU, n=n),
                          "ground", "j1"),
                  Element("e2", get_law("linear_spring").bind(k=K), "j1", "ground")])


def _exact_x(n: float, t: np.ndarray) -> np.ndarray:
    """The junction's exact position (see the module notes)."""
    d0 = K * XJ0 - TAU
    s = np.maximum(d0 ** (1.0 - n) - (1.0 - n) * K * GAMMA * t, 0.0)
    return (TAU + s ** (1.0 / (1.0 - n))) / K


@pytest.mark.parametrize("n", [0.8, 0.9])
@pytest.mark.parametrize("rtol", [1e-3, 5e-4, 1e-4, 1e-6])
def test_a_junction_dashpot_stopping_in_finite_time_sticks(n: float, rtol: float) -> None:
    """The run ends without a bridge within a few tens of passes, the dashpot stuck at its
    yield force from its last switch on (the junction at rest to ``atol``, ``|F| <= tau``
    to round-off), and the junction's position
    within the run's position tolerance ``atol + rtol x`` of the exact one throughout."""
    atol = rtol ** 1.5
    sol = simulate(_scene(n), method="radau5", dt=0.01, t_end=T_END, rtol=rtol, atol=atol,
                   compiled=False, max_steps=MAX_STEPS)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.stats["steps"] + sol.stats["rejected"] <= 100, sol.stats
    stops = [ev for ev in sol.events if ev.element == "e1"]
    assert stops and stops[-1].kind == "switch", sol.events
    t_stop = stops[-1].t
    after = np.asarray(sol.t) > t_stop
    assert after.any()
    assert np.all(np.abs(np.asarray(sol.v["j1"])[after]) <= atol)
    assert np.all(np.abs(np.asarray(sol.F["e1"])[after]) <= TAU * (1.0 + 1e-12))
    err = np.abs(np.asarray(sol.x["j1"]) - _exact_x(n, np.asarray(sol.t))).max()
    assert err <= atol + rtol * XJ0, err
