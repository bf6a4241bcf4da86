"""Tabulated inputs: CSV and AT2 readers, units, errors naming file and line, the Table as
a forcing (interpolation, breakpoints) and its exact integration."""

from __future__ import annotations

import bisect
import math
import pickle
import runpy
import sys
import tempfile
from dataclasses import replace
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.io import Table, TableError, detrend, read_at2, read_table
from lumped.io.units import UNITS, G, unit_scale
from lumped.scene import SineBurst

ROOT = Path(__file__).resolve().parents[2]
RECORDS = ROOT / "examples" / "records"

AT2_NEW = """PEER NGA STRONG MOTION DATABASE RECORD
SYNTHETIC, TEST
ACCELERATION TIME SERIES IN UNITS OF G
NPTS=  7, DT=   .0050 SEC
  .1000000E-01  .2000000E-01 -.3000000E-01 -.4000000E-01  .5000000E-01
  .6000000E-01  .7000000E-01
"""
AT2_OLD = """PACIFIC ENGINEERING AND ANALYSIS STRONG-MOTION DATA
 SYNTHETIC, TEST
 ACCELERATION TIME HISTORY IN UNITS OF G
 7 0.00500 NPTS, DT
  .1000000E-01  .2000000E-01 -.3000000E-01 -.4000000E-01  .5000000E-01
  .6000000E-01  .7000000E-01
"""
EXPECTED_G = [0.01, 0.02, -0.03, -0.04, 0.05, 0.06, 0.07]


