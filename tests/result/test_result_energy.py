"""Solution.energy(): the ledger balances to the method's accuracy, and shrinks with dt."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.scene import bingham_oscillator, paper_F1, paper_F2

T_END = 3.0


def _paper(name: str) -> Scene:
    return {"forcing-F1": bingham_oscillator(forcing=paper_F1),
            "forcing-F2": bingham_oscillator(forcing=paper_F2),
            "release-0.5": bingham_oscillator(x0=0.5)}[name]


def _maxwell() -> Scene:
    """A mass on a spring to ground and a Maxwell arm (spring + Bingham dashpot in series)
    driven by a force."""
    return Scene(
        [Mass("mass", m=1.0, x0=0.2), Junction("j", x0=0.0)],
        [Element("spring", get_law("linear_spring").bind(k=50.0), "ground", "mass"),
         Element("arm", get_law("linear_spring").bind(k=200.0), "j", "mass"),
         Element("damper", get_law("bingham").bind(gamma=0.5, tau=0.5), "ground", "j")],
        forces={"mass": "3*sin(4*t)"},
    )


def _relative_residual(sol) -> float:
    ledger = sol.energy()
    return float(np.max(np.abs(ledger.residual))) / ledger.scale()


# (scene, method, order p): max |residual| <= C_p dt^p (largest energy entry). Measured
# C (dt = 4e-3 .. 2.5e-4): order 1 at most 54, order 2 at most 1.1e4 (the Maxwell scene;
# the paper's scenes about 150); the bounds leave a margin of about 1.5.
CASES = [
    ("forcing-F2", "bdf1", 1), ("forcing-F2", "closed-bdf1", 1),
    ("release-0.5", "bdf1", 1), ("release-0.5", "closed-bdf1", 1),
    ("forcing-F2", "bdf2", 2), ("forcing-F2", "closed-bdf2", 2),
    ("release-0.5", "bdf2", 2), ("release-0.5", "closed-bdf2", 2),
    ("maxwell", "bdf1", 1), ("maxwell", "bdf2", 2),
]


@pytest.mark.parametrize(("scene", "method", "order"), CASES)
def test_energy_balance_closes_to_the_method_accuracy(scene, method, order):
    make = _maxwell if scene == "maxwell" else lambda: _paper(scene)
    errs = []
    for dt in (4e-3, 1e-3):
        sol = simulate(make(), method=method, dt=dt, t_end=T_END)
        errs.append(_relative_residual(sol))
    bound = {1: 80.0 * 4e-3, 2: 1.6e4 * 4e-3**2}[order]
    assert errs[0] <= bound, (errs, bound)
    assert errs[1] <= errs[0] / (3.0 if order == 1 else 8.0), errs   # dt / 4: order p


def test_exact_samples_balance_to_the_quadrature_error():
    """The exact motion sampled: only the trapezoidal rule's O(dt^2) remains (measured
    1.0e-5 at dt = 1e-3)."""
    sol = simulate(_paper("forcing-F2"), method="exact", dt=1e-3, t_end=T_END)
    assert _relative_residual(sol) < 20.0 * 1e-3**2


def test_ledger_entries():
    sol = simulate(_paper("forcing-F2"), method="closed-bdf1", dt=1e-3, t_end=T_END)
    led = sol.energy()
    x = sol.x["mass"]
    # trapezoidal F dq is exact for a linear spring: k (x^2 - x0^2) / 2
    np.testing.assert_allclose(led.stored["spring"], 50.0 * (x**2 - x[0] ** 2),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(led.kinetic["mass"], 0.5 * sol.v["mass"] ** 2)
    assert np.all(np.diff(led.dissipated["dashpot"]) >= 0)   # Bingham: F q >= 0
    assert led.work["mass"][-1] > 0 and not led.impacts.any()
    table = led.to_dict()
    assert set(table) == {"t", "kinetic_mass", "stored_spring", "dissipated_dashpot",
                          "work_mass", "impacts", "residual"}
    assert "max |residual|" in repr(led) and len(repr(led)) < 300
    frame = led.to_pandas()
    assert list(frame.columns) == list(table)[1:] and len(frame) == len(sol.t)
