"""Scene files: loading, the shipped examples, errors naming file/key/value, `lumped run`."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pytest

from lumped.cli import compare as cmd_compare
from lumped.cli import run as cmd_run
from lumped.compare import compare
from lumped.io.scenefile import SceneFileError, load_scene, scene_from_dict
from lumped.scene import Junction, Mass, SineBurst
from lumped.solvers.closed.closed_form import BinghamOscillator
from lumped.solvers.closed.integrate import integrate

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
PAPER = {"forcing-F1": (0.0, 0.5), "forcing-F2": (0.0, 10.0),
         "release-0.005": (0.005, None), "release-0.5": (0.5, None)}


@pytest.mark.parametrize("name", sorted(PAPER))
def test_paper_examples_load_as_the_paper_scene(name):
    scene, settings = load_scene(EXAMPLES / f"{name}.toml")
    x0, amp = PAPER[name]
    assert settings == {"method": "auto", "dt": 1e-4, "t_end": 5.0}
    (mass,) = scene.nodes
    assert isinstance(mass, Mass) and (mass.m, mass.x0, mass.v0) == (1.0, x0, 0.0)
    assert scene.element_names == ("spring", "dashpot")
    assert dict(scene.elements[0].law.params) == {"k": 100.0}
    assert dict(scene.elements[1].law.params) == {"gamma": 1.0, "tau": 1.0}
    force = scene.forcing[0]
    if amp is None:
        assert force is None
    else:
        assert force == SineBurst(amp, 5 * math.pi, 1.0)


def test_other_examples_load_and_run():
    for path in sorted(EXAMPLES.glob("*.toml")):
        scene, settings = load_scene(path)
        if path.stem in PAPER:
            continue
        assert (any(isinstance(n, Junction) for n in scene.nodes) or len(scene.nodes) > 1
                or path.stem in ("impact", "lock")  # issue 11: one mass on a string
                or scene.supports)  # issue 28: one mass on a moving support
        from lumped.simulate import simulate

        sol = simulate(scene, method=settings["method"], dt=settings["dt"] * 10, t_end=1.0)
        assert sol.ok


def _run(tmp_path, *argv):
    parser = argparse.ArgumentParser()
    cmd_run.add_arguments(parser)
    args = parser.parse_args([*argv])
    return cmd_run.run(args)


@pytest.mark.parametrize("method", ["closed-bdf1", "bdf1"])
def test_lumped_run_reproduces_algorithm_1(tmp_path, method, capsys):
    out = tmp_path / "r.csv"
    t_end = 0.5 if method == "bdf1" else 5.0
    code = _run(tmp_path, str(EXAMPLES / "release-0.5.toml"), "--out", str(out),
                "--method", method, "--dt", "1e-4", "--t-end", str(t_end))
    assert code == 0
    header = out.read_text().splitlines()[0]
    assert header == "t,x_mass,v_mass,F_spring,F_dashpot"
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    traj = integrate(BinghamOscillator(1.0, 100.0, 1.0, 1.0), x0=0.5, dt=1e-4, t_end=t_end)
    ref = traj.as_array()
    scale = np.maximum(1.0, np.abs(ref).max(axis=0))
    assert (np.abs(data - ref) <= 1e-12 * scale).all()
    if method == "closed-bdf1":
        np.testing.assert_array_equal(data, ref)


def test_lumped_run_writes_partial_csv_and_fails_with_code_1(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(
        '[nodes.mass]\nmass = 0.01\nx0 = -6.0\nforce = "-9 + 2*t"\n'
        '[elements.s]\nlaw = "s_shaped"\nbetween = ["ground", "mass"]\n'
        "parameters = { q0 = 1.0, F0 = 1.0 }\n"
        '[elements.damper]\nlaw = "newtonian"\nbetween = ["ground", "mass"]\n'
        "parameters = { c = 0.05 }\n"
    )
    out = tmp_path / "s.csv"
    assert _run(tmp_path, str(path), "--out", str(out), "--dt", "1e-3", "--t-end", "8") == 1
    assert "solver stopped" in capsys.readouterr().err
    assert len(out.read_text().splitlines()) > 100


def test_lumped_run_needs_dt_and_t_end(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text('[nodes.mass]\nmass = 1.0\n')
    with pytest.raises(ValueError, match="--dt"):  # a fixed-step method needs dt
        _run(tmp_path, str(path), "--out", str(tmp_path / "o.csv"), "--method", "bdf2")
    with pytest.raises(ValueError, match="--t-end"):  # auto (radau5 here) does not
        _run(tmp_path, str(path), "--out", str(tmp_path / "o.csv"))
    with pytest.raises(ValueError, match="--t-end"):
        _run(tmp_path, str(path), "--out", str(tmp_path / "o.csv"), "--dt", "0.1")


def test_bad_method_on_the_command_line(tmp_path):
    with pytest.raises(SystemExit):
        _run(tmp_path, "x.toml", "--out", "o.csv", "--method", "rk4")


GOOD = {
    "solver": {"dt": 0.01, "t_end": 1.0},
    "nodes": {"mass": {"mass": 1.0, "x0": 0.1}},
    "elements": {"spring": {"law": "linear_spring", "between": ["ground", "mass"],
                            "parameters": {"k": 10.0}}},
}


def _with(path, value):
    import copy

    data = copy.deepcopy(GOOD)
    *head, last = path
    d = data
    for k in head:
        d = d.setdefault(k, {})
    if value is _DELETE:
        del d[last]
    else:
        d[last] = value
    return data


_DELETE = object()


@pytest.mark.parametrize(
    "path, value, match",
    [
        (("solver", "dt"), -1.0, r"\[solver\] dt: must be positive, got -1.0"),
        (("solver", "rtol"), 0.0, r"\[solver\] rtol: must be positive, got 0.0"),
        (("solver", "atol"), "x", r"\[solver\] atol: must be a number"),
        (("solver", "method"), "euler", r"\[solver\] method: must be one of"),
        (("solver", "tol"), 1.0, r"\[solver\] tol: unknown key"),
        (("nodes", "mass", "mass"), "heavy", r"\[nodes.mass\] mass: must be a number, got 'heavy'"),
        (("nodes", "mass", "mass"), 0.0, r"\[nodes.mass\]: .mass of node 'mass'. must be positive"),
        (("nodes", "mass", "colour"), 1, r"\[nodes.mass\] colour: unknown key"),
        (("nodes", "mass", "force"), "__import__('os')", r"\[nodes.mass\] force: bad expression"),
        (("nodes", "mass", "force"), "t.real", r"\[nodes.mass\] force: bad expression"),
        (("nodes", "mass", "force"), "x + t", r"\[nodes.mass\] force: bad expression"),
        (("nodes", "mass", "force"), {"kind": "square"}, r"force kind: must be one of .*square"),
        (("nodes", "mass", "force"), {"kind": "sine", "amplitude": 1.0}, r"force omega: missing"),
        (("elements", "spring", "law"), "hooke", r"\[elements.spring\] law: unknown law 'hooke'"),
        (("elements", "spring", "parameters"), {"q": 1.0}, r"\[elements.spring\] parameters"),
        (("elements", "spring", "parameters"), {}, r"\[elements.spring\] parameters"),
        (("elements", "spring", "between"), ["ground"], r"between: must be a list of two"),
        (("elements", "spring", "between"), ["ground", "moon"], r"unknown node 'moon'"),
        (("elements", "spring", "between"), ["mass", "mass"], r"'mass' to itself"),
        (("elements", "spring", "F0"), 5.0, None),
        (("extra",), {}, r"extra: unknown top-level table"),
        (("nodes",), _DELETE, r"nodes: a scene needs"),
    ],
)
def test_scene_file_errors_name_file_key_value(path, value, match):
    data = _with(path, value)
    if match is None:  # F0 = 5 breaks the spring law at x0 = 0.1 (k x0 = 1): caught later
        scene, _ = scene_from_dict(data, source="s.toml")
        from lumped.simulate import simulate
        from lumped.solvers.status import InconsistentInitialForce

        with pytest.raises(InconsistentInitialForce, match="linear_spring"):
            simulate(scene, dt=0.01, t_end=0.1)
        return
    with pytest.raises(SceneFileError, match=match) as info:
        scene_from_dict(data, source="s.toml")
    assert str(info.value).startswith("s.toml: ")


def test_toml_syntax_and_missing_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[nodes.mass\nmass = 1")
    with pytest.raises(SceneFileError, match="bad.toml: not valid TOML"):
        load_scene(bad)
    with pytest.raises(SceneFileError, match="no such scene file"):
        load_scene(tmp_path / "nope.toml")


def test_expression_forcing_from_a_file(tmp_path):
    data = _with(("nodes", "mass", "force"), "Piecewise((0.5*sin(5*pi*t), t <= 1), (0, True))")
    scene, _ = scene_from_dict(data)
    f = scene.forcing[0]
    assert f(0.1) == pytest.approx(0.5, rel=1e-15) and f(2.0) == 0.0


def test_junction_without_mass_and_no_v0(tmp_path):
    data = _with(("nodes", "j"), {"x0": 0.0, "v0": 1.0})
    with pytest.raises(SceneFileError, match=r"\[nodes.j\] v0: a junction"):
        scene_from_dict(data)


def test_compare_reports_differences_and_ratio(capsys):
    scene, _ = load_scene(EXAMPLES / "forcing-F2.toml")
    rep = compare(scene, dt=1e-3, t_end=1.0, method="bdf1", repeat=1)
    assert rep.steps == 1000 and rep.ratio > 0
    assert max(rep.max_rel_diff.values()) < 1e-11
    assert "ratio" in rep.format()
    parser = argparse.ArgumentParser()
    cmd_compare.add_arguments(parser)
    args = parser.parse_args([str(EXAMPLES / "release-0.5.toml"), "--dt", "1e-3",
                              "--t-end", "0.5", "--repeat", "1"])
    assert cmd_compare.run(args) == 0
    assert "x_mass" in capsys.readouterr().out
    maxwell, _ = load_scene(EXAMPLES / "maxwell.toml")
    with pytest.raises(ValueError, match="does not cover"):
        compare(maxwell, dt=1e-2, t_end=0.1)


def test_custom_law_example_runs(tmp_path, monkeypatch, capsys):
    import runpy

    path = EXAMPLES / "custom_law_simulate.py"
    assert len(path.read_text().splitlines()) < 20
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(path), run_name="__main__")
    assert capsys.readouterr().out.startswith("success")
    header = (tmp_path / "custom_law.csv").read_text().splitlines()[0]
    assert header == "t,x_mass,v_mass,F_spring,F_drag"


@pytest.mark.parametrize("name", sorted(PAPER))
def test_example_files_are_the_paper_scenarios(name, tmp_path):
    """`lumped run examples/<name>.toml --method closed-bdf1` writes the same numbers as
    `lumped paper`'s <name>.csv (only the header names differ)."""
    from lumped.scenarios import PAPER_SCENARIOS, run_scenario

    scen = PAPER_SCENARIOS[name]
    scene, _ = load_scene(EXAMPLES / f"{name}.toml")
    assert scene.nodes[0].x0 == scen.x0 and scene.nodes[0].v0 == scen.v0
    f = scene.forcing[0]
    for t in np.linspace(0.0, 2.0, 41):
        assert (f(t) if f is not None else 0.0) == scen.forcing(t)
    out = tmp_path / "run.csv"
    assert _run(tmp_path, str(EXAMPLES / f"{name}.toml"), "--out", str(out),
                "--method", "closed-bdf1", "--t-end", "0.5") == 0
    paper = run_scenario(name, method="closed-bdf1", t_end=0.5).to_csv(tmp_path / "paper.csv")
    assert out.read_text().splitlines()[1:] == paper.read_text().splitlines()[1:]


