"""What ``radau5``'s compiled loop compiles (counted with numba's event API, never timed).

The shared loop (:mod:`lumped.solvers.eventdriven.loop_jit`) is compiled once per machine
and takes the structure-generic kernels of :mod:`lumped.codegen.dispatch` as addresses,
which reach each element's law template module through the constants' header: new
numbers compile nothing, a new structure whose laws' templates are compiled compiles
nothing, a new law template compiles its template module only; the fold test of a law
that is not a known monotone one, and the code of a table forcing, are compiled for such
a scene only. The compiled helpers of the events (the mode probe, the break-out scan and
root of a stuck interval, an attempt's crossing root) are compiled only once a process
needs them often (:mod:`lumped.solvers.modes.on_demand`), so a first run on a fresh
machine does not pay for them; with or without them a run gives the Python loop's
numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from _compile_events import compiles as _compiles

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.bench.impact_scenes import impact_scene
from lumped.codegen.jit import njit, numba_enabled
from lumped.io import Table
from lumped.laws import ElementLaw
from lumped.scene.forcing import SineBurst
from lumped.solvers.eventdriven import attempt_root_jit, first_step_jit, loop_jit
from lumped.solvers.eventdriven import fast as fast_mod
from lumped.solvers.modes import mode_guess_jit, on_demand, stuck_jit

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")

KW = dict(method="radau5", t_end=3.0, rtol=1e-8, atol=1e-11)


def _same_run(got, ref) -> None:
    """The Python loop's run: its steps, counters and events, its output to round-off (a
    stuck element's force after an event, as in ``test_radau_loop_jit``)."""
    for key in ("steps", "rejected", "newton_iterations", "factorizations", "events"):
        assert got.stats[key] == ref.stats[key], key
    assert [(e.element, e.kind, e.to_branch) for e in got.events] == [
        (e.element, e.kind, e.to_branch) for e in ref.events]
    scale = np.maximum(np.abs(ref.data).max(axis=0), 1e-300)
    assert np.all(np.abs(got.data - ref.data) <= 1e-11 * scale)


def _paper(k: float = 100.0, tau: float = 1.0) -> Scene:
    return Scene([Mass("mass", m=1.0, x0=0.0)],
                 [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=tau), "ground",
                          "mass")],
                 {"mass": SineBurst(10.0, 5.0 * np.pi, 1.0)})


def _fresh_helpers(monkeypatch, cache_dir) -> None:
    """The event helpers as on a machine that never compiled them: none in this process,
    numba's disk cache for new dispatchers in ``cache_dir`` (empty)."""
    from numba.core import config

    for mod, name in ((stuck_jit, "_COMPILED"), (stuck_jit, "_SCAN"),
                      (mode_guess_jit, "_COMPILED"), (attempt_root_jit, "_ROOT"),
                      (first_step_jit, "_FIRST")):
        monkeypatch.setattr(mod, name, [], raising=False)
    for name, make in (("_SCAN", "compiled_breakout_scan"), ("_ROOT", "compiled_breakout_root"),
                       ("_PROBE", "compiled_probe_modes"),
                       ("_ATTEMPT_ROOT", "compiled_attempt_root"),
                       ("_FIRST_STEP", "compiled_first_step")):
        owner = {"_ATTEMPT_ROOT": attempt_root_jit, "_PROBE": mode_guess_jit,
                 "_FIRST_STEP": first_step_jit}.get(name, stuck_jit)
        monkeypatch.setattr(fast_mod, name, on_demand.OnDemand(getattr(owner, make)),
                            raising=False)
    monkeypatch.setattr(config, "CACHE_DIR", str(cache_dir))


def test_a_compiled_run_with_few_events_compiles_none_of_the_event_helpers(
        monkeypatch, tmp_path):
    # the shared loop and this structure's kernels, once (the disk cache as a user has it)
    warm = simulate(_paper(), compiled=True, **KW)
    assert warm.stats["loop"] == "compiled"
    ref = simulate(_paper(k=103.0, tau=1.1), compiled=False, **KW)
    _fresh_helpers(monkeypatch, tmp_path)
    with _compiles() as names:
        got = simulate(_paper(k=103.0, tau=1.1), compiled=True, **KW)
    # new numbers on a known structure: no compilation at all; the run's few events take
    # the Python references of the probe and the break-out (before: about 5 s of CPU for
    # them on a fresh machine)
    assert names == []
    assert got.stats["loop"] == "compiled" and got.ok
    assert len(got.events) >= 2
    _same_run(got, ref)


