r"""The :class:`Table`: values of one quantity at given times, callable as a forcing.

A table holds strictly increasing times ``t_0 < t_1 < ... < t_{n-1}`` and finite values
``y_k`` of one quantity (force, acceleration, velocity or displacement, in SI units: see
:mod:`lumped.io.units`). Files are read by :mod:`lumped.io.tables`.

**Interpolation and time events.** ``table(t)`` is the linear interpolant of the points,

.. math::  y(t) = y_k + \frac{t - t_k}{t_{k+1} - t_k}\,(y_{k+1} - y_k),
           \qquad t_k \le t \le t_{k+1},

which equals ``y_k`` exactly at ``t = t_k``. Outside ``[t_0, t_{n-1}]`` it is ``0``
(``outside="zero"``, the default: a record is silent before and after it was
recorded) or the nearest end value (``outside="hold"``). The interpolant has a kink at
every point (and, with ``"zero"``, may jump at the two ends), so
``table.breakpoints(t0, t1)`` lists every point strictly inside ``(t0, t1)``: the
adaptive method steps exactly onto them (time events), and a fixed-step method whose
grid misses them loses its order there.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .._validate import as_finite, as_int_at_least
from .units import SI_UNITS, check_quantity

__all__ = ["Table", "detrend", "OUTSIDE"]

#: The choices of ``outside``.
OUTSIDE = ("zero", "hold")
#: What integrating a quantity once gives.
_INTEGRAL = {"acceleration": "velocity", "velocity": "displacement"}


@dataclass(frozen=True, eq=False)
class Table:
    r"""Values of one quantity at strictly increasing times, callable as a forcing.

    Parameters
    ----------
    times : array_like
        ``t_k`` (s), strictly increasing, finite, at least two.
    values : array_like
        ``y_k`` in the SI unit of ``quantity`` (:attr:`unit`), finite, as many as times.
    quantity : str
        ``"force"``, ``"acceleration"``, ``"velocity"`` or ``"displacement"``.
    source : str
        Where the values came from (a file name), for messages.
    outside : str
        The value outside ``[t_0, t_{n-1}]``: ``"zero"`` (default) or ``"hold"`` (the
        first value before, the last value after). Change it with
        ``dataclasses.replace(table, outside="hold")``.

    Notes
    -----
    A call ``table(t)`` runs on Python floats (``bisect`` on a list of the times, no
    numpy): it is cheap enough for a step loop. ``times`` and ``values`` are read-only
    float64 arrays.

    Examples
    --------
    >>> f = Table([0.0, 1.0, 3.0], [0.0, 2.0, -2.0], quantity="force")
    >>> f(0.5), f(1.0), f(2.0), f(4.0)
    (1.0, 2.0, 0.0, 0.0)
    >>> f.breakpoints(0.0, 3.5)        # the points strictly inside: time events
    [1.0, 3.0]
    >>> v, x = Table([0.0, 1.0, 2.0], [1.0, 1.0, 1.0], quantity="acceleration").integrated()
    >>> v.values.tolist(), x.values.tolist()
    ([0.0, 1.0, 2.0], [0.0, 0.5, 2.0])
    """

    times: np.ndarray
    values: np.ndarray
    quantity: str
    source: str = "<arrays>"
    outside: str = "zero"
    _t: list[float] = field(init=False, repr=False)
    _y: list[float] = field(init=False, repr=False)
    _segment: list[int] = field(init=False, repr=False)  # the last segment, a hint

    def __post_init__(self) -> None:
        check_quantity(self.quantity)
        if self.outside not in OUTSIDE:
            raise ValueError(f"`outside` must be 'zero' or 'hold', got {self.outside!r}")
        if not isinstance(self.source, str):
            raise TypeError(f"`source` must be a str, got {self.source!r}")
        arrays = []
        for name in ("times", "values"):
            try:
                arr = np.array(getattr(self, name), dtype=np.float64)
            except (TypeError, ValueError):
                raise TypeError(f"`{name}` must be an array of real numbers, got "
                                f"{getattr(self, name)!r}") from None
            if arr.ndim != 1:
                raise ValueError(f"`{name}` must be one-dimensional, got shape {arr.shape}")
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                raise ValueError(f"`{name}[{bad[0]}]` must be finite, got {arr[bad[0]]!r}")
            arr.setflags(write=False)
            arrays.append(arr)
        times, values = arrays
        if len(times) != len(values):
            raise ValueError(f"`times` and `values` must have the same length, got "
                             f"{len(times)} and {len(values)}")
        if len(times) < 2:
            raise ValueError(f"a table needs at least 2 points, got {len(times)}")
        down = np.flatnonzero(np.diff(times) <= 0.0)
        if down.size:
            k = int(down[0]) + 1
            raise ValueError(f"`times` must increase strictly: times[{k}] = {times[k]!r} "
                             f"is not after times[{k - 1}] = {times[k - 1]!r}")
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "_t", times.tolist())
        object.__setattr__(self, "_y", values.tolist())
        object.__setattr__(self, "_segment", [0])

    # -- as a forcing ----------------------------------------------------------------------
    def __call__(self, t: float) -> float:
        """The linear interpolant at ``t`` (see the module notes); a Python float.

        The segment of the previous call is tried first (a step loop calls at times
        that mostly stay in one segment), then ``bisect``."""
        tt, yy = self._t, self._y
        k = self._segment[0]
        if not tt[k] <= t < tt[k + 1]:
            if not tt[0] <= t < tt[-1]:
                if t == tt[-1]:
                    return yy[-1]
                if t != t:
                    raise ValueError(f"{self.source}: a table was called at t = nan")
                if self.outside == "zero":
                    return 0.0
                return yy[0] if t < tt[0] else yy[-1]
            k = bisect_right(tt, t) - 1
            self._segment[0] = k
        t0, y0 = tt[k], yy[k]
        if t == t0:
            return y0
        return y0 + (t - t0) / (tt[k + 1] - t0) * (yy[k + 1] - y0)

    def interpolant(self) -> tuple:
        """``("table", t, y, y, before, after, 1.0)``: what compiled code needs to compute
        :meth:`__call__` with its arithmetic (:func:`lumped.scene.forcing_jit.linear_row`):
        the times, the values, and the values before and after the table."""
        before = after = 0.0
        if self.outside != "zero":
            before, after = self._y[0], self._y[-1]
        return "table", self._t, self._y, self._y, before, after, 1.0

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        """The table's times strictly inside ``(t0, t1)``, in order: where the interpolant
        kinks (time events for an adaptive method)."""
        return self._t[bisect_right(self._t, t0):bisect_left(self._t, t1)]

    def kinks(self, t0: float, t1: float) -> list[float]:
        """The :meth:`breakpoints` at which the interpolant is continuous (a kink, not a
        jump): every inner point, and an end point where the value outside equals the
        end value (``outside="hold"``, or a record that starts or ends at 0). An
        adaptive method steps onto a kink without choosing the mode again."""
        _, tt, yy, _, before, after, _ = self.interpolant()
        inner = self.breakpoints(t0, t1)
        return [tk for tk in inner
                if (tk != tt[0] or before == yy[0]) and (tk != tt[-1] or after == yy[-1])]

    # -- description -----------------------------------------------------------------------
    @property
    def unit(self) -> str:
        """The SI unit of the values (``"m/s^2"`` for an acceleration, ...)."""
        return SI_UNITS[self.quantity]

    @property
    def span(self) -> tuple[float, float]:
        """``(t_0, t_{n-1})``, the recorded interval (s)."""
        return self._t[0], self._t[-1]

    def __len__(self) -> int:
        return len(self._t)

    def __repr__(self) -> str:
        t0, t1 = self.span
        return (f"Table({self.quantity} in {self.unit}, {len(self)} points on "
                f"[{t0:g}, {t1:g}] s, outside={self.outside!r}, source={self.source!r})")

    # -- integration -----------------------------------------------------------------------
    def integral(self, initial: float = 0.0) -> Table:
        r"""The running integral of the interpolant, sampled at the table's times.

        .. math::  Y_0 = Y_{\text{initial}}, \qquad
                   Y_k = Y_{k-1} + \tfrac12 (t_k - t_{k-1}) (y_{k-1} + y_k),

        the trapezoidal rule, which is the exact integral of the linear interpolant: the
        samples ``Y_k`` are exact up to round-off (``Y`` itself is piecewise quadratic;
        the returned table interpolates it linearly between the samples).

        Parameters
        ----------
        initial : float
            ``Y`` at ``t_0`` (the initial velocity, or displacement).

        Returns
        -------
        Table
            Of the next quantity (acceleration -> velocity, velocity -> displacement),
            ``outside="hold"``.

        Raises
        ------
        ValueError
            For a force or a displacement table.
        """
        if self.quantity not in _INTEGRAL:
            raise ValueError(f"only an acceleration or a velocity table can be integrated, "
                             f"this one holds {self.quantity}")
        y0 = as_finite("initial", initial)
        h = np.diff(self.times)
        out = np.empty(len(self))
        out[0] = y0
        out[1:] = y0 + np.cumsum(0.5 * h * (self.values[:-1] + self.values[1:]))
        return self._derived(out, _INTEGRAL[self.quantity])

    def integrated(self, v0: float = 0.0, x0: float = 0.0) -> tuple[Table, Table]:
        r"""Velocity and displacement of an acceleration record, exact for its interpolant.

        With ``h_k = t_k - t_{k-1}`` and the acceleration ``a`` piecewise linear,

        .. math::

            v_k &= v_{k-1} + \tfrac12 h_k\,(a_{k-1} + a_k), \\
            x_k &= x_{k-1} + h_k\,v_{k-1} + \tfrac16 h_k^2\,(2 a_{k-1} + a_k),

        the exact velocity (piecewise quadratic) and displacement (piecewise cubic) of
        the motion whose acceleration is ``table(t)``, at the table's times: exact up to
        round-off, so the three tables describe one motion at the points. Between the
        points each returned table interpolates linearly (as every table does), which is
        *not* the exact quadratic or cubic: prescribe the acceleration when the motion
        between the points matters. (``x_k`` is not the trapezoidal rule on ``v_k``,
        which would be off by ``h_k^3 (a_k - a_{k-1}) / 12`` per step.)

        Baseline drift is **not** corrected: a small offset or noise in a measured
        acceleration grows linearly in the velocity and quadratically in the
        displacement. Correcting it is the user's choice, before integrating; e.g.
        :func:`detrend` with ``order=1`` subtracts the least-squares line, after which
        the final velocity and displacement nearly vanish (see :func:`detrend` and
        ``docs/records_and_loops.md``).

        Parameters
        ----------
        v0, x0 : float
            Velocity (m/s) and displacement (m) at ``t_0``.

        Returns
        -------
        velocity, displacement : Table
            With ``outside="hold"``: ``v0, x0`` before ``t_0`` (consistent with a zero
            acceleration there) and the last values after ``t_{n-1}`` (the exact
            continuation under zero acceleration keeps the final velocity, so the
            displacement would go on growing unless that velocity is zero).

        Raises
        ------
        ValueError
            If the table is not an acceleration.
        """
        if self.quantity != "acceleration":
            raise ValueError(f"integrated() needs an acceleration table, this one holds "
                             f"{self.quantity} (use integral() for a velocity)")
        x_start = as_finite("x0", x0)
        vel = self.integral(v0)
        a, v, h = self.values, vel.values, np.diff(self.times)
        x = np.empty(len(self))
        x[0] = x_start
        x[1:] = x_start + np.cumsum(h * v[:-1] + h * h * (2.0 * a[:-1] + a[1:]) / 6.0)
        return vel, self._derived(x, "displacement")

    def _derived(self, values: np.ndarray, quantity: str) -> Table:
        return Table(self.times, values, quantity=quantity, source=self.source,
                     outside="hold")

    # -- output ----------------------------------------------------------------------------
    def to_csv(self, path: str | Path) -> Path:
        """Write ``t,<quantity>`` with a header line, SI units, ``%.17g`` (round trip:
        ``read_table(path, quantity=q)`` gives the same table)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(path, np.column_stack([self.times, self.values]), fmt="%.17g",
                   delimiter=",", header=f"t,{self.quantity}", comments="")
        return path


