r"""Generic BDF1 / BDF2 time stepping of a :class:`~lumped.scene.Scene`.

One step is one discrete system in all unknowns at ``t_{n+1}``. BDF with fixed step
``dt`` reads, for every node, ``x_{n+1} = x_hat + h v_{n+1}`` and (masses)
``m (v_{n+1} - v_hat) / h = net force at t_{n+1}``, with

* BDF1 (backward Euler): ``h = dt``, ``x_hat = x_n``, ``v_hat = v_n``;
* BDF2: ``h = 2 dt / 3``, ``x_hat = (4 x_n - x_{n-1}) / 3``, ``v_hat = (4 v_n - v_{n-1}) / 3``,
  computed as ``y_n + (y_n - y_{n-1}) / 3`` (the same value, but exact when
  ``y_n == y_{n-1}``, so a stuck state stays put bit for bit; as
  :func:`lumped.bingham.bdf2_step`); its first step is a BDF1 step.

The positions are eliminated (``x_{n+1} = x_hat + h v_{n+1}``), which leaves the unknowns
``u = (v_1 .. v_N, F_1 .. F_E)`` -- every node's velocity and every element's force --
and the equations (rows in that order)::

    mass i:      (m_i / h)(v_i - v_hat_i) - f_i(t) - sum_{a_e = i} F_e + sum_{b_e = i} F_e = 0
    junction i:                         - f_i(t) - sum_{a_e = i} F_e + sum_{b_e = i} F_e = 0
    element e:   R_e(q_e, F_e) = 0,   q_e = x_b - x_a (spring) or v_b - v_a (dashpot)

solved by :func:`lumped.newton.newton_solve` from the previous step's solution. The
Jacobian is assembled from the kernels' ``dR/dq, dR/dF`` (``dq/dv = +-h`` for springs,
``+-1`` for dashpots). Everything runs on Python floats.

**Consistent initial state.** The same system with a vanishing step ``h = eps`` and the
masses' accelerations as unknowns (``v_i = v_i(0) + eps a_i``) selects the initial
forces that the limit ``dt -> 0`` of the implicit steps selects: a stuck dashpot takes
the force that keeps its mass at rest if its law admits it, else the nearest admissible
one (for the paper's scene ``clip(F(0) - k x0, -tau, tau)``, as
:func:`lumped.bingham.initial_dashpot_force`), and junction velocities follow from the
laws.

**Branches of non-monotone laws.** After each step, every element whose law is not a
known monotone built-in is checked for a jump between branches: if ``dR/dq`` or
``dR/dF`` takes strictly opposite signs at the old and new point (or, when the step
leaves the tangent of the law, at points sampled on the segment between them), the
step has crossed or skipped a fold. The run stops with :class:`BranchError` (time,
element, the two points) instead of jumping silently.
"""

from __future__ import annotations

import enum
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field

from .newton import (
    FactorCache,
    NewtonCode,
    NewtonOptions,
    NewtonResult,
    _residual_ok,
    _update_ok,
    newton_solve,
)
from .scene import Junction, Mass, Scene

__all__ = [
    "Status",
    "SolverError",
    "BranchError",
    "InconsistentInitialForce",
    "RunResult",
    "consistent_initial_state",
    "run_bdf",
    "GENERIC_METHODS",
    "MONOTONE_BUILTINS",
]

#: Generic step formulas by name.
GENERIC_METHODS = ("bdf1", "bdf2")

#: Built-in laws whose graph is monotone (no folds); their branch check is skipped.
MONOTONE_BUILTINS = frozenset(
    {"linear_spring", "string_spring", "newtonian", "bingham", "coulomb", "herschel_bulkley",
     "implicit_spring"}
)


class Status(enum.Enum):
    """Outcome of a run."""

    SUCCESS = "success"
    MAX_ITERS = "max_iters"  #: Newton's iteration budget ran out
    DIVERGED = "diverged"  #: Newton's line search found no decrease
    SINGULAR = "singular"  #: singular step Jacobian
    NON_FINITE = "non_finite"  #: NaN or infinity met
    BRANCH_LOST = "branch_lost"  #: a non-monotone law would have jumped between branches


class SolverError(RuntimeError):
    """A step failed. Attributes: ``status``, ``t``, ``where`` (element or node), ``residual``."""

    def __init__(self, message: str, *, status: Status, t: float, where: str,
                 residual: float) -> None:
        super().__init__(message)
        self.status, self.t, self.where, self.residual = status, t, where, residual


