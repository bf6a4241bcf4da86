"""What a run with **new numbers** no longer makes again (issue 27): kept per structure or
per law class, never per number. Counted, never timed; and every run gives the numbers
of a run from scratch, whatever ran before and in whatever order."""

from __future__ import annotations

import numpy as np
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped import simulate
from lumped.codegen import jit, parametric, rebound, scene_numbers, templates
from lumped.codegen.branches import LawBranches, law_branches
from lumped.codegen.jit import jit_scene, position_locks
from lumped.codegen.templates import law_template
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.eventdriven.setup import clear_plans
from lumped.solvers.implicit import initial_state

try:
    from lumped.solvers.implicit import initial_kept
except ImportError:  # (the code before: nothing kept)
    initial_kept = None
from lumped.solvers.implicit.initial_state import consistent_initial_state


def _released(k: float, x0: float = 0.3, friction: bool = False) -> Scene:
    """``viscous-soft`` of the bench (k = 10, gamma = 0.2, tau = 0.5, x0 = 0.3): the
    dashpot slips from rest, it does not stay at rest (its initial force, its yield
    force, is read without Newton). With ``friction``, a Coulomb dashpot beside it: two
    forces left to one mass's balance, the initial state takes Newton."""
    elements = [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                Element("dashpot", get_law("bingham").bind(gamma=0.2, tau=0.5), "ground",
                        "mass")]
    if friction:
        elements.append(Element("friction", get_law("coulomb").bind(tau=0.25, r=10.0),
                                "ground", "mass"))
    return Scene([Mass("mass", m=1.0, x0=x0)], elements)


def _same_run(a, b) -> None:
    assert np.array_equal(a.data, b.data) and a.columns == b.columns
    assert a.stats == b.stats and (a.status, a.message) == (b.status, b.message)
    assert a.events == b.events


def _from_scratch() -> None:
    clear_plans()
    templates._BY_LAW.clear()
    getattr(jit, "_ARRAYS", {}).clear()
    if initial_kept is not None:
        initial_kept.forget()


def test_a_run_solves_its_initial_state_once(monkeypatch):
    """The start at rest is tried first and the general driver runs: one Newton solve of
    the initial state, not one each (counted)."""
    calls = []
    limit = initial_state._limit_system
    monkeypatch.setattr(initial_state, "_limit_system",
                        lambda *a: calls.append(1) or limit(*a))
    for k in (10.000123, 10.000456):  # new numbers each
        sol = simulate(_released(k, friction=True), t_end=1.0, method="radau5", rtol=1e-6,
                       compiled=False)
        assert sol.stats["initial_newton_iterations"] > 0
    assert len(calls) == 2


def test_the_kept_initial_state_is_a_copy_and_reads_its_arguments():
    scene = _released(10.000789)
    v, F, stats = consistent_initial_state(scene, time_scale=1.0)
    want = (list(v), list(F), dict(stats))
    v[0], F[0], stats["newton_iterations"] = 7.0, 7.0, -1  # a caller's edits
    assert consistent_initial_state(scene, time_scale=1.0) == want
    other = consistent_initial_state(scene, time_scale=3.0)  # another argument: solved
    _from_scratch()
    assert consistent_initial_state(scene, time_scale=3.0) == other


def test_a_new_law_of_a_class_swaps_no_expression_until_one_is_read(monkeypatch):
    """The branches of a law bound to new numbers come from its class with no sympy: its
    expressions are swapped when first read, and equal a derivation's from scratch."""
    law = get_law("bingham")
    for gamma in (2.3000001, 2.3000002):  # the class: its first two laws
        law_branches(law.bind(gamma=gamma, tau=1.7))
    swaps = []
    swap = rebound.swap
    monkeypatch.setattr(rebound, "swap", lambda *a: swaps.append(1) or swap(*a))
    bound = law.bind(gamma=2.3000003, tau=1.7)
    lb = law_branches(bound)
    assert isinstance(lb, parametric.ReboundBranches)
    assert [info.locks for info in lb.info] and not swaps
    scratch = LawBranches(bound.kernel.expressions[0])
    assert lb.info == scratch.info and scratch.info == lb.info and swaps
    assert all(a.path == b.path and a.dR_dF == b.dR_dF for a, b in zip(
        lb.info, scratch.info, strict=True))


def _string(L: float, k: float) -> Scene:
    return Scene(
        [Mass("m", m=1.0, x0=0.0), Mass("n", m=2.0, x0=0.05)],
        [Element("s", get_law("string_spring").bind(k=k, L=L), "m", "n"),
         Element("d", get_law("bingham").bind(gamma=1.3, tau=0.7), "ground", "m")],
    )


