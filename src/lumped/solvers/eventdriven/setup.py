r"""Setup of the adaptive method ``radau5``: its keywords, the forcing's breakpoints, the
optional compiled stage Newton and the per-scene plan (:func:`scene_plan`).
"""

from __future__ import annotations

import math
import threading
import weakref
from collections import OrderedDict, deque
from dataclasses import dataclass, field

from ...codegen.rebound import ReboundBranches
from ...codegen.scene_key import scene_key
from ...scene import Mass, Scene
from ...scene.forcing import jumps
from ...scene.shifted_laws import branches_of
from ...scene.supports import support_time_events
from ..modes.stuck import forcing_kinds

__all__ = ["EXTRA_OPTIONS", "read_options", "breakpoints", "time_events", "step_floor",
           "scope_error", "ScenePlan", "scene_plan", "clear_plans",
           "SHARED_PLANS", "structure", "structure_parts", "branches_structure",
           "accumulating",
           "too_many"]

#: The double's machine epsilon (the step floor's unit).
_EPS = 2.220446049250313e-16


#: Method-specific keywords of ``radau5`` and their defaults.
EXTRA_OPTIONS = {"max_events": 10_000, "zeno_events": 50, "zeno_window": None,
                 "max_steps": 1_000_000, "first_step": None, "restitution": 0.0,
                 "compiled": None, "bridge": True}


def read_options(settings) -> dict:
    """The keywords of ``settings.extra`` over :data:`EXTRA_OPTIONS`, checked.

    Raises
    ------
    TypeError
        For an unknown keyword, or a ``compiled`` that is not ``True``, ``False`` or
        ``None`` (``None``, the default: the compiled loop where the scene allows it).
    ValueError
        For a bad value; the message names the keyword and quotes the value.
    """
    out = dict(EXTRA_OPTIONS)
    if not settings.extra:  # the defaults (valid)
        return out
    for key, val in settings.extra.items():
        if key not in EXTRA_OPTIONS:
            raise TypeError(f"method 'radau5' takes no keyword argument {key!r} "
                            f"(it takes {sorted(EXTRA_OPTIONS)})")
        out[key] = val
    for key in ("max_events", "zeno_events", "max_steps"):
        if isinstance(out[key], bool) or not isinstance(out[key], int) or out[key] < 1:
            raise ValueError(f"`{key}` must be a positive integer, got {out[key]!r}")
    e = out["restitution"]
    if out["compiled"] is not None and not isinstance(out["compiled"], bool):
        raise TypeError(f"`compiled` must be True, False or None, got {out['compiled']!r}")
    if not isinstance(out["bridge"], bool):
        raise TypeError(f"`bridge` must be True or False, got {out['bridge']!r}")
    if isinstance(e, bool) or not isinstance(e, (int, float)) or not 0.0 <= e <= 1.0:
        raise ValueError(f"`restitution` must be a number in [0, 1], got {e!r}")
    for key in ("zeno_window", "first_step"):
        val = out[key]
        if val is not None and not (isinstance(val, (int, float)) and math.isfinite(val)
                                    and val > 0):
            raise ValueError(f"`{key}` must be a positive number, got {val!r}")
    return out


def scope_error(scene: Scene, branches: list | None = None) -> str | None:
    """Why ``radau5`` does not take ``scene``, or ``None`` when it does (``branches``:
    the elements' :func:`~lumped.scene.shifted_laws.branches_of` when already made).

    A scene with moving supports (:mod:`lumped.scene.supports`) is taken, a string on a
    support too; its laws read ``q + o_e(t)`` at the time of every system solved (see
    that module).

    A branch whose ``dR/dF`` is unbounded at its boundary
    (:attr:`lumped.codegen.branches.BranchInfo.steep`: Herschel-Bulkley with ``n < 1`` at
    its yield force, where ``dq/dF -> infinity``) is solved in its inverse form
    ``F = G(q)`` (:attr:`~lumped.codegen.branches.BranchInfo.stage`), smooth there. A
    steep branch with no such form would make the stage Newton of a step that starts on
    that boundary fail at every step size: ``radau5`` refuses such a scene rather than
    stop mid-run, and ``auto`` runs ``bdf2`` there (its globalised Newton takes such
    points).
    """
    if branches is None:
        branches = [branches_of(el.law) for el in scene.elements]
    for el, lb in zip(scene.elements, branches, strict=True):
        for info in lb.info:
            if info.steep and info.stage is None:
                return (f"method 'radau5' does not take element {el.name!r}: branch "
                        f"{info.index} of its law {el.law_name!r} has an unbounded dR/dF "
                        f"({info.dR_dF}) at its boundary and no inverse form F = G(q); "
                        "use 'bdf2' (or 'auto')")
    return None