def test_an_edit_from_one_to_another_number_compiles_nothing(monkeypatch, tmp_path):
    # gamma = 1 and k = 1 used to be templates of their own (sympy dropped the integer
    # factor 1 from the code): the paper's scene edited to gamma = 0.8 compiled a law
    # module (0.5-0.8 s) or ran the Python loop
    from lumped.codegen.template_module import template_module
    from lumped.codegen.templates import law_template

    bingham, spring = get_law("bingham"), get_law("linear_spring")
    for one, other in ((bingham.bind(gamma=1.0, tau=1.0), bingham.bind(gamma=0.8, tau=1.0)),
                       (spring.bind(k=1.0), spring.bind(k=1.3))):
        assert template_module(law_template(one)) is template_module(law_template(other))
    simulate(_paper(), compiled=True, **KW)  # the shared loop; gamma = 1's templates
    edited = Scene(_paper().nodes,
                   [Element("spring", spring.bind(k=1.0), "ground", "mass"),
                    Element("dashpot", bingham.bind(gamma=0.8, tau=0.05), "ground", "mass")],
                   {"mass": SineBurst(1.0, 2.0, 1.0)})
    _fresh_helpers(monkeypatch, tmp_path)
    with _compiles() as names:
        got = simulate(edited, **KW)  # compiled=None: compiled from step 0
    assert names == []
    assert got.stats["loop"] == "compiled" and got.ok and len(got.events) >= 2
    _same_run(got, simulate(edited, compiled=False, **KW))


def _chain(n: int, spring) -> Scene:
    """``n`` masses in a chain, each link a spring (``spring(i)``, a bound law) and the
    paper's Bingham dashpot, the burst on the last but one
    mass: a structure no other test builds."""
    damp = get_law("bingham").bind(gamma=1.0, tau=1.0)
    nodes = [Mass(f"q{i}", m=1.0 + 0.1 * i, x0=0.0) for i in range(n)]
    elements = []
    for i in range(n):
        a = "ground" if i == 0 else f"q{i - 1}"
        elements += [Element(f"k{i}", spring(i), a, f"q{i}"), Element(f"d{i}", damp, a, f"q{i}")]
    return Scene(nodes, elements, {f"q{n - 2}": SineBurst(12.0, 7.0, 0.8)})


def test_a_new_structure_of_compiled_templates_compiles_nothing(monkeypatch, tmp_path):
    from lumped.codegen import module_cache

    simulate(_paper(), compiled=True, **KW)  # the shared loop; the paper's laws' templates
    lin = get_law("linear_spring")
    scene = _chain(4, lambda i: lin.bind(k=40.0 + i))  # (those templates, other numbers)
    _fresh_helpers(monkeypatch, tmp_path)  # (no event helper compiled in the run)
    modules = len(module_cache.LOADED_MODULES)
    with _compiles() as names:
        got = simulate(scene, compiled=True, method="radau5", t_end=0.5, rtol=1e-6)
    assert got.stats["loop"] == "compiled" and got.ok
    # before: the structure's generated module (``lumped_jit_<hash>``) was compiled,
    # about 0.5-1 s of CPU; now the structure-generic kernels reach the templates'
    # compiled code through the header of the constants: no compile, no module
    assert names == []
    assert len(module_cache.LOADED_MODULES) == modules
    ref = simulate(scene, compiled=False, method="radau5", t_end=0.5, rtol=1e-6)
    assert np.array_equal(got.data, ref.data)
    assert simulate(scene, method="radau5", t_end=0.5, rtol=1e-6).stats["loop"] == "compiled"


#: A law no other test uses: its template is compiled only by the test below.
_NEW_TEMPLATE = ElementLaw("only_in_the_compile_counts", "spring", "F = k*q + c*q**5",
                           ["k", "c"])