def detrend(table: Table, order: int = 1) -> Table:
    r"""Subtract the least-squares polynomial of degree ``order`` in ``t`` from the values.

    .. math::  \tilde y_k = y_k - P(t_k), \qquad
               P = \arg\min_{\deg P \le \text{order}} \sum_k (y_k - P(t_k))^2 .

    The simplest baseline correction of an acceleration record: ``order=0`` removes the
    mean (the constant offset that makes the velocity drift linearly). ``order=1``
    makes ``sum_k a~_k = 0`` and ``sum_k t_k a~_k = 0``; since the final velocity and
    displacement of a record on ``[0, T]`` are

    .. math::  v(T) - v(0) = \int_0^T a\,dt, \qquad
               x(T) - x(0) - T v(0) = \int_0^T (T - t)\,a\,dt,

    both nearly vanish after it (the sums over equally spaced samples equal the
    trapezoidal integrals up to the end terms of one step). It changes the record, and
    whether it is the right correction is the user's judgement.

    Parameters
    ----------
    table : Table
    order : int
        Polynomial degree, ``0 <= order < len(table)``.

    Returns
    -------
    Table
        Same times, quantity, source and ``outside``.

    Examples
    --------
    >>> t = Table([0.0, 1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0], quantity="acceleration")
    >>> [round(y, 12) + 0.0 for y in detrend(t, order=1).values.tolist()]
    [0.0, 0.0, 0.0, 0.0]
    """
    if not isinstance(table, Table):
        raise TypeError(f"`table` must be a Table, got {table!r}")
    as_int_at_least("order", order, 0)
    if order >= len(table):
        raise ValueError(f"`order` must be below the number of points ({len(table)}), "
                         f"got {order!r}")
    fit = np.polynomial.Polynomial.fit(table.times, table.values, order)
    return replace(table, values=table.values - fit(table.times))
