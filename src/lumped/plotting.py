"""Figures of x, v, F_s and F_d against t (paper Figures 5-14); needs the ``plot`` extra."""

from __future__ import annotations

from pathlib import Path

from .trajectory import Trajectory

__all__ = ["have_matplotlib", "plot_trajectory"]

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