class BranchError(SolverError):
    """A non-monotone law reached a fold: no solution continuous with the past."""


class InconsistentInitialForce(ValueError):
    """A user-supplied initial force breaks its element's law (or a junction balance)."""


@dataclass
class RunResult:
    """Raw output of :func:`run_bdf`: the node displacements ``xs``, velocities ``vs`` and
    element forces ``Fs`` of all samples (``t_n = n dt``), each flat (sample-major, so the
    step loop creates no lasting containers for the garbage collector), and the counters."""

    dt: float
    n_nodes: int
    n_elements: int
    xs: list[float]
    vs: list[float]
    Fs: list[float]
    stats: dict = field(default_factory=dict)
    status: Status = Status.SUCCESS
    message: str = ""

    def as_array(self):
        """``(n, 1 + 2 N + E)`` array: ``t``, then ``x_i, v_i`` per node, then ``F_e``."""
        import numpy as np

        N, E = self.n_nodes, self.n_elements
        n = len(self.xs) // N
        out = np.empty((n, 1 + 2 * N + E))
        out[:, 0] = np.arange(n, dtype=float) * self.dt
        out[:, 1:1 + 2 * N:2] = np.array(self.xs, dtype=float).reshape(n, N)
        out[:, 2:2 + 2 * N:2] = np.array(self.vs, dtype=float).reshape(n, N)
        out[:, 1 + 2 * N:] = np.array(self.Fs, dtype=float).reshape(n, E)
        return out


# ---------------------------------------------------------------------------------------
# the discrete system of one step


def _make_evaluate(scene: Scene, h: float, cm: Sequence[float], vbase: Sequence[float],
                   vscale: Sequence[float], uref: list[float], x_hat: list[float],
                   f: list[float], qs: list[float], rq: list[float], rf: list[float],
                   roundoff: bool = False):
    """Build ``evaluate(u) -> (G, J, S)`` for one step size.

    The scale of a law row is ``|dR/dq q| + |dR/dF F|``; with ``roundoff`` it is
    :func:`_law_scale` (at least that, more where the law's terms cancel).

    ``uref, x_hat, f`` are read at call time (the step loop updates them in place);
    ``qs, rq, rf`` receive each element's ``q, dR/dq, dR/dF`` at the last evaluated point.
    This loop version is the readable reference of the step system; the step loop runs its
    generated twin :func:`_generate_evaluate` (tested equal)."""
    N = len(scene.nodes)
    E = len(scene.elements)
    n = N + E
    kernels = tuple(el.law.kernel for el in scene.elements)
    spring = tuple(el.kind == "spring" for el in scene.elements)
    ea, eb = scene.elem_a, scene.elem_b
    cm = tuple(cm)
    vbase = tuple(vbase)
    vscale = tuple(vscale)
    nodes = range(N)
    elements = tuple(
        (e, N + e, ea[e], eb[e], spring[e], kernels[e]) for e in range(E)
    )

    def evaluate(u: list[float]):
        G = [0.0] * n
        S = [0.0] * n
        J = [[0.0] * n for _ in range(n)]
        vel = [vbase[i] + vscale[i] * u[i] for i in nodes]
        for i in nodes:
            c = cm[i]
            fi = f[i]
            if c:
                p = c * u[i]
                r = c * uref[i]
                G[i] = (p - r) - fi
                S[i] = abs(p) + abs(r) + abs(fi)
                J[i][i] = c
            else:
                G[i] = -fi
                S[i] = abs(fi)
        for e, k, a, b, is_spring, kernel in elements:
            Fe = u[k]
            aF = abs(Fe)
            if is_spring:
                qb = x_hat[b] + h * vel[b] if b >= 0 else 0.0
                qa = x_hat[a] + h * vel[a] if a >= 0 else 0.0
                dq = h
            else:
                qb = vel[b] if b >= 0 else 0.0
                qa = vel[a] if a >= 0 else 0.0
                dq = 1.0
            q = qb - qa
            R, Rq, RF = kernel(q, Fe)
            G[k] = R
            S[k] = (_law_scale(kernel, q, Fe, R, Rq, RF) if roundoff
                    else abs(Rq * q) + abs(RF * Fe))
            row = J[k]
            row[k] = RF
            g = Rq * dq
            if a >= 0:
                G[a] -= Fe
                S[a] += aF
                J[a][k] = -1.0
                row[a] = -g * vscale[a]
            if b >= 0:
                G[b] += Fe
                S[b] += aF
                J[b][k] = 1.0
                row[b] = g * vscale[b]
            qs[e] = q
            rq[e] = Rq
            rf[e] = RF
        return G, J, S

    return evaluate


