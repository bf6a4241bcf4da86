"""Figures: x, v, F_s and F_d against t (paper Figures 5-14), and x, v and the forces of
any :class:`~lumped.result.Solution` (:func:`plot_solution`); needs the ``plot`` extra."""

from __future__ import annotations

from pathlib import Path

from ._optional import require
from .trajectory import Trajectory

__all__ = ["have_matplotlib", "plot_solution", "plot_trajectory"]

_PANELS = (
    ("x", "displacement x"),
    ("v", "velocity v"),
    ("F_s", "spring force F_s"),
    ("F_d", "dashpot force F_d"),
)


def have_matplotlib() -> bool:
    """True when matplotlib can be imported."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


def plot_trajectory(traj: Trajectory, path: str | Path, title: str = "") -> Path:
    """Save a four-panel figure of ``traj`` (x, v, F_s, F_d against t) to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(7.0, 8.0), constrained_layout=True)
    for ax, (name, label) in zip(axes, _PANELS, strict=True):
        ax.plot(traj.t, getattr(traj, name), lw=1.0)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time t")
    if title:
        axes[0].set_title(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_solution(sol, ax=None, *, title: str = "", shade_sticks: bool = True):
    """Three panels against ``t`` (s): ``x`` (m) and ``v`` (m/s) of every node, and the
    force (N, positive in tension) of every element; the stick intervals of the dashpots
    shaded (see :meth:`lumped.result.Solution.plot`).

    Parameters
    ----------
    sol : Solution
    ax : sequence of three matplotlib Axes, optional
        Default: a new figure with three stacked panels sharing ``t``.
    title : str
    shade_sticks : bool

    Returns
    -------
    numpy.ndarray of Axes
    """
    import numpy as np

    plt = require("matplotlib.pyplot", "Solution.plot()")
    if ax is None:
        _, ax = plt.subplots(3, 1, sharex=True, figsize=(7.0, 7.0), constrained_layout=True)
    axes = np.asarray(ax, dtype=object).ravel()
    if len(axes) != 3:
        raise ValueError(f"`ax` must hold three Axes (x, v, forces), got {len(axes)}")
    panels = ((sol.x, "displacement x [m]"), (sol.v, "velocity v [m/s]"),
              (sol.F, "force F [N] (tension > 0)"))
    for axis, (table, label) in zip(axes, panels, strict=True):
        for name, values in table.items():
            axis.plot(sol.t, values, lw=1.0, label=name)
        axis.set_ylabel(label)
        axis.grid(True, alpha=0.3)
        if len(table) > 1:
            axis.legend(loc="best", fontsize="small")
    if shade_sticks and sol.scene is not None:
        colours = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["grey"])
        for k, (name, spans) in enumerate(sol.stick_intervals().items()):
            for j, (a, b) in enumerate(spans):
                for axis in axes:
                    axis.axvspan(a, b, color=colours[k % len(colours)], alpha=0.15, lw=0,
                                 label=f"{name} sticks" if (j == 0 and axis is axes[0])
                                 else None)
        if any(sol.stick_intervals().values()):
            axes[0].legend(loc="best", fontsize="small")
    axes[-1].set_xlabel("time t [s]")
    if title:
        axes[0].set_title(title)
    return axes
