r"""Reading tabulated inputs: CSV tables and PEER NGA ``.AT2`` records, as :class:`Table`.

:func:`read_table` reads a CSV file with a header line (a time column and a value
column, by name or index); :func:`read_at2` reads the PEER NGA accelerogram format (a
4-line header giving ``NPTS`` and ``DT``, then the values in rows). Both convert the
values to SI units (:mod:`lumped.io.units`) and return a :class:`Table`
(:mod:`lumped.io.tabulated`): a forcing ``f(t)`` by linear interpolation, with its points
as time events, that integrates an acceleration record to velocity and displacement.

Files are data, never code: numbers are read by a plain float pattern (a Fortran
exponent ``1.0D-02`` is accepted), and every problem raises :class:`TableError` (a
``ValueError``) naming the file, the line and the problem.

Examples
--------
>>> import pathlib, tempfile
>>> path = pathlib.Path(tempfile.mkdtemp()) / "record.csv"
>>> _ = path.write_text("time,acc\n0.0,0.0\n0.01,0.1\n0.02,-0.2\n")
>>> acc = read_table(path, quantity="acceleration", time_column="time",
...                  value_column="acc", units="g")
>>> acc
Table(acceleration in m/s^2, 3 points on [0, 0.02] s, outside='zero', source='record.csv')
>>> round(acc(0.005), 6)                     # m/s^2: half of 0.1 g
0.490333
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from .._validate import as_finite
from .tabulated import OUTSIDE, Table, detrend
from .units import check_quantity, unit_scale

__all__ = ["Table", "TableError", "read_table", "read_at2", "detrend"]


class TableError(ValueError):
    """A bad table file; the message names the file, the line and the problem."""


# -- reading files ------------------------------------------------------------------------
_FLOAT = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][+-]?\d+)?")
_NOT_FINITE = {"nan", "inf", "infinity"}


def _fail(path: Path, line: int, problem: str) -> TableError:
    return TableError(f"{path}: line {line}: {problem}")


def _number(token: str, path: Path, line: int, what: str) -> float:
    """``token`` as a finite float (a plain number pattern, never evaluated)."""
    text = token.strip()
    if _FLOAT.fullmatch(text):
        x = float(text.replace("d", "e").replace("D", "e"))
        if math.isfinite(x):
            return x
        raise _fail(path, line, f"{what} {text!r} is not finite (it overflows)")
    if text.lower().lstrip("+-") in _NOT_FINITE:
        raise _fail(path, line, f"{what} {text!r} is not finite")
    if not text:
        raise _fail(path, line, f"{what} is empty")
    raise _fail(path, line, f"{what} {text!r} is not a number")


def _lines(path: str | Path) -> tuple[Path, list[str]]:
    path = Path(path)
    try:
        return path, path.read_text(encoding="utf-8-sig").splitlines()
    except FileNotFoundError:
        raise TableError(f"{path}: no such table file") from None
    except IsADirectoryError:
        raise TableError(f"{path}: is a directory, not a table file") from None
    except UnicodeDecodeError as err:
        line = path.read_bytes()[:err.start].count(b"\n") + 1
        raise _fail(path, line, "not a text file (cannot decode it as UTF-8)") from None


def _check_increasing(path: Path, times: list[float], lines: list[int]) -> None:
    for k in range(1, len(times)):
        if not times[k] > times[k - 1]:
            raise _fail(path, lines[k], f"time {times[k]!r} is not after the time "
                        f"{times[k - 1]!r} on line {lines[k - 1]} (times must increase "
                        "strictly)")


def _finish(path: Path, times, values, quantity: str, scale: float, outside: str,
            last_line: int) -> Table:
    values = np.asarray(values, dtype=np.float64) * scale
    if not np.isfinite(values).all():
        raise _fail(path, last_line, f"a value overflows when scaled by {scale!r}")
    return Table(np.asarray(times, dtype=np.float64), values, quantity=quantity,
                 source=path.name, outside=outside)


def _scale(units: object, quantity: str, factor: object) -> float:
    return as_finite("factor", factor) * unit_scale(units, quantity)


def _column(spec: object, header: list[str], which: str, path: Path, line: int) -> int:
    names = ", ".join(repr(h) for h in header)
    if isinstance(spec, bool) or not isinstance(spec, (int, str)):
        raise TypeError(f"`{which}` must be a column name (str) or index (int), got {spec!r}")
    if isinstance(spec, int):
        if not 0 <= spec < len(header):
            raise _fail(path, line, f"missing column: `{which}` = {spec} but the header has "
                        f"{len(header)} columns ({names})")
        return spec
    found = [i for i, h in enumerate(header) if h == spec.strip()]
    if not found:
        raise _fail(path, line, f"missing column: no column {spec!r} in the header "
                    f"(columns: {names})")
    if len(found) > 1:
        raise _fail(path, line, f"column {spec!r} appears {len(found)} times in the header")
    return found[0]


def read_table(
    path: str | Path,
    *,
    quantity: str,
    time_column: int | str = 0,
    value_column: int | str = 1,
    units: str | None = None,
    factor: float = 1.0,
    delimiter: str = ",",
    outside: str = "zero",
) -> Table:
    """Read a table from a CSV file with a header line.

    Blank lines and lines starting with ``#`` are skipped; the first other line is the
    header (column names), every line after it a row. Only the two chosen columns are
    read; other columns may hold anything.

    Parameters
    ----------
    path : str or Path
    quantity : str
        What the values are: ``"force"``, ``"acceleration"``, ``"velocity"`` or
        ``"displacement"`` (required: a record read as the wrong quantity is a silent
        error).
    time_column, value_column : int or str
        A column by index (from 0) or by its name in the header. Times in seconds.
    units : str, optional
        The unit of the values (see :mod:`lumped.io.units`); default: SI already.
    factor : float
        A scale applied to the values as well (OpenSees' ``-factor``).
    delimiter : str
        The field separator.
    outside : str
        ``"zero"`` or ``"hold"``, see :class:`Table`.

    Returns
    -------
    Table
        Values in SI units, ``source`` the file name.

    Raises
    ------
    TableError
        A ``ValueError`` naming the file, the line and the problem: no such file, no
        header, a missing column, a field that is not a number or not finite, times that
        do not increase strictly, no data rows, fewer than 2 rows.
    ValueError, TypeError
        For bad arguments (an unknown unit, a unit of another quantity, ...).
    """
    check_quantity(quantity)
    scale = _scale(units, quantity, factor)
    if outside not in OUTSIDE:
        raise ValueError(f"`outside` must be 'zero' or 'hold', got {outside!r}")
    if not isinstance(delimiter, str) or not delimiter:
        raise ValueError(f"`delimiter` must be a non-empty str, got {delimiter!r}")
    path, text = _lines(path)
    rows = [(n, line) for n, line in enumerate(text, start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise _fail(path, max(len(text), 1), "the table is empty (no header, no data)")
    head_line, head = rows[0]
    header = [h.strip().strip('"').strip() for h in head.split(delimiter)]
    if all(_FLOAT.fullmatch(h) for h in header):
        raise _fail(path, head_line, "expected a header line naming the columns, got "
                    "numbers")
    ti = _column(time_column, header, "time_column", path, head_line)
    vi = _column(value_column, header, "value_column", path, head_line)
    if ti == vi:
        raise ValueError(f"`time_column` and `value_column` are the same column "
                         f"{header[ti]!r}")
    need = max(ti, vi)
    times: list[float] = []
    values: list[float] = []
    lines: list[int] = []
    for n, line in rows[1:]:
        fields = line.split(delimiter)
        if len(fields) <= need:
            missing = header[ti] if len(fields) <= ti else header[vi]
            raise _fail(path, n, f"missing column: the row has {len(fields)} field(s), "
                        f"no {missing!r}")
        times.append(_number(fields[ti], path, n, f"time ({header[ti]!r})"))
        values.append(_number(fields[vi], path, n, f"value ({header[vi]!r})"))
        lines.append(n)
    if not times:
        raise _fail(path, head_line, "the table is empty (no data rows below the header)")
    if len(times) < 2:
        raise _fail(path, lines[0], "only one data row; a table needs at least 2 points")
    _check_increasing(path, times, lines)
    return _finish(path, times, values, quantity, scale, outside, lines[-1])


# PEER NGA .AT2: line 3 names the quantity and units, line 4 holds NPTS and DT
_AT2_NEW = re.compile(r"NPTS\s*=\s*([^,\s]+)\s*,?\s*DT\s*=\s*([^,\s]+)", re.IGNORECASE)
_AT2_OLD = re.compile(r"\s*([^,\s]+)\s*,?\s+([^,\s]+)\s+NPTS\s*,\s*DT\b", re.IGNORECASE)
_AT2_UNITS = {"G": "g", "CM/S/S": "cm/s^2", "CM/SEC/SEC": "cm/s^2", "CM/S^2": "cm/s^2",
              "CM/S2": "cm/s^2", "CM/SEC^2": "cm/s^2", "CM/SEC2": "cm/s^2", "GAL": "gal",
              "M/S/S": "m/s^2", "M/S^2": "m/s^2", "M/S2": "m/s^2", "CM/S": "cm/s",
              "CM/SEC": "cm/s", "M/S": "m/s", "CM": "cm", "M": "m", "MM": "mm"}
_TOKEN = re.compile(r"[^\s,]+")


def _at2_values(path: Path, text: list[str]) -> tuple[list[float], int]:
    """The numbers from line 5 on (whitespace or commas between them; Fortran output
    whose fields touch, ``-.1E-02-.2E-02``, is split), and the last line with one."""
    values: list[float] = []
    last = 4
    for n, line in enumerate(text[4:], start=5):
        for token in _TOKEN.findall(line):
            if _FLOAT.fullmatch(token):
                values.append(_number(token, path, n, "value"))
                continue
            parts = _FLOAT.findall(token)
            if len(parts) > 1 and "".join(parts) == token:
                values.extend(_number(p, path, n, "value") for p in parts)
            else:
                values.append(_number(token, path, n, "value"))  # raises, naming it
        if line.strip():
            last = n
    return values, last


def read_at2(
    path: str | Path,
    *,
    quantity: str | None = None,
    units: str | None = None,
    factor: float = 1.0,
    outside: str = "zero",
) -> Table:
    """Read a PEER NGA strong-motion record (``.AT2``; also ``.VT2``, ``.DT2``).

    The format: four header lines, then the values in rows of several columns::

        PEER NGA STRONG MOTION DATABASE RECORD
        IMPERIAL VALLEY 10/15/79 2316, EL CENTRO ARRAY #6, 140
        ACCELERATION TIME SERIES IN UNITS OF G
        NPTS=  3930, DT=   .0100 SEC
          .2277619E-02  .2582129E-02  .2739830E-02  .2838950E-02  .2888820E-02
          ...

    Line 4 may also have the older form ``3930 .0100 NPTS, DT``. The samples are at
    ``t_k = k DT``, ``k = 0 .. NPTS - 1``.

    Parameters
    ----------
    path : str or Path
    quantity : str, optional
        Default: read from line 3 (``ACCELERATION``, ``VELOCITY`` or ``DISPLACEMENT``).
    units : str, optional
        Default: read from line 3 (``UNITS OF G``, ``CM/S/S``, ``CM/S``, ``CM``, ...).
        Arguments given win over the header.
    factor : float
        A scale applied to the values as well.
    outside : str
        ``"zero"`` (default: no shaking outside the record) or ``"hold"``.

    Returns
    -------
    Table
        Values in SI units (m/s^2 for an acceleration), ``source`` the file name.

    Raises
    ------
    TableError
        A ``ValueError`` naming the file, the line and the problem: a short header, an
        unreadable NPTS or DT (or DT not positive), an NPTS that does not match the
        number of values, a value that is not a number or not finite, fewer than 2
        points, quantity or units not given and not found on line 3.
    """
    if quantity is not None:
        check_quantity(quantity)
    if outside not in OUTSIDE:
        raise ValueError(f"`outside` must be 'zero' or 'hold', got {outside!r}")
    path, text = _lines(path)
    if len(text) < 4:
        raise _fail(path, max(len(text), 1), "the file ends inside the 4-line AT2 header")
    title = text[2].upper()
    if quantity is None:
        found = [q for q in ("acceleration", "velocity", "displacement") if q.upper() in title]
        if len(found) != 1:
            raise _fail(path, 3, "cannot tell the quantity from the header (expected one "
                        "of ACCELERATION, VELOCITY, DISPLACEMENT); pass `quantity`")
        quantity = found[0]
    if units is None:
        match = re.search(r"UNITS\s+OF\s+([A-Z/^0-9]+)", title)
        units = _AT2_UNITS.get(match.group(1)) if match else None
        if units is None:
            raise _fail(path, 3, "cannot tell the units from the header (expected 'UNITS "
                        "OF G', 'UNITS OF CM/S/S', ...); pass `units`")
    try:
        scale = _scale(units, quantity, factor)
    except ValueError as err:
        raise _fail(path, 3, str(err)) from None
    match = _AT2_NEW.search(text[3]) or _AT2_OLD.match(text[3])
    if match is None:
        raise _fail(path, 4, f"cannot read NPTS and DT from {text[3].strip()!r} (expected "
                    "'NPTS= 1234, DT= .0050 SEC' or '1234 .0050 NPTS, DT')")
    npts_text, dt_text = match.group(1), match.group(2)
    if not npts_text.isdigit():
        raise _fail(path, 4, f"NPTS {npts_text!r} is not a whole number")
    npts = int(npts_text)
    dt = _number(dt_text, path, 4, "DT")
    if not dt > 0.0:
        raise _fail(path, 4, f"bad DT {dt_text!r}: the time step must be positive")
    values, last = _at2_values(path, text)
    if len(values) != npts:
        raise _fail(path, 4, f"the header says NPTS = {npts} but the file holds "
                    f"{len(values)} values (lines 5 to {last})")
    if npts == 0:
        raise _fail(path, 4, "the table is empty (NPTS = 0)")
    if npts < 2:
        raise _fail(path, 4, "only one value; a table needs at least 2 points")
    return _finish(path, np.arange(npts) * dt, values, quantity, scale, outside, last)