def _generate_evaluate(scene: Scene, h: float, uref: list[float], x_hat: list[float],
                       f: list[float], roundoff: bool = False):
    """The step system of :func:`_make_evaluate` (regular steps, ``v = u``, without the
    per-element side outputs) as generated, unrolled straight-line Python for this scene:
    no loops, no index lookups, constants inlined. Only indices and float literals enter
    the source (never a name from the scene), so a scene file cannot inject code. The
    source is kept in ``__source__``. ``roundoff`` as in :func:`_make_evaluate`."""
    N, E = len(scene.nodes), len(scene.elements)
    n = N + E
    masses = scene.masses
    lines = ["def evaluate(u):"]
    lines.append("    " + "".join(f"u{j}, " for j in range(n)) + "= u")
    J: dict[tuple[int, int], str] = {}
    for i in range(N):
        c = masses[i] / h
        if c:
            lines += [f"    p = {c!r} * u{i}", f"    r = {c!r} * uref[{i}]", f"    fi = f[{i}]",
                      f"    G{i} = (p - r) - fi", f"    S{i} = abs(p) + abs(r) + abs(fi)"]
            J[i, i] = repr(c)
        else:
            lines += [f"    fi = f[{i}]", f"    G{i} = -fi", f"    S{i} = abs(fi)"]
    for e, el in enumerate(scene.elements):
        k, a, b = N + e, scene.elem_a[e], scene.elem_b[e]
        if el.kind == "spring":
            qb = f"(xh[{b}] + {h!r} * u{b})" if b >= 0 else "0.0"
            qa = f"(xh[{a}] + {h!r} * u{a})" if a >= 0 else "0.0"
            dq = h
        else:
            qb = f"u{b}" if b >= 0 else "0.0"
            qa = f"u{a}" if a >= 0 else "0.0"
            dq = 1.0
        scale = (f"law_scale(k{e}, q, u{k}, R, Rq, RF)" if roundoff
                 else f"abs(Rq * q) + abs(RF * u{k})")
        lines += [f"    q = {qb} - {qa}", f"    R, Rq, RF = k{e}(q, u{k})", f"    G{k} = R",
                  f"    S{k} = {scale}", f"    g{e} = Rq * {dq!r}", f"    RF{e} = RF"]
        J[k, k] = f"RF{e}"
        if a >= 0:
            lines += [f"    G{a} -= u{k}", f"    S{a} += abs(u{k})"]
            J[a, k] = "-1.0"
            J[k, a] = f"-g{e}"
        if b >= 0:
            lines += [f"    G{b} += u{k}", f"    S{b} += abs(u{k})"]
            J[b, k] = "1.0"
            J[k, b] = f"g{e}"
    rows = ", ".join("[" + ", ".join(J.get((r, c), "0.0") for c in range(n)) + "]"
                     for r in range(n))
    lines += ["    return ([" + ", ".join(f"G{i}" for i in range(n)) + "], [" + rows + "], ["
              + ", ".join(f"S{i}" for i in range(n)) + "])"]
    src = "\n".join(lines) + "\n"
    namespace: dict = {"uref": uref, "xh": x_hat, "f": f, "abs": abs, "law_scale": _law_scale,
                       "__builtins__": {}}
    for e, el in enumerate(scene.elements):
        namespace[f"k{e}"] = el.law.kernel
    exec(compile(src, "<lumped step system>", "exec"), namespace)  # noqa: S102 - our own code
    evaluate = namespace["evaluate"]
    evaluate.__source__ = src
    return evaluate


#: Unit roundoff of a double (``2**-52``).
_EPS = sys.float_info.epsilon


