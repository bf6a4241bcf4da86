r"""The one result type of :func:`lumped.simulate`: :class:`Solution`.

A solution holds the samples of a run (``data``, one row per sample, laid out as
:meth:`lumped.scene.Scene.columns`) and the scene that produced them, and works out from
them, on demand: dense output ``sol(t)``, switching ``events``, the ``stick_intervals()``
of the dashpots, the ``energy()`` ledger, a ``plot()`` and tables (``to_csv``,
``to_pandas``). Names follow ``scipy.integrate.solve_ivp`` where scipy has one
(``t``, ``sol``, ``status``, ``message``, ``success``, ``nfev``/``njev``/``nlu``).
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._optional import require
from .post.dense import check_times, hermite_dense
from .post.energy import EnergyLedger, energy_ledger
from .post.frames import (
    Frame,
    GroundTrace,
    absolute_frame,
    frame_columns,
    ground_trace,
    relative_frame,
    support_traces,
)
from .post.switching import (
    branch_history,
    event_lock_intervals,
    lock_intervals,
    locking_branches,
    switch_events,
)
from .solvers.status import Event, Status

__all__ = ["Solution"]

#: scipy-like aliases of the counters (alias -> the key every method fills).
STAT_ALIASES = {"nfev": "residual_evals", "njev": "jacobian_evals", "nlu": "factorizations"}


@dataclass(frozen=True, eq=False)
class Solution:
    """The result of :func:`lumped.simulate`.

    Attributes
    ----------
    columns : tuple of str
        ``t``, then ``x_<node>``, ``v_<node>`` per node, then ``F_<element>`` per element.
    data : numpy.ndarray
        ``(n_samples, len(columns))`` array; row 0 is the consistent initial state. Never
        holds NaN or infinity (checked: :class:`FloatingPointError`).
    node_names, element_names : tuple of str
    method : str
        The method that ran (``auto`` resolved).
    stats : dict
        Cost counters: ``steps``, ``newton_iterations``, ``residual_evals``,
        ``jacobian_evals``, ``factorizations``, ``max_newton_iterations`` (zero for the
        closed forms), and the scipy-like aliases ``nfev``, ``njev``, ``nlu`` of the
        residual evaluations, Jacobian evaluations and LU factorisations.
    status : Status
    message : str
        Empty on success; otherwise what failed, when and where.
    located_events : tuple of Event or None
        The events the method located itself, or ``None`` when it reported none (the
        fixed-step methods): :attr:`events` then derives the branch switches from the
        samples.
    indeterminate : dict
        Element name -> intervals ``(t0, t1)`` on which its force is not unique.
    scene : Scene or None
        The scene that was simulated (needed by ``sol``, ``events``, ``energy``, ...).
    dense : callable or None
        The method's own dense output ``t -> rows``; ``None``: cubic Hermite between
        samples (:mod:`lumped.post.dense`).

    Examples
    --------
    >>> from lumped import simulate
    >>> from lumped.scene import bingham_oscillator
    >>> sol = simulate(bingham_oscillator(x0=0.5), method="closed-bdf2", dt=1e-3, t_end=5.0)
    >>> sol.success, sol.method, len(sol.t)
    (True, 'closed-bdf2', 5001)
    >>> sol.stick_intervals("dashpot")[-1]        # at rest from t = 3.145 s on
    (3.145, 5.0)
    >>> round(float(sol.x["mass"][-1]), 5)         # where: |k x| <= tau
    0.00275
    """

    columns: tuple[str, ...]
    data: np.ndarray
    node_names: tuple[str, ...]
    element_names: tuple[str, ...]
    method: str
    stats: dict = field(default_factory=dict)
    status: Status = Status.SUCCESS
    message: str = ""
    located_events: tuple[Event, ...] | None = None
    indeterminate: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    scene: Any = field(default=None, repr=False)
    dense: Callable[[np.ndarray], np.ndarray] | None = field(default=None, repr=False)
    _cache: dict = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        if self.data.ndim != 2 or self.data.shape[1] != len(self.columns):
            raise ValueError(
                f"`data` has shape {self.data.shape}, expected (n, {len(self.columns)})"
            )
        # (a finite sum is the common case, one pass; a sum that overflows is checked
        # value by value)
        if not (math.isfinite(self.data.sum()) or np.isfinite(self.data).all()):
            r, c = np.argwhere(~np.isfinite(self.data))[0]
            raise FloatingPointError(
                f"non-finite {self.columns[c]} = {self.data[r, c]!r} at row {r}"
            )
        stats = dict(self.stats)
        for alias, key in STAT_ALIASES.items():
            if key in stats:
                stats.setdefault(alias, stats[key])
        object.__setattr__(self, "stats", stats)

    # -- states by name --------------------------------------------------------------------
    def column(self, name: str) -> np.ndarray:
        """One column by name, e.g. ``"x_mass"``."""
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(f"no column {name!r}; columns are {self.columns}") from None

    @property
    def t(self) -> np.ndarray:
        """Sample times (s)."""
        return self.data[:, 0]

    @property
    def x(self) -> dict[str, np.ndarray]:
        """Displacement per node (m)."""
        return {n: self.column(f"x_{n}") for n in self.node_names}

    @property
    def v(self) -> dict[str, np.ndarray]:
        """Velocity per node (m/s)."""
        return {n: self.column(f"v_{n}") for n in self.node_names}

    @property
    def F(self) -> dict[str, np.ndarray]:
        """Force per element (N, positive in tension)."""
        return {e: self.column(f"F_{e}") for e in self.element_names}

    @property
    def forces(self) -> np.ndarray:
        """``(n_samples, n_elements)`` array of the element forces."""
        return self.data[:, 1 + 2 * len(self.node_names):]

    @property
    def ok(self) -> bool:
        """``status is Status.SUCCESS``."""
        return self.status is Status.SUCCESS

    @property
    def success(self) -> bool:
        """``status is Status.SUCCESS`` (scipy's name)."""
        return self.ok

    # -- derived on demand -----------------------------------------------------------------
    def _need_scene(self, what: str):
        if self.scene is None:
            raise ValueError(f"{what} needs the scene; this Solution was built without one")
        return self.scene

    def _cached(self, key: str, make: Callable[[], Any]) -> Any:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    def sol(self, t: float | Sequence[float] | np.ndarray) -> np.ndarray:
        """Dense output: the state at any time(s) in the solved interval.

        Uses the method's own interpolant when it has one (``dense``); otherwise the
        cubic Hermite interpolant of :mod:`lumped.post.dense` (``x`` with ``v`` as its
        derivative, a mass's ``v`` with its acceleration from the momentum balance,
        junction velocities and forces linear), exact at the samples.

        Parameters
        ----------
        t : float or array_like
            Time(s) in ``[t[0], t[-1]]`` (``[0, t_end]`` for a complete run).

        Returns
        -------
        numpy.ndarray
            A row laid out like :attr:`columns` (shape ``(len(columns),)``) for a scalar
            ``t``, else ``(len(t), len(columns))``.

        Raises
        ------
        ValueError
            If a time is outside the solved interval or not finite (the message names
            ``t`` and quotes the value).
        """
        times, scalar = check_times(t, float(self.t[0]), float(self.t[-1]))
        dense = self.dense or self._cached(
            "dense", lambda: hermite_dense(self._need_scene("sol()"), self.data))
        rows = np.asarray(dense(times), dtype=float).reshape(len(times), len(self.columns))
        return rows[0] if scalar else rows

    @property
    def events(self) -> tuple[Event, ...]:
        """Switching events, impacts and time events, in time order.

        The method's own (located) events when it locates them; for the fixed-step
        methods, the branch switches read off the samples: an event at the first sample
        on which an element's new branch is active (late by less than one step, see
        :mod:`lumped.post.switching`).
        """
        if self.located_events is not None:
            return tuple(self.located_events)
        if self.scene is None:
            return ()
        return self._cached("events", lambda: tuple(switch_events(self.t, self._history())))

    def _history(self) -> dict[str, np.ndarray]:
        return self._cached("history", lambda: branch_history(
            self._need_scene("the branch history"), self.data))

    def stick_intervals(self, element: str | None = None):
        """Intervals on which a dashpot sticks (its law's active branch is a rate lock,
        ``q = 0`` exactly), as ``[(t_start, t_end), ...]``: for a method that locates its
        events (``radau5``), from the event into the lock to the event out of it (a
        velocity reversal through ``q = 0`` is no stick); otherwise from sample to sample
        (:mod:`lumped.post.switching`).

        Parameters
        ----------
        element : str, optional
            A dashpot element's name; ``None`` for all dashpots.

        Returns
        -------
        list of (float, float), or dict
            The intervals of ``element``, or ``{dashpot name: intervals}``.

        Raises
        ------
        ValueError
            If ``element`` is not the name of a dashpot of the scene.
        """
        scene = self._need_scene("stick_intervals()")
        dashpots = [el.name for el in scene.elements if el.kind == "dashpot"]
        if element is None:
            return {name: self.stick_intervals(name) for name in dashpots}
        if element not in dashpots:
            raise ValueError(f"`element` must name a dashpot of the scene {dashpots}, "
                             f"got {element!r}")
        locking = locking_branches(scene, element)
        if self.located_events is not None:  # the method located its events: use them
            own = [e for e in self.located_events
                   if e.element == element and e.kind == "switch"]
            initial = (min(own, key=lambda e: e.t).from_branch if own
                       else int(self._history()[element][-1]))
            return event_lock_intervals(own, element, locking, float(self.t[0]),
                                        float(self.t[-1]), initial)
        return lock_intervals(self.t, self._history()[element], locking)

    def energy(self, frame: str = "relative") -> EnergyLedger:
        """The energy ledger over time: kinetic energy per mass, stored energy per spring,
        dissipated energy per dashpot, work of the forcing per node, work of a moving
        ground (``support``), energy lost at impacts and the balance residual (see
        :mod:`lumped.post.energy`).

        Parameters
        ----------
        frame : {"relative", "absolute"}
            The frame of the kinetic energy and the work when the ground moves (the same
            ledger otherwise)."""
        return self._cached(f"energy-{frame}", lambda: energy_ledger(
            self._need_scene("energy()"), self.data, self.events if self.located_events
            else (), frame=frame))

    # -- frames (a moving ground, lumped.post.frames) ----------------------------------
    @property
    def a(self) -> dict[str, np.ndarray]:
        """Acceleration per mass (m/s^2), relative to the ground, from the momentum
        balance at each sample (:mod:`lumped.post.frames`)."""
        return self.relative.a

    @property
    def relative(self) -> Frame:
        """The motion relative to the ground (the solver's states: ``x``, ``v`` per node
        as :attr:`x`, :attr:`v`; ``a`` per mass from the balance)."""
        return self._cached("relative", lambda: relative_frame(
            self._need_scene("the relative frame"), self.data))

    @property
    def absolute(self) -> Frame:
        """The absolute motion, ``x + x_g``, ``v + v_g``, ``a + a_g`` (equal to
        :attr:`relative` when the ground does not move)."""
        return self._cached("absolute", lambda: absolute_frame(
            self._need_scene("the absolute frame"), self.data, self.relative))

    @property
    def supports(self) -> dict[str, GroundTrace]:
        """Each support's prescribed absolute ``x``, ``v``, ``a`` at the samples
        (:func:`lumped.post.frames.support_traces`; empty without supports)."""
        return self._cached("supports", lambda: support_traces(
            self._need_scene("the support motion"), self.t))

    @property
    def ground(self) -> GroundTrace:
        """The ground's prescribed ``x``, ``v``, ``a`` at the samples (zero if fixed)."""
        return self._cached("ground", lambda: ground_trace(
            self._need_scene("the ground motion"), self.t))

    # -- output ----------------------------------------------------------------------------
    def plot(self, ax=None, *, title: str = "", shade_sticks: bool = True):
        """Plot ``x``, ``v`` and the element forces against ``t`` (three panels, units in
        the labels), stick intervals shaded. Needs the ``plot`` extra (matplotlib).

        Parameters
        ----------
        ax : sequence of three matplotlib Axes, optional
            Where to draw; default a new figure.
        title : str
        shade_sticks : bool
            Shade the stick intervals of the dashpots.

        Returns
        -------
        numpy.ndarray of Axes
        """
        from .plotting import plot_solution

        return plot_solution(self, ax, title=title, shade_sticks=shade_sticks)

    def to_csv(self, path: str | Path) -> Path:
        """Write the columns with a header line, ``%.17g`` (round-trip precision).

        When the ground moves, the columns of :func:`lumped.post.frames.frame_columns`
        follow (``x_ground``, ``v_ground``, ``a_ground``, the relative ``a_<mass>``, the
        absolute ``x_abs_<node>``, ``v_abs_<node>``, ``a_abs_<mass>``); with supports,
        ``x_<support>``, ``v_<support>``, ``a_<support>`` and ``a_<mass>``."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        names, data = list(self.columns), self.data
        if (getattr(self.scene, "ground_motion", None) is not None
                or getattr(self.scene, "supports", None)):
            extra, cols = frame_columns(self.scene, self.data)
            names, data = names + extra, np.hstack([data, cols])
        np.savetxt(path, data, fmt="%.17g", delimiter=",", header=",".join(names),
                   comments="")
        return path

    def to_pandas(self):
        """The samples as a ``pandas.DataFrame`` indexed by ``t`` (needs pandas)."""
        pd = require("pandas", "Solution.to_pandas()")
        return pd.DataFrame(self.data, columns=list(self.columns)).set_index("t")

    def _summary(self) -> list[tuple[str, str]]:
        t0, t1 = (float(self.t[0]), float(self.t[-1]))
        rows = [("method", self.method), ("status", self.status.value),
                ("samples", str(len(self.data))), ("t", f"[{t0:g}, {t1:g}] s"),
                ("nodes", ", ".join(self.node_names)),
                ("elements", ", ".join(self.element_names))]
        if self.scene is not None or self.located_events is not None:
            try:
                rows.append(("events", str(len(self.events))))
            except TypeError:  # a law the branch machinery cannot read (hand-written kernel)
                pass
        rows += [(k, str(self.stats[k])) for k in ("steps", "nfev", "njev", "nlu")
                 if k in self.stats]
        if self.message:
            rows.append(("message", self.message))
        return rows

    def __repr__(self) -> str:
        keep = ("method", "status", "samples", "t", "events")
        body = ", ".join(f"{k}={v}" if k != "samples" else f"{v} samples"
                         for k, v in self._summary() if k in keep)
        return f"Solution({body})"

    def _repr_html_(self) -> str:
        cells = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                        f"<td style='text-align:left'>{html.escape(v)}</td></tr>"
                        for k, v in self._summary())
        return f"<table><caption>lumped Solution</caption>{cells}</table>"