def breakpoints(scene: Scene, t_end: float) -> list[float]:
    """The times in ``(0, t_end)`` where a forcing of ``scene`` jumps or kinks, from the
    ``breakpoints(t0, t1)`` method of the forcing objects that have one (time events);
    :func:`time_events`."""
    return time_events(scene, t_end)[0]


def time_events(scene: Scene, t_end: float) -> tuple[list[float], list[bool]]:
    """``(breaks, kinks)``: the times in ``(0, t_end)`` where a forcing of ``scene`` jumps
    or kinks, in order, and per time whether every forcing is continuous there (a kink:
    a point of a record; :func:`lumped.scene.forcing.jumps`). The breakpoints of a
    support's motion (:func:`lumped.scene.supports.support_time_events`; ``scene`` or the
    scene of its :class:`~lumped.scene.supports.SupportFrame`) count as the forcing's: a
    jump of the support's acceleration is a time event, a point where it is continuous
    a kink.

    A step of ``radau5`` ends on each of them. At a jump the full laws choose the mode
    again (a time event, in the run's events); at a kink the state, the forces and so
    every guard are continuous, and the held mode goes on (not an event).

    Times closer than the step floor ``16 eps max(|t|, 1e-3 t_end)`` to the one before
    (or to ``0`` or ``t_end``) are one time, the first of them (a kink only if all of
    them are): no step fits between them (two forcings' points an ulp apart, a sine
    switched off where a record has a point), so each would be a step below the
    floor."""
    out: set[float] = set()
    jumped: set[float] = set()
    for fn in scene.forcing:
        get = getattr(fn, "breakpoints", None)
        if get is not None:
            out.update(float(b) for b in get(0.0, t_end) if 0.0 < b < t_end)
            jumped.update(float(b) for b in jumps(fn, 0.0, t_end))
    frame = getattr(scene, "support_frame", None)
    source = frame.source if frame is not None else scene
    if getattr(source, "supports", None):  # (none: no support events)
        s_breaks, s_kinks = support_time_events(source, t_end)
        out.update(b for b in s_breaks if 0.0 < b < t_end)
        jumped.update(b for b in s_breaks if 0.0 < b < t_end and b not in s_kinks)
    breaks: list[float] = []
    kinks: list[bool] = []
    last = 0.0
    end_room = step_floor(t_end, t_end)
    for b in sorted(out):
        if b - last >= step_floor(b, t_end) and t_end - b >= end_room:
            breaks.append(b)
            kinks.append(b not in jumped)
            last = b
        elif breaks and b in jumped:
            kinks[-1] = False
    return breaks, kinks


def step_floor(t: float, t_end: float) -> float:
    """The step floor of a run to ``t_end`` at ``t``: ``16 eps max(|t|, 1e-3 t_end)`` (the
    compiled loop, :mod:`lumped.solvers.eventdriven.loop_jit`, writes it out)."""
    return 16.0 * _EPS * max(abs(t), t_end * 1e-3)


@dataclass
class ScenePlan:
    """What ``radau5`` reads from a scene's structure and laws before it steps, kept per
    scene content (:func:`scene_plan`): the refusal (:func:`scope_error`), the laws'
    branches, the elements whose law needs the fold check (not a known monotone one),
    the elements on cycles of the network, ``fast`` (the compiled loop's parts or why
    there is none, :mod:`lumped.solvers.eventdriven.fast`) and ``module_loaded`` (its
    generated module was loaded in this process when the plan was first asked).
    ``key`` is the scene's content key (:func:`lumped.codegen.scene_key.scene_key`), or
    ``None`` for a plan kept per scene object only."""

    refused: str | None
    branches: list
    checked: list[int]
    cyclic: tuple[int, ...]
    key: tuple | None
    fast: object = None
    module_loaded: bool | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)
    #: the parts of the structure alone, shared by the plans of one structure
    #: (:func:`structure_parts`)
    structure: dict = field(default_factory=dict)


#: scene object -> (its nodes, elements, forcing ids, forcing, plan) when the plan was
#: asked: the plan holds while those are the same objects.
_PLANS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: content key -> (plan, the objects the key names by id), the last :data:`SHARED_PLANS`
#: asked (least recently used first).
_SHARED: OrderedDict = OrderedDict()
_SHARED_LOCK = threading.Lock()
#: How many plans are kept by content (a sweep of new numbers makes a plan per point;
#: only a repeat of recent content finds one).
SHARED_PLANS = 64


