"""Solution.plot(): three panels with units, stick intervals shaded; the plot extra."""

from __future__ import annotations

import sys

import pytest

from lumped import simulate
from lumped.scene import bingham_oscillator, paper_F2


def test_plot_renders_to_png_with_agg(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sol = simulate(bingham_oscillator(forcing=paper_F2), method="closed-bdf1", dt=1e-2,
                   t_end=5.0)
    axes = sol.plot(title="forcing F2")
    labels = [ax.get_ylabel() for ax in axes]
    assert labels == ["displacement x [m]", "velocity v [m/s]", "force F [N] (tension > 0)"]
    assert axes[-1].get_xlabel() == "time t [s]"
    shaded = [p for p in axes[0].patches]
    assert len(shaded) >= 1        # the final stick at least
    path = tmp_path / "sol.png"
    axes[0].figure.savefig(path)
    plt.close(axes[0].figure)
    assert path.stat().st_size > 1000


def test_plot_without_matplotlib_says_which_extra(monkeypatch):
    sol = simulate(bingham_oscillator(x0=0.5), method="closed-bdf1", dt=1e-2, t_end=1.0)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match=r"plot.*extra"):
        sol.plot()