def _law_scale(kernel, q: float, F: float, R: float, Rq: float, RF: float) -> float:
    r"""Scale of the terms of a law row ``R(q, F)``, for the residual test.

    ``max(|R_q q| + |R_F F|, M)``, ``M = kernel.magnitude(q, F)`` the magnitude of the
    residual's terms generated with the kernel (:func:`lumped.codegen.magnitude_expression`):
    on a smooth piece without cancellation about the linearised scale; where the law's
    terms cancel, their size. Example: a Bingham dashpot on its stuck piece
    (``R_F = 0``) with its true root ``1e-17`` beyond ``tau``: the residual is ``q``
    (``gamma * 1e-17`` away from 0) and only the terms ``gamma F`` and ``gamma clip(F)``
    (``M = |q| + 2 gamma |F|``) show that this is round-off, not an error -- also a few
    hundred ulps inside the stuck piece, where a long Newton step lands after
    cancellation.

    A kernel without ``magnitude`` (hand-written) gets ``rho / eps`` instead of ``M``,
    ``rho`` the largest change of ``R`` when ``q`` or ``F`` moves to a floating-point
    neighbour (four kernel calls): the terms as the law's round-off shows them, which
    sees a cancellation only within an ulp of the kink. Used where Newton iterates (the
    initial state, steps off the fast path).
    """
    lin = abs(Rq * q) + abs(RF * F)
    mag = getattr(kernel, "magnitude", None)
    if mag is not None:
        M = mag(q, F)
        return M if M > lin and M != math.inf else lin  # NaN fails the comparison
    rho = 0.0
    inf = math.inf
    for qq, FF in ((math.nextafter(q, -inf), F), (math.nextafter(q, inf), F),
                   (q, math.nextafter(F, -inf)), (q, math.nextafter(F, inf))):
        d = abs(kernel(qq, FF)[0] - R)
        if d > rho and d != inf:  # NaN fails the comparison
            rho = d
    ro = rho / _EPS
    return ro if ro > lin else lin


def _where(scene: Scene, row: int) -> str:
    N = len(scene.nodes)
    if row < N:
        node = scene.nodes[row]
        kind = "momentum balance" if isinstance(node, Mass) else "force balance"
        return f"{kind} of node {node.name!r}"
    el = scene.elements[row - N]
    return f"law {el.law_name!r} of element {el.name!r}"


def _newton_failure(scene: Scene, res: NewtonResult, t: float, step: int) -> SolverError:
    where = _where(scene, res.worst_row)
    r = res.residual[res.worst_row] if res.residual else math.nan
    msg = (
        f"Newton failed ({res.code.value}) at t = {t!r} (step {step}) after "
        f"{res.iterations} iterations: largest residual {r!r} in the {where}"
    )
    if res.code is NewtonCode.SINGULAR:
        msg += (" (singular step Jacobian: the laws do not determine all forces and "
                "velocities, e.g. two rigid or stuck elements in parallel, or a junction "
                "whose elements are all stuck)")
    return SolverError(msg, status=Status(res.code.value), t=t, where=where, residual=r)


# ---------------------------------------------------------------------------------------
# consistent initial state


def _scalar_root(kernel, q: float, F0: float) -> tuple[float, bool]:
    """Solve ``R(q, F) = 0`` for ``F`` (``q`` fixed) by safeguarded Newton in a bracket.

    Returns ``(F, pinned)``: ``pinned`` is False when the law is flat in ``F`` at an
    exact root (``R = 0`` with ``dR/dF = 0``: a set-valued law, e.g. a stuck Bingham
    dashpot), so that ``F`` is not fixed by the law alone; a root found only as a sign
    change between neighbouring floats is isolated, hence pinned. Raises ValueError if
    no sign change is found.
    """
    R, _, RF = kernel(q, F0)
    if R == 0.0:
        return F0, RF != 0.0
    # bracket: expand both ways from F0
    lo = hi = None
    step = 1.0 + abs(F0)
    for _ in range(2000):
        for cand in (F0 + step, F0 - step):
            Rc = kernel(q, cand)[0]
            if Rc == 0.0:
                _, _, RFc = kernel(q, cand)
                return cand, RFc != 0.0
            if (Rc > 0.0) != (R > 0.0):
                lo, hi = (F0, cand) if cand > F0 else (cand, F0)
                break
        if lo is not None or step > 1e300:
            break
        step *= 2.0
    if lo is None:
        raise ValueError(f"no root of the law in F at q = {q!r}")
    R_lo = kernel(q, lo)[0]
    F = F0 if lo <= F0 <= hi else 0.5 * (lo + hi)
    for _ in range(400):
        R, _, RF = kernel(q, F)
        if R == 0.0:
            return F, RF != 0.0
        if (R > 0.0) == (R_lo > 0.0):
            lo, R_lo = F, R
        else:
            hi = F
        F_new = F - R / RF if RF != 0.0 else math.nan
        if not (lo < F_new < hi):
            F_new = 0.5 * (lo + hi)
        if F_new == F or not (lo < F_new < hi):
            break
        F = F_new
    # No exact zero: the root lies between floating-point neighbours (e.g. a Bingham
    # force tau + q / gamma with q / gamma below an ulp of tau, at the kink). The sign
    # change isolates it, so the law fixes F there even if the nearest float sits on a
    # flat piece: take the candidate with the smallest |R| (the correctly rounded root).
    best = min((F, lo, hi), key=lambda c: abs(kernel(q, c)[0]))
    return best, True