def test_a_new_law_template_compiles_its_template_module_only(monkeypatch, tmp_path):
    from lumped.codegen.template_module import template_addresses, template_module
    from lumped.codegen.templates import law_template
    from lumped.solvers.radau import step_jit

    simulate(_paper(), compiled=True, **KW)  # the shared loop
    # ... and the fold test, shared code that this law (not a known monotone one) needs:
    # compiled (or loaded) here, whatever ran before in this process
    step_jit.fold_test()
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))  # (no template module on disk)
    for el in _paper().elements:  # the paper's laws' templates, in this cache
        template_addresses(law_template(el.law))
    scene = _chain(3, lambda i: _NEW_TEMPLATE.bind(k=30.0 + i, c=0.5))
    with _compiles() as names:
        got = simulate(scene, compiled=True, method="radau5", t_end=0.5, rtol=1e-6)
    assert got.stats["loop"] == "compiled" and got.ok
    # the new law's template module: its three dispatchers (and the kernels they call,
    # compiled apart: the branch selector); no shared code, no module of the structure
    ours = template_module(law_template(scene.elements[0].law)).__name__
    assert {n.rsplit(".", 1)[0] for n in names if not n.startswith("numba.")} == {ours}
    assert {f"{ours}.t_law", f"{ours}.t_guards", f"{ours}.t_select"} <= set(names)
    ref = simulate(scene, compiled=False, method="radau5", t_end=0.5, rtol=1e-6)
    assert np.array_equal(got.data, ref.data)


def test_the_fold_test_is_compiled_for_a_law_not_known_monotone_only(monkeypatch):
    from lumped.solvers.radau import step_jit

    monkeypatch.setattr(step_jit, "_FOLD", [])  # as in a process that never needed it
    paper = simulate(_paper(), compiled=True, **KW)  # a linear spring and Bingham
    assert paper.stats["loop"] == "compiled"
    assert step_jit._FOLD == []
    s_shaped = Scene([Mass("mass", m=0.01, x0=-6.0)],
                     [Element("s", get_law("s_shaped").bind(q0=1.0, F0=1.0), "ground", "mass"),
                      Element("damper", get_law("newtonian").bind(c=0.05), "ground", "mass")],
                     {"mass": SineBurst(9.0, 0.25)})
    got = simulate(s_shaped, method="radau5", t_end=8.0, rtol=1e-8, throw=False, compiled=True)
    assert got.stats["loop"] == "compiled" and got.status.value == "branch_lost"
    assert step_jit._FOLD != []


@pytest.mark.parametrize("helpers", ["compiled", "python"])
def test_the_event_helpers_compiled_or_not_give_the_python_loop_run(monkeypatch, helpers):
    if helpers == "compiled":
        monkeypatch.setattr(on_demand, "AFTER", 1)  # compiled (or loaded) at the first call
    else:
        for name in ("_SCAN", "_ROOT", "_PROBE", "_ATTEMPT_ROOT", "_FIRST_STEP"):
            monkeypatch.setattr(fast_mod, name, on_demand.OnDemand(lambda compile: None))
    scene = impact_scene()
    kw = dict(method="radau5", t_end=1.5, rtol=1e-8, atol=1e-11)
    ref = simulate(scene, compiled=False, **kw)
    got = simulate(scene, compiled=True, **kw)
    assert got.stats["loop"] == "compiled"
    _same_run(got, ref)
    if helpers == "compiled":
        assert fast_mod._PROBE.fn is not None or fast_mod._SCAN.fn is not None


#: The table's code (:func:`lumped.scene.forcing_jit.linear_value` and its helpers).
_TABLE_CODE = ("linear_value", "_table_value", "_segment")