def test_a_structures_arrays_are_made_once_and_its_numbers_read_per_scene(monkeypatch):
    calls = []
    monkeypatch.setattr(scene_numbers, "position_locks",
                        lambda s: calls.append(s) or position_locks(s))
    monkeypatch.setattr(jit, "_ARRAYS", {}, raising=False)
    scenes = [_string(0.25 + 0.01 * j, 50.0 + j) for j in range(3)]
    got = [jit_scene(s) for s in scenes]
    assert len(calls) == 1  # the first scene's structure; the others read it
    for s, js in zip(scenes, got, strict=True):
        assert np.array_equal(js.lock_q, position_locks(s), equal_nan=True)
        assert js.module is got[0].module and js.ea is got[0].ea
        assert np.array_equal(js.masses, [1.0, 2.0])
    assert got[0].lock_q[0, ~np.isnan(got[0].lock_q[0])].tolist() == [0.25]
    assert got[2].lock_q[0, ~np.isnan(got[2].lock_q[0])].tolist() == [0.27]


def test_runs_with_new_numbers_in_any_order_as_from_scratch():
    makes = [lambda: _released(10.0 + 1e-4), lambda: _released(10.0 + 2e-4, x0=0.2),
             lambda: _string(0.25, 50.0), lambda: _string(0.26, 51.0)]
    kw = {"t_end": 0.6, "method": "radau5", "rtol": 1e-6, "compiled": False}
    forward = [simulate(make(), **kw) for make in makes]
    backward = [simulate(make(), **kw) for make in reversed(makes)][::-1]
    for i, make in enumerate(makes):
        _from_scratch()
        scratch = simulate(make(), **kw)
        _same_run(forward[i], scratch)
        _same_run(backward[i], scratch)


@settings(max_examples=60, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False).filter(lambda x: x != 0.0))
def test_the_class_key_reads_sympys_order_of_floats_in_plain_python(x):
    assert parametric.float_content(x) == sp.Float(x)._hashable_content()


def test_a_new_law_of_a_class_makes_no_sympy_float(monkeypatch):
    """Binding new numbers finds the law's class in plain floats: its kernel, branches
    and template make no sympy number (counted)."""
    law = get_law("bingham")
    for gamma in (3.3000001, 3.3000002):  # the class: its first two laws
        bound = law.bind(gamma=gamma, tau=1.9)
        law_template(bound), law_branches(bound).kernel_for(0), bound.kernel
    made = []
    real = sp.Float
    monkeypatch.setattr(sp, "Float", lambda *a, **k: made.append(a) or real(*a, **k))
    bound = law.bind(gamma=3.3000003, tau=1.9)
    assert parametric.class_key(bound) is not None
    law_template(bound), law_branches(bound).kernel_for(0), bound.kernel(0.1, 2.0)
    assert not made


def test_a_released_scene_reads_no_rest_mode(monkeypatch):
    """A mass whose net force at t = 0 is no round-off is not at rest: the start at rest
    stops there, before reading a mode (counted); the run is the general driver's."""
    from lumped.solvers.eventdriven import rest_start

    modes = []
    real = rest_start.rest_mode
    monkeypatch.setattr(rest_start, "rest_mode", lambda *a: modes.append(1) or real(*a))
    sol = simulate(_released(10.000321), t_end=0.5, method="radau5", rtol=1e-6,
                   compiled=False)
    assert not modes and sol.stats["loop"] != "none: at rest throughout (no steps)"
    at_rest = simulate(_released(10.000321, x0=0.01), t_end=0.5, method="radau5",
                       rtol=1e-6, compiled=False)  # k x0 = 0.1 < tau: held, mode read
    assert modes and at_rest.stats["loop"] == "none: at rest throughout (no steps)"


@settings(max_examples=60, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False).filter(lambda x: x != 0.0))
def test_a_sympy_float_made_from_its_content_is_sympys(x):
    got, want = parametric.sympy_float(x), sp.Float(x)
    assert type(got) is type(want) and got == want and float(got) == x
    assert got._hashable_content() == want._hashable_content() and hash(got) == hash(want)


def _never_moving(name: str):
    from lumped.bench.scenes import PAPER_SCENES, generic_scene

    bench = {s.name: s for s in PAPER_SCENES}[name]
    return generic_scene(bench), bench.t_end