def scene_plan(scene: Scene) -> ScenePlan:
    """The :class:`ScenePlan` of ``scene``, made once per scene content: kept per scene
    object (while its nodes, elements and forcing are the objects it was made from) and,
    for a scene with a content key (:func:`lumped.codegen.scene_key.scene_key`: every
    number, name, end, law and forcing a run reads), shared by every scene object with
    that key, the last :data:`SHARED_PLANS` of them, so that repeated runs of one scene
    and a new scene object with the same numbers (a user's script run again, a study)
    skip this set-up and what the runs keep on the plan. Everything kept on a plan is a
    function of that content alone (the runs' arguments are keys of what they keep)."""
    got = _PLANS.get(scene)
    if got is not None and got[0] is scene.nodes and got[1] is scene.elements \
            and (got[3] is scene.forcing or got[2] == tuple(id(f) for f in scene.forcing)):
        return got[4]
    keyed = scene_key(scene)
    key = None if keyed is None else keyed[0]
    plan = None
    if key is not None:
        with _SHARED_LOCK:
            got = _SHARED.get(key)
            if got is not None:
                _SHARED.move_to_end(key)
                plan = got[0]
    if plan is None:
        plan = _new_plan(scene, key)
        if keyed is not None:
            with _SHARED_LOCK:  # (the plan and the objects the key names by id)
                plan = _SHARED.setdefault(key, (plan, keyed[1]))[0]
                while len(_SHARED) > SHARED_PLANS:
                    _SHARED.popitem(last=False)
    _PLANS[scene] = (scene.nodes, scene.elements, tuple(id(f) for f in scene.forcing),
                     scene.forcing, plan)
    return plan


def _new_plan(scene: Scene, key: tuple | None) -> ScenePlan:
    """A new :class:`ScenePlan` of ``scene`` (``key``: its content key or ``None``), its
    parts of the structure alone taken from :func:`structure_parts`."""
    branches = [branches_of(el.law) for el in scene.elements]
    parts = structure_parts(scene, branches)
    plan = ScenePlan(scope_error(scene, branches) if parts["steep"] else None, branches,
                     parts["checked"], parts["cyclic"], key, structure=parts)
    kinds = _FORCING_KINDS.get(tuple(map(id, scene.forcing)))
    if kinds is not None and all(a is b for a, b in zip(kinds[0], scene.forcing,
                                                        strict=True)):
        plan.forcing_kinds = kinds[1]
    else:
        got = forcing_kinds(scene, plan)
        if len(_FORCING_KINDS) >= SHARED_PLANS:
            _FORCING_KINDS.clear()
        _FORCING_KINDS[tuple(map(id, scene.forcing))] = (scene.forcing, got)
    return plan


#: structure key (:func:`structure_parts`) -> the parts of a plan that depend on it
#: alone, the last :data:`SHARED_PLANS` structures asked (least recently used first).
_STRUCTURES: OrderedDict = OrderedDict()
#: ids of a scene's forcing objects -> (those objects, their
#: :func:`~lumped.solvers.modes.stuck.forcing_kinds`), whose arrays nothing changes.
_FORCING_KINDS: dict[tuple, tuple] = {}


def branches_structure(lb) -> object:
    """What fixes a law's branches apart from its numbers: its class
    (:class:`~lumped.codegen.parametric.LawClass`) for a law remade from one (every law
    of the class has the same branches, locks and lock values, and the same ``dR/dF``
    but for its floats), else the branches object itself."""
    return lb._rebound.cls if type(lb) is ReboundBranches else lb


