r"""When ``radau5`` with ``compiled=None`` builds its compiled loop: rent or buy.

The compiled loop has two parts with two costs. The shared loop
(:func:`~lumped.solvers.eventdriven.loop_jit.advance` and the kernels it calls) is
compiled once per machine and kept in numba's disk cache: 10-14 s of CPU the first time
(a fresh install, an upgrade, an emptied cache). A law template's module
(:mod:`lumped.codegen.template_module`) is compiled once per template: 0.5-0.8 s. The two
loops give the same numbers bit for bit, so when to switch is a question of time alone,
answered as in the rent-or-buy problem: run the Python loop (rent, about 0.3 ms a step on
the paper's scene) until its steps have cost about what the compile would (buy), which
bounds the time of any run at about twice that of the better choice made in hindsight.
The budgets count steps, not seconds, so that which loop runs depends on the process's
runs only, never on the machine's load; where a step costs more the bound is looser
(the 3-mass chain: 0.65 ms a step, about 2.7).

* The shared loop compiled (in this process, or loaded from numba's disk cache) and every
  template's module too: compiled from step 0.
* The shared loop compiled, a template's module not: compiled after :data:`COMPILE_AFTER`
  steps of the run (about 0.25 s of Python steps).
* The shared loop not compiled on this machine: compiled once the Python steps of this
  process's runs that waited for it reach :data:`SHARED_COMPILE_AFTER` (about 12 s of
  Python steps on the paper's scene), so a fresh machine's short runs, and a sweep of
  them, never wait 10 s for a compile, while a long run or a long sweep still gets the
  compiled loop. ``lumped warm`` compiles it ahead.

The numbers never depend on the choice; ``Solution.stats["loop"]`` says which loop ran.
The rule reads no forecast of a run's length: its first steps are often its densest (a
forcing's start, a break-out), so a forecast from its pace so far overstated the steps
left (the paper's scene under F2 at rtol 1e-9, 900 steps over 1 s, with the counts
scaled down to 100 and 1350: compiled after step 100) and would pay the compile for runs
that end sooner, losing the bound.
"""

from __future__ import annotations

from ...codegen.jit import numba_enabled
from ...scene import Scene
from . import loop_jit as L
from .fast_parts import loaded

__all__ = ["COMPILE_AFTER", "SHARED_COMPILE_AFTER", "WAITING", "due", "shared_compiled",
           "waited", "waiting"]

#: Steps of one run in the Python loop before its scene's law templates are compiled
#: (the shared loop compiled already; see the module notes).
COMPILE_AFTER = 2000
#: Python steps of a process's runs before the shared loop is compiled there (when numba's
#: disk cache does not hold it; see the module notes).
SHARED_COMPILE_AFTER = 40_000
#: The start of ``stats["loop"]`` of a run in the Python loop that waits for a compile.
WAITING = "python: not compiled yet"

_WAITED = [0]  # Python steps of this process's runs that waited for the shared loop


def shared_compiled() -> bool:
    """Whether the shared loop is compiled in this process, or loaded now from numba's
    disk cache (looked at once a process)."""
    return L.compiled_advance(compile=False) is not None


def waiting(scene: Scene, plan, steps: int) -> str | None:
    """``None`` when a run with ``compiled=None`` that has taken ``steps`` steps in the
    Python loop builds the compiled loop now (see the module notes), else why it waits
    (``stats["loop"]``, starting with :data:`WAITING`). Without numba: ``None`` (the
    compiled loop's parts then say why the Python loop runs)."""
    if not numba_enabled():
        return None
    if not shared_compiled():
        if _budget_spent(steps):
            return None
        return (f"{WAITING} (radau5's shared loop is not compiled on this machine: "
                "`lumped warm` compiles it)")
    if steps >= COMPILE_AFTER or loaded(scene, plan):
        return None
    return f"{WAITING} (a short run)"


def due(steps: int) -> bool:
    """A cheap first test of :func:`waiting` for the run loop, at every step of a
    waiting run: whether ``steps`` reach the step count of either rule."""
    return steps >= COMPILE_AFTER and (_budget_spent(steps) or shared_compiled())


def _budget_spent(steps: int) -> bool:
    """The Python steps of this process's waiting runs, with ``steps`` of the current one,
    reach :data:`SHARED_COMPILE_AFTER`."""
    return _WAITED[0] + steps >= SHARED_COMPILE_AFTER


def waited(stats: dict) -> None:
    """At the end of a run: count its steps towards :data:`SHARED_COMPILE_AFTER` if it ran
    in the Python loop waiting for the shared loop."""
    if stats["loop"].startswith(WAITING) and numba_enabled() and not shared_compiled():
        _WAITED[0] += stats["steps"]
