r"""The bridge between the ``radau5`` driver and its compiled inner loop.

:func:`compiled_loop` decides whether a scene runs its held-mode steps in
:func:`lumped.solvers.eventdriven.loop_jit.advance` (and says why not when it does not), and
:class:`CompiledLoop` moves the driver's state into that loop's arrays and back, and its
accepted steps into the dense output and the output rows; :func:`compiled_stage_solver`
gives the driver's own attempts (``compiled=True``) the compiled stage Newton.

The compiled loop takes a scene when numba is enabled, every forcing is absent, zero,
constant, a :class:`~lumped.scene.forcing.SineBurst` or a linearly interpolated table (a
:class:`lumped.io.Table` force, or the inertial force of a ground acceleration record;
:data:`lumped.scene.forcing_jit.FORCE_LINEAR`, its code compiled for such a scene only;
other callables of ``t`` run in Python), every law is a sympy residual (the generated
modules of its law templates, :mod:`lumped.codegen.template_module`, reached through the
structure-generic kernels of :mod:`lumped.codegen.dispatch`), and no locked elements sit
in parallel (their forces are the minimum-norm split, Python's)."""

from __future__ import annotations

import numpy as np

from ...scene import Scene
from ...scene.forcing_jit import FORCE_LINEAR
from ..modes.mode_guess_jit import compiled_probe_modes, probe_workspace
from ..modes.on_demand import OnDemand
from ..modes.stuck_jit import compiled_breakout_root, compiled_breakout_scan
from ..radau.forces_jit import table_forcing
from ..radau.stage_jit import roundoff_test, with_impact_sign
from ..radau.step_jit import fold_test
from . import loop_jit as L
from .attempt_root_jit import compiled_attempt_root
from .compile_when import waiting
from .creep import creep_floor
from .fast_parts import dispatch_pointers, loop_parts
from .first_step_jit import compiled_first_step
from .step import NOT_SOUGHT

__all__ = ["CompiledLoop", "compiled_loop", "compiled_stage_solver"]

#: Steps per block of output arrays (a full block returns to Python, which keeps it).
BLOCK = 256


def compiled_loop(scene: Scene, plan, option: bool | None, steps: int = 0
                  ) -> tuple[CompiledLoop | None, str]:
    """``(loop, "compiled")`` or ``(None, why the Python loop runs)``.

    ``plan`` is the scene's :class:`~lumped.solvers.eventdriven.setup.ScenePlan` (the
    compiled parts are kept on it); ``option`` is the ``compiled`` keyword: ``False``
    asks for the Python loop, ``True`` for the compiled loop now, ``None`` for it when a
    run that has taken ``steps`` steps should build it
    (:func:`~lumped.solvers.eventdriven.compile_when.waiting`: at once if it is
    compiled on this machine, else after some Python steps). A scene with moving
    supports (a :class:`~lumped.scene.supports.SupportFrame`'s view) has none: the
    compiled loop has no support offsets."""
    if option is False:
        return None, "python: compiled=False"
    if getattr(scene, "support_frame", None) is not None:  # (lumped.scene.supports)
        return None, "python: moving supports (no compiled loop)"
    with plan.lock:
        if plan.fast is None:
            why = None if option is not None else waiting(scene, plan, steps)
            if why is not None:
                return None, why
            plan.fast = loop_parts(scene, plan)
    if isinstance(plan.fast, str):
        return None, plan.fast
    return CompiledLoop(*plan.fast), "compiled" if steps == 0 else f"compiled from step {steps}"