def consistent_initial_state(
    scene: Scene, *, time_scale: float = 1.0, options: NewtonOptions | None = None
) -> tuple[list[float], list[float], dict]:
    """Initial velocities of all nodes and forces of all elements at ``t = 0``.

    Masses keep their given ``v0``. Then:

    1. every element whose ``q`` is known at ``t = 0`` (all springs; dashpots between
       masses and ground) gets its force from its own law, ``R(q0, F) = 0``, if the law
       fixes it there (``dR/dF != 0``);
    2. the rest -- forces of laws that are flat in ``F`` at ``q0`` (a stuck dashpot),
       dashpots at junctions, junction velocities -- solve the limit ``h -> 0`` of an
       implicit step: the masses' accelerations ``a`` are unknowns, a flat law is read
       at ``q0 + h (a_b - a_a)`` with ``h = 1e-20 * time_scale``, junction balances hold.
       A stuck dashpot thus takes the force that keeps its mass at rest if its law
       admits it, else the nearest admissible one (for the paper's scene
       ``clip(F(0) - k x0, -tau, tau)``, as :func:`lumped.bingham.initial_dashpot_force`).

    User forces ``Element.F0`` are checked against the law at the initial state (and the
    junction balances), then replace the computed ones.

    Returns
    -------
    v, F, stats
        Node velocities, element forces and Newton counters.

    Raises
    ------
    InconsistentInitialForce
        If a user ``F0`` breaks its element's law or a junction's force balance.
    SolverError
        If the algebraic system has no solution Newton can find.
    """
    options = options or NewtonOptions()
    nodes, elements = scene.nodes, scene.elements
    N, E = len(nodes), len(elements)
    n = N + E
    eps = 1e-20 * time_scale
    is_mass = [isinstance(nd, Mass) for nd in nodes]
    mass = [nd.m if isinstance(nd, Mass) else 0.0 for nd in nodes]
    v0 = [nd.v0 if isinstance(nd, Mass) else 0.0 for nd in nodes]
    x0 = [nd.x0 for nd in nodes]
    ea, eb = scene.elem_a, scene.elem_b
    f = scene.external_forces(0.0)

    def at(vals: list[float], i: int) -> float:
        return vals[i] if i >= 0 else 0.0

    # 1. forces fixed by the laws alone
    pinned: list[float | None] = [None] * E
    q0 = [0.0] * E
    for e, el in enumerate(elements):
        a, b = ea[e], eb[e]
        if el.kind == "spring":
            q0[e] = at(x0, b) - at(x0, a)
        elif all(i < 0 or is_mass[i] for i in (a, b)):
            q0[e] = at(v0, b) - at(v0, a)
        else:
            continue  # a dashpot at a junction: its rate is unknown
        guess = el.F0 if el.F0 is not None else 0.0
        try:
            F_root, fixed = _scalar_root(el.law.kernel, q0[e], guess)
        except ValueError as err:
            raise SolverError(
                f"no consistent initial state: law {el.law_name!r} of element {el.name!r} "
                f"has no force at q = {q0[e]!r}: {err}", status=Status.DIVERGED, t=0.0,
                where=f"element {el.name!r}", residual=math.nan,
            ) from None
        if fixed:
            pinned[e] = F_root
    # 2. the limit system
    kernels = [el.law.kernel for el in elements]
    spring = [el.kind == "spring" for el in elements]

    def evaluate(u: list[float]):
        G = [0.0] * n
        S = [0.0] * n
        J = [[0.0] * n for _ in range(n)]
        # d_i: the node's velocity increment (eps a for masses, v for junctions)
        d = [eps * u[i] if is_mass[i] else u[i] for i in range(N)]
        dd = [eps if is_mass[i] else 1.0 for i in range(N)]
        for i in range(N):
            if is_mass[i]:
                p = mass[i] * u[i]
                G[i] = p - f[i]
                S[i] = abs(p) + abs(f[i])
                J[i][i] = mass[i]
            else:
                G[i] = -f[i]
                S[i] = abs(f[i])
        for e in range(E):
            k = N + e
            Fe = u[k]
            a, b = ea[e], eb[e]
            for i, sgn in ((a, -1.0), (b, 1.0)):
                if i >= 0:
                    G[i] += sgn * Fe
                    S[i] += abs(Fe)
                    J[i][k] = sgn
            row = J[k]
            Fp = pinned[e]
            if Fp is not None:
                G[k] = Fe - Fp
                S[k] = abs(Fe) + abs(Fp)
                row[k] = 1.0
                continue
            scale = eps if spring[e] else 1.0  # springs see x0 + eps * v
            q = q0[e] + scale * (at(d, b) - at(d, a))
            R, Rq, RF = kernels[e](q, Fe)
            G[k] = R
            S[k] = _law_scale(kernels[e], q, Fe, R, Rq, RF)
            row[k] = RF
            if a >= 0:
                row[a] = -Rq * scale * dd[a]
            if b >= 0:
                row[b] = Rq * scale * dd[b]
        return G, J, S

    u0 = [0.0] * N + [
        Fp if Fp is not None else (el.F0 if el.F0 is not None else 0.0)
        for Fp, el in zip(pinned, elements, strict=True)
    ]
    # one solve per run: allow a generous budget (degenerate yields converge linearly)
    ic_options = NewtonOptions(rtol=options.rtol, atol=options.atol,
                               max_iters=max(options.max_iters, 200),
                               max_backtracks=options.max_backtracks,
                               free_steps=options.free_steps)
    res = newton_solve(evaluate, u0, ic_options)
    if res.code is not NewtonCode.SUCCESS:
        err = _newton_failure(scene, res, 0.0, 0)
        raise SolverError(
            f"no consistent initial state: {err}", status=err.status, t=0.0,
            where=err.where, residual=err.residual,
        )
    u = res.u
    v = [v0[i] if is_mass[i] else u[i] for i in range(N)]
    F = list(u[N:])
    user = [e for e, el in enumerate(elements) if el.F0 is not None]
    if user:
        q_init = scene.elongations(x0, v)
        for e in user:
            el = elements[e]
            R, Rq, RF = el.law.kernel(q_init[e], el.F0)
            tol = 1e-9 * (abs(Rq * q_init[e]) + abs(RF * el.F0)) + 1e-12
            if not abs(R) <= tol:
                raise InconsistentInitialForce(
                    f"initial force F0 = {el.F0!r} of element {el.name!r} breaks its law "
                    f"{el.law_name!r}: R(q={q_init[e]!r}, F={el.F0!r}) = {R!r} != 0"
                )
            F[e] = el.F0
        net = scene.net_forces(0.0, F)
        for i, node in enumerate(nodes):
            if isinstance(node, Junction):
                scale = abs(f[i]) + sum(abs(F[e]) for e in range(E) if i in (ea[e], eb[e]))
                if not abs(net[i]) <= 1e-9 * scale + 1e-12:
                    raise InconsistentInitialForce(
                        f"initial forces break the force balance of junction {node.name!r}: "
                        f"net force {net[i]!r} != 0"
                    )
    stats = {
        "newton_iterations": res.iterations, "residual_evals": res.residual_evals,
        "jacobian_evals": res.jacobian_evals, "factorizations": res.factorizations,
    }
    return v, F, stats