def test_the_shared_loops_forcing_types_no_table_code():
    # the forcing function the shared loop calls, compiled afresh (no disk cache): none of
    # numba's passes runs on the table's code (on main the whole table interpolation was
    # inlined at numba's IR level, typed and lowered for every scene: about 1.2 s)
    from numba.core import event, types

    arg = {"t": types.float64, "fkind": types.int64[::1], "fpar": types.float64[:, ::1],
           "table": types.int64, "f": types.float64[::1]}
    py_func = loop_jit.forces.py_func
    sig = tuple(arg[name] for name in py_func.__code__.co_varnames[:py_func.__code__.co_argcount])
    with event.install_recorder("numba:run_pass") as rec:
        fresh = njit(py_func)
        fresh.compile(sig)
    passed_on = {ev.data["qualname"] for _, ev in rec.buffer if ev.is_start}
    assert "forces" in passed_on
    assert not passed_on & set(_TABLE_CODE), passed_on


def _tabled(k: float = 100.0) -> Scene:
    ts = np.linspace(0.0, 1.0, 41)
    table = Table(ts, 10.0 * np.sin(5.0 * np.pi * ts), quantity="force")
    return Scene([Mass("mass", m=1.0, x0=0.0)],
                 [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground",
                          "mass")],
                 {"mass": table})


def _compiled_for_such_a_scene_only(monkeypatch, module, store: str, scene: Scene,
                                    t_end: float) -> None:
    """``module.<store>`` (a helper compiled on demand) stays empty for the paper scene's
    compiled run, and is filled by ``scene``'s, which gives the Python loop's run."""
    monkeypatch.setattr(module, store, [])  # as in a process that never needed it
    assert simulate(_paper(), compiled=True, **KW).stats["loop"] == "compiled"
    assert getattr(module, store) == []
    kw = dict(method="radau5", t_end=t_end, rtol=1e-8, atol=1e-11)
    ref = simulate(scene, compiled=False, **kw)
    got = simulate(scene, compiled=True, **kw)
    assert got.stats["loop"] == "compiled"
    assert getattr(module, store) != []
    _same_run(got, ref)


def test_the_table_code_is_compiled_for_a_scene_with_a_table_only(monkeypatch):
    from lumped.solvers.radau import forces_jit

    _compiled_for_such_a_scene_only(monkeypatch, forces_jit, "_TABLE", _tabled(), 1.5)


def _maxwell_bingham() -> Scene:
    """A mass on a spring in series with a Bingham dashpot through a massless junction."""
    return Scene([Mass("mass", m=1.0, x0=0.0), Junction("j", x0=0.0)],
                 [Element("dashpot", get_law("bingham").bind(gamma=2.0, tau=1.0), "ground",
                          "j"),
                  Element("spring", get_law("linear_spring").bind(k=50.0), "j", "mass"),
                  Element("wall", get_law("linear_spring").bind(k=20.0), "ground", "mass")],
                 {"mass": SineBurst(6.0, 4.0, 1.0)})


def test_the_shared_loops_stage_newton_calls_no_roundoff_test():
    # the stage Newton of the shared loop, typed afresh for the loop's arguments: it does not
    # call the junctions' round-off test (on main it did, which compiled it with the loop
    # for every scene); it reaches it through an address, given only for junctions
    from numba.core import types

    from lumped.codegen.function_types import BRANCH_LAW_TYPE

    f8, i8 = types.float64, types.int64
    v, m, a2, iv = f8[::1], f8[:, ::1], f8[:, :], i8[::1]
    sig = (BRANCH_LAW_TYPE, v, v, iv, iv, types.boolean[::1], m, iv, m, m, v, f8, v, v, a2, v,
           f8, i8, v, a2, a2, iv, v, v, iv)
    from lumped.solvers.radau.stage_jit import stage_solve

    fresh = njit(stage_solve)
    fresh.compile(sig)
    typemap = fresh.overloads[sig].type_annotation.typemap
    called = {ty.dispatcher.py_func.__name__ for ty in typemap.values()
              if isinstance(ty, types.Dispatcher)}
    assert "stage_evaluate" in called
    assert "roundoff_worst_jit" not in called


def test_the_junctions_roundoff_test_is_compiled_for_a_scene_with_a_junction_only(
        monkeypatch):
    from lumped.solvers.radau import stage_jit

    _compiled_for_such_a_scene_only(monkeypatch, stage_jit, "_ROUNDOFF", _maxwell_bingham(),
                                    2.0)