class CompiledLoop:
    """The compiled loop of one scene: its generated kernels, arrays and output blocks."""

    def __init__(self, js, law, guards, fkind: np.ndarray, fpar: np.ndarray,
                 checked: np.ndarray, branch) -> None:
        # (``branch``: ``() -> Pointer`` of the ``active_branch``, compiled for the probe
        # only: :func:`~lumped.solvers.eventdriven.fast_parts.branch_pointer`)
        self.js, self.law, self.guards, self._branch = js, law, guards, branch
        self._probe: tuple | None = None
        self.fn = L.compiled_advance()
        self.fkind, self.fpar, self.checked = fkind, fpar, checked
        self.fold = fold_test() if len(checked) else 0  # (for laws not known monotone)
        self.table = table_forcing() if (fkind == FORCE_LINEAR).any() else 0
        self.A, self.W = _butcher()
        self.N, self.E = len(js.masses), len(js.ea)
        self.outputs = self.ws = self.wm = self.iw = None  # on the first call
        self.fst, self.ist = np.zeros(16), np.zeros(L.DEFECT_REJECTED + 1, dtype=np.int64)
        self.breaks, self.kinks = np.zeros(0), np.zeros(0, dtype=np.int64)
        self.flat = np.full((self.E, 2), np.nan)  # (the held branches' flat ends: run())
        self._breaks_of: list | None = None  # the run's list they were made from
        self.calls, self._akey, self._arrays = 0, None, ()

    def setup(self, t_final: float, rtol: float, atol: float, m_min: float) -> None:
        """The run's constants."""
        fst = self.fst
        fst[L.T_FINAL], fst[L.RTOL], fst[L.ATOL], fst[L.M_MIN] = t_final, rtol, atol, m_min
        fst[L.TWO] = 2.0
        fst[L.CREEP_FLOOR] = creep_floor(0.0, t_final)  # (its part that t does not change)

    def _load(self, st: dict, modes: list[int], watched: list[int], stats: dict | None):
        """The driver's state into the arrays of :func:`~lumped.solvers.eventdriven.loop_jit.
        advance`; returns ``(x, v, F, dF)``."""
        fst, ist = self.fst, self.ist
        x = np.array(st["x"], dtype=float)
        v = np.array(st["v"], dtype=float)
        F = np.array(st["F"], dtype=float)
        dF = np.zeros(self.E) if st["dF_n"] is None else np.array(st["dF_n"], dtype=float)
        fst[L.T], fst[L.H], fst[L.F_SEEN] = st["t"], st["h"], st["F_seen"]
        fst[L.H_ACC] = 0.0 if st["h_acc"] is None else st["h_acc"]
        fst[L.ERR_ACC] = 0.0 if st["err_acc"] is None else st["err_acc"]
        fst[L.H_GOOD], fst[L.T_STOP], fst[L.T_FINAL] = st["h_good"], st["t_stop"], st["t_final"]
        fst[L.RTOL], fst[L.ATOL], fst[L.M_MIN] = st["rtol"], st["atol"], st["m_min"]
        fst[L.PREV_BREAK], fst[L.TWO] = st["prev_break"], 2.0
        ist[:] = 0
        ist[L.HAVE_ACC] = st["h_acc"] is not None
        ist[L.HAVE_DF] = st["dF_n"] is not None
        ist[L.STALLED] = st["stalled"]
        ist[L.MAX_STEPS] = st["max_steps"]
        ist[L.BI] = st["bi"]
        ist[L.CREEPING] = st["creeping"]
        if self._breaks_of is not st["breaks"]:  # (one list for a whole run)
            self._breaks_of = st["breaks"]
            self.breaks = np.array(st["breaks"], dtype=float)
            self.kinks = np.array(st["kinks"], dtype=np.int64)
        if stats is not None:
            for key, i in _COUNTERS:
                ist[i] = stats[key]
        self.modes_a = np.array(modes, dtype=np.int64)
        self.watched_a = np.array(watched, dtype=np.int64)
        self.flat = st["flat"]
        return x, v, F, dF

    def _call(self, x, v, F, dF, T0, HS, Y0, D, ROWS) -> None:
        self.fn(self.law.addr, self.guards.addr, self.fold, self.js.consts, self.js.masses,
                self.js.ea, self.js.eb, self.js.spring, self.js.lock_q, self.modes_a,
                self.watched_a, self.checked, self.A, self.W, self.fkind, self.fpar, self.table,
                self.breaks, self.kinks, self.flat, x, v, F, dF, self.fst, self.ist, T0, HS, Y0,
                D, ROWS, self.ws, self.wm, self.iw)
        self.calls += 1

    def _workspace(self) -> None:
        """The compiled loop's work arrays, made on the first call (a run that is stuck
        throughout makes none); the attempts write no output rows: their blocks hold one
        row (a run writes its steps in place, :meth:`run`)."""
        self.outputs, self.ws, self.wm, self.iw = L.loop_workspace(self.N, self.E, self.E, 1)
        self.iw[1, 3] = roundoff_test() if (self.js.masses == 0.0).any() else 0  # junctions

    def compile_kernels(self) -> None:
        """Compile (or load from numba's disk cache) every kernel this loop calls through
        an address: the stage solve, the error estimate and the crossing test (its work
        arrays) and the probe's branch selector. A run compiles each at its first use;
        ``lumped warm`` calls this, as its short run may never step or probe (a scene held
        at rest)."""
        if self.ws is None:
            self._workspace()
        self._branch()

    @property
    def breakout_scan(self):
        """:func:`lumped.solvers.modes.stuck_jit.breakout_scan` compiled, or ``None`` while
        not compiled (:class:`~lumped.solvers.modes.on_demand.OnDemand`; then the Python
        reference of :class:`lumped.solvers.modes.stuck.StaticHold`, the same numbers)."""
        return _SCAN.get()

    @property
    def breakout_root(self):
        """:func:`lumped.solvers.modes.stuck_jit.breakout_root` compiled, or ``None``, as
        :attr:`breakout_scan`."""
        return _ROOT.get()

    def can_probe(self) -> bool:
        """:meth:`probe_modes` may run (its compiled probe is compiled on this machine,
        :class:`~lumped.solvers.modes.on_demand.OnDemand`); else the caller runs the
        Python probe of :func:`lumped.solvers.modes.mode_guess.try_modes` (the same
        numbers)."""
        if self._probe is None:
            fn = _PROBE.get()
            if fn is None:
                return False
            self._probe = (fn, *probe_workspace(self.N, self.E))
        return True

    def probe_modes(self, candidates, current, f: list[float], x: list[float], v: list[float],
                    F: list[float], h_p: float, locks: np.ndarray) -> tuple[int, np.ndarray]:
        """:func:`lumped.solvers.modes.mode_guess_jit.probe_modes` on the scene's kernels
        (``locks``: :func:`~lumped.solvers.modes.mode_guess.lock_rows`): ``(the index of the
        confirmed candidate or UNDECIDED or REFUSED, out)``, ``v_p, F_p`` in ``out``."""
        if self._probe is None:
            self._probe = (compiled_probe_modes(), *probe_workspace(self.N, self.E))
        fn, out, wm = self._probe
        js = self.js
        cands = np.array(candidates, dtype=np.int64).reshape(len(candidates), self.E)
        cur = _NO_MODE if current is None else np.array(current, dtype=np.int64)
        branch = self._branch()
        k = fn(self.law.addr, branch.addr, self.guards.addr, js.consts, js.masses, js.ea,
               js.eb, js.spring, cands, cur, np.array(f, dtype=float), np.array(x, dtype=float),
               np.array(v, dtype=float), np.array(F, dtype=float), h_p, out, wm, locks)
        return k, out

    def first_step_ready(self) -> bool:
        """:meth:`run` may take the first step after an event: its check is compiled
        (:mod:`~lumped.solvers.eventdriven.first_step_jit`, on demand) and no law's folds
        are checked (their test reads the start forces); else Python's, the same numbers."""
        return not len(self.checked) and _FIRST_STEP.get() is not None

    def forget(self) -> None:
        """The driver changed its state lists in place (an event): convert them again."""
        self._akey = None

    def attempt(self, t: float, h: float, x: list[float], v: list[float], F: list[float],
                dF_n: list[float] | None, F_seen: float, prev_break: float, modes: list[int],
                watched: list[int], after_impact: bool):
        """One step of size ``h`` from ``t``, not accepted: ``(U or None, its, nfac,
        err_norm, F_seen, hit)`` as the Python loop computes them (``hit``: ``(s, (w, j))``,
        the first guard crossing on the step, :func:`lumped.solvers.modes.crossing_root.
        first_root`, or ``None``, or :data:`~lumped.solvers.eventdriven.step.NOT_SOUGHT`
        while its compiled root finder is not compiled), or ``None`` when a Jacobian is
        singular (the Python loop's minimum-norm solve must run).

        The state lists are converted to arrays once while they are the same objects
        (the landing steps of an event retry one state with other ``h``); a driver that
        changes them in place calls :meth:`forget`."""
        fst, ist = self.fst, self.ist
        key = self._akey
        if (key is None or key[0] is not x or key[1] is not v or key[2] is not F
                or key[3] is not dF_n or key[4] != modes or key[5] != watched):
            self._akey = (x, v, F, dF_n, list(modes), list(watched))
            self._arrays = (np.array(x, dtype=float), np.array(v, dtype=float),
                            np.array(F, dtype=float),
                            np.zeros(self.E) if dF_n is None else np.array(dF_n, dtype=float))
            self.modes_a = np.array(modes, dtype=np.int64)
            self.watched_a = np.array(watched, dtype=np.int64)
        # (else: run() may have replaced the mode arrays with equal ones: kept)
        fst[L.T], fst[L.H], fst[L.F_SEEN], fst[L.PREV_BREAK] = t, h, F_seen, prev_break
        ist[L.SINGLE] = 1
        ist[L.HAVE_DF] = dF_n is not None
        if self.ws is None:
            self._workspace()
        # (the first step after an impact: the round-off floor within the tolerance)
        self.iw[1, 3] = with_impact_sign(self.iw[1, 3], after_impact)
        self._call(*self._arrays, *self.outputs)  # (an attempt writes no output)
        ok = int(ist[L.A_OK])
        if ok < 0:
            return None
        U = self.ws[0, :3 * (self.N + self.E)].tolist() if ok else None
        hit = None
        if ok and watched:  # the first crossing's root, compiled once compiled
            root = _ATTEMPT_ROOT.get()
            if root is None:
                hit = NOT_SOUGHT
            else:
                js = self.js
                root(self.guards.addr, js.consts, js.ea, js.eb, js.spring, self.modes_a,
                     self.watched_a, self.A, *self._arrays[:3], fst, ist, self.ws, self.wm)
                if ist[L.A_HIT]:
                    hit = (float(fst[L.A_ROOT]), (int(ist[L.A_W]), int(ist[L.A_J])))
        return (U, int(ist[L.A_ITS]), int(ist[L.A_NFAC]), float(fst[L.A_ERR]),
                float(fst[L.F_SEEN]), hit)

    def root_from(self, hit, F0: list[float]):
        """The first crossing on the last :meth:`attempt`'s step with the guards read from
        the forces ``F0`` at its start ``t`` (the driver's test after an event,
        :meth:`~lumped.solvers.eventdriven.checks.StepChecks.crossing`: ``F0`` the stage
        forces' quadratic at ``s = 0``, not the probe's forces): ``hit``, the attempt's
        crossing from the probe's forces, when it is ``None`` or at ``t`` itself
        (``s = 0``); else the compiled root finder again on the attempt's stage values
        (still in the work arrays), ``(s, (w, j))`` or ``None``, as
        :func:`~lumped.solvers.modes.crossing_root.first_root_py` finds it. One compiled
        call: no guard is evaluated in Python."""
        if hit is None or hit[0] == 0.0:
            return hit
        js, fst, ist = self.js, self.fst, self.ist
        x, v = self._arrays[0], self._arrays[1]
        _ATTEMPT_ROOT.get()(self.guards.addr, js.consts, js.ea, js.eb, js.spring, self.modes_a,
                            self.watched_a, self.A, x, v, np.array(F0, dtype=float), fst, ist,
                            self.ws, self.wm)
        again = (float(fst[L.A_ROOT]), (int(ist[L.A_W]), int(ist[L.A_J]))) if ist[L.A_HIT] \
            else None
        return hit if again is not None and again[0] == 0.0 else again  # (as crossing)

    def run(self, st: dict, modes: list[int], watched: list[int], stats: dict, dense,
            rows) -> str:
        """Advance the driver's state ``st`` (keys ``t, h, x, v, F, dF_n, F_seen, h_acc,
        err_acc, h_good, h_big, stalled, creeping, t_stop, t_final, prev_break, rtol, atol,
        m_min, max_steps, group, flat, held``: the dense output's group of the mode's locks,
        the held branches' flat ends (:meth:`~lumped.solvers.radau.flat_start.FlatEnds.table`)
        and after an event the elements whose dense output starts from the stage forces
        (:meth:`~lumped.solvers.eventdriven.checks.StepChecks.takes_first`), else ``None``)
        in place; returns the reason the loop stopped (``REASONS``).

        ``h_big`` is the longest step the run accepted (the scale of a bridge's steps,
        :mod:`lumped.solvers.eventdriven.bridge`): the longest of the steps taken here
        too, as the Python loop's accepted steps raise it one by one (but the one that
        stops a run that creeps, ``"creep"``: then ``st["t_prev"]`` is its start)."""
        x, v, F, dF = self._load(st, modes, watched, stats)
        fst, ist = self.fst, self.ist
        width = 1 + 2 * self.N + self.E
        h_big = st["h_big"]
        if self.ws is None:
            self._workspace()
        self.iw[1, 3] = with_impact_sign(self.iw[1, 3], False)  # (no impact at its start)
        if st["held"] is not None:  # (the first step after an event: first_step_jit)
            ist[L.FIRST], self.iw[3, :self.E], self.iw[1, L.FIRST_AT] = 1, st["held"], \
                _FIRST_STEP.get()
        while True:  # the accepted steps written in place into the output's arrays
            ist[L.N_OUT] = 0
            T0, HS, Y0, D = dense.block(BLOCK)
            self._call(x, v, F, dF, T0, HS, Y0, D, rows.block(BLOCK, width))
            k = int(ist[L.N_OUT])
            kept = k - (ist[L.REASON] == L.CREEP)  # (the Python loop's order)
            if kept > 0:
                h_big = max(h_big, float(HS[:kept].max()))
            if ist[L.REASON] == L.CREEP:
                st["t_prev"] = float(T0[k - 1])
            dense.commit(k, st["group"])
            rows.commit(k)
            if ist[L.REASON] != L.FULL:
                break
        st["h_big"] = h_big
        for key, i in _COUNTERS:
            stats[key] = int(ist[i])
        if ist[L.DEFECT_REJECTED]:  # (as the Python loop counts them)
            stats["defect_rejected"] = stats.get("defect_rejected", 0) + int(ist[L.DEFECT_REJECTED])
        st["t"], st["h"], st["F_seen"] = float(fst[L.T]), float(fst[L.H]), float(fst[L.F_SEEN])
        st["stalled"] = int(ist[L.STALLED])
        if ist[L.HAVE_ACC]:
            st["h_acc"], st["err_acc"] = float(fst[L.H_ACC]), float(fst[L.ERR_ACC])
        else:
            st["h_acc"] = st["err_acc"] = None
        st["h_good"] = float(fst[L.H_GOOD])
        st["x"], st["v"], st["F"] = x.tolist(), v.tolist(), F.tolist()
        st["dF_n"] = dF.tolist() if ist[L.HAVE_DF] else None
        st["bi"] = int(ist[L.BI])
        st["creeping"] = int(ist[L.CREEPING])
        return L.REASONS.get(int(ist[L.REASON]), "?")


