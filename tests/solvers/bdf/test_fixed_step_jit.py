"""The compiled generic BDF (``jit-bdf1``, ``jit-bdf2``) against its pure-Python reference.

The faithful compiled loop (``fast=False``) is a port of
:func:`lumped.solvers.bdf.fixed_step.run_bdf` operation for operation, so on these scenes (at
most 8 unknowns, where both use the same LU) the results and the cost counters must be
equal bit for bit, not merely close. The fast path (the default for runs of 1000 steps
or more) is held to the reference in ``test_bdf_fast_jit.py``; the exactness tests below
(eq. 19, a stuck velocity) run it. Compiling a
scene takes seconds, so the scenes below are few and each is compiled once per session
(scenes that differ only in masses, initial state or forcing share one compiled module).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from lumped import Element, Junction, Mass, Scene, simulate
from lumped.laws import ElementLaw, get_law
from lumped.scenarios import scenario_scene
from lumped.scene.forcing import SineBurst
from lumped.solvers.status import SolverError

METHODS = [("jit-bdf1", "bdf1"), ("jit-bdf2", "bdf2")]


def law(name, **params):
    return get_law(name).bind(**params)


def two_masses(force="Piecewise((4*sin(2*pi*t), t <= 3), (0, True))"):
    """examples/two-masses.toml: a Bingham dashpot on m1, a forced m2 hung on a spring."""
    return Scene(
        [Mass("m1", 1.0), Mass("m2", 0.5)],
        [Element("spring1", law("linear_spring", k=40.0), "ground", "m1"),
         Element("friction", law("bingham", gamma=0.5, tau=1.5), "ground", "m1"),
         Element("spring2", law("linear_spring", k=20.0), "m1", "m2")],
        {"m2": force},
    )


def maxwell():
    """ground --newtonian(c)-- j --spring(k)-- mass (examples/maxwell.toml)."""
    return Scene(
        [Mass("mass", 1.0, x0=0.3), Junction("j")],
        [Element("dashpot", law("newtonian", c=2.0), "ground", "j"),
         Element("spring", law("linear_spring", k=50.0), "j", "mass")],
    )


DRAG = ElementLaw("quadratic_drag", "dashpot", "F = c*q*Abs(q)", ["c"])


def custom(x0=0.4):
    """A user law (not a known monotone built-in: the fold check runs every step)."""
    return Scene(
        [Mass("mass", 2.0, x0=x0)],
        [Element("spring", law("linear_spring", k=30.0), "ground", "mass"),
         Element("drag", DRAG.bind(c=0.7), "ground", "mass")],
        {"mass": lambda t: 3.0 * math.cos(4.0 * t)},
    )


def both(scene, jit, ref, dt, t_end, **kw):
    """The faithful port (``fast=False``) and the reference."""
    return (simulate(scene, method=jit, dt=dt, t_end=t_end, fast=False, **kw),
            simulate(scene, method=ref, dt=dt, t_end=t_end, **kw))


def assert_identical(a, b):
    assert a.ok and b.ok
    assert a.columns == b.columns
    assert np.array_equal(a.data, b.data), np.max(np.abs(a.data - b.data))
    assert a.stats == b.stats


@pytest.mark.parametrize("jit,ref", METHODS)
@pytest.mark.parametrize("name", ["release-0.5", "release-0.005", "forcing-F1", "forcing-F2"])
def test_paper_scenes_bit_for_bit(name, jit, ref):
    a, b = both(scenario_scene(name), jit, ref, 1e-3, 5.0)
    assert_identical(a, b)


@pytest.mark.parametrize("jit,ref", METHODS)
@pytest.mark.parametrize("make", [maxwell, two_masses, custom], ids=["maxwell", "two", "custom"])
def test_examples_and_custom_law_bit_for_bit(make, jit, ref):
    a, b = both(make(), jit, ref, 1e-3, 4.0)
    assert_identical(a, b)


@pytest.mark.parametrize("jit", ["jit-bdf1", "jit-bdf2"])
def test_forcing_below_yield_is_exact_eq19(jit):
    """Paper eq. (19): x = v = F_s = 0 and F_d = F1(t) exactly, every step."""
    F = SineBurst(0.5, 5.0 * math.pi, 1.0)
    scene = scenario_scene("forcing-F1")
    sol = simulate(scene, method=jit, dt=1e-4, t_end=1.2)
    assert sol.ok
    assert np.all(sol.column("x_mass") == 0.0)
    assert np.all(sol.column("v_mass") == 0.0)
    assert np.all(sol.column("F_spring") == 0.0)
    assert np.all(sol.column("F_dashpot") == np.array([F(float(t)) for t in sol.t]))


@pytest.mark.parametrize("jit", ["jit-bdf1", "jit-bdf2"])
def test_stuck_velocity_is_exactly_zero(jit):
    """Released at rest below the yield force, and after the final stick of release-0.5:
    the velocity is 0.0 exactly and the position does not creep (BDF2's position settles
    within 100 steps: its increments shrink by 1/3 per step once ``v = 0``)."""
    sol = simulate(scenario_scene("release-0.005"), method=jit, dt=1e-3, t_end=3.0)
    assert np.all(sol.column("v_mass") == 0.0)
    assert np.all(sol.column("x_mass") == 0.005)
    sol = simulate(scenario_scene("release-0.5"), method=jit, dt=1e-3, t_end=5.0)
    v, x = sol.column("v_mass"), sol.column("x_mass")
    last_move = np.nonzero(v != 0.0)[0][-1]
    assert last_move < len(v) - 1000  # it sticks for good well before t_end
    assert np.all(x[last_move + 100:] == x[-1])


def test_bad_input():
    from lumped.solvers.bdf.fixed_step_jit import run_bdf_jit

    with pytest.raises(ValueError, match="`method`.*'jit-bdf3'"):
        run_bdf_jit(maxwell(), method="jit-bdf3", dt=1e-3, n_steps=3)
    with pytest.raises(ValueError, match="dt"):
        simulate(maxwell(), method="jit-bdf2", dt=-1e-3, t_end=1.0)
    with pytest.raises(ValueError, match="`dt` is required"):
        simulate(maxwell(), method="jit-bdf2", t_end=1.0)


@pytest.mark.parametrize("c", [1.0, 0.77])
def test_hand_written_kernel_is_refused(c):
    # (an object naming a law and numbers of a class, c = 0.77, was given the law's
    # compiled code for them and ran it, its own kernel never called)
    class HandWritten:
        law = get_law("newtonian")
        params = {"c": c}

        @staticmethod
        def kernel(q, F):
            return F - q, -1.0, 1.0

    scene = Scene([Mass("m", 1.0, x0=0.1)],
                  [Element("d", HandWritten(), "ground", "m"),
                   Element("s", law("linear_spring", k=1.0), "ground", "m")])
    with pytest.raises(ValueError, match="hand-written"):
        simulate(scene, method="jit-bdf1", dt=1e-3, t_end=0.01)


def test_non_finite_force_names_node_and_time():
    scene = custom()
    scene.forcing = (lambda t: math.nan if t > 0.0105 else 1.0,)
    with pytest.raises(ValueError, match=r"force on node 'mass' returned nan at t = 0.011"):
        simulate(scene, method="jit-bdf2", dt=1e-3, t_end=1.0)


def test_newton_failure_reports_like_the_reference():
    """A budget of one Newton iteration fails at the same step, with the same message.

    The load jumps to ``1.7e308`` (finite) at ``t = 0.11``: one iteration does not take
    the step there (with the default tolerance alone, the globalised solve's restart from
    the nodes' balances solved by bisection gives a start that one iteration takes to the
    solution; a tolerance below eps, once used here, is now met where every row is at
    round-off, :func:`lumped.solvers.newton.criteria.at_roundoff`)."""
    from lumped.solvers.newton.options import NewtonOptions

    opts = NewtonOptions(max_iters=1, free_steps=0)
    scene = two_masses()
    scene.forcing = (lambda t: 1.7e308 if t > 0.105 else 1.0, None)
    with pytest.raises(SolverError) as ref:
        simulate(scene, method="bdf2", dt=1e-2, t_end=4.0, options=opts)
    with pytest.raises(SolverError) as got:
        simulate(scene, method="jit-bdf2", dt=1e-2, t_end=4.0, options=opts, fast=False)
    assert str(got.value) == str(ref.value)
    assert got.value.status is ref.value.status
    a = simulate(scene, method="jit-bdf2", dt=1e-2, t_end=4.0, options=opts, throw=False,
                 fast=False)
    b = simulate(scene, method="bdf2", dt=1e-2, t_end=4.0, options=opts, throw=False)
    assert not a.ok and a.status is b.status and a.message == b.message
    assert np.array_equal(a.data, b.data)


def _run_child(code: str, **env) -> str:
    full = dict(os.environ, **env)
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=full,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_second_process_loads_the_compiled_loop_from_disk():
    """The loop and the scene were compiled (and cached) by the tests above; a fresh
    process must load their machine code from the disk cache, not compile it."""
    simulate(scenario_scene("release-0.5"), method="jit-bdf2", dt=1e-3, t_end=0.01, fast=True)
    out = _run_child("""
        from lumped import simulate
        from lumped.codegen.step_dispatch import step_callbacks
        from lumped.scenarios import scenario_scene
        from lumped.solvers.bdf.fast_codegen import fast_module
        from lumped.solvers.bdf.core_jit import compiled_run_bdf_core
        scene = scenario_scene("release-0.5")
        simulate(scene, method="jit-bdf2", dt=1e-3, t_end=0.01, fast=True)
        simulate(scene, method="jit-bdf2", dt=1e-3, t_end=0.01, fast=False)
        for f in (compiled_run_bdf_core(), *step_callbacks(), fast_module(scene).run_fast):
            print(sum(f.stats.cache_hits.values()), sum(f.stats.cache_misses.values()))
    """)
    counts = [tuple(map(int, line.split())) for line in out.splitlines()]
    assert counts == [(1, 0)] * 4  # the loops and the port's callbacks: loaded, not compiled


def test_disabled_jit_gives_the_same_numbers():
    """NUMBA_DISABLE_JIT=1: the same code runs as plain Python, same results."""
    out = _run_child("""
        import numpy as np
        from lumped import simulate
        from lumped.scenarios import scenario_scene
        scene = scenario_scene("forcing-F2")
        a = simulate(scene, method="jit-bdf2", dt=1e-2, t_end=0.6, fast=False)
        b = simulate(scene, method="bdf2", dt=1e-2, t_end=0.6)
        c = simulate(scene, method="jit-bdf2", dt=1e-2, t_end=0.6, fast=True)
        print(np.array_equal(a.data, b.data) and a.stats == b.stats
              and c.stats["fast_steps"] == 60 and np.allclose(c.data, b.data, 1e-12, 1e-12))
    """, NUMBA_DISABLE_JIT="1")
    assert out.strip() == "True"


def test_without_numba_gives_the_same_numbers():
    """numba not installed (blocked in a child process): the package imports, and the
    compiled methods run the same code uncompiled, with the same results."""
    out = _run_child("""
        import sys
        sys.modules["numba"] = None  # `import numba` now raises ImportError
        import numpy as np
        from lumped import simulate
        from lumped.scenarios import scenario_scene
        scene = scenario_scene("release-0.5")
        a = simulate(scene, method="jit-bdf1", dt=1e-2, t_end=0.3, fast=False)
        b = simulate(scene, method="bdf1", dt=1e-2, t_end=0.3)
        c = simulate(scene, method="jit-bdf1", dt=1e-2, t_end=0.3, fast=True)
        print(np.array_equal(a.data, b.data) and a.stats == b.stats
              and c.stats["fast_steps"] == 30 and np.allclose(c.data, b.data, 1e-12, 1e-12))
    """)
    assert out.strip() == "True"