# ---------------------------------------------------------------------------------------
# the step loop


def run_bdf(
    scene: Scene,
    *,
    method: str,
    dt: float,
    n_steps: int,
    options: NewtonOptions | None = None,
    throw: bool = True,
) -> RunResult:
    """Advance ``scene`` by ``n_steps`` fixed steps of BDF1 or BDF2 (first step BDF1).

    Returns the samples (see :class:`RunResult`; ``as_array()`` gives the columns ``t``,
    ``x_i, v_i`` per node, ``F_e`` per element) and the counters. On a failed step: raise
    :class:`SolverError` (``throw=True``) or return the samples so far with ``status`` and
    ``message`` set.
    """
    if method not in GENERIC_METHODS:
        raise ValueError(f"`method` must be one of {GENERIC_METHODS}, got {method!r}")
    options = options or NewtonOptions()
    N, E = len(scene.nodes), len(scene.elements)
    v, F, ic_stats = consistent_initial_state(scene, time_scale=dt, options=options)
    x = [n.x0 for n in scene.nodes]
    forcing = [(i, fn) for i, fn in enumerate(scene.forcing) if fn is not None]
    isfinite = math.isfinite

    x_hat, uref, f = [0.0] * N, [0.0] * N, [0.0] * N
    h1 = dt
    h2 = 2.0 * dt / 3.0
    # the fast path tests with the linearised row scales; Newton proper (from the same
    # start, when the fast path declines) with the round-off scales of _law_scale
    ev1 = _generate_evaluate(scene, h1, uref, x_hat, f)
    full1 = _generate_evaluate(scene, h1, uref, x_hat, f, roundoff=True)
    ev2 = full2 = None
    if method == "bdf2":
        ev2 = _generate_evaluate(scene, h2, uref, x_hat, f)
        full2 = _generate_evaluate(scene, h2, uref, x_hat, f, roundoff=True)

    # branch bookkeeping: q, dR/dq, dR/dF at the last accepted point of checked elements
    checked = [e for e, el in enumerate(scene.elements) if not _known_monotone(el.law)]
    prev_q = scene.elongations(x, v)
    prev_d = [el.law.kernel(prev_q[e], F[e]) for e, el in enumerate(scene.elements)]

    cache1, cache2 = FactorCache(), FactorCache()
    rtol, atol = options.rtol, options.atol
    fast = options.free_steps >= 1
    xs, vs, Fs = list(x), list(v), list(F)
    total_it = res_ev = jac_ev = facts = 0
    max_it = 0
    status, message = Status.SUCCESS, ""
    x_prev, v_prev = x, v
    for step in range(1, n_steps + 1):
        t = step * dt
        for i, fn in forcing:
            val = fn(t)
            if not isfinite(val):
                raise ValueError(
                    f"force on node {scene.nodes[i].name!r} returned {val!r} at t = {t!r}"
                )
            f[i] = val
        if ev2 is None or step == 1:
            h = h1
            evaluate, full = ev1, full1
            for i in range(N):
                x_hat[i] = x[i]
                uref[i] = v[i]
        else:
            h = h2
            evaluate, full = ev2, full2
            for i in range(N):
                # (4 y_n - y_{n-1}) / 3 as an increment: exact for a stuck state
                # (y_n == y_{n-1}), where the textbook form is one ulp off for about one
                # value in seven; the closed form (bingham.bdf2_step) uses the same formula
                xi, vi = x[i], v[i]
                x_hat[i] = xi + (xi - x_prev[i]) / 3.0
                uref[i] = vi + (vi - v_prev[i]) / 3.0
        cache = cache1 if h == h1 else cache2
        u = _fast_step(evaluate, v + F, cache, rtol, atol) if fast else None
        if u is not None:  # the common case, counted as newton_solve would count it
            it = u.pop()
            total_it += it
            res_ev += 1 + it
            jac_ev += 1
            if it > max_it:
                max_it = it
        else:
            res = newton_solve(full, v + F, options, cache)
            total_it += res.iterations
            res_ev += res.residual_evals
            jac_ev += res.jacobian_evals
            facts += res.factorizations
            if res.iterations > max_it:
                max_it = res.iterations
            if res.code is not NewtonCode.SUCCESS:
                err = _newton_failure(scene, res, t, step)
                if throw:
                    raise err
                status, message = err.status, str(err)
                break
            u = res.u
        v_new = u[:N]
        x_new = [x_hat[i] + h * v_new[i] for i in range(N)]
        F_prev, F = F, u[N:]
        q_new = scene.elongations(x_new, v_new) if checked else ()
        for e in checked:
            q0, d0 = prev_q[e], prev_d[e]
            kernel = scene.elements[e].law.kernel
            d1 = kernel(q_new[e], F[e])  # at the accepted point
            if _left_branch(kernel, q0, F_prev[e], d0[1], d0[2], q_new[e], F[e], d1[1], d1[2]):
                el = scene.elements[e]
                msg = (
                    f"element {el.name!r} (law {el.law_name!r}) left its branch at t = {t!r} "
                    f"(step {step}): from (q, F) = ({q0!r}, {F_prev[e]!r}) to "
                    f"({q_new[e]!r}, {F[e]!r}) the law's dR/dq or dR/dF changes sign -- a fold; "
                    "there is no solution continuous with the past at this step"
                )
                err = BranchError(msg, status=Status.BRANCH_LOST, t=t,
                                  where=f"law {el.law_name!r} of element {el.name!r}",
                                  residual=d1[0])
                if throw:
                    raise err
                status, message = Status.BRANCH_LOST, msg
                break
            prev_q[e] = q_new[e]
            prev_d[e] = d1
        if status is not Status.SUCCESS:
            break
        x_prev, v_prev, x, v = x, v, x_new, v_new
        xs += x
        vs += v
        Fs += F
    steps = len(xs) // N - 1
    stats = {
        "steps": steps,
        "newton_iterations": total_it,
        "residual_evals": res_ev,
        "jacobian_evals": jac_ev,
        "factorizations": facts,
        "max_newton_iterations": max_it,
        "initial_newton_iterations": ic_stats["newton_iterations"],
    }
    return RunResult(dt, N, E, xs, vs, Fs, stats, status, message)


