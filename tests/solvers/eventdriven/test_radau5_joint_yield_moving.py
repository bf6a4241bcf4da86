"""``radau5`` on a mass that moves, then sticks on three yield dashpots in parallel to
ground with a load within ``1e-12`` to ``1e-9`` (relative) of the sum of their yield
forces (issue 29; the dashpots of ``test_radau5_joint_yield_excess.py``).

Released at ``x0`` with ``v0 = 0.3`` onto a spring (``k = 50``) to ground, the mass
slides, turns and sticks where the spring's force lies just within the joint yield
force; ``x0`` was found by the secant method on ``radau5`` at ``rtol = 1e-12`` (the rest
force ``1e-9`` and ``1e-12`` within). These ran through before the fixes of this series
too: they guard the static hold of such a rest
(:func:`lumped.solvers.modes.force_bounds.split_near_joint_bounds`) after motion."""

from __future__ import annotations

import pytest
from _joint_yield import JOINT, TAUS, M, joint_yield_laws

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

K, V0, T_END = 50.0, 0.3, 1.0
#: within -> x0: the rest force ``within`` (relative) inside the joint yield force
X0 = {1e-9: 0.016074830961074062, 1e-12: 0.016074830984330473}


def _scene(within: float) -> Scene:
    elements = [Element(f"e{k}", law, "ground", "m0") for k, law in enumerate(joint_yield_laws())]
    elements.append(Element("s", get_law("linear_spring").bind(k=K), "ground", "m0"))
    return Scene([Mass("m0", m=M, x0=X0[within], v0=V0)], elements)


@pytest.mark.parametrize("rtol", [1e-10, 1e-6])
@pytest.mark.parametrize("within", [1e-9, 1e-12])
def test_a_mass_that_sticks_near_the_joint_yield_force_after_moving(within, rtol):
    """The run goes through with at most one bridge; at the end the mass is at rest, the
    spring's force within ``1e-7`` of the joint yield force (the run's own rest position
    moves it by ``K`` times its position error), every dashpot within its yield band and
    the balance closed, to the forces' tolerance (the exact condition of a rest). (The
    rest position, ``0.0212120498`` at every ``rtol`` from ``1e-6`` to ``1e-12``, is
    ``bdf2``'s limit too: ``0.0212058``, ``...064``, ``...106``, ``...118``, ``...118``,
    ``...120`` at ``dt = 1/1600`` halved five times, too slow and uneven near the stick for a
    cheap test.)"""
    atol = 1e-3 * rtol
    sol = simulate(_scene(within), method="radau5", dt=T_END / 160, t_end=T_END, rtol=rtol,
                   atol=atol, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) <= 1, sol.message
    assert sol.stats["steps"] <= 400, sol.stats
    assert abs(sol.v["m0"][-1]) <= atol
    spring = -float(sol.F["s"][-1])  # (its force on the mass)
    assert JOINT * (1.0 - 1e-7) <= abs(spring) <= JOINT * (1.0 + rtol)
    total = spring
    for k, tau in enumerate(TAUS):
        Fk = float(sol.F[f"e{k}"][-1])
        assert abs(Fk) <= tau + rtol * JOINT, (k, abs(Fk) - tau)
        total -= Fk
    assert abs(total) <= rtol * JOINT
