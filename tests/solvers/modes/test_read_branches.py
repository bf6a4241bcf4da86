"""The probe's branch read (:func:`lumped.solvers.modes.mode_guess.read_branches`): the held
branch where its stage guards are all positive, else the law's own read (issue 29)."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from lumped.codegen.branches import law_branches
from lumped.laws import get_law
from lumped.solvers.modes.mode_guess import read_branches

TAU = 0.31622776601683794


def _hb():
    return law_branches(get_law("herschel_bulkley").bind(gamma=1.0, tau=TAU, n=0.3))


def test_a_herschel_bulkley_dashpot_starting_to_slip_reads_as_slipping():
    lb = _hb()
    # slipping at 2e-9, its force tau + 1e-29 rounds to tau: the law reads "stuck"
    assert lb.branch(2e-9, TAU) == 2
    assert read_branches([lb], [0], [2e-9], [TAU]) == [0]
    # ... but not as slipping the other way (the spurious root of seed 22228), nor
    # slipping at a rate of 0 or below
    assert read_branches([lb], [1], [2e-9], [-TAU]) == [lb.branch(2e-9, -TAU)] != [1]
    assert read_branches([lb], [0], [0.0], [TAU]) == [2]
    assert read_branches([lb], [0], [-1e-12], [TAU]) == [2]


_STEEP = [get_law("herschel_bulkley").bind(gamma=1.0, tau=TAU, n=0.3),
          get_law("herschel_bulkley").bind(gamma=0.05, tau=2.0, n=0.5),
          get_law("bingham").bind(gamma=1e6, tau=1.0),
          get_law("bingham").bind(gamma=1e12, tau=0.3)]
_PLAIN = [get_law("bingham").bind(gamma=1.0, tau=1.0),
          get_law("coulomb").bind(tau=0.5, r=1.0),
          get_law("linear_spring").bind(k=3.0)]
_finite = st.floats(-10.0, 10.0, allow_nan=False)


@given(law=st.sampled_from(_STEEP), q=_finite, data=st.data())
def test_a_point_on_a_steep_slip_branch_reads_as_it_by_its_rate(law, q, data):
    lb = law_branches(law)
    held = data.draw(st.sampled_from([i for i, info in enumerate(lb.info)
                                      if info.stage is not None]), label="held")
    k = lb.stage_kernel_for(held)
    F = -k(q, 0.0)[0]  # (the inverse form F - G(q): the force on the branch at rate q)
    assert abs(k(q, F)[0]) <= 4e-16 * (1.0 + abs(F))
    # inside the branch: slipping the way of its force at rate 0 (+tau or -tau), the
    # sign relation; else on its odd continuation
    inside = q != 0.0 and (q > 0.0) == (-k(0.0, 0.0)[0] > 0.0)
    read = read_branches([lb], [held], [q], [F])[0]
    assert (read == held) == inside
    if read != lb.branch(q, F):  # (the law's read in F: stuck where F rounds to tau)
        assert abs(abs(F) - law.params["tau"]) <= 1e-12 * law.params["tau"]


@given(law=st.sampled_from(_PLAIN), q=_finite, F=_finite, data=st.data())
def test_on_branches_without_an_inverse_form_the_read_is_the_laws(law, q, F, data):
    lb = law_branches(law)
    held = data.draw(st.integers(0, lb.count - 1), label="held")
    assert lb.stage_guards_for(held) is lb.guards_for(held)
    assert read_branches([lb], [held], [q], [F]) == [lb.branch(q, F)]