def test_new_numbers_make_no_structure_part_again(monkeypatch):
    """A run with new numbers (every spring's ``k`` new) takes the parts of its plan that
    depend on the structure alone from the first scene of that structure: the static
    balance's structure of the mode, the forcing's kinds, the elements on cycles (counted);
    and it swaps no sympy expression of its law's class."""
    from lumped.bench.new_numbers import scene_with_new_numbers
    from lumped.scene import forcing_jit
    from lumped.solvers.eventdriven import fast_parts
    from lumped.solvers.eventdriven.setup import scene_plan
    from lumped.solvers.modes import stuck
    from lumped.solvers.nonsmooth import locks

    base, t_end = _never_moving("forcing-F1")
    kw = {"t_end": t_end, "method": "radau5", "rtol": 1e-7, "compiled": False}
    for _ in range(3):  # a class's first two laws are derived; the third is its class's
        simulate(scene_with_new_numbers(base), **kw)
    calls = {"structure": 0, "forcing": 0, "cycles": 0, "swap": 0}

    def counted(module, name, what):
        real = getattr(module, name)

        def fn(*a, **k):
            calls[what] += 1
            return real(*a, **k)

        monkeypatch.setattr(module, name, fn)

    counted(stuck, "_structure", "structure")
    counted(forcing_jit, "forcing_arrays", "forcing")
    counted(locks, "cyclic_elements", "cycles")
    counted(rebound, "swap", "swap")
    scenes = [scene_with_new_numbers(base) for _ in range(3)]
    sols = [simulate(scene, **kw) for scene in scenes]
    assert all(s.stats["loop"] == "none: at rest throughout (no steps)" for s in sols)
    # the compiled loop's check for locks in parallel reads the structure's part too
    assert not any(fast_parts.locks_in_parallel(scene_plan(s)) for s in scenes)
    assert calls == {"structure": 0, "forcing": 0, "cycles": 0, "swap": 0}


def test_runs_with_new_numbers_sharing_a_structure_as_from_scratch():
    """Runs of scenes that share a structure's parts (new ``k``, any order) give the
    numbers of a run from scratch: the never-moving bench scenes and a string."""
    from lumped.bench.new_numbers import scene_with_new_numbers

    cases = []
    for name in ("release-0.005", "forcing-F1"):
        base, t_end = _never_moving(name)
        cases += [(scene_with_new_numbers(base, 1.0 + 1e-6 * j), t_end) for j in (1, 2, 3)]
    cases += [(_string(0.25 + 0.01 * j, 50.0 + 0.5 * j), 0.6) for j in (1, 2, 3)]
    kw = {"method": "radau5", "rtol": 1e-6, "compiled": False}
    forward = [simulate(s, t_end=t, **kw) for s, t in cases]
    _from_scratch()
    backward = [simulate(s, t_end=t, **kw) for s, t in reversed(cases)][::-1]
    for (scene, t_end), a, b in zip(cases, forward, backward, strict=True):
        _from_scratch()
        scratch = simulate(scene, t_end=t_end, **kw)
        _same_run(a, scratch)
        _same_run(b, scratch)


def test_a_scene_run_at_rest_is_not_kept_alive():
    """What a run at rest keeps on the scene's plan (its start, the static balances)
    holds no reference to the scene: once the user drops it, it is freed (a sweep of new
    numbers kept every scene and its plan for good)."""
    import gc
    import weakref

    from lumped.bench.new_numbers import scene_with_new_numbers

    base, t_end = _never_moving("forcing-F1")
    scene = scene_with_new_numbers(base)
    sol = simulate(scene, t_end=t_end, method="radau5", rtol=1e-7, compiled=False)
    assert sol.stats["loop"] == "none: at rest throughout (no steps)"
    ref = weakref.ref(scene)
    del scene, sol
    gc.collect()
    assert ref() is None


def _ranks(keys: list) -> tuple[int, ...]:
    order = {k: r for r, k in enumerate(sorted(set(keys)))}
    return tuple(order[k] for k in keys)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e300,
                          max_value=1e300).filter(lambda x: x != 0.0), min_size=2,
                max_size=2))
def test_the_class_key_is_sympys_order_of_the_floats(values):
    """The class key of a law's numbers (made in plain floats, the content of ``-v`` from
    that of ``v``) is the order sympy gives the floats ``+-v_j`` (from ``sympy.Float``)."""
    from lumped.codegen.float_keys import numbers_key

    law = get_law("bingham")
    got = numbers_key(law, tuple(values))
    if got is None:  # (an integral value or 0.5: derived from scratch)
        assert any(v.is_integer() or abs(v) == 0.5 for v in values)
        return
    pm = [s * v for v in values for s in (1.0, -1.0)]
    assert got[2] == _ranks(pm) and got[3] == _ranks([sp.Float(x)._hashable_content()
                                                      for x in pm])
    one = numbers_key(get_law("linear_spring"), (values[0],))
    assert one[2] == _ranks(pm[:2]) and one[3] == _ranks([sp.Float(x)._hashable_content()
                                                          for x in pm[:2]])


