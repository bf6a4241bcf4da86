r"""The discrete system of one implicit step (see :mod:`lumped.solvers.bdf.fixed_step`).

Residual and Jacobian of the balances and the laws in the unknowns ``u`` (the velocity of
every node and the force of every element), the scale of a law row's residual, and the
report of a failed Newton solve.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence

from ...scene import Mass, Scene
from ..newton.options import NewtonCode, NewtonResult
from ..status import SolverError, Status

# ---------------------------------------------------------------------------------------
# the discrete system of one step


def make_evaluate(scene: Scene, h: float, cm: Sequence[float], vbase: Sequence[float],
                   vscale: Sequence[float], uref: list[float], x_hat: list[float],
                   f: list[float], qs: list[float], rq: list[float], rf: list[float],
                   roundoff: bool = False, kernels: Sequence[Callable] | None = None):
    """Build ``evaluate(u) -> (G, J, S)`` for one step size.

    The scale of a law row is ``|dR/dq q| + |dR/dF F|``; with ``roundoff`` it is
    :func:`law_scale` (at least that, more where the law's terms cancel).

    ``uref, x_hat, f`` are read at call time (the step loop updates them in place);
    ``qs, rq, rf`` receive each element's ``q, dR/dq, dR/dF`` at the last evaluated point.
    ``kernels`` replaces the laws' own kernels (e.g. by their stage forms,
    :meth:`lumped.codegen.branches.LawBranches.stage_law_for`). This loop version is the
    readable reference of the step system; the step loop runs its generated twin
    :func:`generate_evaluate` (tested equal)."""
    N = len(scene.nodes)
    E = len(scene.elements)
    n = N + E
    if kernels is None:
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
            S[k] = (law_scale(kernel, q, Fe, R, Rq, RF, abs(qb) + abs(qa)) if roundoff
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


def generate_evaluate(scene: Scene, h: float, uref: list[float], x_hat: list[float],
                       f: list[float], roundoff: bool = False,
                       kernels: Sequence[Callable] | None = None):
    """The step system of :func:`make_evaluate` (regular steps, ``v = u``, without the
    per-element side outputs) as generated, unrolled straight-line Python for this scene:
    no loops, no index lookups, constants inlined. Only indices and float literals enter
    the source (never a name from the scene), so a scene file cannot inject code. The
    source is kept in ``__source__``. ``roundoff`` and ``kernels`` as in
    :func:`make_evaluate`."""
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
        scale = (f"law_scale(k{e}, q, u{k}, R, Rq, RF, abs(qb) + abs(qa))" if roundoff
                 else f"abs(Rq * q) + abs(RF * u{k})")
        lines += [f"    qb = {qb}", f"    qa = {qa}", "    q = qb - qa",
                  f"    R, Rq, RF = k{e}(q, u{k})", f"    G{k} = R",
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
    namespace: dict = {"uref": uref, "xh": x_hat, "f": f, "abs": abs, "law_scale": law_scale,
                       "__builtins__": {}}
    for e, el in enumerate(scene.elements):
        namespace[f"k{e}"] = el.law.kernel if kernels is None else kernels[e]
    exec(compile(src, "<lumped step system>", "exec"), namespace)  # noqa: S102 - our own code
    evaluate = namespace["evaluate"]
    evaluate.__source__ = src
    return evaluate


#: Unit roundoff of a double (``2**-52``).
EPS = sys.float_info.epsilon


def law_scale(kernel, q: float, F: float, R: float, Rq: float, RF: float,
              q_terms: float | None = None) -> float:
    r"""Scale of the terms of a law row ``R(q, F)``, for the residual test.

    ``max(|R_q| Q + |R_F F|, M)``, ``M = kernel.magnitude(q, F)`` the magnitude of the
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

    ``Q = q_terms`` is the magnitude of the terms ``q`` is computed from, ``|q_b| + |q_a|``
    for ``q = q_b - q_a`` (a spring's end positions ``x_hat + h v``, a dashpot's end
    velocities), ``|q|`` when not given. The rounding of ``q`` is ``eps Q``, not
    ``eps |q|``: a taut string ``q - L = 0`` between masses at ``x ~ 1`` has ``q``
    on a lattice of spacing ``ulp(x)`` that may miss ``L`` by up to half of it, however
    small ``|q|`` and ``L`` are; Newton's round-off test
    (:mod:`lumped.solvers.newton.criteria`) reads that from this scale.
    """
    lin = (abs(Rq * q) if q_terms is None else abs(Rq) * q_terms) + abs(RF * F)
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
    ro = rho / EPS
    return ro if ro > lin else lin


def _where(scene: Scene, row: int) -> str:
    N = len(scene.nodes)
    if row < N:
        node = scene.nodes[row]
        kind = "momentum balance" if isinstance(node, Mass) else "force balance"
        return f"{kind} of node {node.name!r}"
    el = scene.elements[row - N]
    return f"law {el.law_name!r} of element {el.name!r}"


def newton_failure(scene: Scene, res: NewtonResult, t: float, step: int) -> SolverError:
    where = _where(scene, res.worst_row)
    r = float(res.residual[res.worst_row]) if res.residual else math.nan
    t = float(t)  # plain numbers in the message, never numpy's np.float64(...)
    msg = (
        f"Newton failed ({res.code.value}) at t = {t!r} (step {step}) after "
        f"{res.iterations} iterations: largest residual {r!r} in the {where}"
    )
    if res.code is NewtonCode.SINGULAR:
        msg += (" (singular step Jacobian: the laws do not determine all forces and "
                "velocities, e.g. two rigid or stuck elements in parallel, or a junction "
                "whose elements are all stuck)")
    if res.singular and res.code is not NewtonCode.SINGULAR and res.jacobian:
        # the minimum-norm steps over a singular Jacobian found no solution: the locked
        # (rigid, dR/dF = 0) elements admit no common motion
        N = len(scene.nodes)
        rigid = [el.name for e, el in enumerate(scene.elements)
                 if res.jacobian[N + e][N + e] == 0.0]
        if len(rigid) < 2:  # no two locks to disagree: a plain Newton failure
            return SolverError(msg, status=Status(res.code.value), t=t, where=where,
                               residual=r)
        msg = (f"no motion satisfies all the laws at t = {t!r} (step {step}): the locked "
               f"elements {rigid} (each fixing its elongation or rate, its force free) admit "
               f"no common motion with the rest of the scene; largest residual {r!r} in "
               f"the {where}")
        return SolverError(msg, status=Status.INCONSISTENT, t=t, where=where, residual=r)
    return SolverError(msg, status=Status(res.code.value), t=t, where=where, residual=r)