_NO_MODE = np.zeros(0, dtype=np.int64)
# the shared compiled helpers of the events, compiled when a process needs them often
_SCAN = OnDemand(compiled_breakout_scan)
_ROOT = OnDemand(compiled_breakout_root)
_PROBE = OnDemand(compiled_probe_modes)
_ATTEMPT_ROOT = OnDemand(compiled_attempt_root)
_FIRST_STEP = OnDemand(compiled_first_step)
_BUTCHER: list = []


def _butcher() -> tuple[np.ndarray, np.ndarray]:
    """``A`` and ``W = A^-1`` of :mod:`lumped.solvers.radau.stage` as arrays, made once (the
    loop only reads them)."""
    if not _BUTCHER:
        from ..radau.tableau import A, W

        _BUTCHER.extend((np.array(A), np.array(W)))
    return _BUTCHER[0], _BUTCHER[1]


_COUNTERS = (("steps", L.STEPS), ("rejected", L.REJECTED),
             ("newton_iterations", L.NEWTON_ITERATIONS), ("factorizations", L.FACTORIZATIONS),
             ("nfev", L.NFEV), ("njev", L.NJEV), ("max_newton_iterations", L.MAX_NEWTON_ITERATIONS))


def compiled_stage_solver(scene: Scene, modes: list[int]):
    """The stage Newton compiled with numba (:mod:`lumped.solvers.radau.stage_jit`, the
    operations of :meth:`StageSystem.solve`, bit for bit) on the scene's branch kernels,
    ``modes`` read at each call (the run's live list): ``(U, h, x, v, f, scale, max_iters,
    after_impact) -> (U or None, its, nfac)`` (``after_impact``: the step starts at an
    impact, :mod:`lumped.solvers.radau.roundoff`), or ``None`` for a singular finite
    Jacobian: the caller redoes the attempt with :meth:`StageSystem.solve`'s minimum-norm
    solve from the same guess (as the compiled loop does,
    :data:`~lumped.solvers.eventdriven.loop_jit.SINGULAR`), so both loops pick the same
    solution of a singular system (a junction between two slipping Coulomb elements)."""
    from ...codegen.dispatch import dispatch_scene
    from ...codegen.jit import jit_scene, numba_enabled
    from ..radau.stage_jit import compiled_stage_solve, workspace
    from ..radau.tableau import A, W

    if numba_enabled():  # the structure-generic kernels, as the compiled loop's
        js, law = dispatch_scene(scene), dispatch_pointers()[0]
    else:  # (plain Python: the scene module's functions)
        js = jit_scene(scene)
        law = js.module.branch_law
    solve = compiled_stage_solve()
    ws = workspace(len(scene.nodes), len(scene.elements))
    A_np, W_np = np.array(A), np.array(W)

    def run(U, h, x, v, f, scale, max_iters, after_impact):
        Ua = np.array(U, dtype=float)
        ws[-1][3] = with_impact_sign(ws[-1][3], after_impact)
        ok = solve(law, js.consts, js.masses, js.ea, js.eb, js.spring, js.lock_q,
                   np.array(modes, dtype=np.int64),
                   A_np, W_np, Ua, h, np.array(x, dtype=float), np.array(v, dtype=float),
                   np.array(f, dtype=float), np.array(scale, dtype=float), 1e-3, max_iters,
                   *ws)
        out = ws[-1]
        if not ok and out[2] == 1 and np.isfinite(ws[1]).all():
            return None  # (singular: Python's minimum-norm solve)
        return (Ua.tolist() if ok else None), int(out[0]), int(out[1])

    return run
