"""A junction's Herschel-Bulkley dashpot starting to slip at the start (issue 29).

A draw of the property of both loops (seed 22228 of the ``long`` profile, after 7321
passing draws): a loaded mass ``m2`` hangs by a stuck Bingham dashpot on junction ``j1``,
which a Herschel-Bulkley dashpot (``n = 0.3``) holds to ground at exactly its yield force
``tau``, moving at ``1e-9``. Slipping at that rate its force is ``tau + 1e-30``, which
rounds to ``tau``, where the law reads its stuck branch: the mode guess "slipping" was
refused, and the full search took a spurious root on the *other* slip branch's odd
continuation (``F = -tau`` at a positive rate). Every step crossed a guard at once:
8 kept modes, 4 bridges by backward Euler, a stop at ``1.5e-8`` s in both loops, at
each of the property's tolerances. The probe now reads a branch inside its stage guards
as held (:func:`lumped.solvers.modes.mode_guess.read_branches`).
"""

from __future__ import annotations

import numpy as np
import pytest
from _yielding_junction import TAU
from _yielding_junction import yielding_junction as _yielding_junction

from lumped import simulate


@pytest.fixture(scope="module")
def reference():
    return simulate(_yielding_junction(), method="bdf2", dt=0.025 / 64, t_end=0.5)


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("level", [0, 1, 2])
def test_a_junction_starting_to_slip_at_its_yield_force_runs_through(compiled, level,
                                                                      reference):
    h = 0.025 / 2**level  # (the property's grid: rtol = h^2, atol = h^3)
    sol = simulate(_yielding_junction(), method="radau5", dt=h, t_end=0.5, rtol=h**2,
                   atol=h**3, compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0 and sol.stats["steps"] <= 40  # (15, 17, 20)
    # the Herschel-Bulkley dashpot slips forward from the start (its force at +tau, not
    # -tau), and the Bingham link breaks out once, at t = 0.4584
    assert sol.F["e1"][1] >= TAU and np.all(np.diff(sol.x["j1"]) > 0.0)
    assert [(e.element, e.kind) for e in sol.events] == [("e2", "switch")]
    assert abs(sol.events[0].t - 0.458358) <= 1e-5
    for name in ("j0", "j1", "m2", "j3"):  # (within 9e-7 of bdf2 at dt/64, its own error)
        assert np.abs(sol.x[name] - reference.x[name][::2**(6 - level)]).max() <= 3e-6
