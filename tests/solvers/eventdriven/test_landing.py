"""The bracket of a radau5 landing on a guard's root (:mod:`lumped.solvers.eventdriven.landing`)."""

from __future__ import annotations

import math

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from lumped.solvers.eventdriven.landing import MAX_PASSES, Landing


def _land(g, h_found: float, s_hit: float, tol: float = 1e-14) -> tuple[float, int]:
    """Drive a landing as the driver does: steps of the sizes it asks for, ``g(h)`` the
    guard at each step's end; the size it lands on and the passes taken."""
    landing = Landing((0, 0), h_found, g(h_found), h_found)
    h = s_hit * h_found
    while True:
        if landing.landed(g(h), tol, t=1.0):
            return h, landing.count
        h = landing.next_size(h, g(h), None)


@pytest.mark.parametrize("g", [lambda h: 0.3 - h, lambda h: math.cos(h) - math.cos(0.3),
                               lambda h: (0.3 - h) ** 3])
def test_a_landing_ends_on_the_root(g):
    h, count = _land(g, 1.0, 0.25)
    assert abs(g(h)) <= 1e-14 or h == pytest.approx(0.3, abs=1e-13)
    assert count < MAX_PASSES


def test_a_crossing_inside_the_step_moves_the_high_end_there():
    landing = Landing((0, 0), 1.0, -1.0, 1.0)
    landing.h_lo = 0.2
    # the guard crossed at s = 0.5 of a step of 0.8 whose end is back above 0
    h = landing.next_size(0.8, 0.1, 0.5)
    assert (landing.h_hi, landing.side) == (0.8, -1) and h == pytest.approx(0.4)
    # a crossing put a hair past the end that held: bisect the bracket
    h = landing.next_size(0.4, 0.1, 0.5000001)
    assert h == pytest.approx(0.5 * (0.2 + 0.4))


def test_a_failed_landing_step_closes_the_bracket():
    landing = Landing((0, 0), 1.0, -1.0, 1.0)
    assert landing.failed_stage(0.5, 1.0) is None  # no step held yet: the driver halves
    landing.h_lo = 0.25
    assert landing.failed_stage(0.5, 1.0) == pytest.approx(0.375)
    assert landing.h_hi == 0.5 and landing.count == 1
    assert landing.failed_stage(0.25 + 1e-16, 1.0) == 0.25  # closed: land on h_lo
    assert landing.h_hi == landing.h_lo


@pytest.mark.parametrize("depth", [0.0, -1e-9, 1e-9, 1e-6])
def test_a_dip_of_the_end_values_is_searched_in_a_few_tries(depth):
    # the guard at the end of a step of size h dips to -depth at h = 0.3 (issue 29: a
    # load at exactly, below or above a stuck lock's bound at its peak); the step of 0.4
    # crossed inside (its polynomial overshoots), its end held, and the polynomial put
    # the crossing at h = 0.25, before the dip
    def g(h):
        return 50.0 * (h - 0.3) ** 2 - depth

    landing = Landing((0, 0), 0.4, g(0.4), 0.4)
    h = 0.25
    while not landing.landed(g(h), 1e-14, 1.0, h, None):
        h = landing.next_size(h, g(h), None)
    assert landing.count <= 10  # (40 passes, the most, and a landing off the dip before)
    if depth > 0.0:  # the first root
        assert h == pytest.approx(0.3 - math.sqrt(depth / 50.0), abs=1e-11)
    else:  # the touch, or the guard's minimum, which holds
        assert h == pytest.approx(0.3, abs=1e-6) and g(h) >= -1e-14


def _dip(g, tol: float = 1e-14) -> tuple[float, Landing, list[tuple[float, bool]]]:
    """A landing driven as in the test above (a step of 0.4 crossed inside and its end
    held, the polynomial put the crossing at 0.25): the size it lands on, the landing, and
    per try its size and whether the dip was being searched after it."""
    landing = Landing((0, 0), 0.4, g(0.4), 0.4)
    h, tries = 0.25, []
    while True:
        done = landing.landed(g(h), tol, 1.0, h, None)
        tries.append((h, landing.dip))
        if done:
            return h, landing, tries
        h = landing.next_size(h, g(h), None)


