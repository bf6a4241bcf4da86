"""One rule for "a ``v0`` the limit step reverses or stops starts at rest" in the closed
form: :func:`lumped.solvers.closed.closed_form.limit_step_velocity`, which
:func:`~lumped.solvers.closed.closed_form.initial_velocity` calls and the compiled
summaries (``closed_form_jit.summary_one``, ``simulate_many``) compile from its code
(before: a copy written out again in the compiled loop)."""

from __future__ import annotations

import pytest

from lumped.solvers.closed import closed_form as ref
from lumped.solvers.closed import closed_form_jit as J


def test_the_compiled_summaries_compile_the_reference_rule():
    assert J._limit_step_velocity.py_func is ref.limit_step_velocity


# ((m, k, inv_gamma, tau, x0, v0, F0, h), the velocity of row 0)
CASES = [
    ((1.0, 100.0, 1.0, 1.0, 0.0, 1e-113, -3.0, 1e-24), 0.0),   # reversed: at rest
    ((1.0, 100.0, 1.0, 1.0, 0.0, 1e-17, -3.0, 1e-24), 1e-17),  # beyond the step: kept
    ((1.0, 100.0, 1.0, 1.0, 0.0, -1e-113, 0.5, 1e-24), 0.0),   # a load within the band
    ((1.0, 100.0, 1e-12, 1.0, 0.01, 5e-324, -1.0, 1e-20), 0.0),
    ((1.0, 100.0, 1.0, 1.0, 0.0, 0.0, 5.0, 1e-24), 0.0),       # at rest
]


@pytest.mark.parametrize(("args", "want"), CASES)
def test_the_rule_gives_the_same_velocity_in_python_and_compiled(args, want):
    assert ref.limit_step_velocity(*args) == want
    assert J._limit_step_velocity(*args) == want
    osc = ref.BinghamOscillator(m=args[0], k=args[1], gamma=1.0 / args[2], tau=args[3])
    assert ref.initial_velocity(osc, *args[4:]) == want