def structure_parts(scene: Scene, branches: list) -> dict:
    """The parts of a :class:`ScenePlan` that depend only on the scene's structure, made
    once per structure and shared by the plans of every scene of that structure, whatever
    its numbers: ``checked`` (the elements whose law is not known monotone), ``cyclic``
    (the elements on cycles), ``free_cyclic`` (those of them with a branch whose
    ``dR/dF`` is not a nonzero constant: their forces can be free), ``free_cycles``
    (those of them on a cycle of such elements alone: the only elements whose forces can
    be indeterminate, :func:`~lumped.solvers.nonsmooth.locks.indeterminate_elements`;
    none, and no element's force ever is), ``hold_structure`` (the static balance's
    structure of each mode, :func:`~lumped.solvers.modes.stuck.static_hold`),
    ``steep`` (some branch is steep with no inverse form: :func:`scope_error` refuses
    the scene; only then is its message written). The structure is each node's kind,
    each element's kind, ends and law (the unbound law object) and its law's branches
    apart from their numbers (:func:`branches_structure`); everything these parts read."""
    laws, kinds, shapes = [], [], []
    for el, lb in zip(scene.elements, branches, strict=True):  # (one pass: a new scene's)
        law = el.law
        laws.append(getattr(law, "law", law))
        kinds.append(el.kind)
        shapes.append(branches_structure(lb))
    laws = tuple(laws)
    key = (tuple([type(nd) for nd in scene.nodes]), tuple(kinds), scene.elem_a,
           scene.elem_b, tuple(map(id, laws)), tuple(shapes))
    with _SHARED_LOCK:
        got = _STRUCTURES.get(key)
        if got is not None:
            _STRUCTURES.move_to_end(key)
            return got
    from ..implicit.branch_check import known_monotone
    from ..nonsmooth.locks import cyclic_elements, on_cycles

    cyclic = cyclic_elements(scene)
    free = tuple(e for e in cyclic if any(
        not (info.dR_dF.is_number and info.dR_dF != 0) for info in branches[e].info))
    got = {"checked": [e for e, el in enumerate(scene.elements)
                       if not known_monotone(el.law)],
           "cyclic": cyclic, "hold_structure": {}, "free_cyclic": free,
           "free_cycles": on_cycles(len(scene.nodes), tuple(
               (e, scene.elem_a[e], scene.elem_b[e]) for e in free)) if len(free) > 1 else (),
           "steep": any(i.steep and i.stage is None for lb in branches for i in lb.info),
           "laws": laws}  # (the laws the key names by id, kept alive with it)
    with _SHARED_LOCK:
        got = _STRUCTURES.setdefault(key, got)
        while len(_STRUCTURES) > SHARED_PLANS:
            _STRUCTURES.popitem(last=False)
    return got


def clear_plans() -> None:
    """Forget every kept plan (per object, per content and per structure): the next run
    of any scene makes its plan from scratch (tests compare the two)."""
    with _SHARED_LOCK:
        _SHARED.clear()
        _PLANS.clear()
        _STRUCTURES.clear()
        _FORCING_KINDS.clear()


def structure(scene: Scene, plan) -> tuple[list[bool], tuple[float, ...], list[bool],
                                           list[bool], float]:
    """``(is_mass, masses, spring, massless, m_min)`` of the scene's nodes and elements,
    made once per plan (the lists are only read, and made once per structure, shared by
    its plans: ``plan.structure``): which nodes are masses, ``m_i`` (``0.0`` at a
    junction), which elements are springs, which are dashpots between junctions and
    ground only (a lock there has its force from a junction's balance), and the lightest
    mass."""
    got = plan.__dict__.get("radau5_structure")
    if got is None:
        kinds = plan.structure.get("radau5_kinds")
        if kinds is None:  # (node kinds, element kinds and ends: the structure's)
            is_mass = [isinstance(nd, Mass) for nd in scene.nodes]
            massless = [not any(p >= 0 and is_mass[p]
                                for p in (scene.elem_a[e], scene.elem_b[e]))
                        and el.kind == "dashpot" for e, el in enumerate(scene.elements)]
            kinds = plan.structure["radau5_kinds"] = (
                is_mass, [el.kind == "spring" for el in scene.elements], massless)
        masses = scene.masses
        got = plan.__dict__["radau5_structure"] = (
            kinds[0], masses, kinds[1], kinds[2], min(mi for mi in masses if mi > 0.0))
    return got


def accumulating(recent: deque, window: float) -> bool:
    """The last ``recent.maxlen`` events fell within ``window`` seconds (Zeno, chattering)."""
    return len(recent) == recent.maxlen and recent[-1] - recent[0] <= window


def too_many(events: list, recent: deque, t: float, opts: dict, time_events: int = 0
             ) -> tuple:
    """``(Status.TOO_MANY_EVENTS, message)``: too many events (beyond the ``time_events``
    of the forcing, which ``max_events`` does not count), or an accumulation."""
    from ..status import Status

    if len(events) - time_events > opts["max_events"]:
        return Status.TOO_MANY_EVENTS, (
            f"radau5 stopped at t = {t!r}: more than max_events = {opts['max_events']} events "
            "(guard crossings and impacts; the forcing's time events aside)")
    names = sorted({ev.element for ev in events[-len(recent):]})
    return Status.TOO_MANY_EVENTS, (
        f"radau5 stopped at t = {t!r}: {len(recent)} events within "
        f"{recent[-1] - recent[0]!r} s (elements {names}; switches undone at one t, which "
        "the events drop, included): an accumulation of events (Zeno or chattering)")
