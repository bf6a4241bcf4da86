r"""The event study: the nodal error of the step methods split at the events of the exact
solution (reversals, stick, break-out, the forcing's switch-off).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..solvers.closed.integrate import integrate
from .scenes import SCENES

__all__ = [
    "EVENT_SCENES",
    "event_study",
    "event_markdown",
]

# --------------------------------------------------------------------------- events


#: Scenes of the event study: reversals, stick/break-out, forcing, a single stop.
EVENT_SCENES = ("release-0.5", "stick-breakout", "forcing-F2", "viscous-soft")


def event_study(
    scene_names: Sequence[str] = EVENT_SCENES,
    *,
    dts: Sequence[float] | None = None,
    methods: Sequence[str] = ("bdf1", "bdf2"),
    windows: int = 3,
) -> list[dict]:
    """Observed order of the closed-form steps between the events of the exact solution.

    For each scene and step formula, the error ``|x_n - x(t_n)|`` at the method's own
    nodes is split into windows: before the first event, then between consecutive
    events (each window named after the event that opens it: ``reversal``, ``stick``
    or ``breakout``; ``forcing-off`` is not counted as an event), plus the whole run
    and the final value.  ``dts`` should not be commensurate (default: 13 values
    ``1e-3 * 10**(-j/6)``), so the events fall at varied fractions ``theta`` of a step;
    each row holds the least-squares slope of ``log err`` on ``log dt`` and the spread
    ``max/min`` of ``err / dt^slope`` over the ladder (near 1 for a clean power law,
    large when the constant depends on ``theta``).
    """
    from ..reference import exact_solution

    dts = tuple(1e-3 * 10.0 ** (-j / 6.0) for j in range(13)) if dts is None else tuple(dts)
    by_name = {s.name: s for s in SCENES}
    rows: list[dict] = []
    for name in scene_names:
        scene = by_name[name]
        probe = exact_solution(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.forcing,
                               t_eval=[0.0, scene.t_end])
        events = [e for e in probe.events if e.kind != "forcing-off"]
        edges = [0.0] + [e.t for e in events[:windows]]
        labels = ["before 1st event"] + [f"after event {i + 1} ({e.kind})"
                                         for i, e in enumerate(events[:windows])]
        ends = edges[1:] + [events[windows].t if len(events) > windows else math.inf]
        for method in methods:
            errs: dict[str, list[tuple[float, float]]] = {}
            for dt in dts:
                traj = integrate(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.force,
                                 dt=dt, t_end=scene.t_end, method=method)
                ref = exact_solution(scene.osc, x0=scene.x0, v0=scene.v0,
                                     forcing=scene.forcing, t_eval=traj.t).trajectory.x
                err = np.abs(traj.x - ref)
                for label, lo, hi in zip(labels, edges, ends, strict=True):
                    inside = (traj.t > lo) & (traj.t < hi) if lo > 0 else traj.t < hi
                    if np.any(inside):
                        errs.setdefault(label, []).append((dt, float(np.max(err[inside]))))
                errs.setdefault("whole run", []).append((dt, float(np.max(err))))
                errs.setdefault("end value", []).append((dt, float(err[-1])))
            for label, pts in errs.items():
                p = slope_above_floor(pts, 1e-13)
                spread = math.nan
                if math.isfinite(p):
                    c = [e / d**p for d, e in pts if e > 1e-13]
                    spread = max(c) / min(c)
                rows.append({"scene": name, "method": f"closed-{method}", "window": label,
                             "order": p, "spread": spread,
                             "err_at_finest": pts[-1][1]})
    return rows


def event_markdown(rows: Sequence[dict]) -> str:
    """The event study as a markdown table."""
    lines = ["| scene | method | window | observed order | spread of err/dt^p | "
             "err at finest dt |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['method']} | {r['window']} | {r['order']:.2f} | "
                     f"{r['spread']:.3g} | {r['err_at_finest']:.2e} |")
    return "\n".join(lines) + "\n"


def slope_above_floor(points: list[tuple[float, float]], floor: float) -> float:
    pts = [(math.log(d), math.log(e)) for d, e in points if e > floor]
    if len(pts) < 3:
        return math.nan
    xs = np.array([p[0] for p in pts])
    ys = np.array([p[1] for p in pts])
    return float(np.polyfit(xs, ys, 1)[0])