def test_a_law_bound_again_to_its_numbers_builds_no_kernel(monkeypatch):
    """A scene with new numbers binds every law anew: those whose numbers did not change
    (the dashpot of a new ``k``) take the kernel of the law already bound to them, no
    function is built (counted), and their runs are those from scratch."""
    from lumped.codegen import rebinding

    dashpot = get_law("bingham")
    first = dashpot.bind(gamma=0.2, tau=0.5000123)
    first.kernel(0.1, 1.0)
    built = []
    real = rebinding.Lifted.build
    monkeypatch.setattr(rebinding.Lifted, "build",
                        lambda self, values, **kw: built.append(values) or real(self, values,
                                                                               **kw))
    again = dashpot.bind(gamma=0.2, tau=0.5000123)
    assert again is not first and again.kernel(0.1, 1.0) == first.kernel(0.1, 1.0)
    assert not built
    scene = _released(10.000654)
    kept = simulate(scene, t_end=1.0, method="radau5", rtol=1e-6, compiled=False)
    _from_scratch()
    parametric._REBOUND.clear()
    _same_run(kept, simulate(_released(10.000654), t_end=1.0, method="radau5", rtol=1e-6,
                             compiled=False))


def _steep(name: str, tau: float, k: float = 10.0) -> Scene:
    """A dashpot with a steep branch and no inverse form (``radau5`` refuses it, issue
    11), named ``name``, beside a spring ``k``."""
    from lumped.laws import ElementLaw

    law = _STEEP.setdefault("law", ElementLaw(
        "two_powers", "dashpot", "q - Piecewise((sqrt(F - tau) + (F - tau)**2, F > tau),"
        " (-sqrt(-F - tau) - (-F - tau)**2, F < -tau), (0, True))", ["tau"]))
    return Scene([Mass("m", m=1.0, x0=0.5)],
                 [Element("s", get_law("linear_spring").bind(k=k), "ground", "m"),
                  Element(name, law.bind(tau=tau), "ground", "m")])


_STEEP: dict = {}


def test_the_refusal_is_read_per_structure_and_names_each_scene(monkeypatch):
    """Whether ``radau5`` refuses a scene is kept with its structure (the branches' flags
    of its laws' classes); the message of each refused scene is its own (its element's
    name and numbers), and a scene it takes with new numbers walks no branch for it
    (counted)."""
    from lumped.bench.new_numbers import scene_with_new_numbers
    from lumped.solvers.eventdriven import setup

    for name, tau in (("d", 1.0), ("brake", 1.5), ("d", 2.5)):
        scene = _steep(name, tau)
        plan = setup.scene_plan(scene)
        assert plan.refused == setup.scope_error(scene)  # (the message from scratch)
        assert f"element {name!r}" in plan.refused and "two_powers" in plan.refused
    calls = []
    real = setup.scope_error
    monkeypatch.setattr(setup, "scope_error", lambda *a: calls.append(1) or real(*a))
    base = _released(10.0)
    setup.scene_plan(scene_with_new_numbers(base))  # the structure's first plan
    calls.clear()
    plans = [setup.scene_plan(scene_with_new_numbers(base)) for _ in range(3)]
    assert [p.refused for p in plans] == [None] * 3
    assert calls == []
    refused = setup.scene_plan(_steep("e", 3.5, k=11.0)).refused
    assert "element 'e'" in refused and calls == [1]


def test_the_branches_kept_per_bound_law_are_bounded(monkeypatch):
    """A sweep of new numbers binds a law per point: at most ``_REMEMBERED`` of their
    branches are kept (they were all kept for good: 45 objects a run with new numbers),
    and a law whose branches were dropped gets them anew, the same."""
    from lumped.codegen import branches

    monkeypatch.setattr(branches, "_REMEMBERED", 8, raising=False)
    law = get_law("linear_spring")
    laws = [law.bind(k=10.0 + 0.001 * j) for j in range(20)]
    first = [law_branches(b) for b in laws]
    assert len(branches._CACHE) <= 8
    again = law_branches(laws[0])  # dropped: made anew
    assert again.info == first[0].info and again.count == first[0].count
    assert [again.branch(0.1, 2.0), again.guards_for(0)(0.1, 2.0)] == [
        first[0].branch(0.1, 2.0), first[0].guards_for(0)(0.1, 2.0)]