def _write(tmp_path: Path, text: str, name: str = "table.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# -- the readers -----------------------------------------------------------------------------
@pytest.mark.parametrize("text", [AT2_NEW, AT2_OLD], ids=["NPTS=,DT=", "n dt NPTS,DT"])
def test_at2_both_header_forms(tmp_path, text):
    table = read_at2(_write(tmp_path, text, "rec.AT2"))
    assert table.quantity == "acceleration" and table.unit == "m/s^2"
    assert table.source == "rec.AT2" and len(table) == 7
    np.testing.assert_allclose(table.times, 0.005 * np.arange(7), rtol=0, atol=1e-15)
    np.testing.assert_allclose(table.values, G * np.array(EXPECTED_G), rtol=1e-15)


def test_at2_units_and_quantity_from_the_header_or_the_arguments(tmp_path):
    text = AT2_NEW.replace("UNITS OF G", "UNITS OF CM/S/S")
    assert read_at2(_write(tmp_path, text, "a.at2")).values[0] == pytest.approx(1e-4)
    vel = AT2_NEW.replace("ACCELERATION TIME SERIES IN UNITS OF G",
                          "VELOCITY TIME SERIES IN UNITS OF CM/S")
    table = read_at2(_write(tmp_path, vel, "v.vt2"))
    assert table.quantity == "velocity" and table.values[0] == pytest.approx(1e-4)
    # arguments win over the header
    table = read_at2(_write(tmp_path, AT2_NEW, "b.at2"), units="m/s^2", factor=2.0)
    assert table.values[0] == pytest.approx(0.02)


def test_at2_fortran_fields_that_touch_and_d_exponents(tmp_path):
    text = AT2_NEW.replace(" -.3000000E-01 -.4000000E-01", "-.3000000D-01-.4000000E-01")
    table = read_at2(_write(tmp_path, text, "a.at2"), units="m/s^2")
    assert table.values.tolist() == pytest.approx(EXPECTED_G)


def test_csv_columns_by_name_and_index_with_comments_and_other_columns(tmp_path):
    path = _write(tmp_path, "# a record\n\nid,time,acc,note\n0,0.0,1.5,a\n1,0.5,-2.5,b\n"
                            "2,1.0,0.25,c\n")
    by_name = read_table(path, quantity="acceleration", time_column="time",
                         value_column="acc", units="cm/s^2")
    by_index = read_table(path, quantity="acceleration", time_column=1, value_column=2,
                          units="gal")
    assert by_name.times.tolist() == [0.0, 0.5, 1.0]
    assert by_name.values.tolist() == pytest.approx([0.015, -0.025, 0.0025], rel=1e-15)
    assert by_index.values.tolist() == by_name.values.tolist()
    semi = _write(tmp_path, "t;F\n0;1\n1;2\n", "semi.csv")
    assert read_table(semi, quantity="force", delimiter=";", units="kN")(0.5) == 1500.0


@pytest.mark.parametrize(("unit", "quantity", "scale"), [
    ("g", "acceleration", 9.80665), ("m/s^2", "acceleration", 1.0),
    ("cm/s^2", "acceleration", 0.01), ("gal", "acceleration", 0.01),
    ("Gal", "acceleration", 0.01), ("cm/s2", "acceleration", 0.01),
    ("mm/s^2", "acceleration", 1e-3), ("m/s", "velocity", 1.0), ("cm/s", "velocity", 0.01),
    ("mm/s", "velocity", 1e-3), ("m", "displacement", 1.0), ("cm", "displacement", 0.01),
    ("mm", "displacement", 1e-3), ("N", "force", 1.0), ("kN", "force", 1e3),
    (None, "force", 1.0),
])
def test_unit_conversions(tmp_path, unit, quantity, scale):
    assert unit_scale(unit, quantity) == scale
    path = _write(tmp_path, "t,y\n0,2\n1,-4\n")
    table = read_table(path, quantity=quantity, units=unit, factor=0.5)
    assert table.values.tolist() == [1.0 * scale, -2.0 * scale]


def test_every_unit_is_listed_with_its_quantity():
    assert {q for q, _ in UNITS.values()} == {"force", "acceleration", "velocity",
                                               "displacement"}


def test_unit_errors_name_the_unit_and_the_known_ones(tmp_path):
    path = _write(tmp_path, "t,y\n0,2\n1,-4\n")
    with pytest.raises(ValueError, match="unknown unit 'furlong'.*known units: g, m/s"):
        read_table(path, quantity="acceleration", units="furlong")
    with pytest.raises(ValueError, match="unit of displacement, not of acceleration"):
        read_table(path, quantity="acceleration", units="cm")
    with pytest.raises(ValueError, match="`quantity` must be one of"):
        read_table(path, quantity="jerk")
    with pytest.raises(ValueError, match="`factor` must be finite"):
        read_table(path, quantity="force", factor=math.inf)
    with pytest.raises(ValueError, match="`outside` must be 'zero' or 'hold'"):
        read_table(path, quantity="force", outside="extrapolate")


# -- every bad file gets its error: the file, the line and the problem ------------------------
BAD_CSV = [
    ("t,y\n0,1\n1,2\n1,3\n", 4, "time .* is not after the time .* on line 3 .*increase strictly"),
    ("t,y\n0,1\n2,2\n1,3\n", 4, "time .* is not after the time .* on line 3"),
    ("t,y\n0,1\n1,nan\n", 3, "value \\('y'\\) 'nan' is not finite"),
    ("t,y\n0,1\n1,-inf\n", 3, "'-inf' is not finite"),
    ("t,y\n0,1\n1,1e999\n", 3, "is not finite \\(it overflows\\)"),
    ("t,y\n0,1\n1,abc\n", 3, "'abc' is not a number"),
    ("t,y\n0,1\n1,__import__('os')\n", 3, "is not a number"),
    ("t,y\n0,1\nx,2\n", 3, "time \\('t'\\) 'x' is not a number"),
    ("t,y\n0,1\n1,\n", 3, "value \\('y'\\) is empty"),
    ("t,y\n0,1\n1\n", 3, "missing column: the row has 1 field"),
    ("t,y\n", 1, "the table is empty \\(no data rows"),
    ("# only a comment\n\n", 2, "the table is empty"),
    ("", 1, "the table is empty"),
    ("t,y\n0,1\n", 2, "only one data row"),
    ("0,1\n1,2\n", 1, "expected a header line"),
]


@pytest.mark.parametrize(("text", "line", "problem"), BAD_CSV)
def test_every_bad_csv_gets_its_error(tmp_path, text, line, problem):
    path = _write(tmp_path, text, "bad.csv")
    with pytest.raises(TableError, match=f"bad.csv: line {line}: .*{problem}"):
        read_table(path, quantity="force")


@pytest.mark.parametrize(("kwargs", "problem"), [
    ({"value_column": "acc"}, "missing column: no column 'acc' in the header \\(columns: 't'"),
    ({"value_column": 5}, "missing column: `value_column` = 5 but the header has 2 columns"),
    ({"time_column": "time"}, "no column 'time'"),
])
def test_a_missing_column_names_the_header_line(tmp_path, kwargs, problem):
    path = _write(tmp_path, "t,y\n0,1\n1,2\n", "cols.csv")
    with pytest.raises(ValueError, match=f"cols.csv: line 1: .*{problem}"):
        read_table(path, quantity="force", **kwargs)


def test_a_missing_file_and_a_binary_file_are_named(tmp_path):
    with pytest.raises(TableError, match="nope.csv: no such table file"):
        read_table(tmp_path / "nope.csv", quantity="force")
    binary = tmp_path / "bin.csv"
    binary.write_bytes(b"t,y\n0,1\n\xff\xfe,2\n")
    with pytest.raises(TableError, match="bin.csv: line 3: not a text file"):
        read_table(binary, quantity="force")


BAD_AT2 = [
    (AT2_NEW.replace("NPTS=  7", "NPTS=  8"), 4,
     "the header says NPTS = 8 but the file holds 7 values \\(lines 5 to 6\\)"),
    (AT2_NEW.replace("NPTS=  7", "NPTS=  6"), 4, "NPTS = 6 but the file holds 7 values"),
    (AT2_OLD.replace(" 7 0.00500", " 9 0.00500"), 4, "NPTS = 9 but the file holds 7"),
    (AT2_NEW.replace("DT=   .0050", "DT=   -.0050"), 4, "bad DT .*must be positive"),
    (AT2_NEW.replace("DT=   .0050", "DT=   0.0"), 4, "bad DT"),
    (AT2_NEW.replace("DT=   .0050", "DT=   fast"), 4, "DT 'fast' is not a number"),
    (AT2_NEW.replace("NPTS=  7", "NPTS=  7.5"), 4, "NPTS '7.5' is not a whole number"),
    (AT2_NEW.replace("NPTS=  7, DT=   .0050 SEC", "SEVEN POINTS"), 4,
     "cannot read NPTS and DT"),
    (AT2_NEW.replace(" .5000000E-01", " NaN"), 5, "value 'NaN' is not finite"),
    (AT2_NEW.replace(" .7000000E-01", " 7e0x"), 6, "value '7e0x' is not a number"),
    ("\n".join(AT2_NEW.splitlines()[:3]) + "\n", 3, "ends inside the 4-line AT2 header"),
    ("\n".join(AT2_NEW.splitlines()[:4]).replace("NPTS=  7", "NPTS=  0") + "\n", 4,
     "the table is empty"),
    ("\n".join(AT2_NEW.splitlines()[:4]).replace("NPTS=  7", "NPTS=  1") + "\n .1\n", 4,
     "only one value; a table needs at least 2 points"),
    (AT2_NEW.replace("IN UNITS OF G", "IN UNITS OF FURLONGS"), 3, "cannot tell the units"),
    (AT2_NEW.replace("ACCELERATION ", ""), 3, "cannot tell the quantity"),
]


@pytest.mark.parametrize(("text", "line", "problem"), BAD_AT2)
def test_every_bad_at2_gets_its_error(tmp_path, text, line, problem):
    path = _write(tmp_path, text, "bad.at2")
    with pytest.raises(TableError, match=f"bad.at2: line {line}: .*{problem}"):
        read_at2(path)


def test_at2_units_of_another_quantity_are_refused_naming_line_3(tmp_path):
    path = _write(tmp_path, AT2_NEW.replace("UNITS OF G", "UNITS OF CM"), "d.at2")
    with pytest.raises(TableError, match="d.at2: line 3: .*unit of displacement, not of "
                                         "acceleration"):
        read_at2(path)


# -- the Table as a forcing ------------------------------------------------------------------
def test_interpolation_outside_and_errors():
    f = Table([0.0, 1.0, 3.0], [1.0, 3.0, -1.0], quantity="force")
    assert [f(t) for t in (0.0, 0.5, 1.0, 2.0, 3.0)] == [1.0, 2.0, 3.0, 1.0, -1.0]
    assert (f(-1.0), f(4.0)) == (0.0, 0.0)
    hold = replace(f, outside="hold")
    assert (hold(-1.0), hold(4.0)) == (1.0, -1.0)
    assert type(f(1)) is float and type(f(0.25)) is float
    with pytest.raises(ValueError, match="called at t = nan"):
        f(math.nan)
    assert f.breakpoints(-1.0, 5.0) == [0.0, 1.0, 3.0]
    assert f.breakpoints(0.0, 3.0) == [1.0] and f.breakpoints(1.5, 2.5) == []
    assert pickle.loads(pickle.dumps(f))(0.5) == 2.0
    with pytest.raises(ValueError, match="read-only"):
        f.times[0] = 5.0


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"times": [0.0], "values": [1.0]}, "at least 2 points"),
    ({"times": [0.0, 0.0], "values": [1.0, 2.0]}, "must increase strictly: times\\[1\\]"),
    ({"times": [0.0, 1.0], "values": [1.0]}, "same length"),
    ({"times": [0.0, math.nan], "values": [1.0, 2.0]}, "`times\\[1\\]` must be finite"),
    ({"times": [[0.0, 1.0]], "values": [1.0, 2.0]}, "one-dimensional"),
    ({"times": [0.0, 1.0], "values": [1.0, 2.0], "quantity": "jerk"}, "`quantity`"),
])
def test_table_arguments_are_checked(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Table(**({"quantity": "force"} | kwargs))
    with pytest.raises(TypeError, match="`values` must be an array of real numbers"):
        Table([0.0, 1.0], ["a", "b"], quantity="force")


def test_integration_of_a_constant_and_a_ramp():
    a = Table([0.0, 1.0, 3.0], [2.0, 2.0, 2.0], quantity="acceleration")
    v, x = a.integrated(v0=1.0, x0=0.5)
    assert v.values.tolist() == [1.0, 3.0, 7.0]               # 1 + 2 t
    assert x.values.tolist() == [0.5, 2.5, 12.5]              # 0.5 + t + t^2
    assert (v.quantity, x.quantity, x.outside) == ("velocity", "displacement", "hold")
    assert v.integral(0.5).values.tolist() == [0.5, 2.5, 12.5]   # trapezoid of a line
    ramp = Table([0.0, 1.0], [0.0, 6.0], quantity="acceleration")   # a = 6 t
    assert ramp.integrated()[1].values.tolist() == [0.0, 1.0]   # x = t^3, exactly
    with pytest.raises(ValueError, match="needs an acceleration table"):
        v.integrated()
    with pytest.raises(ValueError, match="only an acceleration or a velocity"):
        x.integral()


def test_detrend_removes_a_polynomial():
    t = np.linspace(0.0, 2.0, 41)
    table = Table(t, 0.3 + 0.2 * t + np.sin(7 * t), quantity="acceleration")
    assert abs(detrend(table, order=0).values.mean()) < 1e-15
    flat = detrend(Table(t, 0.3 - 1.5 * t + 0.25 * t**2, quantity="force"), order=2)
    assert np.abs(flat.values).max() < 1e-13 and flat.quantity == "force"
    with pytest.raises(ValueError, match="`order` must be below the number of points"):
        detrend(table, order=41)
    with pytest.raises(ValueError, match="`order` must be at least 0"):
        detrend(table, order=-1)


# -- properties over random tables -----------------------------------------------------------
finite = st.floats(-1e12, 1e12, allow_nan=False, allow_infinity=False)


@st.composite
def tables(draw, min_size: int = 2, max_size: int = 40):
    times = draw(st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=min_size,
                          max_size=max_size, unique=True).map(sorted))
    values = draw(st.lists(finite, min_size=len(times), max_size=len(times)))
    return times, values