def _skewed(depth: float):
    """End values that dip to ``-depth`` at ``h = 0.3``, not a parabola (the searches'
    parabolas miss its minimum: they take a few tries)."""
    return lambda h: 50.0 * (h - 0.3) ** 2 * (1.0 + (h - 0.3)) - depth


def test_a_dip_below_minus_tol_brackets_the_first_root():
    g = _skewed(1e-6)
    h, landing, tries = _dip(g)
    # held twice towards the high end (0.25, 0.325): the search starts; its third value
    # is below -tol: a root bracket (the search ends), refined on end values to the root
    assert [dip for _, dip in tries] == [False, True, True, True, False, False, False, False]
    assert g(tries[4][0]) < -1e-14 and not landing.poly
    assert landing.count == 7
    first = 0.3 - (1e-6 / 50.0) ** 0.5  # (to 1e-8: the cubic term)
    assert abs(g(h)) <= 1e-14 and h == pytest.approx(first, abs=2e-8)  # (not the second)


def test_a_dip_that_touches_zero_lands_within_tol():
    g = _skewed(0.0)
    h, landing, tries = _dip(g)
    # no value below -tol: the search goes on to a value within tol, the touch (the
    # parabolas through the three lowest values: 8 passes through the lowest one's
    # neighbours, which kept the far value at 0.25)
    assert [dip for _, dip in tries] == [False] + [True] * 6
    assert landing.count == 6 and not landing.final
    assert 0.0 <= g(h) <= 1e-14 and h == pytest.approx(0.3, abs=1e-7)


def test_a_clear_minimum_above_zero_ends_the_search_on_the_lowest_value():
    g = _skewed(-1e-3)  # the minimum holds by 1e-3
    h, landing, tries = _dip(g)
    # the second parabola's vertex is met at what it promised, within half its height
    # above tol, and the third's vertex value exceeds tol by more than twice what it
    # promises below: the search lands on that lowest value (the full laws choose). (The
    # first parabola's vertex, 0.2983, came out 6.6e-3 above its promise: not yet)
    assert [dip for _, dip in tries] == [False, True, True, True]
    assert landing.count == 3 and landing.final
    assert h == min(landing.seen, key=lambda p: p[1])[0] and g(h) > 1e-3


@pytest.mark.parametrize("g", [lambda h: 1.0 - h, lambda h: 1.0 + 1e-3 * h],
                         ids=["falling to the high end", "flat"])
def test_end_values_that_do_not_dip_start_no_search(g):
    h, landing, tries = _dip(g)
    # the lowest value is at the high end, or not below half of its neighbours: no dip
    # search; the bracket is bisected towards the high end until the passes are spent
    assert not any(dip for _, dip in tries) and landing.poly
    assert landing.count == MAX_PASSES
    assert all(hk == pytest.approx(0.5 * (prev + 0.4), rel=1e-12)
               for (prev, _), (hk, _) in zip(tries, tries[1:], strict=False))
    assert 0.4 - h < 1e-12 and landing.h_hi == pytest.approx(0.4, rel=1e-15)


def test_a_clear_minimum_is_not_read_off_a_parabola_that_misses_a_dip_below_zero():
    # end values that dip to -1e-6 at h = 0.3, skewed five times as much as _skewed: the
    # parabola through 0.25, 0.2932 and 0.325 has its vertex value (1.7e-3) above the
    # lowest value by less than half of it, but the value met at 0.2932 had come out
    # 3.7e-2 above the first parabola's promise. The search used to end there, on a value
    # that holds (2.2e-3), and the step crossed the guard's first root near h = 0.29986
    # unseen; the search goes on to a value below -tol and lands on that root
    def g(h):
        return 50.0 * (h - 0.3) ** 2 * (1.0 + 5.0 * (h - 0.3)) - 1e-6

    h, landing, _ = _dip(g)
    first = 0.3 - (1e-6 / 50.0) ** 0.5  # (to 1e-7: the cubic term)
    assert abs(g(h)) <= 1e-14 and h == pytest.approx(first, abs=1e-7)
    assert landing.count <= 10