def test_lumped_run_junction_held_by_two_stuck_dashpots(tmp_path, capsys):
    # a junction held by two stuck Bingham dashpots and pulled by a spring: the motion is
    # determinate (the junction stays), the split of the force between the dashpots is
    # not (issue 11): the run completes
    path = tmp_path / "c.toml"
    path.write_text(
        '[nodes.mass]\nmass = 1.0\nx0 = 0.5\n[nodes.j]\n'
        '[elements.s]\nlaw = "linear_spring"\nbetween = ["j", "mass"]\n'
        "parameters = { k = 10.0 }\n"
        '[elements.d1]\nlaw = "bingham"\nbetween = ["ground", "j"]\n'
        "parameters = { gamma = 1.0, tau = 10.0 }\n"
        '[elements.d2]\nlaw = "bingham"\nbetween = ["ground", "j"]\n'
        "parameters = { gamma = 1.0, tau = 10.0 }\n"
    )
    out = tmp_path / "o.csv"
    code = _run(tmp_path, str(path), "--out", str(out), "--dt", "1e-2", "--t-end", "0.1")
    assert code == 0, capsys.readouterr().err
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.all(np.abs(data[:, 3]) <= 1e-12)  # x_j: the junction stays


def test_lumped_run_without_consistent_initial_state(tmp_path, capsys):
    # a Maxwell link whose spring starts stretched beyond what its Coulomb element can
    # carry: no initial state satisfies the laws; refused naming element and law
    path = tmp_path / "c.toml"
    path.write_text(
        '[nodes.mass]\nmass = 1.0\nx0 = 0.5\n[nodes.j]\n'
        '[elements.s]\nlaw = "linear_spring"\nbetween = ["j", "mass"]\n'
        "parameters = { k = 10.0 }\n"
        '[elements.d]\nlaw = "coulomb"\nbetween = ["ground", "j"]\n'
        "parameters = { tau = 1.0, r = 10.0 }\n"
    )
    with pytest.raises(ValueError, match="inconsistent initial state") as info:
        _run(tmp_path, str(path), "--out", str(tmp_path / "o.csv"), "--dt", "1e-2",
             "--t-end", "0.1")
    err = str(info.value)
    assert "'d'" in err and "'coulomb'" in err and "junction 'j'" in err


def test_tolerances_from_the_file_and_the_command_line(tmp_path, capsys):
    path = tmp_path / "r.toml"
    path.write_text('[solver]\nmethod = "radau5"\nt_end = 1.0\nrtol = 1e-3\natol = 1e-6\n'
                    '[nodes.mass]\nmass = 1.0\nx0 = 0.1\n'
                    '[elements.spring]\nlaw = "linear_spring"\nbetween = ["ground", "mass"]\n'
                    'parameters = { k = 10.0 }\n')
    _, settings = load_scene(path)
    assert (settings["rtol"], settings["atol"]) == (1e-3, 1e-6)
    out = tmp_path / "o.csv"
    assert _run(tmp_path, str(path), "--out", str(out)) == 0
    loose = np.loadtxt(out, delimiter=",", skiprows=1)
    assert _run(tmp_path, str(path), "--out", str(out), "--rtol", "1e-9", "--atol", "1e-12") == 0
    tight = np.loadtxt(out, delimiter=",", skiprows=1)
    assert len(tight) > len(loose)  # step points: more of them at the tighter tolerance
    exact = 0.1 * np.cos(math.sqrt(10.0) * tight[:, 0])
    assert np.max(np.abs(tight[:, 1] - exact)) <= 1e-8
