"""The generated numba module of a scene (:mod:`lumped.codegen.jit`): its functions agree
with the Python kernels and branch machinery they are generated from, and the disk cache
is written safely. Only the small functions are called here (numba compiles lazily, one
function at a time); the compiled solver loop is tested in tests/solvers."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped import Element, Mass, Scene
from lumped.codegen.branches import law_branches
from lumped.codegen.jit import jit_scene, scene_source
from lumped.codegen.module_cache import _write_once, cache_dir
from lumped.laws import ElementLaw, get_law

CUBIC = ElementLaw("cubic", "spring", "F = k*q + c*q**3", ["k", "c"])


@pytest.fixture(scope="module")
def js():
    """One mass on a Bingham dashpot, a taut-or-slack string and a user law; the string
    and the Bingham law appear twice (one compiled kernel each)."""
    bingham = get_law("bingham").bind(gamma=2.0, tau=1.0)
    scene = Scene(
        [Mass("m", 1.0), Mass("n", 2.0)],
        [Element("d", bingham, "ground", "m"),
         Element("s", get_law("string_spring").bind(k=10.0, L=0.5), "m", "n"),
         Element("c", CUBIC.bind(k=3.0, c=0.5), "ground", "n"),
         Element("d2", get_law("bingham").bind(gamma=2.0, tau=1.0), "n", "ground")],
    )
    return scene, jit_scene(scene)


finite = st.floats(-3.0, 3.0, allow_nan=False)


def test_one_kernel_per_distinct_law(js):
    scene, j = js
    assert list(j.law_index) == [0, 1, 2, 0]
    assert j.masses.tolist() == [1.0, 2.0]
    assert j.ea.tolist() == [-1, 0, -1, 1] and j.eb.tolist() == [0, 1, 1, -1]
    assert j.spring.tolist() == [False, True, True, False]


def _agree(got: tuple, want: tuple) -> None:
    """Equal to 2 ulps of each entry: LLVM may fuse ``a*b + c`` into one rounding (an
    FMA) where Python rounds twice, e.g. ``1.5*q**2 + 3.0`` at ``q = 2.494295631933623``
    differs in the last bit."""
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert abs(g - w) <= 2 * math.ulp(max(abs(g), abs(w))), (got, want)


@given(q=finite, F=finite)
def test_element_laws_and_branches_match_python(js, q, F):
    scene, j = js
    m = j.module
    out = np.empty(4)
    for e, el in enumerate(scene.elements):
        c = j.consts
        _agree(m.element_law(e, q, F, c), el.law.kernel(q, F))
        assert m.element_magnitude(e, q, F, c) == el.law.kernel.magnitude(q, F)
        lb = law_branches(el.law)
        assert m.branch_count(e) == lb.count
        assert m.active_branch(e, q, F, c) == lb.branch(q, F)
        for i in range(lb.count):
            _agree(m.branch_law(e, i, q, F, c), lb.kernel_for(i)(q, F))
            k = m.branch_guards(e, i, q, F, out, c)
            assert tuple(out[:k]) == lb.guards_for(i)(q, F)


def test_scene_laws_all_elements_at_once(js):
    scene, j = js
    q = np.array([0.3, 0.7, -0.2, 0.0])
    F = np.array([1.5, 2.0, -0.4, 0.2])
    R, Rq, RF = np.empty(4), np.empty(4), np.empty(4)
    j.module.scene_laws(q, F, R, Rq, RF, j.consts)
    for e, el in enumerate(scene.elements):
        assert (R[e], Rq[e], RF[e]) == el.law.kernel(q[e], F[e])


def test_one_module_per_structure_the_numbers_are_data(js):
    scene, j = js
    again = Scene([Mass("m", 5.0, x0=1.0), Mass("n", 1.0, v0=2.0)], scene.elements)
    assert jit_scene(again).module is j.module  # masses and state are data
    # new numbers in every law: the same module, other constants
    numbers = Scene(scene.nodes, [
        Element("d", get_law("bingham").bind(gamma=2.5, tau=1.25), "ground", "m"),
        Element("s", get_law("string_spring").bind(k=13.0, L=0.75), "m", "n"),
        Element("c", CUBIC.bind(k=3.5, c=0.25), "ground", "n"),
        Element("d2", get_law("bingham").bind(gamma=2.25, tau=0.5), "n", "ground")])
    jn = jit_scene(numbers)
    assert jn.module is j.module
    assert scene_source(numbers).source == scene_source(scene).source
    assert not np.array_equal(jn.consts, j.consts)
    # another structure (one element less): another module
    other = Scene(scene.nodes, scene.elements[:3])
    assert scene_source(other).source != scene_source(scene).source


def _numbers_pool(scene, count: int = 8) -> list:
    """``count`` scenes of ``scene``'s structure with other numbers in every law (a seeded
    draw: gamma in [1.5, 3.5], tau in [0.05, 4.5] -- gamma tau < 16, no steep branch --,
    k in [0.1, 1e4], c in [0.01, 10]), and one more with every multiplier 1."""
    rng = np.random.default_rng(20261127)
    pool = []
    for _ in range(count):
        gamma, tau = rng.uniform(1.5, 3.5), rng.uniform(0.05, 4.5)
        k, c = 10.0 ** rng.uniform(-1, 4), rng.uniform(0.01, 10.0)
        pool.append(Scene(scene.nodes, [
            Element("d", get_law("bingham").bind(gamma=gamma, tau=tau), "ground", "m"),
            Element("s", get_law("string_spring").bind(k=k, L=0.5), "m", "n"),
            Element("c", CUBIC.bind(k=k, c=c), "ground", "n"),
            Element("d2", get_law("bingham").bind(gamma=gamma, tau=tau), "n", "ground")]))
    # ... and every number 1 (a factor sympy would drop from the code if it took 1.0 for
    # the integer 1)
    pool.append(Scene(scene.nodes, [
        Element("d", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m"),
        Element("s", get_law("string_spring").bind(k=1.0, L=1.0), "m", "n"),
        Element("c", CUBIC.bind(k=1.0, c=1.0), "ground", "n"),
        Element("d2", get_law("bingham").bind(gamma=1.0, tau=0.5), "n", "ground")]))
    return pool


@given(q=finite, F=finite, which=st.integers(0, 8))
def test_new_numbers_reuse_the_module_and_match_python(js, q, F, which):
    # the compiled functions given another parameter set at run time compute what that
    # set's own Python kernels compute
    scene, j = js
    pool = _numbers_pool.__dict__.setdefault("pool", _numbers_pool(scene))
    numbers = pool[which]
    jn = jit_scene(numbers)
    assert jn.module is j.module
    out = np.empty(4)
    for e, el in enumerate(numbers.elements):
        _agree(j.module.element_law(e, q, F, jn.consts), el.law.kernel(q, F))
        lb = law_branches(el.law)
        assert j.module.active_branch(e, q, F, jn.consts) == lb.branch(q, F)
        for i in range(lb.count):
            _agree(j.module.branch_law(e, i, q, F, jn.consts), lb.stage_kernel_for(i)(q, F))
            n = j.module.branch_guards(e, i, q, F, out, jn.consts)
            assert tuple(out[:n]) == lb.stage_guards_for(i)(q, F)


def test_new_numbers_share_the_module_unless_they_change_the_code(js):
    scene, j = js
    pool = _numbers_pool.__dict__.setdefault("pool", _numbers_pool(scene))
    assert all(jit_scene(s).module is j.module for s in pool)
    assert len({tuple(jit_scene(s).consts) for s in pool}) == len(pool)
    # gamma tau >= 16 makes a Bingham branch steep: radau5 takes its inverse form, other
    # code; gamma = 1 or 2 does not (an integral value is a float like any other: 1.0 * y
    # is y to the bit, the factor stays in the code; 2.0 prints as 2.0, not 2)
    for gamma, same in [(40.0, False), (1.0, True), (2.0, True)]:
        other = Scene(scene.nodes, [Element("d", get_law("bingham").bind(gamma=gamma, tau=1.0),
                                            "ground", "m"), *scene.elements[1:]])
        assert (scene_source(other).source == scene_source(scene).source) is same, gamma


def test_module_file_is_named_by_its_source_hash(js):
    scene, j = js
    path = Path(j.module.__file__)
    assert path.parent == cache_dir() / "jit"
    source = scene_source(scene).source
    assert path.read_text(encoding="utf-8") == source
    assert hashlib.sha256(source.encode()).hexdigest()[:24] in path.name


def test_cache_dir_from_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path / "a"))
    assert cache_dir() == tmp_path / "a"
    monkeypatch.delenv("LUMPED_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert cache_dir() == tmp_path / "x" / "lumped"
    monkeypatch.delenv("XDG_CACHE_HOME")  # (only then is HOME read)
    for home in ("h1", "h2"):
        monkeypatch.setenv("HOME", str(tmp_path / home))
        assert cache_dir() == tmp_path / home / ".cache" / "lumped"
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path / "b"))
    assert cache_dir() == tmp_path / "b"


def test_a_generated_module_exists_when_loaded_or_on_disk(js, monkeypatch, tmp_path):
    from lumped.codegen.module_cache import generated_module_exists, module_cached, module_name

    source = scene_source(js[0]).source
    name = module_name(source)
    assert generated_module_exists(name) and module_cached(source)  # loaded by the fixture
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path / "c"))  # loaded under another key
    assert not generated_module_exists(name) and not module_cached(source)
    (cache_dir() / "jit").mkdir(parents=True)
    (cache_dir() / "jit" / f"{name}.py").write_text(source)
    assert generated_module_exists(name) and module_cached(source)


def test_write_once_never_replaces_a_file(tmp_path):
    path = tmp_path / "d" / "m.py"
    _write_once(path, "A = 1\n")
    stamp = path.stat().st_mtime_ns
    _write_once(path, "A = 2\n")
    assert path.read_text() == "A = 1\n" and path.stat().st_mtime_ns == stamp
    assert [p.name for p in path.parent.iterdir()] == ["m.py"]  # no temp file left


@pytest.mark.parametrize("method", ["jit-bdf1", "jit-bdf2"])
def test_position_lock_runs_compiled_with_the_reference_across_the_lock(method):
    # the compiled loop alone refuses a position lock by name; simulate() runs it while
    # the string is slack and the reference's steps from the impact on (located in the
    # step; issue 27): the reference's numbers (the faithful port: bit for bit)
    from lumped import simulate
    from lumped.solvers.bdf.fixed_step_jit import run_bdf_jit

    scene = Scene([Mass("m", 1.0, v0=1.0)],
                  [Element("s", get_law("string_spring").bind(k=1.0, L=0.5), "ground", "m")])
    with pytest.raises(ValueError, match="position lock.*'string_spring'.*element 's'"):
        run_bdf_jit(scene, method=method, dt=1e-3, n_steps=10)
    sol = simulate(scene, method=method, dt=1e-3, t_end=1.0, fast=False)
    ref = simulate(scene, method=method.removeprefix("jit-"), dt=1e-3, t_end=1.0)
    assert sol.method == method
    assert "fallback" not in sol.stats
    assert sol.stats["compiled_steps"] > 0 and sol.stats["handovers"] == 1
    np.testing.assert_array_equal(sol.data, ref.data)
    assert [e.kind for e in sol.events] == ["impact"]
    assert sol.events == ref.events


def test_unwritable_cache_falls_back_to_a_temporary_directory(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(blocker))
    scene = Scene([Mass("m", 3.0)],
                  [Element("c", CUBIC.bind(k=2.0, c=0.25), "ground", "m")])  # a new module
    with pytest.warns(UserWarning, match="cannot write the compiled-code cache"):
        j = jit_scene(scene)
    assert not Path(j.module.__file__).is_relative_to(blocker)
    assert j.module.element_law(0, 0.5, 1.0, j.consts) == scene.elements[0].law.kernel(0.5, 1.0)


@pytest.mark.parametrize("n", [0.5, 2.0])
def test_square_roots_and_squares_give_pythons_numbers(n):
    """A Herschel-Bulkley law bound with ``n = 0.5`` (in its inverse form, a square) or
    ``n = 2.0`` (a square root): numba's LLVM turns ``pow(x, 2.0)`` into ``x*x`` and
    ``pow(x, 0.5)`` into ``sqrt(x)``, where CPython's ``math.pow`` is the C library's, off
    by an ulp for about 1 argument in 1000. The printer writes them out, so the compiled
    kernel and the Python kernel agree bit for bit (the random-network suite's two radau5
    loops differed by 5.6e-17 in a force: LUMPED_LARGE, 1 of 1000)."""
    law = get_law("herschel_bulkley").bind(gamma=0.11192851693127487,
                                           tau=0.01625835211236202, n=n)
    scene = Scene([Mass("m", 1.0)], [Element("d", law, "ground", "m")])
    js = jit_scene(scene)
    m = js.module
    rng = np.random.default_rng(7)
    F = 0.01625835211236202 + rng.random(4000) * 10.0 ** rng.uniform(-12, 2, 4000)
    q = rng.standard_normal(4000)
    for qi, Fi in zip(q.tolist(), F.tolist(), strict=True):
        for sign in (1.0, -1.0):
            assert (m.element_law(0, sign * qi, sign * Fi, js.consts)
                    == law.kernel(sign * qi, sign * Fi))