def test_a_dip_skewed_the_other_way_is_found_too():
    # the mirror: steep on the low side. The first parabola (0.25, 0.325, 0.4) promised
    # 2.4e-2 at 0.315, less than half of that below 0.325's value (2.7e-2): the search
    # used to land on 0.325 after one pass, over the first root near 0.29986
    def g(h):
        return 50.0 * (h - 0.3) ** 2 * (1.0 - 5.0 * (h - 0.3)) - 1e-6

    h, landing, tries = _dip(g)
    first = 0.3 - (1e-6 / 50.0) ** 0.5
    assert abs(g(h)) <= 1e-14 and h == pytest.approx(first, abs=1e-7)
    assert landing.count <= 10 and any(g(hk) < -1e-14 for hk, _ in tries)


@pytest.mark.parametrize("skew", [5.0, -5.0])
def test_a_skewed_dip_that_holds_ends_clear_in_a_few_passes(skew):
    # the same dips 1e-3 above zero: the search must still end on its lowest value,
    # without spending DIP_TRIES values, near the minimum
    def g(h):
        return 50.0 * (h - 0.3) ** 2 * (1.0 + skew * (h - 0.3)) + 1e-3

    h, landing, _ = _dip(g)
    assert landing.final and landing.count <= 5
    assert h == min(landing.seen, key=lambda p: p[1])[0]
    assert 1e-3 <= g(h) <= 1.1e-3


def test_a_root_bracket_after_a_dip_search_starts_at_a_value_that_held():
    # a guard noisier than its tolerance (a random network's, issue 29: 4e-13 and
    # -5.6e-12 at steps 5e-10 apart, tol 1.9e-14) met a value below zero at 0.3 before
    # the search, which then meets the same value at 0.4: the root bracket's low end was
    # the value at 0.3, and the Illinois secant divided by g_lo - g_hi = 0
    landing = Landing((0, 0), 1.0, 0.5, 1.0)
    landing.seen = [(0.2, 1e-3), (0.3, -1e-12), (0.5, 2e-3), (1.0, 0.5)]
    landing.dip, landing.poly, landing.h_lo = True, False, 0.1
    assert not landing.landed(-1e-12, 1e-14, 1.0, 0.4, None)
    assert (landing.h_lo, landing.g_lo) == (0.2, 1e-3) and not landing.dip
    h = landing.next_size(0.4, -1e-12, None)
    assert 0.2 < h < 0.4 and landing.h_hi == 0.4


@settings(max_examples=150)
@given(h_min=st.floats(0.27, 0.37), skew=st.floats(-10.0, 10.0),
       scale=st.floats(0.1, 100.0), depth=st.floats(-1e-2, 1e-2))
def test_a_dip_search_never_lands_beyond_a_crossing(h_min, skew, scale, depth):
    # end values ``scale (h - h_min)^2 exp(skew (h - h_min)) - depth``: where the dip is
    # searched, it lands on the first root when the dip goes below zero by more than
    # tol, on a value that holds otherwise, and never after a value below zero
    def g(h):
        return scale * (h - h_min) ** 2 * math.exp(skew * (h - h_min)) - depth

    h, landing, tries = _dip(g)
    assume(any(dip for _, dip in tries))
    grid = [0.25 + (h - 0.25) * n / 2000 for n in range(2001)]
    assert min(map(g, grid)) >= -1e-14 * max(1.0, scale)  # no crossing before h
    if depth > 1e-14:
        assert abs(g(h)) <= 1e-14 and h < h_min  # the first root
    assert landing.count <= 15
