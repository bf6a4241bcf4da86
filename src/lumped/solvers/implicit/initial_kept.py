r"""The last consistent initial state per scene object, kept for a second call.

A ``radau5`` run tries its start at rest first
(:mod:`lumped.solvers.eventdriven.rest_start`) and, when the scene moves, hands it to
its general driver, which asks :func:`~lumped.solvers.implicit.initial_state.
consistent_initial_state` for the same state again; a repeat of one scene object asks
for it once more. The state is a function of the scene (immutable: frozen nodes and
elements, bound laws) and of the call's ``time_scale`` and Newton ``options``: it is
kept per scene object while its nodes, elements and forcing are the objects it was
solved for (as the plans of :mod:`lumped.solvers.eventdriven.setup`), for the last
call's arguments only, and handed out as copies (callers edit their lists). Its counters
are those of the one solve.
"""

from __future__ import annotations

import functools
import weakref
from collections.abc import Callable

__all__ = ["forget", "kept_per_scene"]

#: scene object -> (its nodes, elements and forcing, the arguments, the result).
_LAST: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

_State = tuple[list[float], list[float], dict]


def kept_per_scene(solve: Callable[..., _State]) -> Callable[..., _State]:
    """``solve(scene, *, time_scale=1.0, options=None) -> (v, F, stats)`` with its last
    result per scene object and arguments kept (see the module notes)."""

    @functools.wraps(solve)
    def kept(scene, *, time_scale: float = 1.0, options=None) -> _State:
        arguments = (time_scale, options)
        try:
            got = _LAST.get(scene)
        except TypeError:  # not weakly referenceable: nothing kept
            return solve(scene, time_scale=time_scale, options=options)
        if got is None or got[0] is not scene.nodes or got[1] is not scene.elements \
                or got[2] is not scene.forcing or got[3] != arguments:
            v, F, stats = solve(scene, time_scale=time_scale, options=options)
            got = _LAST[scene] = (scene.nodes, scene.elements, scene.forcing, arguments,
                                  (tuple(v), tuple(F), dict(stats)))
        v, F, stats = got[4]
        return list(v), list(F), dict(stats)

    return kept


def forget(scene=None) -> None:
    """Forget the state kept for ``scene`` (every scene's when ``None``)."""
    if scene is None:
        _LAST.clear()
    else:
        _LAST.pop(scene, None)