def _fast_step(evaluate, u0: list[float], cache: FactorCache, rtol: float,
               atol: float) -> list[float] | None:
    """The common step of :func:`~lumped.newton.newton_solve`, without its bookkeeping.

    When the Jacobian at ``u0`` equals the cached one (the laws stay on the same pieces),
    Newton's path is: accept ``u0`` (0 iterations) or take the full step and accept it
    after the simplified-Newton check with the same factors (1 iteration). This function
    follows exactly that path -- same operations, same result -- and returns the solution
    with the iteration count appended, or ``None`` when anything else would happen
    (then the caller runs ``newton_solve`` from ``u0``).
    """
    G, J, S = evaluate(u0)
    if J != cache.J or not math.isfinite(sum(G)):
        return None
    solve = cache.hit()
    du = solve(G)
    if not math.isfinite(sum(du)):
        return None
    if _residual_ok(G, S, rtol, atol):
        if _update_ok(du, u0, rtol, atol):
            out = [ui - di for ui, di in zip(u0, du, strict=True)]
            out.append(0)
            return out
        return None  # newton_solve would try a directional Jacobian here
    u1 = [ui - di for ui, di in zip(u0, du, strict=True)]
    G1, J1, S1 = evaluate(u1)
    if J1 != J or not math.isfinite(sum(G1)) or not _residual_ok(G1, S1, rtol, atol):
        return None
    d = solve(G1)
    if not (math.isfinite(sum(d)) and _update_ok(d, u1, rtol, atol)):
        return None
    out = [ui - di for ui, di in zip(u1, d, strict=True)]
    out.append(1)
    return out


