"""Scene files with a moving ground and force tables (issue 28): round trips against the
same scene built in Python, and every bad entry named with the file, key and value."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.io import SceneFileError, load_scene, read_at2, read_table
from lumped.scene import GroundMotion, SineBurst

RECORD = Path(__file__).resolve().parents[2] / "examples" / "records" / "synthetic_ground.at2"

HEAD = """
[solver]
method = "bdf2"
dt = 0.01
t_end = 3.0

[nodes.m]
mass = 2.0
{force}

[elements.spring]
law = "linear_spring"
between = ["ground", "m"]
parameters = {{ k = 50.0 }}

[elements.slider]
law = "coulomb"
between = ["ground", "m"]
parameters = {{ tau = 1.0, r = 1.0 }}
"""


def _scene(**motion) -> Scene:
    return Scene([Mass("m", m=2.0)],
                 [Element("spring", get_law("linear_spring").bind(k=50.0), "ground", "m"),
                  Element("slider", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "m")],
                 forces=motion.pop("forces", None), ground_motion=GroundMotion(**motion))


def _write(tmp_path: Path, ground: str, force: str = "") -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(HEAD.format(force=force) + "\n[ground]\n" + ground)
    return path


def test_a_record_and_a_force_table_round_trip(tmp_path):
    sub = tmp_path / "data"
    sub.mkdir()
    (sub / "push.csv").write_text("t,F\n0,0\n1,2\n2,0\n")
    rec = tmp_path / "data" / "record.at2"
    rec.write_text(RECORD.read_text())
    path = _write(tmp_path, 'motion = { kind = "table", file = "data/record.at2", '
                  'quantity = "acceleration", units = "g", factor = 0.5 }\nv0 = 0.1\n',
                  'force = { kind = "table", file = "data/push.csv", units = "kN" }')
    scene, settings = load_scene(path)
    table = read_at2(RECORD, units="g", factor=0.5)
    push = read_table(sub / "push.csv", quantity="force", units="kN")
    twin = _scene(acceleration=table, v0=0.1, forces={"m": push})
    a, b = simulate(scene, **settings), simulate(twin, **settings)
    np.testing.assert_array_equal(a.data, b.data)
    np.testing.assert_array_equal(a.ground.x, b.ground.x)
    assert a.ground.v[0] == 0.1


@pytest.mark.parametrize(("toml", "motion"), [
    ('motion = { kind = "sine", amplitude = 0.02, omega = 6.0, quantity = "displacement" }',
     {"displacement": SineBurst(0.02, 6.0)}),
    ('motion = { kind = "sine", amplitude = 2.0, omega = 6.0, t_off = 1.5 }',
     {"acceleration": SineBurst(2.0, 6.0, 1.5)}),
    ('motion = { kind = "expression", expression = "0.1*t*exp(-t)", quantity = "velocity" }',
     {"velocity": "0.1*t*exp(-t)"}),
    ('motion = "1.5*sin(2*t)"\nx0 = 0.25', {"acceleration": "1.5*sin(2*t)", "x0": 0.25}),
])
def test_sine_and_expression_motions_round_trip(tmp_path, toml, motion):
    scene, settings = load_scene(_write(tmp_path, toml))
    a, b = simulate(scene, **settings), simulate(_scene(**motion), **settings)
    np.testing.assert_array_equal(a.data, b.data)
    np.testing.assert_allclose(a.absolute.x["m"], b.x["m"] + b.ground.x, rtol=0, atol=0)


@pytest.mark.parametrize(("ground", "force", "words"), [
    ('motion = { kind = "table", file = "nope.at2" }', "",
     "[ground] motion file: 'nope.at2'"),
    ('motion = { kind = "table", file = "r.csv", quantity = "force" }', "",
     "[ground] motion quantity: must be 'acceleration' or 'velocity' or 'displacement' here, "
     "got 'force'"),
    ('motion = { kind = "table", file = "r.csv", units = "furlong" }', "", "furlong"),
    ('motion = { kind = "wave", amplitude = 1.0 }', "", "[ground] motion kind"),
    ('motion = { kind = "sine", amplitude = 1.0 }', "", "[ground] motion omega: missing"),
    ('motion = { kind = "sine", amplitude = 1.0, omega = 2.0, quantity = "velocity", '
     't_off = 1.0 }', "", "t_off"),
    ('motion = "__import__(\'os\')"', "", "[ground] motion: bad expression"),
    ('motion = 1.0\nshake = 2', "", "[ground] shake: unknown key"),
    ("v0 = 1.0", "", "[ground] motion: missing"),
    ("motion = 1.0", 'force = { kind = "table", file = "r.csv", quantity = "acceleration" }',
     "[nodes.m] force quantity: must be 'force' here, got 'acceleration'"),
    ("motion = 1.0", 'force = { kind = "table", file = "r.csv", quantity = "force", '
     'units = "g" }', "[nodes.m] force file"),
])
def test_bad_entries_name_the_file_key_and_value(tmp_path, ground, force, words):
    (tmp_path / "r.csv").write_text("t,a\n0,0\n1,1\n")
    path = _write(tmp_path, ground, force)
    with pytest.raises(SceneFileError) as info:
        load_scene(path)
    assert str(info.value).startswith(str(path)) and words in str(info.value), info.value


def test_the_force_sine_table_still_reads_as_before(tmp_path):
    path = _write(tmp_path, "motion = 0.0",
                  f'force = {{ kind = "sine", amplitude = 0.5, omega = {5 * math.pi}, '
                  't_off = 1.0 }')
    scene, _ = load_scene(path)
    assert scene.applied_forcing[0] == SineBurst(0.5, 5 * math.pi, 1.0)