def _csv(times, values) -> str:
    rows = "".join(f"{t!r}, {y!r}\n" for t, y in zip(times, values, strict=True))
    return "time, value\n" + rows


@given(tables())
def test_reader_round_trips_random_tables(data):
    times, values = data
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "random.csv"
        path.write_text(_csv(times, values))
        table = read_table(path, quantity="force", time_column="time", value_column="value")
    assert table.times.tolist() == times and table.values.tolist() == values
    assert [table(t) for t in times] == values                  # the points exactly
    assert table.breakpoints(-math.inf, math.inf) == times


@given(tables(max_size=30))
def test_at2_round_trips_random_values(data):
    _, values = data
    body = "".join(f" {y!r}" + ("\n" if k % 5 == 4 else "") for k, y in enumerate(values))
    text = f"T\nT\nACCELERATION IN UNITS OF G\nNPTS= {len(values)}, DT= .01 SEC\n{body}\n"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "random.at2"
        path.write_text(text)
        table = read_at2(path, units="m/s^2")
    assert table.values.tolist() == values and len(table) == len(values)


@given(st.text(alphabet=st.sampled_from("0123456789.,-+eEdDnaif \n#tyx"), max_size=80))
def test_reader_never_crashes_on_garbage(text):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "garbage.csv"
        path.write_text(text)
        try:
            read_table(path, quantity="force")
        except TableError as err:
            assert str(err).startswith(f"{path}: line ")
        path.write_text("H\nH\nACCELERATION IN UNITS OF G\n" + text)
        try:
            read_at2(path)
        except TableError as err:
            assert str(err).startswith(f"{path}: line ")


