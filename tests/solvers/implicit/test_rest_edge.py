"""The edge of a dashpot's set at rest (:func:`lumped.solvers.implicit.initial_slip.rest_edge`):
Newton steps from outside, then bisection, give the one float at the edge."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped.laws import ElementLaw, get_law
from lumped.solvers.implicit.initial_slip import rest_edge


def _bisection(kernel, F: float) -> float:
    """The reference: the edge by bisection over the floats themselves, their bit patterns
    from ``0`` to ``|F|`` in order (an oracle apart from :func:`rest_edge`'s midpoints):
    the largest float on the segment with ``R(0, .) = 0``."""
    if not math.isfinite(F) or kernel(0.0, F)[0] == 0.0 or kernel(0.0, 0.0)[0] != 0.0:
        return F

    def at(k: int) -> float:
        return math.copysign(struct.unpack("<d", struct.pack("<q", k))[0], F)

    inside, outside = 0, struct.unpack("<q", struct.pack("<d", abs(F)))[0]
    while outside - inside > 1:
        mid = (inside + outside) // 2
        if kernel(0.0, at(mid))[0] == 0.0:
            inside = mid
        else:
            outside = mid
    return at(inside)


_SOFT = ElementLaw("soft_yield_edge", "dashpot", "q = gamma*Max(Abs(F) - tau, 0)**3*sign(F)",
                   ["gamma", "tau"])

#: ``(law, tau)``: the yield laws at a spread of numbers (bound once: a new law costs a
#: derivation in sympy, and the property is about the edge search, not the binding)
_LAWS = [(get_law("bingham").bind(gamma=g, tau=t), t)
         for g, t in ((0.3, 1.0), (7.0, 0.05), (1e3, 2.5), (1e9, 0.7))]
_LAWS += [(get_law("coulomb").bind(tau=t, r=r), t) for t, r in ((1.0, 1.0), (0.3, 40.0))]
_LAWS += [(get_law("herschel_bulkley").bind(gamma=g, tau=t, n=n), t)
          for g, t, n in ((0.5, 1.0, 0.3), (2.0, 0.2, 0.5), (9.0, 3.0, 1.0), (0.9, 0.04, 1.5),
                          (0.1, 1.0, 2.0), (40.0, 0.7, 3.0))]
_LAWS += [(_SOFT.bind(gamma=g, tau=t), t) for g, t in ((0.2, 0.5), (30.0, 4.0))]


@given(law=st.sampled_from(_LAWS), offset=st.floats(min_value=-50.0, max_value=2.0),
       sign=st.sampled_from([1.0, -1.0]))
def test_the_edge_is_the_bisections(law, offset, sign):
    bound, tau = law
    F = sign * (tau + tau * 10.0 ** offset)  # beyond the yield force by 1e-50 .. 100 tau
    got = rest_edge(bound.kernel, F)
    assert got == _bisection(bound.kernel, F)
    assert bound.kernel(0.0, got)[0] == 0.0
    beyond = math.nextafter(got, F)
    assert beyond == F or bound.kernel(0.0, beyond)[0] != 0.0


@pytest.mark.parametrize("F", [2.0, -2.0, 1.0 + 2**-40, 1.0 + 2**-52, 1e3])
def test_a_bingham_edge_in_a_few_kernel_calls(F):
    kernel = get_law("bingham").bind(gamma=3.0, tau=1.0).kernel
    calls = []

    def counted(q, f):
        calls.append(f)
        return kernel(q, f)

    assert rest_edge(counted, F) == math.copysign(1.0, F) == _bisection(kernel, F)
    assert len(calls) <= 5  # (the bisection alone: about 55)


def test_far_beyond_the_edge_newton_hands_over_to_the_bisection():
    # F - R / R_F rounds to 0 (1e300 - 1e300): no step inside the bracket, bisection
    kernel = get_law("bingham").bind(gamma=3.0, tau=1.0).kernel
    assert rest_edge(kernel, 1e300) == 1.0 == _bisection(kernel, 1e300)


def test_inside_or_not_finite_is_left():
    kernel = get_law("bingham").bind(gamma=3.0, tau=1.0).kernel
    assert rest_edge(kernel, 0.5) == 0.5
    assert rest_edge(kernel, math.inf) == math.inf
    assert math.isnan(rest_edge(kernel, math.nan))
    newtonian = get_law("newtonian").bind(c=2.0).kernel  # (R(0, 0) = 0 but not set-valued)
    assert rest_edge(newtonian, 3.0) == _bisection(newtonian, 3.0)
