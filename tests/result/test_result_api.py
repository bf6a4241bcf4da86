"""The Solution as a researcher uses it: names, stats, tables, display; the oscillator
helper and the deprecated front door."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import lumped
from lumped import simulate
from lumped.scene import SineBurst, bingham_oscillator, paper_F2
from lumped.solvers import Status


@pytest.fixture(scope="module")
def sol():
    return simulate(bingham_oscillator(forcing=paper_F2), method="bdf2", dt=1e-2, t_end=5.0)


def test_states_status_and_scipy_like_counters(sol):
    assert sol.success and sol.ok and sol.status is Status.SUCCESS and sol.message == ""
    assert np.array_equal(sol.x["mass"], sol.column("x_mass"))
    assert set(sol.F) == {"spring", "dashpot"}
    for alias, key in (("nfev", "residual_evals"), ("njev", "jacobian_evals"),
                       ("nlu", "factorizations")):
        assert sol.stats[alias] == sol.stats[key] > 0


def test_repr_is_short_and_html_is_a_table(sol):
    text = repr(sol)
    assert text.startswith("Solution(") and "bdf2" in text and "success" in text
    assert "501 samples" in text and "events=" in text and len(text) < 200
    assert "array" not in text and "\n" not in text
    page = sol._repr_html_()
    assert page.startswith("<table>") and "<td style='text-align:left'>bdf2</td>" in page


def test_to_pandas_and_missing_pandas(sol, monkeypatch):
    frame = sol.to_pandas()
    assert list(frame.columns) == list(sol.columns[1:]) and frame.index.name == "t"
    np.testing.assert_array_equal(frame["x_mass"].to_numpy(), sol.x["mass"])
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match="needs pandas"):
        sol.to_pandas()


def test_to_csv_header_unchanged(sol, tmp_path):
    path = sol.to_csv(tmp_path / "out.csv")
    assert path.read_text().splitlines()[0] == "t,x_mass,v_mass,F_spring,F_dashpot"
    np.testing.assert_array_equal(np.loadtxt(path, delimiter=",", skiprows=1), sol.data)


def test_bound_law_shows_its_residual_in_latex():
    law = lumped.get_law("linear_spring")
    assert law._repr_latex_().startswith("$") and "k" in law._repr_latex_()
    bound = law.bind(k=100.0)
    latex = bound._repr_latex_()
    assert latex.startswith("$") and latex.endswith("$") and "100" in latex


def test_oscillator_helper_is_the_papers_scene():
    scene = bingham_oscillator(m=2.0, k=50.0, gamma=0.5, tau=0.3, x0=0.1, v0=-0.2,
                               forcing=SineBurst(1.0, 3.0, 2.0))
    assert scene.node_names == ("mass",) and scene.element_names == ("spring", "dashpot")
    sol = simulate(scene, dt=1e-3, t_end=1.0)
    assert sol.method == "closed-bdf2"
    assert (sol.x["mass"][0], sol.v["mass"][0]) == (0.1, -0.2)
    generic = simulate(scene, method="bdf2", dt=1e-3, t_end=1.0)
    np.testing.assert_allclose(generic.data, sol.data, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="k"):
        bingham_oscillator(k=-1.0)


def test_the_closed_form_integrate_is_the_closed_methods_numbers():
    """``lumped.solvers.closed.integrate.integrate`` (its ``Trajectory``) and
    ``simulate(..., method="closed-bdf1")`` (a ``Solution``) give the same numbers."""
    from lumped.solvers.closed.closed_form import BinghamOscillator
    from lumped.solvers.closed.integrate import integrate

    osc = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)
    traj = integrate(osc, x0=0.0, forcing=paper_F2, dt=1e-3, t_end=1.0, method="bdf1")
    sol = simulate(bingham_oscillator(forcing=paper_F2), method="closed-bdf1", dt=1e-3,
                   t_end=1.0)
    np.testing.assert_array_equal(traj.x, sol.x["mass"])