@given(tables(), finite, finite)
def test_breakpoints_are_exactly_the_interior_points(data, a, b):
    times, values = data
    table = Table(times, values, quantity="force")
    t0, t1 = min(a, b), max(a, b)
    assert table.breakpoints(t0, t1) == [t for t in times if t0 < t < t1]


@example(([-1.0, -7.29101987247249e-264], [1.0, 1.0]), 1.0)
@given(tables(), st.floats(0.0, 1.0))
def test_interpolation_lies_between_its_neighbours(data, s):
    times, values = data
    table = Table(times, values, quantity="force")
    k = int(s * (len(times) - 2))
    # inside [t_k, t_k+1]: t_k + s (t_k+1 - t_k) rounds past t_k+1 for some draws
    # (t = -1 + 1.0 = 0.0 beyond a last point of -7.3e-264, where the table is 0)
    t = min(max(times[k] + s * (times[k + 1] - times[k]), times[k]), times[k + 1])
    lo, hi = sorted(values[k:k + 2])
    assert lo - 1e-9 * abs(lo) <= table(t) <= hi + 1e-9 * abs(hi)


@given(tables(), st.lists(st.floats(-2e6, 2e6, allow_nan=False), max_size=30))
def test_any_call_order_gives_the_interpolant(data, queries):
    """The segment hint of the previous call never changes a value."""
    times, values = data
    table = Table(times, values, quantity="force", outside="hold")
    for t in [*queries, *times[::-1], *queries[::-1]]:
        if t <= times[0] or t >= times[-1]:
            expected = values[0] if t <= times[0] else values[-1]
        else:
            i = bisect.bisect_right(times, t)
            t0, y0 = times[i - 1], values[i - 1]
            expected = y0 if t == t0 else y0 + (t - t0) / (times[i] - t0) * (values[i] - y0)
        assert table(t) == expected


