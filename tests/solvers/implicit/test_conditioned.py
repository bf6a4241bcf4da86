"""The laws in their conditioned form (:mod:`lumped.solvers.implicit.conditioned`): a
steep branch solved for its force, read at the yield force where the force of a tiny
rate rounds to it."""

from __future__ import annotations

import math
import sys

import pytest

from lumped.codegen.branches import law_branches
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.implicit.conditioned import conditioned_kernels, conditioned_law

_EPS = sys.float_info.epsilon
_GAMMA, _TAU = 0.3694690741303337, 1.0


def _hb(n: float = 0.5):
    return get_law("herschel_bulkley").bind(gamma=_GAMMA, tau=_TAU, n=n)


def test_a_rate_whose_force_rounds_to_the_yield_force_reads_the_slip_branch():
    """``q = -3.1e-9``: its force ``-tau - (q/gamma)^2 = -1 - 7e-17`` rounds to ``-tau``,
    where the law reads its stuck branch (residual ``q``) and the slip branch one ulp
    beyond has the residual ``q + gamma sqrt(2.2e-16) = +2.4e-9``: no float zeroes the
    forward form. The conditioned law reads the slip branch's inverse form there, which
    holds at ``F = -tau`` to the rounding of its terms, with ``dR/dF = 1``."""
    law = _hb()
    q = -3.111386254896798e-09
    assert law.kernel(q, -_TAU)[0] == q  # the stuck branch: off by all of q
    beyond = math.nextafter(-_TAU, -math.inf)
    assert law.kernel(q, beyond)[0] > 0.5 * abs(q)  # and across the root one ulp on
    kernel = conditioned_law(law_branches(law), law.kernel)
    R, _, RF = kernel(q, -_TAU)
    assert abs(R) <= 8.0 * _EPS * kernel.magnitude(q, -_TAU)
    assert RF == 1.0


@pytest.mark.parametrize(("q", "F"), [(3.1e-9, -_TAU), (0.0, -_TAU), (0.0, 0.3),
                                      (-3.1e-9, -0.5)])
def test_elsewhere_the_conditioned_law_reads_the_law_s_branch(q, F):
    """A rate of the wrong sign at ``-tau`` (the slip branch's stage guard is negative),
    rest at the yield force and inside it (the stuck branch holds), a rate deep inside the
    stuck interval: the law's own branch, as :meth:`~lumped.codegen.branches.LawBranches.
    stage_law_for` evaluates it."""
    law = _hb()
    lb = law_branches(law)
    assert conditioned_law(lb, law.kernel)(q, F) == lb.stage_law_for(law.kernel)(q, F)


def test_only_laws_with_a_steep_branch_are_replaced():
    """A linear spring and a Bingham dashpot with ``gamma tau < 16`` have no steep
    branch: a scene of them keeps its kernels (``None``); beside a Herschel-Bulkley
    ``n < 1`` dashpot only that one is replaced."""
    spring = Element("s", get_law("linear_spring").bind(k=100.0), "ground", "m")
    bingham = Element("d", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m")
    plain = Scene([Mass("m", m=1.0, x0=0.0)], [spring, bingham])
    assert conditioned_kernels(plain) is None
    hb = Element("h", _hb(0.3), "ground", "m")
    kernels = conditioned_kernels(Scene([Mass("m", m=1.0, x0=0.0)], [spring, bingham, hb]))
    assert kernels is not None
    assert kernels[0] is spring.law.kernel and kernels[1] is bingham.law.kernel
    assert kernels[2] is not hb.law.kernel