def _known_monotone(bound) -> bool:
    """True for the built-in monotone laws (their graphs have no folds)."""
    law = getattr(bound, "law", None)
    name = getattr(law, "name", None)
    if name not in MONOTONE_BUILTINS:
        return False
    try:
        from .laws import BUILTIN_LAWS
    except ImportError:  # the law library is not there: check everything
        return False
    builtin = BUILTIN_LAWS.get(name) if isinstance(BUILTIN_LAWS, dict) else None
    return builtin is not None and (law is builtin or law == builtin)


def _sign(x: float, scale: float) -> int:
    if x > 1e-12 * scale:
        return 1
    if x < -1e-12 * scale:
        return -1
    return 0


def _left_branch(kernel, q0: float, F0: float, Rq0: float, RF0: float,
                 q1: float, F1: float, Rq1: float, RF1: float) -> bool:
    """Did the step from ``(q0, F0)`` to ``(q1, F1)`` cross or skip a fold of ``R = 0``?

    A fold is where ``dR/dF`` (or ``dR/dq``) changes sign strictly. The partial
    derivatives at both ends are compared; when the step is not close to the tangent of
    the law at either end (``|R_q dq + R_F dF|`` above half of ``|R_q dq| + |R_F dF|``),
    three interior points of the segment are sampled too.
    """
    s0 = abs(Rq0) + abs(RF0)
    s1 = abs(Rq1) + abs(RF1)
    signs_q = {_sign(Rq0, s0), _sign(Rq1, s1)}
    signs_F = {_sign(RF0, s0), _sign(RF1, s1)}
    if {1, -1} <= signs_q or {1, -1} <= signs_F:
        return True
    dq, dF = q1 - q0, F1 - F0
    off = 0.0
    for Rq, RF in ((Rq0, RF0), (Rq1, RF1)):
        total = abs(Rq * dq) + abs(RF * dF)
        if total > 0.0:
            off = max(off, abs(Rq * dq + RF * dF) / total)
    if off <= 0.5:
        return False
    for s in (0.25, 0.5, 0.75):
        _, Rq, RF = kernel(q0 + s * dq, F0 + s * dF)
        sc = abs(Rq) + abs(RF)
        signs_q.add(_sign(Rq, sc))
        signs_F.add(_sign(RF, sc))
        if {1, -1} <= signs_q or {1, -1} <= signs_F:
            return True
    return False
