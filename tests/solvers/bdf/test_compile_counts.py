"""What a run of ``jit-bdf1``/``jit-bdf2`` on the faithful port compiles (counted with
numba's event API, never timed).

The port's loop (:mod:`lumped.solvers.bdf.core_jit`) and its step system
(:mod:`lumped.codegen.step_dispatch`) are compiled once per machine; each element's law is
reached through the law module of its template (compiled once per law template). So a new
structure whose laws' templates are compiled compiles nothing, and a new law template
compiles its law module only. Each test warms what it depends on first: the tests run in
any order, in any worker.
"""

from __future__ import annotations

import numpy as np
import pytest
from _compile_events import compiles as _compiles  # (numba's compile events)

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.codegen.jit import numba_enabled
from lumped.laws import ElementLaw
from lumped.scenarios import scenario_scene
from lumped.scene import SineBurst
from lumped.solvers.bdf import fast_codegen

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the compiled port needs numba")


def _warm() -> None:
    """The port, its step system and the paper's laws' law modules (compiled or loaded)."""
    sol = simulate(scenario_scene("forcing-F2"), method="jit-bdf2", dt=1e-2, t_end=0.3,
                   fast=False)
    assert sol.ok


def _chain(n: int, spring) -> Scene:
    """``n`` masses in a chain, each link a spring (``spring(i)``) beside the paper's
    Bingham dashpot (``gamma = tau = 1``: its template), the burst on the first mass: a
    structure no other test builds."""
    damp = get_law("bingham").bind(gamma=1.0, tau=1.0)
    nodes = [Mass(f"p{i}", m=1.0 + 0.2 * i, x0=0.0) for i in range(n)]
    elements = []
    for i in range(n):
        a = "ground" if i == 0 else f"p{i - 1}"
        elements += [Element(f"k{i}", spring(i), a, f"p{i}"),
                     Element(f"d{i}", damp, a, f"p{i}")]
    return Scene(nodes, elements, {"p0": SineBurst(9.0, 6.0, 0.8)})


def _new_structure(monkeypatch) -> None:
    """Its fast loop never built (on this machine): a short run takes the port."""
    monkeypatch.setattr(fast_codegen, "fast_module_cached", lambda scene, key=None: False)


@pytest.mark.parametrize("method", ["jit-bdf1", "jit-bdf2"])
def test_a_new_structure_of_compiled_laws_compiles_nothing(monkeypatch, method):
    from lumped.codegen import module_cache

    _warm()
    lin = get_law("linear_spring")
    scene = _chain(2, lambda i: lin.bind(k=60.0 + 7.0 * i))  # the paper's laws' templates
    _new_structure(monkeypatch)
    modules = len(module_cache.LOADED_MODULES)
    kw = dict(method=method, dt=1e-2, t_end=2.0)
    with _compiles() as names:
        got = simulate(scene, **kw)
    assert got.ok and got.stats["steps"] == 200
    assert "fast_steps" not in got.stats  # the faithful port took the run
    # before: the structure's generated module (``lumped_jit_<hash>``: its ``evaluate``
    # and ``element_law``), about 1 s of CPU; now the port's structure-generic step
    # system reaches the laws through the header of the constants: no compile, no module
    assert names == []
    assert len(module_cache.LOADED_MODULES) == modules
    # the reference's numbers and counters (6 unknowns: bit for bit)
    ref = simulate(scene, method=method.removeprefix("jit-"), dt=1e-2, t_end=2.0)
    assert np.array_equal(got.data, ref.data)
    assert {k: got.stats[k] for k in ref.stats} == ref.stats


#: A law no other test uses: its template is compiled only by the test below.
_NEW_LAW = ElementLaw("only_in_the_bdf_compile_counts", "spring", "F = k*q + c*q**3",
                      ["k", "c"])


def test_a_new_law_compiles_its_law_module_only(monkeypatch, tmp_path):
    from lumped.codegen.template_module import law_addresses, law_module_text
    from lumped.codegen.templates import law_template

    _warm()
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))  # (no generated module on disk)
    for el in scenario_scene("forcing-F2").elements:  # the paper's law modules, here
        law_addresses(law_template(el.law))
    scene = _chain(2, lambda i: _NEW_LAW.bind(k=50.0 + i, c=2.0))
    _new_structure(monkeypatch)
    with _compiles() as names:
        got = simulate(scene, method="jit-bdf2", dt=1e-2, t_end=1.0)
    assert got.ok and "fast_steps" not in got.stats
    from lumped.codegen.module_cache import module_name

    ours = module_name(law_module_text(law_template(scene.elements[0].law)))
    assert {n.rsplit(".", 1)[0] for n in names if not n.startswith("numba.")} == {ours}
    assert {f"{ours}.t_full", f"{ours}.t_mag"} <= set(names)
    ref = simulate(scene, method="bdf2", dt=1e-2, t_end=1.0)
    assert np.array_equal(got.data, ref.data)