@given(tables(), finite, finite)
@settings(max_examples=100)
def test_integration_is_exact_for_the_piecewise_linear_acceleration(data, v0, x0):
    times, values = data
    v0, x0 = v0 / 1e6, x0 / 1e6
    acc = Table(times, values, quantity="acceleration")
    vel, disp = acc.integrated(v0, x0)
    t = [Fraction(u) for u in times]
    a = [Fraction(y) for y in values]
    v, x = [Fraction(v0)], [Fraction(x0)]
    v_scale, x_scale = [abs(v0)], [abs(x0)]
    for k in range(1, len(t)):
        h = t[k] - t[k - 1]
        v.append(v[-1] + h * (a[k - 1] + a[k]) / 2)
        x.append(x[-1] + h * v[-2] + h * h * (2 * a[k - 1] + a[k]) / 6)
        v_scale.append(v_scale[-1] + float(h) * (abs(values[k - 1]) + abs(values[k])) / 2)
        x_scale.append(x_scale[-1] + float(h) * v_scale[-2]
                       + float(h * h) * (2 * abs(values[k - 1]) + abs(values[k])) / 6)
    eps = 4 * len(t) * np.finfo(float).eps
    for k in range(len(t)):
        assert abs(vel.values[k] - float(v[k])) <= eps * v_scale[k] + 1e-300
        assert abs(disp.values[k] - float(x[k])) <= 4 * eps * x_scale[k] + 1e-300


