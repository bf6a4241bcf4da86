"""Sampled trajectories of one mass, and the stick/slip summary of Section 3.

A :class:`Trajectory` holds the four unknowns of the semi-explicit DAE (paper
eqs. 8a-8c) on a time grid: displacement ``x``, velocity ``v``, spring force
``F_s`` and dashpot force ``F_d``. Sign convention: both forces act on the mass
opposite to positive ``x``, so ``m v' = F(t) - F_s - F_d``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Trajectory", "StickSummary", "summarize", "CSV_COLUMNS"]

CSV_COLUMNS = ("t", "x", "v", "F_s", "F_d")


@dataclass(frozen=True)
class Trajectory:
    """Arrays ``t, x, v, F_s, F_d`` of equal length ``n_steps + 1``.

    Attributes
    ----------
    t, x, v, F_s, F_d : numpy.ndarray
        Time, displacement, velocity, spring force and dashpot force. Row 0 is the
        (consistent) initial state.
    method : str
        The method that produced the arrays, e.g. ``"closed-bdf1"``.
    stats : dict
        Cost counters (steps, and for iterative methods Newton iterations etc.).
    predictor : numpy.ndarray or None
        For the closed-form steps, the predictor ``F~`` of each step (row 0 holds
        ``F_d(0)``); ``None`` otherwise.
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    F_s: np.ndarray
    F_d: np.ndarray
    method: str
    stats: dict = field(default_factory=dict)
    predictor: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.t)
        for name in CSV_COLUMNS:
            arr = getattr(self, name)
            if len(arr) != n:
                raise ValueError(f"`{name}` has {len(arr)} samples, expected {n}")
            if not np.all(np.isfinite(arr)):
                bad = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise FloatingPointError(
                    f"non-finite `{name}` = {arr[bad]!r} at t = {self.t[bad]!r} (step {bad})"
                )

    def __len__(self) -> int:
        return len(self.t)

    def as_array(self) -> np.ndarray:
        """Return an ``(n, 5)`` array with the columns of :data:`CSV_COLUMNS`."""
        return np.column_stack([getattr(self, c) for c in CSV_COLUMNS])

    def to_csv(self, path: str | Path) -> Path:
        """Write ``t,x,v,F_s,F_d`` with one row per step at full (round-trip) precision."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(
            path, self.as_array(), fmt="%.17g", delimiter=",",
            header=",".join(CSV_COLUMNS), comments="",
        )
        return path


@dataclass(frozen=True)
class StickSummary:
    """What Section 3 reads off a run.

    Attributes
    ----------
    final_x, final_v : float
        State at the last sample.
    last_stick_time : float or None
        Time of the last slip-to-stick transition (first sample with ``|v| <= v_tol``
        after one with ``|v| > v_tol``); ``None`` if the mass never came to rest
        after moving.
    rest_position : float or None
        ``x`` at the end if the mass is stuck there, else ``None``.
    stick_time : float
        Total time spent stuck: ``dt`` times the number of steps ``n >= 1`` with
        ``|v_n| <= v_tol``.
    """

    final_x: float
    final_v: float
    last_stick_time: float | None
    rest_position: float | None
    stick_time: float


def summarize(traj: Trajectory, v_tol: float = 0.0) -> StickSummary:
    """Summarise stick/slip behaviour of ``traj``; ``v_tol`` is the velocity counted as rest."""
    stuck = np.abs(traj.v) <= v_tol
    dts = np.diff(traj.t)
    stick_time = float(np.sum(dts[stuck[1:]]))
    onsets = np.flatnonzero(stuck[1:] & ~stuck[:-1]) + 1
    last = float(traj.t[onsets[-1]]) if onsets.size else None
    rest = float(traj.x[-1]) if stuck[-1] else None
    return StickSummary(
        final_x=float(traj.x[-1]), final_v=float(traj.v[-1]),
        last_stick_time=last, rest_position=rest, stick_time=stick_time,
    )


def fmt_number(value: float | None) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value:.6g}"
