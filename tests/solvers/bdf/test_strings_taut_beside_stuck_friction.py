"""A loaded mass stopped by two taut strings in series, beside stuck friction (issue 29).

A draw of ``jit-bdf1``'s property (seed 22320 of the ``long`` profile, after 6116 passing
draws of that method): ``m1`` under a constant load of ``46.7`` hangs by a string
(``e1``) on ``m0``, which a Coulomb element, a dashpot and a second string (``e3``) hold
to ground. At ``t = 0.4749`` ``e3`` goes taut: both masses stop, ``m0`` at ``x = L3``
exactly and ``m1`` one ulp short of ``L1`` beyond it, and the Coulomb element sticks in
parallel with ``e3`` (a free split of their forces). The backward-Euler substep after
the impact then had every row at the rounding of its terms, but ``e1``'s lock row
flipped between ``+-1.1e-16`` (the position lattice) and asked ``m1``'s velocity for
``1.4e-12`` and the forces for ``m ulp(x) / h^2 = 1.9e-8`` at every iteration: Newton
ran out of iterations, and ``bdf1``, ``jit-bdf1`` (at ``dt = 0.025 / 4``), ``bdf2`` and
``jit-bdf2`` (at ``dt = 0.025 / 8``) stopped. Newton now takes a row at round-off that
its full correction does not reduce as solved (it took only rows left bit for bit).
"""

from __future__ import annotations

import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

L1, L3, TAU = 0.7392651608827139, 0.8080679732701407, 0.03305771895959975


def _stopped_by_two_strings() -> Scene:
    def law(name, **values):
        return get_law(name).bind(**values)

    return Scene(
        [Mass("m0", m=5.113807607241006), Mass("m1", m=1.0, x0=0.7087443848781669),
         Mass("m2", m=5.113807607241006, x0=-0.5288629175189737)],
        [Element("e0", law("coulomb", tau=TAU, r=1.0), "ground", "m0"),
         Element("e1", law("string_spring", k=34.5408082143737, L=L1), "m0", "m1"),
         Element("e2", law("herschel_bulkley", gamma=1.2589254117941673,
                           tau=0.03207627619041544, n=2.0), "m1", "m2"),
         Element("e3", law("string_spring", k=1.2589254117941673, L=L3), "ground", "m0"),
         Element("e4", law("newtonian", c=1.0), "ground", "m0"),
         Element("e5", law("string_spring", k=0.5890606274633191, L=2.237607302397141),
                 "m2", "m1")],
        {"m1": 46.66684212242399})


@pytest.mark.parametrize("method, dt", [("bdf1", 0.025 / 4), ("bdf2", 0.025 / 8),
                                        ("jit-bdf1", 0.025 / 4), ("jit-bdf2", 0.025 / 8)])
def test_two_strings_stop_a_loaded_mass_beside_stuck_friction(method, dt):
    sol = simulate(_stopped_by_two_strings(), method=method, dt=dt, t_end=0.5)
    assert sol.ok, sol.message
    # e1 goes taut at 0.0619 and e3 at 0.4778 (bdf2 at dt / 64); each method's impact
    # within its step of those
    assert [(e.element, e.kind) for e in sol.events] == [("e1", "impact"), ("e3", "impact")]
    assert abs(sol.events[0].t - 0.0619) <= 2.0 * dt
    assert abs(sol.events[1].t - 0.4778) <= 2.0 * dt
    # then both masses rest on their strings, the Coulomb element stuck within its band
    assert abs(sol.x["m0"][-1] - L3) <= 1e-12
    assert abs(sol.x["m1"][-1] - sol.x["m0"][-1] - L1) <= 1e-12
    assert abs(sol.v["m0"][-1]) <= 1e-9 and abs(sol.v["m1"][-1]) <= 1e-9
    assert abs(sol.F["e0"][-1]) <= TAU * (1.0 + 1e-9)
    # m2 is dragged by the Herschel-Bulkley dashpot (within the method's error)
    assert abs(sol.x["m2"][-1] - (-0.48483)) <= 2e-3
