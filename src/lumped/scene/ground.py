r"""Prescribed ground motion (uniform support excitation), written in the relative frame.

The ground of a scene may move: its displacement ``x_g(t)``, velocity ``v_g(t)`` and
acceleration ``a_g(t)`` are prescribed (OpenSees' ``UniformExcitation``). The scene's
states are then **relative to the ground**, ``x_i = x_i^{abs} - x_g`` and
``v_i = v_i^{abs} - v_g``, and each mass's momentum balance gains the inertial
(d'Alembert) force of the moving frame:

.. math::

    m_i \dot v_i = f_i(t) - m_i\,a_g(t)
                   + \sum_{e: a_e = i} F_e - \sum_{e: b_e = i} F_e .

Junctions, being massless, get no inertial force. An element's law sees the same
elongation ``q = x_b - x_a`` (and rate) in either frame, the ground end counting ``0``:
the relative elongation of an element to ground is the absolute one, ``x_i - x_g``.
Since the inertial term is a forcing, every method runs these scenes with no solver
change. The absolute motion is post-processed (``x_abs = x + x_g``, ...,
:mod:`lumped.post.frames`). An *absolute* frame, with the ground end of an element
moving, would need solver support and is not offered.

Sign convention: ``x_g``, ``v_g``, ``a_g`` are positive towards ``+x``, as every
displacement; a positive ground acceleration pushes each mass towards ``-x`` relative
to the ground.

**The three quantities of one motion.** The motion is given as exactly one of the
acceleration, the velocity or the displacement; the other two follow exactly:

* an expression of ``t`` (a string parsed by the safe parser
  :func:`lumped.laws.parser.parse_expression`, a sympy expression or a number) or a
  :class:`~lumped.scene.SineBurst` (``A sin(omega t)`` for ``t <= t_off``, zero after):
  differentiated and integrated by sympy in closed form (``v_g(0) = v0``,
  ``x_g(0) = x0`` where they are not given by the input). An expression sympy cannot
  integrate in closed form is refused; ``t_off`` is refused on a velocity or
  displacement sine (switching it off would make the velocity jump, an impulse);
* a :class:`~lumped.io.Table`, whose linear interpolant is the input:

  - **acceleration**: ``a_g`` is the table (piecewise linear), ``v_g`` piecewise
    quadratic and ``x_g`` piecewise cubic, exact between the points
    (:meth:`~lumped.io.Table.integrated` at the points); outside the record ``a_g`` is
    the table's ``outside`` value and ``v_g``, ``x_g`` continue consistently;
  - **velocity**: ``v_g`` is the table, ``a_g`` its slope (piecewise constant, jumping
    at the points) and ``x_g`` its exact integral (piecewise quadratic);
  - **displacement**: the linear interpolant's second derivative is a train of impulses,
    so ``x_g`` is the *natural cubic spline* through the points
    (``scipy.interpolate.CubicSpline``, ``a_g = 0`` at both ends), ``v_g`` its
    derivative and ``a_g`` its second derivative, piecewise linear;

  for velocity and displacement tables ``a_g = 0`` outside the record (the ground keeps
  its end velocity) and the table's ``outside`` is not used. The table's points are the
  motion's breakpoints (time events of ``radau5``). A table holding a force is refused.
"""

from __future__ import annotations

import math
import numbers
import threading
from bisect import bisect_right
from collections.abc import Callable

import numpy as np

from .._validate import as_finite
from .forcing import SineBurst

__all__ = ["GroundMotion", "QUANTITIES"]

#: sympy's rule-based integration keeps state of its own: one thread at a time (Dask
#: workers in threads build scenes side by side).
_SYMPY_LOCK = threading.Lock()

#: The quantities a ground motion may be given as.
QUANTITIES = ("acceleration", "velocity", "displacement")