# -- the shipped synthetic record ------------------------------------------------------------
def test_shipped_record_reads_the_same_from_at2_and_csv():
    at2 = read_at2(RECORDS / "synthetic_ground.at2")
    csv = read_table(RECORDS / "synthetic_ground.csv", quantity="acceleration",
                     time_column="t", value_column="acceleration_g", units="g")
    assert len(at2) == len(csv) == 4001 and at2.span == (0.0, 20.0)
    np.testing.assert_allclose(csv.times, at2.times, rtol=0, atol=1e-12)
    np.testing.assert_allclose(csv.values, at2.values, rtol=0, atol=1e-7 * G)
    assert np.abs(at2.values).max() / G == pytest.approx(0.3, rel=1e-6)
    assert at2.values[0] == 0.0 and at2.values[-1] == 0.0
    for name in ("synthetic_ground.at2", "synthetic_ground.csv"):
        assert (RECORDS / name).stat().st_size < 100_000
    # no baseline correction in the file: it drifts; a least-squares line removes it
    vel, disp = at2.integrated()
    assert abs(vel.values[-1]) > 0.02 and abs(disp.values[-1]) > 0.5
    vel, disp = detrend(at2, order=1).integrated()
    assert abs(vel.values[-1]) < 1e-4 and abs(disp.values[-1]) < 1e-3


def test_the_record_recipe_reproduces_the_shipped_files(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["make_synthetic_record.py", "--out", str(tmp_path)])
    runpy.run_path(str(RECORDS / "make_synthetic_record.py"), run_name="__main__")
    assert "peak 0.3 g" in capsys.readouterr().out
    new, shipped = (read_at2(d / "synthetic_ground.at2") for d in (tmp_path, RECORDS))
    np.testing.assert_allclose(new.values, shipped.values, rtol=0, atol=2e-7 * G)


# -- a table as the forcing of a scene ---------------------------------------------------------
def _pushed(force) -> Scene:
    return Scene([Mass("mass", m=1.0)],
                 [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground",
                          "mass")],
                 forces={"mass": force})


def test_a_table_that_samples_a_sine_converges_to_the_sine_forcing():
    sine = SineBurst(10.0, 5 * math.pi)
    ref = simulate(_pushed(sine), method="bdf2", dt=1e-3, t_end=1.5).x["mass"]
    errors = []
    for h in (0.02, 0.01):
        t = np.arange(0.0, 1.5 + h / 2, h)
        table = Table(t, [sine(tk) for tk in t], quantity="force")
        x = simulate(_pushed(table), method="bdf2", dt=1e-3, t_end=1.5).x["mass"]
        errors.append(float(np.abs(x - ref).max()))
    assert errors[0] < 2e-3 and 3.0 < errors[0] / errors[1] < 5.0, errors  # O(h^2)


def test_the_adaptive_method_steps_onto_every_point():
    t = np.linspace(0.0, 0.5, 26)
    table = Table(t, 10.0 * np.sin(5 * math.pi * t), quantity="force")
    sol = simulate(_pushed(table), method="radau5", rtol=1e-6, atol=1e-9, t_end=0.5)
    assert sol.success
    assert set(table.times[1:-1].tolist()) <= set(sol.t.tolist())
    # the interpolant is continuous there (kinks): no time events, the mode goes on
    assert not [e for e in sol.events if e.kind == "time"]
    # a table that jumps at its end (outside="zero") ends with a time event there
    t_cut = Table(t[:17], 10.0 * np.sin(5 * math.pi * t[:17]) + 1.0, quantity="force")
    sol = simulate(_pushed(t_cut), method="radau5", rtol=1e-6, atol=1e-9, t_end=0.5)
    assert [e.t for e in sol.events if e.kind == "time"] == [t_cut.times[-1]]
    assert set(t_cut.times[1:].tolist()) <= set(sol.t.tolist())
