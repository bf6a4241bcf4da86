r"""Small dense linear algebra for the Newton solver, on Python floats.

:func:`lu_factor` / :func:`lu_solve` (partial pivoting) for systems of at most
:data:`DENSE_PYTHON_MAX` unknowns, numpy on the whole matrix above; :func:`unrolled_lu_solve`
generates a branch-free solve for fixed factors, and :class:`FactorCache` keeps the last
factorisation so that a step whose Jacobian is unchanged reuses it; :func:`kept_factor_solver`
keeps the factorisations of the last few Jacobians of any solve, by their bits.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

__all__ = ["DENSE_PYTHON_MAX", "FactorCache", "factor_solver", "kept_factor_solver",
           "lu_factor", "lu_solve", "unrolled_lu_solve"]


#: Largest system factorised in plain Python; larger ones use numpy on the whole matrix.
DENSE_PYTHON_MAX = 8


def lu_factor(A: Sequence[Sequence[float]]) -> tuple[list[list[float]], list[int]] | None:
    """LU factorisation with partial pivoting of a small dense matrix, in plain floats.

    The pivot of column ``k`` is the first *singleton row* (no other nonzero in the
    columns ``k..n-1``) if there is one, else the largest entry (partial pivoting).

    Returns ``(LU, perm)`` (unit lower and upper factors packed in one matrix, and the
    row permutation), or ``None`` when a pivot is exactly zero or not finite.
    """
    n = len(A)
    LU = [list(row) for row in A]
    perm = list(range(n))
    for k in range(n):
        p = k
        best = abs(LU[k][k])
        for i in range(k + 1, n):
            a = abs(LU[i][k])
            if a > best:
                best, p = a, i
        # A singleton row (its only nonzero in the active columns is in column k) is
        # preferred as the pivot: eliminating with it is an exact substitution (no
        # growth: it adds nothing to the other rows' entries), and the unknown it fixes
        # comes out of one division, exactly where the row says so (a stuck dashpot's
        # row `v = 0` gives `v = 0`, not the round-off of a mixed row).
        if best > 0.0:
            for i in range(k, n):
                ri = LU[i]
                if ri[k] != 0.0 and not any(ri[k + 1:]):
                    p, best = i, abs(ri[k])
                    break
        if not (best > 0.0) or best == math.inf:
            return None
        if p != k:
            LU[k], LU[p] = LU[p], LU[k]
            perm[k], perm[p] = perm[p], perm[k]
        rk = LU[k]
        piv = rk[k]
        for i in range(k + 1, n):
            ri = LU[i]
            f = ri[k]
            if f != 0.0:
                f /= piv
                ri[k] = f
                for j in range(k + 1, n):
                    ri[j] -= f * rk[j]
    return LU, perm


def lu_solve(factors: tuple[list[list[float]], list[int]], b: Sequence[float]) -> list[float]:
    """Solve ``A y = b`` with the factors from :func:`lu_factor`."""
    LU, perm = factors
    n = len(LU)
    y = [b[p] for p in perm]
    for i in range(1, n):
        ri = LU[i]
        s = y[i]
        for j in range(i):
            s -= ri[j] * y[j]
        y[i] = s
    for i in range(n - 1, -1, -1):
        ri = LU[i]
        s = y[i]
        for j in range(i + 1, n):
            s -= ri[j] * y[j]
        y[i] = s / ri[i]
    return y


class _NumpyLU:
    """Factor/solve pair for systems larger than :data:`DENSE_PYTHON_MAX` (numpy/scipy)."""

    def __init__(self, A: Sequence[Sequence[float]]) -> None:
        import numpy as np
        import scipy.linalg

        M = np.array(A, dtype=float)
        if not np.all(np.isfinite(M)):
            raise ZeroDivisionError
        # LAPACK's getrf directly: scipy.linalg.lu_factor warns (LinAlgWarning) on an
        # exactly singular matrix, which Newton expects and handles (min-norm steps)
        (getrf,) = scipy.linalg.get_lapack_funcs(("getrf",), (M,))
        lu, piv, info = getrf(M, overwrite_a=True)
        if info != 0 or np.any(np.diag(lu) == 0.0):
            raise ZeroDivisionError
        self._f = (lu, piv)

    def solve(self, b: Sequence[float]) -> list[float]:
        import scipy.linalg

        return scipy.linalg.lu_solve(self._f, list(b), check_finite=False).tolist()


def factor_solver(J: list[list[float]]):
    """Return a ``solve(b)`` callable for ``J``, or ``None`` if ``J`` is singular."""
    if len(J) <= DENSE_PYTHON_MAX:
        f = lu_factor(J)
        if f is None:
            return None

        def solve(b: Sequence[float]) -> list[float]:
            return lu_solve(f, b)

        solve.factors = f  # type: ignore[attr-defined]
        return solve
    try:
        return _NumpyLU(J).solve
    except (ZeroDivisionError, ValueError):
        return None


#: :func:`kept_factor_solver`'s solvers by the bits of their Jacobians, the last
#: :data:`KEPT_FACTORS` made.
_KEPT: dict[bytes, object] = {}
KEPT_FACTORS = 64


def kept_factor_solver(J: list[list[float]]):
    """:func:`factor_solver` ``(J)``, kept per ``J``'s bits (a signed zero is not the other
    zero) for the last :data:`KEPT_FACTORS` Jacobians of at most :data:`DENSE_PYTHON_MAX`
    unknowns: the same factors, so the same solves, bit for bit. For the few solves whose
    Jacobians recur across scenes: the consistent initial state's read the masses, the
    laws' slopes and the vanishing step, not a spring's force, so a new spring constant
    meets the Jacobians of the last one (:mod:`lumped.solvers.implicit.initial_state`)."""
    n = len(J)
    if n > DENSE_PYTHON_MAX:
        return factor_solver(J)
    try:
        key = struct.pack(f"{n * n}d", *[x for row in J for x in row])
    except struct.error:  # (not floats: not kept)
        return factor_solver(J)
    got = _KEPT.get(key, False)
    if got is False:
        got = factor_solver(J)
        if len(_KEPT) >= KEPT_FACTORS:
            _KEPT.clear()
        _KEPT[key] = got
    return got


class FactorCache:
    """The last factorised Jacobian and its solver, shared by consecutive solves.

    Piecewise-linear laws give the same Jacobian step after step (same pieces, fixed
    ``dt``); a solve whose Jacobian equals the cached one (entrywise) reuses the factors
    and counts no factorisation.
    """

    __slots__ = ("J", "solve", "hits")

    def __init__(self) -> None:
        self.J: list[list[float]] | None = None
        self.solve = None
        self.hits = 0

    def store(self, J: list[list[float]], solve) -> None:
        self.J, self.solve, self.hits = J, solve, 0

    def hit(self):
        """The cached solver; from the second reuse on, an unrolled one (same arithmetic)."""
        self.hits += 1
        if self.hits == 2 and hasattr(self.solve, "factors"):
            self.solve = unrolled_lu_solve(self.solve.factors)
        return self.solve


def unrolled_lu_solve(factors: tuple[list[list[float]], list[int]]):
    """:func:`lu_solve` for fixed factors as generated straight-line code.

    The same operations in the same order as :func:`lu_solve` (so the same results, bit
    for bit), with the factors inlined as float literals (``repr`` round-trips exactly).
    Worth its compilation (~0.1 ms) only for factors that are reused many times.
    """
    LU, perm = factors
    n = len(LU)
    lines = ["def solve(b):"]
    lines += [f"    y{i} = b[{perm[i]}]" for i in range(n)]
    for i in range(1, n):
        terms = "".join(f" - {LU[i][j]!r} * y{j}" for j in range(i))
        lines.append(f"    y{i} = y{i}{terms}")
    for i in range(n - 1, -1, -1):
        terms = "".join(f" - {LU[i][j]!r} * y{j}" for j in range(i + 1, n))
        lines.append(f"    y{i} = (y{i}{terms}) / {LU[i][i]!r}")
    lines.append("    return [" + ", ".join(f"y{i}" for i in range(n)) + "]")
    namespace: dict = {"__builtins__": {}}
    exec(compile("\n".join(lines) + "\n", "<lumped LU solve>", "exec"), namespace)  # noqa: S102
    return namespace["solve"]
