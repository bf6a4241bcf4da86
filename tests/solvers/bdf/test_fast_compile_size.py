"""What a new structure's fast loop costs to compile, counted, not timed (issue 27).

numba's compile time grows with the statements of the function it compiles (typing and
lowering each one; its SSA pass with blocks times variables). The generated fast loop
(:mod:`lumped.solvers.bdf.fast_codegen`) used to hold the step's inverse in ``n^2``
unrolled locals, so its source, and the first run of a new structure, grew like ``n^2``
(7 s of CPU for the 9 unknowns of the 3-mass chain). These tests hold the source to
linear growth in the unknowns, and count the compilations of a new structure: each
generated function once, and nothing for new numbers.
"""

from __future__ import annotations

from collections import Counter

from lumped import Element, Mass, Scene, simulate
from lumped.laws import get_law
from lumped.scene.forcing import SineBurst


def chain(n: int, k_factor: float = 1.0) -> Scene:
    """``n`` masses in series, each link a linear spring beside a Bingham dashpot, the last
    mass driven by a sine burst: ``3 n`` unknowns a step."""
    nodes, elements = [], []
    for i in range(1, n + 1):
        a, b = ("ground" if i == 1 else f"m{i - 1}"), f"m{i}"
        nodes.append(Mass(b, m=1.0 + 0.1 * i))
        elements += [Element(f"s{i}", get_law("linear_spring").bind(k=30.0 * k_factor), a, b),
                     Element(f"d{i}", get_law("bingham").bind(gamma=1.0, tau=0.5 + 0.1 * i),
                             a, b)]
    return Scene(nodes, elements, {f"m{n}": SineBurst(4.0, 6.0, 0.05)})


def test_the_fast_loop_source_grows_linearly_with_the_unknowns():
    """Characters of the generated module for chains of 3 to 6 masses (9 to 18 unknowns):
    each added mass adds the same amount of code, to within a few percent (its forcing,
    its two laws' calls and rows). With the inverse unrolled in ``n^2`` locals, each
    mass added 15-25 % more than the one before."""
    from lumped.solvers.bdf.fast_codegen import fast_source

    size = [len(fast_source(chain(n))) for n in range(3, 7)]
    steps = [b - a for a, b in zip(size[:-1], size[1:], strict=True)]
    assert max(steps) - min(steps) <= 0.05 * min(steps), (size, steps)


def test_a_new_structure_compiles_each_generated_function_once(monkeypatch, tmp_path):
    """A new structure (an empty disk cache) compiles its fast loop and each helper of the
    generated module once, no forcing helper of its own (the shared
    :func:`~lumped.solvers.bdf.fast_force_jit.force_at`), and a run with new numbers
    compiles nothing."""
    from numba.core import event

    from lumped.solvers.bdf import fast_codegen

    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))  # an empty disk cache
    monkeypatch.setattr(fast_codegen, "_BY_KEY", {})
    monkeypatch.setattr(fast_codegen, "LOADED_MODULES", {})
    compiled: list[tuple[str, str]] = []

    class Recorder(event.Listener):
        def on_start(self, ev):
            f = ev.data["dispatcher"].py_func
            compiled.append((f.__module__, f.__qualname__))

        def on_end(self, ev):
            pass

    rec = Recorder()
    event.register("numba:compile", rec)
    try:
        first = simulate(chain(2), method="jit-bdf2", dt=1e-3, t_end=0.2, fast=True)
        n_first = len(compiled)
        again = simulate(chain(2, k_factor=1.03), method="jit-bdf2", dt=1e-3, t_end=0.2,
                         fast=True)
    finally:
        event.unregister("numba:compile", rec)
    assert first.ok and again.ok
    assert first.stats["fast_steps"] == again.stats["fast_steps"] == 200
    generated = Counter(name for module, name in compiled[:n_first]
                        if module.startswith("lumped_jitfast_"))
    assert generated["run_fast"] == 1, generated
    # the forcing helper is shared, compiled once per machine, not once per structure
    assert "force_at" not in generated, generated
    assert max(generated.values()) == 1, generated  # no function compiled twice
    assert compiled[n_first:] == []  # new numbers: nothing compiled


def test_a_small_structure_keeps_its_factor_cache_key_in_locals():
    """Up to :data:`~lumped.solvers.bdf.fast_codegen.UNROLLED_SOLVE` unknowns (the paper
    scene's 3) the key of the factor cache is held in locals: read from the array ``key``
    at every Newton iteration, it sat on the step's chain of dependent operations and made
    the paper scene's ``jit-bdf2`` 7 % slower (issue 27). Above, it stays in ``key``
    (locals carried through both loops cost compile time, not speed)."""
    from lumped.scenarios import scenario_scene
    from lumped.solvers.bdf.fast_codegen import UNROLLED_SOLVE, fast_source

    paper = scenario_scene("forcing-F2")
    assert len(paper.nodes) + len(paper.elements) <= UNROLLED_SOLVE
    assert "key[" not in fast_source(paper)
    assert "== key[" in fast_source(chain(3))  # 9 unknowns