class GroundMotion:
    r"""A prescribed motion of the ground (uniform support excitation).

    Give exactly one of ``acceleration``, ``velocity``, ``displacement``: an expression
    of ``t`` (str, sympy expression or number), a :class:`~lumped.scene.SineBurst`, or a
    :class:`~lumped.io.Table` of that quantity (see :mod:`lumped.scene.ground`).

    Parameters
    ----------
    acceleration, velocity, displacement : str, number, sympy expression, SineBurst or Table
        The motion (m/s^2, m/s or m), positive towards ``+x``.
    v0 : float
        ``v_g(0)`` when the acceleration is given (default 0).
    x0 : float
        ``x_g(0)`` when the acceleration or the velocity is given (default 0).

    Examples
    --------
    >>> g = GroundMotion(displacement=SineBurst(amplitude=0.01, omega=2.0))
    >>> g.omega, round(g.acceleration_at(math.pi / 4), 6)       # -D w^2 sin(w t)
    (2.0, -0.04)
    >>> x, v, a = g.motion(np.array([0.0, math.pi / 4]))
    >>> [round(float(u), 6) for u in (*x, *v)]
    [0.0, 0.01, 0.02, 0.0]
    """

    def __init__(self, *, acceleration: object = None, velocity: object = None,
                 displacement: object = None, v0: float = 0.0, x0: float = 0.0) -> None:
        given = {k: val for k, val in (("acceleration", acceleration), ("velocity", velocity),
                                        ("displacement", displacement)) if val is not None}
        if len(given) != 1:
            raise ValueError("give exactly one of `acceleration`, `velocity`, `displacement`, "
                             f"got {sorted(given) or 'none'}")
        (quantity, spec), = given.items()
        self.quantity: str = quantity
        self.spec: object = spec
        self.v0 = as_finite("v0", v0)
        self.x0 = as_finite("x0", x0)
        self.omega: float | None = None
        table_quantity = getattr(spec, "quantity", None)
        if table_quantity is not None and hasattr(spec, "breakpoints"):
            if table_quantity != quantity:
                raise ValueError(
                    f"`{quantity}` is a table of {table_quantity}"
                    + (" (a force is not a ground motion: give it as `forces`)"
                       if table_quantity == "force" else
                       f" (pass it as `{table_quantity}=`)") + f", got {spec!r}")
            self._pp = _table_motion(spec, quantity, self.v0, self.x0)
            self._accel: Callable[[float], float] = self._pp
            self._exprs = None
            return
        self._pp = None
        with _SYMPY_LOCK:
            self._exprs = _symbolic_motion(spec, quantity, self.v0, self.x0)
        if isinstance(spec, SineBurst):
            self.omega = float(spec.omega)
        self._accel = _acceleration_forcing(spec, quantity, self._exprs[2])

    # -- the acceleration, as the scene's forcing needs it ------------------------------
    def acceleration_at(self, t: float) -> float:
        """``a_g(t)`` (m/s^2), a Python float."""
        return float(self._accel(t))

    @property
    def acceleration(self) -> Callable[[float], float]:
        """``a_g`` as a forcing callable (a :class:`SineBurst`, a constant, a compiled
        expression or a piecewise polynomial, with ``breakpoints`` where it has any)."""
        return self._accel

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        """Times in ``(t0, t1)`` where ``a_g`` jumps or kinks (time events)."""
        get = getattr(self._accel, "breakpoints", None)
        return list(get(t0, t1)) if get is not None else []

    def kinks(self, t0: float, t1: float) -> list[float]:
        """The :meth:`breakpoints` at which ``a_g`` is continuous (kinks, not jumps)."""
        get = getattr(self._accel, "kinks", None)
        return list(get(t0, t1)) if get is not None else []

    # -- the whole motion, for post-processing ------------------------------------------
    def motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(x_g, v_g, a_g)`` at the times ``t`` (arrays of ``t``'s shape)."""
        t = np.asarray(t, dtype=float)
        if self._pp is not None:
            return tuple(self._pp.evaluate(t, d) for d in (0, 1, 2))  # type: ignore[return-value]
        return tuple(np.broadcast_to(np.asarray(fn(t), dtype=float), t.shape).copy()
                     for fn in self._numeric())  # type: ignore[return-value]

    def at(self, t: float) -> tuple[float, float, float]:
        """``(x_g, v_g, a_g)`` at the one time ``t``, as Python floats (what a step loop
        reads; :meth:`motion` for arrays)."""
        if self._pp is not None:
            tt = np.array([float(t)])
            return tuple(float(self._pp.evaluate(tt, d)[0]) for d in (0, 1, 2))  # type: ignore[return-value]
        if not hasattr(self, "_scalar"):
            import sympy

            s = sympy.Symbol("t")
            self._scalar = [sympy.lambdify(s, e, modules="math") for e in self._exprs]
        return tuple(float(fn(float(t))) for fn in self._scalar)  # type: ignore[return-value]

    def _numeric(self):
        if not hasattr(self, "_lambdas"):
            import sympy

            t = sympy.Symbol("t")
            self._lambdas = [sympy.lambdify(t, e, modules="numpy") for e in self._exprs]
        return self._lambdas

    def __repr__(self) -> str:
        return f"GroundMotion({self.quantity}={self.spec!r}, v0={self.v0!r}, x0={self.x0!r})"


# ---------------------------------------------------------------- symbolic inputs


def _symbolic_motion(spec: object, quantity: str, v0: float, x0: float):
    """``(x_g, v_g, a_g)`` as sympy expressions in ``t``."""
    import sympy

    t = sympy.Symbol("t")
    where = f"`{quantity}`"
    if isinstance(spec, SineBurst):
        if quantity != "acceleration" and spec.t_off != math.inf:
            raise ValueError(f"{where}: a {quantity} sine cannot be switched off (t_off = "
                             f"{spec.t_off!r}): the ground velocity would jump")
        wave = spec.amplitude * sympy.sin(spec.omega * t)
        expr = wave if spec.t_off == math.inf else \
            sympy.Piecewise((wave, t <= spec.t_off), (0, True))
    elif isinstance(spec, str):
        from ..laws.parser import parse_expression

        try:
            expr = parse_expression(spec, ["t"])
        except ValueError as err:
            raise ValueError(f"{where}: {err}") from None
    elif isinstance(spec, numbers.Real) and not isinstance(spec, bool):
        expr = sympy.Float(as_finite(quantity, spec))
    elif isinstance(spec, sympy.Basic):
        expr = spec
    else:
        raise TypeError(f"{where} must be an expression of t (str, number, sympy), a "
                        f"SineBurst or a Table, got {spec!r}")
    free = {s.name for s in expr.free_symbols}
    if not free <= {"t"}:
        raise ValueError(f"{where}: expression {expr} may only depend on `t`, found "
                         f"{sorted(free - {'t'})}")
    expr = expr.subs({s: t for s in expr.free_symbols})

    def integral(e, start: float):
        # rule-based antiderivatives (fast, fail fast), sympy.integrate for Piecewise
        # only once each piece has one: never an open-ended Risch search
        from sympy.integrals.manualintegrate import manualintegrate

        s = sympy.Symbol("s", real=True)
        es = e.subs(t, s)
        pieces = [p.expr for p in es.atoms(sympy.Piecewise) for p in p.args] or [es]
        refused = sympy.Integral(e, t)
        for piece in pieces:
            if manualintegrate(piece, s).has(sympy.Integral):
                raise ValueError(f"{where}: no closed-form integral of {refused.args[0]}; "
                                 "give the motion as a velocity or displacement, or as a "
                                 "table")
        if es.has(sympy.Piecewise):
            out = sympy.integrate(es, (s, 0, t))
        else:
            prim = manualintegrate(es, s)
            out = prim.subs(s, t) - prim.subs(s, 0)
        if out.has(sympy.Integral):
            raise ValueError(f"{where}: no closed-form integral of {e}; give the motion "
                             "as a velocity or displacement, or as a table")
        return sympy.piecewise_fold((out + start).rewrite(sympy.Piecewise))

    if quantity == "acceleration":
        a = expr
        v = integral(a, v0)
        x = integral(v, x0)
    elif quantity == "velocity":
        v, x = expr, integral(expr, x0)
        a = sympy.diff(v, t)
    else:
        x = expr
        v = sympy.diff(x, t)
        a = sympy.diff(v, t)
    return x, v, a


def _acceleration_forcing(spec: object, quantity: str, a_expr) -> Callable[[float], float]:
    """``a_g`` as a forcing: a SineBurst where it is one (exact on every compiled path),
    a constant, else the compiled expression of :func:`lumped.scene.as_forcing`."""
    from .forcing_spec import as_forcing

    if isinstance(spec, SineBurst):
        if quantity == "acceleration":
            return spec
        if quantity == "displacement":  # x = D sin(w t): a = -D w^2 sin(w t)
            return SineBurst(amplitude=-spec.amplitude * spec.omega ** 2, omega=spec.omega)
    if a_expr.is_number:
        return as_forcing(float(a_expr), where=f"`{quantity}`")
    return as_forcing(a_expr, where=f"`{quantity}`")


# ---------------------------------------------------------------- tables


class _PiecewiseMotion:
    r"""A motion cubic between knots: ``x(t) = c_0 + c_1 s + c_2 s^2 + c_3 s^3``,
    ``s = t - t_k``, with quadratic continuations ``x_e + v_e s + a_e s^2 / 2`` beyond
    both ends. Called with a float it is ``a(t)`` on Python floats (a forcing)."""

    def __init__(self, knots: np.ndarray, coef: np.ndarray, a_before: float,
                 a_after: float) -> None:
        self.knots = np.asarray(knots, dtype=float)
        self.coef = np.asarray(coef, dtype=float)  # (n - 1, 4), ascending powers
        h = np.diff(self.knots)[-1]
        c = self.coef[-1]
        self.end = (c[0] + h * (c[1] + h * (c[2] + h * c[3])),
                    c[1] + h * (2 * c[2] + 3 * h * c[3]), 2 * c[2] + 6 * h * c[3])
        self.start = (self.coef[0, 0], self.coef[0, 1], 2 * self.coef[0, 2])
        self.a_before, self.a_after = float(a_before), float(a_after)
        self._t = self.knots.tolist()
        self._a = [(2.0 * float(r[2]), 6.0 * float(r[3])) for r in self.coef]
        # per knot, whether a(t) is continuous there: its values on both sides agree to
        # 1e-9 of its largest value (see kinks)
        tt, segs = self._t, self._a
        left = [self.a_before] + [a + s * (tt[k + 1] - tt[k]) for k, (a, s) in enumerate(segs)]
        right = [a for a, _ in segs] + [self.a_after]
        scale = 1e-9 * max([abs(a) for a in left + right] + [1e-300])
        self._continuous = [abs(lv - rv) <= scale for lv, rv in zip(left, right, strict=True)]

    def __call__(self, t: float) -> float:
        tt = self._t
        if t < tt[0]:
            return self.a_before
        if t > tt[-1]:
            return self.a_after
        k = min(bisect_right(tt, t) - 1, len(tt) - 2)
        a0, slope = self._a[k]
        return a0 + slope * (t - tt[k])

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        return [tk for tk in self._t if t0 < tk < t1]

    def kinks(self, t0: float, t1: float) -> list[float]:
        """The knots in ``(t0, t1)`` at which ``a(t)`` is continuous: its values on both
        sides agree to ``1e-9`` of its largest value (an acceleration record, a
        displacement spline; a velocity record's slope jumps at every knot)."""
        continuous = self._continuous
        return [tk for k, tk in enumerate(self._t) if t0 < tk < t1 and continuous[k]]

    def interpolant(self) -> tuple:
        """``("motion", t, a, s, a_before, a_after, 1.0)``: the knots, each segment's
        start value and slope of ``a(t)``, and ``a`` beyond both ends, for compiled code
        (:func:`lumped.scene.forcing_jit.linear_row`)."""
        return ("motion", self._t, [a for a, _ in self._a], [s for _, s in self._a],
                self.a_before, self.a_after, 1.0)

    def evaluate(self, t: np.ndarray, derivative: int) -> np.ndarray:
        """``x``, ``v`` or ``a`` (``derivative`` 0, 1, 2) at the times ``t``."""
        k = np.clip(np.searchsorted(self.knots, t, side="right") - 1, 0, len(self.coef) - 1)
        s = t - self.knots[k]
        c = self.coef[k]
        if derivative == 0:
            out = c[:, 0] + s * (c[:, 1] + s * (c[:, 2] + s * c[:, 3]))
        elif derivative == 1:
            out = c[:, 1] + s * (2 * c[:, 2] + 3 * s * c[:, 3])
        else:
            out = 2 * c[:, 2] + 6 * s * c[:, 3]
        for mask, (xe, ve, _), ae, te in (
                (t < self.knots[0], self.start, self.a_before, self.knots[0]),
                (t > self.knots[-1], self.end, self.a_after, self.knots[-1])):
            if mask.any():
                s = t[mask] - te
                out[mask] = (xe + ve * s + 0.5 * ae * s * s, ve + ae * s,
                             np.full(s.shape, ae))[derivative]
        return out

    def __repr__(self) -> str:
        return f"piecewise motion ({len(self._t)} knots)"


def _table_motion(table, quantity: str, v0: float, x0: float) -> _PiecewiseMotion:
    t = np.asarray(table.times, dtype=float)
    y = np.asarray(table.values, dtype=float)
    h = np.diff(t)
    coef = np.zeros((len(t) - 1, 4))
    if quantity == "acceleration":
        vel, disp = table.integrated(v0, x0)
        coef[:, 0], coef[:, 1] = disp.values[:-1], vel.values[:-1]
        coef[:, 2] = 0.5 * y[:-1]
        coef[:, 3] = np.diff(y) / h / 6.0
        if table.outside == "zero":
            before = after = 0.0
        else:
            before, after = float(y[0]), float(y[-1])
        return _PiecewiseMotion(t, coef, before, after)
    if quantity == "velocity":
        disp = table.integral(x0)
        coef[:, 0], coef[:, 1] = disp.values[:-1], y[:-1]
        coef[:, 2] = 0.5 * np.diff(y) / h
        return _PiecewiseMotion(t, coef, 0.0, 0.0)
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(t, y, bc_type="natural")
    coef[:] = spline.c[::-1].T  # scipy: descending powers, (4, n - 1)
    return _PiecewiseMotion(t, coef, 0.0, 0.0)
